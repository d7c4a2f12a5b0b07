//! Normalised associated Legendre functions N_l^m = K_l^m P_l^m (001 eqs. 3.4–3.8, with the
//! Condon–Shortley phase of 3.5), m ≥ 0, for every l below an order, by the recurrences of the
//! normalised functions: no factorials, so no overflow at high orders (NOTES-001 §A.2).
//!
//! The argument comes as (x, s) with s = √(1 − x²) given by the caller: spherical harmonics pass
//! (cos θ, sin θ); hemispherical ones pass (2 cos θ − 1, 2√(cos θ (1 − cos θ))), the shifted
//! argument of 3.15 with its sine formed without the cancellation of 1 − x² near the pole.

/// Index of (l, m), 0 ≤ m ≤ l, in a table of [`normalized_legendre`].
#[inline]
#[must_use]
pub const fn triangle_index(l: usize, m: usize) -> usize {
    l * (l + 1) / 2 + m
}

/// Size of the table for `order` bands.
#[inline]
#[must_use]
pub const fn table_len(order: usize) -> usize {
    order * (order + 1) / 2
}

/// N_l^m(x) = K_l^m P_l^m(x) for 0 ≤ m ≤ l < `order`, K_l^m = √((2l+1)(l−m)! / (4π (l+m)!)) (3.8),
/// into `out` at [`triangle_index`]. Recurrences (the normalised forms of 3.4–3.6):
/// N_0^0 = 1/√(4π), N_m^m = −√((2m+1)/2m) · s · N_{m−1}^{m−1} (the minus is Condon–Shortley's phase),
/// N_{m+1}^m = √(2m+3) · x · N_m^m, and N_l^m = a (x N_{l−1}^m − b N_{l−2}^m) with
/// a = √((4l² − 1)/(l² − m²)), b = √(((l−1)² − m²)/(4(l−1)² − 1)).
pub fn normalized_legendre(order: usize, x: f64, s: f64, out: &mut [f64]) {
    assert!(out.len() >= table_len(order), "Legendre table too short");
    if order == 0 {
        return;
    }
    let mut diagonal = 0.5 / std::f64::consts::PI.sqrt();
    for m in 0..order {
        if m > 0 {
            let mf = m as f64;
            diagonal *= -((2.0 * mf + 1.0) / (2.0 * mf)).sqrt() * s;
        }
        out[triangle_index(m, m)] = diagonal;
        if m + 1 >= order {
            break;
        }
        let mf = m as f64;
        let mut below = diagonal;
        let mut current = (2.0 * mf + 3.0).sqrt() * x * diagonal;
        out[triangle_index(m + 1, m)] = current;
        for l in m + 2..order {
            let (lf, m2) = (l as f64, mf * mf);
            let a = ((4.0 * lf * lf - 1.0) / (lf * lf - m2)).sqrt();
            let lm1 = lf - 1.0;
            let b = ((lm1 * lm1 - m2) / (4.0 * lm1 * lm1 - 1.0)).sqrt();
            let next = a * (x * current - b * below);
            out[triangle_index(l, m)] = next;
            below = current;
            current = next;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// P_l^m by the unnormalised recurrences 3.4–3.6 and K_l^m by factorials, for low orders.
    fn reference(l: usize, m: usize, x: f64) -> f64 {
        let s = (1.0 - x * x).sqrt();
        let double_factorial = (1..2 * m).step_by(2).map(|k| k as f64).product::<f64>();
        let sign = if m % 2 == 1 { -1.0 } else { 1.0 };
        let pmm = sign * double_factorial * s.powi(m as i32);
        let p = if l == m {
            pmm
        } else {
            let mut below = pmm;
            let mut current = x * (2 * m + 1) as f64 * pmm;
            for ll in m + 2..=l {
                let next = (x * (2 * ll - 1) as f64 * current - (ll + m - 1) as f64 * below)
                    / (ll - m) as f64;
                below = current;
                current = next;
            }
            current
        };
        let factorial = |n: usize| (1..=n).map(|k| k as f64).product::<f64>();
        let k = ((2 * l + 1) as f64 * factorial(l - m) / (4.0 * PI * factorial(l + m))).sqrt();
        k * p
    }

    #[test]
    fn matches_the_unnormalised_recurrences() {
        let order = 9;
        let mut t = vec![0.0; table_len(order)];
        for x in [-0.93, -0.4, 0.0, 0.25, 0.77, 1.0] {
            normalized_legendre(order, x, (1.0f64 - x * x).sqrt(), &mut t);
            for l in 0..order {
                for m in 0..=l {
                    let want = reference(l, m, x);
                    let got = t[triangle_index(l, m)];
                    assert!(
                        (got - want).abs() < 1e-12 * want.abs().max(1.0),
                        "l {l} m {m} x {x}"
                    );
                }
            }
        }
    }

    #[test]
    fn closed_forms_with_the_condon_shortley_phase() {
        // P_1^1 = −s, P_2^1 = −3xs, P_2^2 = 3s² (3.5–3.6 with the phase).
        let (x, s) = (0.6f64, 0.8f64);
        let mut t = vec![0.0; table_len(3)];
        normalized_legendre(3, x, s, &mut t);
        let k = |l: f64, num: f64, den: f64| ((2.0 * l + 1.0) * num / (4.0 * PI * den)).sqrt();
        assert!((t[triangle_index(1, 1)] - k(1.0, 1.0, 2.0) * -s).abs() < 1e-15);
        assert!((t[triangle_index(2, 1)] - k(2.0, 1.0, 6.0) * -3.0 * x * s).abs() < 1e-15);
        assert!((t[triangle_index(2, 2)] - k(2.0, 1.0, 24.0) * 3.0 * s * s).abs() < 1e-15);
    }
}
