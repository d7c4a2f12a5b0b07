//! Errors of the scene loaders. Every error that concerns a place in a file names that place.

use std::fmt;
use std::path::PathBuf;
use std::sync::Arc;

/// A position in a source file (1-based line and column).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SourceLocation {
    /// The file.
    pub file: Arc<PathBuf>,
    /// Line, from 1.
    pub line: u32,
    /// Column, from 1.
    pub column: u32,
}

impl SourceLocation {
    /// The start of file `path` (for what concerns the file as a whole).
    #[must_use]
    pub fn start_of(path: &std::path::Path) -> SourceLocation {
        SourceLocation {
            file: Arc::new(path.to_path_buf()),
            line: 1,
            column: 1,
        }
    }
}

impl fmt::Display for SourceLocation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}:{}", self.file.display(), self.line, self.column)
    }
}

/// A scene that could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// Something at a known place in a file is wrong; `message` says what was expected.
    #[error("{location}: {message}")]
    At {
        /// Where.
        location: SourceLocation,
        /// What was wrong and what was expected.
        message: String,
    },
    /// A file could not be read.
    #[error("{}: cannot read: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        source: std::io::Error,
    },
    /// A file referenced from a scene could not be read; `location` is the reference.
    #[error("{location}: cannot read {}: {message}", path.display())]
    Referenced {
        /// Where the file was referenced.
        location: SourceLocation,
        /// The referenced file.
        path: PathBuf,
        /// The cause.
        message: String,
    },
    /// The file's extension names no format this crate reads.
    #[error("{}: unknown scene format (expected .xml for Mitsuba 3, .obj for Wavefront OBJ, .rad or .oct for Radiance)", path.display())]
    UnknownFormat {
        /// The file.
        path: PathBuf,
    },
}

impl SceneError {
    /// An error at a place.
    pub fn at(location: SourceLocation, message: impl Into<String>) -> SceneError {
        SceneError::At {
            location,
            message: message.into(),
        }
    }

    /// This error, met reading a file that `location` names: a file that could not be read
    /// becomes [`SceneError::Referenced`] there; other errors stay as they are.
    #[must_use]
    pub fn referenced_from(self, location: &SourceLocation) -> SceneError {
        match self {
            SceneError::Io { path, source } => SceneError::Referenced {
                location: location.clone(),
                path,
                message: source.to_string(),
            },
            other => other,
        }
    }
}
