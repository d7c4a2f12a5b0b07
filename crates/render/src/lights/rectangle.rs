//! Solid-angle sampling of rectangular emitters (Ureña, Fajardo and King 2013, "An
//! Area-Preserving Parametrization for Spherical Rectangles", EGSR): a point uniform in the solid
//! angle the rectangle subtends at the reference point, so that the estimator no longer carries
//! area sampling's `cos θ_light / d²`, which varies most for points near a large light (walls
//! beside a ceiling lamp, a desk under its lamp).
//!
//! A mesh light uses it when the mesh is one rectangle (two triangles, four corners, a right angle;
//! Mitsuba's `rectangle` shape) without bent vertex normals, for points within the rectangle's
//! diagonal of it or whose cheap guess of the solid angle is large, and only where the solid angle
//! lies in `[MIN_SOLID_ANGLE, MAX_SOLID_ANGLE]`: below, the rectangle is small enough that area
//! sampling is as good and the parametrisation loses precision; above (a point almost on the
//! light), the angles it is built from do, and there directions are drawn uniformly over the
//! hemisphere facing the light ([`Seen::Nearly`]: the rectangle covers all but 1 % of it;
//! directions past its edge carry nothing), where pbrt-v4 samples by area, whose weight `A cos
//! θ/d²` grows without bound as the point nears the light (a medium's march point a millimetre
//! below a ceiling lamp weighed 10⁵). The density follows the same rule at the same point, so
//! sampling and MIS agree. The bounds are pbrt-v4's.

use ircache_math::{Vec2, Vec3, PI};

/// Smallest solid angle (sr) sampled by solid angle.
pub const MIN_SOLID_ANGLE: f32 = 3e-4;
/// Below this first guess of the solid angle (sr), area sampling is used: its variance differs
/// from solid-angle sampling's by the spread of `cos θ_light / d²` over the light, small for a
/// small solid angle, and it costs a quarter of the time.
pub const SOLID_ANGLE_FROM: f32 = 0.1;
/// Largest solid angle (sr) sampled by solid angle.
pub const MAX_SOLID_ANGLE: f32 = 6.22;

/// A rectangle `corner + [0, width]·ex + [0, height]·ey` emitting towards `normal = ex × ey`
/// (or its opposite).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rectangle {
    corner: Vec3,
    ex: Vec3,
    ey: Vec3,
    width: f32,
    height: f32,
}

/// The rectangle as seen from one reference point: what sampling needs (the paper's local
/// frame, coordinates and internal angles).
#[derive(Clone, Copy, Debug)]
pub struct SphericalRectangle {
    /// Local frame: x along the rectangle's first edge, y along the second, z away from it.
    x: Vec3,
    y: Vec3,
    z: Vec3,
    x0: f32,
    x1: f32,
    y0: f32,
    y1: f32,
    z0: f32,
    b0: f32,
    b1: f32,
    /// `g2 + g3`: the paper's `k = 2π − g2 − g3` up to a full turn.
    k: f32,
    /// The solid angle.
    pub solid_angle: f32,
}

/// How a reference point samples a rectangle ([`Rectangle::seen_from`]).
#[derive(Clone, Copy, Debug)]
pub enum Seen {
    /// By area: small, or the point in its plane.
    Area,
    /// By solid angle.
    Spherical(SphericalRectangle),
    /// Uniformly over the hemisphere towards it (unit axis from the point to its plane): it
    /// subtends more than [`MAX_SOLID_ANGLE`].
    Nearly(Vec3),
}

impl Seen {
    /// The solid-angle density of the directions this way of sampling draws, where it draws
    /// directions (by area it draws points: `None`).
    #[inline]
    #[must_use]
    pub fn solid_angle_pdf(&self) -> Option<f32> {
        match self {
            Seen::Area => None,
            Seen::Spherical(sph) => Some(1.0 / sph.solid_angle),
            Seen::Nearly(_) => Some(0.5 / PI),
        }
    }
}

/// The angle between unit vectors, accurate near 0 and π.
#[inline]
fn angle_between(a: Vec3, b: Vec3) -> f32 {
    if a.dot(b) < 0.0 {
        PI - 2.0 * ((a + b).length() * 0.5).min(1.0).asin()
    } else {
        2.0 * ((b - a).length() * 0.5).min(1.0).asin()
    }
}

