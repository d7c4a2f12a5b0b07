//! The Radiance scene loader: geometry and transforms against hand-worked values, materials and
//! sources as documented, views as rpict sizes them, and errors that name the place.

use ircache_math::{Rgb, Vec3};
use ircache_scene::obj_scene::ObjCamera;
use ircache_scene::radiance::sky::SkyBrightness;
use ircache_scene::radiance::view::View;
use ircache_scene::{BsdfDesc, EmitterDesc, Geometry, SceneDesc, SceneError};
use ircache_testing::ScratchDir;
use std::path::{Path, PathBuf};

fn dir(name: &str) -> ScratchDir {
    ScratchDir::new(&format!("rad-{name}"))
}

fn load(d: &Path, files: &[(&str, &str)]) -> Result<SceneDesc, SceneError> {
    for (name, text) in files {
        std::fs::write(d.join(name), text).unwrap();
    }
    ircache_scene::load_scene(&d.join(files[0].0), &[], &ObjCamera::default())
}

fn area(desc: &SceneDesc) -> f64 {
    desc.shapes
        .iter()
        .map(|s| match &s.geometry {
            Geometry::Mesh(m) => ircache_scene::shapes::mesh_area(m),
            Geometry::Sphere { radius, .. } => {
                4.0 * std::f64::consts::PI * f64::from(*radius).powi(2)
            }
        })
        .sum()
}

const GREY: &str = "void plastic grey\n0\n0\n5 .5 .5 .5 0 0\n";

#[test]
fn polygons_keep_their_area_and_front_concave_ones_included() {
    // An L-shaped (concave) polygon of area 3, counter-clockwise seen from +z.
    let d = dir("poly");
    let desc = load(
        &d,
        &[(
            "l.rad",
            &format!("{GREY}grey polygon l\n0\n0\n18 0 0 0 2 0 0 2 1 0 1 1 0 1 2 0 0 2 0\n"),
        )],
    )
    .unwrap();
    assert!((area(&desc) - 3.0).abs() < 1e-5, "area {}", area(&desc));
    let Geometry::Mesh(m) = &desc.shapes[0].geometry else {
        panic!()
    };
    for t in 0..m.indices.len() {
        let n = ircache_scene::shapes::triangle_normal(m, t);
        assert!((n - Vec3::Z).length() < 1e-6, "triangle {t} faces {n}");
    }
    // A wall with a window cut in by a seam (Radiance's way of writing holes): 4 × 3 less 2 × 1.5.
    let desc = load(
        &d,
        &[(
            "w.rad",
            &format!(
                "{GREY}grey polygon w\n0\n0\n30 0 0 0 0 0 3 4 0 3 4 0 0 3 0 0.9 3 0 2.4 1 0 2.4 \
                 1 0 0.9 3 0 0.9 4 0 0\n"
            ),
        )],
    )
    .unwrap();
    assert!((area(&desc) - 9.0).abs() < 1e-5, "area {}", area(&desc));
}

#[test]
fn xform_transforms_in_the_order_written_and_mirrors_reverse_polygons() {
    let d = dir("xform");
    let unit = format!("{GREY}grey polygon sq\n0\n0\n12 0 0 0 1 0 0 1 1 0 0 1 0\n");
    // Rotate 90° about z (x → y), then move by (5, 0, 0): (1, 0, 0) lands on (5, 1, 0).
    let desc = load(
        &d,
        &[
            ("main.rad", "!xform -n a -rz 90 -t 5 0 0 sq.rad\n!xform -mz sq.rad\n!xform -s 2 -a 3 -t 10 0 0 sq.rad\n"),
            ("sq.rad", &unit),
        ],
    )
    .unwrap();
    let mesh = |i: usize| match &desc.shapes[i].geometry {
        Geometry::Mesh(m) => m.clone(),
        Geometry::Sphere { .. } => panic!(),
    };
    assert_eq!(desc.shapes[0].id.as_deref(), Some("a.sq"));
    let m = mesh(0);
    assert!(m
        .positions
        .iter()
        .any(|p| (*p - Vec3::new(5.0, 1.0, 0.0)).length() < 1e-5));
    assert!(m
        .positions
        .iter()
        .any(|p| (*p - Vec3::new(4.0, 1.0, 0.0)).length() < 1e-5));
    // A mirror through z = 0 reverses the vertex order (as xform writes it), so the square's
    // front turns to −z as a mirror image's does.
    let m = mesh(1);
    assert!((ircache_scene::shapes::triangle_normal(&m, 0) - Vec3::NEG_Z).length() < 1e-6);
    // -a 3: copies at x = 0, 10, 20, each scaled by 2 (area 4).
    assert_eq!(desc.shapes.len(), 5);
    for (k, s) in desc.shapes[2..].iter().enumerate() {
        let Geometry::Mesh(m) = &s.geometry else {
            panic!()
        };
        let min_x = m
            .positions
            .iter()
            .map(|p| p.x)
            .fold(f32::INFINITY, f32::min);
        assert!(
            (min_x - 10.0 * k as f32).abs() < 1e-4,
            "copy {k} at {min_x}"
        );
        assert!((ircache_scene::shapes::mesh_area(m) - 4.0).abs() < 1e-4);
    }
}

