//! The splat buffer and Algorithm 3 of paper 001 (NOTES-001 §C.2): a record adds its weighted,
//! extrapolated irradiance (000 eq. 3.15) to every sample of the layer it serves, and, for a
//! radiance record, the light its rotated, extrapolated coefficients reflect through the
//! sample's BRDF towards the camera (3.19). The pixels visited are those inside the film
//! rectangle of the record's influence sphere (its validity radius: every metric's error
//! exceeds its threshold beyond it), grown by the pixel filter's reach.
//!
//! Bands of rows own their pixels and take their records in index order, so a pixel's sums do
//! not depend on the thread count. The glossy part sums the dot products before clamping, as
//! the lookup clamps the dot product of the blended coefficients.

use super::gbuffer::GBuffer;
use crate::irradiance_cache::gather::IrradianceCache;
use crate::irradiance_cache::record::extrapolate;
use crate::radiance_cache::brdf::clamped;
use crate::radiance_cache::lookup::GlossyView;
use crate::render::TILE;
use ircache_math::{Mat4, Rgb, Vec2};
use rayon::prelude::*;
use std::ops::Range;

/// One sample's sums.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SplatPixel {
    /// Σ w E′ (3.15's numerator).
    pub irradiance: Rgb,
    /// Σ w.
    pub weight: f32,
    /// Records that reached the sample.
    pub count: u32,
    /// The smallest normalised error among them (∞ when none): the sample is covered when it
    /// is at most the cache's coverage threshold there.
    pub min_error: f32,
    /// Σ w ⟨Rot(Λ + d·∇Λ), c(ωo)⟩ per channel over radiance records.
    pub glossy: [f64; 3],
    /// Σ w over those radiance records.
    pub glossy_weight: f64,
}

impl Default for SplatPixel {
    fn default() -> Self {
        SplatPixel {
            irradiance: Rgb::ZERO,
            weight: 0.0,
            count: 0,
            min_error: f32::INFINITY,
            glossy: [0.0; 3],
            glossy_weight: 0.0,
        }
    }
}

impl SplatPixel {
    /// The blended irradiance (clamped at zero, as the lookup's), `None` when no record reached.
    #[must_use]
    pub fn irradiance(&self) -> Option<Rgb> {
        (self.count > 0).then(|| (self.irradiance / self.weight).max(Rgb::ZERO))
    }

    /// The glossy radiance towards the camera, `None` when no radiance record reached.
    #[must_use]
    pub fn glossy(&self) -> Option<Rgb> {
        (self.glossy_weight > 0.0).then(|| clamped(self.glossy.map(|g| g / self.glossy_weight)))
    }
}

/// The splat buffer of one layer (SPLATBUFF, NOTES-001 §C.1).
#[derive(Clone, Debug)]
pub struct SplatBuffer {
    /// Image width.
    pub width: usize,
    /// Per sample, row-major.
    pub pixels: Vec<SplatPixel>,
}

impl SplatBuffer {
    /// A cleared buffer for `g`.
    #[must_use]
    pub fn new(g: &GBuffer) -> SplatBuffer {
        SplatBuffer {
            width: g.width,
            pixels: vec![SplatPixel::default(); g.width * g.height],
        }
    }

    /// Clears every sample's sums (for the next layer).
    pub fn clear(&mut self) {
        self.pixels
            .par_iter_mut()
            .for_each(|p| *p = SplatPixel::default());
    }
}

/// Where records are splatted: on the CPU ([`CpuSplatter`], [`splat`]) or on a GPU (the
/// `ircache-gpu` crate, which implements this for its device). Every implementation adds the
/// same sums to the same samples.
pub trait Splatter: Send + Sync + std::fmt::Debug {
    /// Splats level-0 records `ids` of `cache` into `buffer` over the samples of `g`, whose
    /// film samples stray up to `filter_reach` pixels from their pixel centres.
    fn splat(
        &self,
        buffer: &mut SplatBuffer,
        g: &GBuffer,
        cache: &IrradianceCache,
        ids: Range<usize>,
        camera: &crate::camera::Camera,
        filter_reach: f32,
    );
}

/// Splatting on the CPU's cores ([`splat`]).
#[derive(Clone, Copy, Debug, Default)]
pub struct CpuSplatter;

impl Splatter for CpuSplatter {
    fn splat(
        &self,
        buffer: &mut SplatBuffer,
        g: &GBuffer,
        cache: &IrradianceCache,
        ids: Range<usize>,
        camera: &crate::camera::Camera,
        filter_reach: f32,
    ) {
        splat(buffer, g, cache, ids, camera, filter_reach);
    }
}

/// Each record's pixel rectangle (x0, y0, x1, y1, exclusive ends) on a `w × h` film: the
/// pixels whose samples may lie in the film rectangle of its influence sphere, `None` where
/// that sphere is off the film or behind the camera. The same for every [`Splatter`].
#[must_use]
pub fn record_rects(
    cache: &IrradianceCache,
    ids: Range<usize>,
    camera: &crate::camera::Camera,
    size: (usize, usize),
    filter_reach: f32,
) -> Vec<Option<[usize; 4]>> {
    record_rects_at(cache, ids, camera, size, filter_reach, 1.0)
}

/// [`record_rects`] for records serving up to error `threshold`: every metric's error grows
/// with the distance as dist / R, so the influence sphere's radius grows `threshold`-fold.
#[must_use]
pub fn record_rects_at(
    cache: &IrradianceCache,
    ids: Range<usize>,
    camera: &crate::camera::Camera,
    (w, h): (usize, usize),
    filter_reach: f32,
    threshold: f32,
) -> Vec<Option<[usize; 4]>> {
    let Some(store) = cache.levels.first() else {
        return Vec::new();
    };
    let to_camera: Mat4 = camera.to_world.inverse();
    ids.into_par_iter()
        .map(|id| {
            let (centre, reach) = store.reach(id as u32);
            let bounds = camera.sphere_bounds(&to_camera, centre, reach * threshold)?;
            pixel_rect(bounds, w, h, filter_reach)
        })
        .collect()
}

