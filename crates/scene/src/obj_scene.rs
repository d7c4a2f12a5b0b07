//! A bare Wavefront OBJ + MTL as a whole scene (`ircache render model.obj`): materials from the
//! MTL (`Kd`/`map_Kd`, `Ks`/`Ns`, `Ke` as an area light), a camera from the command line or an
//! automatic framing of the model's bounds.

use crate::{SceneDesc, SceneError};
use ircache_math::Vec3;
use std::path::Path;

/// Camera settings for an OBJ scene; anything left `None` is chosen automatically.
#[derive(Clone, Debug, Default)]
pub struct ObjCamera {
    /// Eye position.
    pub eye: Option<Vec3>,
    /// Point looked at.
    pub target: Option<Vec3>,
    /// Up vector (default +y).
    pub up: Option<Vec3>,
    /// Vertical field of view in degrees (default 45).
    pub fov: Option<f32>,
    /// Image width (default 640).
    pub width: Option<u32>,
    /// Image height (default 480).
    pub height: Option<u32>,
}

/// Loads an OBJ file as a scene.
pub fn load(path: &Path, _camera: &ObjCamera) -> Result<SceneDesc, SceneError> {
    Err(SceneError::UnknownFormat { path: path.to_path_buf() }) // replaced by the OBJ scene loader
}
