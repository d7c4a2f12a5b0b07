//! Irradiance caching in participating media (002, NOTES-002 §2): what a record's hemisphere
//! gather sees through a medium, and the irradiance gradients that account for it.
//!
//! - [`gradient`]: the stratified estimator of surface and medium irradiance with the changing
//!   cell area (002 eqs. 10–13) on attenuated radiance, the absorption term (14–18), the
//!   visibility gradient of the medium's radiance (19–26) and the transmittance gradient (27–30)
//!   in the notes' consistent form, with the paper's literal reading and the older ones for
//!   comparison ([`gradient::MediaGradient`]). It sees the scene through a narrow interface
//!   ([`gradient::GatherMedium`]) so that it is tested against closed forms.
//! - [`cache`]: surface records gathered through media (stage 1).
//! - [`volume_records`]: records of the in-scattered indirect light inside media (stage 2).

pub mod cache;
pub mod gradient;
pub mod points;
pub mod scene_medium;
pub mod volume_records;
