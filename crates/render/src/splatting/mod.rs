//! Radiance cache splatting (paper 001 ch. 4, Algorithms 3 and 4; NOTES-001 part C), on the CPU,
//! or on a GPU through the [`buffer::Splatter`] interface (the `ircache-gpu` crate).
//!
//! Instead of each pixel sample looking up the records that serve it, each record is splatted
//! over the samples inside its zone of influence: a G-buffer holds the first vertex of every
//! sample of one layer (one sample per pixel), every record of the first bounce level adds its
//! weighted, extrapolated value to the samples it serves, and a sample no record reaches is a
//! cache miss that gets a new record, splatted at once.
//!
//! - [`gbuffer`]: one layer of first vertices (the camera rays and what they hit).
//! - [`buffer`]: the splat buffer and splatting a range of records into it (Algorithm 3), in
//!   parallel over bands of rows that own their pixels, so sums are deterministic; the
//!   [`buffer::Splatter`] interface a GPU implements, and the records' film rectangles every
//!   splatter uses.
//! - [`pass`]: cache-miss detection on the splat buffer, coarse to fine (NOTES-001 §C.6), with
//!   an optional budget of new records (§C.7), and the `splat` integrator's pixel pass.
//! - [`walkthrough`]: the progressive walkthrough (§C.7): one layer a frame, a budget of new
//!   records, a running mean restarted when the view or the accuracy changes.
//!
//! Splatting and the lookup of [`crate::integrators::ic`] combine the same records with the same
//! weights (the store's error rule and weight at threshold 1, the glossy lookup's at its
//! threshold), so given the same cache they agree to float rounding; where splatting finds
//! nothing, the lookup's relaxed fallbacks apply as in `ic`. Deeper levels keep the spatial
//! index: they have no image.

pub mod buffer;
pub mod gbuffer;
pub mod pass;
pub mod walkthrough;

pub use buffer::{SplatBuffer, SplatPixel};
pub use gbuffer::{GBuffer, GSample};
pub use pass::{fill_misses, SplatStats};