#[test]
fn cones_cylinders_and_rings_have_the_exact_areas() {
    let d = dir("quadrics");
    let desc = load(
        &d,
        &[(
            "q.rad",
            &format!(
                "{GREY}grey cylinder c\n0\n0\n7 0 0 0 0 0 2 0.5\n\
                 grey cone k\n0\n0\n8 0 0 0 0 0 1 1 0\n\
                 grey ring r\n0\n0\n8 0 0 0 0 0 1 0.5 1\n\
                 grey sphere s\n0\n0\n4 0 0 5 2\n"
            ),
        )],
    )
    .unwrap();
    let pi = std::f64::consts::PI;
    let expect = [
        2.0 * pi * 0.5 * 2.0,   // cylinder
        pi * 1.0 * 2f64.sqrt(), // cone of radius 1, height 1: π r l
        pi * (1.0 - 0.25),      // ring
        4.0 * pi * 4.0,         // sphere
    ];
    for (s, e) in desc.shapes.iter().zip(expect) {
        let a = match &s.geometry {
            Geometry::Mesh(m) => ircache_scene::shapes::mesh_area(m),
            Geometry::Sphere { radius, .. } => 4.0 * pi * f64::from(*radius).powi(2),
        };
        assert!((a - e).abs() < 2e-3 * e, "{:?}: {a} against {e}", s.id);
    }
}

#[test]
fn materials_and_sources_become_what_the_documentation_says() {
    let d = dir("materials");
    let desc = load(
        &d,
        &[(
            "m.rad",
            "void metal steel\n0\n0\n5 .8 .7 .6 .9 .1\n\
             void glass pane\n0\n0\n3 .96 .96 .96\n\
             void light lamp\n0\n0\n3 10 20 30\n\
             void illum port\n1 steel\n0\n3 1 1 1\n\
             void alias steel2 steel\n\
             steel2 sphere ball\n0\n0\n4 0 0 0 1\n\
             pane polygon window\n0\n0\n12 0 0 0 1 0 0 1 1 0 0 1 0\n\
             lamp polygon panel\n0\n0\n12 0 0 3 0 1 3 1 1 3 1 0 3\n\
             port polygon p2\n0\n0\n12 0 0 4 1 0 4 1 1 4 0 1 4\n\
             void polygon invisible\n0\n0\n12 0 0 5 1 0 5 1 1 5 0 1 5\n\
             lamp source sun\n0\n0\n4 0 0 1 0.5\n",
        )],
    )
    .unwrap();
    assert_eq!(desc.shapes.len(), 4, "the void polygon is left out");
    assert!(desc.notes.iter().any(|n| n.contains("'void'")));
    assert!(desc.notes.iter().any(|n| n.contains("illum")));
    let BsdfDesc::TwoSided { front, .. } = &*desc.shapes[0].bsdf else {
        panic!("{:?}", desc.shapes[0].bsdf)
    };
    assert!(
        matches!(**front, BsdfDesc::Ward { metal: true, specularity, roughness, .. } if specularity == 0.9 && roughness == 0.1)
    );
    assert!(matches!(*desc.shapes[1].bsdf, BsdfDesc::Glass { ior, .. } if ior == 1.52));
    assert_eq!(desc.shapes[2].emitter, Some(Rgb::new(10.0, 20.0, 30.0)));
    // The illum renders as its alternate, the metal.
    assert!(
        matches!(&*desc.shapes[3].bsdf, BsdfDesc::TwoSided { front, .. } if matches!(**front, BsdfDesc::Ward { metal: true, .. }))
    );
    // A 0.5° light source: a directional light with the irradiance L·Ω, Ω = 2π(1 − cos 0.25°).
    let omega = (2.0 * std::f64::consts::PI * (1.0 - 0.25f64.to_radians().cos())) as f32;
    let [EmitterDesc::Directional {
        direction,
        irradiance,
    }] = desc.emitters.as_slice()
    else {
        panic!("{:?}", desc.emitters)
    };
    assert!((*direction - Vec3::NEG_Z).length() < 1e-6);
    assert!((irradiance.g / (20.0 * omega) - 1.0).abs() < 1e-3);
}

