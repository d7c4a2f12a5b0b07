//! Fresnel equations as in Mitsuba 3 (`include/mitsuba/render/fresnel.h`): unpolarised reflectance
//! of a dielectric interface, of a conductor with a complex index of refraction, and the diffuse
//! (hemispherically averaged) Fresnel reflectance used by the plastic models.

use ircache_math::{Rgb, Vec3};

/// Result of [`fresnel_dielectric`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DielectricFresnel {
    /// Unpolarised reflectance `R` (1 under total internal reflection).
    pub r: f32,
    /// Signed cosine of the refracted direction (opposite sign to `cos_theta_i`).
    pub cos_theta_t: f32,
    /// Relative index `η_t/η_i` seen from the incident side.
    pub eta_it: f32,
    /// Its reciprocal `η_i/η_t`.
    pub eta_ti: f32,
}

/// Unpolarised Fresnel reflectance of a smooth dielectric interface with relative index `eta`
/// (interior over exterior) for an incident direction with signed cosine `cos_theta_i` (negative:
/// arriving from the interior), like Mitsuba 3's `fresnel()`.
#[must_use]
pub fn fresnel_dielectric(cos_theta_i: f32, eta: f32) -> DielectricFresnel {
    let outside = cos_theta_i >= 0.0;
    let rcp_eta = 1.0 / eta;
    let (eta_it, eta_ti) = if outside {
        (eta, rcp_eta)
    } else {
        (rcp_eta, eta)
    };
    // Snell's law.
    let cos_t_sqr = 1.0 - eta_ti * eta_ti * (1.0 - cos_theta_i * cos_theta_i);
    let cos_i = cos_theta_i.abs();
    let cos_t = cos_t_sqr.max(0.0).sqrt();
    let r = if eta == 1.0 {
        0.0
    } else if cos_i == 0.0 {
        1.0
    } else {
        // Amplitudes of the reflected s- and p-polarised waves.
        let a_s = (cos_i - eta_it * cos_t) / (cos_i + eta_it * cos_t);
        let a_p = (cos_t - eta_it * cos_i) / (cos_t + eta_it * cos_i);
        0.5 * (a_s * a_s + a_p * a_p)
    };
    let cos_theta_t = if cos_theta_i >= 0.0 { -cos_t } else { cos_t };
    DielectricFresnel {
        r,
        cos_theta_t,
        eta_it,
        eta_ti,
    }
}

/// Unpolarised Fresnel reflectance of a conductor with complex relative index `eta + i k` at
/// incidence cosine `cos_theta_i` (K. D. Möller, *Optics*, 1988, as in Mitsuba 3's
/// `fresnel_conductor`). `eta = 0, k = 1` gives a perfect mirror (Mitsuba's `material="none"`).
#[must_use]
pub fn fresnel_conductor_1(cos_theta_i: f32, eta: f32, k: f32) -> f32 {
    let c2 = cos_theta_i * cos_theta_i;
    let s2 = 1.0 - c2;
    let s4 = s2 * s2;
    let temp_1 = eta * eta - k * k - s2;
    let a2pb2 = (temp_1 * temp_1 + 4.0 * k * k * eta * eta).max(0.0).sqrt();
    let a = (0.5 * (a2pb2 + temp_1)).max(0.0).sqrt();
    let term_1 = a2pb2 + c2;
    let term_2 = 2.0 * cos_theta_i * a;
    let r_s = (term_1 - term_2) / (term_1 + term_2);
    let term_3 = a2pb2 * c2 + s4;
    let term_4 = term_2 * s2;
    let r_p = r_s * (term_3 - term_4) / (term_3 + term_4);
    let r = 0.5 * (r_s + r_p);
    if r.is_finite() {
        r.clamp(0.0, 1.0)
    } else {
        1.0
    }
}

/// [`fresnel_conductor_1`] per channel.
#[must_use]
pub fn fresnel_conductor(cos_theta_i: f32, eta: Rgb, k: Rgb) -> Rgb {
    Rgb::new(
        fresnel_conductor_1(cos_theta_i, eta.r, k.r),
        fresnel_conductor_1(cos_theta_i, eta.g, k.g),
        fresnel_conductor_1(cos_theta_i, eta.b, k.b),
    )
}

