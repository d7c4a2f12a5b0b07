//! Irradiance and its gradients through media against NOTES-002 §3.2's closed forms: an emitting
//! plane seen through an absorbing medium (T2), a black plane in an emitting medium (T3), the
//! equilibrium of both (T4), a linear emission ramp (T5), a Henyey–Greenstein slab lit by a
//! distant light (T7), and the same values at a thousand times the scale. Each comparison
//! variant fails where the notes say it fails.

mod common;

use ircache_math::{DVec3, Vec2};
use ircache_render::irradiance_cache::hemisphere::Stratification;
use ircache_render::media_cache::gradient::{gather, GatherMedium, March, MediaGradient};

/// A plane {y : m·y = d} of radiance `plane_l` in a homogeneous medium σ filling space with a
/// source q(p) = q0 (1 + ramp·p.x) (ramp's gradient along x).
struct PlaneInMedium {
    m: DVec3,
    d: f64,
    plane_l: f64,
    sigma: f64,
    q0: f64,
    ramp: f64,
    has_plane: bool,
}

impl GatherMedium for PlaneInMedium {
    fn surface(&self, o: DVec3, w: DVec3) -> (f64, [f64; 3]) {
        let cos = self.m.dot(w);
        if self.has_plane && cos > 0.0 {
            let s = (self.d - self.m.dot(o)) / cos;
            if s > 0.0 {
                return (s, [self.plane_l; 3]);
            }
        }
        (f64::INFINITY, [0.0; 3])
    }
    fn boundaries(&self, _: DVec3, _: DVec3, _: f64) -> Vec<(f64, DVec3)> {
        Vec::new()
    }
    fn sigma_t(&self, _: DVec3, _: DVec3, _: f64) -> [f64; 3] {
        [self.sigma; 3]
    }
    fn sigma_t_gradient(&self, _: DVec3, _: DVec3, _: f64) -> [DVec3; 3] {
        [DVec3::ZERO; 3]
    }
    fn source(&self, o: DVec3, w: DVec3, t: f64) -> [f64; 3] {
        [self.q0 * (1.0 + self.ramp * (o + w * t).x); 3]
    }
    fn source_gradient(&self, _: DVec3, _: DVec3, _: f64) -> [DVec3; 3] {
        [DVec3::X * (self.q0 * self.ramp); 3]
    }
}

fn plane(beta_degrees: f64, plane_l: f64, q0: f64, scale: f64) -> PlaneInMedium {
    let b = beta_degrees.to_radians();
    PlaneInMedium {
        m: DVec3::new(b.sin(), 0.0, b.cos()),
        d: scale,
        plane_l,
        sigma: 1.0 / scale,
        q0: q0 / scale,
        ramp: 0.0,
        has_plane: true,
    }
}

const FRAME: [DVec3; 3] = [DVec3::X, DVec3::Y, DVec3::Z];

/// E and the gradient parts at the origin, cell centres, M × 2M cells.
fn at_origin(
    scene: &dyn GatherMedium,
    m: usize,
) -> ircache_render::media_cache::gradient::MediaGather {
    let strata = Stratification {
        polar: m,
        azimuthal: 2 * m,
    };
    gather(
        scene,
        DVec3::ZERO,
        FRAME,
        strata,
        &March::default(),
        |_, _| Vec2::splat(0.5),
    )
}

fn close(got: f64, want: f64, rel: f64, what: &str) {
    assert!(
        (got - want).abs() <= rel * want.abs().max(1e-9),
        "{what}: {got} vs {want} (allowed {:.1} %)",
        rel * 100.0
    );
}

