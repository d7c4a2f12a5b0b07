//! Mitsuba 3 XML scenes (being written).

use crate::{SceneDesc, SceneError};
use std::path::Path;

/// Loads a Mitsuba 3 XML scene with `-D name=value` overrides.
pub fn load(path: &Path, _defines: &[(String, String)]) -> Result<SceneDesc, SceneError> {
    Err(SceneError::UnknownFormat { path: path.to_path_buf() }) // replaced by the XML loader
}