#[test]
fn errors_name_the_place_and_what_was_expected() {
    let d = dir("errors");
    let cases: [(&str, &str); 8] = [
        (
            "void plastic p\n0\n0\n4 .5 .5 .5 0\n",
            "m.rad:1:1: plastic 'p': expected 5 real arguments, found 4",
        ),
        (
            "nothing polygon x\n0\n0\n9 0 0 0 1 0 0 0 1 0\n",
            "m.rad:1:1: polygon 'x': undefined modifier 'nothing'",
        ),
        (
            "void brightfunc f\n2 x my.cal\n0\n0\nf plastic p\n0\n0\n5 .5 .5 .5 0 0\n",
            "m.rad:1:1: cannot find function file \"my.cal\"",
        ),
        (
            "void aBSDF t\n0\n0\n0\nt sphere s\n0\n0\n4 0 0 0 1\n",
            "m.rad:5:1: sphere 's': its material 't'",
        ),
        (
            "void plastic p\n0\n0\n5 .5 .5 x 0 0\n",
            "m.rad:4:9: expected a real argument, found \"x\"",
        ),
        (
            "!xform -q 3 nothing.rad\n",
            "m.rad:1:1: !xform: unknown or unsupported option \"-q\"",
        ),
        ("!xform missing.rad\n", "m.rad:1:1: cannot read"),
        (
            "void plastic p\n0\n0\n5 .5 .5 .5 0 0\np sphere s\n0\n0\n4 1e39 0 0 1\n",
            "m.rad:5:1: sphere 's': its coordinates, transformed, exceed single precision",
        ),
    ];
    for (text, expect) in cases {
        let e = load(&d, &[("m.rad", text)]).unwrap_err().to_string();
        assert!(e.contains(expect), "{e}\n  expected to contain: {expect}");
    }
    // Patterns, their function and data files.
    let lamp = "f light l\n0\n0\n3 1 1 1\nl polygon q\n0\n0\n12 0 0 1 1 0 1 1 1 1 0 1 1\n";
    let pattern_cases: [(&str, &str, &str); 9] = [
        (
            "void brightfunc f\n2 v my.cal\n0\n0\nf dielectric p\n0\n0\n5 1 1 1 1.5 0\n",
            "v = 1;\n",
            "m.rad:5:1: dielectric 'p': its modifier 'f' is a pattern; ircache reads patterns on \
             plastic, metal, trans, plastic2, metal2, trans2, mirror, glass, light, glow and \
             spotlight materials (and on other patterns), not on dielectric",
        ),
        (
            "void colorpict f\n7 red green blue none.hdr . Px Py\n0\n0\n",
            "",
            "colorpict 'f': cannot find picture \"none.hdr\"",
        ),
        (
            "void brightfunc f\n2 Lu+1 .\n0\n0\n",
            "",
            "polygon 'q': its patterns read Lu or Lv, which only a mesh with (u, v) has",
        ),
        (
            "void plastic a\n0\n0\n5 .5 .5 .5 0 0\nvoid mixfunc f\n4 a void .5 .\n0\n0\n",
            "",
            "mixfunc 'f': 'void': a mixture's parts must be plastic, metal, trans or mirror",
        ),
        (
            "void brightfunc f\n2 v my.cal\n0\n0\n",
            "a = 1;\nv = a + b;\n",
            "my.cal:2:1: undefined variable 'b'",
        ),
        (
            "void brightfunc f\n2 v my.cal\n0\n0\n",
            "v = (1 + ;\n",
            "my.cal:1:10: an expression expected",
        ),
        (
            "void brightfunc f\n2 A3*Dz .\n0\n2 1 2\n",
            "",
            "polygon 'q': its light's patterns give no number",
        ),
        (
            "void brightdata f\n4 noop t.dat . Dz\n0\n0\n",
            "",
            "cannot find data file \"t.dat\"",
        ),
        (
            "void brightfunc f\n3 1 . junk\n0\n0\n",
            "",
            "m.rad:1:1: brightfunc 'f': unexpected string argument \"junk\"",
        ),
    ];
    for (text, cal, expect) in pattern_cases {
        let text = format!("{text}{lamp}");
        let e = load(&d, &[("m.rad", &text), ("my.cal", cal)])
            .unwrap_err()
            .to_string();
        assert!(e.contains(expect), "{e}\n  expected to contain: {expect}");
    }
    let e = load(
        &d,
        &[(
            "m.rad",
            "void spotlight s\n0\n0\n7 1 1 1 30 0 0 -1\ns source sun\n0\n0\n4 0 0 1 1\n",
        )],
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("a distant source cannot be a spotlight"), "{e}");
}

