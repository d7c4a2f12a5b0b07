//! Radiance caching of glossy indirect light (001 ch. 3 and §2.2.6, 000 §3.5; NOTES-001 §B): records
//! that store incoming radiance in hemispherical harmonics ([`ircache_math::harmonics`]) and shade
//! any moderately glossy BRDF from them.
//!
//! - [`brdf`]: the BRDFs' cosine-weighted glossy lobes in HSH over the outgoing directions, and the
//!   order each material needs.
//!
//! Not yet here: the radiance records themselves, their gradients, lookups and the pre-pass.

pub mod brdf;
