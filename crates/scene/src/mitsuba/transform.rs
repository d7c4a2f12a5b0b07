//! Mitsuba 3's transform operations (`<transform>` children), as 4×4 matrices.
//!
//! Inside a `<transform>`, operations compose in document order, each later one multiplying from
//! the left: `<translate/><rotate/>` is `R · T`, as in Mitsuba's XML parser.

use ircache_math::{Mat4, Vec3, Vec4};

/// A matrix from 16 numbers in row-major order (Mitsuba's `<matrix value="...">`).
#[must_use]
pub fn matrix_row_major(v: &[f32; 16]) -> Mat4 {
    Mat4::from_cols_array(v).transpose()
}

/// A matrix from 9 numbers in row-major order, embedded in a 4×4 identity (Mitsuba accepts
/// 3×3 matrices this way).
#[must_use]
pub fn matrix3_row_major(v: &[f32; 9]) -> Mat4 {
    Mat4::from_cols(
        Vec4::new(v[0], v[3], v[6], 0.0),
        Vec4::new(v[1], v[4], v[7], 0.0),
        Vec4::new(v[2], v[5], v[8], 0.0),
        Vec4::W,
    )
}

/// Translation.
#[must_use]
pub fn translate(v: Vec3) -> Mat4 {
    Mat4::from_translation(v)
}

/// Non-uniform scale.
#[must_use]
pub fn scale(v: Vec3) -> Mat4 {
    Mat4::from_scale(v)
}

/// Rotation by `angle_degrees` counter-clockwise about `axis` (normalised here), as Mitsuba's
/// `Transform4f::rotate`. `None` for a zero or non-finite axis.
#[must_use]
pub fn rotate(axis: Vec3, angle_degrees: f32) -> Option<Mat4> {
    let len = axis.length();
    if !len.is_finite() || len == 0.0 || !angle_degrees.is_finite() {
        return None;
    }
    Some(Mat4::from_axis_angle(
        axis / len,
        angle_degrees.to_radians(),
    ))
}

/// Mitsuba's `Transform4f::look_at`: camera at `origin` looking along +z towards `target`;
/// `left = normalize(up × dir)`, `new_up = dir × left`; the matrix columns are left, new_up, dir
/// and origin. A zero `up` is replaced by a vector perpendicular to the view direction, as
/// Mitsuba's parser does. `None` when the result is not finite (target = origin, or `up` parallel
/// to the view direction).
#[must_use]
pub fn look_at(origin: Vec3, target: Vec3, up: Vec3) -> Option<Mat4> {
    let dir = (target - origin).normalize();
    let up = if up.length_squared() == 0.0 {
        coordinate_system(dir).0
    } else {
        up
    };
    let left = up.cross(dir).normalize();
    let new_up = dir.cross(left);
    let m = Mat4::from_cols(
        left.extend(0.0),
        new_up.extend(0.0),
        dir.extend(0.0),
        origin.extend(1.0),
    );
    m.is_finite().then_some(m)
}

/// Two unit vectors completing `n` to an orthonormal basis (Duff et al. 2017, as Mitsuba's
/// `coordinate_system`).
#[must_use]
pub fn coordinate_system(n: Vec3) -> (Vec3, Vec3) {
    let sign = 1.0f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        Vec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn assert_mat_close(a: Mat4, b: Mat4) {
        let (a, b) = (a.to_cols_array(), b.to_cols_array());
        for i in 0..16 {
            assert!((a[i] - b[i]).abs() < 1e-5, "{a:?} vs {b:?}");
        }
    }

    #[test]
    fn row_major_matrix() {
        let m = matrix_row_major(&[
            1., 2., 3., 4., 5., 6., 7., 8., 9., 10., 11., 12., 0., 0., 0., 1.,
        ]);
        // Row 0 is (1 2 3 4): the translation column is (4, 8, 12).
        assert_eq!(m.w_axis, Vec4::new(4., 8., 12., 1.));
        assert_eq!(m.row(1), Vec4::new(5., 6., 7., 8.));
        assert_eq!(m.transform_point3(Vec3::ZERO), Vec3::new(4., 8., 12.));
    }

    #[test]
    fn rotate_is_counter_clockwise() {
        let r = rotate(Vec3::new(0., 0., 2.), 90.0).unwrap();
        assert!((r.transform_vector3(Vec3::X) - Vec3::Y).length() < 1e-6);
        assert!(rotate(Vec3::ZERO, 10.0).is_none());
    }

    #[test]
    fn look_at_matches_mitsuba() {
        let o = Vec3::new(1., 2., 3.);
        let t = Vec3::new(1., 2., 10.);
        let m = look_at(o, t, Vec3::Y).unwrap();
        // dir = +z, left = y × z = x, up = z × x = y: identity rotation.
        assert_mat_close(m, Mat4::from_translation(o));
        let m = look_at(Vec3::ZERO, Vec3::new(0., 0., -1.), Vec3::Y).unwrap();
        // dir = −z, left = y × (−z) = −x.
        assert!((m.x_axis.truncate() + Vec3::X).length() < 1e-6);
        assert!((m.y_axis.truncate() - Vec3::Y).length() < 1e-6);
        assert!(look_at(Vec3::ZERO, Vec3::Y, Vec3::Y).is_none());
        assert!(look_at(Vec3::ZERO, Vec3::Y, Vec3::ZERO).is_some());
    }
}
