//! A balanced kd-tree over photons (Jensen, *Realistic Image Synthesis Using Photon Mapping*,
//! §6.3) with buckets for leaves. The photon array itself is in tree order: each range split at
//! its median along its widest axis, down to leaves of at most [`BUCKET`] photons, each leaf a
//! contiguous run of the array, so that photons near each other in space lie near each other in
//! memory. A query walks the splits (8 bytes each, in heap order: node i's children at 2i + 1
//! and 2i + 2; a tree of 10⁵ photons has 8 191 of them, 64 kB, which stay in cache) and scans the
//! leaves it reaches, their positions and tags side by side in two arrays in the photons' order:
//! one run of cache lines per leaf, where a tree with a photon at every node met a new line,
//! one dependent load after another, at each of its last levels (a fifth of the lamp room's
//! time went to those loads in the final gather's lookups).
//!
//! Queries take a predicate, so that photons of the wrong side or bounce count are skipped
//! during the search rather than after it (a k-nearest query that filters afterwards would come
//! back short); the predicate reads a compact tag ([`Located::Tag`]) kept beside the positions,
//! not the photon itself.

use super::photon::{Photon, PhotonTag};
use std::cmp::Ordering;
use std::collections::BinaryHeap;

/// What a kd-tree holds: anything with a position, and a tag that queries filter on.
pub trait Located: Send {
    /// What a query's predicate tests (kept beside the positions).
    type Tag: Copy + Default + Send + Sync + std::fmt::Debug;
    /// Its position.
    fn key(&self) -> [f32; 3];
    /// Its tag.
    fn tag(&self) -> Self::Tag;
}

impl Located for Photon {
    type Tag = PhotonTag;
    #[inline]
    fn key(&self) -> [f32; 3] {
        Photon::key(self)
    }
    #[inline]
    fn tag(&self) -> PhotonTag {
        PhotonTag::of(self)
    }
}

/// Items (photons by default) in tree order, the splits in heap order, and each leaf's run.
#[derive(Clone, Debug)]
pub struct KdTree<T: Located = Photon> {
    /// The items, leaf by leaf.
    pub photons: Vec<T>,
    /// The items' positions, in the same order.
    points: Vec<[f32; 3]>,
    /// The items' tags, in the same order.
    tags: Vec<T::Tag>,
    /// The inner nodes' splits, in heap order (`2^depth − 1` of them).
    splits: Vec<Split>,
    /// Where each leaf's run starts in [`Self::photons`] (`2^depth + 1` entries, `depth` the
    /// levels of splits).
    leaf_start: Vec<u32>,
}

impl<T: Located> Default for KdTree<T> {
    fn default() -> Self {
        KdTree {
            photons: Vec::new(),
            points: Vec::new(),
            tags: Vec::new(),
            splits: Vec::new(),
            leaf_start: vec![0, 0],
        }
    }
}

/// An inner node: items of its left half lie at or below `value` along `axis`, those of its
/// right half at or above.
#[derive(Clone, Copy, Debug, Default)]
struct Split {
    value: f32,
    axis: u32,
}

/// Most items a leaf holds.
pub const BUCKET: usize = 16;

/// Most items a tree holds (indices are 32-bit).
pub const MAX_ITEMS: usize = 1 << 31;

/// Deepest a tree goes: the descent's stack of far halves.
const MAX_DEPTH: usize = 32;

/// A found photon: its index in [`KdTree::photons`] and squared distance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Neighbour {
    /// Index into the tree's photons.
    pub index: u32,
    /// Squared distance to the query point.
    pub distance2: f32,
}

impl Eq for Neighbour {}
impl PartialOrd for Neighbour {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Neighbour {
    fn cmp(&self, other: &Self) -> Ordering {
        self.distance2
            .total_cmp(&other.distance2)
            .then(self.index.cmp(&other.index))
    }
}

/// Ranges below this size are built on the calling thread.
const PARALLEL_BUILD: usize = 1 << 14;

impl<T: Located> KdTree<T> {
    /// Builds the tree, reordering `photons` (deterministically: the order depends on the input
    /// only, not on the threads).
    #[must_use]
    pub fn build(mut photons: Vec<T>) -> KdTree<T> {
        photons.truncate(MAX_ITEMS);
        let n = photons.len();
        // The fewest levels whose leaves hold at most BUCKET (halves differ by one at most).
        let mut depth = 0u32;
        while n.div_ceil(1 << depth) > BUCKET {
            depth += 1;
        }
        let mut splits = vec![Split::default(); (1usize << depth) - 1];
        let Built {
            splits: made,
            mut leaf_start,
        } = build_range(&mut photons, 0, 0, depth);
        for (i, split) in made {
            splits[i] = split;
        }
        leaf_start.push(n as u32);
        KdTree {
            points: photons.iter().map(Located::key).collect(),
            tags: photons.iter().map(Located::tag).collect(),
            photons,
            splits,
            leaf_start,
        }
    }

