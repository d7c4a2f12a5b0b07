//! Bad Mitsuba XML input: every error names the exact file:line:column and says what is wrong.
//! The loader must never panic.

use ircache_scene::{mitsuba, SceneError};
use ircache_testing::ScratchDir;
use std::path::{Path, PathBuf};

/// A fresh scratch folder under the system temp dir, removed when dropped.
fn scratch(name: &str) -> ScratchDir {
    ScratchDir::new(&format!("mitsuba-{name}"))
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// Loads `text` as `scene.xml` in a scratch folder; returns the error's text.
fn load_err(name: &str, text: &str) -> (String, PathBuf) {
    let dir = scratch(name);
    let path = write(&dir, "scene.xml", text);
    let err = mitsuba::load(&path, &[]).expect_err("the scene must not load");
    (err.to_string(), path)
}

/// Asserts that the error is at `line:column` of `path` and contains `message`.
fn assert_error(err: &str, path: &Path, line: u32, column: u32, message: &str) {
    let prefix = format!("{}:{line}:{column}: ", path.display());
    assert!(
        err.starts_with(&prefix),
        "expected the error at {line}:{column}, got: {err}"
    );
    assert!(err.contains(message), "expected \"{message}\" in: {err}");
}

const SENSOR: &str = r#"  <sensor type="perspective"><float name="fov" value="45"/></sensor>"#;

/// A scene: line 1 `<scene>`, line 2 the sensor, `body` from line 3, then `</scene>`.
fn scene(body: &str) -> String {
    format!("<scene version=\"3.0.0\">\n{SENSOR}\n{body}\n</scene>\n")
}

#[test]
fn malformed_xml() {
    let (err, path) = load_err(
        "malformed",
        &scene("  <shape type=\"cube\">\n  <shape type=\"cube\"/>"),
    );
    // The unclosed <shape> of line 3 meets </scene> on line 5.
    assert_error(
        &err,
        &path,
        5,
        1,
        "malformed XML: expected 'shape' tag, not 'scene'",
    );
    let (err, path) = load_err(
        "malformed-attr",
        "<scene version=\"3.0.0\">\n  <shape type=cube/>\n</scene>\n",
    );
    assert_error(&err, &path, 2, 15, "malformed XML");
}

#[test]
fn unknown_plugin() {
    let (err, path) = load_err(
        "unknown-plugin",
        &scene("  <shape type=\"cube\">\n    <bsdf type=\"difuse\"/>\n  </shape>"),
    );
    assert_error(&err, &path, 4, 5, "bsdf plugin \"difuse\" not found");
    assert!(err.contains("diffuse, twosided"), "{err}");
}

#[test]
fn unknown_parameter() {
    let body = "  <shape type=\"cube\">\n    <bsdf type=\"diffuse\">\n      <float name=\"roughnes\" value=\"0.1\"/>\n    </bsdf>\n  </shape>";
    let (err, path) = load_err("unknown-param", &scene(body));
    assert_error(
        &err,
        &path,
        5,
        7,
        "unreferenced property \"roughnes\" in bsdf plugin of type \"diffuse\"",
    );
}

#[test]
fn unused_parameter() {
    // `alpha` is a Mitsuba parameter, but a smooth conductor does not use it.
    let body = "  <shape type=\"cube\">\n    <bsdf type=\"conductor\"><float name=\"alpha\" value=\"0.1\"/></bsdf>\n  </shape>";
    let (err, path) = load_err("unused-param", &scene(body));
    assert_error(
        &err,
        &path,
        4,
        28,
        "unreferenced property \"alpha\" in bsdf plugin of type \"conductor\"",
    );
    // `max_depth` is not a parameter of the direct integrator.
    let body = "  <integrator type=\"direct\">\n    <integer name=\"max_depth\" value=\"3\"/>\n  </integrator>\n  <shape type=\"cube\"/>";
    let (err, path) = load_err("unused-param-direct", &scene(body));
    assert_error(
        &err,
        &path,
        4,
        5,
        "unreferenced property \"max_depth\" in integrator plugin of type \"direct\"",
    );
}

#[test]
fn undefined_variable() {
    let body = "  <integrator type=\"path\">\n    <integer name=\"max_depth\" value=\"$depth\"/>\n  </integrator>\n  <shape type=\"cube\"/>";
    let (err, path) = load_err("undefined-var", &scene(body));
    // Points at the `$`.
    assert_error(&err, &path, 4, 38, "undefined parameter \"$depth\"");
    // A <default> after the use does not count (Mitsuba substitutes in document order)...
    let body = "  <shape type=\"sphere\"><float name=\"radius\" value=\"$r\"/></shape>\n  <default name=\"r\" value=\"2\"/>";
    let (err, path) = load_err("default-after-use", &scene(body));
    assert_error(&err, &path, 3, 52, "undefined parameter \"$r\"");
    // ...one before does, and -D overrides it.
    let dir = scratch("default-ok");
    let body = "  <default name=\"r\" value=\"2\"/>\n  <shape type=\"sphere\"><float name=\"radius\" value=\"$r\"/></shape>";
    let path = write(&dir, "scene.xml", &scene(body));
    let radius = |d: &[(String, String)]| match mitsuba::load(&path, d).unwrap().shapes[0].geometry
    {
        ircache_scene::Geometry::Sphere { radius, .. } => radius,
        _ => panic!(),
    };
    assert_eq!(radius(&[]), 2.0);
    assert_eq!(radius(&[("r".into(), "3".into())]), 3.0);
}

/// A `-D` value the scene never uses is an error naming it and the scene's parameters (as
/// Mitsuba 3 refuses unused parameters), in XML, in a file it includes, and for OBJ models,
/// which have none; a used one, in the scene or in an included file, is taken.
#[test]
fn unused_defines_are_errors() {
    let dir = scratch("unused-define");
    write(
        &dir,
        "part.xml",
        "<scene version=\"3.0.0\">\n  <shape type=\"sphere\"><float name=\"radius\" value=\"$r\"/></shape>\n</scene>\n",
    );
    let body = "  <default name=\"r\" value=\"2\"/>\n  <default name=\"spp\" value=\"4\"/>\n  <include filename=\"part.xml\"/>";
    let path = write(&dir, "scene.xml", &scene(body));
    let d = |pairs: &[(&str, &str)]| -> Vec<(String, String)> {
        pairs
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect()
    };
    // $r is used inside the included file.
    assert!(mitsuba::load(&path, &d(&[("r", "3")])).is_ok());
    let err = mitsuba::load(&path, &d(&[("r", "3"), ("max_detph", "7")]))
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("-D max_detph=7") && err.contains("$r") && err.contains("$spp"),
        "{err}"
    );
    assert!(!err.contains("-D r=3"), "{err}");
    // Declared by a <default> but named by no attribute: unused too (Mitsuba's rule).
    let err = mitsuba::load(&path, &d(&[("spp", "16")]))
        .unwrap_err()
        .to_string();
    assert!(err.contains("-D spp=16"), "{err}");
    // OBJ models take no -D at all.
    let obj = write(&dir, "m.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    let camera = ircache_scene::obj_scene::ObjCamera::default();
    assert!(ircache_scene::load_scene(&obj, &[], &camera).is_ok());
    let err = ircache_scene::load_scene(&obj, &d(&[("resx", "16")]), &camera)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("m.obj:1:1") && err.contains("-D resx=16"),
        "{err}"
    );
}