/// Diffuse Fresnel reflectance `F_dr(η)`: the cosine-weighted hemispherical average of the
/// dielectric reflectance, by the fits Mitsuba 3 uses (Egan and Hilgeman 1973 for `η < 1`, d'Eon
/// and Irving 2011 otherwise).
#[must_use]
pub fn fresnel_diffuse_reflectance(eta: f32) -> f32 {
    if eta < 1.0 {
        -1.4399 * eta * eta + 0.7099 * eta + 0.6681 + 0.0636 / eta
    } else {
        let x = 1.0 / eta;
        0.919_317 + x * (-3.4793 + x * (6.753_35 + x * (-7.809_89 + x * (4.985_54 - 1.368_81 * x))))
    }
}

/// Mirror reflection about the normal (+z): `(−x, −y, z)`.
#[must_use]
pub fn reflect(w: Vec3) -> Vec3 {
    Vec3::new(-w.x, -w.y, w.z)
}

/// Reflection of `w` about the unit vector `m`.
#[must_use]
pub fn reflect_about(w: Vec3, m: Vec3) -> Vec3 {
    2.0 * w.dot(m) * m - w
}

/// Refraction through the normal (+z) given [`fresnel_dielectric`]'s `cos_theta_t` and `eta_ti`.
#[must_use]
pub fn refract(w: Vec3, cos_theta_t: f32, eta_ti: f32) -> Vec3 {
    Vec3::new(-eta_ti * w.x, -eta_ti * w.y, cos_theta_t)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dielectric_normal_incidence_and_tir() {
        let f = fresnel_dielectric(1.0, 1.5);
        assert!((f.r - 0.04).abs() < 1e-6);
        assert!((f.cos_theta_t + 1.0).abs() < 1e-6);
        // From inside, beyond the critical angle: total internal reflection.
        let f = fresnel_dielectric(-0.3, 1.5);
        assert_eq!(f.r, 1.0);
        // Symmetry: R from inside at the refracted angle equals R from outside.
        let out = fresnel_dielectric(0.6, 1.5);
        let inside = fresnel_dielectric(out.cos_theta_t, 1.5);
        assert!((out.r - inside.r).abs() < 1e-5);
        assert!((inside.cos_theta_t - 0.6).abs() < 1e-5);
        assert_eq!(fresnel_dielectric(0.3, 1.0).r, 0.0);
    }

    #[test]
    fn conductor_limits() {
        // k = 0 reduces to the dielectric formula.
        for c in [0.1f32, 0.5, 0.9, 1.0] {
            let d = fresnel_dielectric(c, 1.5).r;
            assert!((fresnel_conductor_1(c, 1.5, 0.0) - d).abs() < 1e-5, "{c}");
            assert!((fresnel_conductor_1(c, 0.0, 1.0) - 1.0).abs() < 1e-6);
        }
        // Gold-ish at normal incidence: ((n−1)² + k²)/((n+1)² + k²).
        let (n, k) = (0.2f32, 3.0f32);
        let r0 = ((n - 1.0).powi(2) + k * k) / ((n + 1.0).powi(2) + k * k);
        assert!((fresnel_conductor_1(1.0, n, k) - r0).abs() < 1e-5);
    }

    #[test]
    fn diffuse_fresnel_matches_numerical_average() {
        for eta in [1.0f32 / 1.5, 1.33, 1.5, 2.0] {
            let n = 20_000;
            let mut s = 0.0f64;
            for i in 0..n {
                // ∫ R(μ) 2μ dμ by the midpoint rule.
                let mu = (i as f64 + 0.5) / n as f64;
                s += f64::from(fresnel_dielectric(mu as f32, eta).r) * 2.0 * mu / n as f64;
            }
            let fit = f64::from(fresnel_diffuse_reflectance(eta));
            assert!(
                (s - fit).abs() < 0.01 * s.max(0.05),
                "eta {eta}: {s} vs {fit}"
            );
        }
    }
}