#[test]
fn views_read_as_rpict_and_pictures_fit_with_square_pixels() {
    let v = View::parse(
        "-vtv -vp 1 2 3 -vd 0 -1 0 -vu 0 0 1 -vh 90 -vv 53.13010235",
        Path::new("."),
    )
    .unwrap();
    assert_eq!(v.position.y, 2.0);
    // tan 45° / tan 26.565° = 2: a 512 × 512 box holds 512 × 256.
    assert_eq!(v.fit(512, 512), (512, 256));
    assert_eq!(v.fit(300, 100), (200, 100));
    // Fisheyes: a hemispherical 180° view is square; an angular one keeps its degrees' ratio;
    // sizes beyond each type's limit are refused.
    let hem = View::parse("-vth -vh 180 -vv 180", Path::new(".")).unwrap();
    assert_eq!(hem.fit(512, 512), (512, 512));
    let ang = View::parse("-vta -vh 200 -vv 100", Path::new(".")).unwrap();
    assert_eq!(ang.fit(512, 512), (512, 256));
    assert!(View::parse("-vta -vh 400", Path::new("."))
        .unwrap_err()
        .contains("out of range"));
    assert!(View::parse("-vth -vh 190", Path::new("."))
        .unwrap_err()
        .contains("out of range"));
    assert!(View::parse("-vd 0 0 1 -vu 0 0 2", Path::new("."))
        .unwrap_err()
        .contains("parallel"));
    // A view file's rvu line.
    let d = dir("view");
    std::fs::write(
        d.join("v.vf"),
        "rvu -vtv -vp 0 0 1.5 -vd 1 0 0 -vh 60 -vv 40\n",
    )
    .unwrap();
    let v = View::parse("v.vf", &d).unwrap();
    assert_eq!((v.direction.x, v.horizontal, v.vertical), (1.0, 60.0, 40.0));
}

#[test]
fn skybright_follows_the_cal_file() {
    // Overcast: zenith · (1 + 2 D_z)/3 above, blended into the ground below the horizon.
    let over = SkyBrightness::Cie {
        kind: 2,
        zenith: 9.0,
        ground: 2.0,
        norm: 1.0,
        sun: ircache_math::DVec3::Z,
    };
    let up = over.brightness(ircache_math::DVec3::Z);
    let w = 2.01f64.powi(10);
    let expect = (w * 9.0 + 2.0 / w) / (w + 1.0 / w);
    assert!((up - expect).abs() < 1e-9);
    let down = over.brightness(-ircache_math::DVec3::Z);
    assert!((down - 2.0).abs() < 1e-6, "{down}");
}

#[test]
fn genbox_is_made_as_radiance_makes_it() {
    // `genbox mat box 1 2 3 -i` as Radiance 6.0 prints it: box.1540 is (0,2,3) (0,2,0) (1,2,0)
    // (1,2,3); without -i it is (1,0,0) (1,0,3) (0,0,3) (0,0,0).
    let d = dir("genbox");
    let desc = load(
        &d,
        &[(
            "g.rad",
            &format!("{GREY}!genbox grey box 1 2 3 -i\n!genbox grey out 1 2 3\n"),
        )],
    )
    .unwrap();
    assert_eq!(desc.shapes.len(), 12);
    assert_eq!(desc.shapes[0].id.as_deref(), Some("box.1540"));
    let corners = |i: usize| match &desc.shapes[i].geometry {
        Geometry::Mesh(m) => m.positions.clone(),
        Geometry::Sphere { .. } => panic!(),
    };
    let v = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    assert_eq!(
        corners(0),
        vec![
            v(0.0, 2.0, 3.0),
            v(0.0, 2.0, 0.0),
            v(1.0, 2.0, 0.0),
            v(1.0, 2.0, 3.0)
        ]
    );
    assert_eq!(
        corners(6),
        vec![
            v(1.0, 0.0, 0.0),
            v(1.0, 0.0, 3.0),
            v(0.0, 0.0, 3.0),
            v(0.0, 0.0, 0.0)
        ]
    );
    // Outward faces: each polygon faces away from the box's centre; with -i, towards it.
    let centre = v(0.5, 1.0, 1.5);
    for (i, s) in desc.shapes.iter().enumerate() {
        let Geometry::Mesh(m) = &s.geometry else {
            panic!()
        };
        let n = ircache_scene::shapes::triangle_normal(m, 0);
        let outward = n.dot(m.positions[0] - centre) > 0.0;
        assert_eq!(outward, i >= 6, "{:?}", s.id);
    }
}