#[test]
fn missing_mesh_file() {
    let body = "  <shape type=\"obj\">\n    <string name=\"filename\" value=\"meshes/nope.obj\"/>\n  </shape>";
    let (err, path) = load_err("missing-mesh", &scene(body));
    assert_error(&err, &path, 4, 5, "nope.obj: file not found");
    let body =
        "  <shape type=\"ply\">\n    <string name=\"filename\" value=\"nope.ply\"/>\n  </shape>";
    let (err, path) = load_err("missing-ply", &scene(body));
    assert_error(&err, &path, 4, 5, "nope.ply: file not found");
}

#[test]
fn mesh_file_errors_keep_their_own_location() {
    let dir = scratch("bad-obj");
    write(&dir, "bad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 zz\nf 1 2 3\n");
    let path = write(
        &dir,
        "scene.xml",
        &scene("  <shape type=\"obj\"><string name=\"filename\" value=\"bad.obj\"/></shape>"),
    );
    let err = mitsuba::load(&path, &[]).unwrap_err().to_string();
    assert!(err.contains("bad.obj:3:"), "{err}");
}

#[test]
fn missing_texture() {
    let body = "  <shape type=\"cube\">\n    <bsdf type=\"diffuse\">\n      <texture type=\"bitmap\" name=\"reflectance\">\n        <string name=\"filename\" value=\"textures/missing.png\"/>\n      </texture>\n    </bsdf>\n  </shape>";
    let (err, path) = load_err("missing-texture", &scene(body));
    assert_error(&err, &path, 6, 9, "missing.png: file not found");
}

