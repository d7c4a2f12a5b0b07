//! Photon tracing (Jensen, *Realistic Image Synthesis Using Photon Mapping*, ch. 5; 001 §2.4):
//! photons leave the emitters ([`crate::lights::emission`]), scatter through every BSDF with
//! Russian roulette, and are stored where they land on a surface with a Lambertian part.
//!
//! - The **global** map keeps photons that scattered at least once before landing: the direct
//!   light is always computed by light samples, so direct photons would count it twice
//!   (NOTES-001 E.7).
//! - The **caustic** map keeps photons that reached their surface through delta lobes only
//!   (glass, mirrors: L S+ D), traced in a pass of their own so that it can be much denser, and
//!   aimed at the bounding spheres of the surfaces with delta lobes
//!   ([`crate::lights::emission::Targets`]); a scene without such surfaces has no caustic photons.
//!
//! Flux through a BSDF: a photon arriving from `ω_in` leaves along `ω_out` sampled from the BSDF
//! with `ω_in` in the place of the viewer, weight `f cos θ_out / p`; refraction does not scale
//! flux by `η²` as it scales radiance, so the sample's radiance factor is undone. Shading-normal
//! asymmetry (Veach §5.3) is not corrected.
//!
//! In media (002; scenes with `null` boundaries), a photon crosses boundaries without a bounce.
//! A global photon scatters in a medium as a `volpath` path does (free flight by delta tracking,
//! the phase function sampled; each scattering a bounce), so the global map holds all the light
//! that reaches its surfaces after a bounce, the medium's included (not a medium's own
//! emission: media cache scenes with emitting media take no global map). A caustic photon never
//! scatters in a medium: each segment keeps the share that crosses it unscattered, the
//! transmittance (closed form, or ratio tracking in grids), with Russian roulette, so the
//! caustic map holds L S+ D light that met no medium on the way, whose complement the paths
//! hold exactly.
//!
//! Parallel and deterministic: photon `i` draws from its own random stream, keyed by the seed
//! and `i`; photons are traced in fixed batches and kept in emission order, whatever the
//! threads. Each pass emits batches until it has stored the number asked for (as Radiance's
//! `-apg` and Mitsuba 0.6's `globalPhotons` count stored photons), at most
//! [`MAX_EMITTED_PER_STORED`] times as many emitted, or fewer where the rate of storing says
//! the cap would hold under a tenth of the number asked; the flux of every photon is divided by
//! the number emitted in its pass.

use super::photon::Photon;
use crate::lights::emission::Targets;
use crate::lights::is_positive_finite;
use crate::media::tracking::{
    across_boundary, medium_after, medium_at, sample_flight, transmittance, Flight,
};
use crate::scene::{Scene, ShapeGeometry};
use ircache_math::ray::offset_ray_origin;
use ircache_math::{Ray, Rgb, Rng, Vec2, Vec3};
use rayon::prelude::*;

/// Which photons a pass keeps.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MapKind {
    /// Photons after at least one bounce, any lobes.
    Global,
    /// Photons after one or more delta-lobe bounces only.
    Caustic,
    /// Every photon, direct ones too (a view of the photons, and tests).
    All,
}

/// What a tracing pass did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TraceStats {
    /// Photons emitted (the flux divisor).
    pub emitted: u64,
    /// Photons stored.
    pub stored: u64,
    /// Rays traced.
    pub rays: u64,
}

/// A pass gives up after emitting this many photons per photon asked for (a scene whose light
/// rarely reaches a Lambertian surface, or has no glass for caustics).
pub const MAX_EMITTED_PER_STORED: u64 = 64;

/// Photons of one pass never bounce more than this (their flux is negligible by then).
const MAX_BOUNCES: u16 = 256;

/// Photons per batch (the unit of parallel work and of the stopping rule).
const BATCH: u64 = 1 << 14;

const PHOTON_SALT: u64 = 0x7068_6f74_6f6e;

/// Traces photons until `wanted` are stored in a map of `kind`, keeping only those that can
/// serve a path of `max_bounces` bounces before landing. Returns the photons (flux divided by
/// the number emitted) and what it did.
#[must_use]
pub fn trace_photons(
    scene: &Scene,
    kind: MapKind,
    wanted: u64,
    max_bounces: u16,
    seed: u64,
) -> (Vec<Photon>, TraceStats) {
    trace_photons_within(
        scene,
        kind,
        wanted,
        max_bounces,
        seed,
        MAX_EMITTED_PER_STORED,
    )
}