impl Rectangle {
    /// The rectangle that the triangles `indices` over `positions` form, if they form one: four
    /// distinct corners of which one pair of edges is at a right angle (relative tolerance
    /// 10⁻⁴) and two triangles covering its area once.
    #[must_use]
    pub fn from_triangles(positions: &[Vec3], indices: &[[u32; 3]]) -> Option<Rectangle> {
        if indices.len() != 2 {
            return None;
        }
        let mut corners: Vec<Vec3> = Vec::with_capacity(4);
        for &i in indices.iter().flatten() {
            let p = *positions.get(i as usize)?;
            if !corners.contains(&p) {
                corners.push(p);
            }
        }
        if corners.len() != 4 {
            return None;
        }
        // The corner farthest from the first is the opposite one; the other two span the edges.
        let c0 = corners[0];
        let far = (1..4).max_by(|&a, &b| {
            (corners[a] - c0)
                .length_squared()
                .total_cmp(&(corners[b] - c0).length_squared())
        })?;
        let others: Vec<Vec3> = (1..4).filter(|&i| i != far).map(|i| corners[i]).collect();
        let (e1, e2) = (others[0] - c0, others[1] - c0);
        let (width, height) = (e1.length(), e2.length());
        let diagonal = (corners[far] - c0).length();
        let tolerance = 1e-4 * diagonal;
        let area: f32 = indices
            .iter()
            .map(|&[a, b, c]| {
                let (a, b, c) = (
                    positions[a as usize],
                    positions[b as usize],
                    positions[c as usize],
                );
                0.5 * (b - a).cross(c - a).length()
            })
            .sum();
        let is_rectangle = width > 0.0
            && height > 0.0
            && (c0 + e1 + e2 - corners[far]).length() <= tolerance
            && e1.dot(e2).abs() <= 1e-4 * width * height
            && (area - width * height).abs() <= 1e-4 * width * height;
        is_rectangle.then(|| Rectangle {
            corner: c0,
            ex: e1 / width,
            ey: e2 / height,
            width,
            height,
        })
    }

    /// Unit normal `ex × ey`.
    #[must_use]
    pub fn normal(&self) -> Vec3 {
        self.ex.cross(self.ey)
    }

    /// The point `u` maps to, uniformly by area: `corner + u.x·width·ex + u.y·height·ey` (the
    /// square's strata stay strata on the rectangle, where a choice between its two triangles
    /// would fold them).
    #[inline]
    #[must_use]
    pub fn point(&self, u: Vec2) -> Vec3 {
        self.corner + self.ex * (u.x * self.width) + self.ey * (u.y * self.height)
    }

    /// The rectangle seen from `p` when its solid angle there is within the bounds this module
    /// samples by solid angle (`None` otherwise, and for a point in its plane); the tests'
    /// view of [`Rectangle::seen_from`].
    #[cfg(test)]
    #[must_use]
    fn spherical(&self, p: Vec3) -> Option<SphericalRectangle> {
        match self.seen_from(p) {
            Seen::Spherical(s) => Some(s),
            _ => None,
        }
    }

    /// How `p` is to sample the rectangle: by area, by solid angle, or over the hemisphere.
    #[inline(always)]
    #[must_use]
    pub fn seen_from(&self, p: Vec3) -> Seen {
        self.classify(p).unwrap_or(Seen::Area)
    }

    /// Where `p + t d` (unit `d`, t > 0) meets the rectangle, if it does: `t`.
    #[must_use]
    pub fn hit(&self, p: Vec3, d: Vec3) -> Option<f32> {
        let n = self.normal();
        let t = (self.corner - p).dot(n) / d.dot(n);
        if !(t > 0.0 && t.is_finite()) {
            return None;
        }
        let q = p + d * t - self.corner;
        let (a, b) = (q.dot(self.ex), q.dot(self.ey));
        ((0.0..=self.width).contains(&a) && (0.0..=self.height).contains(&b)).then_some(t)
    }

    /// Whether a point at `q` from the corner lies within the rectangle's diagonal of it. The
    /// centre's guess of the solid angle misses what such a point sees: near the plane beside
    /// the centre the guess's cosine vanishes while the nearest part of the rectangle is close
    /// (a march point a centimetre below a ceiling lamp's corner guessed 0.07 sr for some 1.5,
    /// and area sampling's weight `A cos θ/d²` read its in-scattered light 200 times over).
    /// `centre2` is the squared distance to the centre, which is within half a diagonal of
    /// the nearest point.
    #[inline]
    fn near(&self, q: Vec3, centre2: f32) -> bool {
        let diagonal2 = self.width * self.width + self.height * self.height;
        if centre2 > 2.25 * diagonal2 {
            return false;
        }
        let (a, b, z) = (q.dot(self.ex), q.dot(self.ey), q.dot(self.normal()));
        let (da, db) = (a - a.clamp(0.0, self.width), b - b.clamp(0.0, self.height));
        da * da + db * db + z * z < diagonal2
    }

