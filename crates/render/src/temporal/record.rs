//! A record over time (plain data): its value at creation, its temporal gradients, its lifespan,
//! and the rigid motion of the shape it sits on (001 §5.2, eqs. 5.9–5.17; `NOTES-001.md` D.1,
//! D.4).

use crate::irradiance_cache::build::Site;
use crate::irradiance_cache::Record;
use crate::radiance_cache::gather::RadianceCoefficients;
use crate::radiance_cache::record::RadianceRecord;
use crate::scene::Interaction;
use ircache_math::{Frame, Mat3, Mat4, Rgb, Vec3};

/// Temporal gradients: the change per frame of the irradiance and of both spatial gradients
/// (∇tE, ∇t∇r, ∇t∇p of 5.9–5.11), in the record's orientation at its creation.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Slope {
    /// ∂E/∂t per frame.
    pub e: Rgb,
    /// ∂∇r/∂t per channel.
    pub grad_r: [Vec3; 3],
    /// ∂∇p/∂t per channel.
    pub grad_t: [Vec3; 3],
}

impl Slope {
    /// The slope from `a` at frame `ta` to `b` at frame `tb` > `ta` (5.12–5.14 with tb = ta + 1,
    /// 5.15–5.17 with the successor's frame): both in the same orientation.
    #[must_use]
    pub fn between(a: &Record, b: &Record, frames: u32) -> Slope {
        let k = 1.0 / frames.max(1) as f32;
        Slope {
            e: (b.e - a.e) * k,
            grad_r: std::array::from_fn(|c| (b.grad_r[c] - a.grad_r[c]) * k),
            grad_t: std::array::from_fn(|c| (b.grad_t[c] - a.grad_t[c]) * k),
        }
    }
}

/// Where a record's gradients come from over its life.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SlopeKind {
    /// None: the value at creation holds (age-based and per-frame caches).
    Constant,
    /// Extrapolated from the estimate of the next frame (5.12–5.14).
    Extrapolated,
    /// Interpolated towards the successor's value (5.15–5.17, attached to this record: the
    /// slope over [t_k, t_l], `NOTES-001.md` D.4).
    Interpolated,
}

/// One record of an animation's cache.
#[derive(Clone, Copy, Debug)]
pub struct TemporalRecord {
    /// The record as gathered, at frame `born`, in that frame's world.
    pub record: Record,
    /// Where and how it was gathered (to gather the next frame and the successor alike).
    pub site: Site,
    /// The seed its gather used.
    pub seed: u64,
    /// Frame of creation (t_k).
    pub born: u32,
    /// Last frame it serves (t_k + L).
    pub last: u32,
    /// Temporal gradients.
    pub slope: Slope,
    /// What the slope is.
    pub kind: SlopeKind,
    /// The record that replaced it at its place, if any.
    pub successor: Option<u32>,
}

impl TemporalRecord {
    /// Whether it serves frame `frame`.
    #[must_use]
    pub fn live_at(&self, frame: u32) -> bool {
        self.born <= frame && frame <= self.last
    }

    /// The record at `frame` (within its life): 5.11's temporal terms added to the value and
    /// both gradients, then moved by `motion`, its shape's motion from `born` to `frame`.
    #[must_use]
    pub fn at(&self, frame: u32, motion: Option<&Mat4>) -> Record {
        let dt = frame.saturating_sub(self.born) as f32;
        let mut r = self.record;
        r.e = (r.e + self.slope.e * dt).max(Rgb::ZERO);
        for c in 0..3 {
            r.grad_r[c] += self.slope.grad_r[c] * dt;
            r.grad_t[c] += self.slope.grad_t[c] * dt;
        }
        match motion {
            Some(m) => move_record(&r, m),
            None => r,
        }
    }
}

/// A radiance record over time (001 §5.2 for radiance caching): its coefficients at birth and
/// the change per frame of each coefficient and gradient coefficient (no rotation term).
#[derive(Clone, Debug)]
pub struct RadianceTrack {
    /// The record at birth.
    pub born: RadianceRecord,
    /// Change per frame (all zero: constant).
    pub slope: RadianceCoefficients,
}

impl RadianceTrack {
    /// A track that holds its value.
    #[must_use]
    pub fn constant(born: RadianceRecord) -> RadianceTrack {
        let zero = |v: &Vec<f64>| vec![0.0; v.len()];
        let r = &born.radiance;
        let slope = RadianceCoefficients {
            order: r.order,
            coefficients: zero(&r.coefficients),
            gradient_x: zero(&r.gradient_x),
            gradient_y: zero(&r.gradient_y),
        };
        RadianceTrack { born, slope }
    }

    /// Sets the slope from the born coefficients to `later`'s, `frames` frames on (same frame).
    pub fn slope_to(&mut self, later: &RadianceCoefficients, frames: u32) {
        let k = 1.0 / f64::from(frames.max(1));
        let d = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| (y - x) * k).collect();
        let r = &self.born.radiance;
        self.slope = RadianceCoefficients {
            order: r.order,
            coefficients: d(&r.coefficients, &later.coefficients),
            gradient_x: d(&r.gradient_x, &later.gradient_x),
            gradient_y: d(&r.gradient_y, &later.gradient_y),
        };
    }

    /// The record `frames` frames after its birth, moved by `motion` (its frame turned with it).
    #[must_use]
    pub fn at(&self, frames: u32, motion: Option<&Mat4>) -> RadianceRecord {
        let t = f64::from(frames);
        let add = |a: &[f64], s: &[f64]| a.iter().zip(s).map(|(x, y)| x + y * t).collect();
        let (r, s) = (&self.born.radiance, &self.slope);
        let mut out = RadianceRecord {
            radiance: RadianceCoefficients {
                order: r.order,
                coefficients: add(&r.coefficients, &s.coefficients),
                gradient_x: add(&r.gradient_x, &s.gradient_x),
                gradient_y: add(&r.gradient_y, &s.gradient_y),
            },
            ..self.born.clone()
        };
        if let Some(m) = motion {
            let (rot, _) = rotation_scale(m);
            out.position = m.transform_point3(out.position.as_vec3()).as_dvec3();
            out.frame = Mat3::from_mat4(rot).as_dmat3() * out.frame;
        }
        out
    }
}

