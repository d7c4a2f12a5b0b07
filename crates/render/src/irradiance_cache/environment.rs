//! The environment's light in the cache (`--cached-environment`): a gather ray that escapes
//! brings the radiance of the `constant` and `envmap` emitters into the record, with the
//! visibility the gather saw. Radiance records project it into HSH with the rest (001 eq. 3.20
//! ff.; a cell's distance is infinite, so only the walls it shares with nearer surfaces move in
//! the gradients); with `all`, irradiance records hold it too, as Radiance's ambient calculation
//! holds a sky (a `glow` source is found by the ambient rays, not by the direct calculation),
//! and the Lambertian part serves it as `k(wo) E/π` (000 eq. 3.4, 3.15). Light samples of the
//! environment then estimate only what the cache does not serve (`integrators/light_sampling.rs`,
//! `EnvironmentServed`): the glossy part where it is traced, and the difference between the
//! BSDF's diffuse part and its Lambertian stand-in (zero for Lambertian surfaces, the coating's
//! directional transmittance for plastics). So the sum stays unbiased, and under a sky held by
//! `all` a diffuse surface needs no light sample of it.
//!
//! What pays (measured on `scenes/sky-glossy` at 128² and 256², 16 spp, multijitter; BENCHMARKS.md):
//! in radiance records (`glossy`), the environment replaces light samples that, with the path
//! ending at a radiance-cached vertex, have no BSDF sample to combine with and are noisy on a
//! glossy lobe. In irradiance records too (`all`), the noise falls further but the records'
//! interpolation error (blotches near contacts, at the default accuracy) lies on all of the
//! sky's light, which the light samples had estimated without bias: the low-frequency error
//! doubles. So `auto` is `glossy` where the environment is smooth at a gather's resolution: a
//! sun in the map holds most of the power in a tiny solid angle that few gather rays find (each
//! record would be wrong by its share, a blotch); light samples find it. The decision is per
//! scene, by the environment's relative variance over the sphere.

use super::params::CachedEnvironment;
use crate::scene::Scene;

/// Which records hold the environment's light.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum HeldEnvironment {
    /// None: light samples estimate all of it.
    #[default]
    None,
    /// Radiance records.
    Glossy,
    /// Irradiance and radiance records.
    All,
}

/// Relative variance of an environment's luminance over the sphere above which `auto` leaves
/// it to the light samples: a standard deviation of twice the mean. A sky without a sun is far
/// below (the scene `sky-glossy`'s ≈ 0.6; an overcast sky over a dark ground ≈ 0.4); a sun disc
/// holding half the power or more is far above (`sky-glossy`'s sky with its sun ≈ 950).
pub const MAX_RELATIVE_VARIANCE: f64 = 4.0;

/// Which records hold the environment's light under `mode`: for `auto`, radiance records where
/// the environment's relative variance over the sphere is at most [`MAX_RELATIVE_VARIANCE`].
/// None without an environment, and none in a scene with window panes or masks (see
/// [`glazing_note`]).
#[must_use]
pub fn held_environment(scene: &Scene, mode: CachedEnvironment) -> HeldEnvironment {
    // A gather ray that leaves through a window pane or a mask's open part ends in the path it
    // continues, which holds no environment: the sky beyond is left to the light samples, which
    // see through them (`Scene::shadow_transmittance`).
    if !scene.lights.has_environment() || scene.has_see_through {
        return HeldEnvironment::None;
    }
    match mode {
        CachedEnvironment::Glossy => HeldEnvironment::Glossy,
        CachedEnvironment::All => HeldEnvironment::All,
        CachedEnvironment::Off => HeldEnvironment::None,
        CachedEnvironment::Auto
            if scene.lights.environment_relative_variance() <= MAX_RELATIVE_VARIANCE =>
        {
            HeldEnvironment::Glossy
        }
        CachedEnvironment::Auto => HeldEnvironment::None,
    }
}

/// What to tell a user who asked records to hold the environment in a scene with window panes
/// or masks, where they cannot (the light samples estimate it all instead).
#[must_use]
pub fn glazing_note(scene: &Scene, mode: CachedEnvironment) -> Option<String> {
    (scene.has_see_through
        && scene.lights.has_environment()
        && matches!(mode, CachedEnvironment::Glossy | CachedEnvironment::All))
    .then(|| {
        "--cached-environment: the scene has window panes (thindielectric) or masks, through \
         which records cannot hold the sky; light samples estimate all of the environment's light"
            .to_string()
    })
}