    #[inline(always)]
    fn classify(&self, p: Vec3) -> Option<Seen> {
        // A cheap first guess of the solid angle (the rectangle as a point at its centre): where
        // it is small, area sampling is as good and costs less.
        let to_centre = self.corner + 0.5 * (self.ex * self.width + self.ey * self.height) - p;
        let d2 = to_centre.length_squared();
        let guess =
            self.width * self.height * self.normal().dot(to_centre).abs() / (d2 * d2.sqrt());
        let d = self.corner - p;
        if guess.is_nan() || guess < SOLID_ANGLE_FROM && !self.near(-d, d2) {
            return Some(Seen::Area);
        }
        let mut z = self.normal();
        let (x0, y0) = (d.dot(self.ex), d.dot(self.ey));
        let mut z0 = d.dot(z);
        if z0 > 0.0 {
            z = -z;
            z0 = -z0;
        }
        if z0.is_nan() || z0 >= 0.0 {
            return None;
        }
        let (x1, y1) = (x0 + self.width, y0 + self.height);
        // The normals of the planes through p and each edge, v00 × v10, v10 × v11, v11 × v01
        // and v01 × v00 over the corners v_ij = (x_i, y_j, z0): each has a zero component and
        // the edge's length as a positive factor (Ureña et al. 2013, Algorithm 1).
        let n0 = Vec3::new(0.0, z0, -y0).try_normalize()?;
        let n1 = Vec3::new(-z0, 0.0, x1).try_normalize()?;
        let n2 = Vec3::new(0.0, -z0, y1).try_normalize()?;
        let n3 = Vec3::new(z0, 0.0, -x0).try_normalize()?;
        let g0 = angle_between(-n0, n1);
        let g1 = angle_between(-n1, n2);
        let g2 = angle_between(-n2, n3);
        let g3 = angle_between(-n3, n0);
        let solid_angle = g0 + g1 + g2 + g3 - 2.0 * PI;
        if solid_angle > MAX_SOLID_ANGLE {
            return Some(Seen::Nearly(-z));
        }
        if solid_angle < MIN_SOLID_ANGLE {
            return Some(Seen::Area);
        }
        Some(Seen::Spherical(SphericalRectangle {
            x: self.ex,
            y: self.ey,
            z,
            x0,
            x1,
            y0,
            y1,
            z0,
            b0: n0.z,
            b1: n2.z,
            k: g2 + g3,
            solid_angle,
        }))
    }
}

impl SphericalRectangle {
    /// The point on the rectangle in the direction `u` maps to, uniformly by solid angle from
    /// `p` (the reference point this was made for).
    #[must_use]
    pub fn sample(&self, p: Vec3, u: Vec2) -> Vec3 {
        // Azimuth: the area of the sub-rectangle left of the sample is u.x of the whole.
        let au = u.x * self.solid_angle - self.k;
        let fu = (au.cos() * self.b0 - self.b1) / au.sin();
        let cu = (1.0 / (fu * fu + self.b0 * self.b0).sqrt())
            .copysign(fu)
            .clamp(-1.0 + f32::EPSILON, 1.0 - f32::EPSILON);
        let xu = (-(cu * self.z0) / (1.0 - cu * cu).max(0.0).sqrt()).clamp(self.x0, self.x1);
        // Elevation along the chosen line, uniform in the sine of the angle from it.
        let dd = (xu * xu + self.z0 * self.z0).sqrt();
        let h0 = self.y0 / (dd * dd + self.y0 * self.y0).sqrt();
        let h1 = self.y1 / (dd * dd + self.y1 * self.y1).sqrt();
        let hv = h0 + u.y * (h1 - h0);
        let hv2 = hv * hv;
        let yv = if hv2 < 1.0 - 1e-6 {
            (hv * dd / (1.0 - hv2).sqrt()).clamp(self.y0, self.y1)
        } else {
            self.y1
        };
        p + self.x * xu + self.y * yv + self.z * self.z0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_square() -> Rectangle {
        let positions = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ];
        Rectangle::from_triangles(&positions, &[[0, 1, 2], [0, 2, 3]]).expect("a rectangle")
    }

