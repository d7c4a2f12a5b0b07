//! Animated scenes: keyframed rigid motions of shapes (area lights included) and of the camera,
//! for rendering frame sequences (temporal radiance caching, 001 ch. 5; age-based invalidation,
//! 000 §3.7.3).
//!
//! An animation is its own small XML file beside a Mitsuba 3 scene, so that the scene file stays
//! one Mitsuba renders as it is (the frame-0 pose of the animation is the scene as written only
//! when every track's first key is the identity):
//!
//! ```xml
//! <animation version="1" scene="scene.xml" frames="48">
//!     <move shape="cube" pivot="0 0.3 0">          <!-- a shape's id -->
//!         <key frame="0"  translate="-0.5 0 0"/>
//!         <key frame="47" translate="0.5 0 0" rotate="0 1 0 90" scale="1"/>
//!     </move>
//!     <camera>                                      <!-- the sensor -->
//!         <key frame="0"/> <key frame="47" rotate="0 1 0 5"/>
//!     </camera>
//! </animation>
//! ```
//!
//! A key's motion is `T(pivot) · T(translate) · R(rotate) · S(scale) · T(−pivot)`, applied to the
//! world-space shape (after its own `to_world`) or to the camera's `to_world`. `rotate` is an
//! axis and an angle in degrees, `scale` one factor or three. Between keys the translation and
//! scale are interpolated linearly and the rotation along the shorter arc (quaternion slerp), so
//! two keys of the same axis must be less than 180° apart; before the first key and after the
//! last the motion holds. Frames are numbered from 0; `frames` is the sequence's length.

use crate::desc::{Geometry, SceneDesc};
use crate::error::{SceneError, SourceLocation};
use glam::{Mat4, Quat, Vec3};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// One pose of a track.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Key {
    /// Frame number (may be fractional).
    pub frame: f32,
    /// Translation.
    pub translate: Vec3,
    /// Rotation about the pivot.
    pub rotation: Quat,
    /// Scale about the pivot.
    pub scale: Vec3,
}

/// What a track moves.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Target {
    /// The shape at this index of [`SceneDesc::shapes`].
    Shape(usize),
    /// The camera.
    Camera,
}

/// The keys of one moving thing.
#[derive(Clone, Debug, PartialEq)]
pub struct Track {
    /// What moves.
    pub target: Target,
    /// Point the rotation and scale are about.
    pub pivot: Vec3,
    /// Keys, by increasing frame (at least one).
    pub keys: Vec<Key>,
}

/// Keyframed rigid motions over a frame sequence (plain data).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Animation {
    /// Frames in the sequence (0 for a static scene given no length).
    pub frames: u32,
    /// The moving things.
    pub tracks: Vec<Track>,
}

impl Track {
    /// The motion (world to world) at `frame`.
    #[must_use]
    pub fn motion(&self, frame: f32) -> Mat4 {
        let k = self.pose(frame);
        Mat4::from_translation(self.pivot + k.translate)
            * Mat4::from_quat(k.rotation)
            * Mat4::from_scale(k.scale)
            * Mat4::from_translation(-self.pivot)
    }

    /// The interpolated pose at `frame`.
    fn pose(&self, frame: f32) -> Key {
        let first = self.keys[0];
        let last = self.keys[self.keys.len() - 1];
        if frame <= first.frame {
            return first;
        }
        if frame >= last.frame {
            return last;
        }
        let i = self.keys.partition_point(|k| k.frame <= frame) - 1;
        let (a, b) = (self.keys[i], self.keys[i + 1]);
        let s = (frame - a.frame) / (b.frame - a.frame);
        Key {
            frame,
            translate: a.translate.lerp(b.translate, s),
            rotation: a.rotation.slerp(b.rotation, s),
            scale: a.scale.lerp(b.scale, s),
        }
    }
}