#[test]
fn gensky_prints_what_radiance_prints() {
    use ircache_scene::radiance::sky::gensky;
    // The numbers Radiance 6.0's gensky (pyradiance 1.3.1) prints for each command: the sun's
    // radiance and direction where there is a sun, then skyfunc's real arguments.
    let cases: [(&str, &[f64]); 7] = [
        (
            "3 21 14 +s -a 40 -o 105 -m 105",
            &[
                6.692e6, -0.471761, -0.572142, 0.670892, 1.0, 8.830, 20.05, 0.5284, -0.471761,
                -0.572142, 0.670892,
            ],
        ),
        (
            "6 21 9:30 -s -a 51.5 -o 0 -m 0 -g 0.3",
            &[1.0, 10.93, 34.57, 0.6527, 0.562922, -0.319177, 0.762394],
        ),
        (
            "12 21 12EST +i -a 42 -o 71",
            &[
                8.559e5, -0.074842, -0.907560, 0.413200, 4.0, 11.74, 4.411, 1.086, -0.074842,
                -0.907560, 0.413200,
            ],
        ),
        ("7 4 +15 -c -a 35 -o 110 -m 105", &[2.0, 32.66, 5.081]),
        (
            "-ang 30 -45 +s -t 4",
            &[
                6.151e6, 0.612372, -0.612372, 0.5, 1.0, 12.38, 16.78, 0.3986, 0.612372, -0.612372,
                0.5,
            ],
        ),
        ("1 15 10 -u -b 50", &[3.0, 50.0, 10.0]),
        (
            "9 1 16 +s -a -33.9 -o -151.2 -m -150 -r 5e6",
            &[
                5e6, -0.867612, 0.378577, 0.322379, 1.0, 4.491, 8.185, 0.328, -0.867612, 0.378577,
                0.322379,
            ],
        ),
    ];
    for (args, expect) in cases {
        let words: Vec<String> = std::iter::once("gensky")
            .chain(args.split_whitespace())
            .map(str::to_string)
            .collect();
        let text = gensky(&words)
            .expect("a gensky command")
            .expect("valid arguments");
        // The reals: the lines after a count, without the sun's angle 0.5 and the sky's count.
        let mut got = Vec::new();
        for line in text.lines() {
            let w: Vec<&str> = line.split_whitespace().collect();
            if w.len() > 1 && w[0].parse::<usize>() == Ok(w.len() - 1) && !line.contains("skybr") {
                let v: Vec<f64> = w[1..].iter().map(|x| x.parse().unwrap()).collect();
                if w[0] == "3" && v[0] == v[1] && v[1] == v[2] && v[0] > 100.0 {
                    got.push(v[0]); // the sun's radiance, once
                } else if w[0] == "4" {
                    got.extend(&v[..3]); // the sun's direction, not its 0.5°
                } else {
                    got.extend(v);
                }
            }
        }
        assert_eq!(got.len(), expect.len(), "{args}: {text}");
        for (g, e) in got.iter().zip(expect) {
            assert!(
                (g - e).abs() <= 1.5e-3 * e.abs().max(1e-3),
                "{args}: {g} against {e}\n{text}"
            );
        }
    }
    assert!(
        gensky(&["gensky".into(), "13".into(), "1".into(), "12".into()])
            .unwrap()
            .is_err()
    );
    assert!(gensky(&[
        "gensky".into(),
        "3".into(),
        "21".into(),
        "12".into(),
        "-y".into(),
        "2020".into()
    ])
    .is_none());
}

/// The octree of `scenes/radiance-octrees`.
fn stool_octree() -> PathBuf {
    ircache_testing::project_scenes().join("radiance-octrees/stool.oct")
}

fn ward_color(b: &BsdfDesc) -> Rgb {
    match b {
        BsdfDesc::TwoSided { front, .. } => ward_color(front),
        BsdfDesc::Ward { color, .. } => *color,
        other => panic!("not a Ward material: {other:?}"),
    }
}

#[test]
fn instances_place_octrees_with_their_own_or_the_instance_s_materials() {
    let d = dir("instances");
    std::fs::copy(stool_octree(), d.join("stool.oct")).unwrap();
    let s = load(
        &d,
        &[(
            "m.rad",
            "void plastic wood\n0\n0\n5 .9 .9 .9 0 0\n\
             void instance a\n1 stool.oct\n0\n0\n\
             wood instance b\n7 stool.oct -rz 90 -t 5 0 0\n0\n0\n\
             wood polygon after\n0\n0\n9 0 0 0 1 0 0 0 1 0\n",
        )],
    )
    .unwrap();
    assert_eq!(s.shapes.len(), 2 * 30 + 1);
    // The octree's own wood stays its own (not the scene's later 'wood' of the same name).
    let (a, b): (Vec<_>, Vec<_>) = s.shapes[..60]
        .iter()
        .partition(|x| x.id.as_deref().unwrap().starts_with("a/"));
    assert_eq!((a.len(), b.len()), (30, 30));
    assert!(a
        .iter()
        .all(|x| ward_color(&x.bsdf) == Rgb::new(0.5, 0.3, 0.2)));
    assert!(b.iter().all(|x| ward_color(&x.bsdf) == Rgb::splat(0.9)));
    assert_eq!(ward_color(&s.shapes[60].bsdf), Rgb::splat(0.9));
    // Instance b turned 90° about z and moved 5 along x: its extent is the stool's, moved.
    let (lo, hi) = b.iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), x| match &x.geometry {
            Geometry::Mesh(m) => m
                .positions
                .iter()
                .fold((lo, hi), |(lo, hi), &p| (lo.min(p), hi.max(p))),
            _ => (lo, hi),
        },
    );
    assert!(
        (lo - Vec3::new(4.75, -0.25, 0.0)).abs().max_element() < 1e-4,
        "{lo}"
    );
    assert!(
        (hi - Vec3::new(5.25, 0.25, 0.5)).abs().max_element() < 1e-4,
        "{hi}"
    );
}

