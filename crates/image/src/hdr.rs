//! Radiance RGBE pictures (`.hdr`, `.pic`), written and read by hand to match Radiance's own
//! `color.c` and `header.c` exactly.
//!
//! Output: the header `#?RADIANCE`, `SOFTWARE=ircache`, `FORMAT=32-bit_rle_rgbe`, a blank line, the
//! standard resolution string `-Y height +X width`, then one scanline per row, top row first, in
//! new-style run-length encoding (Radiance's `fwritecolrs`, byte for byte: components separately,
//! runs of at least 4, literal chunks of at most 128); widths outside 8..=32767 are written flat as
//! Radiance does. Pixels are converted as by `setcolr` (common exponent, truncated mantissas).
//!
//! Input: any `#?` signature; `FORMAT=` must be `32-bit_rle_rgbe` when present; every `EXPOSURE=`
//! line multiplies the exposure, which is divided out so values come back as the radiance the
//! renderer computed (as `pvalue -o` reports). All eight resolution-string orientations are accepted.
//! Each scanline may be new-style RLE, or old-style (flat RGBE, with `(1, 1, 1, n)` repeat counts);
//! mantissas decode as Radiance's `colr_color`: `(m + 0.5) · 2^(e − 136)`.

use crate::{read_bytes, write::write_atomically, Image, ImageError, MAX_PIXELS};
use ircache_math::Rgb;
use std::path::Path;

/// Shortest scanline that Radiance run-length encodes.
const MIN_ELEN: usize = 8;
/// Longest scanline that Radiance run-length encodes.
const MAX_ELEN: usize = 0x7fff;
/// Shortest run that is written as a run.
const MIN_RUN: usize = 4;
/// Exponent excess.
const COLXS: i32 = 128;

/// `frexp` for a finite positive normal `f64`: the exponent `e` with `d = m · 2^e`, `m ∈ [0.5, 1)`.
fn frexp_exponent(d: f64) -> i32 {
    // Biased exponent field; for a normal number d = 1.f · 2^(E − 1023) = 0.1f · 2^(E − 1022).
    ((d.to_bits() >> 52) & 0x7ff) as i32 - 1022
}

/// One linear RGB colour as RGBE, as Radiance's `setcolr` (NaN and negative channels become 0;
/// values beyond the largest RGBE value saturate).
#[must_use]
pub fn to_rgbe(c: Rgb) -> [u8; 4] {
    let clean = |v: f32| if v > 0.0 { f64::from(v) } else { 0.0 };
    let (r, g, b) = (clean(c.r), clean(c.g), clean(c.b));
    let d = r.max(g).max(b);
    if d <= 1e-32 {
        return [0; 4];
    }
    // The largest exponent byte is 255, i.e. e = 127.
    let e = if d.is_finite() {
        frexp_exponent(d).min(127)
    } else {
        127
    };
    let scale = 2f64.powi(8 - e);
    // Radiance truncates; the saturating cast and the clamp cover rounding and saturation.
    let m = |v: f64| (v * scale).min(255.0) as u8;
    [m(r), m(g), m(b), (e + COLXS) as u8]
}

/// RGBE back to linear RGB, as Radiance's `colr_color`.
#[must_use]
pub fn from_rgbe(p: [u8; 4]) -> [f64; 3] {
    if p[3] == 0 {
        return [0.0; 3];
    }
    let f = 2f64.powi(i32::from(p[3]) - (COLXS + 8));
    [
        (f64::from(p[0]) + 0.5) * f,
        (f64::from(p[1]) + 0.5) * f,
        (f64::from(p[2]) + 0.5) * f,
    ]
}

/// Appends one component of a scanline, run-length encoded as Radiance's `fwritecolrs`.
fn encode_component(out: &mut Vec<u8>, v: &[u8]) {
    let len = v.len();
    let mut j = 0;
    let mut cnt = 1;
    while j < len {
        // Find the next run of at least MIN_RUN equal values.
        let mut beg = j;
        while beg < len {
            cnt = 1;
            while cnt < 127 && beg + cnt < len && v[beg + cnt] == v[beg] {
                cnt += 1;
            }
            if cnt >= MIN_RUN {
                break;
            }
            beg += cnt;
        }
        // A short run (2 or 3 equal values) right before the long one is written as a run too.
        if beg - j > 1 && beg - j < MIN_RUN {
            let mut c2 = j + 1;
            loop {
                let same = v[c2] == v[j];
                c2 += 1;
                if !same {
                    break;
                }
                if c2 == beg {
                    out.push((128 + beg - j) as u8);
                    out.push(v[j]);
                    j = beg;
                    break;
                }
            }
        }
        // Literal values up to the run, in chunks of at most 128.
        while j < beg {
            let n = (beg - j).min(128);
            out.push(n as u8);
            out.extend_from_slice(&v[j..j + n]);
            j += n;
        }
        if cnt >= MIN_RUN {
            out.push((128 + cnt) as u8);
            out.push(v[beg]);
        } else {
            cnt = 0;
        }
        j += cnt;
    }
}