#[test]
fn unreadable_texture() {
    let dir = scratch("bad-texture");
    write(&dir, "bad.png", "this is not a PNG");
    let body = "  <shape type=\"cube\">\n    <bsdf type=\"diffuse\">\n      <texture type=\"bitmap\" name=\"reflectance\">\n        <string name=\"filename\" value=\"bad.png\"/>\n      </texture>\n    </bsdf>\n  </shape>";
    let path = write(&dir, "scene.xml", &scene(body));
    let err = mitsuba::load(&path, &[]).unwrap_err();
    assert!(matches!(err, SceneError::Referenced { .. }), "{err:?}");
    assert_error(&err.to_string(), &path, 6, 9, "bad.png");
}

#[test]
fn nan_radiance() {
    let body = "  <shape type=\"rectangle\">\n    <emitter type=\"area\">\n      <rgb name=\"radiance\" value=\"1, nan, 1\"/>\n    </emitter>\n  </shape>";
    let (err, path) = load_err("nan-radiance", &scene(body));
    assert_error(&err, &path, 5, 7, "radiance (1, NaN, 1) is NaN");
}

#[test]
fn negative_radiance() {
    let body = "  <shape type=\"rectangle\">\n    <emitter type=\"area\">\n      <rgb name=\"radiance\" value=\"1 -2 1\"/>\n    </emitter>\n  </shape>";
    let (err, path) = load_err("negative-radiance", &scene(body));
    assert_error(
        &err,
        &path,
        5,
        7,
        "radiance (1, -2, 1) must be finite and non-negative",
    );
    let body = "  <emitter type=\"directional\">\n    <rgb name=\"irradiance\" value=\"-1\"/>\n  </emitter>\n  <shape type=\"cube\"/>";
    let (err, path) = load_err("negative-irradiance", &scene(body));
    assert_error(
        &err,
        &path,
        4,
        5,
        "irradiance (-1, -1, -1) must be finite and non-negative",
    );
    let body = "  <emitter type=\"point\">\n    <float name=\"intensity\" value=\"inf\"/>\n  </emitter>\n  <shape type=\"cube\"/>";
    let (err, path) = load_err("inf-intensity", &scene(body));
    assert_error(
        &err,
        &path,
        4,
        5,
        "intensity (inf, inf, inf) must be finite",
    );
}

#[test]
fn duplicate_id() {
    let body = "  <bsdf type=\"diffuse\" id=\"white\"/>\n  <bsdf type=\"diffuse\" id=\"white\"/>\n  <shape type=\"cube\"><ref id=\"white\"/></shape>";
    let (err, path) = load_err("duplicate-id", &scene(body));
    assert_error(
        &err,
        &path,
        4,
        3,
        "<bsdf> has duplicate id \"white\" (previous was at",
    );
    assert!(err.contains("scene.xml:3:3)"), "{err}");
}

#[test]
fn unknown_ref() {
    let body = "  <bsdf type=\"diffuse\" id=\"white\"/>\n  <shape type=\"cube\">\n    <ref id=\"whtie\"/>\n  </shape>";
    let (err, path) = load_err("unknown-ref", &scene(body));
    assert_error(
        &err,
        &path,
        5,
        5,
        "reference to unknown id \"whtie\" (known ids: \"white\")",
    );
}

#[test]
fn ref_of_wrong_kind() {
    let body = "  <shape type=\"cube\" id=\"box\"/>\n  <shape type=\"cube\">\n    <bsdf type=\"twosided\"><ref id=\"box\"/></bsdf>\n  </shape>";
    let (err, path) = load_err("wrong-kind", &scene(body));
    assert_error(
        &err,
        &path,
        5,
        27,
        "expected a <bsdf> here, but the reference \"box\" names a <shape>",
    );
}