    /// The solid angle of a rectangle seen from above one corner (Howell's B-3 / the
    /// closed form Ω = atan(ab / (h √(a² + b² + h²)))).
    #[test]
    fn solid_angle_matches_the_closed_form() {
        let r = unit_square();
        for h in [0.1f32, 0.5, 1.0, 3.0] {
            let s = r.spherical(Vec3::new(0.0, 0.0, h)).expect("in range");
            let expect = (1.0 / (h * (2.0 + h * h).sqrt())).atan();
            assert!(
                (s.solid_angle - expect).abs() < 1e-4 * expect.max(1e-2),
                "h {h}: {} vs {expect}",
                s.solid_angle
            );
        }
    }

    #[test]
    fn parallelograms_and_other_meshes_are_not_rectangles() {
        let skew = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.5, 1.0, 0.0),
            Vec3::new(0.5, 1.0, 0.0),
        ];
        assert!(Rectangle::from_triangles(&skew, &[[0, 1, 2], [0, 2, 3]]).is_none());
        let square = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ];
        // One triangle twice: not the rectangle's area.
        assert!(Rectangle::from_triangles(&square, &[[0, 1, 2], [0, 1, 2]]).is_none());
        assert!(Rectangle::from_triangles(&square, &[[0, 1, 2]]).is_none());
    }

    /// Points near the rectangle are not sampled by area where its weight `A cos θ/d²` could
    /// pass the hemisphere's 2π: near the plane, beside or under the rectangle's edges and
    /// corners, where the centre's guess of the solid angle is small.
    #[test]
    fn points_near_a_rectangle_are_not_sampled_by_area() {
        let positions = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 0.8, 0.0),
            Vec3::new(0.0, 0.8, 0.0),
        ];
        let r =
            Rectangle::from_triangles(&positions, &[[0, 1, 2], [0, 2, 3]]).expect("a rectangle");
        let mut area_sampled = 0;
        for z in [-0.3f32, -0.02, -0.003, 0.01, 0.1, 2.0] {
            for i in 0..=40 {
                for j in 0..=40 {
                    let p = Vec3::new(-3.0 + i as f32 * 0.175, -3.0 + j as f32 * 0.17, z);
                    if !matches!(r.seen_from(p), Seen::Area) {
                        continue;
                    }
                    area_sampled += 1;
                    // The largest weight over the rectangle: at its nearest point.
                    let nearest = Vec3::new(p.x.clamp(0.0, 1.0), p.y.clamp(0.0, 0.8), 0.0);
                    let d = (p - nearest).length();
                    let weight = 0.8 * z.abs() / (d * d * d);
                    assert!(weight < 2.0 * PI, "{p}: by area, weights up to {weight}");
                }
            }
        }
        assert!(area_sampled > 100, "{area_sampled} points sampled by area");
    }

    /// Uniform by solid angle: the fraction of samples falling on each quarter of the rectangle
    /// is that quarter's share of the solid angle.
    #[test]
    fn samples_are_uniform_in_solid_angle() {
        let r = unit_square();
        let p = Vec3::new(0.2, 0.3, 0.4);
        let s = r.spherical(p).expect("in range");
        let quarters = [(0.0, 0.0), (0.5, 0.0), (0.0, 0.5), (0.5, 0.5)];
        let mut counts = [0u32; 4];
        let n = 256;
        for i in 0..n {
            for j in 0..n {
                let u = Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
                let q = s.sample(p, u);
                assert!(
                    q.z.abs() < 1e-5 && (-1e-5..=1.0 + 1e-5).contains(&q.x),
                    "{q}"
                );
                let k = usize::from(q.x >= 0.5) + 2 * usize::from(q.y >= 0.5);
                counts[k] += 1;
            }
        }
        for (k, &(qx, qy)) in quarters.iter().enumerate() {
            let positions = [
                Vec3::new(qx, qy, 0.0),
                Vec3::new(qx + 0.5, qy, 0.0),
                Vec3::new(qx + 0.5, qy + 0.5, 0.0),
                Vec3::new(qx, qy + 0.5, 0.0),
            ];
            let quarter = Rectangle::from_triangles(&positions, &[[0, 1, 2], [0, 2, 3]])
                .and_then(|r| r.spherical(p))
                .expect("quarter");
            let share = f64::from(counts[k]) / f64::from(n * n);
            let expect = f64::from(quarter.solid_angle / s.solid_angle);
            assert!(
                (share - expect).abs() < 2e-3,
                "quarter {k}: {share} vs {expect}"
            );
        }
    }
}