/// Appends one scanline of RGBE pixels as Radiance's `fwritecolrs`: new-style RLE, or flat
/// outside Radiance's length limits (8..=32767).
pub fn encode_scanline(out: &mut Vec<u8>, line: &[[u8; 4]]) {
    let len = line.len();
    if !(MIN_ELEN..=MAX_ELEN).contains(&len) {
        for p in line {
            out.extend_from_slice(p);
        }
        return;
    }
    out.extend_from_slice(&[2, 2, (len >> 8) as u8, (len & 0xff) as u8]);
    let mut component = vec![0u8; len];
    for i in 0..4 {
        for (c, p) in component.iter_mut().zip(line) {
            *c = p[i];
        }
        encode_component(out, &component);
    }
}

/// The header and resolution string of a standard (`-Y h +X w`) picture.
fn header(width: usize, height: usize) -> Vec<u8> {
    format!("#?RADIANCE\nSOFTWARE=ircache\nFORMAT=32-bit_rle_rgbe\n\n-Y {height} +X {width}\n")
        .into_bytes()
}

/// Encodes `image` as a Radiance picture in memory (new-style RLE scanlines).
pub fn encode(image: &Image) -> Result<Vec<u8>, String> {
    encode_with(image, encode_scanline)
}

/// Encodes `image` as a Radiance picture with flat (uncompressed) RGBE scanlines, as very old
/// Radiance versions wrote them; every Radiance reader accepts both.
pub fn encode_flat(image: &Image) -> Result<Vec<u8>, String> {
    encode_with(image, |out, line| {
        for p in line {
            out.extend_from_slice(p);
        }
    })
}

fn encode_with(
    image: &Image,
    scanline: impl Fn(&mut Vec<u8>, &[[u8; 4]]),
) -> Result<Vec<u8>, String> {
    if image.width == 0 || image.height == 0 || image.width * image.height != image.pixels.len() {
        return Err(format!(
            "cannot encode a {}×{} image with {} pixels",
            image.width,
            image.height,
            image.pixels.len()
        ));
    }
    let mut out = header(image.width, image.height);
    out.reserve(image.pixels.len() * 4);
    let mut line = vec![[0u8; 4]; image.width];
    for row in image.pixels.chunks_exact(image.width) {
        for (l, &c) in line.iter_mut().zip(row) {
            *l = to_rgbe(c);
        }
        scanline(&mut out, &line);
    }
    Ok(out)
}

/// A cursor over the file's bytes with truncation errors.
struct Bytes<'a> {
    data: &'a [u8],
    pos: usize,
}

impl Bytes<'_> {
    fn byte(&mut self) -> Result<u8, String> {
        let b = *self.data.get(self.pos).ok_or("truncated pixel data")?;
        self.pos += 1;
        Ok(b)
    }
    fn pixel(&mut self) -> Result<[u8; 4], String> {
        let p = self
            .data
            .get(self.pos..self.pos + 4)
            .ok_or("truncated pixel data")?;
        self.pos += 4;
        Ok([p[0], p[1], p[2], p[3]])
    }
    /// The next line without its `\n`; an error if no `\n` follows.
    fn line(&mut self, what: &str) -> Result<&[u8], String> {
        let rest = &self.data[self.pos..];
        let n = rest
            .iter()
            .position(|&b| b == b'\n')
            .ok_or_else(|| format!("truncated {what}"))?;
        self.pos += n + 1;
        Ok(&rest[..n])
    }
}

/// Reads one scanline of `len` RGBE pixels onto the end of `out`, as Radiance's `freadcolrs`.
/// Memory grows only with data actually read (new-style scanlines are at most 32767 pixels).
fn decode_scanline(input: &mut Bytes, len: usize, out: &mut Vec<[u8; 4]>) -> Result<(), String> {
    if len == 0 {
        return Ok(());
    }
    let first = input.pixel()?;
    if first[0] != 2 || first[1] != 2 || first[2] & 0x80 != 0 {
        // Old style: real pixels, or (1, 1, 1, n) repeating the previous one, counts little-endian.
        out.push(first);
        let mut left = len - 1;
        let mut shift = 0u32;
        while left > 0 {
            let p = input.pixel()?;
            if p[0] == 1 && p[1] == 1 && p[2] == 1 {
                let count = if shift >= usize::BITS {
                    usize::MAX
                } else {
                    usize::from(p[3]) << shift
                };
                let n = count.min(left);
                let prev = out[out.len() - 1];
                out.resize(out.len() + n, prev);
                left -= n;
                shift += 8;
            } else {
                out.push(p);
                left -= 1;
                shift = 0;
            }
        }
        return Ok(());
    }
    let stated = usize::from(first[2]) << 8 | usize::from(first[3]);
    if stated != len {
        return Err(format!(
            "scanline length {stated} does not match the width {len}"
        ));
    }
    let start = out.len();
    out.resize(start + len, [0; 4]);
    let line = &mut out[start..];
    for i in 0..4 {
        let mut j = 0;
        while j < len {
            let code = usize::from(input.byte()?);
            if code > 128 {
                let n = code & 127;
                let v = input.byte()?;
                if j + n > len {
                    return Err("run-length data overruns the scanline".into());
                }
                for p in &mut line[j..j + n] {
                    p[i] = v;
                }
                j += n;
            } else {
                if j + code > len {
                    return Err("run-length data overruns the scanline".into());
                }
                for p in &mut line[j..j + code] {
                    p[i] = input.byte()?;
                }
                j += code;
            }
        }
    }
    Ok(())
}