/// The pixel rectangle (x0, y0, x1, y1), exclusive ends, whose samples may lie in the film
/// rectangle `bounds`: samples stray up to `reach` pixels from their pixel's centre.
fn pixel_rect(bounds: (Vec2, Vec2), w: usize, h: usize, reach: f32) -> Option<[usize; 4]> {
    let (lo, hi) = bounds;
    let clamp = |v: f32, n: usize| -> f32 { v.clamp(-1.0, n as f32 + 1.0) };
    // A sample of pixel x lies in [x + 0.5 − reach, x + 0.5 + reach]; a hundredth of a pixel
    // more for the rounding of the bounds.
    let reach = reach + 0.01;
    let x0 = clamp((lo.x * w as f32 - 0.5 - reach).floor(), w);
    let y0 = clamp((lo.y * h as f32 - 0.5 - reach).floor(), h);
    let x1 = clamp((hi.x * w as f32 - 0.5 + reach).floor() + 1.0, w);
    let y1 = clamp((hi.y * h as f32 - 0.5 + reach).floor() + 1.0, h);
    let (x0, y0) = (x0.max(0.0) as usize, y0.max(0.0) as usize);
    let (x1, y1) = ((x1.max(0.0) as usize).min(w), (y1.max(0.0) as usize).min(h));
    (x0 < x1 && y0 < y1).then_some([x0, y0, x1, y1])
}

/// Splats level-0 records `ids` of `cache` into `buffer` over the samples of `g`, whose film
/// samples stray up to `filter_reach` pixels from their pixel centres.
pub fn splat(
    buffer: &mut SplatBuffer,
    g: &GBuffer,
    cache: &IrradianceCache,
    ids: Range<usize>,
    camera: &crate::camera::Camera,
    filter_reach: f32,
) {
    splat_parts(buffer, g, cache, ids, camera, filter_reach, Sums::All);
}

/// Which sums a splat adds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sums {
    /// Irradiance and glossy.
    All,
    /// The radiance records' glossy sums alone, for a splatter that adds the irradiance sums
    /// itself (the GPU's).
    Glossy,
}

/// [`splat`], adding the sums `sums`.
pub fn splat_parts(
    buffer: &mut SplatBuffer,
    g: &GBuffer,
    cache: &IrradianceCache,
    ids: Range<usize>,
    camera: &crate::camera::Camera,
    filter_reach: f32,
    sums: Sums,
) {
    let Some(store) = cache.levels.first() else {
        return;
    };
    let (w, h) = (g.width, g.height);
    // Each record's rectangle, filed under the bands of rows it touches.
    let bands = h.div_ceil(TILE);
    let rects = record_rects(cache, ids.clone(), camera, (w, h), filter_reach);
    let mut per_band: Vec<Vec<(u32, [usize; 4])>> = vec![Vec::new(); bands];
    for (id, rect) in ids.clone().zip(&rects) {
        if let Some(r) = rect {
            for list in &mut per_band[r[1] / TILE..r[3].div_ceil(TILE)] {
                list.push((id as u32, *r));
            }
        }
    }
    let mode = cache.params.gradients;
    let records = store.records();
    buffer
        .pixels
        .par_chunks_mut(w * TILE)
        .zip(g.samples.par_chunks(w * TILE))
        .zip(per_band.par_iter())
        .enumerate()
        .for_each(|(band, ((pixels, samples), list))| {
            if list.is_empty() {
                return;
            }
            let y_band = band * TILE;
            // Set up lazily: most samples never meet a radiance record.
            let mut views: Vec<Option<Option<GlossyView>>> = Vec::new();
            let mut seen = Vec::new();
            for &(id, [x0, y0, x1, y1]) in list {
                let rec = &records[id as usize];
                let radiance = cache.radiance_records.get(rec.radiance as usize);
                for y in y0.max(y_band)..y1.min(y_band + TILE) {
                    for x in x0..x1 {
                        let i = (y - y_band) * w + x;
                        let Some(sp) = &samples[i].point else {
                            continue;
                        };
                        let Some(err) = store.error(rec, sp.it.p, sp.n) else {
                            continue;
                        };
                        if err > 1.0 {
                            continue;
                        }
                        let px = &mut pixels[i];
                        if sums == Sums::All {
                            let weight = store.weight(err, 1.0);
                            px.irradiance += extrapolate(rec, sp.it.p, sp.n_bump, mode) * weight;
                            px.weight += weight;
                            px.count += 1;
                            px.min_error = px.min_error.min(err);
                        }
                        let Some(r) = radiance else {
                            continue;
                        };
                        if views.is_empty() {
                            views.resize_with(samples.len(), || None);
                        }
                        let view = views[i]
                            .get_or_insert_with(|| GlossyView::new(cache, sp, -samples[i].ray.d));
                        let Some(view) = view else {
                            continue;
                        };
                        if err > view.threshold
                            || r.radiance.order != view.order
                            || !r.seen_from_into(
                                sp.it.p.as_dvec3(),
                                view.frame,
                                view.tilt,
                                &mut seen,
                            )
                        {
                            continue;
                        }
                        let weight = f64::from(store.weight(err, view.threshold));
                        for (g, dot) in px.glossy.iter_mut().zip(view.reflect_unclamped(&seen)) {
                            *g += weight * dot;
                        }
                        px.glossy_weight += weight;
                    }
                }
            }
        });
}