/// T2: an emitting plane (L = 1) at distance 1 through an absorbing medium (σ = 1): E and ∂E/∂u
/// with eq. 11's and eq. 17's parts to the notes' digits; the media-blind and JDZJ08 variants
/// miss by more than 30 %.
#[test]
fn emitting_plane_through_absorbing_medium() {
    for (beta, e, du, walls, absorption) in [
        (0.0, 0.6892150, 0.0, 0.0, 0.0),
        (45.0, 0.5021742, 0.4922892, 0.3070227, 0.1852666),
        (90.0, 0.1808828, 0.2948074, 0.1726878, 0.1221196),
    ] {
        let g = at_origin(&plane(beta, 1.0, 0.0, 1.0), 64);
        let (es, em) = g.irradiance();
        close(es[0], e, 0.01, &format!("T2 β {beta}: E_s"));
        assert_eq!(em[0], 0.0);
        let parts = g.gradient_parts();
        let total = parts.total(MediaGradient::Corrected)[0];
        if du == 0.0 {
            assert!(
                total.x.abs() < 0.01 && total.y.abs() < 0.01,
                "T2 β 0: {total}"
            );
            continue;
        }
        close(f64::from(total.x), du, 0.05, &format!("T2 β {beta}: ∂E/∂u"));
        assert!(f64::from(total.y).abs() < 0.02 * du, "∂E/∂v {}", total.y);
        close(
            f64::from(parts.surface_walls[0].x),
            walls,
            0.05,
            "eq. 11 part",
        );
        close(
            f64::from(parts.absorption[0].x),
            absorption,
            0.05,
            "eq. 17 part",
        );
        for v in [MediaGradient::None, MediaGradient::Jdzj08] {
            let x = f64::from(parts.total(v)[0].x);
            assert!(
                (x - du).abs() > 0.3 * du,
                "{v:?} should miss T2: {x} vs {du}"
            );
        }
        assert_eq!(
            parts.total(MediaGradient::Paper)[0].x,
            total.x,
            "no medium: paper = corrected"
        );
    }
}

/// T3: a black plane in an absorbing, emitting medium (σ_a = 1, L_e = 1): E = π − I and
/// ∂E/∂u = −(eq. 24 walls + radial endpoint); `none` sees only the walls, `jdzj08` only the
/// radial part; 002's literal pivot reading happens to be right here.
#[test]
fn black_plane_in_emitting_medium() {
    for (beta, e, du, walls, radial) in [
        (90.0, 2.9607099, -0.2948074, -0.1726878, -0.1221196),
        (45.0, 2.6394185, -0.4922892, -0.3070227, -0.1852666),
    ] {
        let g = at_origin(&plane(beta, 0.0, 1.0, 1.0), 64);
        let (es, em) = g.irradiance();
        assert_eq!(es[0], 0.0);
        close(em[0], e, 0.01, &format!("T3 β {beta}: E_m"));
        let parts = g.gradient_parts();
        close(
            f64::from(parts.total(MediaGradient::Corrected)[0].x),
            du,
            0.05,
            &format!("T3 β {beta}: ∂E/∂u"),
        );
        close(
            f64::from(parts.medium_walls[0].x),
            walls,
            0.05,
            "eq. 24 walls",
        );
        close(
            f64::from(parts.radial[0].x),
            radial,
            0.05,
            "radial endpoint",
        );
        close(
            f64::from(parts.total(MediaGradient::Paper)[0].x),
            du,
            0.05,
            "paper (pivot) on T3",
        );
        for v in [MediaGradient::None, MediaGradient::Jdzj08] {
            let x = f64::from(parts.total(v)[0].x);
            assert!(
                (x - du).abs() > 0.3 * du.abs(),
                "{v:?} should miss T3: {x} vs {du}"
            );
        }
    }
}

/// T4: an emitting wall (L = 1) in an equally emitting medium: E = π and no gradient, while
/// ∇E_s = −∇E_m = 0.2948 (β = 90°).
#[test]
fn equilibrium_has_no_gradient() {
    for m in [8, 32] {
        let g = at_origin(&plane(90.0, 1.0, 1.0, 1.0), m);
        let (es, em) = g.irradiance();
        close(es[0] + em[0], std::f64::consts::PI, 1e-4, "T4: E");
        let p = g.gradient_parts();
        let surface = f64::from(p.surface_walls[0].x + p.absorption[0].x);
        let total = f64::from(p.total(MediaGradient::Corrected)[0].x);
        assert!(
            total.abs() <= 1e-3 * surface.abs(),
            "T4 at M = {m}: {total} against ∇E_s {surface}"
        );
        if m == 32 {
            close(surface, 0.2948074, 0.05, "T4: ∇E_s");
        }
    }
}