/// One axis of a resolution string: `+X`, `-Y`, ...
#[derive(Clone, Copy)]
struct Axis {
    is_y: bool,
    plus: bool,
    size: usize,
}

fn parse_resolution(line: &[u8]) -> Result<(Axis, Axis), String> {
    let text = std::str::from_utf8(line).map_err(|_| "unreadable resolution string")?;
    let bad = || format!("bad resolution string {:?}", text.trim());
    let t: Vec<&str> = text.split_ascii_whitespace().collect();
    if t.len() != 4 {
        return Err(bad());
    }
    let axis = |s: &str, n: &str| -> Result<Axis, String> {
        let (plus, is_y) = match s {
            "+X" => (true, false),
            "-X" => (false, false),
            "+Y" => (true, true),
            "-Y" => (false, true),
            _ => return Err(bad()),
        };
        let size = n.parse::<usize>().map_err(|_| bad())?;
        Ok(Axis { is_y, plus, size })
    };
    let (major, minor) = (axis(t[0], t[1])?, axis(t[2], t[3])?);
    if major.is_y == minor.is_y {
        return Err(bad());
    }
    Ok((major, minor))
}

/// Decodes a Radiance picture held in memory, dividing out its `EXPOSURE`.
pub fn decode(bytes: &[u8]) -> Result<Image, String> {
    if !bytes.starts_with(b"#?") {
        return Err("not a Radiance picture (no #? signature)".into());
    }
    let mut input = Bytes {
        data: bytes,
        pos: 0,
    };
    let mut exposure = 1.0f64;
    loop {
        let line = input.line("header")?;
        if line.is_empty() {
            break;
        }
        let text = String::from_utf8_lossy(line);
        if let Some(f) = text.strip_prefix("FORMAT=") {
            let f = f.trim();
            if f != "32-bit_rle_rgbe" {
                return Err(format!(
                    "unsupported pixel format {f} (only 32-bit_rle_rgbe is read)"
                ));
            }
        } else if let Some(e) = text.strip_prefix("EXPOSURE=") {
            let e: f64 = e
                .trim()
                .parse()
                .map_err(|_| format!("bad header line {:?}", text))?;
            if !(e.is_finite() && e > 0.0) {
                return Err(format!("bad exposure {e}"));
            }
            exposure *= e;
        }
    }
    let (major, minor) = parse_resolution(input.line("resolution string")?)?;
    let (width, height) = if major.is_y {
        (minor.size, major.size)
    } else {
        (major.size, minor.size)
    };
    if !matches!(width.checked_mul(height), Some(n) if n <= MAX_PIXELS) {
        return Err(format!(
            "size {width}×{height} exceeds the limit of {MAX_PIXELS} pixels"
        ));
    }
    // Grow the image as scanlines decode, so a header promising more than the file holds fails
    // on truncation before allocating it all.
    let mut colrs: Vec<[u8; 4]> = Vec::new();
    for _ in 0..major.size {
        decode_scanline(&mut input, minor.size, &mut colrs)?;
    }
    let mut image = Image {
        width,
        height,
        pixels: vec![Rgb::ZERO; width * height],
    };
    let inv = 1.0 / exposure;
    for (s, scan) in colrs.chunks_exact(minor.size.max(1)).enumerate() {
        let s = if major.plus == major.is_y {
            major.size - 1 - s
        } else {
            s
        };
        for (j, &p) in scan.iter().enumerate() {
            let j = if minor.plus == minor.is_y {
                minor.size - 1 - j
            } else {
                j
            };
            // Radiance's +Y runs bottom to top and -Y top to bottom; +X left to right.
            let (x, y) = if major.is_y { (j, s) } else { (s, j) };
            let [r, g, b] = from_rgbe(p);
            image.pixels[y * width + x] =
                Rgb::new((r * inv) as f32, (g * inv) as f32, (b * inv) as f32);
        }
    }
    Ok(image)
}

/// Writes `image` as a Radiance RGBE picture with RLE scanlines (atomically).
pub fn write_hdr(path: &Path, image: &Image) -> Result<(), ImageError> {
    crate::check_writable(path, image)?;
    let bytes = encode(image).map_err(|m| ImageError::write(path, m))?;
    write_atomically(path, &bytes)
}

/// Reads a Radiance RGBE picture (RLE or flat scanlines) as linear RGB, `EXPOSURE` divided out.
pub fn read_hdr(path: &Path) -> Result<Image, ImageError> {
    let bytes = read_bytes(path)?;
    decode(&bytes).map_err(|m| ImageError::read(path, m))
}
