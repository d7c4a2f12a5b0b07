//! The irradiance-cache integrator (`ic`, `<integrator type="irrcache">`): per pixel sample,
//! emission, direct light (light and BSDF sampling combined by MIS) and specular reflection and
//! refraction are computed as a path tracer would; the diffuse indirect light at the first
//! non-specular surface is ρ/π times the irradiance interpolated from the level-0 cache
//! (000 eq. 3.15). The cache is filled before the pixels are rendered (see
//! [`crate::irradiance_cache::build`]).
//!
//! Glossy interreflection (the non-Lambertian part of indirect light) is not in the cache and is
//! left out; the scenes this targets are diffuse.

use super::direct::estimate_direct;
use super::RayCounts;
use crate::irradiance_cache::gather::{mix, Deeper, Gatherer, ShadingPoint, WorkState};
use crate::irradiance_cache::hemisphere::Stratification;
use crate::irradiance_cache::{IcParams, IrradianceCache};
use crate::scene::Scene;
use ircache_embree::Hit;
use ircache_math::{Ray, Rgb, Rng, INV_PI};
use ircache_scene::{IntegratorDesc, ParamValue};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;

/// The `ic` integrator with its cache (filled by the renderer before the pixel pass).
#[derive(Clone, Debug)]
pub struct IcIntegrator {
    /// Cache settings.
    pub params: IcParams,
    /// Hide emitters seen directly.
    pub hide_emitters: bool,
    /// The filled cache; `None` until the pre-pass has run.
    pub cache: Option<Arc<IrradianceCache>>,
    /// Seed of the records made during the pixel pass.
    pub seed: u64,
    /// Pixel samples no record reached even at twice the accuracy (a record was gathered for
    /// them alone and not kept).
    pub uncached_samples: Arc<AtomicU64>,
    /// Persistent cache file: read before the pre-pass, new records appended batch by batch.
    pub cache_file: Option<std::path::PathBuf>,
    /// Use a cache file made for another scene or with other settings anyway.
    pub force_reuse: bool,
    /// Surfaces excluded from the cache (003 item 6).
    pub exclusions: Exclusions,
}

/// Which surfaces take no cache records (Radiance's `-ae`/`-aE` and `-ai`/`-aI`): they get the
/// ambient value as their indirect light, a much cheaper estimate.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub enum Exclusions {
    /// Every surface takes records.
    #[default]
    None,
    /// These names (shape ids in XML, material names in OBJ) take none.
    Exclude(Vec<String>),
    /// Only these names take records.
    Include(Vec<String>),
}

impl Exclusions {
    /// Per shape, whether it is excluded; names that match no shape are an error.
    pub fn resolve(&self, scene: &Scene) -> Result<Vec<bool>, String> {
        let names = match self {
            Exclusions::None => return Ok(vec![false; scene.shapes.len()]),
            Exclusions::Exclude(n) | Exclusions::Include(n) => n,
        };
        for n in names {
            if !scene.shapes.iter().any(|s| s.name.as_deref() == Some(n)) {
                let mut known: Vec<&str> = scene
                    .shapes
                    .iter()
                    .filter_map(|s| s.name.as_deref())
                    .collect();
                known.sort_unstable();
                known.dedup();
                return Err(format!(
                    "no surface is named \"{n}\" (names: {})",
                    if known.is_empty() {
                        "none".into()
                    } else {
                        known.join(", ")
                    }
                ));
            }
        }
        let listed = |s: &crate::scene::Shape| s.name.as_ref().is_some_and(|x| names.contains(x));
        Ok(scene
            .shapes
            .iter()
            .map(|s| match self {
                Exclusions::Include(_) => !listed(s),
                _ => listed(s),
            })
            .collect())
    }

    /// A hash of the list, folded into a cache file's scene hash (exclusions change records).
    #[must_use]
    pub fn hash(&self) -> u64 {
        use std::fmt::Write;
        let mut h = crate::irradiance_cache::file::Fnv::default();
        let _ = write!(h, "{self:?}");
        if *self == Exclusions::None {
            0
        } else {
            h.0
        }
    }
}

impl IcIntegrator {
    /// Builds the integrator from a scene's `<integrator type="irrcache">` (or any integrator
    /// description whose type was overridden to `ic`): `max_depth` N gives N − 2 bounces unless
    /// `bounces` is given; further parameters are [`IcParams::set`]'s names.
    pub fn from_desc(desc: &IntegratorDesc) -> Result<IcIntegrator, String> {
        let mut params = IcParams::default();
        if desc.max_depth >= 0 {
            params.bounces = (desc.max_depth - 2).max(0) as u32;
        }
        for (name, value, loc) in &desc.extra {
            let text = match value {
                ParamValue::Integer(v) => v.to_string(),
                ParamValue::Float(v) => v.to_string(),
                ParamValue::Boolean(v) => v.to_string(),
                ParamValue::String(v) => v.clone(),
                ParamValue::Rgb(c) => format!("{} {} {}", c.r, c.g, c.b),
            };
            params.set(name, &text).map_err(|e| format!("{loc}: {e}"))?;
        }
        Ok(IcIntegrator {
            params,
            hide_emitters: desc.hide_emitters,
            cache: None,
            seed: 0,
            uncached_samples: Arc::new(AtomicU64::new(0)),
            cache_file: None,
            force_reuse: false,
            exclusions: Exclusions::None,
        })
    }

