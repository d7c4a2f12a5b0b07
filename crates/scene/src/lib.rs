//! Scene description and loaders.
//!
//! Data flows one way: a loader ([`mitsuba`] for Mitsuba 3 XML, [`obj_scene`] for a bare Wavefront
//! OBJ + MTL) reads files and produces a [`SceneDesc`], plain data with every shape already in world
//! space. The renderer builds its acceleration structure, materials and lights from that; nothing
//! here knows about ray tracing.

pub mod animation;
pub mod desc;
pub mod error;
pub mod ior;
pub mod klems;
pub mod mesh;
pub mod mitsuba;
pub mod obj_scene;
pub mod radiance;
pub mod shapes;
pub mod volume_file;

pub use desc::*;
pub use error::{SceneError, SourceLocation};

use std::path::Path;

/// Loads a scene by file extension: `.xml` as Mitsuba 3 XML (with `-D name=value` overrides in
/// `defines`), `.obj` as a bare Wavefront OBJ (camera from `obj_camera`, or automatic framing),
/// `.rad` as a Radiance scene and `.oct` as the scene a Radiance octree holds (the view from
/// `obj_camera.radiance_view`).
pub fn load_scene(
    path: &Path,
    defines: &[(String, String)],
    obj_camera: &obj_scene::ObjCamera,
) -> Result<SceneDesc, SceneError> {
    match path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .as_deref()
    {
        Some("xml") => mitsuba::load(path, defines),
        Some("rad" | "oct") => match defines.first() {
            Some((name, value)) => Err(SceneError::at(
                SourceLocation::start_of(path),
                format!(
                    "-D {name}={value}: a Radiance scene has no parameters (-D sets a Mitsuba XML \
                     scene's $parameters; for Radiance scenes use --view, --width, --height, \
                     --spp, --max-depth)"
                ),
            )),
            None => radiance::load(path, obj_camera),
        },
        Some("obj") => match defines.first() {
            // An OBJ file has no parameters: a -D would be dropped without a word.
            Some((name, value)) => Err(SceneError::at(
                SourceLocation::start_of(path),
                format!(
                    "-D {name}={value}: an OBJ scene has no parameters (-D sets a Mitsuba XML \
                     scene's $parameters; for OBJ use --width, --height, --spp, --max-depth, --eye, \
                     --target, --fov)"
                ),
            )),
            None => obj_scene::load(path, obj_camera),
        },
        _ => Err(SceneError::UnknownFormat {
            path: path.to_path_buf(),
        }),
    }
}