/// T5: no occluders, σ_a = σ_t = 2, L_e = 1 + 0.05x: E = π(1 + 0.05x), ∂E/∂u = 0.05π; 002's
/// pivot reading gives 0.0625π (+25 %).
#[test]
fn linear_emission_ramp() {
    let scene = PlaneInMedium {
        m: DVec3::Z,
        d: 1.0,
        plane_l: 0.0,
        sigma: 2.0,
        q0: 2.0,
        ramp: 0.05,
        has_plane: false,
    };
    let g = at_origin(&scene, 16);
    let (_, em) = g.irradiance();
    close(em[0], std::f64::consts::PI, 1e-3, "T5: E");
    let p = g.gradient_parts();
    let pi = std::f64::consts::PI;
    close(
        f64::from(p.total(MediaGradient::Corrected)[0].x),
        0.05 * pi,
        0.01,
        "T5 consistent",
    );
    let paper = f64::from(p.total(MediaGradient::Paper)[0].x);
    close(paper, 0.0625 * pi, 0.02, "T5 paper reading");
    assert!((paper - 0.05 * pi).abs() > 0.15 * 0.05 * pi);
}

/// T7: a slab 0 < z < 2 (σ_t = 1, albedo 0.8, Henyey–Greenstein g = 0.8) over a black floor, lit
/// by a distant light 45° off vertical: translation invariant along the floor, so ∇E = 0; the
/// pivot reading is not.
#[test]
fn henyey_greenstein_slab_is_translation_invariant() {
    struct Slab;
    const TOP: f64 = 2.0;
    impl Slab {
        /// The light's direction of travel.
        fn light() -> DVec3 {
            DVec3::new(1.0, 0.0, -1.0).normalize()
        }
        fn q(p: DVec3, w: DVec3) -> f64 {
            if p.z >= TOP {
                return 0.0;
            }
            let g = 0.8;
            let cos = Slab::light().dot(-w);
            let phase = (1.0 - g * g)
                / (4.0 * std::f64::consts::PI * (1.0 + g * g - 2.0 * g * cos).powf(1.5));
            let to_top = (TOP - p.z) / -Slab::light().z;
            0.8 * phase * (-to_top).exp()
        }
    }
    impl GatherMedium for Slab {
        fn surface(&self, _: DVec3, _: DVec3) -> (f64, [f64; 3]) {
            (f64::INFINITY, [0.0; 3])
        }
        fn boundaries(&self, o: DVec3, w: DVec3, t_max: f64) -> Vec<(f64, DVec3)> {
            let t = (TOP - o.z) / w.z;
            if w.z > 0.0 && t < t_max {
                vec![(t, DVec3::Z)]
            } else {
                vec![]
            }
        }
        fn sigma_t(&self, o: DVec3, w: DVec3, t: f64) -> [f64; 3] {
            [if (o + w * t).z < TOP { 1.0 } else { 0.0 }; 3]
        }
        fn sigma_t_gradient(&self, _: DVec3, _: DVec3, _: f64) -> [DVec3; 3] {
            [DVec3::ZERO; 3]
        }
        fn source(&self, o: DVec3, w: DVec3, t: f64) -> [f64; 3] {
            [Slab::q(o + w * t, w); 3]
        }
        fn source_gradient(&self, o: DVec3, w: DVec3, t: f64) -> [DVec3; 3] {
            // q ∝ e^{−(H − z)/cos 45°}: only z varies.
            [DVec3::Z * (Slab::q(o + w * t, w) / -Slab::light().z); 3]
        }
    }
    let g = at_origin(&Slab, 32);
    let (_, em) = g.irradiance();
    assert!(em[0] > 0.05, "lit: {}", em[0]);
    let p = g.gradient_parts();
    let h = TOP;
    let corrected = p.total(MediaGradient::Corrected)[0];
    assert!(
        f64::from(corrected.length()) <= 0.01 * em[0] / h,
        "T7 consistent: |∇E| = {} against E/H = {}",
        corrected.length(),
        em[0] / h
    );
    let paper = p.total(MediaGradient::Paper)[0];
    assert!(
        f64::from(paper.length()) > 0.05 * em[0] / h,
        "the pivot reading should see a gradient: {}",
        paper.length()
    );
}

