//! The renderer: from a [`ircache_scene::SceneDesc`] to an image.
//!
//! - [`scene`]: the render-time scene: Embree geometry, materials and lights, surface interactions.
//! - [`camera`], [`film`]: primary rays and pixel filters.
//! - [`sampler`]: where a pixel sample's coordinates come from (Mitsuba 3's samplers, Sobol').
//! - [`texture`], [`bsdf`]: materials with importance sampling (Mitsuba 3's models).
//! - [`lights`]: emitters with importance sampling, for next-event estimation and MIS.
//! - [`media`]: participating media: phase functions, grids, delta and ratio tracking (002).
//! - [`media_cache`]: irradiance gradients through media and occlusions (002, begun).
//! - [`integrators`]: `direct`, `path` and `volpath` (the unbiased references).
//! - [`irradiance_cache`]: Ward's irradiance cache with gradients (the `ic` integrator's records).
//! - [`radiance_cache`]: radiance caching of glossy light in hemispherical harmonics (issue 10, begun).
//! - [`splatting`]: radiance cache splatting and the progressive walkthrough (001 ch. 4).
//! - [`photon_map`]: photon tracing, the global and caustic maps, density estimation (001 §2.4, ch. 6).
//! - [`temporal`]: animations: temporal radiance caching, age-based invalidation (001 ch. 5).
//! - [`render`]: the parallel, deterministic tile loop; [`adaptive`]: adaptive pixel sampling.

pub mod adaptive;
pub mod bsdf;
pub mod camera;
pub mod film;
pub mod integrators;
pub mod irradiance_cache;
pub mod lights;
pub mod media;
pub mod media_cache;
pub mod photon_map;
pub mod radiance_cache;
pub mod render;
pub mod sampler;
pub mod scene;
pub mod splatting;
pub mod temporal;
pub mod testing;
pub mod texture;