/// The rotation and the uniform scale of a rigid (similarity) motion.
fn rotation_scale(m: &Mat4) -> (Mat4, f32) {
    let s = m.transform_vector3(Vec3::X).length().max(f32::MIN_POSITIVE);
    let mut r = *m * (1.0 / s);
    r.w_axis = ircache_math::Vec4::W;
    (r, s)
}

/// A record carried by its shape's motion `m`: position and normal moved; the gradients, which
/// live in the record's tangent frame, turned with it (∇p also scaled by 1/s, R by s).
#[must_use]
pub fn move_record(r: &Record, m: &Mat4) -> Record {
    let (rot, s) = rotation_scale(m);
    let turn = |v: Vec3| rot.transform_vector3(v);
    Record {
        p: m.transform_point3(r.p),
        n: turn(r.n).normalize_or_zero(),
        grad_r: r.grad_r.map(turn),
        grad_t: r.grad_t.map(|g| turn(g) / s),
        r: r.r * s,
        ..*r
    }
}

/// A shading point carried by its shape's motion `m`.
#[must_use]
pub fn move_point(
    sp: &crate::irradiance_cache::gather::ShadingPoint,
    m: &Mat4,
) -> crate::irradiance_cache::gather::ShadingPoint {
    let (rot, _) = rotation_scale(m);
    let turn = |v: Vec3| rot.transform_vector3(v).normalize_or_zero();
    let it = sp.it;
    crate::irradiance_cache::gather::ShadingPoint {
        it: Interaction {
            p: m.transform_point3(it.p),
            ng: turn(it.ng),
            frame: Frame {
                s: turn(it.frame.s),
                t: turn(it.frame.t),
                n: turn(it.frame.n),
            },
            base_n: turn(it.base_n),
            ..it
        },
        n: turn(sp.n),
        n_bump: turn(sp.n_bump),
        ..*sp
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::irradiance_cache::record::NO_RADIANCE;

    fn record(e: f32, p: Vec3) -> Record {
        Record {
            p,
            n: Vec3::Z,
            e: Rgb::splat(e),
            r: 1.0,
            grad_t: [Vec3::new(0.1, 0.0, 0.0); 3],
            grad_r: [Vec3::new(0.0, 0.2, 0.0); 3],
            level: 0,
            ray_variance: 0.0,
            radiance: NO_RADIANCE,
        }
    }

    #[test]
    fn interpolated_slope_reaches_the_successor_exactly() {
        // 5.15–5.17: evaluating k at t_l with the slope towards l gives l's value.
        let k = record(1.0, Vec3::ZERO);
        let mut l = record(1.6, Vec3::ZERO);
        l.grad_t[1] = Vec3::new(0.4, -0.2, 0.0);
        let slope = Slope::between(&k, &l, 6);
        let tr = TemporalRecord {
            record: k,
            site: Site {
                index: 0,
                point: a_point(),
                key: 0,
                rays: 0,
            },
            seed: 0,
            born: 10,
            last: 15,
            slope,
            kind: SlopeKind::Interpolated,
            successor: None,
        };
        let at = tr.at(16, None);
        assert!((at.e.r - 1.6).abs() < 1e-6);
        assert!((at.grad_t[1] - l.grad_t[1]).length() < 1e-6);
        // Halfway, halfway.
        assert!((tr.at(13, None).e.g - 1.3).abs() < 1e-6);
    }

    #[test]
    fn a_moved_record_extrapolates_as_the_unmoved_one_in_its_own_frame() {
        // Rotating and translating the record and the query point together leaves 3.15's value
        // unchanged.
        let r = record(1.0, Vec3::new(0.5, 0.0, 0.0));
        let m = Mat4::from_translation(Vec3::new(1.0, 2.0, 3.0))
            * Mat4::from_axis_angle(Vec3::new(1.0, 1.0, 0.0).normalize(), 0.7);
        let moved = move_record(&r, &m);
        let (p, n) = (
            Vec3::new(0.6, 0.1, 0.0),
            Vec3::new(0.1, 0.0, 1.0).normalize(),
        );
        use crate::irradiance_cache::record::{extrapolate, GradientMode};
        let a = extrapolate(&r, p, n, GradientMode::Full);
        let b = extrapolate(
            &moved,
            m.transform_point3(p),
            m.transform_vector3(n),
            GradientMode::Full,
        );
        assert!((a.r - b.r).abs() < 1e-5 && (a.g - b.g).abs() < 1e-5);
    }

    fn a_point() -> crate::irradiance_cache::gather::ShadingPoint {
        crate::irradiance_cache::gather::ShadingPoint {
            it: Interaction {
                p: Vec3::ZERO,
                ng: Vec3::Z,
                frame: Frame::from_z(Vec3::Z),
                base_n: Vec3::Z,
                uv: ircache_math::Vec2::ZERO,
                shape: 0,
                prim: 0,
                t: 1.0,
            },
            n: Vec3::Z,
            n_bump: Vec3::Z,
            cos_view: 1.0,
            travelled: 1.0,
        }
    }
}