/// T4b, heterogeneous: an emitting wall (L = 1) in an emitting medium (L_e = 1) whose absorption
/// varies in space, σ_a = 1 + ½ sin 2x cos 3y + 0.3 z: radiance 1 everywhere, so E = π and no
/// gradient, while the heterogeneous parts (the pivot ∇τ of the surface light, the rigid
/// transmittance gradient and the source's gradient in the medium) are each far from zero
/// (measured: parts ±0.24, total 5e-4; 002's pivot reading 0.44).
#[test]
fn heterogeneous_equilibrium_has_no_gradient() {
    struct Field;
    fn sigma(p: DVec3) -> f64 {
        1.0 + 0.5 * (2.0 * p.x).sin() * (3.0 * p.y).cos() + 0.3 * p.z
    }
    fn grad(p: DVec3) -> DVec3 {
        DVec3::new(
            (2.0 * p.x).cos() * (3.0 * p.y).cos(),
            -1.5 * (2.0 * p.x).sin() * (3.0 * p.y).sin(),
            0.3,
        )
    }
    impl GatherMedium for Field {
        fn surface(&self, o: DVec3, w: DVec3) -> (f64, [f64; 3]) {
            if w.x > 0.0 {
                ((1.0 - o.x) / w.x, [1.0; 3])
            } else {
                (f64::INFINITY, [0.0; 3])
            }
        }
        fn boundaries(&self, _: DVec3, _: DVec3, _: f64) -> Vec<(f64, DVec3)> {
            Vec::new()
        }
        fn sigma_t(&self, o: DVec3, w: DVec3, t: f64) -> [f64; 3] {
            [sigma(o + w * t); 3]
        }
        fn sigma_t_gradient(&self, o: DVec3, w: DVec3, t: f64) -> [DVec3; 3] {
            [grad(o + w * t); 3]
        }
        fn source(&self, o: DVec3, w: DVec3, t: f64) -> [f64; 3] {
            self.sigma_t(o, w, t)
        }
        fn source_gradient(&self, o: DVec3, w: DVec3, t: f64) -> [DVec3; 3] {
            self.sigma_t_gradient(o, w, t)
        }
    }
    let strata = Stratification {
        polar: 64,
        azimuthal: 128,
    };
    let march = March {
        optical_step: 0.02,
        max_steps: 2048,
        ..March::default()
    };
    let g = gather(
        &Field,
        DVec3::new(0.1, 0.2, 0.0),
        FRAME,
        strata,
        &march,
        |_, _| Vec2::splat(0.5),
    );
    let (es, em) = g.irradiance();
    close(es[0] + em[0], std::f64::consts::PI, 0.005, "T4b: E");
    let p = g.gradient_parts();
    let surface = p.surface_walls[0] + p.absorption[0];
    let medium = p.medium_walls[0] + p.interior_rigid[0] + p.radial[0];
    let total = p.total(MediaGradient::Corrected)[0];
    let scale = surface.length().max(medium.length());
    assert!(scale > 0.1, "the parts are sizeable: {surface} {medium}");
    let paper = p.total(MediaGradient::Paper)[0];
    assert!(
        paper.length() > 0.5 * scale,
        "the pivot reading sees a gradient here: {paper}"
    );
    assert!(
        total.length() <= 0.02 * scale,
        "T4b: ∇E = {total} against parts {surface} (surface) and {medium} (medium)"
    );
}