/// [`trace_photons`], emitting at most `emitted_per_stored` photons per photon wanted.
#[must_use]
pub fn trace_photons_within(
    scene: &Scene,
    kind: MapKind,
    wanted: u64,
    max_bounces: u16,
    seed: u64,
    emitted_per_stored: u64,
) -> (Vec<Photon>, TraceStats) {
    let mut stats = TraceStats::default();
    let mut photons: Vec<Photon> = Vec::new();
    if wanted == 0 || scene.lights.is_empty() || (max_bounces == 0 && kind != MapKind::All) {
        return (photons, stats);
    }
    let max_bounces = max_bounces.min(MAX_BOUNCES);
    // Caustic photons are aimed at the surfaces with delta lobes; without any, there are none.
    let targets = (kind == MapKind::Caustic).then(|| caustic_targets(scene));
    if targets.as_ref().is_some_and(Targets::is_empty) {
        return (photons, stats);
    }
    let limit = wanted.saturating_mul(emitted_per_stored);
    while (photons.len() as u64) < wanted && stats.emitted < limit {
        let first = stats.emitted;
        let batches: Vec<(Vec<Photon>, u64)> = (0..4u64)
            .into_par_iter()
            .map(|part| {
                let mut out = Vec::new();
                let mut rays = 0;
                let quarter = BATCH / 4;
                for i in first + part * quarter..first + (part + 1) * quarter {
                    rays += trace_one(
                        scene,
                        kind,
                        targets.as_ref(),
                        max_bounces,
                        seed,
                        i,
                        &mut out,
                    );
                }
                (out, rays)
            })
            .collect();
        for (batch, rays) in batches {
            photons.extend(batch);
            stats.rays += rays;
        }
        stats.emitted += BATCH;
        // Where light mostly leaves the scene before it may be stored (lamps over an open
        // floor), emitting up to the cap would spend its time on a map of almost nothing: stop
        // once the rate so far says the cap would hold under a tenth of what was asked.
        let stored = photons.len() as u64;
        if stats.emitted >= wanted
            && stored.saturating_mul(limit).saturating_mul(10)
                < wanted.saturating_mul(stats.emitted)
        {
            break;
        }
    }
    let scale = 1.0 / stats.emitted as f32;
    for p in &mut photons {
        p.flux *= scale;
    }
    stats.stored = photons.len() as u64;
    (photons, stats)
}

/// Russian roulette on a photon whose flux a step scales by `weight`: it goes on with
/// probability min(max(`weight`), 1), its flux times `weight` over that, so that the flux per
/// photon stays about even (Jensen §5.2.1); false where it ends.
fn survives(flux: &mut Rgb, weight: Rgb, rng: &mut Rng) -> bool {
    let q = weight.max_channel().min(1.0);
    if !is_positive_finite(q) || rng.next_f32() >= q {
        return false;
    }
    *flux = *flux * weight / q;
    true
}

