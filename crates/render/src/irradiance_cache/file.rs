//! The persistent cache file (`--cache FILE`, Radiance's `-af`): a versioned binary format whose
//! header records the scene's content hash and every parameter that changes record values, then
//! records appended in batches, each with its own checksum, so that a file cut short by a crash
//! opens with every record that was written completely (003 item 7's file, without its races).
//!
//! Layout (little-endian):
//! - header, 1024 bytes: magic `IRCACHE\0`, format version (u32), 0 (u32), scene hash (u64),
//!   view hash (u64), length (u32) and text of the record-shaping settings as `name=value` lines
//!   (from the parameter table, [`super::params::PARAMS`]), zeros, header checksum (u64: FNV-1a
//!   of the bytes before it);
//! - records, 128 bytes each: level (u8), whether radiance follows (u8), 2 bytes zero, position,
//!   normal, irradiance (f32 × 9), radius (f32), translational then rotational gradient
//!   (f32 × 18), variance per ray (f32), checksum (u64: FNV-1a of the 120 bytes before it);
//! - after a record on a radiance-cached surface, its radiance in continuation slots of 128 bytes:
//!   0xFE, 1 byte zero, the slot's number (u16), 29 f32 (the first slot's first two: the order
//!   and the count of values; then coefficients, x and y gradients, 3 × order² each), checksum.
//!   A record whose continuation is incomplete or damaged is skipped with it.
//! - in scenes with media, volumetric records (`media_cache::volume_records`): a slot tagged
//!   0xFD, 1 byte zero, 2 bytes zero, with position, radius, medium index and the first 24 of
//!   the 27 spherical-harmonic values (9 coefficients × 3 channels), then three continuation
//!   slots (numbers 0 to 2) with the last 3, the direction of the camera ray that placed the
//!   record, the light bands above 2 scatter towards it (3 + 3; format 5) and the 27 values of
//!   the light one bounce shorter (format 6), then 27 of it two bounces shorter (format 7). The media cache's surface records are ordinary
//!   records.

use super::params::{IcParams, PARAMS};
use super::record::{Record, NO_RADIANCE};
use crate::media_cache::volume_records::{VolumeRecord, COEFFICIENTS};
use crate::radiance_cache::gather::RadianceCoefficients;
use ircache_math::{Rgb, Vec3};
use std::fs::{File, OpenOptions};
use std::io::{Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};

/// Bytes that open every cache file.
pub const MAGIC: &[u8; 8] = b"IRCACHE\0";
/// The format version this build reads and writes.
pub const VERSION: u32 = 7;
/// Header size in bytes.
pub const HEADER_BYTES: usize = 1024;
/// Record size in bytes (payload and checksum).
pub const RECORD_BYTES: usize = 128;
const PAYLOAD_BYTES: usize = RECORD_BYTES - 8;
/// First byte of a radiance continuation slot (levels are far below).
const CONTINUATION: u8 = 0xFE;
/// First byte of a volumetric record's slot.
const VOLUME: u8 = 0xFD;
/// Values a slot holds (a record's or a continuation's), after its 4 bytes of tags.
const SLOT_FLOATS: usize = 29;

/// A record as a file holds it: on a radiance-cached surface with its coefficients (the
/// record's own [`Record::radiance`] index is [`NO_RADIANCE`] here; the cache assigns one).
pub type Stored = (Record, Option<RadianceCoefficients>);

/// Problems with a cache file.
#[derive(Debug, thiserror::Error)]
pub enum CacheFileError {
    /// Reading or writing failed.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// What the system said.
        source: std::io::Error,
    },
    /// Not a cache file, or a damaged header.
    #[error("{path}: {why}")]
    Invalid {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        why: String,
    },
    /// The file was made for another scene or with other settings.
    #[error("{path}: made {why}; delete it, use another file, or pass --cache-reuse force")]
    Stale {
        /// The file.
        path: PathBuf,
        /// What differs.
        why: String,
    },
}

/// FNV-1a, 64 bits: a stable checksum and content hash (the same on every machine and run).
#[derive(Clone, Copy, Debug)]
pub struct Fnv(pub u64);

impl Default for Fnv {
    fn default() -> Self {
        Fnv(0xcbf2_9ce4_8422_2325)
    }
}

impl Fnv {
    /// Feeds bytes.
    pub fn bytes(&mut self, b: &[u8]) {
        for &x in b {
            self.0 = (self.0 ^ u64::from(x)).wrapping_mul(0x0100_0000_01b3);
        }
    }
    /// Feeds 32-bit words (one multiply each: four times faster than their bytes, for texels).
    pub fn words(&mut self, w: impl Iterator<Item = u32>) {
        for x in w {
            self.0 = (self.0 ^ u64::from(x)).wrapping_mul(0x0100_0000_01b3);
        }
    }
    /// The hash of `b`.
    #[must_use]
    pub fn of(b: &[u8]) -> u64 {
        let mut h = Fnv::default();
        h.bytes(b);
        h.0
    }
}

impl std::fmt::Write for Fnv {
    fn write_str(&mut self, s: &str) -> std::fmt::Result {
        self.bytes(s.as_bytes());
        Ok(())
    }
}

