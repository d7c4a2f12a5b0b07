//! Irradiance cache records (plain data) and Ward's split-sphere weight (000 eqs. 3.7–3.10,
//! 3.15).

use ircache_math::{Rgb, Vec3};

/// One cached irradiance value with what is needed to interpolate it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Record {
    /// Position.
    pub p: Vec3,
    /// Unit normal of the side the hemisphere was gathered on.
    pub n: Vec3,
    /// Indirect irradiance.
    pub e: Rgb,
    /// Harmonic mean distance (3.8) after the spacing and gradient limits.
    pub r: f32,
    /// World-space translational gradient per channel (R, G, B).
    pub grad_t: [Vec3; 3],
    /// World-space rotational gradient per channel (R, G, B).
    pub grad_r: [Vec3; 3],
    /// Bounce level: 0 for irradiance seen by the camera's surfaces, 1 for the surfaces seen by
    /// level-0 gather rays, ...
    pub level: u8,
    /// Relative variance of the irradiance estimate per gather ray, estimated from the gather's
    /// own strata ([`super::hemisphere::HemisphereSamples::relative_variance`]): the rays a
    /// gather here needs for a relative standard error t are about this / t².
    pub ray_variance: f32,
    /// Where the record is on a radiance-cached surface: its incoming radiance in HSH, an index
    /// into [`super::IrradianceCache::radiance_records`] (while a gather's work state holds it,
    /// into the state's own list); [`NO_RADIANCE`] elsewhere.
    pub radiance: u32,
}

/// The pixel's footprint at the end of a camera path (000 eq. 3.60): the square root of the
/// pixel's area (`spread.at(travelled)` across) projected onto the surface `travelled` along the
/// path, seen at `cos_view` (floored at 0.05 for grazing views).
#[must_use]
pub fn pixel_footprint(spread: crate::camera::PixelSpread, travelled: f32, cos_view: f32) -> f32 {
    spread.at(travelled) / cos_view.max(0.05).sqrt()
}

/// Tabellion–Lamorlette's radius (000 eqs. 3.59–3.60): half the nearest of the gather's hit
/// `distances`, and its limits: half the resolution's `(r_min, r_max)` (so that R/2 ≥ size/(2·ar)
/// as in Radiance), and at a record the camera sees `footprints` (smallest, largest; the
/// paper's 1.5 and 10) times its pixel `footprint`. Returns the radius (not yet limited) and
/// the limits.
///
/// A record whose gather touches another surface (its nearest hit closer than
/// [`CONTACT_SHARE`] of the smallest footprint radius) sits on the edge where two surfaces
/// meet, often a rounding error beyond it: its hemisphere then sees the far side of the
/// adjoining wall, and its irradiance is that of the outside (0 in a closed room). Raised to
/// the footprint floor it would serve a band of pixels along every such edge (the cube-in-box
/// floor along the right wall: a 3 × 5-pixel patch 25 % dark at 128²), so it keeps only the
/// resolution's floor.
#[must_use]
pub fn tabellion_radius(
    distances: &[f32],
    (r_min, r_max): (f32, f32),
    footprint: Option<f32>,
    (smallest, largest): (f32, f32),
) -> (f32, (f32, f32)) {
    let (mut r_min, mut r_max) = (0.5 * r_min, 0.5 * r_max);
    let nearest = distances.iter().copied().fold(f32::INFINITY, f32::min);
    if let Some(footprint) = footprint {
        let floor = smallest * footprint;
        if 0.5 * nearest >= CONTACT_SHARE * floor {
            r_min = r_min.max(floor);
        }
        r_max = r_max.min(largest * footprint).max(r_min);
    }
    (0.5 * nearest, (r_min, r_max))
}

/// The share of the footprint floor below which a record's nearest hit counts as a contact
/// ([`tabellion_radius`]): a thousandth, far below any pixel sample's distance from an edge
/// that the pixel resolves, far above rounding errors (relative to the footprint, so
/// scale-free).
pub const CONTACT_SHARE: f32 = 1.0e-3;