    /// Number of photons.
    #[must_use]
    pub fn len(&self) -> usize {
        self.photons.len()
    }

    /// Bytes its arrays hold.
    #[must_use]
    pub fn bytes(&self) -> usize {
        use std::mem::size_of;
        self.photons.capacity() * size_of::<T>()
            + self.points.capacity() * size_of::<[f32; 3]>()
            + self.tags.capacity() * size_of::<T::Tag>()
            + self.splits.capacity() * size_of::<Split>()
            + self.leaf_start.capacity() * size_of::<u32>()
    }

    /// True when it holds no photon.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.photons.is_empty()
    }

    /// The (at most) `k` photons nearest to `q` within `sqrt(max_distance2)` whose tags
    /// `accept`, nearest first, into `out` (cleared first; its allocation is the search's heap).
    pub fn nearest<A: Fn(&T::Tag) -> bool + ?Sized>(
        &self,
        q: [f32; 3],
        k: usize,
        max_distance2: f32,
        accept: &A,
        out: &mut Vec<Neighbour>,
    ) {
        out.clear();
        if k == 0 {
            return;
        }
        let mut heap = BinaryHeap::from(std::mem::take(out));
        self.descend(q, max_distance2, |index, distance2| {
            if !accept(&self.tags[index]) {
                return None;
            }
            heap.push(Neighbour {
                index: index as u32,
                distance2,
            });
            if heap.len() > k {
                heap.pop();
            }
            (heap.len() == k).then(|| heap.peek().map_or(distance2, |n| n.distance2))
        });
        *out = heap.into_sorted_vec();
    }

    /// The index of the item nearest to `q` within `sqrt(max_distance2)` whose tag `accept`s
    /// (the one-neighbour query, without a heap).
    #[must_use]
    pub fn nearest_one<A: Fn(&T::Tag) -> bool + ?Sized>(
        &self,
        q: [f32; 3],
        max_distance2: f32,
        accept: &A,
    ) -> Option<usize> {
        let mut best = None;
        self.descend(q, max_distance2, |index, distance2| {
            accept(&self.tags[index]).then(|| {
                best = Some(index);
                distance2
            })
        });
        best
    }

    /// Visits the items within `sqrt(bound)` of `q`: down the splits to the leaf on `q`'s side,
    /// then the far halves that the shrinking bound still reaches; `visit` sees each item's
    /// index and squared distance and may return a new, smaller bound (generic, so that each
    /// query's visitor is inlined into its own descent, which keeps its far halves on a stack
    /// rather than recursing).
    #[inline]
    fn descend<V: FnMut(usize, f32) -> Option<f32>>(
        &self,
        q: [f32; 3],
        mut bound: f32,
        mut visit: V,
    ) {
        let inner = self.splits.len();
        let mut far_halves = [(0u32, 0f32); MAX_DEPTH];
        let mut pending = 0usize;
        let mut i = 0usize;
        loop {
            while i < inner {
                let split = self.splits[i];
                let delta = q[split.axis as usize] - split.value;
                let (near, far) = if delta < 0.0 {
                    (2 * i + 1, 2 * i + 2)
                } else {
                    (2 * i + 2, 2 * i + 1)
                };
                if delta * delta < bound {
                    far_halves[pending] = (far as u32, delta * delta);
                    pending += 1;
                }
                i = near;
            }
            let leaf = i - inner;
            let (start, end) = (
                self.leaf_start[leaf] as usize,
                self.leaf_start[leaf + 1] as usize,
            );
            for (j, p) in self.points[start..end].iter().enumerate() {
                let distance2 =
                    (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2);
                if distance2 < bound {
                    if let Some(b) = visit(start + j, distance2) {
                        bound = b;
                    }
                }
            }
            // The nearest far half the bound still reaches.
            loop {
                if pending == 0 {
                    return;
                }
                pending -= 1;
                let (far, plane2) = far_halves[pending];
                if plane2 < bound {
                    i = far as usize;
                    break;
                }
            }
        }
    }
}

/// The axis along which `points` spread widest (the lowest of equals).
fn widest_axis(points: impl Iterator<Item = [f32; 3]>) -> usize {
    let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
    for p in points {
        for (c, v) in p.into_iter().enumerate() {
            lo[c] = lo[c].min(v);
            hi[c] = hi[c].max(v);
        }
    }
    let extent = [hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]];
    (0..3)
        .max_by(|&a, &b| extent[a].total_cmp(&extent[b]).then(b.cmp(&a)))
        .unwrap_or(0)
}

/// What [`build_range`] made of a range: its splits by heap index (the halves' nodes
/// interleave in the heap, so each half returns its own and the caller writes them), and the
/// start of each of its leaves' runs, left to right.
struct Built {
    splits: Vec<(usize, Split)>,
    leaf_start: Vec<u32>,
}