/// What a header holds.
#[derive(Clone, Debug, PartialEq)]
pub struct Header {
    /// Format version.
    pub version: u32,
    /// Content hash of the scene (geometry, materials, emitters; not the camera).
    pub scene_hash: u64,
    /// Hash of the view (camera and film width) where records' radii depend on it (Tabellion's
    /// pixel-footprint limits); 0 where they do not.
    pub view_hash: u64,
    /// The settings the records were made with (those that shape records are stored).
    pub params: IcParams,
}

/// Offset of the header checksum (the header's last 8 bytes).
const HEADER_SUM_AT: usize = HEADER_BYTES - 8;
/// Offset of the settings text.
const HEADER_TEXT_AT: usize = 8 + 4 + 4 + 8 + 8 + 4;

impl Header {
    /// The settings that shape records, as `name=value` lines in table order.
    fn settings_text(params: &IcParams) -> String {
        PARAMS
            .iter()
            .filter(|s| s.shapes_records)
            .map(|s| format!("{}={}\n", s.name, (s.get)(params)))
            .collect()
    }

    fn encode(&self) -> [u8; HEADER_BYTES] {
        let mut out = [0u8; HEADER_BYTES];
        let text = Self::settings_text(&self.params);
        let mut b = Vec::with_capacity(HEADER_BYTES);
        b.extend_from_slice(MAGIC);
        b.extend_from_slice(&self.version.to_le_bytes());
        b.extend_from_slice(&0u32.to_le_bytes());
        b.extend_from_slice(&self.scene_hash.to_le_bytes());
        b.extend_from_slice(&self.view_hash.to_le_bytes());
        // The table's values are short: the text fits with room to spare (tested).
        let len = text.len().min(HEADER_SUM_AT - HEADER_TEXT_AT);
        b.extend_from_slice(&(len as u32).to_le_bytes());
        b.extend_from_slice(&text.as_bytes()[..len]);
        out[..b.len()].copy_from_slice(&b);
        let sum = Fnv::of(&out[..HEADER_SUM_AT]);
        out[HEADER_SUM_AT..].copy_from_slice(&sum.to_le_bytes());
        out
    }

    fn decode(b: &[u8; HEADER_BYTES], path: &Path) -> Result<Header, CacheFileError> {
        let invalid = |why: String| CacheFileError::Invalid {
            path: path.to_path_buf(),
            why,
        };
        if &b[..8] != MAGIC {
            return Err(invalid(
                "not an ircache cache file (bad magic bytes)".into(),
            ));
        }
        let u32_at = |i: usize| u32::from_le_bytes(b[i..i + 4].try_into().unwrap_or([0; 4]));
        let u64_at = |i: usize| u64::from_le_bytes(b[i..i + 8].try_into().unwrap_or([0; 8]));
        let version = u32_at(8);
        if version != VERSION {
            return Err(invalid(format!(
                "format version {version}; this ircache reads version {VERSION}"
            )));
        }
        if Fnv::of(&b[..HEADER_SUM_AT]) != u64_at(HEADER_SUM_AT) {
            return Err(invalid("damaged header (checksum mismatch)".into()));
        }
        let len = (u32_at(HEADER_TEXT_AT - 4) as usize).min(HEADER_SUM_AT - HEADER_TEXT_AT);
        let text = std::str::from_utf8(&b[HEADER_TEXT_AT..HEADER_TEXT_AT + len])
            .map_err(|_| invalid("damaged header (settings are not text)".into()))?;
        let mut params = IcParams::default();
        for line in text.lines() {
            let (name, value) = line
                .split_once('=')
                .ok_or_else(|| invalid(format!("damaged header: \"{line}\"")))?;
            params
                .set(name, value)
                .map_err(|e| invalid(format!("header setting {e}")))?;
        }
        Ok(Header {
            version,
            scene_hash: u64_at(16),
            view_hash: u64_at(24),
            params,
        })
    }

    /// Why records made under `self` cannot serve `other` (`None`: they can). Settings that do
    /// not shape records (the pre-pass's extent, light samples) do not matter, nor does the
    /// view: records serve any view (Radiance's workflow of one file for many views), though
    /// under Tabellion's metric they keep radii sized for the view they were made for, which
    /// [`Header::view_note`] says.
    #[must_use]
    pub fn mismatch(&self, other: &Header) -> Option<String> {
        if self.scene_hash != other.scene_hash {
            return Some(format!(
                "for another scene (content hash {:016x}, this scene {:016x})",
                self.scene_hash, other.scene_hash
            ));
        }
        let diffs: Vec<String> = PARAMS
            .iter()
            .filter(|s| s.shapes_records)
            .map(|s| (s.name, (s.get)(&self.params), (s.get)(&other.params)))
            .filter(|(_, x, y)| x != y)
            .map(|(n, x, y)| format!("{n} {x} (now {y})"))
            .collect();
        (!diffs.is_empty()).then(|| format!("with other settings: {}", diffs.join(", ")))
    }

