//! Mitsuba's binary `.vol` grid format (`gridvolume`): bytes `VOL`, version 3, encoding 1
//! (float32), int32 resolution x, y, z, int32 channel count, six float32 bounds (xmin ymin zmin
//! xmax ymax zmax), then float32 samples indexed `((z·ny + y)·nx + x)·channels + c`, all little
//! endian.

use std::path::Path;

/// A grid read from a `.vol` file.
#[derive(Clone, Debug)]
pub struct VolFile {
    /// Samples along x, y, z.
    pub resolution: [usize; 3],
    /// Channels per sample.
    pub channels: usize,
    /// The file's bounding box (min, max).
    pub bounds: ([f32; 3], [f32; 3]),
    /// Samples.
    pub data: Vec<f32>,
}

/// Reads a `.vol` file; the error says what was wrong in words (the caller adds the file and the
/// place that referenced it).
pub fn read_vol(path: &Path) -> Result<VolFile, String> {
    let bytes = std::fs::read(path).map_err(|e| e.to_string())?;
    parse_vol(&bytes)
}

/// Parses the bytes of a `.vol` file.
pub fn parse_vol(bytes: &[u8]) -> Result<VolFile, String> {
    if bytes.len() < 48 || &bytes[0..3] != b"VOL" {
        return Err(
            "not a Mitsuba .vol file (expected the bytes \"VOL\" and a 48-byte header)".into(),
        );
    }
    if bytes[3] != 3 {
        return Err(format!(
            "unsupported .vol version {} (expected 3)",
            bytes[3]
        ));
    }
    let int = |i: usize| i32::from_le_bytes(bytes[i..i + 4].try_into().unwrap_or_default());
    let float = |i: usize| f32::from_le_bytes(bytes[i..i + 4].try_into().unwrap_or_default());
    let encoding = int(4);
    if encoding != 1 {
        return Err(format!(
            "unsupported .vol encoding {encoding} (only 1, float32, is supported)"
        ));
    }
    let (nx, ny, nz, channels) = (int(8), int(12), int(16), int(20));
    if nx <= 0 || ny <= 0 || nz <= 0 {
        return Err(format!("invalid resolution {nx}×{ny}×{nz}"));
    }
    if channels != 1 && channels != 3 {
        return Err(format!(
            "{channels} channels per sample: only 1 (scalar) and 3 (RGB) are supported"
        ));
    }
    let min = [float(24), float(28), float(32)];
    let max = [float(36), float(40), float(44)];
    let count = (nx as usize)
        .checked_mul(ny as usize)
        .and_then(|n| n.checked_mul(nz as usize))
        .and_then(|n| n.checked_mul(channels as usize))
        .ok_or("the resolution overflows")?;
    let expected = 48 + count * 4;
    if bytes.len() != expected {
        return Err(format!(
            "the header says {nx}×{ny}×{nz}×{channels} samples ({expected} bytes), the file has {} bytes",
            bytes.len()
        ));
    }
    let data: Vec<f32> = bytes[48..]
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    if let Some(i) = data.iter().position(|v| !v.is_finite()) {
        return Err(format!("sample {i} is not finite ({})", data[i]));
    }
    Ok(VolFile {
        resolution: [nx as usize, ny as usize, nz as usize],
        channels: channels as usize,
        bounds: (min, max),
        data,
    })
}

/// The bytes of a `.vol` file (for tests and tools that write grids).
#[must_use]
pub fn write_vol(grid: &VolFile) -> Vec<u8> {
    let mut out = b"VOL\x03".to_vec();
    out.extend(1i32.to_le_bytes());
    for r in grid.resolution {
        out.extend((r as i32).to_le_bytes());
    }
    out.extend((grid.channels as i32).to_le_bytes());
    for v in grid.bounds.0.iter().chain(&grid.bounds.1).chain(&grid.data) {
        out.extend(v.to_le_bytes());
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_errors() {
        let grid = VolFile {
            resolution: [2, 3, 1],
            channels: 1,
            bounds: ([0.0; 3], [1.0, 2.0, 3.0]),
            data: (0..6).map(|i| i as f32 * 0.5).collect(),
        };
        let bytes = write_vol(&grid);
        let back = parse_vol(&bytes).unwrap();
        assert_eq!(back.resolution, [2, 3, 1]);
        assert_eq!(back.bounds.1, [1.0, 2.0, 3.0]);
        assert_eq!(back.data, grid.data);
        assert!(parse_vol(&bytes[..bytes.len() - 4])
            .unwrap_err()
            .contains("bytes"));
        let mut bad = bytes.clone();
        bad[20] = 6;
        assert!(parse_vol(&bad).unwrap_err().contains("channels"));
        assert!(parse_vol(b"PLY").unwrap_err().contains("VOL"));
    }
}
