//! Orthonormal shading frames: world ↔ local, with the normal as local +z.

use glam::Vec3;

/// An orthonormal basis `(s, t, n)`; local coordinates have `n` as +z.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    /// First tangent.
    pub s: Vec3,
    /// Second tangent.
    pub t: Vec3,
    /// Normal.
    pub n: Vec3,
}

impl Frame {
    /// A frame around the unit vector `n` (Duff et al. 2017, "Building an Orthonormal Basis,
    /// Revisited": continuous except at n.z = -1 sign flip, no normalisation needed).
    #[must_use]
    pub fn from_z(n: Vec3) -> Frame {
        let sign = 1.0f32.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        let s = Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
        let t = Vec3::new(b, sign + n.y * n.y * a, -n.y);
        Frame { s, t, n }
    }

    /// A frame with normal `n` whose first tangent is `s` projected orthogonal to `n` (falls back to
    /// [`Frame::from_z`] if `s` is parallel to `n`).
    #[must_use]
    pub fn from_normal_tangent(n: Vec3, s: Vec3) -> Frame {
        let s = s - n * n.dot(s);
        let len = s.length();
        if len.is_nan()
            || len <= 1e-6 * s.abs().max_element().max(f32::MIN_POSITIVE)
            || len.is_infinite()
        {
            return Frame::from_z(n);
        }
        let s = s / len;
        Frame {
            s,
            t: n.cross(s),
            n,
        }
    }

    /// World direction → local coordinates.
    #[must_use]
    pub fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.s), v.dot(self.t), v.dot(self.n))
    }

    /// Local coordinates → world direction.
    #[must_use]
    pub fn from_local(&self, v: Vec3) -> Vec3 {
        self.s * v.x + self.t * v.y + self.n * v.z
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_is_orthonormal_and_round_trips() {
        for &n in &[
            Vec3::Z,
            -Vec3::Z,
            Vec3::X,
            Vec3::new(0.3, -0.5, 0.8).normalize(),
            Vec3::new(-1e-7, 0.0, -1.0).normalize(),
        ] {
            let f = Frame::from_z(n);
            assert!((f.s.length() - 1.0).abs() < 1e-5);
            assert!((f.t.length() - 1.0).abs() < 1e-5);
            assert!(
                f.s.dot(f.t).abs() < 1e-5 && f.s.dot(n).abs() < 1e-5 && f.t.dot(n).abs() < 1e-5
            );
            assert!((f.s.cross(f.t) - n).length() < 1e-5, "right-handed");
            let v = Vec3::new(0.2, 0.7, -0.4);
            assert!((f.from_local(f.to_local(v)) - v).length() < 1e-5);
        }
    }
}