    /// A note when the file's records were sized for another view than `other`'s.
    #[must_use]
    pub fn view_note(&self, other: &Header) -> Option<String> {
        (self.view_hash != other.view_hash).then(|| {
            "the cache file's records were made for another view (camera or film width): \
             their radii keep that view's pixel footprints"
                .to_string()
        })
    }
}

/// A slot with tag bytes `tags` and `values` (at most [`SLOT_FLOATS`], the rest zero), sealed
/// with the checksum of its payload in its last 8 bytes.
fn write_slot(tags: [u8; 4], values: &[f32]) -> [u8; RECORD_BYTES] {
    let mut b = [0u8; RECORD_BYTES];
    b[..4].copy_from_slice(&tags);
    for (i, f) in values.iter().enumerate() {
        b[4 + 4 * i..8 + 4 * i].copy_from_slice(&f.to_le_bytes());
    }
    let sum = Fnv::of(&b[..PAYLOAD_BYTES]);
    b[PAYLOAD_BYTES..].copy_from_slice(&sum.to_le_bytes());
    b
}

/// A slot's values; `None` when it is short, its checksum fails or a value is not finite.
fn read_slot(b: &[u8]) -> Option<[f32; SLOT_FLOATS]> {
    let sum = u64::from_le_bytes(b.get(PAYLOAD_BYTES..RECORD_BYTES)?.try_into().ok()?);
    if Fnv::of(&b[..PAYLOAD_BYTES]) != sum {
        return None;
    }
    let mut f = [0.0f32; SLOT_FLOATS];
    for (i, v) in f.iter_mut().enumerate() {
        *v = f32::from_le_bytes(b[4 + 4 * i..8 + 4 * i].try_into().ok()?);
    }
    f.iter().all(|v| v.is_finite()).then_some(f)
}

/// A record's slot and its radiance continuation slots.
fn encode_stored((r, radiance): &Stored) -> Vec<u8> {
    let mut out = encode_record(r, radiance.is_some()).to_vec();
    if let Some(c) = radiance {
        let mut values = vec![
            c.order as f32,
            (c.coefficients.len() + c.gradient_x.len() + c.gradient_y.len()) as f32,
        ];
        for v in c
            .coefficients
            .iter()
            .chain(&c.gradient_x)
            .chain(&c.gradient_y)
        {
            values.push(*v as f32);
        }
        for (k, chunk) in values.chunks(SLOT_FLOATS).enumerate() {
            let [lo, hi] = (k as u16).to_le_bytes();
            out.extend_from_slice(&write_slot([CONTINUATION, 0, lo, hi], chunk));
        }
    }
    out
}

/// The values of continuation slot number `k`, `None` when it is not one or is damaged.
fn decode_continuation(b: &[u8], k: usize) -> Option<[f32; SLOT_FLOATS]> {
    let tags = b.get(..4)?;
    if tags[0] != CONTINUATION || usize::from(u16::from_le_bytes([tags[2], tags[3]])) != k {
        return None;
    }
    read_slot(b)
}

/// The radiance in the continuation slots at the start of `slots`, and how many slots it took.
fn decode_radiance(slots: &[u8]) -> Option<(RadianceCoefficients, usize)> {
    let first = decode_continuation(slots.get(..RECORD_BYTES)?, 0)?;
    let (order, count) = (first[0] as usize, first[1] as usize);
    let n = 3 * order * order;
    if order == 0 || order > 32 || count != 3 * n {
        return None;
    }
    let total = count + 2;
    let blocks = total.div_ceil(SLOT_FLOATS);
    let mut values = Vec::with_capacity(blocks * SLOT_FLOATS);
    values.extend_from_slice(&first);
    for k in 1..blocks {
        let slot = slots.get(k * RECORD_BYTES..(k + 1) * RECORD_BYTES)?;
        values.extend_from_slice(&decode_continuation(slot, k)?);
    }
    let v: Vec<f64> = values[2..total].iter().map(|&x| f64::from(x)).collect();
    Some((
        RadianceCoefficients {
            order,
            coefficients: v[..n].to_vec(),
            gradient_x: v[n..2 * n].to_vec(),
            gradient_y: v[2 * n..].to_vec(),
        },
        blocks,
    ))
}

/// A volumetric record's [`VOLUME_SLOTS`] slots.
fn encode_volume(v: &VolumeRecord) -> Vec<u8> {
    let mut values = Vec::with_capacity(11 + 9 * COEFFICIENTS);
    values.extend_from_slice(&v.p.to_array());
    values.push(v.r);
    values.push(v.medium as f32);
    values.extend(v.radiance.iter().flat_map(|c| c.to_array()));
    values.extend_from_slice(&v.towards.to_array());
    values.extend_from_slice(&v.high_bands.to_array());
    values.extend(v.shorter.iter().flatten().flat_map(|c| c.to_array()));
    let mut out = write_slot([VOLUME, 0, 0, 0], &values[..SLOT_FLOATS]).to_vec();
    for (k, chunk) in values[SLOT_FLOATS..].chunks(SLOT_FLOATS).enumerate() {
        let [lo, hi] = (k as u16).to_le_bytes();
        out.extend_from_slice(&write_slot([CONTINUATION, 0, lo, hi], chunk));
    }
    out
}