#[test]
fn empty_scene() {
    let (err, path) = load_err("empty", &scene("  <!-- nothing -->"));
    assert_error(&err, &path, 1, 1, "scene has no shapes");
    let (err, path) = load_err(
        "no-sensor",
        "<scene version=\"3.0.0\">\n  <shape type=\"cube\"/>\n</scene>\n",
    );
    assert_error(&err, &path, 1, 1, "scene has no <sensor>");
}

#[test]
fn include_cycle() {
    let dir = scratch("include-cycle");
    let a = write(
        &dir,
        "a.xml",
        &scene("  <include filename=\"parts/b.xml\"/>\n  <shape type=\"cube\"/>"),
    );
    std::fs::create_dir_all(dir.join("parts")).unwrap();
    let b = write(
        &dir,
        "parts/b.xml",
        "<scene version=\"3.0.0\">\n    <include filename=\"../a.xml\"/>\n</scene>\n",
    );
    let err = mitsuba::load(&a, &[]).unwrap_err().to_string();
    assert_error(&err, &b, 2, 5, "include cycle:");
    assert!(
        err.contains("a.xml includes") && err.contains("b.xml includes"),
        "{err}"
    );
}

#[test]
fn includes_are_relative_to_the_including_file() {
    let dir = scratch("include-ok");
    std::fs::create_dir_all(dir.join("parts/meshes")).unwrap();
    write(
        &dir,
        "parts/meshes/tri.obj",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    );
    write(
        &dir,
        "parts/geometry.xml",
        "<scene version=\"3.0.0\">\n  <shape type=\"obj\"><string name=\"filename\" value=\"meshes/tri.obj\"/><ref id=\"red\"/></shape>\n</scene>\n",
    );
    let bsdf =
        "  <bsdf type=\"diffuse\" id=\"red\"><rgb name=\"reflectance\" value=\"0.8 0 0\"/></bsdf>";
    let path = write(
        &dir,
        "scene.xml",
        &scene(&format!(
            "{bsdf}\n  <include filename=\"parts/geometry.xml\"/>"
        )),
    );
    let s = mitsuba::load(&path, &[]).unwrap();
    assert_eq!(s.shapes.len(), 1);
    assert!(s.shapes[0].location.file.ends_with("parts/geometry.xml"));
    assert_eq!(
        (s.shapes[0].location.line, s.shapes[0].location.column),
        (2, 3)
    );
    // Errors inside an included file name that file.
    write(
        &dir,
        "parts/bad.xml",
        "<scene version=\"3.0.0\">\n  <shape type=\"cub\"/>\n</scene>\n",
    );
    let path = write(
        &dir,
        "scene2.xml",
        &scene("  <include filename=\"parts/bad.xml\"/>"),
    );
    let err = mitsuba::load(&path, &[]).unwrap_err().to_string();
    assert_error(
        &err,
        &dir.join("parts/bad.xml"),
        2,
        3,
        "shape plugin \"cub\" not found",
    );
    // A missing include.
    let path = write(
        &dir,
        "scene3.xml",
        &scene("  <include filename=\"parts/none.xml\"/>"),
    );
    let err = mitsuba::load(&path, &[]).unwrap_err().to_string();
    assert_error(&err, &path, 3, 3, "included file");
}

