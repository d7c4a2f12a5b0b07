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
//! scene, by the environment's relative variance over the sphere. Where little of the sky's
//! light reaches the surfaces in view (a room lit through windows), `auto` is `all`: there the
//! light samples of the sky that get through are rare and bright, and a record's gather, which
//! crosses window panes as paths do, holds that light smoothly ([`environment_visibility`]).

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

/// Share of the environment's light that must reach the surfaces in view for `auto` to leave
/// the Lambertian parts' share of it to light samples. Below it (a room lit by the sky through
/// windows: most light samples of the sky end on a wall or a frame), the samples that get
/// through are rare and bright, speckles in the image, and the records hold all of it, as
/// Radiance's ambient rays find the sky through `glass`. Measured (BENCHMARKS.md, blurred
/// relMSE_trim of `all` against `glossy`, two seeds): the interior of `scenes/radiance-office`
/// (visibility 0.03) 0.47×, `sunlit-window` (0.41, its glazed roof) 0.25×; `bumps` (0.72) 1.43×,
/// `sky-glossy` (0.83) 1.2×. Since a `constant` sky's samples are cosine-weighted at reflecting
/// surfaces (`lights::Receiver`) and the sky a pane mirrors is in the gathers (seventeenth
/// session): `sunlit-window` 0.42×, `bumps` 3.1×.
pub const MIN_VISIBILITY_FOR_LIGHT_SAMPLES: f64 = 0.5;

/// Camera rays and light samples [`environment_visibility`] spends.
const VISIBILITY_POINTS: usize = 1024;
const VISIBILITY_SAMPLES: usize = 4;

/// The share of the environment's light (by luminance, cosine-weighted) that reaches the
/// surfaces the camera sees, window panes and masks passing what they transmit: estimated from
/// the environment's own light samples at the first hits of random camera rays. 1 where no
/// surface is in view or the environment sends nothing.
#[must_use]
pub fn environment_visibility(scene: &Scene) -> f64 {
    use ircache_math::{Rng, Vec2};
    let mut rng = Rng::new(0x656e_7669_7369, 0);
    let (mut reached, mut total) = (0.0f64, 0.0f64);
    for _ in 0..VISIBILITY_POINTS {
        let ray = scene.camera.generate_ray(rng.next_2d());
        let Some(it) = scene.intersect(&ray) else {
            continue;
        };
        let n = if it.frame.n.dot(ray.d) < 0.0 {
            it.frame.n
        } else {
            -it.frame.n
        };
        for _ in 0..VISIBILITY_SAMPLES {
            let u_sel = rng.next_f32();
            let u = Vec2::new(rng.next_f32(), rng.next_f32());
            let Some(ls) = scene.lights.sample(it.p, u_sel, u) else {
                continue;
            };
            let cos = n.dot(ls.wi);
            if !scene.lights.is_environment(ls.light) || cos <= 0.0 || ls.pdf <= 0.0 {
                continue;
            }
            let w = f64::from(ls.radiance.luminance() * cos / ls.pdf);
            total += w;
            let tr = scene.shadow_transmittance(&scene.shadow_ray(&it, ls.wi, ls.distance));
            reached += w * f64::from(tr.luminance());
        }
    }
    if total > 0.0 {
        reached / total
    } else {
        1.0
    }
}

/// Which records hold the environment's light under `mode`: for `auto`, none where the
/// environment's relative variance over the sphere is above [`MAX_RELATIVE_VARIANCE`] (a sun in
/// it), all where less of its light than [`MIN_VISIBILITY_FOR_LIGHT_SAMPLES`] reaches the
/// surfaces in view ([`environment_visibility`]), radiance records otherwise. None without an
/// environment. Behind window panes and masks the gathers cross them
/// (`SceneRadiance::through_see_through`), so records hold the sky seen through them too.
#[must_use]
pub fn held_environment(scene: &Scene, mode: CachedEnvironment) -> HeldEnvironment {
    decide(scene, mode).0
}

/// [`held_environment`]'s choice, with the visibility `auto` measured to make it (`None` where
/// it measured none).
#[must_use]
pub fn decide(scene: &Scene, mode: CachedEnvironment) -> (HeldEnvironment, Option<f64>) {
    if !scene.lights.has_environment() {
        return (HeldEnvironment::None, None);
    }
    match mode {
        CachedEnvironment::Glossy => (HeldEnvironment::Glossy, None),
        CachedEnvironment::All => (HeldEnvironment::All, None),
        CachedEnvironment::Off => (HeldEnvironment::None, None),
        CachedEnvironment::Auto
            if scene.lights.environment_relative_variance() > MAX_RELATIVE_VARIANCE =>
        {
            (HeldEnvironment::None, None)
        }
        CachedEnvironment::Auto => {
            let visibility = environment_visibility(scene);
            let held = if visibility < MIN_VISIBILITY_FOR_LIGHT_SAMPLES {
                HeldEnvironment::All
            } else {
                HeldEnvironment::Glossy
            };
            (held, Some(visibility))
        }
    }
}

/// What to tell a user where `auto` made every record hold the environment's light, from the
/// cache's choice (`held`) and the visibility it measured.
#[must_use]
pub fn auto_note(
    mode: CachedEnvironment,
    held: HeldEnvironment,
    visibility: Option<f64>,
) -> Option<String> {
    let visibility = visibility.filter(|_| mode == CachedEnvironment::Auto)?;
    (held == HeldEnvironment::All).then(|| {
        format!(
            "--cached-environment auto: {:.0} % of the environment's light reaches the surfaces \
             in view (through windows or openings), so every record holds it (all) rather than \
             light samples",
            100.0 * visibility
        )
    })
}

/// `mode` with `auto` replaced by what the cache chose (`held`), for a cache file's header:
/// `auto` looks at the view, and a file made from another view may hold the environment
/// otherwise.
#[must_use]
pub fn resolved(mode: CachedEnvironment, held: HeldEnvironment) -> CachedEnvironment {
    match (mode, held) {
        (CachedEnvironment::Auto, HeldEnvironment::None) => CachedEnvironment::Off,
        (CachedEnvironment::Auto, HeldEnvironment::Glossy) => CachedEnvironment::Glossy,
        (CachedEnvironment::Auto, HeldEnvironment::All) => CachedEnvironment::All,
        (other, _) => other,
    }
}