#[test]
fn damaged_octrees_and_instances_are_errors_naming_the_file() {
    let d = dir("bad-octrees");
    let good = std::fs::read(stool_octree()).unwrap();
    std::fs::write(d.join("cut.oct"), &good[..good.len() / 2]).unwrap();
    std::fs::write(d.join("text.oct"), "void plastic p 0 0 5 1 1 1 0 0\n").unwrap();
    let e = ircache_scene::load_scene(&d.join("cut.oct"), &[], &ObjCamera::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("cut.oct") && e.contains("truncated"), "{e}");
    let e = ircache_scene::load_scene(&d.join("text.oct"), &[], &ObjCamera::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("not a Radiance octree"), "{e}");
    let cases = [
        (
            "void instance a\n3 cut.oct -q 1\n0\n0\n",
            "m.rad:1:1: instance 'a': unknown or unsupported option \"-q\"",
        ),
        (
            "void instance a\n1 missing.oct\n0\n0\n",
            "m.rad:1:1: cannot read",
        ),
        ("void instance a\n0\n0\n0\n", "expected the octree file"),
        (
            "void instance a\n1 cut.oct\n0\n0\n",
            "cut.oct:1:1: the file is truncated",
        ),
    ];
    for (text, expect) in cases {
        let e = load(&d, &[("m.rad", text)]).unwrap_err().to_string();
        assert!(e.contains(expect), "{e}\n  expected to contain: {expect}");
    }
}

#[test]
fn meshes_keep_their_materials_normals_and_uvs_and_damaged_ones_are_errors() {
    let d = dir("meshes");
    let rtm = ircache_testing::project_scenes().join("radiance-octrees/bowl.rtm");
    std::fs::copy(&rtm, d.join("bowl.rtm")).unwrap();
    let s = load(
        &d,
        &[(
            "m.rad",
            "void mesh own\n1 bowl.rtm\n0\n0\n\
             void plastic grey\n0\n0\n5 .5 .5 .5 0 0\n\
             grey mesh given\n5 bowl.rtm -t 3 0 0\n0\n0\n",
        )],
    )
    .unwrap();
    // Its own materials: two bands; given one: the same triangles, grouped as the file groups
    // them, all grey.
    let own: Vec<_> = s
        .shapes
        .iter()
        .filter(|x| x.id.as_deref().unwrap().starts_with("own#"))
        .collect();
    assert_eq!(own.len(), 2);
    let colors: Vec<Rgb> = own.iter().map(|x| ward_color(&x.bsdf)).collect();
    assert!(colors.contains(&Rgb::new(0.7, 0.1, 0.1)) && colors.contains(&Rgb::new(0.1, 0.2, 0.7)));
    let given: Vec<_> = s
        .shapes
        .iter()
        .filter(|x| x.id.as_deref().unwrap().starts_with("given#"))
        .collect();
    assert!(given.iter().all(|x| ward_color(&x.bsdf) == Rgb::splat(0.5)));
    let triangles = |v: &[&ircache_scene::ShapeDesc]| {
        v.iter()
            .map(|x| match &x.geometry {
                Geometry::Mesh(m) => m.indices.len(),
                _ => 0,
            })
            .sum::<usize>()
    };
    // 24 × 12 quads, less the 24 degenerate ones at the pole obj2mesh drops.
    assert_eq!(triangles(&own), 24 * 12 * 2 - 24);
    assert_eq!(triangles(&given), triangles(&own));
    for x in &own {
        let Geometry::Mesh(m) = &x.geometry else {
            panic!()
        };
        // A unit half sphere below its rim: normals are the positions' directions, quantised
        // to Radiance's 32-bit code and its 2⁻³² grid.
        let (n, uv) = (m.normals.as_ref().unwrap(), m.uvs.as_ref().unwrap());
        for (i, p) in m.positions.iter().enumerate() {
            assert!((p.length() - 1.0).abs() < 1e-4 && p.z <= 1e-4, "{p}");
            assert!((n[i] - *p).length() < 1e-3, "{} against {p}", n[i]);
            assert!((0.0..=1.0).contains(&uv[i].x) && (0.0..=1.0).contains(&uv[i].y));
        }
    }
    let good = std::fs::read(&rtm).unwrap();
    std::fs::write(d.join("cut.rtm"), &good[..good.len() * 2 / 3]).unwrap();
    let e = load(&d, &[("m.rad", "void mesh a\n1 cut.rtm\n0\n0\n")])
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("cut.rtm") && (e.contains("truncated") || e.contains("damaged")),
        "{e}"
    );
    let e = load(&d, &[("m.rad", "void mesh a\n1 m.rad\n0\n0\n")])
        .unwrap_err()
        .to_string();
    assert!(e.contains("not a Radiance mesh"), "{e}");
}