    /// Radiance along the camera ray `ray`, whose closest hit `first_hit` the caller traced.
    pub fn li(
        &self,
        scene: &Scene,
        ray: &Ray,
        first_hit: Option<&Hit>,
        rng: &mut Rng,
        rays: &mut RayCounts,
    ) -> Rgb {
        let mut l = Rgb::ZERO;
        let mut beta = Rgb::ONE;
        let mut ray = *ray;
        for depth in 0..8u32 {
            let hit = if depth == 0 {
                first_hit.map(|h| scene.interaction(&ray, h))
            } else {
                rays.bounce += 1;
                scene.intersect(&ray)
            };
            let visible = !(depth == 0 && self.hide_emitters);
            let Some(it) = hit else {
                if visible {
                    l += beta * scene.lights.environment_radiance(ray.d);
                }
                break;
            };
            let wo = -ray.d;
            let shape = &scene.shapes[it.shape as usize];
            if let (Some(light), true) = (shape.area_light, visible) {
                l += beta * scene.lights.area_radiance(light, it.frame.n, wo);
            }
            let bsdf = scene.materials[shape.material].at(it.uv);
            let wo_local = it.frame.to_local(wo);
            if !bsdf.has_smooth() {
                // Specular: follow the sampled lobe (deterministic chains stay sharp).
                let (u_lobe, u) = (rng.next_f32(), rng.next_2d());
                let Some(bs) = bsdf.sample(wo_local, u_lobe, u) else {
                    break;
                };
                beta *= bs.weight;
                if beta.is_black() {
                    break;
                }
                ray = scene.spawn_ray(&it, it.frame.from_local(bs.wi));
                continue;
            }
            // Direct light: light samples (one when the only light is a delta light, where
            // all samples are alike), plus a BSDF sample where the BSDF is not Lambertian.
            let ne = if scene.lights.all_delta() && scene.lights.len() == 1 {
                1
            } else {
                self.params.direct_samples.max(1)
            };
            let nb = u32::from(!bsdf.is_diffuse_only());
            l += beta * estimate_direct(scene, &it, &bsdf, wo_local, ne, nb, rng, rays);
            let albedo = bsdf.lambertian_albedo(wo_local);
            if !albedo.is_black() {
                let excluded = self.cache.as_ref().is_some_and(|c| c.is_excluded(it.shape));
                let e = if self.params.bounces == 0 || excluded {
                    let av = self
                        .cache
                        .as_ref()
                        .map_or(self.params.ambient_value, |c| c.ambient);
                    av * std::f32::consts::PI
                } else {
                    self.indirect_irradiance(scene, &ShadingPoint::facing(it, wo), rng, rays)
                };
                l += beta * albedo * e * INV_PI;
            }
            break;
        }
        l
    }

    /// Level-0 indirect irradiance at `sp`: interpolated at the accuracy `a`; else from records
    /// up to 4a away (pixel samples off the pre-pass's pixel centres); else from a record
    /// gathered for this sample alone.
    fn indirect_irradiance(
        &self,
        scene: &Scene,
        sp: &ShadingPoint,
        rng: &mut Rng,
        rays: &mut RayCounts,
    ) -> Rgb {
        let fresh;
        let cache = match &self.cache {
            Some(c) => c.as_ref(),
            None => {
                fresh = IrradianceCache::new(scene, &self.params);
                &fresh
            }
        };
        let store = &cache.levels[0];
        for threshold in [1.0, 2.0, 4.0] {
            if let Some(i) =
                store.interpolate(sp.it.p, sp.n, sp.n_bump, threshold, self.params.gradients)
            {
                return i.e;
            }
        }
        self.uncached_samples.fetch_add(1, Ordering::Relaxed);
        let g = Gatherer {
            scene,
            cache,
            seed: self.seed,
            deeper: Deeper::Cache,
        };
        let mut st = WorkState::new(cache.levels.len());
        let key = mix(
            0x0070_6978_656c,
            u64::from(rng.next_u32()) << 32 | u64::from(rng.next_u32()),
        );
        // It serves this sample alone (thin or newly seen geometry): a quarter of the divisions.
        let strata = Stratification::from_divisions((self.params.divisions / 4).max(16));
        let rec = g.record_with(&mut st, sp, 0, key, strata);
        rays.gather += st.counts.gather_rays;
        rays.shadow += st.counts.shadow_rays;
        rec.e
    }
}