/// Splits `photons` (the range at `offset` in the whole array that inner node `i` covers,
/// `levels` levels of splits above its leaves) at its median along its widest axis, and
/// recurses on the halves `[..mid)` and `[mid..)`.
fn build_range<T: Located>(photons: &mut [T], offset: usize, i: usize, levels: u32) -> Built {
    if levels == 0 {
        return Built {
            splits: Vec::new(),
            leaf_start: vec![offset as u32],
        };
    }
    let mid = photons.len() / 2;
    let axis = widest_axis(photons.iter().map(Located::key));
    if mid < photons.len() {
        photons.select_nth_unstable_by(mid, |a, b| a.key()[axis].total_cmp(&b.key()[axis]));
    }
    let value = photons.get(mid).map_or(0.0, |p| p.key()[axis]);
    let (left, right) = photons.split_at_mut(mid);
    let (mut made, right_made) = if mid > PARALLEL_BUILD {
        rayon::join(
            || build_range(left, offset, 2 * i + 1, levels - 1),
            || build_range(right, offset + mid, 2 * i + 2, levels - 1),
        )
    } else {
        (
            build_range(left, offset, 2 * i + 1, levels - 1),
            build_range(right, offset + mid, 2 * i + 2, levels - 1),
        )
    };
    made.splits.push((
        i,
        Split {
            value,
            axis: axis as u32,
        },
    ));
    made.splits.extend(right_made.splits);
    made.leaf_start.extend(right_made.leaf_start);
    made
}

#[cfg(test)]
mod tests {
    use super::*;
    use ircache_math::{Rgb, Rng, Vec3};

    #[test]
    fn leaves_hold_at_most_a_bucket_and_every_item_once() {
        for n in [0usize, 1, 15, 16, 17, 100, 1000, 4097] {
            let items: Vec<Photon> = (0..n)
                .map(|i| Photon {
                    // Many equal coordinates: medians with duplicates on both sides.
                    position: Vec3::new((i % 7) as f32, (i % 3) as f32, 0.0),
                    normal: Vec3::Z,
                    incoming: Vec3::Z,
                    flux: Rgb::splat(i as f32),
                    bounces: 0,
                    distance: 1.0,
                    caustic: false,
                })
                .collect();
            let tree = KdTree::build(items);
            assert_eq!(tree.leaf_start.len(), tree.splits.len() + 2);
            assert_eq!(*tree.leaf_start.last().unwrap() as usize, n);
            assert!(tree
                .leaf_start
                .windows(2)
                .all(|w| w[1] >= w[0] && (w[1] - w[0]) as usize <= BUCKET));
            let mut fluxes: Vec<u32> = tree.photons.iter().map(|p| p.flux.r as u32).collect();
            fluxes.sort_unstable();
            assert!(fluxes.iter().enumerate().all(|(i, &f)| i as u32 == f));
            // Every item is found where it lies.
            let mut out = Vec::new();
            for p in &tree.photons {
                tree.nearest(p.key(), 1, f32::INFINITY, &|_: &PhotonTag| true, &mut out);
                assert_eq!(out.len(), 1);
                assert_eq!(out[0].distance2, 0.0);
            }
        }
    }

    #[test]
    fn nearest_matches_brute_force_with_a_predicate() {
        let mut rng = Rng::new(3, 0);
        let photons: Vec<Photon> = (0..5000)
            .map(|i| Photon {
                position: Vec3::new(rng.next_f32(), rng.next_f32() * 0.5, rng.next_f32() * 2.0),
                normal: Vec3::Z,
                incoming: Vec3::Z,
                flux: Rgb::splat(1.0),
                bounces: (i % 3) as u16,
                distance: 1.0,
                caustic: false,
            })
            .collect();
        let tree = KdTree::build(photons.clone());
        assert_eq!(tree.len(), photons.len());
        let accept = |p: &PhotonTag| p.bounces() != 1;
        let mut out = Vec::new();
        for _ in 0..200 {
            let q = [rng.next_f32(), rng.next_f32() * 0.5, rng.next_f32() * 2.0];
            let max2 = if rng.next_f32() < 0.5 {
                0.01
            } else {
                f32::INFINITY
            };
            tree.nearest(q, 17, max2, &accept, &mut out);
            let mut brute: Vec<f32> = photons
                .iter()
                .filter(|p| p.bounces != 1)
                .map(|p| p.position.distance_squared(Vec3::from(q)))
                .filter(|&d| d < max2)
                .collect();
            brute.sort_by(f32::total_cmp);
            brute.truncate(17);
            let found: Vec<f32> = out.iter().map(|n| n.distance2).collect();
            assert_eq!(found.len(), brute.len());
            for (a, b) in found.iter().zip(&brute) {
                assert!((a - b).abs() <= 1e-6 * b.max(1e-6), "{a} {b}");
            }
            assert!(out
                .iter()
                .all(|n| tree.photons[n.index as usize].bounces != 1));
            let one = tree.nearest_one(q, max2, &accept);
            assert_eq!(one.map(|i| i as u32), out.first().map(|n| n.index));
        }
    }
}