impl Animation {
    /// The track moving shape `shape`, if any.
    #[must_use]
    pub fn shape_track(&self, shape: usize) -> Option<&Track> {
        self.tracks
            .iter()
            .find(|t| t.target == Target::Shape(shape))
    }

    /// Whether shape `shape` moves.
    #[must_use]
    pub fn is_moving(&self, shape: usize) -> bool {
        self.shape_track(shape).is_some()
    }

    /// Whether anything but the camera moves.
    #[must_use]
    pub fn moves_shapes(&self) -> bool {
        self.tracks.iter().any(|t| t.target != Target::Camera)
    }

    /// The transform taking shape `shape` as it is at frame `from` to where it is at frame `to`
    /// (the identity for a static shape).
    #[must_use]
    pub fn shape_motion(&self, shape: usize, from: f32, to: f32) -> Mat4 {
        match self.shape_track(shape) {
            Some(t) => t.motion(to) * t.motion(from).inverse(),
            None => Mat4::IDENTITY,
        }
    }

    /// The scene at `frame`: each track's motion applied to its shape or to the camera.
    #[must_use]
    pub fn scene_at(&self, base: &SceneDesc, frame: f32) -> SceneDesc {
        let mut desc = base.clone();
        for track in &self.tracks {
            let m = track.motion(frame);
            match track.target {
                Target::Camera => desc.sensor.to_world = m * desc.sensor.to_world,
                Target::Shape(i) => transform_geometry(&mut desc.shapes[i].geometry, &m),
            }
        }
        desc
    }
}

/// Moves world-space geometry by the rigid (or uniformly scaled, for spheres) motion `m`.
fn transform_geometry(g: &mut Geometry, m: &Mat4) {
    match g {
        Geometry::Mesh(mesh) => {
            for p in &mut mesh.positions {
                *p = m.transform_point3(*p);
            }
            if let Some(normals) = &mut mesh.normals {
                let nm = m.inverse().transpose();
                for n in normals {
                    *n = nm.transform_vector3(*n).normalize_or_zero();
                }
            }
        }
        Geometry::Sphere { center, radius, .. } => {
            *center = m.transform_point3(*center);
            // Uniform scale only (checked when the animation is read).
            *radius *= m.transform_vector3(Vec3::X).length();
        }
    }
}

/// Whether `path` is an animation file: an `.xml` file whose root element is `<animation>`
/// (anything else, malformed XML included, is left to the scene loaders to read or report).
///
/// # Errors
/// An `.xml` file that cannot be read.
pub fn is_animation(path: &Path) -> Result<bool, SceneError> {
    let xml = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("xml"));
    if !xml {
        return Ok(false);
    }
    let text = std::fs::read_to_string(path).map_err(|source| SceneError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    Ok(roxmltree::Document::parse(&text)
        .is_ok_and(|doc| doc.root_element().tag_name().name() == "animation"))
}

