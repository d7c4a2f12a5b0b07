//! Radiance caching of glossy indirect light (001 ch. 3 and §2.2.6, 000 §3.5; NOTES-001 §B): records
//! that store incoming radiance in hemispherical harmonics ([`ircache_math::harmonics`]) and shade
//! any moderately glossy BRDF from them.
//!
//! - [`brdf`]: the BRDFs' cosine-weighted glossy lobes in HSH over the outgoing directions, and the
//!   order each material needs.
//! - [`gather`]: a gather's incoming radiance in HSH and its translational gradients.
//! - [`record`]: a radiance record and its reading at a shading point (extrapolation, rotation
//!   into the shading frame, blending).
//!
//! Not yet here: radiance records in the cache's store and pre-pass, the `ic` integrator's use of
//! them for glossy lobes, the cache file, parameters and images.

pub mod brdf;
pub mod gather;
pub mod record;
#[cfg(test)]
mod test_room;