#[test]
fn unknown_element_and_bad_values() {
    let (err, path) = load_err(
        "unknown-element",
        &scene("  <shape type=\"cube\">\n    <colour name=\"x\" value=\"1\"/>\n  </shape>"),
    );
    assert_error(&err, &path, 4, 5, "unexpected tag <colour>");
    let (err, path) = load_err(
        "bad-float",
        &scene(
            "  <shape type=\"sphere\">\n    <float name=\"radius\" value=\"1.5.2\"/>\n  </shape>",
        ),
    );
    assert_error(
        &err,
        &path,
        4,
        26,
        "could not parse floating point value \"1.5.2\"",
    );
    let (err, path) = load_err("bad-int", &scene("  <integrator type=\"path\"><integer name=\"max_depth\" value=\"3.5\"/></integrator>\n  <shape type=\"cube\"/>"));
    assert_error(&err, &path, 3, 53, "could not parse integer value \"3.5\"");
    let (err, path) = load_err("wrong-type", &scene("  <integrator type=\"path\"><float name=\"max_depth\" value=\"3\"/></integrator>\n  <shape type=\"cube\"/>"));
    assert_error(
        &err,
        &path,
        3,
        27,
        "has the wrong type: expected integer, got float",
    );
    let (err, path) = load_err(
        "bad-bool",
        &scene("  <shape type=\"cube\"><boolean name=\"flip_normals\" value=\"yes\"/></shape>"),
    );
    assert_error(&err, &path, 3, 51, "could not parse boolean value \"yes\"");
    let (err, path) = load_err("bad-rgb", &scene("  <shape type=\"cube\"><bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"1 2\"/></bsdf></shape>"));
    assert_error(&err, &path, 3, 67, "<rgb> requires one or three values");
    let (err, path) = load_err("reflectance-range", &scene("  <shape type=\"cube\"><bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"1.2\"/></bsdf></shape>"));
    assert_error(
        &err,
        &path,
        3,
        43,
        "reflectance (1.2, 1.2, 1.2) must lie in [0, 1]",
    );
    let (err, path) = load_err("bad-matrix", &scene("  <shape type=\"cube\"><transform name=\"to_world\"><matrix value=\"1 0 0 1\"/></transform></shape>"));
    assert_error(&err, &path, 3, 57, "<matrix> expects 16");
    let (err, path) = load_err("dup-param", &scene("  <shape type=\"sphere\"><float name=\"radius\" value=\"1\"/><float name=\"radius\" value=\"2\"/></shape>"));
    assert_error(
        &err,
        &path,
        3,
        56,
        "property \"radius\" was specified multiple times",
    );
    let (err, path) = load_err("bad-attr", &scene("  <shape type=\"cube\" size=\"2\"/>"));
    assert_error(&err, &path, 3, 22, "unexpected attribute \"size\"");
    let (err, path) = load_err("no-version", "<scene>\n</scene>\n");
    assert_error(&err, &path, 1, 1, "missing version attribute");
    let (err, path) = load_err("two-bsdfs", &scene("  <shape type=\"cube\">\n    <bsdf type=\"diffuse\"/>\n    <bsdf type=\"diffuse\"/>\n  </shape>"));
    assert_error(&err, &path, 5, 5, "only one BSDF");
    let (err, path) = load_err("ior-name", &scene("  <shape type=\"cube\"><bsdf type=\"dielectric\"><string name=\"int_ior\" value=\"glas\"/></bsdf></shape>"));
    assert_error(&err, &path, 3, 46, "unknown IOR name \"glas\"");
    let (err, path) = load_err("degenerate", &scene("  <shape type=\"rectangle\"><transform name=\"to_world\"><scale y=\"0\"/></transform></shape>"));
    assert_error(&err, &path, 3, 3, "singular");
    let (err, path) = load_err("sphere-scale", &scene("  <shape type=\"sphere\"><transform name=\"to_world\"><scale x=\"2\"/></transform></shape>"));
    assert_error(&err, &path, 3, 3, "uniform scale");
}

#[test]
fn never_panics_on_garbage() {
    let inputs = [
        "",
        "<",
        "<scene version=\"3.0.0\">",
        "<scene version=\"3.0.0\"><sensor/></scene>",
        "<scene version=\"x\"></scene>",
        "<scene version=\"3.0.0\"><shape type=\"cube\"><transform name=\"to_world\"><rotate angle=\"1\"/></transform></shape></scene>",
        "<scene version=\"3.0.0\"><shape type=\"cube\"><transform name=\"to_world\"><lookat origin=\"0 0 0\" target=\"0 0 0\"/></transform></shape></scene>",
        "<scene version=\"3.0.0\">text<shape type=\"cube\"/></scene>",
        "<scene version=\"3.0.0\"><default name=\"a\" value=\"$a\"/><float name=\"$\" value=\"1\"/></scene>",
        "<scene version=\"3.0.0\"><ref id=\"x\"/></scene>",
        "<scene version=\"3.0.0\"><film type=\"hdrfilm\"/></scene>",
        "<scene version=\"3.0.0\"><integer name=\"x\" value=\"99999999999999999999\"/></scene>",
    ];
    let deep = format!(
        "<scene version=\"3.0.0\">{}{}</scene>",
        "<bsdf type=\"twosided\">".repeat(100_000),
        "</bsdf>".repeat(100_000)
    );
    let inputs: Vec<&str> = inputs.iter().copied().chain([deep.as_str()]).collect();
    for (i, text) in inputs.iter().enumerate() {
        let (err, _) = load_err(&format!("garbage-{i}"), text);
        assert!(err.contains("scene.xml:"), "{err}");
    }
}

