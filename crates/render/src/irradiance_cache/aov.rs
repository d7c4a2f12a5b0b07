//! Seeing the cache: the interpolated indirect irradiance per pixel, the photon maps'
//! irradiance, the glossy light shaded from radiance records, and the record positions drawn as
//! dots over an image (as in 004's first figure).

use super::build::first_diffuse_point;
use super::gather::{IrradianceCache, ShadingPoint};
use crate::scene::Scene;
use ircache_image::Image;
use ircache_math::{Rgb, Vec2};
use rayon::prelude::*;

/// The level-0 indirect irradiance interpolated at each pixel centre's first diffuse surface
/// (black where there is none or no record reaches within twice the accuracy).
#[must_use]
pub fn irradiance_image(
    scene: &Scene,
    cache: &IrradianceCache,
    width: usize,
    height: usize,
) -> Image {
    per_pixel_centre(scene, width, height, |ray| {
        first_diffuse_point(scene, ray, 1)
            .and_then(|sp| {
                [1.0, 2.0].into_iter().find_map(|m| {
                    cache.levels[0].interpolate(sp.it.p, sp.n, sp.n_bump, m, cache.params.gradients)
                })
            })
            .map_or(Rgb::ZERO, |i| i.e)
    })
}

/// The indirect irradiance the photon maps give at each pixel centre's first diffuse surface:
/// the global map's (photons of one or more bounces, as a gather hit reads them) plus the
/// caustic map's (black without maps).
#[must_use]
pub fn photon_image(scene: &Scene, cache: &IrradianceCache, width: usize, height: usize) -> Image {
    let Some(maps) = cache.photons.as_deref() else {
        return Image::new(width, height);
    };
    per_pixel_centre(scene, width, height, |ray| {
        first_diffuse_point(scene, ray, 1).map_or(Rgb::ZERO, |sp| {
            let global = maps
                .global
                .irradiance(sp.it.p, sp.n, u16::MAX, &maps.global_lookup);
            let caustic = maps.caustic.as_ref().map_or(Rgb::ZERO, |c| {
                c.irradiance(sp.it.p, sp.n, u16::MAX, &maps.caustic_lookup)
            });
            global + caustic
        })
    })
}

/// An image of `f` along the camera ray through each pixel centre.
fn per_pixel_centre(
    scene: &Scene,
    width: usize,
    height: usize,
    f: impl Fn(&ircache_math::Ray) -> Rgb + Sync,
) -> Image {
    let pixels: Vec<Rgb> = (0..width * height)
        .into_par_iter()
        .with_max_len(256)
        .map(|i| {
            let film = Vec2::new(
                ((i % width) as f32 + 0.5) / width as f32,
                ((i / width) as f32 + 0.5) / height as f32,
            );
            f(&scene.camera.generate_ray(film))
        })
        .collect();
    let mut image = Image::new(width, height);
    for (i, c) in pixels.into_iter().enumerate() {
        image.set(i % width, i / width, c);
    }
    image
}

/// The indirect light that the first surface each pixel centre sees reflects towards the camera
/// by its radiance-cached glossy lobe, shaded from the level-0 radiance records (black where the
/// surface's lobe is not cached, the view is traced, or no record serves).
#[must_use]
pub fn glossy_image(scene: &Scene, cache: &IrradianceCache, width: usize, height: usize) -> Image {
    per_pixel_centre(scene, width, height, |ray| {
        scene
            .intersect(ray)
            .and_then(|it| {
                let sp = ShadingPoint::facing(it, -ray.d);
                crate::radiance_cache::lookup::glossy(cache, &sp, 0, -ray.d)
            })
            .unwrap_or(Rgb::ZERO)
    })
}

/// `image` with a dot at every level-0 record visible from the camera: red (cyan for records
/// that also hold radiance coefficients), one pixel plus its four neighbours, bright enough to
/// show at any exposure.
#[must_use]
pub fn record_overlay(scene: &Scene, cache: &IrradianceCache, image: &Image) -> Image {
    let (w, h) = (image.width, image.height);
    let mut out = image.clone();
    let peak = (0..w * h)
        .map(|i| image.get(i % w, i / w).max_channel())
        .fold(0.0f32, f32::max)
        .max(1.0);
    for rec in cache.levels[0].records() {
        let dot = if rec.radiance == super::record::NO_RADIANCE {
            Rgb::new(peak, 0.0, 0.0)
        } else {
            Rgb::new(0.0, peak, peak)
        };
        let Some(film) = scene.camera.project(rec.p) else {
            continue;
        };
        // Only records on the surface the camera sees.
        let (ray, dist) = scene.camera.ray_to(rec.p);
        let visible = scene
            .accel
            .intersect(&ray)
            .is_none_or(|hit| (hit.t - dist).abs() <= 1e-3 * dist);
        if !visible {
            continue;
        }
        let (x, y) = ((film.x * w as f32) as i64, (film.y * h as f32) as i64);
        for (dx, dy) in [(0, 0), (1, 0), (-1, 0), (0, 1), (0, -1)] {
            let (px, py) = (x + dx, y + dy);
            if px >= 0 && py >= 0 && (px as usize) < w && (py as usize) < h {
                out.set(px as usize, py as usize, dot);
            }
        }
    }
    out
}
