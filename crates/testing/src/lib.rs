//! What the tests of every ircache crate share (a dev-dependency only): scratch directories that
//! a test writes its scene files, images and caches into, removed when the test ends, so a test
//! run leaves nothing behind in the temporary directory; and where the project's scenes lie.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

/// Scratch directories made so far by this process (their names stay unique when tests run in
/// parallel threads).
static MADE: AtomicUsize = AtomicUsize::new(0);

/// A fresh, empty directory under the system's temporary directory, named after `name`, the
/// process and a count; removed with everything in it when dropped.
#[derive(Debug)]
pub struct ScratchDir(PathBuf);

impl ScratchDir {
    /// Makes the directory `ircache-NAME-PID-N`.
    ///
    /// # Panics
    /// If it cannot be made.
    #[must_use]
    pub fn new(name: &str) -> ScratchDir {
        let n = MADE.fetch_add(1, Ordering::Relaxed);
        let dir = std::env::temp_dir().join(format!("ircache-{name}-{}-{n}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir)
            .unwrap_or_else(|e| panic!("scratch directory {}: {e}", dir.display()));
        ScratchDir(dir)
    }

    /// The directory.
    #[must_use]
    pub fn path(&self) -> &Path {
        &self.0
    }
}

impl std::ops::Deref for ScratchDir {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

impl AsRef<Path> for ScratchDir {
    fn as_ref(&self) -> &Path {
        &self.0
    }
}

impl Drop for ScratchDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// The repository's own scenes folder (`scenes/`), where the tests find the project's scenes
/// and their reference files.
#[must_use]
pub fn project_scenes() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes")
}

#[cfg(test)]
mod tests {
    use super::ScratchDir;

    /// Two scratch directories of one name are two directories, and each is gone, with its
    /// files, once dropped.
    #[test]
    fn scratch_directories_are_distinct_and_removed() {
        let a = ScratchDir::new("testing");
        let b = ScratchDir::new("testing");
        assert_ne!(a.path(), b.path());
        std::fs::write(a.join("file.txt"), "x").unwrap();
        let (pa, pb) = (a.path().to_path_buf(), b.path().to_path_buf());
        assert!(pa.join("file.txt").exists());
        drop(a);
        drop(b);
        assert!(!pa.exists() && !pb.exists());
    }
}