#[test]
fn serialized_mesh_errors_name_the_reference() {
    use ircache_math::Vec3;
    use ircache_scene::mesh::write_serialized;
    use ircache_scene::TriangleMesh;
    let dir = scratch("serialized");
    let mesh = TriangleMesh {
        positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
        normals: None,
        uvs: None,
        indices: vec![[0, 1, 2]],
    };
    std::fs::write(
        dir.join("one.serialized"),
        write_serialized(&[("t", &mesh, false)]),
    )
    .unwrap();
    std::fs::write(dir.join("bad.serialized"), b"not a mesh").unwrap();
    for (file, index, message) in [
        (
            "one.serialized",
            1,
            "shape_index 1 is out of range: the file holds 1 mesh",
        ),
        ("bad.serialized", 0, "not a Mitsuba serialized mesh"),
    ] {
        let path = write(
            &dir,
            "scene.xml",
            &scene(&format!(
                "  <shape type=\"serialized\">\n    <string name=\"filename\" value=\"{file}\"/>\n    <integer name=\"shape_index\" value=\"{index}\"/>\n  </shape>"
            )),
        );
        let err = mitsuba::load(&path, &[])
            .expect_err("must not load")
            .to_string();
        // The error sits at the filename's line and names the mesh file.
        assert_error(&err, &path, 4, 5, message);
        assert!(err.contains(file), "{err}");
    }
}

#[test]
fn a_mask_needs_a_bsdf_and_an_opacity_in_range() {
    let (err, path) = load_err(
        "mask-empty",
        &scene("  <shape type=\"cube\">\n    <bsdf type=\"mask\"/>\n  </shape>"),
    );
    assert_error(&err, &path, 4, 5, "a nested BSDF is required");
    let (err, path) = load_err(
        "mask-range",
        &scene(
            "  <shape type=\"cube\">\n    <bsdf type=\"mask\">\n      <float name=\"opacity\" value=\"1.5\"/>\n      <bsdf type=\"diffuse\"/>\n    </bsdf>\n  </shape>",
        ),
    );
    assert_error(&err, &path, 5, 7, "opacity");
}

#[test]
fn a_mask_on_one_side_of_a_twosided_is_refused() {
    // The renderer masks a shape as a whole: a mask on the back alone would be dropped.
    let (err, path) = load_err(
        "mask-deep",
        &scene(
            "  <shape type=\"cube\">\n    <bsdf type=\"twosided\">\n      <bsdf type=\"diffuse\"/>\n      <bsdf type=\"mask\"><bsdf type=\"diffuse\"/></bsdf>\n    </bsdf>\n  </shape>",
        ),
    );
    assert_error(&err, &path, 4, 5, "a mask must wrap the shape's whole BSDF");
}