/// An absorbing, emitting unit cube in vacuum (σ_a = 1, L_e = 1), bottom at z = 0.5, beside the
/// receiver (T6): every ray escapes, so the whole gradient is the interface terms (the medium's
/// light starting and ending where rays cross the faces). Against central differences of the
/// irradiance at the same cell centres (continuous in x: chords shrink to nothing at the
/// silhouette), within 1 %.
#[test]
fn emitting_cube_gradient_comes_from_its_faces() {
    struct Cube;
    const LO: [f64; 3] = [-0.5, -0.5, 0.5];
    const HI: [f64; 3] = [0.5, 0.5, 1.5];
    fn inside(p: DVec3) -> bool {
        (0..3).all(|a| p[a] > LO[a] && p[a] < HI[a])
    }
    impl GatherMedium for Cube {
        fn surface(&self, _: DVec3, _: DVec3) -> (f64, [f64; 3]) {
            (f64::INFINITY, [0.0; 3])
        }
        fn boundaries(&self, o: DVec3, w: DVec3, t_max: f64) -> Vec<(f64, DVec3)> {
            let (mut t0, mut t1) = (0.0f64, t_max);
            let (mut n0, mut n1) = (DVec3::ZERO, DVec3::ZERO);
            for a in 0..3 {
                let (mut near, mut far) = ((LO[a] - o[a]) / w[a], (HI[a] - o[a]) / w[a]);
                if near > far {
                    std::mem::swap(&mut near, &mut far);
                }
                let mut axis = DVec3::ZERO;
                axis[a] = 1.0;
                if near > t0 {
                    t0 = near;
                    n0 = axis;
                }
                if far < t1 {
                    t1 = far;
                    n1 = axis;
                }
            }
            if t0 < t1 && t0 > 0.0 {
                vec![(t0, n0), (t1, n1)]
            } else {
                vec![]
            }
        }
        fn sigma_t(&self, o: DVec3, w: DVec3, t: f64) -> [f64; 3] {
            [if inside(o + w * t) { 1.0 } else { 0.0 }; 3]
        }
        fn sigma_t_gradient(&self, _: DVec3, _: DVec3, _: f64) -> [DVec3; 3] {
            [DVec3::ZERO; 3]
        }
        fn source(&self, o: DVec3, w: DVec3, t: f64) -> [f64; 3] {
            self.sigma_t(o, w, t)
        }
        fn source_gradient(&self, _: DVec3, _: DVec3, _: f64) -> [DVec3; 3] {
            [DVec3::ZERO; 3]
        }
    }
    let e_at = |x: f64, m: usize| {
        let strata = Stratification {
            polar: m,
            azimuthal: 2 * m,
        };
        let g = gather(
            &Cube,
            DVec3::new(x, 0.0, 0.0),
            FRAME,
            strata,
            &March::default(),
            |_, _| Vec2::splat(0.5),
        );
        let (_, em) = g.irradiance();
        (em[0], g)
    };
    // The same cells at x ± h: the estimator's own derivative (cell-centred sums of a sharp-edged
    // cube alias by a few per cent from one M to the next; the gradient must follow its E).
    let h = 1e-3;
    let fd = (e_at(0.6 + h, 64).0 - e_at(0.6 - h, 64).0) / (2.0 * h);
    let (e, g) = e_at(0.6, 64);
    assert!(e > 0.05, "the cube is seen: E = {e}");
    let parts = g.gradient_parts();
    let corrected = f64::from(parts.total(MediaGradient::Corrected)[0].x);
    assert!(fd < 0.0, "moving away from the cube darkens: {fd}");
    close(corrected, fd, 0.01, "T6: ∂E/∂x from the interface terms");
    assert_eq!(parts.radial[0].x, 0.0, "no opaque hits, no radial term");
    let paper = f64::from(parts.total(MediaGradient::Paper)[0].x);
    assert!(
        (paper - fd).abs() > 0.5 * fd.abs(),
        "the paper, without interface terms: {paper} vs {fd}"
    );
}

