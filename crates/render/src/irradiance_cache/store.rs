//! The records of one bounce level and the spatial index over them: a multi-level hash grid
//! playing the role of Radiance's octree. A record whose validity radius is ρ = a·R lives at the
//! level whose cell size is the first ≥ ρ, in every cell its sphere overlaps (at most 8), so a
//! query visits one cell per level in use. Records are only ever appended, in an order decided by
//! the caller, which keeps lookups deterministic. The store holds any kind of record
//! ([`CachedRecord`]: position, normal, radius); interpolating irradiance is the irradiance
//! record's own.

use super::record::{extrapolate, CachedRecord, ErrorMetric, GradientMode, Record};
use ircache_math::{Rgb, Vec3};
use rustc_hash::FxHashMap;

/// Records of one bounce level with their index, for any kind of record.
#[derive(Clone, Debug)]
pub struct RecordStore<R: CachedRecord = Record> {
    records: Vec<R>,
    /// Each record's position and validity radius at threshold 1, beside the records: lookups
    /// reject the far candidates of a cell from these 16 bytes without reading the record.
    reach: Vec<[f32; 4]>,
    /// Cell size of grid level 0 (the smallest validity radius expected).
    base_cell: f32,
    /// Accuracy `a`.
    accuracy: f32,
    /// How errors are measured.
    metric: ErrorMetric,
    /// Neighbour clamping: a record's radius never exceeds a neighbour's plus their distance.
    clamp_neighbours: bool,
    /// (level, cell) → record indices.
    cells: FxHashMap<(u8, [i32; 3]), Vec<u32>>,
    /// Grid levels holding at least one record.
    levels_used: u64,
}

/// Result of an interpolation query.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Interpolated {
    /// Interpolated irradiance (3.15), clamped to be non-negative.
    pub e: Rgb,
    /// Sum of the weights of the contributing records.
    pub weight_sum: f32,
    /// Number of contributing records.
    pub count: u32,
}

const MAX_GRID_LEVEL: u8 = 40;

impl<R: CachedRecord> RecordStore<R> {
    /// An empty store; `min_validity_radius` sets the finest grid (any positive value works,
    /// close to the smallest a·R keeps cells small).
    #[must_use]
    pub fn new(
        min_validity_radius: f32,
        accuracy: f32,
        metric: ErrorMetric,
        clamp_neighbours: bool,
    ) -> RecordStore<R> {
        RecordStore {
            records: Vec::new(),
            reach: Vec::new(),
            base_cell: min_validity_radius.max(f32::MIN_POSITIVE),
            accuracy,
            metric,
            clamp_neighbours,
            cells: FxHashMap::default(),
            levels_used: 0,
        }
    }

    /// The records, in insertion order.
    #[must_use]
    pub fn records(&self) -> &[R] {
        &self.records
    }

    /// The accuracy its errors are measured at and how.
    #[must_use]
    pub fn metric(&self) -> (ErrorMetric, f32) {
        (self.metric, self.accuracy)
    }

    /// Number of records.
    #[must_use]
    pub fn len(&self) -> usize {
        self.records.len()
    }