/// Ward's gradient limit on a record's radius (003 item 4): within the distance at which the
/// record serves, its translational gradient may not predict a change larger than `a·E` (a the
/// accuracy). Under Ward's metric a record serves within `a·R`, so this is Radiance's own rule
/// R ≤ E/‖∇E‖; the other metrics serve farther per unit of R (Tabellion's `R·a/0.2`), and the
/// same rule in R would let the gradient predict 1.75 E within reach at a = 0.35: indirect hot
/// spots (a lamp's shade reflecting its bulb onto a desk) were then interpolated from records
/// outside them, 30 % low. `scale` is `a` over the serving distance per unit R
/// ([`ErrorMetric::gradient_limit_scale`]). A channel with a gradient but no irradiance loses
/// its gradient; where the limit falls below `r_min`, the radius stays at `r_min` and the
/// gradient is scaled down instead. Returns the radius.
#[must_use]
pub fn limit_radius_by_gradient(
    e: Rgb,
    grad_t: &mut [Vec3; 3],
    r: f32,
    r_min: f32,
    scale: f32,
) -> f32 {
    let mut limit = f32::INFINITY;
    for c in 0..3 {
        let g = grad_t[c].length();
        if g > 0.0 && e[c] > 0.0 {
            limit = limit.min(scale * e[c] / g);
        } else if g > 0.0 {
            grad_t[c] = Vec3::ZERO;
        }
    }
    let mut r = r.min(limit);
    if r < r_min {
        r = r_min;
        if limit < r {
            let f = limit / r;
            *grad_t = grad_t.map(|g| g * f);
        }
    }
    r
}

/// [`Record::radiance`] of a record without radiance coefficients.
pub const NO_RADIANCE: u32 = u32::MAX;

/// What a record store and the error metrics need of any kind of record (irradiance records
/// today; radiance, photon and media records later): where it sits, which side it serves, and the
/// radius R by which the metrics scale distances.
pub trait CachedRecord: Copy + Send + Sync {
    /// Position.
    fn position(&self) -> Vec3;
    /// Unit normal of the side it serves.
    fn normal(&self) -> Vec3;
    /// The metric's radius R.
    fn radius(&self) -> f32;
    /// Sets R (neighbour clamping shrinks it).
    fn set_radius(&mut self, r: f32);
}

impl CachedRecord for Record {
    #[inline]
    fn position(&self) -> Vec3 {
        self.p
    }
    #[inline]
    fn normal(&self) -> Vec3 {
        self.n
    }
    #[inline]
    fn radius(&self) -> f32 {
        self.r
    }
    #[inline]
    fn set_radius(&mut self, r: f32) {
        self.r = r;
    }
}

/// Which gradients interpolation uses (`--gradients`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum GradientMode {
    /// Plain weighted average (3.9).
    None,
    /// Rotational gradient only.
    Rotation,
    /// Rotational and translational gradients (3.15).
    #[default]
    Full,
}

impl GradientMode {
    /// Parses `none`, `rotation` or `full`.
    pub fn parse(s: &str) -> Result<GradientMode, String> {
        match s {
            "none" => Ok(GradientMode::None),
            "rotation" => Ok(GradientMode::Rotation),
            "full" => Ok(GradientMode::Full),
            _ => Err(format!(
                "unknown gradient mode \"{s}\" (expected none, rotation or full)"
            )),
        }
    }

    /// The name `parse` accepts.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            GradientMode::None => "none",
            GradientMode::Rotation => "rotation",
            GradientMode::Full => "full",
        }
    }
}

/// How a record's error at a query point is measured (`--error-metric`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum ErrorMetric {
    /// Ward's split sphere (000 eq. 3.10): ε = ‖x − xᵢ‖/Rᵢ + √(1 − n·nᵢ), valid where ε ≤ a,
    /// weight 1/ε; R is the harmonic mean distance.
    Ward,
    /// Tabellion and Lamorlette (000 eqs. 3.59–3.62): ε = κ max(‖x − xᵢ‖/Rᵢ,
    /// √(1 − n·nᵢ)/√(1 − cos 10°)), valid where ε < 1, weight 1 − ε; R is half the closest
    /// distance clamped to `footprint_limits` pixel footprints; κ = 0.2/a (1 at the default
    /// accuracy).
    /// The cache's default (chosen by measurement, BENCHMARKS.md).
    #[default]
    Tabellion,
    /// Second-order error control after Schwarzhaupt, Jensen and Jarosz (2012): R is the
    /// distance at which ½ λ R² = a E, λ the largest eigenvalue of the translational Hessian of
    /// the irradiance (estimated by reprojecting the gather's hit points), bounded by the
    /// harmonic mean distance where occluders hide what reprojection cannot see; the error is
    /// ‖x − xᵢ‖/R plus √(1 − n·nᵢ)/a, valid up to 1, weight its inverse. Isotropic: the
    /// paper's anisotropic (elliptical) radii are not implemented.
    Hessian,
}

