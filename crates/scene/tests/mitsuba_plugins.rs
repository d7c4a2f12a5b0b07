//! Plugins, defaults and transforms of the Mitsuba 3 XML loader on small hand-written scenes.

use ircache_math::{Mat4, Rgb, Vec3, Vec4};
use ircache_scene::shapes::{mesh_area, triangle_normal};
use ircache_scene::{
    mitsuba, BsdfDesc, EmitterDesc, FilterDesc, FovAxis, Geometry, MicrofacetDistribution,
    ParamValue, SceneDesc, TextureDesc,
};
use ircache_testing::ScratchDir;
use std::path::PathBuf;

fn load(body: &str) -> SceneDesc {
    load_full(&format!(
        "<scene version=\"3.0.0\">\n<sensor type=\"perspective\"><float name=\"fov\" value=\"45\"/></sensor>\n{body}\n</scene>\n"
    ))
}

fn load_full(text: &str) -> SceneDesc {
    let dir = ScratchDir::new("mitsuba-plugins");
    let path = dir.join("scene.xml");
    std::fs::write(&path, text).unwrap();
    mitsuba::load(&path, &[]).unwrap_or_else(|e| panic!("{e}"))
}

fn close(a: Mat4, b: Mat4) -> bool {
    a.to_cols_array()
        .iter()
        .zip(b.to_cols_array())
        .all(|(x, y)| (x - y).abs() < 1e-5)
}

fn spot_to_world(transform: &str) -> Mat4 {
    let s = load(&format!(
        "<emitter type=\"spot\"><transform name=\"to_world\">{transform}</transform></emitter>\n<shape type=\"cube\"/>"
    ));
    match &s.emitters[0] {
        EmitterDesc::Spot { to_world, .. } => *to_world,
        e => panic!("{e:?}"),
    }
}

#[test]
fn transform_composition() {
    // Each later operation multiplies from the left: translate, then rotate 90° about +y.
    let m = spot_to_world("<translate x=\"1\"/><rotate y=\"1\" angle=\"90\"/>");
    // R_y(90°) · T(1,0,0): the translated origin (1,0,0) rotates to (0,0,−1).
    let expected = Mat4::from_cols(
        Vec4::new(0.0, 0.0, -1.0, 0.0),
        Vec4::new(0.0, 1.0, 0.0, 0.0),
        Vec4::new(1.0, 0.0, 0.0, 0.0),
        Vec4::new(0.0, 0.0, -1.0, 1.0),
    );
    assert!(close(m, expected), "{m:?}");
    // scale (uniform via one value), then translate via value, then a row-major matrix.
    let m = spot_to_world(
        "<scale value=\"2\"/><translate value=\"1, 2, 3\"/><matrix value=\"0 -1 0 0  1 0 0 0  0 0 1 5  0 0 0 1\"/>",
    );
    // M · T · S with M = rotate z by 90° then +5 z: p ↦ M(2p + (1,2,3)).
    let expected = Mat4::from_cols(
        Vec4::new(0.0, 2.0, 0.0, 0.0),
        Vec4::new(-2.0, 0.0, 0.0, 0.0),
        Vec4::new(0.0, 0.0, 2.0, 0.0),
        Vec4::new(-2.0, 1.0, 8.0, 1.0),
    );
    assert!(close(m, expected), "{m:?}");
    // Non-uniform scale with x/y/z attributes (missing ones 1), rotation about an unnormalised axis.
    let m = spot_to_world("<scale x=\"2\" z=\"3\"/><rotate value=\"0 0 5\" angle=\"180\"/>");
    let expected = Mat4::from_cols(
        Vec4::new(-2.0, 0.0, 0.0, 0.0),
        Vec4::new(0.0, -1.0, 0.0, 0.0),
        Vec4::new(0.0, 0.0, 3.0, 0.0),
        Vec4::W,
    );
    assert!(close(m, expected), "{m:?}");
}

#[test]
fn lookat_matches_mitsuba() {
    let s = load_full(
        "<scene version=\"3.0.0\"><sensor type=\"perspective\"><transform name=\"to_world\">\
         <lookat origin=\"1, 2, 3\" target=\"4, 2, 7\" up=\"0, 1, 0\"/></transform></sensor>\
         <shape type=\"cube\"/></scene>",
    );
    let (o, t, up) = (Vec3::new(1., 2., 3.), Vec3::new(4., 2., 7.), Vec3::Y);
    let dir = (t - o).normalize();
    let left = up.cross(dir).normalize();
    let new_up = dir.cross(left);
    let expected = Mat4::from_cols(
        left.extend(0.),
        new_up.extend(0.),
        dir.extend(0.),
        o.extend(1.),
    );
    assert!(close(s.sensor.to_world, expected));
    assert!((dir - Vec3::new(0.6, 0.0, 0.8)).length() < 1e-6);
    assert!((left - Vec3::new(0.8, 0.0, -0.6)).length() < 1e-6);
    // Defaults: focal length 50 mm (diagonal fov), 768×576, Gaussian filter, 4 spp independent.
    assert_eq!(s.sensor.fov_axis, FovAxis::Diagonal);
    assert!(
        (s.sensor.fov_degrees - 46.7930).abs() < 1e-3,
        "{}",
        s.sensor.fov_degrees
    );
    assert_eq!((s.sensor.film.width, s.sensor.film.height), (768, 576));
    assert_eq!(s.sensor.film.filter, FilterDesc::Gaussian { stddev: 0.5 });
    assert_eq!(
        (s.sensor.spp, s.sensor.sampler.as_str()),
        (4, "independent")
    );
    // No integrator: Mitsuba's default path tracer.
    assert_eq!(
        (s.integrator.kind.as_str(), s.integrator.max_depth),
        ("path", -1)
    );
}

