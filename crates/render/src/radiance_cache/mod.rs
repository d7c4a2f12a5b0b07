//! Radiance caching of glossy indirect light (001 ch. 3 and §2.2.6, 000 §3.5; NOTES-001 §B): records
//! that store incoming radiance in hemispherical harmonics ([`ircache_math::harmonics`]) and shade
//! any moderately glossy BRDF from them.
//!
//! - [`brdf`]: the BRDFs' cosine-weighted glossy lobes in HSH over the outgoing directions, and the
//!   order each material needs.
//! - [`gather`]: a gather's incoming radiance in HSH and its translational gradients.
//! - [`record`]: a radiance record and its reading at a shading point (extrapolation, rotation
//!   into the shading frame, blending).
//! - [`lookup`]: a cached glossy lobe shaded from the cache's records.
//!
//! [`RadianceCache`] holds what the irradiance cache needs to carry radiance records: per
//! material, the BRDF table at the order its glossy lobe needs (or none: traced); per order, the
//! tilt table; per stratification, the cell integrals. Records live in the irradiance cache's
//! stores (one cache, two record kinds: a record on a radiance-cached surface also points at its
//! coefficients, [`crate::irradiance_cache::Record::radiance`]); the `ic` integrator shades a
//! cached glossy lobe from them (`integrators/ic.rs`).
//!
//! Cache files carry the coefficients (`irradiance_cache/file.rs`); `--aov glossy` shows what the
//! records give.
//!
//! Environment light reaches the records through their gather where the cache holds it
//! ([`crate::irradiance_cache::environment`]): its glossy share is then shaded by the same dot
//! product as the indirect light.

pub mod brdf;
pub mod gather;
pub mod lookup;
pub mod record;
#[cfg(test)]
mod test_room;

use crate::bsdf::Bsdf;
use crate::irradiance_cache::gather::ShadingPoint;
use crate::irradiance_cache::hemisphere::Stratification;
use crate::scene::Scene;
use gather::CellBasis;
use ircache_math::harmonics::rotation::TiltTable;
use ircache_math::Vec2;
use rayon::prelude::*;
use std::collections::HashMap;
use std::sync::{Arc, RwLock};

/// Energy a cached lobe's expansion keeps (3.32): the order is chosen for it at every viewing
/// angle up to 60° (`brdf`).
pub const ENERGY_KEPT: f64 = 0.95;

/// Energy the chosen order must keep at a viewing angle for the cache to serve it; grazing
/// views keeping less are traced. Measured (16 spp, relMSE_trim; blurred): on cornell-rough,
/// whose rough-plastic floor is mostly seen at grazing angles, 0.95 and 0.9 give 2.9e-4, 0.8 and
/// 0.7 1.5e-4, 0 (serve every view) 1.4e-4 with the blurred error 6.7e-5, 6.8e-5, 6.8e-5, 7.3e-5;
/// cornell-glossy and the lamp room unchanged (6.84e-4 / 6.84e-4; 1.63e-2 / 1.63e-2).
pub const ENERGY_SERVED: f64 = 0.8;

/// Largest angle between a record's normal and a shading normal that the tilt tables hold: beyond
/// the accuracy's normal limit at relaxed thresholds (Tabellion's at a = 0.35 allows 17.5° at
/// threshold 1; Ward's arccos(1 − a²) = 28.6°).
const MAX_TILT_DEGREES: f64 = 30.0;

/// The tables radiance records are made and read with.
#[derive(Debug)]
pub struct RadianceCache {
    /// Per material: the BRDF table of its glossy lobe (its front side's) at the order it
    /// needs, or `None` where the lobe stays traced (no glossy part, or too sharp for the highest
    /// order); and whether the back side is the same model (a `twosided` of one model).
    materials: Vec<Option<(Arc<brdf::BrdfCoefficients>, bool)>>,
    /// Per shape, its material.
    shape_material: Vec<usize>,
    /// Per order in use: the tilt table MR(β) at 1° steps.
    tilts: HashMap<usize, Arc<TiltTable>>,
    /// Per (polar, azimuthal, order): the cells' basis integrals, made on first use.
    bases: RwLock<HashMap<(usize, usize, usize), Arc<CellBasis>>>,
}