/// T2 and T3 with every length ×1000 and σ ÷1000: the same E, gradients ÷1000.
#[test]
fn scale_free() {
    for (l, q) in [(1.0, 0.0), (0.0, 1.0)] {
        let unit = at_origin(&plane(90.0, l, q, 1.0), 32);
        let big = at_origin(&plane(90.0, l, q, 1000.0), 32);
        let (eu, ebig) = (unit.irradiance(), big.irradiance());
        close(ebig.0[0] + ebig.1[0], eu.0[0] + eu.1[0], 1e-6, "E at ×1000");
        let gu = unit.gradient_parts().total(MediaGradient::Corrected)[0].x;
        let gb = big.gradient_parts().total(MediaGradient::Corrected)[0].x;
        close(f64::from(gb) * 1000.0, f64::from(gu), 1e-4, "∇E at ×1000");
    }
}

mod in_scenes {
    //! The 002 gradients through the renderer's scene (null boundaries, occluders, tracked
    //! media) against central differences of the irradiance with common random numbers
    //! (NOTES-002 §3.3, scene F4: an emissive medium around black occluders).
    use super::*;
    use ircache_math::{Mat4, Rgb, Rng, Vec3};
    use ircache_render::media::tracking::medium_at;
    use ircache_render::media_cache::scene_medium::SceneMedium;
    use ircache_render::scene::Scene;
    use ircache_scene::*;
    use std::path::PathBuf;
    use std::sync::Arc;

    use common::here;

    fn shape(geometry: Geometry, bsdf: Arc<BsdfDesc>, media: MediumInterface) -> ShapeDesc {
        ShapeDesc {
            id: None,
            geometry,
            bsdf,
            emitter: None,
            emitter_texture: None,
            emitter_pattern: None,
            media,
            location: here(),
        }
    }

    fn boxed(center: Vec3, half: Vec3) -> Geometry {
        let mut mesh = shapes::cube();
        assert!(shapes::transform_mesh(
            &mut mesh,
            &(Mat4::from_translation(center) * Mat4::from_scale(half))
        ));
        Geometry::Mesh(mesh)
    }

    /// 002's occluder scene (NOTES-002 §3.3): floor, sphere, box and a wall at x = 2, all black,
    /// in an absorbing, emitting medium (σ_a = 1, L_e = 1) inside a null box.
    pub fn f4() -> Scene {
        f4_with(MediumKind::Homogeneous)
    }

    /// F4 with a heterogeneous medium: σ_a = σ_t on a 24 × 24 × 12 grid over the null box,
    /// 0.6 + 0.5 (1 + sin 1.3x cos 1.7y) e^{−z/2}, emission 1.
    fn f4_grid() -> Scene {
        f4_with(MediumKind::Heterogeneous)
    }

    fn f4_with(kind: MediumKind) -> Scene {
        let black = Arc::new(BsdfDesc::TwoSided {
            front: Arc::new(BsdfDesc::Diffuse {
                reflectance: TextureDesc::Constant(Rgb::ZERO),
            }),
            back: None,
        });
        let none = MediumInterface::default();
        let shapes = vec![
            shape(
                boxed(Vec3::new(0.0, 0.0, -0.05), Vec3::new(2.0, 2.0, 0.05)),
                black.clone(),
                none,
            ),
            shape(
                Geometry::Sphere {
                    center: Vec3::new(-0.8, 0.3, 0.4),
                    radius: 0.4,
                    flip_normals: false,
                    orientation: ircache_math::Mat3::IDENTITY,
                },
                black.clone(),
                none,
            ),
            shape(
                boxed(Vec3::new(0.7, -0.5, 0.4), Vec3::new(0.3, 0.3, 0.4)),
                black.clone(),
                none,
            ),
            shape(
                boxed(Vec3::new(2.05, 0.0, 1.0), Vec3::new(0.05, 2.0, 1.0)),
                black,
                none,
            ),
            shape(
                boxed(Vec3::new(0.0, 0.0, 1.0), Vec3::new(2.1, 2.1, 1.1)),
                Arc::new(BsdfDesc::Null),
                MediumInterface {
                    interior: Some(0),
                    exterior: None,
                },
            ),
        ];
        let sensor = common::sensor(Vec3::new(0.0, -5.0, 1.0), Vec3::ZERO, 45.0, 4, 1);
        let desc = SceneDesc {
            source: PathBuf::from("<test>"),
            sensor,
            integrator: IntegratorDesc::default(),
            shapes,
            emitters: vec![],
            media: vec![MediumDesc {
                id: None,
                kind,
                sigma_t: match kind {
                    MediumKind::Homogeneous => VolumeDesc::constant(Rgb::ONE),
                    MediumKind::Heterogeneous => density_grid(),
                },
                albedo: VolumeDesc::constant(Rgb::ZERO),
                emission: Some(VolumeDesc::constant(Rgb::ONE)),
                scale: 1.0,
                phase: PhaseDesc::Isotropic,
                sample_emitters: true,
                location: here(),
            }],
            notes: vec![],
        };
        Scene::build(&desc).expect("scene")
    }

