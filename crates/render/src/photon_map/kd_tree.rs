//! A balanced kd-tree over photons (Jensen, *Realistic Image Synthesis Using Photon Mapping*,
//! §6.3). The photon array itself is in tree order (the median of a range along its widest axis
//! in the middle of the range, the halves on either side), so that photons near each other in
//! space lie near each other in memory; queries walk a compact copy of the same splits in heap
//! order (node i's children at 2i + 1 and 2i + 2, Jensen's left-balanced tree): the top levels
//! share cache lines, where a descent through the photon array met a new cache line at every
//! level. Queries take a predicate, so that photons of the wrong side or bounce count are skipped
//! during the search rather than after it (a k-nearest query that filters afterwards would come
//! back short); the predicate reads a compact tag kept in the node beside the position
//! ([`Located::Tag`]), since reading the item itself cost a second cache miss per candidate
//! (half the time of a lookup in the precomputed irradiance).

use super::photon::{Photon, PhotonTag};
use std::cmp::Ordering;
use std::collections::BinaryHeap;

/// What a kd-tree holds: anything with a position, and a tag that queries filter on.
pub trait Located: Send {
    /// What a query's predicate tests (kept in the search node).
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

/// Items (photons by default) in kd-tree order, and the splits in heap order for queries.
#[derive(Clone, Debug)]
pub struct KdTree<T: Located = Photon> {
    /// The items, each range's median in its middle.
    pub photons: Vec<T>,
    /// The search tree: a left-balanced kd-tree over the items' positions, in heap order.
    nodes: Vec<Node<T::Tag>>,
}

impl<T: Located> Default for KdTree<T> {
    fn default() -> Self {
        KdTree {
            photons: Vec::new(),
            nodes: Vec::new(),
        }
    }
}

/// A search node: an item's position, its index in [`KdTree::photons`] with the split axis in
/// the top two bits, and its tag.
#[derive(Clone, Copy, Debug, Default)]
struct Node<G> {
    position: [f32; 3],
    index_axis: u32,
    tag: G,
}

impl<G> Node<G> {
    #[inline]
    fn index(&self) -> usize {
        (self.index_axis & INDEX_MASK) as usize
    }

    #[inline]
    fn axis(&self) -> usize {
        (self.index_axis >> 30) as usize
    }
}

const INDEX_MASK: u32 = (1 << 30) - 1;

/// Most items a tree holds (the index shares a word with the split axis).
pub const MAX_ITEMS: usize = INDEX_MASK as usize + 1;

/// Deepest a tree of [`MAX_ITEMS`] goes: the descent's stack of far halves.
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
        build_range(&mut photons);
        let mut items: Vec<Node<T::Tag>> = photons
            .iter()
            .enumerate()
            .map(|(i, p)| Node {
                position: p.key(),
                index_axis: i as u32,
                tag: p.tag(),
            })
            .collect();
        let mut nodes = vec![Node::default(); items.len()];
        build_heap(&mut items, &mut nodes, 0);
        KdTree { photons, nodes }
    }

    /// Number of photons.
    #[must_use]
    pub fn len(&self) -> usize {
        self.photons.len()
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
        self.descend(q, max_distance2, |node, distance2| {
            if !accept(&node.tag) {
                return None;
            }
            heap.push(Neighbour {
                index: node.index() as u32,
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
        self.descend(q, max_distance2, |node, distance2| {
            accept(&node.tag).then(|| {
                best = Some(node.index());
                distance2
            })
        });
        best
    }

    /// Visits the nodes within `sqrt(bound)` of `q`, each node on the way down to the leaf on
    /// its side and the far halves that the shrinking bound still reaches afterwards; `visit`
    /// sees each node and its squared distance and may return a new, smaller bound (generic,
    /// so that each query's visitor is inlined into its own descent, which keeps its far halves
    /// on a stack rather than recursing).
    #[inline]
    fn descend<V: FnMut(&Node<T::Tag>, f32) -> Option<f32>>(
        &self,
        q: [f32; 3],
        mut bound: f32,
        mut visit: V,
    ) {
        let mut far_halves = [(0u32, 0f32); MAX_DEPTH];
        let mut pending = 0usize;
        let mut i = 0usize;
        loop {
            while let Some(node) = self.nodes.get(i) {
                let p = node.position;
                let delta = q[node.axis()] - p[node.axis()];
                let distance2 =
                    (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2) + (p[2] - q[2]).powi(2);
                if distance2 < bound {
                    if let Some(b) = visit(node, distance2) {
                        bound = b;
                    }
                }
                let (near, far) = if delta < 0.0 {
                    (2 * i + 1, 2 * i + 2)
                } else {
                    (2 * i + 2, 2 * i + 1)
                };
                if far < self.nodes.len() && delta * delta < bound {
                    far_halves[pending] = (far as u32, delta * delta);
                    pending += 1;
                }
                i = near;
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

/// The size of the left subtree of a left-balanced (complete) binary tree of `n` nodes.
fn left_size(n: usize) -> usize {
    if n <= 1 {
        return 0;
    }
    // Levels above the last are full: 2^h − 1 nodes; the last holds the rest, left first.
    let h = usize::BITS - 1 - n.leading_zeros();
    let full = (1usize << h) - 1;
    let last = n - full;
    let half_last = 1usize << (h - 1);
    (full - 1) / 2 + last.min(half_last)
}

/// Fills heap node `i` and its subtrees from `items`: the item splitting them along the widest
/// axis at the rank that keeps the tree left-balanced.
fn build_heap<G: Copy>(items: &mut [Node<G>], nodes: &mut [Node<G>], i: usize) {
    if items.is_empty() {
        return;
    }
    let axis = widest_axis(items.iter().map(|n| n.position));
    let rank = left_size(items.len());
    items.select_nth_unstable_by(rank, |a, b| {
        a.position[axis]
            .total_cmp(&b.position[axis])
            .then(a.index_axis.cmp(&b.index_axis))
    });
    let mut node = items[rank];
    node.index_axis = (node.index_axis & INDEX_MASK) | (axis as u32) << 30;
    nodes[i] = node;
    let (left, rest) = items.split_at_mut(rank);
    build_heap(left, nodes, 2 * i + 1);
    build_heap(&mut rest[1..], nodes, 2 * i + 2);
}

/// Puts the median along the widest axis of `photons` in the middle and recurses on the halves
/// (the photons' own order: neighbours in space near in memory).
fn build_range<T: Located>(photons: &mut [T]) {
    if photons.len() <= 1 {
        return;
    }
    let axis = widest_axis(photons.iter().map(Located::key));
    let mid = photons.len() / 2;
    photons.select_nth_unstable_by(mid, |a, b| a.key()[axis].total_cmp(&b.key()[axis]));
    let (left, rest) = photons.split_at_mut(mid);
    let right = &mut rest[1..];
    if left.len() > PARALLEL_BUILD {
        rayon::join(|| build_range(left), || build_range(right));
    } else {
        build_range(left);
        build_range(right);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ircache_math::{Rgb, Rng, Vec3};

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