#[test]
fn lens_sensor_errors() {
    let wrap = |sensor: &str| format!("<scene version=\"3.0.0\">\n{sensor}\n</scene>\n");
    // Mitsuba has no default aperture.
    let (err, path) = load_err(
        "no-aperture",
        &wrap(r#"  <sensor type="thinlens"><float name="fov" value="45"/></sensor>"#),
    );
    assert_error(&err, &path, 2, 3, "aperture_radius");
    let (err, path) = load_err(
        "negative-aperture",
        &wrap(
            r#"  <sensor type="thinlens">
    <float name="aperture_radius" value="-1"/></sensor>"#,
        ),
    );
    assert_error(&err, &path, 3, 5, "must be finite and not negative");
    let (err, path) = load_err(
        "focus-zero",
        &wrap(
            r#"  <sensor type="thinlens"><float name="aperture_radius" value="0.1"/>
    <float name="focus_distance" value="0"/></sensor>"#,
        ),
    );
    assert_error(&err, &path, 3, 5, "focus_distance 0");
    let (err, path) = load_err(
        "lens-scale",
        &wrap(
            r#"  <sensor type="thinlens"><float name="aperture_radius" value="0.1"/>
    <transform name="to_world"><scale value="2"/></transform></sensor>"#,
        ),
    );
    assert_error(&err, &path, 2, 3, "must not scale");
    // An orthographic camera has no field of view: a `fov` is not silently ignored.
    let (err, path) = load_err(
        "ortho-fov",
        &wrap(r#"  <sensor type="orthographic"><float name="fov" value="45"/></sensor>"#),
    );
    assert_error(&err, &path, 2, 31, "unreferenced property \"fov\"");
}

#[test]
fn blend_bsdf_errors() {
    let (err, path) = load_err(
        "blend-no-weight",
        &scene(
            r#"  <bsdf type="blendbsdf" id="b"><bsdf type="diffuse"/><bsdf type="diffuse"/></bsdf>"#,
        ),
    );
    assert_error(&err, &path, 3, 3, "needs a \"weight\"");
    let (err, path) = load_err(
        "blend-one",
        &scene(
            r#"  <bsdf type="blendbsdf" id="b"><float name="weight" value="0.5"/><bsdf type="diffuse"/></bsdf>"#,
        ),
    );
    assert_error(&err, &path, 3, 3, "two nested BSDFs must be given");
    let (err, path) = load_err(
        "blend-weight-range",
        &scene(
            r#"  <bsdf type="blendbsdf" id="b">
    <float name="weight" value="1.5"/><bsdf type="diffuse"/><bsdf type="diffuse"/></bsdf>"#,
        ),
    );
    assert_error(&err, &path, 4, 5, "weight");
    // One side twosided, the other not: the back would be half a blend.
    let (err, path) = load_err(
        "blend-sides",
        &scene(
            r#"  <bsdf type="blendbsdf" id="b"><float name="weight" value="0.5"/>
    <bsdf type="twosided"><bsdf type="diffuse"/></bsdf>
    <bsdf type="diffuse"/></bsdf>"#,
        ),
    );
    assert_error(&err, &path, 4, 5, "plain model");
    let (err, path) = load_err(
        "blend-nested",
        &scene(
            r#"  <bsdf type="blendbsdf" id="b"><float name="weight" value="0.5"/>
    <bsdf type="diffuse"/>
    <bsdf type="blendbsdf"><float name="weight" value="0.5"/><bsdf type="diffuse"/><bsdf type="diffuse"/></bsdf></bsdf>"#,
        ),
    );
    assert_error(&err, &path, 5, 5, "plain model");
    // Mitsuba's twosided refuses models that transmit, inside a blend too.
    let (err, path) = load_err(
        "twosided-blend-glass",
        &scene(
            r#"  <bsdf type="twosided" id="b">
    <bsdf type="blendbsdf"><float name="weight" value="0.5"/><bsdf type="diffuse"/><bsdf type="roughdielectric"/></bsdf></bsdf>"#,
        ),
    );
    assert_error(&err, &path, 4, 5, "without transmission");
}

#[test]
fn instancing_errors() {
    // As in Mitsuba: no emitters in a group, no nested groups or instances, one group per
    // instance; and an analytic sphere cannot be stretched.
    let (err, path) = load_err(
        "group-emitter",
        &scene(
            r#"  <shape type="shapegroup" id="g">
    <shape type="cube"><emitter type="area"/></shape></shape>"#,
        ),
    );
    assert_error(&err, &path, 4, 5, "cannot be an emitter");
    let (err, path) = load_err(
        "group-nested",
        &scene(
            r#"  <shape type="shapegroup" id="g">
    <shape type="shapegroup"><shape type="cube"/></shape></shape>"#,
        ),
    );
    assert_error(&err, &path, 4, 5, "no nested groups");
    let (err, path) = load_err("instance-empty", &scene(r#"  <shape type="instance"/>"#));
    assert_error(&err, &path, 3, 3, "needs a reference to a shapegroup");
    let (err, path) = load_err(
        "instance-bsdf",
        &scene(
            r#"  <shape type="shapegroup" id="g"><shape type="cube"/></shape>
  <shape type="instance"><ref id="g"/>
    <bsdf type="diffuse"/></shape>"#,
        ),
    );
    assert_error(&err, &path, 5, 5, "only a shapegroup");
    let (err, path) = load_err(
        "instance-stretched-sphere",
        &scene(
            r#"  <shape type="shapegroup" id="g"><shape type="sphere"/></shape>
  <shape type="instance"><ref id="g"/>
    <transform name="to_world"><scale x="2"/></transform></shape>"#,
        ),
    );
    assert_error(&err, &path, 4, 3, "alike along every axis");
}

#[test]
fn principled_errors() {
    let (err, path) = load_err(
        "principled-both-iors",
        &scene(
            r#"  <bsdf type="principled" id="b"><float name="eta" value="1.5"/>
    <float name="specular" value="0.5"/></bsdf>"#,
        ),
    );
    assert_error(&err, &path, 4, 5, "either \"eta\" or \"specular\"");
    let (err, path) = load_err(
        "principled-range",
        &scene(
            r#"  <bsdf type="principled" id="b">
    <float name="roughness" value="1.5"/></bsdf>"#,
        ),
    );
    assert_error(&err, &path, 4, 5, "roughness");
    // Mitsuba's twosided refuses a principled material that transmits.
    let (err, path) = load_err(
        "twosided-principled-glass",
        &scene(
            r#"  <bsdf type="twosided" id="b">
    <bsdf type="principled"><float name="spec_trans" value="0.5"/></bsdf></bsdf>"#,
        ),
    );
    assert_error(&err, &path, 4, 5, "without transmission");
}

#[test]
fn checkerboard_errors() {
    // Nested textures as colours are not read; a checkerboard is no normal map.
    let (err, path) = load_err(
        "checker-nested",
        &scene(
            r#"  <texture type="checkerboard" id="c">
    <texture type="checkerboard" name="color0"/></texture>
  <shape type="cube"><bsdf type="diffuse"><ref name="reflectance" id="c"/></bsdf></shape>"#,
        ),
    );
    assert_error(&err, &path, 4, 5, "must be a colour or a float");
    let (err, path) = load_err(
        "checker-normalmap",
        &scene(
            r#"  <bsdf type="normalmap" id="n">
    <texture type="checkerboard"/><bsdf type="diffuse"/></bsdf>"#,
        ),
    );
    assert_error(&err, &path, 4, 5, "normal and bump maps read a bitmap");
}

#[test]
fn textured_emitters_are_checked() {
    // A texel that is not a valid radiance is named with its file and position.
    let dir = scratch("textured-emitter");
    let mut img = ircache_image::Image::new(2, 1);
    img.pixels[1] = ircache_math::Rgb::new(1.0, -3.0, 1.0);
    ircache_image::write_image(&dir.join("bad.exr"), &img, 1.0).unwrap();
    let body = "  <shape type=\"rectangle\">\n    <emitter type=\"area\">\n      <texture type=\"bitmap\" name=\"radiance\">\n        <string name=\"filename\" value=\"bad.exr\"/>\n      </texture>\n    </emitter>\n  </shape>";
    let path = write(&dir, "scene.xml", &scene(body));
    let err = mitsuba::load(&path, &[])
        .expect_err("a negative texel")
        .to_string();
    assert_error(&err, &path, 5, 7, "radiance texel (1, 0) of");
    assert!(err.contains("must be finite and non-negative"), "{err}");
}

#[test]
fn bad_wavelength_spectra() {
    for (value, message) in [
        ("500:1", "at least two wavelength:value pairs"),
        ("500:1, 450:2", "wavelengths must increase"),
        ("500:1, 600", "\"600\" is not a wavelength:value pair"),
        (
            "500:1, 600:nan",
            "needs a positive wavelength and a finite value",
        ),
        ("1 2", "one number or wavelength:value pairs"),
    ] {
        let body = format!(
            "  <shape type=\"rectangle\">\n    <emitter type=\"area\">\n      <spectrum name=\"radiance\" value=\"{value}\"/>\n    </emitter>\n  </shape>"
        );
        let (err, path) = load_err("bad-spectrum", &scene(&body));
        assert_error(&err, &path, 5, 33, message);
    }
}

/// A root element that is not `<scene>` is refused at its place; an ircache animation file
/// given where a scene is expected is named as one, with the command that renders it.
#[test]
fn root_element_must_be_a_scene() {
    let (err, path) = load_err("root", "<shapes version=\"3.0.0\"/>\n");
    assert_error(&err, &path, 1, 1, "root element <shapes> must be <scene");
    assert!(!err.contains("animate"), "{err}");
    let (err, path) = load_err(
        "animation-root",
        "<animation version=\"1\" scene=\"scene.xml\" frames=\"4\"/>\n",
    );
    assert_error(&err, &path, 1, 1, "ircache animate");
}