/// The bounding spheres of the shapes whose material has a delta lobe (emitters left out).
#[must_use]
pub fn caustic_targets(scene: &Scene) -> Targets {
    let spheres = scene
        .shapes
        .iter()
        .filter(|s| s.area_light.is_none())
        .filter(|s| !s.thin_sheet && scene.materials[s.material].at(Vec2::ZERO).has_delta())
        .filter_map(|s| match &s.geometry {
            ShapeGeometry::Sphere { center, radius, .. } => Some((*center, *radius)),
            ShapeGeometry::Mesh(m) => {
                let (lo, hi) = m.positions.iter().fold(
                    (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
                    |(lo, hi), &p| (lo.min(p), hi.max(p)),
                );
                (lo.x <= hi.x).then(|| ((lo + hi) * 0.5, (hi - lo).length() * 0.5))
            }
        })
        .filter(|&(_, r)| r > 0.0 && r.is_finite())
        .collect();
    Targets::new(spheres, scene.center, scene.radius)
}

/// Traces photon `index`, appending what it stores to `out`; returns the rays traced.
fn trace_one(
    scene: &Scene,
    kind: MapKind,
    targets: Option<&Targets>,
    max_bounces: u16,
    seed: u64,
    index: u64,
    out: &mut Vec<Photon>,
) -> u64 {
    let mut rng = Rng::keyed(seed, &[PHOTON_SALT, index]);
    let (u_select, u_pick) = (rng.next_f32(), rng.next_f32());
    let (u_position, u_direction) = (rng.next_2d(), rng.next_2d());
    let emitted = match targets {
        Some(t) => {
            scene
                .lights
                .sample_emission_towards(t, (u_select, u_pick), u_position, u_direction)
        }
        None => scene
            .lights
            .sample_emission(u_select, u_position, u_direction),
    };
    let Some(emitted) = emitted else {
        return 0;
    };
    let origin = match emitted.normal {
        Some(n) => offset_ray_origin(emitted.origin, n, emitted.direction, scene.scale),
        None => emitted.origin,
    };
    let mut ray = Ray::new(origin, emitted.direction);
    let mut flux: Rgb = emitted.flux;
    let mut rays = 0u64;
    let mut bounces: u16 = 0;
    let mut delta_only = true;
    // Thin sheets and `null` boundaries met so far (a bound against a ray caught at one).
    let mut crossings = 0u32;
    // The medium the photon travels in (see the module for where it scatters).
    let mut medium = if scene.has_media() {
        medium_at(scene, origin, emitted.direction)
    } else {
        None
    };
    loop {
        rays += 1;
        let Some(it) = scene.intersect(&ray) else {
            break;
        };
        if let Some(m) = medium {
            let med = &scene.media[m];
            if kind == MapKind::Caustic {
                // The share that crosses the segment unscattered.
                let tr = transmittance(med, ray.o, ray.d, it.t, &mut rng);
                if !survives(&mut flux, tr, &mut rng) {
                    break;
                }
            } else {
                // Free flight: a scattering in the medium is a bounce, as in `volpath`.
                let (mut weight, mut emitted) = (Rgb::ONE, Rgb::ZERO);
                let flight =
                    sample_flight(med, ray.o, ray.d, it.t, &mut weight, &mut emitted, &mut rng);
                if flight == Flight::Absorbed
                    || (bounces + 1 > max_bounces && flight != Flight::Passed)
                {
                    break;
                }
                if !survives(&mut flux, weight, &mut rng) {
                    break;
                }
                if let Flight::Scattered { t, .. } = flight {
                    let (d, _) = med.phase.sample(ray.d, rng.next_2d());
                    bounces += 1;
                    delta_only = false;
                    ray = Ray::new(ray.o + ray.d * t, d);
                    continue;
                }
            }
        }
        let incoming = -ray.d;
        let shape = &scene.shapes[it.shape as usize];
        if shape.null {
            // A medium's boundary: crossed without a bounce, into the medium beyond.
            let Some(next) = across_boundary(scene, &it, ray.d, medium, &mut crossings) else {
                break;
            };
            (ray, medium) = next;
            continue;
        }
        if shape.masked && rng.next_f32() >= scene.materials[shape.material].opacity(it.uv) {
            // A mask's open part: crossed, as light samples cross it.
            crossings += 1;
            if crossings > crate::scene::MAX_SHEET_CROSSINGS {
                break;
            }
            medium = medium_after(shape.media, it.ng, ray.d, medium);
            ray = scene.spawn_ray(&it, ray.d);
            continue;
        }
        if let Some(sheet) = scene.thin_sheet(&it, ray.d) {
            crossings += 1;
            if crossings > crate::scene::MAX_SHEET_CROSSINGS {
                break;
            }
            // A window pane: crossed without a bounce, as light samples cross it (the light
            // beyond it stays direct light, which the photons must not hold twice).
            // Reflected (a delta bounce) with probability R'.
            let cos = it.frame.n.dot(incoming);
            let choice = sheet.choose(cos, rng.next_f32());
            let reflected = choice.reflected;
            if reflected && bounces + 1 > max_bounces {
                break;
            }
            let (scale, d) = if reflected {
                (choice.weight, 2.0 * cos * it.frame.n - incoming)
            } else {
                (choice.weight, ray.d)
            };
            if !survives(&mut flux, scale, &mut rng) {
                break;
            }
            bounces += u16::from(reflected);
            medium = medium_after(shape.media, it.ng, d, medium);
            ray = scene.spawn_ray(&it, d);
            continue;
        }
        let bsdf = it.bsdf(&scene.materials[shape.material], -incoming);
        let wo_local = it.frame.to_local(incoming);
        if (bounces >= 1 || kind == MapKind::All) && !bsdf.lambertian_albedo(wo_local).is_black() {
            let normal = if it.ng.dot(incoming) < 0.0 {
                -it.ng
            } else {
                it.ng
            };
            out.push(Photon {
                position: it.p,
                normal,
                incoming,
                flux,
                bounces,
                distance: it.t,
                caustic: bounces >= 1 && delta_only,
            });
        }
        // (A smooth `trans` may be crossed without a bounce: decided after sampling.)
        if bounces + 1 > max_bounces && !shape.straight_trans {
            break;
        }
        let Some(bs) = bsdf.sample_adjoint(wo_local, rng.next_f32(), rng.next_2d()) else {
            break;
        };
        // A caustic photon leaves the pass at its first non-delta bounce.
        if kind == MapKind::Caustic && !bs.delta {
            break;
        }
        let wo = it.frame.from_local(bs.wi);
        if (wo.dot(it.ng) > 0.0) != (bs.wi.z > 0.0) && !bs.delta {
            break;
        }
        // Light from a point, spot or sun straight through a smooth `trans` is direct light
        // (light samples pass it, as Radiance's shadow rays do): crossed without a bounce, so
        // that no map holds it twice.
        let direct_through = emitted.from_delta_light
            && bounces == 0
            && bs.delta
            && shape.straight_trans
            && wo.dot(ray.d) > 1.0 - 1e-6;
        if !direct_through && bounces + 1 > max_bounces {
            break;
        }
        delta_only &= bs.delta;
        // Flux is not scaled by η² across a refraction (radiance is).
        let weight = bs.weight * (bs.eta * bs.eta) * scene.perturbed_shadowing(&it, wo);
        if !survives(&mut flux, weight, &mut rng) {
            break;
        }
        if direct_through {
            crossings += 1;
            if crossings > crate::scene::MAX_SHEET_CROSSINGS {
                break;
            }
        } else {
            bounces += 1;
        }
        medium = medium_after(shape.media, it.ng, wo, medium);
        ray = scene.spawn_ray(&it, wo);
    }
    rays
}