impl ErrorMetric {
    /// Parses `ward` or `tabellion`.
    pub fn parse(s: &str) -> Result<ErrorMetric, String> {
        match s {
            "ward" => Ok(ErrorMetric::Ward),
            "tabellion" => Ok(ErrorMetric::Tabellion),
            "hessian" => Ok(ErrorMetric::Hessian),
            _ => Err(format!(
                "unknown error metric \"{s}\" (expected ward, tabellion or hessian)"
            )),
        }
    }

    /// The name `parse` accepts.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            ErrorMetric::Ward => "ward",
            ErrorMetric::Tabellion => "tabellion",
            ErrorMetric::Hessian => "hessian",
        }
    }

    /// The record's error at (p, n) divided by its threshold (≤ 1: the record serves), or `None`
    /// when the record lies in front of p (Ward 1988: it would see occluders p does not). The
    /// in-front test is an angle, so it is scale-free: more than about 3° above the mean
    /// tangent plane as seen from p.
    #[inline]
    #[must_use]
    pub fn error<R: CachedRecord>(self, rec: &R, p: Vec3, n: Vec3, accuracy: f32) -> Option<f32> {
        let (rp, rn, rr) = (rec.position(), rec.normal(), rec.radius());
        let d = p - rp;
        let dist = d.length();
        // Ward's in-front test, not within a ten-thousandth of the radius: there the point is
        // the record's own up to rounding (a GPU's G-buffer finds it a few ulps off, often
        // just behind the surface), not a point the record lies in front of.
        if dist > 1e-4 * rr && d.dot(n + rn) < -0.1 * dist {
            return None;
        }
        let normal = (1.0 - n.dot(rn).min(1.0)).max(0.0).sqrt();
        Some(match self {
            ErrorMetric::Ward => (dist / rr + normal) / accuracy,
            ErrorMetric::Tabellion => {
                // √(1 − cos 10°)
                const NORMAL_SCALE: f32 = 0.123_257_4;
                (0.2 / accuracy) * (dist / rr).max(normal / NORMAL_SCALE)
            }
            ErrorMetric::Hessian => dist / rr + normal / accuracy,
        })
    }

    /// Weight of a record whose normalised error is `e`, serving up to `threshold`.
    #[inline]
    #[must_use]
    pub fn weight(self, e: f32, threshold: f32) -> f32 {
        match self {
            ErrorMetric::Ward | ErrorMetric::Hessian => 1.0 / e.max(1e-4),
            ErrorMetric::Tabellion => (1.0 - e / threshold).max(1e-6),
        }
    }

    /// Distance from the record beyond which it never serves (at threshold 1).
    #[inline]
    #[must_use]
    pub fn validity_radius<R: CachedRecord>(self, rec: &R, accuracy: f32) -> f32 {
        self.reach_per_radius(accuracy) * rec.radius()
    }

    /// The serving distance per unit of a record's radius R.
    #[inline]
    #[must_use]
    pub fn reach_per_radius(self, accuracy: f32) -> f32 {
        match self {
            ErrorMetric::Ward => accuracy,
            ErrorMetric::Tabellion => accuracy / 0.2,
            ErrorMetric::Hessian => 1.0,
        }
    }

    /// The factor of [`limit_radius_by_gradient`]: the accuracy over the serving distance per
    /// unit R (1 for Ward's metric, 0.2 for Tabellion's, `a` for the Hessian radius).
    #[inline]
    #[must_use]
    pub fn gradient_limit_scale(self, accuracy: f32) -> f32 {
        accuracy / self.reach_per_radius(accuracy)
    }
}