/// Slots a volumetric record takes: its own and [`VOLUME_CONTINUATIONS`].
const VOLUME_SLOTS: usize = 1 + VOLUME_CONTINUATIONS;
/// Continuation slots after a volumetric record's: 11 + 9 · 9 values, 29 a slot.
const VOLUME_CONTINUATIONS: usize = 3;

/// A volumetric record from the start of `slots`; `None` when it is not one, is damaged or
/// lacks its continuation.
fn decode_volume(slots: &[u8]) -> Option<VolumeRecord> {
    if slots.first() != Some(&VOLUME) {
        return None;
    }
    let mut values = read_slot(slots.get(..RECORD_BYTES)?)?.to_vec();
    for k in 0..VOLUME_CONTINUATIONS {
        let slot = slots.get((k + 1) * RECORD_BYTES..(k + 2) * RECORD_BYTES)?;
        values.extend_from_slice(&decode_continuation(slot, k)?);
    }
    let medium = values[4];
    if medium < 0.0 || medium.fract() != 0.0 {
        return None;
    }
    let rgb = |at: usize| Rgb::new(values[at], values[at + 1], values[at + 2]);
    let end = 5 + 3 * COEFFICIENTS;
    Some(VolumeRecord {
        p: Vec3::new(values[0], values[1], values[2]),
        r: values[3],
        medium: medium as usize,
        radiance: std::array::from_fn(|i| rgb(5 + 3 * i)),
        towards: Vec3::from_slice(&values[end..end + 3]),
        high_bands: rgb(end + 3),
        shorter: std::array::from_fn(|k| {
            std::array::from_fn(|i| rgb(end + 6 + 3 * (k * COEFFICIENTS + i)))
        }),
    })
}

fn encode_record(r: &Record, with_radiance: bool) -> [u8; RECORD_BYTES] {
    let mut floats = Vec::with_capacity(SLOT_FLOATS);
    for v in [r.p, r.n] {
        floats.extend_from_slice(&v.to_array());
    }
    floats.extend_from_slice(&r.e.to_array());
    floats.push(r.r);
    for g in r.grad_t.iter().chain(&r.grad_r) {
        floats.extend_from_slice(&g.to_array());
    }
    floats.push(r.ray_variance);
    write_slot([r.level, u8::from(with_radiance), 0, 0], &floats)
}

/// A record from its bytes and whether radiance follows; `None` when the checksum fails, a
/// value is not finite, or the slot is a continuation.
fn decode_record(b: &[u8]) -> Option<(Record, bool)> {
    if matches!(b.first(), Some(&CONTINUATION | &VOLUME)) {
        return None;
    }
    let f = read_slot(b)?;
    let v = |i: usize| Vec3::new(f[i], f[i + 1], f[i + 2]);
    let record = Record {
        level: b[0],
        p: v(0),
        n: v(3),
        e: Rgb::new(f[6], f[7], f[8]),
        r: f[9],
        grad_t: [v(10), v(13), v(16)],
        grad_r: [v(19), v(22), v(25)],
        ray_variance: f[28],
        radiance: NO_RADIANCE,
    };
    Some((record, b[1] == 1))
}

/// What reading a file found.
#[derive(Clone, Debug)]
pub struct Contents {
    /// Its header.
    pub header: Header,
    /// Every complete, intact record, in file order (with its radiance where it has some).
    pub records: Vec<Stored>,
    /// Every complete, intact volumetric record, in file order.
    pub volume: Vec<VolumeRecord>,
    /// Damaged slots (records and their radiance continuations) between intact records
    /// (skipped).
    pub damaged: u64,
    /// Bytes after the last intact record (a torn tail or damage), ignored.
    pub torn_bytes: u64,
}

impl Contents {
    /// What a user should hear of the file at `path`, opened for `header`: records sized for
    /// another view ([`Header::view_note`]), damaged records skipped.
    #[must_use]
    pub fn notes(&self, path: &Path, header: &Header) -> Vec<String> {
        let mut notes: Vec<String> = self.header.view_note(header).into_iter().collect();
        if self.damaged > 0 {
            notes.push(format!(
                "{}: {} damaged records skipped",
                path.display(),
                self.damaged
            ));
        }
        notes
    }
}

/// Reads a cache file.
pub fn read(path: &Path) -> Result<Contents, CacheFileError> {
    let io = |source| CacheFileError::Io {
        path: path.to_path_buf(),
        source,
    };
    let mut bytes = Vec::new();
    File::open(path)
        .and_then(|mut f| f.read_to_end(&mut bytes))
        .map_err(io)?;
    if bytes.len() < HEADER_BYTES {
        return Err(CacheFileError::Invalid {
            path: path.to_path_buf(),
            why: format!(
                "{} bytes: too short for the {HEADER_BYTES}-byte header of a cache file",
                bytes.len()
            ),
        });
    }
    let header_bytes: [u8; HEADER_BYTES] =
        bytes[..HEADER_BYTES]
            .try_into()
            .map_err(|_| CacheFileError::Invalid {
                path: path.to_path_buf(),
                why: "short header".into(),
            })?;
    let header = Header::decode(&header_bytes, path)?;
    let scan = scan_records(&bytes[HEADER_BYTES..]);
    Ok(Contents {
        header,
        records: scan.records,
        volume: scan.volume,
        damaged: scan.damaged,
        torn_bytes: (bytes.len() - HEADER_BYTES - scan.end) as u64,
    })
}