    /// True when empty.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.records.is_empty()
    }

    /// Record `id`'s position and the distance beyond which it never serves at threshold 1
    /// (its validity radius): the sphere a splat covers (NOTES-001 §C.2 step 1).
    #[must_use]
    pub fn reach(&self, id: u32) -> (Vec3, f32) {
        let [x, y, z, rho] = self.reach[id as usize];
        (Vec3::new(x, y, z), rho)
    }

    /// Record `rec`'s normalised error at (p, n), `None` when it lies in front of p: the rule
    /// every lookup applies ([`ErrorMetric::error`] at the store's accuracy).
    #[inline]
    #[must_use]
    pub fn error(&self, rec: &R, p: Vec3, n: Vec3) -> Option<f32> {
        self.metric.error(rec, p, n, self.accuracy)
    }

    /// The weight of a record whose normalised error is `e`, serving up to `threshold`.
    #[inline]
    #[must_use]
    pub fn weight(&self, e: f32, threshold: f32) -> f32 {
        self.metric.weight(e, threshold)
    }

    fn cell_size(&self, level: u8) -> f32 {
        self.base_cell * (1u64 << level) as f32
    }

    /// The cell holding `p` at cell size `size`. The floor is by truncation: a lookup takes a
    /// cell per grid level, and without SSE4.1 `f32::floor` is a call into libm (a twentieth
    /// of the pixel pass on Sponza); clamped first, the same integer as `floor`.
    #[inline]
    fn cell_of(p: Vec3, size: f32) -> [i32; 3] {
        let q = p / size;
        [q.x, q.y, q.z].map(|c| {
            let c = c.clamp(-2.0e9, 2.0e9);
            let t = c as i32;
            t - i32::from(t as f32 > c)
        })
    }

    /// Appends a record and indexes it. With neighbour clamping (Křivánek et al. 2006), the
    /// records whose validity sphere holds the new one's position and the new one bound each
    /// other's radius by their own plus their distance; records are only ever shrunk, and
    /// in insertion order, so the result does not depend on timing.
    pub fn insert(&mut self, mut rec: R) {
        let p = rec.position();
        if self.clamp_neighbours {
            let mut near = Vec::new();
            self.for_each_near(p, |id| near.push(id));
            near.sort_unstable();
            near.dedup();
            for id in near {
                let other = &mut self.records[id as usize];
                let d = other.position().distance(p);
                if d <= self.metric.validity_radius(other, self.accuracy) {
                    rec.set_radius(rec.radius().min(other.radius() + d));
                    other.set_radius(other.radius().min(rec.radius() + d));
                    self.reach[id as usize][3] = self.metric.validity_radius(other, self.accuracy);
                }
            }
        }
        let rho = self.metric.validity_radius(&rec, self.accuracy);
        let mut level = 0u8;
        while level < MAX_GRID_LEVEL && self.cell_size(level) < rho {
            level += 1;
        }
        let size = self.cell_size(level);
        let lo = Self::cell_of(p - Vec3::splat(rho), size);
        let hi = Self::cell_of(p + Vec3::splat(rho), size);
        let id = self.records.len() as u32;
        for x in lo[0]..=hi[0] {
            for y in lo[1]..=hi[1] {
                for z in lo[2]..=hi[2] {
                    self.cells.entry((level, [x, y, z])).or_default().push(id);
                }
            }
        }
        self.levels_used |= 1 << level;
        self.reach.push([p.x, p.y, p.z, rho]);
        self.records.push(rec);
    }

    /// Reorders the records along a Morton (Z-order) curve through their positions and rebuilds
    /// the index, so that records near each other in space are near each other in memory
    /// (003 item 8). The order depends only on the records, so the result is deterministic.
    pub fn sort_spatially(&mut self) {
        if self.records.is_empty() {
            return;
        }
        let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        for r in &self.records {
            lo = lo.min(r.position());
            hi = hi.max(r.position());
        }
        let scale = 1023.0 / (hi - lo).max_element().max(f32::MIN_POSITIVE);
        let spread = |v: u32| -> u64 {
            // Interleave 10 bits with two zero bits between each.
            let mut x = u64::from(v & 0x3ff);
            x = (x | (x << 16)) & 0x0300_00ff;
            x = (x | (x << 8)) & 0x0300_f00f;
            x = (x | (x << 4)) & 0x030c_30c3;
            (x | (x << 2)) & 0x0924_9249
        };
        let key = |r: &R| {
            let q = ((r.position() - lo) * scale).round();
            spread(q.x as u32) | (spread(q.y as u32) << 1) | (spread(q.z as u32) << 2)
        };
        let mut records = std::mem::take(&mut self.records);
        self.reach.clear();
        // Stable: equal keys keep their insertion order.
        records.sort_by_key(key);
        self.cells.clear();
        self.levels_used = 0;
        let clamp = std::mem::replace(&mut self.clamp_neighbours, false);
        for r in records {
            self.insert(r);
        }
        self.clamp_neighbours = clamp;
    }

    /// Calls `f(record index)` for every record whose validity sphere may hold `p`.
    #[inline]
    pub fn for_each_near(&self, p: Vec3, mut f: impl FnMut(u32)) {
        // Every level's cell first, then their records: the hash probes, each a likely cache
        // miss in a large cache, overlap instead of waiting one behind the other's records.
        let mut cells: [&[u32]; MAX_GRID_LEVEL as usize + 1] = [&[]; MAX_GRID_LEVEL as usize + 1];
        let mut found = 0;
        let mut used = self.levels_used;
        while used != 0 {
            let level = used.trailing_zeros() as u8;
            used &= used - 1;
            let key = (level, Self::cell_of(p, self.cell_size(level)));
            if let Some(ids) = self.cells.get(&key) {
                cells[found] = ids;
                found += 1;
            }
        }
        for ids in &cells[..found] {
            for &id in *ids {
                if self.may_reach(id, p, 1.0) {
                    f(id);
                }
            }
        }
    }

    /// False when record `id`'s validity sphere grown `threshold` times cannot hold `p` (every
    /// metric's error exceeds the threshold beyond that distance); a relative margin keeps
    /// the records on the boundary, whatever the rounding.
    #[inline]
    fn may_reach(&self, id: u32, p: Vec3, threshold: f32) -> bool {
        let [x, y, z, rho] = self.reach[id as usize];
        let reach = threshold * rho;
        (p - Vec3::new(x, y, z)).length_squared() <= reach * reach * (1.0 + 1e-4)
    }

    /// Calls `f(record index)` once for every record whose validity sphere grown `threshold`
    /// times may hold `p`. A record at grid level L has ρ ≤ the level's cell size s and is
    /// filed in every cell its ρ-sphere overlaps; if ‖p − xᵢ‖ ≤ tρ, the point of that sphere
    /// nearest p lies within (t − 1)s of p, so the cells overlapping p ± (t − 1)s hold it.
    pub fn for_each_near_within(&self, p: Vec3, threshold: f32, mut f: impl FnMut(u32)) {
        if threshold <= 1.0 {
            return self.for_each_near(p, f);
        }
        let mut ids = Vec::new();
        let mut used = self.levels_used;
        while used != 0 {
            let level = used.trailing_zeros() as u8;
            used &= used - 1;
            let size = self.cell_size(level);
            let reach = Vec3::splat((threshold - 1.0) * size);
            let lo = Self::cell_of(p - reach, size);
            let hi = Self::cell_of(p + reach, size);
            for x in lo[0]..=hi[0] {
                for y in lo[1]..=hi[1] {
                    for z in lo[2]..=hi[2] {
                        if let Some(c) = self.cells.get(&(level, [x, y, z])) {
                            ids.extend_from_slice(c);
                        }
                    }
                }
            }
        }
        ids.sort_unstable();
        ids.dedup();
        for id in ids {
            if self.may_reach(id, p, threshold) {
                f(id);
            }
        }
    }

    /// The records serving (p, n) within `threshold`, with their weights.
    pub fn for_each_serving(&self, p: Vec3, n: Vec3, threshold: f32, mut f: impl FnMut(&R, f32)) {
        self.for_each_near_within(p, threshold, |id| {
            let rec = &self.records[id as usize];
            if let Some(err) = self.metric.error(rec, p, n, self.accuracy) {
                if err <= threshold {
                    f(rec, self.metric.weight(err, threshold));
                }
            }
        });
    }

    /// Indices of the records serving (p, n) within `threshold`, in index order.
    #[must_use]
    pub fn serving(&self, p: Vec3, n: Vec3, threshold: f32) -> Vec<u32> {
        let mut ids = Vec::new();
        self.for_each_near_within(p, threshold, |id| {
            let rec = &self.records[id as usize];
            if self
                .metric
                .error(rec, p, n, self.accuracy)
                .is_some_and(|e| e <= threshold)
            {
                ids.push(id);
            }
        });
        ids.sort_unstable();
        ids
    }

    /// True when some record covers (p, n) at the store's accuracy.
    #[must_use]
    pub fn covers(&self, p: Vec3, n: Vec3) -> bool {
        self.covers_within(p, n, 1.0)
    }

    /// True when some record's normalised error at (p, n) is at most `threshold` ≤ 1 (a finer
    /// accuracy: `threshold` = a′/a for Ward's and Tabellion's metrics).
    #[must_use]
    pub fn covers_within(&self, p: Vec3, n: Vec3, threshold: f32) -> bool {
        let mut hit = false;
        self.for_each_near(p, |id| {
            if !hit {
                let rec = &self.records[id as usize];
                hit = self
                    .metric
                    .error(rec, p, n, self.accuracy)
                    .is_some_and(|e| e <= threshold);
            }
        });
        hit
    }
}

