//! Ward's irradiance cache with Ward–Heckbert gradients (papers 000 §3.1–3.6, 004, 003, 001
//! §2.2.5), per-bounce caches, filled in parallel and deterministically.
//!
//! - [`record`]: the record (plain data), the split-sphere weight (3.10) and 3.15's
//!   extrapolation.
//! - [`hemisphere`]: stratified gather samples and what is computed from them: irradiance (3.4),
//!   harmonic mean distance (3.8), rotational (3.29) and translational (3.47, 3.48) gradients.
//! - [`store`]: the records of one bounce level with their spatial index (a multi-level hash
//!   grid in the role of Radiance's octree) and interpolation.
//! - [`params`]: accuracy, divisions, resolution, bounces, ambient value, gradients.
//! - [`gather`]: computing a record: gather rays, shading what they hit, radius limits.
//! - [`file`]: the persistent cache file (versioned header, checksummed records).
//! - [`build`]: the coarse-to-fine pre-pass that fills the cache in parallel batches.
//! - [`aov`]: the irradiance image and the record-position overlay.
//! - [`points`]: irradiance at given points (Radiance's `rtrace -I`), by the cache or brute force.
//! - [`prepare`]: filling the cache for an image, with the cache file.
//!
//! The integrator that renders with it is [`crate::integrators::ic`].

pub mod aov;
pub mod build;
pub mod environment;
pub mod file;
pub mod gather;
pub mod hemisphere;
pub mod params;
pub mod plane;
pub mod points;
pub mod prepare;
pub mod record;
pub mod store;

pub use build::CacheStats;
pub use gather::IrradianceCache;
pub use params::IcParams;
pub use record::{GradientMode, Record};