#[test]
fn bsdf_defaults() {
    let s = load(
        "<shape type=\"cube\"/>\
         <shape type=\"cube\"><bsdf type=\"plastic\"/></shape>\
         <shape type=\"cube\"><bsdf type=\"roughplastic\"><string name=\"distribution\" value=\"ggx\"/></bsdf></shape>\
         <shape type=\"cube\"><bsdf type=\"conductor\"/></shape>\
         <shape type=\"cube\"><bsdf type=\"roughconductor\"><string name=\"material\" value=\"Au\"/>\
           <float name=\"alpha_u\" value=\"0.2\"/><float name=\"alpha_v\" value=\"0.3\"/></bsdf></shape>\
         <shape type=\"cube\"><bsdf type=\"dielectric\"><string name=\"int_ior\" value=\"water\"/></bsdf></shape>\
         <shape type=\"cube\"><bsdf type=\"thindielectric\"><float name=\"int_ior\" value=\"1.6\"/>\
           <string name=\"ext_ior\" value=\"acrylic glass\"/></bsdf></shape>\
         <shape type=\"cube\"><bsdf type=\"twosided\"><bsdf type=\"diffuse\"/><bsdf type=\"diffuse\">\
           <float name=\"reflectance\" value=\"0.25\"/></bsdf></bsdf></shape>\
         <shape type=\"cube\"><bsdf type=\"roughdielectric\"/></shape>\
         <shape type=\"cube\"><bsdf type=\"roughdielectric\"><string name=\"distribution\" value=\"ggx\"/>\
           <float name=\"alpha_u\" value=\"0.05\"/><float name=\"alpha_v\" value=\"0.4\"/>\
           <string name=\"int_ior\" value=\"water\"/></bsdf></shape>",
    );
    let b: Vec<&BsdfDesc> = s.shapes.iter().map(|sh| &*sh.bsdf).collect();
    assert!(
        matches!(b[0], BsdfDesc::Diffuse { reflectance: TextureDesc::Constant(c) } if *c == Rgb::splat(0.5))
    );
    assert!(
        matches!(b[1], BsdfDesc::Plastic { int_ior, ext_ior, nonlinear: false, .. }
        if *int_ior == 1.49 && *ext_ior == 1.000277)
    );
    assert!(
        matches!(b[2], BsdfDesc::RoughPlastic { distribution: MicrofacetDistribution::Ggx, alpha, .. } if *alpha == 0.1)
    );
    assert!(
        matches!(b[3], BsdfDesc::Conductor { eta, k, specular_reflectance }
        if *eta == Rgb::splat(0.0) && *k == Rgb::splat(1.0) && *specular_reflectance == Rgb::ONE)
    );
    let BsdfDesc::RoughConductor {
        distribution,
        alpha_u,
        alpha_v,
        eta,
        ..
    } = b[4]
    else {
        panic!()
    };
    assert_eq!(
        (*distribution, *alpha_u, *alpha_v),
        (MicrofacetDistribution::Beckmann, 0.2, 0.3)
    );
    assert!((eta.r - 0.143119).abs() < 1e-5);
    assert!(
        matches!(b[5], BsdfDesc::Dielectric { int_ior, ext_ior, .. } if *int_ior == 1.333 && *ext_ior == 1.000277)
    );
    assert!(
        matches!(b[6], BsdfDesc::ThinDielectric { int_ior, ext_ior, .. } if *int_ior == 1.6 && *ext_ior == 1.49)
    );
    let BsdfDesc::TwoSided {
        back: Some(back), ..
    } = b[7]
    else {
        panic!()
    };
    assert!(
        matches!(&**back, BsdfDesc::Diffuse { reflectance: TextureDesc::Constant(c) } if *c == Rgb::splat(0.25))
    );
    assert!(
        matches!(b[8], BsdfDesc::RoughDielectric { distribution: MicrofacetDistribution::Beckmann,
            alpha_u, alpha_v, int_ior, ext_ior, .. }
        if *alpha_u == 0.1 && *alpha_v == 0.1 && *int_ior == 1.5046 && *ext_ior == 1.000277)
    );
    assert!(
        matches!(b[9], BsdfDesc::RoughDielectric { distribution: MicrofacetDistribution::Ggx,
            alpha_u, alpha_v, int_ior, .. }
        if *alpha_u == 0.05 && *alpha_v == 0.4 && *int_ior == 1.333)
    );
}

#[test]
fn shared_bsdf_by_reference() {
    let s = load(
        "<shape type=\"cube\"><ref id=\"m\"/></shape><bsdf type=\"diffuse\" id=\"m\"/>\
         <shape type=\"disk\"><ref name=\"bsdf\" id=\"m\"/></shape><alias id=\"m\" as=\"n\"/>\
         <shape type=\"rectangle\"><ref id=\"n\"/></shape>",
    );
    assert!(std::sync::Arc::ptr_eq(&s.shapes[0].bsdf, &s.shapes[1].bsdf));
    assert!(std::sync::Arc::ptr_eq(&s.shapes[0].bsdf, &s.shapes[2].bsdf));
}