#[test]
fn klems_bsdf_files_load_with_their_sides_and_errors_name_the_place() {
    use ircache_scene::klems::KlemsComponent;
    let d = dir("klems");
    let xml = ircache_testing::project_scenes()
        .join("radiance-bsdf/diffuser.xml")
        .canonicalize()
        .unwrap();
    let text = std::fs::read_to_string(&xml).unwrap();
    std::fs::write(d.join("diffuser.xml"), &text).unwrap();
    let surface = "w polygon p\n0\n0\n12 0 0 0 1 0 0 1 1 0 0 1 0\n";
    let desc = load(
        &d,
        &[(
            "m.rad",
            &format!("void BSDF w\n6 0 diffuser.xml 0 0 1 .\n0\n3 .1 .2 .3\n{surface}"),
        )],
    )
    .unwrap();
    let BsdfDesc::Klems {
        data,
        up,
        reflect_front,
        ..
    } = &*desc.shapes[0].bsdf
    else {
        panic!("a Klems BSDF: {:?}", desc.shapes[0].bsdf);
    };
    assert_eq!(*up, Vec3::Z);
    assert_eq!(*reflect_front, Rgb::new(0.1, 0.2, 0.3));
    // Every side present, 41 × 41 on the quarter basis, 0.35/π transmitted.
    for c in KlemsComponent::ALL {
        let m = data.component(c).unwrap();
        assert_eq!(m.values.len(), 41 * 41);
    }
    let t = data
        .component(KlemsComponent::TransmitFront)
        .unwrap()
        .value(3, 17);
    assert!((t.g - 0.35 / std::f32::consts::PI).abs() < 1e-6);
    // The up vector turned by the !xform around the material.
    let desc = load(
        &d,
        &[
            ("n.rad", "!xform -rz 90 m2.rad\n"),
            (
                "m2.rad",
                &format!("void BSDF w\n6 0 diffuser.xml 1 0 0 .\n0\n0\n{surface}"),
            ),
        ],
    )
    .unwrap();
    let BsdfDesc::Klems { up, .. } = &*desc.shapes[0].bsdf else {
        panic!()
    };
    assert!((*up - Vec3::Y).length() < 1e-6, "{up}");
    // Errors.
    let tree = text.replace(">Rows<", ">TensorTree3<");
    std::fs::write(d.join("tree.xml"), tree).unwrap();
    let short = text.replacen("0.063662, ", "", 1);
    std::fs::write(d.join("short.xml"), short).unwrap();
    let cases = [
        (
            "6 0 missing.xml 0 0 1 .\n0\n0",
            "m.rad:1:1: BSDF 'w': cannot find BSDF file \"missing.xml\"",
        ),
        ("6 0 tree.xml 0 0 1 .\n0\n0", "tensor tree (TensorTree3)"),
        (
            "6 0 short.xml 0 0 1 .\n0\n0",
            "1680 values where a 41 × 41 matrix has 1681",
        ),
        (
            "6 0.01 diffuser.xml 0 0 1 .\n0\n0",
            "thickness 0.01: a BSDF proxy",
        ),
        ("6 0 diffuser.xml 0 0 0 .\n0\n0", "its up vector is zero"),
        ("6 0 diffuser.xml 0 0 Dx .\n0\n0", "depends on the ray"),
        (
            "6 0 diffuser.xml 0 0 1 .\n0\n2 1 1",
            "expected 0 or 3 or 6 or 9 real arguments, found 2",
        ),
    ];
    assert_errors(&d, &cases, |args| format!("void BSDF w\n{args}\n{surface}"));
}

/// Each case's scene (`scene` of its first part) fails to load with a message containing its
/// second part.
fn assert_errors(d: &Path, cases: &[(&str, &str)], scene: impl Fn(&str) -> String) {
    for (part, expect) in cases {
        let e = load(d, &[("m.rad", &scene(part))]).unwrap_err().to_string();
        assert!(e.contains(expect), "{e}\n  expected to contain: {expect}");
    }
}