/// The records in a run of record slots.
struct Scan {
    /// Every intact record, in order.
    records: Vec<Stored>,
    /// Every intact volumetric record, in order.
    volume: Vec<VolumeRecord>,
    /// Damaged slots followed by an intact one (skipped).
    damaged: u64,
    /// Bytes up to the end of the last intact record (what follows is a torn tail).
    end: usize,
}

/// Reads record slots: a damaged slot (checksum or value) is skipped, so one bad record in the
/// middle loses only itself; damage after the last intact record is the torn tail of a write
/// that did not finish.
fn scan_records(bytes: &[u8]) -> Scan {
    let mut scan = Scan {
        records: Vec::new(),
        volume: Vec::new(),
        damaged: 0,
        end: 0,
    };
    let mut bad_run = 0u64;
    let slots = bytes.len() / RECORD_BYTES;
    let mut i = 0;
    while i < slots {
        let slot = &bytes[i * RECORD_BYTES..(i + 1) * RECORD_BYTES];
        if let Some(v) = decode_volume(&bytes[i * RECORD_BYTES..slots * RECORD_BYTES]) {
            scan.volume.push(v);
            scan.damaged += bad_run;
            bad_run = 0;
            i += VOLUME_SLOTS;
            scan.end = i * RECORD_BYTES;
            continue;
        }
        let decoded = decode_record(slot).and_then(|(r, with_radiance)| {
            if with_radiance {
                let rest = &bytes[(i + 1) * RECORD_BYTES..slots * RECORD_BYTES];
                let (c, used) = decode_radiance(rest)?;
                Some(((r, Some(c)), 1 + used))
            } else {
                Some(((r, None), 1))
            }
        });
        match decoded {
            Some((stored, used)) => {
                scan.records.push(stored);
                scan.damaged += bad_run;
                bad_run = 0;
                i += used;
                scan.end = i * RECORD_BYTES;
            }
            None => {
                bad_run += 1;
                i += 1;
            }
        }
    }
    scan
}

/// A cache file shared with other processes: every access holds an advisory lock on the file
/// (shared to read, exclusive to write), and writes are whole batches, so readers never see half
/// a batch. Each process reads the records the others appended since it last looked.
#[derive(Debug)]
pub struct CacheFile {
    path: PathBuf,
    file: File,
    /// Offset just after the last record this process has read or written.
    read_pos: u64,
}

/// Holds a lock until dropped.
struct Locked<'a>(&'a File);

impl Drop for Locked<'_> {
    fn drop(&mut self) {
        let _ = self.0.unlock();
    }
}

