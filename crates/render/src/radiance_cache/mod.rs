//! Radiance caching of glossy indirect light (001 ch. 3 and §2.2.6, 000 §3.5; NOTES-001 §B): records
//! that store incoming radiance in hemispherical harmonics ([`ircache_math::harmonics`]) and shade
//! any moderately glossy BRDF from them.
//!
//! - [`brdf`]: the BRDFs' cosine-weighted glossy lobes in HSH over the outgoing directions, and the
//!   order each material needs.
//! - [`gather`]: a gather's incoming radiance in HSH and its translational gradients.
//!
//! Not yet here: the radiance records in the cache, their lookups (rotation by
//! [`ircache_math::harmonics::rotation::TiltTable`]) and the pre-pass.

pub mod brdf;
pub mod gather;
