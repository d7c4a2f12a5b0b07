//! Animations with a cache reused over time (001 ch. 5, 000 §3.7.3; `NOTES-001.md` part D).
//!
//! - [`lifespan`]: how long a record serves, from its change over one frame (5.1–5.8).
//! - [`record`]: a record over time: temporal gradients (5.9–5.17), motion with its shape.
//! - [`reprojection`]: a record's next frame by reprojecting its gather (§5.2.4).
//! - [`pixel_reuse`]: pixels nothing moving reaches, and their sampled light's running mean
//!   over the frames.
//! - [`sequence`]: the frame loop: temporal caching, age-based invalidation, or a new cache each
//!   frame (`--cache-mode`).
//!
//! The flicker measures over frame sequences are in `ircache_image::flicker`; the animation
//! format in `ircache_scene::animation`.

pub mod lifespan;
pub mod pixel_reuse;
pub mod record;
pub mod reprojection;
pub mod sequence;

pub use sequence::{CacheMode, FrameStats, Motion, NextFrame, SequenceCache, TemporalParams};