    /// The smooth density of [`f4_grid`] sampled at cell centres over the null box.
    fn density_grid() -> VolumeDesc {
        common::grid(
            [24, 24, 12],
            Vec3::new(-2.1, -2.1, -0.1),
            Vec3::new(2.1, 2.1, 2.1),
            |p| 0.6 + 0.5 * (1.0 + (1.3 * p.x).sin() * (1.7 * p.y).cos()) * (-p.z / 2.0).exp(),
        )
    }

    fn strata(m: usize) -> Stratification {
        Stratification {
            polar: m,
            azimuthal: 2 * m,
        }
    }

    /// E at `x` (normal +z) with cell jitter from `seed`.
    fn irradiance(
        scene: &Scene,
        x: DVec3,
        m: usize,
        seed: u64,
        gradients: bool,
    ) -> ircache_render::media_cache::gradient::MediaGather {
        let medium = medium_at(scene, x.as_vec3(), Vec3::Z);
        assert_eq!(medium, Some(0), "the receiver is in the fog");
        let view = SceneMedium::new(scene, medium, true, 1).with_gradients(gradients);
        let march = March {
            gradients,
            ..March::default()
        };
        let n = 2 * m;
        gather(&view, x, FRAME, strata(m), &march, |j, k| {
            let mut rng = Rng::new(seed, (j * n + k) as u64);
            rng.next_2d()
        })
    }

    /// Central differences along x and y with common random numbers, averaged over seeds.
    fn finite_difference(scene: &Scene, x: DVec3, h: f64, m: usize, seeds: u64) -> [f64; 2] {
        let mut g = [0.0; 2];
        for seed in 0..seeds {
            for (axis, e) in [DVec3::X, DVec3::Y].into_iter().enumerate() {
                let plus = irradiance(scene, x + e * h, m, 100 + seed, false).irradiance();
                let minus = irradiance(scene, x - e * h, m, 100 + seed, false).irradiance();
                let total = |p: ([f64; 3], [f64; 3])| p.0[0] + p.1[0];
                g[axis] += (total(plus) - total(minus)) / (2.0 * h) / seeds as f64;
            }
        }
        g
    }