#[test]
fn emitters() {
    let s = load(
        "<emitter type=\"point\"><point name=\"position\" x=\"1\" y=\"2\" z=\"3\"/><rgb name=\"intensity\" value=\"5\"/></emitter>\
         <emitter type=\"point\"><transform name=\"to_world\"><translate x=\"4\"/></transform></emitter>\
         <emitter type=\"spot\"><float name=\"cutoff_angle\" value=\"40\"/></emitter>\
         <emitter type=\"directional\"><transform name=\"to_world\"><rotate x=\"1\" angle=\"90\"/></transform></emitter>\
         <emitter type=\"constant\"><rgb name=\"radiance\" value=\"0.1 0.2 0.3\"/></emitter>\
         <shape type=\"sphere\"><emitter type=\"area\"/></shape>",
    );
    assert!(
        matches!(s.emitters[0], EmitterDesc::Point { position, intensity }
        if position == Vec3::new(1., 2., 3.) && intensity == Rgb::splat(5.0))
    );
    assert!(
        matches!(s.emitters[1], EmitterDesc::Point { position, intensity }
        if position == Vec3::new(4., 0., 0.) && intensity == Rgb::ONE)
    );
    assert!(
        matches!(s.emitters[2], EmitterDesc::Spot { cutoff_angle, beam_width, .. }
        if cutoff_angle == 40.0 && beam_width == 30.0)
    );
    let EmitterDesc::Directional {
        direction,
        irradiance,
    } = s.emitters[3]
    else {
        panic!()
    };
    assert!(
        (direction - Vec3::new(0., -1., 0.)).length() < 1e-6,
        "{direction}"
    );
    assert_eq!(irradiance, Rgb::ONE);
    assert!(
        matches!(s.emitters[4], EmitterDesc::Constant { radiance } if radiance == Rgb::new(0.1, 0.2, 0.3))
    );
    assert_eq!(s.shapes[0].emitter, Some(Rgb::ONE));
}

#[test]
fn analytic_shapes_in_world_space() {
    let s = load(
        "<shape type=\"disk\"><transform name=\"to_world\"><scale x=\"2\" y=\"3\"/><rotate x=\"1\" angle=\"-90\"/>\
         </transform></shape>\
         <shape type=\"rectangle\"><boolean name=\"flip_normals\" value=\"true\"/></shape>\
         <shape type=\"rectangle\"><transform name=\"to_world\"><scale x=\"-1\"/></transform></shape>\
         <shape type=\"cube\"><boolean name=\"face_normals\" value=\"true\"/>\
           <transform name=\"to_world\"><scale value=\"0.5\"/><translate y=\"1\"/></transform></shape>\
         <shape type=\"sphere\"><point name=\"center\" value=\"1 0 0\"/><float name=\"radius\" value=\"2\"/>\
           <transform name=\"to_world\"><scale value=\"3\"/><rotate z=\"1\" angle=\"90\"/></transform></shape>",
    );
    let mesh = |i: usize| match &s.shapes[i].geometry {
        Geometry::Mesh(m) => m.clone(),
        _ => panic!(),
    };
    // Ellipse of semi-axes 2 and 3 (exact area 6π), rotated to face +y.
    let disk = mesh(0);
    assert!((mesh_area(&disk) - 6.0 * std::f64::consts::PI).abs() < 1e-4);
    assert!((triangle_normal(&disk, 7) - Vec3::Y).length() < 1e-5);
    // flip_normals: the rectangle faces −z.
    assert!((triangle_normal(&mesh(1), 0) + Vec3::Z).length() < 1e-6);
    // A mirroring to_world keeps Mitsuba's analytic normal to_world⁻ᵀ·z = +z.
    assert!((triangle_normal(&mesh(2), 0) - Vec3::Z).length() < 1e-6);
    let cube = mesh(3);
    assert!(cube.normals.is_none());
    assert!((mesh_area(&cube) - 6.0).abs() < 1e-6);
    assert!(cube
        .positions
        .iter()
        .all(|p| p.y >= 0.5 - 1e-6 && p.y <= 1.5 + 1e-6));
    // Sphere: centre and radius through the uniform scale and rotation.
    let Geometry::Sphere { center, radius, .. } = s.shapes[4].geometry else {
        panic!()
    };
    assert!((center - Vec3::new(0., 3., 0.)).length() < 1e-5, "{center}");
    assert!((radius - 6.0).abs() < 1e-5);
}

#[test]
fn integrators() {
    let s = load(
        "<integrator type=\"direct\"><integer name=\"shading_samples\" value=\"4\"/>\
         <integer name=\"bsdf_samples\" value=\"2\"/><boolean name=\"hide_emitters\" value=\"true\"/></integrator>\
         <shape type=\"cube\"/>",
    );
    assert_eq!(s.integrator.kind, "direct");
    assert_eq!(
        (s.integrator.emitter_samples, s.integrator.bsdf_samples),
        (4, 2)
    );
    assert!(s.integrator.hide_emitters);
    let s = load(
        "<integrator type=\"irrcache\"><integer name=\"max_depth\" value=\"4\"/>\
         <float name=\"error\" value=\"0.2\"/>\n<string name=\"mode\" value=\"fast\"/></integrator>\
         <shape type=\"cube\"/>",
    );
    assert_eq!(
        (s.integrator.kind.as_str(), s.integrator.max_depth),
        ("irrcache", 4)
    );
    assert_eq!(s.integrator.extra.len(), 2);
    assert_eq!(s.integrator.extra[0].0, "error");
    assert_eq!(s.integrator.extra[0].1, ParamValue::Float(0.2));
    assert_eq!(s.integrator.extra[1].1, ParamValue::String("fast".into()));
    assert_eq!(
        (s.integrator.extra[1].2.line, s.integrator.extra[1].2.column),
        (4, 1)
    );
}

