//! Media in Mitsuba 3 XML: `homogeneous` and `heterogeneous` with Mitsuba's defaults, `.vol`
//! grids, phase functions, `null` boundaries, media on shapes and around the camera, and the
//! errors a wrong file gets (file:line and what was expected).

use ircache_math::{Rgb, Vec3};
use ircache_scene::volume_file::{write_vol, VolFile};
use ircache_scene::{mitsuba, BsdfDesc, MediumKind, PhaseDesc, SceneDesc, SceneError, VolumeDesc};
use ircache_testing::ScratchDir;

fn dir() -> ScratchDir {
    ScratchDir::new("media")
}

fn try_load(body: &str, sensor_extra: &str) -> Result<SceneDesc, SceneError> {
    let dir = dir();
    let grid = VolFile {
        resolution: [2, 2, 2],
        channels: 1,
        bounds: ([-1.0; 3], [1.0, 3.0, 1.0]),
        data: vec![0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0],
    };
    std::fs::write(dir.join("density.vol"), write_vol(&grid)).unwrap();
    std::fs::write(dir.join("broken.vol"), &write_vol(&grid)[..60]).unwrap();
    let path = dir.join("scene.xml");
    std::fs::write(
        &path,
        format!(
            "<scene version=\"3.0.0\">\n<sensor type=\"perspective\">{sensor_extra}</sensor>\n{body}\n</scene>\n"
        ),
    )
    .unwrap();
    mitsuba::load(&path, &[])
}

fn load(body: &str, sensor_extra: &str) -> SceneDesc {
    try_load(body, sensor_extra).unwrap_or_else(|e| panic!("{e}"))
}

fn error(body: &str) -> String {
    match try_load(body, "") {
        Ok(_) => panic!("loaded: {body}"),
        Err(e) => e.to_string(),
    }
}

const FOG: &str = r#"<medium type="homogeneous" id="fog">
    <float name="sigma_t" value="2"/>
    <float name="scale" value="0.5"/>
    <rgb name="albedo" value="0.8, 0.7, 0.6"/>
    <phase type="hg"><float name="g" value="0.3"/></phase>
</medium>"#;

#[test]
fn homogeneous_fog_in_a_null_box_around_the_camera() {
    let s = load(
        &format!(
            "{FOG}\n<shape type=\"cube\"><bsdf type=\"null\"/><ref name=\"interior\" id=\"fog\"/></shape>\n\
             <shape type=\"sphere\"><ref name=\"exterior\" id=\"fog\"/></shape>"
        ),
        "<ref id=\"fog\"/>",
    );
    assert_eq!(s.media.len(), 1, "one medium, referenced three times");
    let m = &s.media[0];
    assert_eq!(m.kind, MediumKind::Homogeneous);
    assert_eq!(m.scale, 0.5);
    assert_eq!(m.phase, PhaseDesc::HenyeyGreenstein { g: 0.3 });
    assert!(
        matches!(m.albedo, VolumeDesc::Constant { value, .. } if value == Rgb::new(0.8, 0.7, 0.6))
    );
    assert!(matches!(*s.shapes[0].bsdf, BsdfDesc::Null));
    assert_eq!(s.shapes[0].media.interior, Some(0));
    assert_eq!(s.shapes[0].media.exterior, None);
    assert_eq!(s.shapes[1].media.exterior, Some(0));
    assert!(
        !matches!(*s.shapes[1].bsdf, BsdfDesc::Null),
        "no BSDF: Mitsuba's diffuse default"
    );
    assert_eq!(s.sensor.medium, Some(0));
}

#[test]
fn mitsuba_defaults() {
    let s = load(
        r#"<shape type="cube"><bsdf type="null"/>
             <medium type="homogeneous" name="interior"><phase type="hg"/></medium></shape>"#,
        "",
    );
    let m = &s.media[0];
    assert!(matches!(m.sigma_t, VolumeDesc::Constant { value, .. } if value == Rgb::ONE));
    assert!(matches!(m.albedo, VolumeDesc::Constant { value, .. } if value == Rgb::splat(0.75)));
    assert_eq!(
        m.phase,
        PhaseDesc::HenyeyGreenstein { g: 0.8 },
        "hg's default g is 0.8"
    );
    assert_eq!(m.scale, 1.0);
    assert!(m.sample_emitters);
    assert!(m.emission.is_none());
    assert_eq!(s.sensor.medium, None);
}

#[test]
fn heterogeneous_grid_with_its_box() {
    let s = load(
        r#"<medium type="heterogeneous" id="smoke">
             <volume name="sigma_t" type="gridvolume">
               <string name="filename" value="density.vol"/>
               <boolean name="use_grid_bbox" value="true"/>
               <string name="filter_type" value="nearest"/>
             </volume>
             <volume name="albedo" type="constvolume"><float name="value" value="0.9"/></volume>
             <rgb name="emission" value="0.1, 0.2, 0.3"/>
             <phase type="isotropic"/>
           </medium>
           <shape type="cube"><bsdf type="null"/><ref name="interior" id="smoke"/></shape>"#,
        "",
    );
    let m = &s.media[0];
    assert_eq!(m.kind, MediumKind::Heterogeneous);
    let VolumeDesc::Grid(g) = &m.sigma_t else {
        panic!("grid expected")
    };
    assert_eq!(g.resolution, [2, 2, 2]);
    assert_eq!(g.data[7], 7.0);
    // use_grid_bbox: the unit cube maps onto the file's box [−1, 1] × [−1, 3] × [−1, 1].
    let top = g.to_world.transform_point3(Vec3::ONE);
    assert!((top - Vec3::new(1.0, 3.0, 1.0)).length() < 1e-6, "{top}");
    assert!(
        matches!(m.emission, Some(VolumeDesc::Constant { value, .. }) if value == Rgb::new(0.1, 0.2, 0.3))
    );
}

#[test]
fn errors_name_the_place_and_what_was_expected() {
    let e = error(
        r#"<medium type="homogeneous"><phase type="hg"><float name="g" value="1"/></phase></medium>"#,
    );
    assert!(e.contains("scene.xml:") && e.contains("(−1, 1)"), "{e}");
    let e = error(r#"<medium type="homogeneous"><float name="sigma_t" value="-1"/></medium>"#);
    assert!(e.contains("non-negative"), "{e}");
    let e = error(r#"<medium type="homogeneous"><float name="albedo" value="1.5"/></medium>"#);
    assert!(e.contains("albedo") && e.contains("[0, 1]"), "{e}");
    let e = error(
        r#"<medium type="homogeneous"><volume name="sigma_t" type="gridvolume"><string name="filename" value="density.vol"/></volume></medium>"#,
    );
    assert!(e.contains("heterogeneous"), "{e}");
    let e = error(
        r#"<medium type="heterogeneous"><volume name="sigma_t" type="gridvolume"><string name="filename" value="broken.vol"/></volume></medium>"#,
    );
    assert!(e.contains("broken.vol") && e.contains("bytes"), "{e}");
    let e = error(r#"<shape type="cube"><medium type="homogeneous" name="inside"/></shape>"#);
    assert!(e.contains("interior") && e.contains("exterior"), "{e}");
    let e = error(r#"<shape type="cube"><ref name="interior" id="nowhere"/></shape>"#);
    assert!(e.contains("nowhere"), "{e}");
    let e = error(r#"<medium type="homogeneous"><float name="density" value="1"/></medium>"#);
    assert!(e.contains("density") && e.contains("unreferenced"), "{e}");
    let e = error(r#"<medium type="fog"/>"#);
    assert!(e.contains("heterogeneous"), "{e}");
}
