//! The records of one bounce level and the spatial index over them: a multi-level hash grid
//! playing the role of Radiance's octree. A record whose validity radius is ρ = a·R lives at the
//! level whose cell size is the first ≥ ρ, in every cell its sphere overlaps (at most 8), so a
//! query visits one cell per level in use. Records are only ever appended, in an order decided by
//! the caller, which keeps lookups deterministic.

use super::record::{extrapolate, split_sphere_error, weight, GradientMode, Record};
use ircache_math::{Rgb, Vec3};
use rustc_hash::FxHashMap;

/// Records of one bounce level with their index.
#[derive(Clone, Debug)]
pub struct RecordStore {
    records: Vec<Record>,
    /// Cell size of grid level 0 (the smallest validity radius expected).
    base_cell: f32,
    /// Accuracy `a`: validity radius is `a · R`.
    accuracy: f32,
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

impl RecordStore {
    /// An empty store; `min_validity_radius` sets the finest grid (any positive value works,
    /// close to the smallest a·R keeps cells small).
    #[must_use]
    pub fn new(min_validity_radius: f32, accuracy: f32) -> RecordStore {
        RecordStore {
            records: Vec::new(),
            base_cell: min_validity_radius.max(f32::MIN_POSITIVE),
            accuracy,
            cells: FxHashMap::default(),
            levels_used: 0,
        }
    }

    /// The records, in insertion order.
    #[must_use]
    pub fn records(&self) -> &[Record] {
        &self.records
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

    fn cell_size(&self, level: u8) -> f32 {
        self.base_cell * (1u64 << level) as f32
    }

    fn cell_of(p: Vec3, size: f32) -> [i32; 3] {
        let q = p / size;
        [q.x, q.y, q.z].map(|c| c.floor().clamp(-2.0e9, 2.0e9) as i32)
    }

    /// Appends a record and indexes it.
    pub fn insert(&mut self, rec: Record) {
        let rho = self.accuracy * rec.r;
        let mut level = 0u8;
        while level < MAX_GRID_LEVEL && self.cell_size(level) < rho {
            level += 1;
        }
        let size = self.cell_size(level);
        let lo = Self::cell_of(rec.p - Vec3::splat(rho), size);
        let hi = Self::cell_of(rec.p + Vec3::splat(rho), size);
        let id = self.records.len() as u32;
        for x in lo[0]..=hi[0] {
            for y in lo[1]..=hi[1] {
                for z in lo[2]..=hi[2] {
                    self.cells.entry((level, [x, y, z])).or_default().push(id);
                }
            }
        }
        self.levels_used |= 1 << level;
        self.records.push(rec);
    }

    /// Calls `f(record index)` for every record whose validity sphere may hold `p`.
    #[inline]
    pub fn for_each_near(&self, p: Vec3, mut f: impl FnMut(u32)) {
        let mut used = self.levels_used;
        while used != 0 {
            let level = used.trailing_zeros() as u8;
            used &= used - 1;
            let key = (level, Self::cell_of(p, self.cell_size(level)));
            if let Some(ids) = self.cells.get(&key) {
                for &id in ids {
                    f(id);
                }
            }
        }
    }

    /// Interpolates at (p, n) from the records with ε ≤ `max_error` (normally the accuracy
    /// `a`, i.e. w ≥ 1/a) that are not in front of p (000 eq. 3.15).
    #[must_use]
    pub fn interpolate(
        &self,
        p: Vec3,
        n: Vec3,
        max_error: f32,
        mode: GradientMode,
    ) -> Option<Interpolated> {
        let mut sum = Rgb::ZERO;
        let mut wsum = 0.0f32;
        let mut count = 0;
        self.for_each_near(p, |id| {
            let rec = &self.records[id as usize];
            if let Some(err) = split_sphere_error(rec, p, n) {
                if err <= max_error {
                    let w = weight(err, self.accuracy);
                    sum += extrapolate(rec, p, n, mode) * w;
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

    /// True when some record covers (p, n) at the store's accuracy.
    #[must_use]
    pub fn covers(&self, p: Vec3, n: Vec3) -> bool {
        let mut hit = false;
        self.for_each_near(p, |id| {
            if !hit {
                let rec = &self.records[id as usize];
                hit = split_sphere_error(rec, p, n).is_some_and(|e| e <= self.accuracy);
            }
        });
        hit
    }
}
