//! Shading a radiance-cached glossy lobe from the records (NOTES-001 §B.3, 000 eq. 3.19): the
//! records serving the point at its depth that hold coefficients of the material's order are
//! extrapolated, rotated into the shading frame and blended; the result is dotted with the BRDF's
//! coefficients for the viewing direction.

use super::brdf::{clamped, dot_per_channel, BrdfCoefficients};
use super::record::{frame_around, interpolate, RadianceRecord};
use crate::irradiance_cache::gather::{IrradianceCache, ShadingPoint};
use ircache_math::harmonics::coefficient_count;
use ircache_math::harmonics::rotation::TiltTable;
use ircache_math::{DMat3, Frame, Rgb, Vec3};

/// What shading a point's cached glossy lobe towards one viewing direction needs, found once:
/// the BRDF's coefficients for that direction, the shading frame, the tilt table of the
/// material's order and the threshold radiance records serve within. Splatting keeps one per
/// sample.
pub struct GlossyView<'a> {
    /// c_i(ωo) per channel (`[channel][coefficient]`).
    pub brdf: Vec<f64>,
    /// The material's order.
    pub order: usize,
    /// The shading frame around the shading normal (as the records' frames are made).
    pub frame: DMat3,
    /// Tilt matrices of the order.
    pub tilt: &'a TiltTable,
    /// Records serve within this normalised error.
    pub threshold: f32,
}

impl<'a> GlossyView<'a> {
    /// The view of the glossy lobe at `sp` towards `wo` (world, unit); `None` where the lobe is
    /// not cached or its order does not serve that view.
    #[must_use]
    pub fn new(cache: &'a IrradianceCache, sp: &ShadingPoint, wo: Vec3) -> Option<Self> {
        let tables = cache.radiance.as_deref()?;
        let brdf: &BrdfCoefficients = tables.brdf_at(sp)?;
        let tilt = tables.tilt(brdf.order())?;
        // The shading frame around the shading normal, its tangent from the normal alone, as
        // the records' frames are (coplanar records and points then share frames: R = I).
        let wo_local = Frame::from_z(sp.n_bump).to_local(wo);
        if !brdf.serves(wo_local) {
            return None;
        }
        let mut c = vec![0.0; 3 * coefficient_count(brdf.order())];
        brdf.at(wo_local, &mut c);
        Some(GlossyView {
            brdf: c,
            order: brdf.order(),
            frame: frame_around(sp.n_bump),
            tilt,
            threshold: cache.coverage_threshold(sp),
        })
    }

    /// Σ_i λ_i c_i(ωo) per channel for incoming radiance `radiance` (`[channel][coefficient]`),
    /// not clamped (a blend of these is clamped once, as a blend of the coefficients is).
    #[must_use]
    pub fn reflect_unclamped(&self, radiance: &[f64]) -> [f64; 3] {
        dot_per_channel(&self.brdf, radiance)
    }
}

/// Indirect light the glossy lobe at `sp` reflects towards `wo` (world, unit) from the records
/// of level `depth`; `None` where the lobe is not cached, the view is one the material's order
/// does not serve, or no record with coefficients serves the point within twice the accuracy.
#[must_use]
pub fn glossy(cache: &IrradianceCache, sp: &ShadingPoint, depth: u32, wo: Vec3) -> Option<Rgb> {
    let view = GlossyView::new(cache, sp, wo)?;
    let store = cache.levels.get(depth as usize)?;
    let mut records: Vec<(f64, &RadianceRecord)> = Vec::new();
    for threshold in [view.threshold, 2.0 * view.threshold] {
        records.clear();
        store.for_each_serving(sp.it.p, sp.n, threshold, |rec, w| {
            if let Some(r) = cache.radiance_records.get(rec.radiance as usize) {
                if r.radiance.order == view.order {
                    records.push((f64::from(w), r));
                }
            }
        });
        if let Some(lambda) = interpolate(&records, sp.it.p.as_dvec3(), view.frame, view.tilt) {
            return Some(clamped(view.reflect_unclamped(&lambda)));
        }
    }
    None
}