    /// The gradient at points beside the box (the box 0.1 away, the wall behind it) against
    /// central differences (h = 0.005, 128 × 256 cells, common jitter, 8 seeds): the consistent form
    /// within 5 % at 64 × 128 cells, and its error falling with the cell count (first order:
    /// the walls' discretisation next to a close occluder); the media-blind walls and the
    /// JDZJ08 terms miss by more.
    #[test]
    fn f4_gradient_converges_to_finite_differences() {
        let scene = f4();
        let x = DVec3::new(1.2, -0.5, 1e-4);
        let fd = finite_difference(&scene, x, 0.005, 128, 8)[0];
        let mean_gradient = |m: usize, variant: MediaGradient| {
            (0..4)
                .map(|seed| {
                    f64::from(
                        irradiance(&scene, x, m, seed, true)
                            .gradient_parts()
                            .total(variant)[0]
                            .x,
                    )
                })
                .sum::<f64>()
                / 4.0
        };
        let fine = mean_gradient(64, MediaGradient::Corrected);
        let coarse = mean_gradient(24, MediaGradient::Corrected);
        let error = |g: f64| (g - fd).abs() / fd.abs();
        assert!(
            error(fine) < 0.05,
            "∂E/∂x at 64 × 128: {fine} against FD {fd}"
        );
        assert!(
            error(fine) < error(coarse),
            "no convergence: {coarse} → {fine} (FD {fd})"
        );
        for v in [MediaGradient::None, MediaGradient::Jdzj08] {
            let g = mean_gradient(64, v);
            assert!(
                error(g) > 2.0 * error(fine),
                "{v:?}: {g} against FD {fd} (consistent {fine})"
            );
        }
    }

    /// The same in a heterogeneous medium (a grid of smoothly varying absorption and emission,
    /// boxes, sphere and wall as occluders): the consistent form within 5 % of the differences
    /// at 64 × 128 cells, the media-blind walls further off (measured: 2.028 against 1.969; none
    /// 1.706).
    #[test]
    fn f4_heterogeneous_gradient_against_finite_differences() {
        let scene = f4_grid();
        let x = DVec3::new(1.2, -0.5, 1e-4);
        let fd = finite_difference(&scene, x, 0.005, 128, 8)[0];
        let mean_gradient = |variant: MediaGradient| {
            (0..4)
                .map(|seed| {
                    f64::from(
                        irradiance(&scene, x, 64, seed, true)
                            .gradient_parts()
                            .total(variant)[0]
                            .x,
                    )
                })
                .sum::<f64>()
                / 4.0
        };
        let corrected = mean_gradient(MediaGradient::Corrected);
        let none = mean_gradient(MediaGradient::None);
        let error = |g: f64| (g - fd).abs() / fd.abs();
        assert!(
            error(corrected) < 0.05,
            "∂E/∂x: {corrected} against FD {fd} (none {none})"
        );
        assert!(
            error(none) > error(corrected),
            "none {none}, corrected {corrected}, FD {fd}"
        );
    }

    #[test]
    #[ignore = "prints the F4 figures: cargo test --release -- --ignored"]
    fn f4_gradients_against_finite_differences() {
        let scene = f4();
        let m: usize = std::env::var("F4_M")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(32);
        let fd_m: usize = std::env::var("F4_FD_M")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(96);
        let h: f64 = std::env::var("F4_H")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(0.001);
        for x in [
            DVec3::new(0.3, -0.5, 1e-4),
            DVec3::new(1.2, -0.5, 1e-4),
            DVec3::new(-0.8, -0.3, 1e-4),
            DVec3::new(0.0, 1.0, 1e-4),
        ] {
            let mut est = [[0.0f64; 2]; 4];
            let seeds = 8;
            let mut e = 0.0;
            for seed in 0..seeds {
                let g = irradiance(&scene, x, m, seed, true);
                let (es, em) = g.irradiance();
                e += (es[0] + em[0]) / seeds as f64;
                let parts = g.gradient_parts();
                for (i, v) in [
                    MediaGradient::Corrected,
                    MediaGradient::Paper,
                    MediaGradient::Jdzj08,
                    MediaGradient::None,
                ]
                .into_iter()
                .enumerate()
                {
                    let t = parts.total(v)[0];
                    est[i][0] += f64::from(t.x) / seeds as f64;
                    est[i][1] += f64::from(t.y) / seeds as f64;
                }
            }
            let fd = finite_difference(&scene, x, h, fd_m, 4);
            let fd2 = finite_difference(&scene, x, h / 2.0, fd_m, 4);
            eprintln!("x {x}: E {e:.5}  FD h {fd:?}  FD h/2 {fd2:?}");
            eprintln!(
                "   corrected {:?} paper {:?} jdzj08 {:?} none {:?}",
                est[0], est[1], est[2], est[3]
            );
        }
    }
}