#[test]
fn textured_sponza() {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/scenes/sponza-sun/scene-textured.xml");
    let s = mitsuba::load(&path, &[]).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.shapes.len(), 20);
    let mut textured = 0;
    for sh in &s.shapes {
        let BsdfDesc::TwoSided { front, .. } = &*sh.bsdf else {
            panic!()
        };
        if let BsdfDesc::Diffuse {
            reflectance: TextureDesc::Bitmap(b),
        } = &**front
        {
            textured += 1;
            assert!(b.image.width > 0 && b.image.height > 0);
            let Geometry::Mesh(m) = &sh.geometry else {
                panic!()
            };
            assert!(m.uvs.is_some(), "{:?}", sh.id);
        }
    }
    assert_eq!(textured, 19);
}

#[test]
fn normalmap_and_bumpmap_wrap_a_bsdf_with_a_texture() {
    let dir = ScratchDir::new("bump");
    let mut img = ircache_image::Image::new(4, 4);
    img.pixels.fill(Rgb::new(0.5, 0.5, 1.0));
    ircache_image::write_image(&dir.join("n.exr"), &img, 0.0).unwrap();
    let scene = |bsdf: &str| {
        format!(
            "<scene version=\"3.0.0\"><sensor type=\"perspective\"/>\
             <shape type=\"rectangle\">{bsdf}</shape></scene>"
        )
    };
    let tex = r#"<texture type="bitmap" name="normalmap"><string name="filename" value="n.exr"/><boolean name="raw" value="true"/></texture>"#;
    let load = |text: String| {
        let path = dir.join("s.xml");
        std::fs::write(&path, text).unwrap();
        mitsuba::load(&path, &[])
    };
    let s = load(scene(&format!(
        r#"<bsdf type="normalmap">{tex}<bsdf type="diffuse"/></bsdf>"#
    )))
    .unwrap();
    assert!(matches!(
        &*s.shapes[0].bsdf,
        BsdfDesc::NormalMap { nested, .. } if matches!(**nested, BsdfDesc::Diffuse { .. })
    ));
    let s = load(scene(&format!(
        r#"<bsdf type="bumpmap">{tex}<float name="scale" value="0.25"/><bsdf type="diffuse"/></bsdf>"#
    )))
    .unwrap();
    assert!(matches!(&*s.shapes[0].bsdf, BsdfDesc::BumpMap { scale, .. } if *scale == 0.25));
    // Missing pieces are errors that say what is expected.
    let e = load(scene(
        r#"<bsdf type="normalmap"><bsdf type="diffuse"/></bsdf>"#,
    ))
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("texture is required") && e.contains("s.xml:"),
        "{e}"
    );
    let e = load(scene(&format!(r#"<bsdf type="bumpmap">{tex}</bsdf>"#)))
        .unwrap_err()
        .to_string();
    assert!(e.contains("BSDF is required"), "{e}");
}

#[test]
fn serialized_meshes_by_index_with_normals_as_mitsuba() {
    use ircache_scene::mesh::write_serialized;
    use ircache_scene::TriangleMesh;
    // A tetrahedron-like fan without normals as mesh 1 of 2: the loader picks it by index and,
    // unless face_normals, gives it angle-weighted vertex normals (as Mitsuba recomputes them).
    let fan = TriangleMesh {
        positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z],
        normals: None,
        uvs: None,
        indices: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2]],
    };
    let single = TriangleMesh {
        positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
        normals: None,
        uvs: None,
        indices: vec![[0, 1, 2]],
    };
    let dir = ScratchDir::new("serialized");
    std::fs::write(
        dir.join("m.serialized"),
        write_serialized(&[("one", &single, false), ("fan", &fan, false)]),
    )
    .unwrap();
    let path = dir.join("scene.xml");
    let shape = |face_normals: bool| {
        format!(
            "<shape type=\"serialized\"><string name=\"filename\" value=\"m.serialized\"/>\
             <integer name=\"shape_index\" value=\"1\"/><boolean name=\"face_normals\" value=\"{face_normals}\"/>\
             <transform name=\"to_world\"><translate x=\"2\"/></transform></shape>"
        )
    };
    std::fs::write(
        &path,
        format!(
            "<scene version=\"3.0.0\"><sensor type=\"perspective\"/>{}{}</scene>",
            shape(false),
            shape(true)
        ),
    )
    .unwrap();
    let s = mitsuba::load(&path, &[]).unwrap_or_else(|e| panic!("{e}"));
    let Geometry::Mesh(smooth) = &s.shapes[0].geometry else {
        panic!("a mesh")
    };
    let Geometry::Mesh(flat) = &s.shapes[1].geometry else {
        panic!("a mesh")
    };
    assert_eq!(smooth.indices.len(), 3);
    assert_eq!(smooth.positions[1], Vec3::new(3.0, 0.0, 0.0));
    assert!(flat.normals.is_none());
    // The apex at the origin: three faces at right angles, normals −x, −y, −z, each weighted
    // by a right angle.
    let n = smooth.normals.as_ref().expect("recomputed normals")[0];
    let expected = Vec3::splat(-1.0).normalize();
    assert!((n - expected).length() < 1e-5, "{n}");
}