impl RadianceCache {
    /// The tables for `scene`'s materials up to `max_order` whose glossy lobes reflect at least
    /// `min_albedo` of uniform light ([`brdf::glossy_albedo`]), in
    /// parallel, in the caller's pool.
    #[must_use]
    pub fn new(scene: &Scene, max_order: usize, min_albedo: f64) -> RadianceCache {
        // Glossy parts are untextured in every model; the texture coordinate is moot.
        let bsdfs: Vec<Bsdf> = scene
            .materials
            .iter()
            .map(|m| m.at(Vec2::splat(0.5)))
            .collect();
        // One table per distinct BSDF: a scene's shapes that name one `<bsdf>` each hold a copy
        // (the lamp room: 7 materials, 2 BSDFs). Keyed by the Debug text, which prints every
        // value exactly (`Bsdf` has floats, so no `Hash`).
        let mut first_of: HashMap<String, usize> = HashMap::new();
        let first: Vec<usize> = bsdfs
            .iter()
            .enumerate()
            .map(|(i, b)| *first_of.entry(format!("{b:?}")).or_insert(i))
            .collect();
        let tables: Vec<Option<(Arc<brdf::BrdfCoefficients>, bool)>> = bsdfs
            .par_iter()
            .enumerate()
            .map(|(i, bsdf)| {
                if first[i] != i {
                    return None;
                }
                let both_sides = matches!(bsdf, Bsdf::TwoSided { front, back } if front == back)
                    || matches!(
                        bsdf,
                        Bsdf::Blend {
                            two_sided: true,
                            ..
                        }
                    );
                // The albedo first: a lobe it leaves traced needs no order search.
                if !bsdf.has_glossy()
                    || (min_albedo > 0.0 && brdf::glossy_albedo(bsdf) < min_albedo)
                {
                    return None;
                }
                let order = brdf::order_for(bsdf, max_order, ENERGY_KEPT)?;
                let table = brdf::BrdfCoefficients::new(bsdf, order, ENERGY_SERVED);
                Some((Arc::new(table), both_sides))
            })
            .collect();
        let materials: Vec<_> = first.iter().map(|&f| tables[f].clone()).collect();
        let mut orders: Vec<usize> = materials.iter().flatten().map(|t| t.0.order()).collect();
        orders.sort_unstable();
        orders.dedup();
        let tilts = orders
            .into_par_iter()
            .map(|order| {
                let table = TiltTable::new(order, 1f64.to_radians(), MAX_TILT_DEGREES.to_radians());
                (order, Arc::new(table))
            })
            .collect();
        RadianceCache {
            materials,
            shape_material: scene.shapes.iter().map(|s| s.material).collect(),
            tilts,
            bases: RwLock::new(HashMap::new()),
        }
    }

    /// Whether any material's glossy lobe is cached.
    #[must_use]
    pub fn caches_any(&self) -> bool {
        self.materials.iter().any(Option::is_some)
    }

    /// The BRDF table of material `material` seen from its front (`front`) or back side, if
    /// that side's glossy lobe is cached.
    #[must_use]
    pub fn brdf(&self, material: usize, front: bool) -> Option<&brdf::BrdfCoefficients> {
        let (table, both_sides) = self.materials.get(material)?.as_ref()?;
        (front || *both_sides).then_some(table.as_ref())
    }

    /// The BRDF table of the side of shape `shape` that `sp` looks at, if cached.
    #[must_use]
    pub fn brdf_at(&self, sp: &ShadingPoint) -> Option<&brdf::BrdfCoefficients> {
        // The shading point's normals are turned towards the viewer: the front is seen where
        // that keeps the shading frame's normal.
        let front = sp.n_bump.dot(sp.it.frame.n) > 0.0;
        self.brdf(*self.shape_material.get(sp.it.shape as usize)?, front)
    }

    /// The tilt table of `order`.
    #[must_use]
    pub fn tilt(&self, order: usize) -> Option<&TiltTable> {
        self.tilts.get(&order).map(|t| t.as_ref())
    }

    /// The cell integrals for a gather's stratification at `order` (made once, shared).
    ///
    /// # Panics
    /// If the lock was poisoned by a panic elsewhere.
    #[must_use]
    pub fn cell_basis(&self, strata: Stratification, order: usize) -> Arc<CellBasis> {
        let key = (strata.polar, strata.azimuthal, order);
        if let Some(b) = self.bases.read().expect("cell tables").get(&key) {
            return b.clone();
        }
        let made = Arc::new(CellBasis::new(strata, order));
        self.bases
            .write()
            .expect("cell tables")
            .entry(key)
            .or_insert(made)
            .clone()
    }
}