impl RecordStore<Record> {
    /// Interpolates at (p, n) from the records whose normalised error is at most `threshold`
    /// (1: the accuracy; more: relaxed) and that are not in front of p (000 eq. 3.15). Weights
    /// use the normal `n`; the rotational gradient turns each record towards `n_rot` (a bump-
    /// or normal-mapped normal, 003 item 5; `n` itself otherwise).
    #[must_use]
    pub fn interpolate(
        &self,
        p: Vec3,
        n: Vec3,
        n_rot: Vec3,
        threshold: f32,
        mode: GradientMode,
    ) -> Option<Interpolated> {
        let mut sum = Rgb::ZERO;
        let mut wsum = 0.0f32;
        let mut count = 0;
        self.for_each_near_within(p, threshold, |id| {
            let rec = &self.records[id as usize];
            if let Some(err) = self.metric.error(rec, p, n, self.accuracy) {
                if err <= threshold {
                    let w = self.metric.weight(err, threshold);
                    sum += extrapolate(rec, p, n_rot, mode) * w;
                    wsum += w;
                    count += 1;
                }
            }
        });
        (count > 0).then(|| Interpolated {
            e: (sum / wsum).max(Rgb::ZERO),
            weight_sum: wsum,
            count,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rec(p: Vec3, r: f32) -> Record {
        Record {
            p,
            n: Vec3::Z,
            e: Rgb::ONE,
            r,
            grad_t: [Vec3::ZERO; 3],
            grad_r: [Vec3::ZERO; 3],
            level: 0,
            ray_variance: 0.0,
            radiance: crate::irradiance_cache::record::NO_RADIANCE,
        }
    }

    #[test]
    fn cells_by_truncation_are_the_cells_floor_gives() {
        // Every grid level's cell comes from a truncation instead of f32::floor: the same cell
        // for whole and fractional, negative and positive, tiny and huge coordinates.
        let floor_cell = |c: f32| c.floor().clamp(-2.0e9, 2.0e9) as i32;
        let mut values = vec![
            0.0, -0.0, 1.0, -1.0, 0.5, -0.5, 1e-30, -1e-30, 3e9, -3e9, 2e9,
        ];
        values.extend([
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            16_777_217.0,
            -16_777_215.5,
        ]);
        let mut x = 0.123_f32;
        for _ in 0..10_000 {
            x = (x * 3.7 + 0.31).fract();
            values.push((x - 0.5) * 2000.0);
            values.push((x - 0.5) * 3.0e7);
        }
        for c in values {
            let got = RecordStore::<Record>::cell_of(Vec3::splat(c), 1.0);
            assert_eq!(got, [floor_cell(c); 3], "coordinate {c}");
        }
    }

    #[test]
    fn relaxed_lookups_find_every_record_in_reach_whatever_the_grid_alignment() {
        // One record at many offsets from the grid; queries at 1.9ρ and 3.7ρ in 14 directions
        // must find it with thresholds 2 and 4 (every metric), and not beyond.
        for metric in [
            ErrorMetric::Ward,
            ErrorMetric::Tabellion,
            ErrorMetric::Hessian,
        ] {
            for i in 0..50 {
                let f = i as f32 / 50.0;
                let p = Vec3::new(0.37 * f, 0.71 * f, 0.13 * f) + Vec3::splat(3.0);
                let mut s = RecordStore::new(0.05, 0.4, metric, false);
                s.insert(rec(p, 0.3));
                let rho = metric.validity_radius(&s.records()[0], 0.4);
                let dirs = [
                    Vec3::X,
                    -Vec3::X,
                    Vec3::Y,
                    -Vec3::Y,
                    Vec3::new(1.0, 1.0, 0.0).normalize(),
                    Vec3::new(-1.0, 1.0, 0.0).normalize(),
                    Vec3::new(1.0, -1.0, 0.0).normalize(),
                    Vec3::new(-1.0, -1.0, 0.0).normalize(),
                    Vec3::new(0.6, 0.8, 0.0),
                    Vec3::new(-0.8, 0.6, 0.0),
                    Vec3::new(0.28, -0.96, 0.0),
                    Vec3::new(-0.96, -0.28, 0.0),
                    Vec3::new(0.0, 1.0, 0.0),
                    Vec3::new(1.0, 0.0, 0.0),
                ];
                for d in dirs {
                    for (t, dist) in [(2.0, 1.9), (4.0, 3.7)] {
                        let q = p + d * (dist * rho);
                        let found = s.interpolate(q, Vec3::Z, Vec3::Z, t, GradientMode::None);
                        assert!(found.is_some(), "{metric:?} offset {f} dir {d} t {t}");
                        let far = p + d * ((t + 0.2) * rho);
                        assert!(
                            s.interpolate(far, Vec3::Z, Vec3::Z, t, GradientMode::None)
                                .is_none(),
                            "{metric:?} beyond reach"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn the_store_serves_any_kind_of_record() {
        // Another record kind (as radiance or photon records will be): the index, the metrics
        // and neighbour clamping work on its position, normal and radius alone.
        #[derive(Clone, Copy)]
        struct Probe {
            p: Vec3,
            r: f32,
            tag: u32,
        }
        impl CachedRecord for Probe {
            fn position(&self) -> Vec3 {
                self.p
            }
            fn normal(&self) -> Vec3 {
                Vec3::Z
            }
            fn radius(&self) -> f32 {
                self.r
            }
            fn set_radius(&mut self, r: f32) {
                self.r = r;
            }
        }
        let mut s: RecordStore<Probe> = RecordStore::new(0.01, 0.5, ErrorMetric::Ward, true);
        s.insert(Probe {
            p: Vec3::ZERO,
            r: 10.0,
            tag: 1,
        });
        s.insert(Probe {
            p: Vec3::X,
            r: 0.2,
            tag: 2,
        });
        // Clamped as irradiance records are: 0.2 + 1.
        assert!((s.records()[0].r - 1.2).abs() < 1e-5);
        // Ward: each serves within a·R (0.6 and 0.1).
        let tags = |x: f32, t: f32| -> Vec<u32> {
            s.serving(Vec3::new(x, 0.0, 0.0), Vec3::Z, t)
                .iter()
                .map(|&i| s.records()[i as usize].tag)
                .collect()
        };
        assert_eq!(tags(0.55, 1.0), [1]);
        assert_eq!(tags(0.95, 1.0), [2]);
        assert_eq!(tags(0.95, 2.0), [1, 2]);
        assert!(s.covers(Vec3::new(0.3, 0.0, 0.0), Vec3::Z));
        assert!(!s.covers(Vec3::new(5.0, 0.0, 0.0), Vec3::Z));
    }

    #[test]
    fn neighbour_clamping_bounds_radii_by_neighbour_plus_distance() {
        for clamp in [false, true] {
            let mut s = RecordStore::new(0.01, 0.5, ErrorMetric::Ward, clamp);
            s.insert(rec(Vec3::ZERO, 10.0));
            s.insert(rec(Vec3::new(1.0, 0.0, 0.0), 0.2));
            let big = s.records()[0].r;
            if clamp {
                assert!((big - 1.2).abs() < 1e-5, "{big}");
            } else {
                assert_eq!(big, 10.0);
            }
            // A later big record next to the small one is clamped on insertion.
            s.insert(rec(Vec3::new(1.05, 0.0, 0.0), 8.0));
            let third = s.records()[2].r;
            assert_eq!(third <= 0.2 + 0.05 + 1e-5, clamp, "{third}");
        }
    }

    #[test]
    fn metrics_measure_as_their_equations_say() {
        let r = rec(Vec3::ZERO, 2.0);
        // Ward (3.10): ε = d/R + √(1 − n·nᵢ), normalised by a.
        let e = ErrorMetric::Ward
            .error(&r, Vec3::new(1.0, 0.0, 0.0), Vec3::Z, 0.5)
            .unwrap();
        assert!((e - 1.0).abs() < 1e-6);
        // Tabellion (3.59–3.61) at a = 0.2 (κ = 1): the larger of d/R and the normal term,
        // which is 1 at 10°.
        let t = ErrorMetric::Tabellion;
        let e = t.error(&r, Vec3::new(1.0, 0.0, 0.0), Vec3::Z, 0.2).unwrap();
        assert!((e - 0.5).abs() < 1e-6);
        let ten = 10f32.to_radians();
        let n = Vec3::new(ten.sin(), 0.0, ten.cos());
        let e = t.error(&r, Vec3::ZERO, n, 0.2).unwrap();
        assert!((e - 1.0).abs() < 1e-3, "{e}");
        assert!((t.weight(0.25, 1.0) - 0.75).abs() < 1e-6);
        // Hessian: d/R + √(1 − n·nᵢ)/a.
        let e = ErrorMetric::Hessian
            .error(&r, Vec3::new(1.0, 0.0, 0.0), n, 0.5)
            .unwrap();
        let expect = 0.5 + (1.0 - n.z).sqrt() / 0.5;
        assert!((e - expect).abs() < 1e-5, "{e} vs {expect}");
        // A record in front of the query point never serves.
        assert!(ErrorMetric::Ward
            .error(&r, Vec3::new(1.0, 0.0, -0.5), Vec3::Z, 0.5)
            .is_none());
    }
}

#[cfg(test)]
mod order_tests {
    use super::*;

    #[test]
    fn spatial_order_changes_memory_not_results() {
        let mut rng = ircache_math::Rng::keyed(3, &[]);
        let mut s = RecordStore::new(0.01, 0.3, ErrorMetric::Ward, false);
        for _ in 0..500 {
            let p = Vec3::new(rng.next_f32(), rng.next_f32(), 0.0) * 10.0;
            s.insert(Record {
                p,
                n: Vec3::Z,
                e: Rgb::splat(1.0 + p.x),
                r: 0.5 + rng.next_f32(),
                grad_t: [Vec3::X * 0.1; 3],
                grad_r: [Vec3::ZERO; 3],
                level: 0,
                ray_variance: 0.0,
                radiance: crate::irradiance_cache::record::NO_RADIANCE,
            });
        }
        let queries: Vec<Vec3> = (0..200)
            .map(|_| Vec3::new(rng.next_f32(), rng.next_f32(), 0.0) * 10.0)
            .collect();
        let before: Vec<_> = queries
            .iter()
            .map(|&q| s.interpolate(q, Vec3::Z, Vec3::Z, 1.0, GradientMode::Full))
            .collect();
        let order_before: Vec<Vec3> = s.records().iter().map(|r| r.p).collect();
        s.sort_spatially();
        let order_after: Vec<Vec3> = s.records().iter().map(|r| r.p).collect();
        assert_ne!(order_before, order_after);
        for (q, b) in queries.iter().zip(&before) {
            let a = s.interpolate(*q, Vec3::Z, Vec3::Z, 1.0, GradientMode::Full);
            match (a, b) {
                (Some(a), Some(b)) => {
                    assert_eq!(a.count, b.count);
                    assert!((a.e.r - b.e.r).abs() <= 1e-5 * b.e.r.abs().max(1.0));
                }
                (None, None) => {}
                _ => panic!("coverage changed at {q}"),
            }
        }
    }
}