#[test]
fn masks_wrap_a_bsdf_with_an_opacity() {
    let s = load(
        "<shape type=\"cube\"><bsdf type=\"mask\"><float name=\"opacity\" value=\"0.25\"/>\
           <bsdf type=\"twosided\"><bsdf type=\"diffuse\"/></bsdf></bsdf></shape>\
         <shape type=\"cube\"><bsdf type=\"mask\"><bsdf type=\"diffuse\"/></bsdf></shape>",
    );
    let BsdfDesc::Mask { opacity, nested } = &*s.shapes[0].bsdf else {
        panic!("a mask")
    };
    assert!(matches!(opacity, TextureDesc::Constant(c) if *c == Rgb::splat(0.25)));
    assert!(matches!(&**nested, BsdfDesc::TwoSided { .. }));
    // Mitsuba's default opacity.
    assert!(matches!(&*s.shapes[1].bsdf,
        BsdfDesc::Mask { opacity: TextureDesc::Constant(c), .. } if *c == Rgb::splat(0.5)));
}

#[test]
fn cylinders_have_the_area_and_outward_normals_of_mitsubas() {
    // Axis from (1, 2, 3) to (3, 4, 3), radius 0.5, under a mirroring to_world: lateral area
    // 2π r h, normals outward and across the axis, winding agreeing with them.
    let s = load(
        "<shape type=\"cylinder\"><point name=\"p0\" x=\"1\" y=\"2\" z=\"3\"/>\
           <point name=\"p1\" x=\"3\" y=\"4\" z=\"3\"/><float name=\"radius\" value=\"0.5\"/>\
           <transform name=\"to_world\"><scale x=\"-1\"/></transform></shape>",
    );
    let Geometry::Mesh(m) = &s.shapes[0].geometry else {
        panic!("a mesh")
    };
    let (p0, p1) = (Vec3::new(-1.0, 2.0, 3.0), Vec3::new(-3.0, 4.0, 3.0));
    let axis = (p1 - p0).normalize();
    let h = (p1 - p0).length();
    let area = mesh_area(m);
    let expected = 2.0 * std::f64::consts::PI * 0.5 * f64::from(h);
    assert!(
        (area / expected - 1.0).abs() < 1e-4,
        "{area} against {expected}"
    );
    let normals = m.normals.as_ref().expect("smooth normals");
    for (p, n) in m.positions.iter().zip(normals) {
        let radial = (*p - p0) - axis * (*p - p0).dot(axis);
        assert!((n.length() - 1.0).abs() < 1e-5 && n.dot(axis).abs() < 1e-4);
        assert!(n.dot(radial.normalize()) > 0.999, "{n} at {p}");
    }
    for (k, t) in m.indices.iter().enumerate() {
        assert!(triangle_normal(m, k).dot(normals[t[0] as usize]) > 0.9);
    }
}

/// `thinlens` and `orthographic` (Mitsuba's `src/sensors/`): their parameters, Mitsuba's
/// defaults (focus at the far clip distance), and the fov of a thin lens read as a pinhole's.
#[test]
fn lens_and_orthographic_sensors() {
    let s = load_full(
        "<scene version=\"3.0.0\"><sensor type=\"thinlens\"><float name=\"fov\" value=\"30\"/>\
         <float name=\"aperture_radius\" value=\"0.05\"/><float name=\"focus_distance\" value=\"3\"/>\
         </sensor><shape type=\"cube\"/></scene>",
    );
    assert_eq!(
        s.sensor.projection,
        ircache_scene::Projection::ThinLens {
            aperture_radius: 0.05,
            focus_distance: 3.0
        }
    );
    assert_eq!(
        (s.sensor.fov_degrees, s.sensor.fov_axis),
        (30.0, FovAxis::X)
    );
    let s = load_full(
        "<scene version=\"3.0.0\"><sensor type=\"thinlens\">\
         <float name=\"aperture_radius\" value=\"0.1\"/><float name=\"far_clip\" value=\"50\"/>\
         </sensor><shape type=\"cube\"/></scene>",
    );
    assert_eq!(
        s.sensor.projection,
        ircache_scene::Projection::ThinLens {
            aperture_radius: 0.1,
            focus_distance: 50.0
        }
    );
    let s = load_full(
        "<scene version=\"3.0.0\"><sensor type=\"orthographic\"><transform name=\"to_world\">\
         <scale value=\"2\"/></transform></sensor><shape type=\"cube\"/></scene>",
    );
    assert_eq!(s.sensor.projection, ircache_scene::Projection::Orthographic);
    assert!(close(s.sensor.to_world, Mat4::from_scale(Vec3::splat(2.0))));
}

/// `blendbsdf`: its weight and two models in order; a blend of two `twosided` models is read as
/// the `twosided` of the blend (the same BSDF on each side).
#[test]
fn blend_bsdf() {
    let s = load(
        "<shape type=\"cube\"><bsdf type=\"blendbsdf\"><float name=\"weight\" value=\"0.25\"/>\
           <bsdf type=\"diffuse\"/><bsdf type=\"conductor\"/></bsdf></shape>\
         <shape type=\"cube\"><bsdf type=\"blendbsdf\"><float name=\"weight\" value=\"0.5\"/>\
           <bsdf type=\"twosided\"><bsdf type=\"diffuse\"/></bsdf>\
           <bsdf type=\"twosided\"><bsdf type=\"roughplastic\"/></bsdf></bsdf></shape>",
    );
    match &*s.shapes[0].bsdf {
        BsdfDesc::Blend {
            weight: TextureDesc::Constant(w),
            first,
            second,
            ..
        } => {
            assert_eq!(*w, Rgb::splat(0.25));
            assert!(matches!(**first, BsdfDesc::Diffuse { .. }));
            assert!(matches!(**second, BsdfDesc::Conductor { .. }));
        }
        other => panic!("{other:?}"),
    }
    match &*s.shapes[1].bsdf {
        BsdfDesc::TwoSided { front, back: None } => match &**front {
            BsdfDesc::Blend { first, second, .. } => {
                assert!(matches!(**first, BsdfDesc::Diffuse { .. }));
                assert!(matches!(**second, BsdfDesc::RoughPlastic { .. }));
            }
            other => panic!("{other:?}"),
        },
        other => panic!("{other:?}"),
    }
}

