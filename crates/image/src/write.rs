//! Atomic file output: bytes go to a temporary file in the target's directory, which is then
//! renamed over the target, so a failed write leaves any existing file untouched.

use crate::ImageError;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

static COUNTER: AtomicU64 = AtomicU64::new(0);

/// The temporary file beside `path`: hidden, named after the target, this process and a counter.
fn temp_path(path: &Path) -> Result<PathBuf, ImageError> {
    let name = path
        .file_name()
        .ok_or_else(|| ImageError::write(path, "the path names no file"))?
        .to_string_lossy();
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let temp = format!(".{name}.{}.{n}.tmp", std::process::id());
    Ok(match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir.join(temp),
        _ => PathBuf::from(temp),
    })
}

/// Writes `bytes` to `path` atomically (temporary file in the same directory, then rename).
pub(crate) fn write_atomically(path: &Path, bytes: &[u8]) -> Result<(), ImageError> {
    let temp = temp_path(path)?;
    let result = (|| -> std::io::Result<()> {
        let mut f = std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&temp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        drop(f);
        std::fs::rename(&temp, path)
    })();
    result.map_err(|e| {
        // The temporary file may or may not exist; either way it must not be left behind.
        let _ = std::fs::remove_file(&temp);
        ImageError::write(path, e.to_string())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn temp_file_sits_beside_the_target() {
        let t = temp_path(Path::new("dir/sub/out.exr")).unwrap();
        assert_eq!(t.parent(), Some(Path::new("dir/sub")));
        assert!(t
            .file_name()
            .unwrap()
            .to_string_lossy()
            .starts_with(".out.exr."));
        let t = temp_path(Path::new("out.exr")).unwrap();
        assert_eq!(t.parent(), Some(Path::new("")));
        assert!(temp_path(Path::new("/")).is_err());
    }
}
