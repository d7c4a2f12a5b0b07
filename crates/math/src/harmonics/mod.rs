//! Spherical and hemispherical harmonics: the bases radiance caching stores incoming light in
//! (001 ch. 3, 000 §3.5; worked through in `NOTES-001.md` §A).
//!
//! Conventions, fixed here once (the thesis mixes several; NOTES-001 §0):
//! - **Order n** means bands l = 0 … n − 1, so n² coefficients (eqs. 3.32–3.33 sum to n, a slip).
//! - **Index** i(l, m) = l² + l + m, m = −l … l: the row and column order of every vector and matrix.
//! - **Condon–Shortley phase** (−1)^m in the associated Legendre functions (3.5), in both bases.
//! - **Local frame** [t b n]: θ from the normal (+z), φ from t (+x) towards b (+y).
//! - **Rotating a function**: (R f)(ω) = f(R⁻¹ω); a record's coefficients reach a shading point's
//!   frame by R = F_pᵀ F_k, applied as Z(α) · Y(β) · Z(γ) ([`rotation::ZyzAngles`]).
//!
//! Modules: [`legendre`] (normalised associated Legendre functions), [`basis`] (evaluating either
//! basis at a direction), [`sh`] (real spherical
//! harmonics 3.7–3.8 and their rotations), [`hsh`] (hemispherical harmonics 3.15–3.19, projection,
//! rotation about the normal), [`conversion`] (the SH ↔ HSH matrix 3.20–3.26), [`rotation`] (the
//! lossy tilt of HSH: the precomputed rotation-with-horizon-loss matrices 3.31 and the SH route),
//! [`quadrature`] (the exact rules the tables and tests are built with). Everything is `f64`: the
//! tables are built once; a cache may store its coefficients in `f32`.

pub mod basis;
pub mod conversion;
pub mod hsh;
pub mod legendre;
pub mod quadrature;
pub mod rotation;
pub mod sh;

/// Number of coefficients of an expansion of order `order` (bands 0 … order − 1).
#[inline]
#[must_use]
pub const fn coefficient_count(order: usize) -> usize {
    order * order
}

/// The linear index l² + l + m of coefficient (l, m).
#[inline]
#[must_use]
pub const fn index(l: usize, m: i64) -> usize {
    ((l * l + l) as i64 + m) as usize
}

/// The band l and degree m of linear index `i` (the inverse of [`index`]).
#[inline]
#[must_use]
pub fn band_and_degree(i: usize) -> (usize, i64) {
    let l = (i as f64).sqrt() as usize;
    // Guard the square root's rounding.
    let l = if (l + 1) * (l + 1) <= i {
        l + 1
    } else if l * l > i {
        l - 1
    } else {
        l
    };
    (l, i as i64 - (l * l + l) as i64)
}

/// Rotates the coefficients of a spherical or hemispherical expansion (the same layout) about
/// the z axis (the normal) by `alpha`: exact and norm-preserving (001 §3.4.2, NOTES-001 §A.5).
/// With (a, b) = (c_{l,m}, c_{l,−m}), m > 0: a' = a cos mα − b sin mα, b' = a sin mα + b cos mα,
/// so that the result is f(φ − α).
pub fn rotate_about_z(order: usize, coefficients: &mut [f64], alpha: f64) {
    // On the stack for the orders a cache uses (it runs per record and pixel sample).
    let (mut small_cos, mut small_sin) = ([0.0; 32], [0.0; 32]);
    let (mut big_cos, mut big_sin) = (Vec::new(), Vec::new());
    let (cos, sin): (&mut [f64], &mut [f64]) = if order <= 32 {
        (
            &mut small_cos[..order.max(1)],
            &mut small_sin[..order.max(1)],
        )
    } else {
        big_cos.resize(order, 0.0);
        big_sin.resize(order, 0.0);
        (&mut big_cos, &mut big_sin)
    };
    let (s, c) = alpha.sin_cos();
    azimuthal(c, s, cos, sin);
    for l in 1..order {
        for m in 1..=l {
            let (i, j) = (index(l, m as i64), index(l, -(m as i64)));
            let (a, b) = (coefficients[i], coefficients[j]);
            coefficients[i] = a * cos[m] - b * sin[m];
            coefficients[j] = a * sin[m] + b * cos[m];
        }
    }
}

/// Sine and cosine of mφ for m = 0 … `count` − 1 from cos φ and sin φ (Chebyshev's recurrence,
/// no trigonometric calls), into `cos` and `sin`.
pub(crate) fn azimuthal(cos_phi: f64, sin_phi: f64, cos: &mut [f64], sin: &mut [f64]) {
    let count = cos.len().min(sin.len());
    if count == 0 {
        return;
    }
    cos[0] = 1.0;
    sin[0] = 0.0;
    for m in 1..count {
        cos[m] = cos[m - 1] * cos_phi - sin[m - 1] * sin_phi;
        sin[m] = sin[m - 1] * cos_phi + cos[m - 1] * sin_phi;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn index_round_trips() {
        let mut i = 0;
        for l in 0..20usize {
            for m in -(l as i64)..=l as i64 {
                assert_eq!(index(l, m), i);
                assert_eq!(band_and_degree(i), (l, m));
                i += 1;
            }
        }
        assert_eq!(coefficient_count(20), i);
    }

    #[test]
    fn azimuthal_recurrence_matches_libm() {
        let phi = 0.731f64;
        let (mut c, mut s) = ([0.0; 12], [0.0; 12]);
        azimuthal(phi.cos(), phi.sin(), &mut c, &mut s);
        for m in 0..12 {
            assert!((c[m] - (m as f64 * phi).cos()).abs() < 1e-13);
            assert!((s[m] - (m as f64 * phi).sin()).abs() < 1e-13);
        }
    }
}