/// `shapegroup` and `instance`: each instance holds the group's shapes placed by its
/// `to_world`, the same geometry as the shapes written out with the composed transforms; the
/// group alone draws nothing.
#[test]
fn instances_of_a_shape_group() {
    let group = "<shape type=\"shapegroup\" id=\"g\">\
           <shape type=\"cube\"><transform name=\"to_world\"><rotate y=\"1\" angle=\"30\"/>\
             <translate x=\"1\"/></transform></shape>\
           <shape type=\"sphere\"><point name=\"center\" x=\"0\" y=\"2\" z=\"0\"/>\
             <float name=\"radius\" value=\"0.5\"/></shape>\
         </shape>";
    let instanced = load(&format!(
        "{group}\
         <shape type=\"instance\"><ref id=\"g\"/><transform name=\"to_world\">\
           <translate x=\"5\" y=\"-1\"/></transform></shape>\
         <shape type=\"instance\"><ref id=\"g\"/><transform name=\"to_world\"><scale value=\"2\"/>\
           <rotate z=\"1\" angle=\"90\"/></transform></shape>"
    ));
    let written = load(
        "<shape type=\"cube\"><transform name=\"to_world\"><rotate y=\"1\" angle=\"30\"/>\
           <translate x=\"1\"/><translate x=\"5\" y=\"-1\"/></transform></shape>\
         <shape type=\"sphere\"><point name=\"center\" x=\"5\" y=\"1\" z=\"0\"/>\
           <float name=\"radius\" value=\"0.5\"/></shape>\
         <shape type=\"cube\"><transform name=\"to_world\"><rotate y=\"1\" angle=\"30\"/>\
           <translate x=\"1\"/><scale value=\"2\"/><rotate z=\"1\" angle=\"90\"/></transform></shape>\
         <shape type=\"sphere\"><point name=\"center\" x=\"-4\" y=\"0\" z=\"0\"/>\
           <float name=\"radius\" value=\"1\"/></shape>",
    );
    assert_eq!(instanced.shapes.len(), 4);
    for (a, b) in instanced.shapes.iter().zip(&written.shapes) {
        match (&a.geometry, &b.geometry) {
            (Geometry::Mesh(a), Geometry::Mesh(b)) => {
                assert_eq!(a.indices, b.indices);
                for (p, q) in a.positions.iter().zip(&b.positions) {
                    assert!((*p - *q).length() < 1e-5, "{p} against {q}");
                }
            }
            (
                Geometry::Sphere { center, radius, .. },
                Geometry::Sphere {
                    center: c,
                    radius: r,
                    ..
                },
            ) => {
                assert!(
                    (*center - *c).length() < 1e-5 && (radius - r).abs() < 1e-6,
                    "{center} {radius}"
                );
            }
            other => panic!("{other:?}"),
        }
    }
}

/// `principled`: the base colour, the scalar parameters in their table's order with Mitsuba's
/// defaults, and the index of refraction from `specular` (0.5 by default) or `eta`.
#[test]
fn principled_bsdf() {
    let s = load(
        "<shape type=\"cube\"><bsdf type=\"principled\"/></shape>\
         <shape type=\"cube\"><bsdf type=\"principled\"><rgb name=\"base_color\" value=\"0.1, 0.2, 0.3\"/>\
           <float name=\"metallic\" value=\"0.7\"/><float name=\"eta\" value=\"1.33\"/></bsdf></shape>\
         <shape type=\"cube\"><bsdf type=\"principled\"><float name=\"spec_trans\" value=\"1\"/>\
           <float name=\"specular\" value=\"0\"/></bsdf></shape>",
    );
    let read = |k: usize| match &*s.shapes[k].bsdf {
        BsdfDesc::Principled {
            base_color: TextureDesc::Constant(base),
            parameters,
            eta,
        } => {
            let values: Vec<f32> = parameters
                .iter()
                .map(|t| match t {
                    TextureDesc::Constant(c) => c.r,
                    other => panic!("{other:?}"),
                })
                .collect();
            (*base, values, *eta)
        }
        other => panic!("{other:?}"),
    };
    let (base, values, eta) = read(0);
    assert_eq!(base, Rgb::splat(0.5));
    assert_eq!(values, [0.5, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]);
    // specular 0.5: η = 2/(1 − √0.04) − 1 = 1.5.
    assert!((eta - 1.5).abs() < 1e-6, "{eta}");
    let (base, values, eta) = read(1);
    assert_eq!((base, values[2], eta), (Rgb::new(0.1, 0.2, 0.3), 0.7, 1.33));
    // A transmitting surface needs η ≠ 1: specular 0 becomes 10⁻³, as in Mitsuba.
    let (_, values, eta) = read(2);
    assert_eq!(values[3], 1.0);
    assert!(eta > 1.0 && (eta - (2.0 / (1.0 - (0.08f32 * 1e-3).sqrt()) - 1.0)).abs() < 1e-6);
}

