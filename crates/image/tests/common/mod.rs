//! Helpers shared by the integration tests: scratch directories and test images.

#![allow(dead_code)]

use ircache_image::Image;
use ircache_math::Rgb;
use std::path::{Path, PathBuf};

/// A fresh, empty scratch directory for one test, removed on drop.
pub struct Scratch(pub ircache_testing::ScratchDir);

impl Scratch {
    pub fn new(name: &str) -> Scratch {
        Scratch(ircache_testing::ScratchDir::new(&format!("image-{name}")))
    }
    pub fn path(&self, file: &str) -> PathBuf {
        self.0.join(file)
    }
    /// The names of the files in the directory, sorted.
    pub fn files(&self) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(&self.0)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }
}

/// A deterministic 32-bit hash (PCG output permutation of an LCG step).
pub fn hash(i: u64) -> u32 {
    let s = i
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    let x = (((s >> 18) ^ s) >> 27) as u32;
    x.rotate_right((s >> 59) as u32)
}

/// A uniform float in [0, 1) from a hash.
pub fn unit(i: u64) -> f32 {
    (hash(i) >> 8) as f32 / (1u32 << 24) as f32
}

/// An image of smooth gradients, flat areas (for RLE runs) and noise spanning many magnitudes.
pub fn test_image(width: usize, height: usize) -> Image {
    let mut img = Image::new(width, height);
    for y in 0..height {
        for x in 0..width {
            let i = (y * width + x) as u64;
            let c = match (x / 4 + y) % 3 {
                0 => Rgb::new(0.25, 0.5, 1.0), // flat
                1 => Rgb::new(x as f32 / width as f32, y as f32 / height as f32, 0.3),
                _ => {
                    let m = 2f32.powi((hash(i) % 40) as i32 - 20);
                    Rgb::new(unit(3 * i) * m, unit(3 * i + 1) * m, unit(3 * i + 2) * m)
                }
            };
            img.set(x, y, c);
        }
    }
    img
}

/// The shared folder beside the checkout (references/, tools/).
pub fn shared() -> PathBuf {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared");
    assert!(
        p.join("references").is_dir(),
        "the shared folder with references/ must sit beside the checkout: {}",
        p.display()
    );
    p
}

/// True when `err`'s message names `path`.
pub fn names(err: &ircache_image::ImageError, path: &Path) -> bool {
    err.to_string().contains(&path.display().to_string())
}

/// The deterministic perturbation of a reference used to check [`ircache_image::compare`] against
/// relmse.py: every channel scaled by a factor in [0.8, 1.2] plus an offset in [0, 0.01], and
/// every 997th pixel made a bright outlier (×8 + 1) so that the trim has something to drop.
pub fn perturb(b: &Image) -> Image {
    let mut a = b.clone();
    for (i, p) in a.pixels.iter_mut().enumerate() {
        let mut c = p.to_array();
        for (k, v) in c.iter_mut().enumerate() {
            let h = hash((3 * i + k) as u64);
            let factor = 1.0 + ((h % 2001) as f32 - 1000.0) / 5000.0;
            let offset = ((h >> 12) % 101) as f32 * 1e-4;
            *v = *v * factor + offset;
            if i % 997 == 0 {
                *v = *v * 8.0 + 1.0;
            }
        }
        *p = Rgb::from_array(c);
    }
    a
}