impl CacheFile {
    fn io(&self) -> impl Fn(std::io::Error) -> CacheFileError + '_ {
        |source| CacheFileError::Io {
            path: self.path.clone(),
            source,
        }
    }

    /// Opens `path`, creating it with `header` if it does not exist or is empty. An existing
    /// file must have been made for the same scene and settings unless `force`; its torn tail
    /// (a crash in the middle of a write) is cut off. Returns the file and what it held.
    pub fn open(
        path: &Path,
        header: &Header,
        force: bool,
    ) -> Result<(CacheFile, Contents), CacheFileError> {
        let file = OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .open(path)
            .map_err(|source| CacheFileError::Io {
                path: path.to_path_buf(),
                source,
            })?;
        let mut this = CacheFile {
            path: path.to_path_buf(),
            file,
            read_pos: 0,
        };
        this.file.lock().map_err(this.io())?;
        let guard = Locked(&this.file);
        let len = this.file.metadata().map_err(this.io())?.len();
        let contents = if len == 0 {
            let mut f = &this.file;
            f.write_all(&header.encode()).map_err(this.io())?;
            f.sync_data().map_err(this.io())?;
            Contents {
                header: header.clone(),
                records: Vec::new(),
                volume: Vec::new(),
                damaged: 0,
                torn_bytes: 0,
            }
        } else {
            let contents = read(path)?;
            if let Some(why) = contents.header.mismatch(header) {
                if !force {
                    return Err(CacheFileError::Stale {
                        path: path.to_path_buf(),
                        why,
                    });
                }
            }
            contents
        };
        let end = len.max(HEADER_BYTES as u64) - contents.torn_bytes;
        if contents.torn_bytes > 0 {
            this.file.set_len(end).map_err(this.io())?;
        }
        drop(guard);
        this.read_pos = end;
        Ok((this, contents))
    }

    /// Intact records from `read_pos` to the end of the file (the caller holds a lock), and
    /// the offset after the last of them.
    fn read_tail(&self) -> Result<(Vec<Stored>, u64, u64), CacheFileError> {
        let mut f = &self.file;
        let len = f.metadata().map_err(self.io())?.len();
        let mut bytes = Vec::new();
        if len > self.read_pos {
            f.seek(SeekFrom::Start(self.read_pos)).map_err(self.io())?;
            f.take(len - self.read_pos)
                .read_to_end(&mut bytes)
                .map_err(self.io())?;
        }
        let scan = scan_records(&bytes);
        let end = self.read_pos + scan.end as u64;
        Ok((scan.records, end, len))
    }

    /// Records other processes appended since this one last looked.
    pub fn read_new(&mut self) -> Result<Vec<Stored>, CacheFileError> {
        self.file.lock_shared().map_err(self.io())?;
        let guard = Locked(&self.file);
        let (records, end, _) = self.read_tail()?;
        drop(guard);
        self.read_pos = end;
        Ok(records)
    }

    /// Appends `records` (flushed to the disk before the lock is released) and returns the
    /// records others appended since this process last looked, which come before them.
    pub fn append(&mut self, records: &[Stored]) -> Result<Vec<Stored>, CacheFileError> {
        let buf: Vec<u8> = records.iter().flat_map(encode_stored).collect();
        self.append_bytes(&buf)
    }

    /// Appends volumetric records, as [`Self::append`]; what others appended since is not read
    /// back (a media scene's pre-passes read the file once, before they start).
    pub fn append_volume(&mut self, records: &[VolumeRecord]) -> Result<(), CacheFileError> {
        let buf: Vec<u8> = records.iter().flat_map(encode_volume).collect();
        self.append_bytes(&buf).map(|_| ())
    }

    fn append_bytes(&mut self, buf: &[u8]) -> Result<Vec<Stored>, CacheFileError> {
        self.file.lock().map_err(self.io())?;
        let guard = Locked(&self.file);
        let (others, end, len) = self.read_tail()?;
        if len > end {
            // What follows the last intact record is the remnant of a crashed write.
            self.file.set_len(end).map_err(self.io())?;
        }
        let mut f = &self.file;
        f.seek(SeekFrom::Start(end)).map_err(self.io())?;
        f.write_all(buf)
            .and_then(|()| f.sync_data())
            .map_err(self.io())?;
        drop(guard);
        self.read_pos = end + buf.len() as u64;
        Ok(others)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record(i: usize) -> Record {
        let f = i as f32;
        Record {
            p: Vec3::new(f, 2.0 * f, -f),
            n: Vec3::Z,
            e: Rgb::new(f, 0.5, 0.25),
            r: 1.0 + f,
            grad_t: [Vec3::X * f, Vec3::Y, Vec3::Z],
            grad_r: [Vec3::ONE, Vec3::X, Vec3::Y * f],
            level: (i % 3) as u8,
            ray_variance: 0.5 * f,
            radiance: crate::irradiance_cache::record::NO_RADIANCE,
        }
    }

    /// Record i, with radiance coefficients (values exact in `f32`) for every third.
    fn stored(i: usize) -> Stored {
        let radiance = (i % 3 == 1).then(|| {
            let n = 3 * 4;
            let v = |k: usize| {
                (0..n)
                    .map(|j| (i * 100 + k * 20 + j) as f64 * 0.25)
                    .collect()
            };
            RadianceCoefficients {
                order: 2,
                coefficients: v(0),
                gradient_x: v(1),
                gradient_y: v(2),
            }
        });
        (record(i), radiance)
    }

    fn header() -> Header {
        Header {
            version: VERSION,
            scene_hash: 0x1234_5678_9abc_def0,
            params: IcParams {
                bounces: 3,
                supersamples: 64,
                ambient_value: Rgb::new(0.1, 0.2, 0.3),
                ..IcParams::default()
            },
            view_hash: 0,
        }
    }

    /// A cache file's path in a scratch directory that goes when the first of the pair drops.
    fn temp(name: &str) -> (ircache_testing::ScratchDir, PathBuf) {
        let dir = ircache_testing::ScratchDir::new(&format!("file-{name}"));
        let path = dir.join("cache");
        (dir, path)
    }

    #[test]
    fn round_trip_of_header_and_records() {
        let (_path_dir, path) = temp("round-trip");
        let _ = std::fs::remove_file(&path);
        let (mut f, c) = CacheFile::open(&path, &header(), false).unwrap();
        assert!(c.records.is_empty());
        let recs: Vec<Stored> = (0..10).map(stored).collect();
        assert!(f.append(&recs[..4]).unwrap().is_empty());
        // A second writer on the same file sees the first one's records and adds its own.
        let (mut g, c) = CacheFile::open(&path, &header(), false).unwrap();
        assert_eq!(c.records, recs[..4]);
        assert!(g.append(&recs[4..7]).unwrap().is_empty());
        assert_eq!(f.read_new().unwrap(), recs[4..7]);
        assert!(f.append(&recs[7..]).unwrap().is_empty());
        assert_eq!(g.read_new().unwrap(), recs[7..]);
        drop((f, g));
        let mut other = header();
        other.params.accuracy = 0.5;
        let e = CacheFile::open(&path, &other, false)
            .unwrap_err()
            .to_string();
        assert!(e.contains("accuracy 0.3 (now 0.5)"), "{e}");
        assert!(CacheFile::open(&path, &other, true).is_ok());
        let c = read(&path).unwrap();
        assert_eq!(c.header, header());
        assert_eq!(c.records, recs);
        assert_eq!(c.torn_bytes, 0);
        assert!(c.header.mismatch(&header()).is_none());
        let mut other = header();
        other.params.divisions = 256;
        let why = c.header.mismatch(&other).unwrap();
        assert!(why.contains("divisions 1024 (now 256)"), "{why}");
        other.scene_hash ^= 1;
        assert!(c.header.mismatch(&other).unwrap().contains("another scene"));
        // Every record-shaping setting of the table survives the header and, when changed, is
        // named as the reason a file is refused: set each to a value other than the default.
        let changed: &[(&str, &str)] = &[
            ("accuracy", "0.25"),
            ("divisions", "300"),
            ("supersamples", "100"),
            ("record_error", "0.5"),
            ("regather_at", "16"),
            ("resolution", "64"),
            ("footprint_limits", "1,8"),
            ("bounces", "5"),
            ("deeper_bounces", "cache"),
            ("ambient_value", "1,2,3"),
            ("ambient_weight", "7"),
            ("error_metric", "hessian"),
            ("neighbour_clamp", "on"),
            ("gradients", "rotation"),
            ("gradient_formula", "krivanek"),
            ("gather_pattern", "jittered"),
            ("record_source", "plane"),
            ("radiance_cache", "on"),
            ("cached_environment", "all"),
            ("radiance_order", "5"),
            ("radiance_accuracy", "0.2"),
            ("photons", "1000"),
            ("caustic_photons", "1000"),
            ("photon_lookup", "50"),
            ("photon_radius", "0.1"),
            ("photon_records", "on"),
            ("media_gradient", "corrected"),
            ("media_light_samples", "3"),
            ("media_volume_divisions", "64"),
            ("media_deeper_paths", "2"),
            ("media_divisions", "256"),
        ];
        for spec in crate::irradiance_cache::params::PARAMS {
            let listed = changed.iter().find(|(n, _)| *n == spec.name);
            assert_eq!(listed.is_some(), spec.shapes_records, "{}", spec.name);
            let Some((name, value)) = listed else {
                continue;
            };
            let mut h = header();
            h.params.set(name, value).unwrap();
            assert_ne!(h.params, header().params, "{name}");
            let bytes = h.encode();
            assert_eq!(Header::decode(&bytes, &path).unwrap(), h, "{name}");
            let why = header().mismatch(&h).expect(name);
            assert!(why.contains(name), "{why}");
        }
        // Another view is no reason to refuse the file, but it is said.
        let mut h = header();
        h.view_hash = 5;
        assert!(header().mismatch(&h).is_none());
        assert!(header().view_note(&h).unwrap().contains("another view"));
        assert!(header().view_note(&header()).is_none());
        let _ = std::fs::remove_file(path);
    }

    /// Radiance continuation slots: a damaged one loses its record alone; a torn one at the end
    /// loses the last record and is cut off by the next write.
    #[test]
    fn radiance_continuations_are_checked_with_their_record() {
        let (_path_dir, path) = temp("radiance");
        let _ = std::fs::remove_file(&path);
        let recs: Vec<Stored> = (0..6).map(stored).collect();
        let (mut f, _) = CacheFile::open(&path, &header(), false).unwrap();
        f.append(&recs).unwrap();
        drop(f);
        let full = std::fs::read(&path).unwrap();
        assert_eq!(read(&path).unwrap().records, recs);
        // Record 1 has radiance: 36 values + 2 in two continuation slots, after its own slot.
        let continuation = HEADER_BYTES + 2 * RECORD_BYTES;
        let mut bad = full.clone();
        bad[continuation + 40] ^= 2;
        let (_cut_dir, cut) = temp("radiance-cut");
        std::fs::write(&cut, &bad).unwrap();
        let c = read(&cut).unwrap();
        let mut expect = recs.clone();
        expect.remove(1);
        // The record's slot and its two continuation slots count as damaged slots.
        assert_eq!((c.records, c.damaged), (expect, 3));
        // Record 4 is the last with radiance: cut inside its continuation.
        let last = full.len() - RECORD_BYTES;
        std::fs::write(&cut, &full[..last - 10]).unwrap();
        let c = read(&cut).unwrap();
        assert_eq!(c.records, recs[..4]);
        let (mut f, _) = CacheFile::open(&cut, &header(), false).unwrap();
        f.append(&[stored(7)]).unwrap();
        drop(f);
        let mut expect = recs[..4].to_vec();
        expect.push(stored(7));
        assert_eq!(read(&cut).unwrap().records, expect);
    }

    /// Volumetric records between ordinary ones come back whole and in order; one whose
    /// continuation is damaged is skipped with it, and the records around it stay.
    #[test]
    fn volumetric_records_round_trip_and_are_checked_with_their_continuation() {
        let (_path_dir, path) = temp("volume");
        let _ = std::fs::remove_file(&path);
        let volume = |i: usize| VolumeRecord {
            p: Vec3::new(i as f32, 0.5, -2.0),
            r: 0.25 * (i + 1) as f32,
            medium: i % 2,
            radiance: std::array::from_fn(|k| Rgb::new(k as f32, -0.5 * k as f32, i as f32)),
            towards: Vec3::new(0.6, -0.8 * i as f32, 0.0),
            high_bands: Rgb::new(0.1, -0.2, i as f32),
            shorter: std::array::from_fn(|j| {
                std::array::from_fn(|k| Rgb::new(0.5 * k as f32, -(k as f32), (i + j) as f32))
            }),
        };
        let recs: Vec<Stored> = (0..3).map(|i| (record(i), None)).collect();
        let vols: Vec<VolumeRecord> = (0..3).map(volume).collect();
        let (mut f, _) = CacheFile::open(&path, &header(), false).unwrap();
        f.append(&recs[..2]).unwrap();
        f.append_volume(&vols).unwrap();
        f.append(&recs[2..]).unwrap();
        drop(f);
        let c = read(&path).unwrap();
        assert_eq!(
            (c.records.as_slice(), c.volume.as_slice()),
            (&recs[..], &vols[..])
        );
        // The second volumetric record's first continuation (slots: 2 records, then 3 per
        // volume record).
        let mut bad = std::fs::read(&path).unwrap();
        bad[HEADER_BYTES + (2 + VOLUME_SLOTS + 1) * RECORD_BYTES + 8] ^= 1;
        std::fs::write(&path, &bad).unwrap();
        let c = read(&path).unwrap();
        assert_eq!(c.records, recs);
        assert_eq!(c.volume, [vols[0], vols[2]]);
        // Its first slot is skipped as damage; its continuations, alone, are too.
        assert_eq!(c.damaged, VOLUME_SLOTS as u64);
    }

    #[test]
    fn a_torn_last_record_leaves_every_earlier_one() {
        let (_path_dir, path) = temp("torn");
        let recs: Vec<Stored> = (0..6).map(|i| (record(i), None)).collect();
        let _ = std::fs::remove_file(&path);
        let (mut f, _) = CacheFile::open(&path, &header(), false).unwrap();
        f.append(&recs).unwrap();
        drop(f);
        let full = std::fs::read(&path).unwrap();
        let last = HEADER_BYTES + 5 * RECORD_BYTES;
        let (_cut_dir, cut) = temp("torn-cut");
        for len in last..full.len() {
            std::fs::write(&cut, &full[..len]).unwrap();
            let c = read(&cut).unwrap();
            assert_eq!(c.records, recs[..5], "cut at {len}");
            assert_eq!(c.torn_bytes, (len - last) as u64);
            // Opening cuts the torn tail off.
            let (mut f, c2) = CacheFile::open(&cut, &header(), false).unwrap();
            assert_eq!(c2.records, recs[..5]);
            f.append(&[(record(9), None)]).unwrap();
            drop(f);
            let c = read(&cut).unwrap();
            assert_eq!(c.records.len(), 6);
            assert_eq!(c.records[5], (record(9), None));
            assert_eq!(c.torn_bytes, 0);
        }
        // A flipped bit in the last record: it is dropped, the others stay.
        let mut bad = full.clone();
        bad[last + 10] ^= 4;
        std::fs::write(&cut, &bad).unwrap();
        assert_eq!(read(&cut).unwrap().records, recs[..5]);
        // A flipped bit in a record in the middle loses only that record; opening keeps the
        // rest, and a new record is appended after the last intact one.
        let mut bad = full.clone();
        bad[HEADER_BYTES + 2 * RECORD_BYTES + 20] ^= 1;
        std::fs::write(&cut, &bad).unwrap();
        let c = read(&cut).unwrap();
        let mut expect = recs.clone();
        expect.remove(2);
        assert_eq!(
            (c.records.clone(), c.damaged, c.torn_bytes),
            (expect.clone(), 1, 0)
        );
        let (mut f, c2) = CacheFile::open(&cut, &header(), false).unwrap();
        assert_eq!(c2.records, expect);
        f.append(&[(record(9), None)]).unwrap();
        drop(f);
        expect.push((record(9), None));
        assert_eq!(read(&cut).unwrap().records, expect);
        // Not a cache file, a short file, a damaged header: clear errors.
        std::fs::write(&cut, b"hello").unwrap();
        assert!(read(&cut).unwrap_err().to_string().contains("too short"));
        let mut bad = full.clone();
        bad[0] = b'X';
        std::fs::write(&cut, &bad).unwrap();
        assert!(read(&cut).unwrap_err().to_string().contains("magic"));
        let mut bad = full;
        bad[30] ^= 1;
        std::fs::write(&cut, &bad).unwrap();
        assert!(read(&cut).unwrap_err().to_string().contains("checksum"));
        let _ = std::fs::remove_file(path);
        let _ = std::fs::remove_file(cut);
    }
}