/// Mitsuba integrators that render the same image as one of ours are read as it, with their
/// own defaults (the differentiable ones stop at depth 6), and said so.
#[test]
fn integrators_read_as_the_same_image() {
    for (theirs, ours, depth) in [
        (
            "<integrator type=\"volpathmis\"><integer name=\"max_depth\" value=\"4\"/>\
          <boolean name=\"use_spectral_mis\" value=\"false\"/></integrator>",
            "volpath",
            4,
        ),
        ("<integrator type=\"prb\"/>", "path", 6),
        ("<integrator type=\"prbvolpath\"/>", "volpath", 6),
    ] {
        let s = load(&format!("{theirs}<shape type=\"cube\"/>"));
        assert_eq!(
            (s.integrator.kind.as_str(), s.integrator.max_depth),
            (ours, depth)
        );
        assert!(
            s.notes.iter().any(|n| n.contains("renders the same image")),
            "{:?}",
            s.notes
        );
    }
}

/// Mitsuba's negative-lobed reconstruction filters: `mitchell` (B, C), `catmullrom` (B 0, C ½)
/// and `lanczos` (lobes).
#[test]
fn negative_lobed_filters() {
    let film = |rfilter: &str| {
        load_full(&format!(
            "<scene version=\"3.0.0\"><sensor type=\"perspective\"><film type=\"hdrfilm\">{rfilter}\
             </film></sensor><shape type=\"cube\"/></scene>"
        ))
        .sensor
        .film
        .filter
    };
    assert_eq!(
        film("<rfilter type=\"mitchell\"><float name=\"B\" value=\"0.5\"/></rfilter>"),
        FilterDesc::Mitchell {
            b: 0.5,
            c: 1.0 / 3.0
        }
    );
    assert_eq!(
        film("<rfilter type=\"catmullrom\"/>"),
        FilterDesc::Mitchell { b: 0.0, c: 0.5 }
    );
    assert_eq!(
        film("<rfilter type=\"lanczos\"/>"),
        FilterDesc::Lanczos { lobes: 3 }
    );
    assert_eq!(
        film("<rfilter type=\"lanczos\"><integer name=\"lobes\" value=\"2\"/></rfilter>"),
        FilterDesc::Lanczos { lobes: 2 }
    );
}

#[test]
fn textured_area_emitters_keep_their_texture_and_mean() {
    // Mitsuba's `area` emitter with a texture as its radiance: the texture, and its mean as
    // the emitter's radiance (what power estimates use).
    let s = load(
        "<shape type=\"rectangle\"><emitter type=\"area\">\
           <texture type=\"checkerboard\" name=\"radiance\">\
             <rgb name=\"color0\" value=\"0.8, 0.6, 0.2\"/><rgb name=\"color1\" value=\"0.2, 0.2, 0.4\"/>\
           </texture></emitter></shape>\
         <shape type=\"rectangle\"><emitter type=\"area\"><rgb name=\"radiance\" value=\"2\"/></emitter></shape>",
    );
    let mean = s.shapes[0].emitter.expect("an emitter");
    assert!(
        (mean.to_array()[0] - 0.5).abs() < 1e-6
            && (mean.to_array()[1] - 0.4).abs() < 1e-6
            && (mean.to_array()[2] - 0.3).abs() < 1e-6,
        "{mean:?}"
    );
    assert!(matches!(
        s.shapes[0].emitter_texture,
        Some(TextureDesc::Checkerboard { .. })
    ));
    assert_eq!(s.shapes[1].emitter, Some(Rgb::splat(2.0)));
    assert!(s.shapes[1].emitter_texture.is_none());
}

#[test]
fn constant_spectra_of_emitters_are_equal_energy_white() {
    // Mitsuba 3.9.1's RGB variants read `<spectrum value="v">` as an emitter's radiance,
    // irradiance or intensity as v · xyz_to_srgb(1, 1, 1): its area emitter evaluates
    // <spectrum name="radiance" value="1"/> to (1.20479, 0.948291, 0.908916), a constant
    // environment the same (printed by Mitsuba itself); as a reflectance v stays v.
    let s = load(
        "<shape type=\"rectangle\"><emitter type=\"area\"><spectrum name=\"radiance\" value=\"2\"/></emitter>\
           <bsdf type=\"diffuse\"><spectrum name=\"reflectance\" value=\"0.5\"/></bsdf></shape>\
         <shape type=\"rectangle\"><emitter type=\"area\"><float name=\"radiance\" value=\"2\"/></emitter></shape>\
         <emitter type=\"constant\"><spectrum name=\"radiance\" value=\"1\"/></emitter>\
         <emitter type=\"point\"><spectrum name=\"intensity\" value=\"3\"/></emitter>",
    );
    let mitsuba = Rgb::new(1.20479, 0.948291, 0.908916);
    let near = |a: Rgb, b: Rgb| {
        (0..3).all(|c| (a.to_array()[c] - b.to_array()[c]).abs() < 2e-5 * b.to_array()[c].max(1.0))
    };
    assert!(
        near(s.shapes[0].emitter.unwrap(), mitsuba * 2.0),
        "{:?}",
        s.shapes[0].emitter
    );
    assert_eq!(s.shapes[1].emitter, Some(Rgb::splat(2.0)));
    match &*s.shapes[0].bsdf {
        BsdfDesc::Diffuse { reflectance } => {
            assert!(matches!(reflectance, TextureDesc::Constant(c) if *c == Rgb::splat(0.5)))
        }
        b => panic!("{b:?}"),
    }
    assert!(matches!(s.emitters[0], EmitterDesc::Constant { radiance } if near(radiance, mitsuba)));
    assert!(
        matches!(s.emitters[1], EmitterDesc::Point { intensity, .. } if near(intensity, mitsuba * 3.0))
    );
}