/// Reads an animation file and the scene it names (with `-D` overrides): the scene at rest and
/// its motions.
///
/// # Errors
/// A malformed file, an unknown shape id, keys out of order, a rotation of 180° or more between
/// keys, a non-uniform scale on a sphere or any scale on the camera, each at file:line:column.
pub fn load_animation(
    path: &Path,
    defines: &[(String, String)],
) -> Result<(SceneDesc, Animation), SceneError> {
    let text = std::fs::read_to_string(path).map_err(|source| SceneError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let file = Arc::new(path.to_path_buf());
    let doc = roxmltree::Document::parse(&text).map_err(|e| {
        let pos = e.pos();
        SceneError::at(
            SourceLocation {
                file: file.clone(),
                line: pos.row,
                column: pos.col,
            },
            format!("malformed XML: {e}"),
        )
    })?;
    let at = |node: roxmltree::Node| {
        let pos = doc.text_pos_at(node.range().start);
        SourceLocation {
            file: file.clone(),
            line: pos.row,
            column: pos.col,
        }
    };
    let root = doc.root_element();
    if root.tag_name().name() != "animation" {
        return Err(SceneError::at(
            at(root),
            format!(
                "root element <{}> must be <animation version=\"1\" scene=\"...\" frames=\"...\">",
                root.tag_name().name()
            ),
        ));
    }
    check_attributes(root, &["version", "scene", "frames"], &at)?;
    if root.attribute("version") != Some("1") {
        return Err(SceneError::at(at(root), "<animation> needs version=\"1\""));
    }
    let scene_name = root
        .attribute("scene")
        .ok_or_else(|| SceneError::at(at(root), "<animation> needs scene=\"FILE.xml\""))?;
    let frames = match root.attribute("frames") {
        Some(f) => f
            .trim()
            .parse::<u32>()
            .ok()
            .filter(|&n| n > 0)
            .ok_or_else(|| {
                SceneError::at(
                    at(root),
                    format!("frames=\"{f}\": expected a whole number of frames ≥ 1"),
                )
            })?,
        None => 0,
    };
    let scene_path: PathBuf = path
        .parent()
        .map_or_else(|| PathBuf::from(scene_name), |d| d.join(scene_name));
    let desc = crate::load_scene(
        &scene_path,
        defines,
        &crate::obj_scene::ObjCamera::default(),
    )
    .map_err(|e| e.referenced_from(&at(root)))?;
    let mut tracks: Vec<Track> = Vec::new();
    for node in root.children().filter(roxmltree::Node::is_element) {
        let (target, pivot) = match node.tag_name().name() {
            "move" => {
                check_attributes(node, &["shape", "pivot"], &at)?;
                let id = node.attribute("shape").ok_or_else(|| {
                    SceneError::at(at(node), "<move> needs shape=\"ID\" (a shape's id)")
                })?;
                let index = desc
                    .shapes
                    .iter()
                    .position(|s| s.id.as_deref() == Some(id))
                    .ok_or_else(|| {
                        SceneError::at(
                            at(node),
                            format!(
                                "no shape with id \"{id}\" in {} (a <move> names a shape by its id)",
                                scene_path.display()
                            ),
                        )
                    })?;
                (Target::Shape(index), node.attribute("pivot"))
            }
            "camera" => {
                check_attributes(node, &["pivot"], &at)?;
                (Target::Camera, node.attribute("pivot"))
            }
            other => {
                return Err(SceneError::at(
                    at(node),
                    format!("unexpected <{other}> (expected <move shape=\"ID\"> or <camera>)"),
                ))
            }
        };
        if tracks.iter().any(|t| t.target == target) {
            return Err(SceneError::at(
                at(node),
                "this shape or the camera already has a track (give each one track)",
            ));
        }
        let pivot = match pivot {
            Some(p) => numbers::<3>(p, "pivot", at(node))?.into(),
            None => Vec3::ZERO,
        };
        let mut keys: Vec<Key> = Vec::new();
        let mut axes: Vec<Option<(Vec3, f32)>> = Vec::new();
        for k in node.children().filter(roxmltree::Node::is_element) {
            if k.tag_name().name() != "key" {
                return Err(SceneError::at(
                    at(k),
                    format!("unexpected <{}> (expected <key>)", k.tag_name().name()),
                ));
            }
            check_attributes(k, &["frame", "translate", "rotate", "scale"], &at)?;
            let frame = k
                .attribute("frame")
                .ok_or_else(|| SceneError::at(at(k), "<key> needs frame=\"N\""))?;
            let frame = numbers::<1>(frame, "frame", at(k))?[0];
            if let Some(prev) = keys.last() {
                if frame <= prev.frame {
                    return Err(SceneError::at(
                        at(k),
                        format!(
                            "key at frame {frame} after one at frame {}: keys must be in increasing frame order",
                            prev.frame
                        ),
                    ));
                }
            }
            let translate = match k.attribute("translate") {
                Some(t) => numbers::<3>(t, "translate", at(k))?.into(),
                None => Vec3::ZERO,
            };
            let (rotation, axis) = match k.attribute("rotate") {
                Some(r) => {
                    let [x, y, z, angle] = numbers::<4>(r, "rotate", at(k))?;
                    let axis = Vec3::new(x, y, z);
                    if axis.length_squared() == 0.0 {
                        return Err(SceneError::at(
                            at(k),
                            "rotate=\"x y z angle\": the axis is zero",
                        ));
                    }
                    let axis = axis.normalize();
                    (
                        Quat::from_axis_angle(axis, angle.to_radians()),
                        Some((axis, angle)),
                    )
                }
                None => (Quat::IDENTITY, None),
            };
            let scale = match k.attribute("scale") {
                Some(s) if s.split_whitespace().count() == 1 => {
                    Vec3::splat(numbers::<1>(s, "scale", at(k))?[0])
                }
                Some(s) => numbers::<3>(s, "scale", at(k))?.into(),
                None => Vec3::ONE,
            };
            if scale.min_element() <= 0.0 {
                return Err(SceneError::at(
                    at(k),
                    "scale must be positive (a mirroring or collapsing motion is not rigid)",
                ));
            }
            let scaled = (scale - Vec3::ONE).abs().max_element() > 0.0;
            let uniform = (scale - Vec3::splat(scale.x)).abs().max_element() == 0.0;
            match target {
                Target::Camera if scaled => {
                    return Err(SceneError::at(at(k), "the camera cannot be scaled"));
                }
                Target::Shape(i)
                    if !uniform && matches!(desc.shapes[i].geometry, Geometry::Sphere { .. }) =>
                {
                    return Err(SceneError::at(
                        at(k),
                        "a sphere can only be scaled uniformly (one scale factor)",
                    ));
                }
                _ => {}
            }
            // Slerp takes the shorter arc: keys about one axis must turn less than 180°.
            let last_axis = axes.last().copied().flatten();
            if let (Some((a0, t0)), Some((a1, t1))) = (last_axis, axis) {
                if a0.dot(a1) > 0.9999 && (t1 - t0).abs() >= 180.0 {
                    return Err(SceneError::at(
                        at(k),
                        format!(
                            "rotation from {t0}° to {t1}° between two keys: interpolation takes the shorter arc, so keys must be less than 180° apart (add a key in between)"
                        ),
                    ));
                }
            }
            keys.push(Key {
                frame,
                translate,
                rotation,
                scale,
            });
            axes.push(axis);
        }
        if keys.is_empty() {
            return Err(SceneError::at(at(node), "a track needs at least one <key>"));
        }
        tracks.push(Track {
            target,
            pivot,
            keys,
        });
    }
    Ok((desc, Animation { frames, tracks }))
}

/// Rejects attributes outside `allowed`.
fn check_attributes(
    node: roxmltree::Node,
    allowed: &[&str],
    at: &dyn Fn(roxmltree::Node) -> SourceLocation,
) -> Result<(), SceneError> {
    for a in node.attributes() {
        if !allowed.contains(&a.name()) {
            return Err(SceneError::at(
                at(node),
                format!(
                    "unexpected attribute {}=\"{}\" on <{}> (expected {})",
                    a.name(),
                    a.value(),
                    node.tag_name().name(),
                    allowed.join(", ")
                ),
            ));
        }
    }
    Ok(())
}

/// `N` finite numbers separated by spaces or commas.
fn numbers<const N: usize>(
    s: &str,
    what: &str,
    loc: SourceLocation,
) -> Result<[f32; N], SceneError> {
    let v: Vec<f32> = s
        .split(|c: char| c == ',' || c.is_whitespace())
        .filter(|t| !t.is_empty())
        .map(str::parse::<f32>)
        .collect::<Result<_, _>>()
        .unwrap_or_default();
    match <[f32; N]>::try_from(v) {
        Ok(a) if a.iter().all(|x| x.is_finite()) => Ok(a),
        _ => Err(SceneError::at(
            loc,
            format!("{what}=\"{s}\": expected {N} finite number(s)"),
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn track(keys: Vec<Key>, pivot: Vec3) -> Track {
        Track {
            target: Target::Shape(0),
            pivot,
            keys,
        }
    }

    fn key(frame: f32, translate: Vec3, axis: Vec3, degrees: f32) -> Key {
        Key {
            frame,
            translate,
            rotation: Quat::from_axis_angle(axis, degrees.to_radians()),
            scale: Vec3::ONE,
        }
    }

    #[test]
    fn translation_is_linear_and_holds_outside_the_keys() {
        let t = track(
            vec![
                key(0.0, Vec3::ZERO, Vec3::Y, 0.0),
                key(10.0, Vec3::new(2.0, 0.0, -1.0), Vec3::Y, 0.0),
            ],
            Vec3::ZERO,
        );
        let p = Vec3::new(0.3, 0.4, 0.5);
        let at = |f: f32| t.motion(f).transform_point3(p);
        assert!((at(5.0) - (p + Vec3::new(1.0, 0.0, -0.5))).length() < 1e-6);
        assert!((at(-3.0) - p).length() < 1e-6);
        assert!((at(12.0) - (p + Vec3::new(2.0, 0.0, -1.0))).length() < 1e-6);
    }

    #[test]
    fn rotation_turns_at_a_constant_rate_about_the_pivot() {
        let pivot = Vec3::new(1.0, 0.0, 0.0);
        let t = track(
            vec![
                key(0.0, Vec3::ZERO, Vec3::Y, 0.0),
                key(4.0, Vec3::ZERO, Vec3::Y, 120.0),
            ],
            pivot,
        );
        // A point one unit from the pivot along +x turns 30° per frame about +y.
        let p = pivot + Vec3::X;
        for f in 0..=4 {
            let q = t.motion(f as f32).transform_point3(p);
            let a = (30.0 * f as f32).to_radians();
            let want = pivot + Vec3::new(a.cos(), 0.0, -a.sin());
            assert!((q - want).length() < 1e-5, "frame {f}: {q} vs {want}");
        }
        // The pivot itself never moves.
        assert!((t.motion(2.5).transform_point3(pivot) - pivot).length() < 1e-6);
    }

    #[test]
    fn motion_between_frames_composes() {
        let t = track(
            vec![
                key(0.0, Vec3::ZERO, Vec3::Z, 0.0),
                key(8.0, Vec3::new(0.0, 1.0, 0.0), Vec3::Z, 90.0),
            ],
            Vec3::ZERO,
        );
        let anim = Animation {
            frames: 9,
            tracks: vec![t.clone()],
        };
        let p0 = Vec3::new(0.2, -0.1, 0.7);
        let p3 = t.motion(3.0).transform_point3(p0);
        let p6 = anim.shape_motion(0, 3.0, 6.0).transform_point3(p3);
        assert!((p6 - t.motion(6.0).transform_point3(p0)).length() < 1e-5);
        assert_eq!(anim.shape_motion(1, 3.0, 6.0), Mat4::IDENTITY);
    }

    /// Writes an animation of the repository's cube-in-box scene with `body` as its tracks, in a
    /// scratch directory that goes when the first of the pair is dropped.
    fn animation_file(name: &str, body: &str) -> (ircache_testing::ScratchDir, std::path::PathBuf) {
        let scene = ircache_testing::project_scenes().join("cube-in-box/scene.xml");
        let scene = scene.display();
        let dir = ircache_testing::ScratchDir::new("anim");
        let path = dir.join(name);
        std::fs::write(
            &path,
            format!(
                "<animation version=\"1\" scene=\"{scene}\" frames=\"5\">\n{body}</animation>\n"
            ),
        )
        .unwrap();
        (dir, path)
    }

    #[test]
    fn camera_and_shape_tracks_move_the_scene() {
        let (_dir, path) = animation_file(
            "camera.xml",
            "<camera><key frame=\"0\"/><key frame=\"4\" translate=\"0 0.4 0\"/></camera>\n\
             <move shape=\"Light\"><key frame=\"0\"/><key frame=\"4\" translate=\"0.2 0 0\"/></move>\n",
        );
        let (desc, anim) = load_animation(&path, &[]).unwrap();
        assert_eq!(anim.frames, 5);
        let at2 = anim.scene_at(&desc, 2.0);
        // The camera rose by half the final 0.4; its orientation kept.
        let eye = |d: &SceneDesc| d.sensor.to_world.transform_point3(Vec3::ZERO);
        assert!((eye(&at2) - eye(&desc) - Vec3::new(0.0, 0.2, 0.0)).length() < 1e-5);
        assert_eq!(
            at2.sensor.to_world.transform_vector3(Vec3::Z),
            desc.sensor.to_world.transform_vector3(Vec3::Z)
        );
        // The light moved by 0.1 in x; every other shape stayed.
        let light = desc
            .shapes
            .iter()
            .position(|s| s.id.as_deref() == Some("Light"))
            .unwrap();
        for (i, (a, b)) in desc.shapes.iter().zip(&at2.shapes).enumerate() {
            let (Geometry::Mesh(a), Geometry::Mesh(b)) = (&a.geometry, &b.geometry) else {
                panic!("meshes")
            };
            let want = if i == light {
                Vec3::new(0.1, 0.0, 0.0)
            } else {
                Vec3::ZERO
            };
            for (p, q) in a.positions.iter().zip(&b.positions) {
                assert!((*q - *p - want).length() < 1e-5, "shape {i}");
            }
        }
        assert!(anim.is_moving(light) && anim.moves_shapes());
    }

    #[test]
    fn animation_files_are_told_from_scenes_by_their_root() {
        let (_dir, anim) = animation_file("root.xml", "");
        assert!(is_animation(&anim).unwrap());
        let scene = ircache_testing::project_scenes().join("cube-in-box/scene.xml");
        assert!(!is_animation(&scene).unwrap());
        // A scene whose comment mentions <animation> at a line's start is still a scene.
        let dir = anim.parent().unwrap().to_path_buf();
        let commented = dir.join("commented.xml");
        std::fs::write(
            &commented,
            "<!--\n<animation> files move shapes\n-->\n<scene version=\"3.0.0\"/>\n",
        )
        .unwrap();
        assert!(!is_animation(&commented).unwrap());
        assert!(!is_animation(Path::new("model.obj")).unwrap());
    }

    #[test]
    fn bad_tracks_are_errors_at_their_place() {
        let cases = [
            (
                "<camera><key frame=\"0\" scale=\"2\"/></camera>\n",
                "2:",
                "cannot be scaled",
            ),
            ("<move shape=\"Cube\"></move>\n", "2:", "at least one <key>"),
            (
                "<move shape=\"Cube\"><key frame=\"0\" translate=\"1 2\"/></move>\n",
                "2:",
                "expected 3",
            ),
            ("<spin shape=\"Cube\"/>\n", "2:", "unexpected <spin>"),
            (
                "<move shape=\"Cube\" speed=\"2\"><key frame=\"0\"/></move>\n",
                "2:",
                "unexpected attribute speed",
            ),
        ];
        for (i, (body, line, what)) in cases.iter().enumerate() {
            let (_dir, path) = animation_file(&format!("bad{i}.xml"), body);
            let e = load_animation(&path, &[]).unwrap_err().to_string();
            assert!(
                e.contains(&format!("bad{i}.xml:{line}")) && e.contains(what),
                "{e}"
            );
        }
    }
}
