//! Shading a radiance-cached glossy lobe from the records (NOTES-001 §B.3, 000 eq. 3.19): the
//! records serving the point at its depth that hold coefficients of the material's order are
//! extrapolated, rotated into the shading frame and blended; the result is dotted with the BRDF's
//! coefficients for the viewing direction.

use super::record::{frame_around, interpolate, RadianceRecord};
use crate::irradiance_cache::gather::{IrradianceCache, ShadingPoint};
use ircache_math::{Frame, Rgb, Vec3};

/// Indirect light the glossy lobe at `sp` reflects towards `wo` (world, unit) from the records
/// of level `depth`; `None` where the lobe is not cached, the view is one the material's order
/// does not serve, or no record with coefficients serves the point within twice the accuracy.
#[must_use]
pub fn glossy(cache: &IrradianceCache, sp: &ShadingPoint, depth: u32, wo: Vec3) -> Option<Rgb> {
    let tables = cache.radiance.as_deref()?;
    let brdf = tables.brdf_at(sp)?;
    let tilt = tables.tilt(brdf.order())?;
    let store = cache.levels.get(depth as usize)?;
    // The shading frame around the shading normal, its tangent from the normal alone, as the
    // records' frames are (coplanar records and points then share frames: R = I).
    let frame = Frame::from_z(sp.n_bump);
    let wo_local = frame.to_local(wo);
    if !brdf.serves(wo_local) {
        return None;
    }
    let f = frame_around(sp.n_bump);
    let mut records: Vec<(f64, &RadianceRecord)> = Vec::new();
    let finer = cache.coverage_threshold(sp);
    for threshold in [finer, 2.0 * finer] {
        records.clear();
        store.for_each_serving(sp.it.p, sp.n, threshold, |rec, w| {
            if let Some(r) = cache.radiance_records.get(rec.radiance as usize) {
                if r.radiance.order == brdf.order() {
                    records.push((f64::from(w), r));
                }
            }
        });
        if let Some(lambda) = interpolate(&records, sp.it.p.as_dvec3(), f, tilt) {
            return Some(brdf.reflect(wo_local, &lambda));
        }
    }
    None
}