#[test]
fn wavelength_spectra_take_mitsubas_colours() {
    // `<spectrum value="w:v, …">` as Mitsuba 3.9.1's RGB variants read it (the values it
    // prints for these spectra): an emission unweighted, a reflectance weighted by D65; a
    // spectrum outside sRGB's gamut raised to zero with a note.
    let s = load(
        "<shape type=\"rectangle\"><emitter type=\"area\"><spectrum name=\"radiance\" value=\"450:0.5, 550:1.5, 650:1\"/></emitter>\
           <bsdf type=\"diffuse\"><spectrum name=\"reflectance\" value=\"380:0.9, 780:0.9\"/></bsdf></shape>\
         <shape type=\"rectangle\"><emitter type=\"area\"><spectrum name=\"radiance\" value=\"580:0, 590:10, 600:0\"/></emitter></shape>",
    );
    let near = |a: Rgb, b: [f32; 3]| {
        a.to_array()
            .iter()
            .zip(b)
            .all(|(x, y)| (x - y).abs() < 3e-4 * y.max(0.1))
    };
    let e = s.shapes[0].emitter.unwrap();
    assert!(near(e, [1.28426, 1.34645, 0.206701]), "{e:?}");
    match &*s.shapes[0].bsdf {
        BsdfDesc::Diffuse {
            reflectance: TextureDesc::Constant(c),
        } => assert!(near(*c, [0.899039, 0.89902, 0.89869]), "{c:?}"),
        b => panic!("{b:?}"),
    }
    let sodium = s.shapes[1].emitter.unwrap();
    assert!(near(sodium, [2.00233, 0.402763, 0.0]), "{sodium:?}");
    assert!(
        s.notes.iter().any(|n| n.contains("outside sRGB's gamut")),
        "{:?}",
        s.notes
    );
}

#[test]
fn ply_texture_coordinates_flip_only_when_asked() {
    // Mitsuba 3's `ply` keeps the file's (s, t) unless `flip_tex_coords` is true (its default
    // is false, where `obj`'s is true).
    let dir = ScratchDir::new("ply-flip");
    std::fs::write(
        dir.join("tri.ply"),
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
         property float s\nproperty float t\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
         0 0 0 0.1 0.2\n1 0 0 0.9 0.3\n0 1 0 0.4 0.8\n3 0 1 2\n",
    )
    .unwrap();
    let uv_of = |flip: &str| {
        let path = dir.join(format!("scene-{}.xml", flip.len()));
        std::fs::write(
            &path,
            format!(
                "<scene version=\"3.0.0\"><sensor type=\"perspective\"><float name=\"fov\" value=\"45\"/></sensor>\
                 <shape type=\"ply\"><string name=\"filename\" value=\"tri.ply\"/>{flip}</shape></scene>"
            ),
        )
        .unwrap();
        let s = mitsuba::load(&path, &[]).unwrap();
        match &s.shapes[0].geometry {
            Geometry::Mesh(m) => m.uvs.clone().expect("uvs"),
            g => panic!("{g:?}"),
        }
    };
    let kept = uv_of("");
    let flipped = uv_of("<boolean name=\"flip_tex_coords\" value=\"true\"/>");
    assert!(
        (kept[0].x - 0.1).abs() < 1e-6 && (kept[0].y - 0.2).abs() < 1e-6,
        "{kept:?}"
    );
    for (k, f) in kept.iter().zip(&flipped) {
        assert!(
            (f.x - k.x).abs() < 1e-6 && (f.y - (1.0 - k.y)).abs() < 1e-6,
            "{f:?}"
        );
    }
}

#[test]
fn bump_and_normal_maps_read_mitsubas_shading_flags() {
    // `use_shadowing_function` and `flip_invalid_normals`, both true by default as in Mitsuba 3.
    use ircache_scene::PerturbedShading;
    let dir = ScratchDir::new("bump-flags");
    let height = dir.join("height.exr");
    ircache_image::write_image(&height, &ircache_image::Image::new(2, 2), 1.0).unwrap();
    let scene = |ty: &str, texture: &str, flags: &str| {
        format!(
            "<shape type=\"rectangle\"><bsdf type=\"{ty}\">{flags}\
               <texture type=\"bitmap\" name=\"{texture}\"><string name=\"filename\" value=\"{}\"/></texture>\
               <bsdf type=\"diffuse\"/></bsdf></shape>",
            height.display()
        )
    };
    let s = load(
        &(scene("bumpmap", "arbitrary", "")
            + &scene(
                "normalmap",
                "normalmap",
                "<boolean name=\"use_shadowing_function\" value=\"false\"/>\
                 <boolean name=\"flip_invalid_normals\" value=\"false\"/>",
            )),
    );
    match &*s.shapes[0].bsdf {
        BsdfDesc::BumpMap { shading, .. } => assert_eq!(*shading, PerturbedShading::default()),
        b => panic!("{b:?}"),
    }
    match &*s.shapes[1].bsdf {
        BsdfDesc::NormalMap { shading, .. } => assert_eq!(
            *shading,
            PerturbedShading {
                shadowing: false,
                flip_invalid_normals: false
            }
        ),
        b => panic!("{b:?}"),
    }
}