#[test]
fn anisotropic_materials_load_with_their_orientation() {
    let d = dir("aniso");
    let surface = "m polygon p\n0\n0\n12 0 0 0 1 0 0 1 1 0 0 1 0\n";
    let u_of = |desc: &SceneDesc| match &*desc.shapes[0].bsdf {
        BsdfDesc::TwoSided { front, .. } => match &**front {
            BsdfDesc::Ward {
                anisotropy: Some(a),
                roughness,
                metal,
                ..
            } => (a.u, a.roughness_v, *roughness, *metal),
            other => panic!("{other:?}"),
        },
        other => panic!("{other:?}"),
    };
    // As written, turned by the transform xform leaves in the strings, and by an !xform.
    let text = format!("void metal2 m\n4 1 0 0 .\n0\n6 .8 .7 .5 .9 .04 .25\n{surface}");
    let (u, v, r, metal) = u_of(&load(&d, &[("m.rad", &text)]).unwrap());
    assert_eq!((u, v, r, metal), (Vec3::X, 0.25, 0.04, true));
    let text =
        format!("void plastic2 m\n8 1 0 0 . -i 1 -rz 90\n0\n6 .8 .7 .5 .1 .3 .06\n{surface}");
    let (u, _, _, metal) = u_of(&load(&d, &[("m.rad", &text)]).unwrap());
    assert!((u - Vec3::Y).length() < 1e-6 && !metal, "{u}");
    let inner = format!("void metal2 m\n4 1 0 0 .\n0\n6 .8 .7 .5 .9 .04 .25\n{surface}");
    let desc = load(&d, &[("n.rad", "!xform -rz 90 i.rad\n"), ("i.rad", &inner)]).unwrap();
    assert!((u_of(&desc).0 - Vec3::Y).length() < 1e-6);
    let cases = [
        (
            "metal2 m\n4 1 0 0 .\n0\n6 .8 .7 .5 .9 0 .25",
            "the roughnesses 0 0.25 above 0",
        ),
        (
            "metal2 m\n4 0 0 0 .\n0\n6 .8 .7 .5 .9 .1 .25",
            "its orientation vector is zero",
        ),
        (
            "metal2 m\n4 Px 0 0 .\n0\n6 .8 .7 .5 .9 .1 .25",
            "ux \"Px\" depends on the ray",
        ),
        (
            "metal2 m\n3 1 0 0\n0\n6 .8 .7 .5 .9 .1 .25",
            "expected at least 4 string arguments",
        ),
        (
            "trans2 m\n4 1 0 0 .\n0\n8 .8 .7 .5 .1 .1 .2 1.5 .5",
            "transmissivity 1.5 and transmitted specular 0.5 must be in [0, 1]",
        ),
        (
            "prism1 m\n4 1 0 0 .\n0\n8 .8 .7 .5 .1 .1 .2 1.5 .5",
            "prism1, not rendered by ircache",
        ),
        (
            "BRTDfunc m\n10 .1 .1 .1 .5 .5 .5 0 0 Dx .\n0\n9 0 0 0 0 0 0 0 0 0",
            "non-specular BRTD functions (0 0 Dx) are not supported",
        ),
        (
            "BRTDfunc m\n9 .1 .1 .1 .5 .5 .5 0 0 0\n0\n9 0 0 0 0 0 0 0 0 0",
            "expected at least 10 string and 9 real arguments, found 9 and 9",
        ),
        (
            "BRTDfunc m\n10 .1 .1 .1 .5 .5 nothing 0 0 0 .\n0\n9 0 0 0 0 0 0 0 0 0",
            "its coefficients",
        ),
    ];
    assert_errors(&d, &cases, |material| format!("void {material}\n{surface}"));
}

#[test]
fn dielectrics_take_radiance_s_indices() {
    // A dielectric's index at 500 nm by its Hartmann constant (dielectric.c: n + H/500); an
    // interface's inside (opposite the normal) and outside indices.
    let d = dir("dielectric");
    let surface = "m sphere s\n0\n0\n4 0 0 0 1\n";
    for (material, inside, outside) in [
        ("dielectric m\n0\n0\n5 1 1 1 1.5 20", 1.54f32, 1.0f32),
        ("interface m\n0\n0\n8 1 1 1 1.33 1 1 1 1.5", 1.33, 1.5),
    ] {
        let desc = load(&d, &[("m.rad", &format!("void {material}\n{surface}"))]).unwrap();
        let BsdfDesc::Dielectric {
            int_ior, ext_ior, ..
        } = *desc.shapes[0].bsdf
        else {
            panic!("{:?}", desc.shapes[0].bsdf);
        };
        assert!((int_ior - inside).abs() < 1e-6 && (ext_ior - outside).abs() < 1e-6);
    }
    let cases = [
        (
            "interface m\n0\n0\n8 1 1 1 1.33 .9 1 1 1.5",
            "transmission per unit length 0.9 1 1",
        ),
        (
            "interface m\n0\n0\n5 1 1 1 1.33 1",
            "expected 8 real arguments",
        ),
    ];
    assert_errors(&d, &cases, |material| format!("void {material}\n{surface}"));
}