/// The record's value extrapolated to (p, n) by 3.15 with the gradients `mode` selects.
#[inline]
#[must_use]
pub fn extrapolate(rec: &Record, p: Vec3, n: Vec3, mode: GradientMode) -> Rgb {
    let mut e = rec.e;
    if mode != GradientMode::None {
        let axis = rec.n.cross(n);
        e += Rgb::new(
            axis.dot(rec.grad_r[0]),
            axis.dot(rec.grad_r[1]),
            axis.dot(rec.grad_r[2]),
        );
    }
    if mode == GradientMode::Full {
        let d = p - rec.p;
        e += Rgb::new(
            d.dot(rec.grad_t[0]),
            d.dot(rec.grad_t[1]),
            d.dot(rec.grad_t[2]),
        );
    }
    e
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tabellion_radii_keep_within_their_pixel_footprints_and_the_resolutions_limits() {
        // Footprint 0.01, limits (1.5, 5) footprints: R₋ = 0.015, R₊ = 0.05 where the
        // resolution's halves (0.001, 0.064) are looser; the resolution's bind where tighter.
        let (r, (lo, hi)) = tabellion_radius(&[0.3, 0.08], (0.002, 0.128), Some(0.01), (1.5, 5.0));
        assert_eq!(r, 0.04);
        assert!(
            (lo - 0.015).abs() < 1e-7 && (hi - 0.05).abs() < 1e-7,
            "{lo} {hi}"
        );
        let (_, (lo, hi)) = tabellion_radius(&[0.3], (0.04, 0.08), Some(0.01), (1.5, 5.0));
        assert!(
            (lo - 0.02).abs() < 1e-7 && (hi - 0.04).abs() < 1e-7,
            "{lo} {hi}"
        );
        // A largest limit below the smallest is lifted to it; no footprint, no pixel limits.
        let (_, (lo, hi)) = tabellion_radius(&[0.3], (0.002, 0.128), Some(0.01), (3.0, 2.0));
        assert!((lo - 0.03).abs() < 1e-7 && hi == lo, "{lo} {hi}");
        assert_eq!(
            tabellion_radius(&[0.3], (0.002, 0.128), None, (1.5, 5.0)).1,
            (0.001, 0.064)
        );
    }

    #[test]
    fn a_record_touching_another_surface_keeps_only_the_resolutions_floor() {
        // Footprint 0.01: the floor is 0.015; a nearest hit of 2e-5 (R 1e-5 < 1.5e-5) is a
        // contact, one of 4e-5 (R 2e-5) is not.
        let (r, (lo, hi)) = tabellion_radius(&[0.3, 2e-5], (0.002, 0.128), Some(0.01), (1.5, 5.0));
        assert!(
            (r - 1e-5).abs() < 1e-9 && lo == 0.001 && (hi - 0.05).abs() < 1e-7,
            "{r} {lo} {hi}"
        );
        let (_, (lo, _)) = tabellion_radius(&[0.3, 4e-5], (0.002, 0.128), Some(0.01), (1.5, 5.0));
        assert!((lo - 0.015).abs() < 1e-7, "{lo}");
    }

    #[test]
    fn the_gradient_limit_bounds_the_change_predicted_within_reach_for_every_metric() {
        let a = 0.35;
        for metric in [
            ErrorMetric::Ward,
            ErrorMetric::Tabellion,
            ErrorMetric::Hessian,
        ] {
            let e = Rgb::new(2.0, 1.0, 4.0);
            // The green channel's gradient binds: |g| = 5 against E = 1.
            let mut g = [
                Vec3::new(1.0, 0.0, 0.0),
                Vec3::new(3.0, 4.0, 0.0),
                Vec3::ZERO,
            ];
            let scale = metric.gradient_limit_scale(a);
            let r = limit_radius_by_gradient(e, &mut g, 10.0, 0.0, scale);
            let reach = metric.reach_per_radius(a) * r;
            assert!(
                (reach * g[1].length() - a * e.g).abs() < 1e-5,
                "{metric:?}: {reach}"
            );
            assert!(reach * g[0].length() <= a * e.r + 1e-6);
            // Below the smallest radius the gradient is scaled down to the same bound.
            let mut g2 = [Vec3::ZERO, Vec3::new(300.0, 400.0, 0.0), Vec3::ZERO];
            let r2 = limit_radius_by_gradient(e, &mut g2, 10.0, r, scale);
            assert_eq!(r2, r);
            let predicted = metric.reach_per_radius(a) * r2 * g2[1].length();
            assert!(
                (predicted - a * e.g).abs() < 1e-4,
                "{metric:?}: {predicted}"
            );
        }
        // Ward's metric keeps Radiance's own rule, R ≤ E/|∇E|.
        assert_eq!(ErrorMetric::Ward.gradient_limit_scale(0.2), 1.0);
    }
}
