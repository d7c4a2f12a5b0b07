//! A thin, safe wrapper over Embree 3's C API (Debian's `libembree-dev` 3.13).
//!
//! The crate holds exactly what the renderer needs: a [`Device`], a [`SceneBuilder`] that collects
//! triangle meshes and analytic spheres, and an immutable, thread-safe [`Scene`] answering
//! closest-hit ([`Scene::intersect`]) and any-hit ([`Scene::occluded`]) queries for single rays and
//! for 16-wide SoA packets ([`Scene::intersect16`], [`Scene::occluded16`], and the `_with`
//! variants taking a [`Coherence`] hint).
//!
//! Why hand-written: the `embree` crate on crates.io (0.3) frees memory with a layout different
//! from the one it allocated with (undefined behaviour) and lags the C API, and bindgen would add a
//! libclang build dependency for a dozen functions. The raw declarations live in [`ffi`], with
//! every struct layout transcribed from the 3.13.5 headers and checked by compile-time
//! assertions.
//!
//! Conventions (all tested):
//! * Triangles: barycentrics `u, v` with `p = (1 − u − v)·p0 + u·p1 + v·p2`; the geometric
//!   normal [`Hit::ng`] points along `(p1 − p0) × (p2 − p0)` and is not normalised.
//! * Spheres: [`Hit::ng`] points outward from the centre (also for rays starting inside); `u`
//!   and `v` are whatever Embree reports (zero in 3.13) and carry no meaning.
//! * [`Hit::t`] is the ray parameter along the (not necessarily unit) direction, accepted in
//!   `[Ray::t_min, Ray::t_max]`; `t_max` may be infinite.
//! * Geometry ids are assigned `0, 1, 2, …` in the order geometry is added; `prim_id` is the
//!   triangle index or sphere index inside its geometry.
//!
//! Embree recommends setting the CPU's flush-to-zero and denormals-are-zero modes on every
//! thread that traces rays; this crate leaves that thread-wide choice to the caller.

#![deny(missing_docs)]

pub mod ffi;

use std::cell::RefCell;
use std::ffi::{c_char, c_void, CStr};
use std::ptr;
use std::sync::Arc;

use ircache_math::{Ray, Vec3};

/// Errors reported by Embree or found while validating input before it reaches Embree.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum EmbreeError {
    /// Embree reported an error (`rtcGetDeviceError` was not `RTC_ERROR_NONE`).
    #[error("Embree error {code} ({name}): {message}")]
    Embree {
        /// The raw `RTCError` code.
        code: u32,
        /// The name of the code, e.g. `RTC_ERROR_INVALID_ARGUMENT`.
        name: &'static str,
        /// The message passed to the device's error callback, if any.
        message: String,
    },
    /// The input was rejected before being handed to Embree (non-finite data, bad indices, …).
    #[error("invalid geometry: {0}")]
    InvalidInput(String),
}

fn error_name(code: ffi::RTCError) -> &'static str {
    match code {
        ffi::RTC_ERROR_NONE => "RTC_ERROR_NONE",
        ffi::RTC_ERROR_UNKNOWN => "RTC_ERROR_UNKNOWN",
        ffi::RTC_ERROR_INVALID_ARGUMENT => "RTC_ERROR_INVALID_ARGUMENT",
        ffi::RTC_ERROR_INVALID_OPERATION => "RTC_ERROR_INVALID_OPERATION",
        ffi::RTC_ERROR_OUT_OF_MEMORY => "RTC_ERROR_OUT_OF_MEMORY",
        ffi::RTC_ERROR_UNSUPPORTED_CPU => "RTC_ERROR_UNSUPPORTED_CPU",
        ffi::RTC_ERROR_CANCELLED => "RTC_ERROR_CANCELLED",
        _ => "unknown RTCError",
    }
}

thread_local! {
    /// The last message Embree passed to the error callback on this thread. Embree's error codes
    /// are per thread and per device, and the callback runs on the thread of the failing call.
    static LAST_MESSAGE: RefCell<Option<String>> = const { RefCell::new(None) };
}

unsafe extern "C" fn error_callback(_user: *mut c_void, _code: ffi::RTCError, msg: *const c_char) {
    let text = if msg.is_null() {
        String::new()
    } else {
        // SAFETY: Embree passes a NUL-terminated string valid for the duration of the callback.
        unsafe { CStr::from_ptr(msg) }
            .to_string_lossy()
            .into_owned()
    };
    // `try_with`/`try_borrow_mut`: never panic (and so never unwind) across the C boundary.
    let _ = LAST_MESSAGE.try_with(|m| {
        if let Ok(mut m) = m.try_borrow_mut() {
            *m = Some(text);
        }
    });
}

/// Reads (and thereby resets) this thread's error code for `device`.
fn take_error(device: ffi::RTCDevice) -> Result<(), EmbreeError> {
    // SAFETY: `device` is null (allowed: reads the thread's device-less error) or a live device.
    let code = unsafe { ffi::rtcGetDeviceError(device) };
    let message = LAST_MESSAGE
        .try_with(|m| m.try_borrow_mut().ok().and_then(|mut m| m.take()))
        .ok()
        .flatten();
    if code == ffi::RTC_ERROR_NONE {
        Ok(())
    } else {
        Err(EmbreeError::Embree {
            code,
            name: error_name(code),
            message: message.unwrap_or_default(),
        })
    }
}

struct DeviceInner {
    raw: ffi::RTCDevice,
}

// SAFETY: an Embree device is reference counted with atomics, its error state is per thread, and
// Embree allows creating and committing scenes from several threads; the handle is never mutated
// through `DeviceInner`.
unsafe impl Send for DeviceInner {}
// SAFETY: see `Send`; all shared use goes through Embree's thread-safe API.
unsafe impl Sync for DeviceInner {}

impl Drop for DeviceInner {
    fn drop(&mut self) {
        // SAFETY: `raw` is the live device created in `Device::new`; this is our only reference.
        // Scenes and builders hold a `Device` clone, so they are released before this runs.
        unsafe { ffi::rtcReleaseDevice(self.raw) };
    }
}

/// An Embree device (`rtcNewDevice`): owns Embree's thread pool and memory accounting.
/// Cheap to clone (reference counted), `Send + Sync`.
#[derive(Clone)]
pub struct Device {
    inner: Arc<DeviceInner>,
}

impl std::fmt::Debug for Device {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Device")
            .field("raw", &self.inner.raw)
            .finish()
    }
}

impl Device {
    /// Creates a device with Embree's default configuration (all hardware threads for builds).
    pub fn new() -> Result<Device, EmbreeError> {
        // Clear any stale device-less error on this thread so it is not attributed to us.
        let _ = take_error(ptr::null_mut());
        // SAFETY: a null config string selects the defaults.
        let raw = unsafe { ffi::rtcNewDevice(ptr::null()) };
        if raw.is_null() {
            take_error(ptr::null_mut())?;
            return Err(EmbreeError::Embree {
                code: ffi::RTC_ERROR_UNKNOWN,
                name: error_name(ffi::RTC_ERROR_UNKNOWN),
                message: "rtcNewDevice returned NULL".into(),
            });
        }
        let device = Device {
            inner: Arc::new(DeviceInner { raw }),
        };
        // SAFETY: `raw` is live; the callback is a plain function that never unwinds and ignores
        // the (null) user pointer.
        unsafe { ffi::rtcSetDeviceErrorFunction(raw, Some(error_callback), ptr::null_mut()) };
        device.check()?;
        Ok(device)
    }

    #[inline]
    fn raw(&self) -> ffi::RTCDevice {
        self.inner.raw
    }

    /// Returns this thread's pending error for the device, resetting it.
    fn check(&self) -> Result<(), EmbreeError> {
        take_error(self.raw())
    }

    /// Discards a stale error left on this thread (by a call that was not ours to check), so
    /// the next [`Device::check`] reports only errors of the call it follows.
    fn clear_error(&self) {
        let _ = take_error(self.raw());
    }
}

/// Owns one reference to an Embree geometry and releases it on drop (also on error paths).
struct GeometryGuard(ffi::RTCGeometry);

impl Drop for GeometryGuard {
    fn drop(&mut self) {
        // SAFETY: the handle is a live geometry from `rtcNewGeometry`; we release only our own
        // reference (a scene it was attached to holds its own).
        unsafe { ffi::rtcReleaseGeometry(self.0) };
    }
}

/// Collects geometry for a [`Scene`]. Geometry ids are `0, 1, 2, …` in call order.
pub struct SceneBuilder {
    device: Device,
    /// Null after `build` handed the scene over.
    raw: ffi::RTCScene,
    next_id: u32,
}

// SAFETY: the builder exclusively owns its uncommitted scene; Embree handles are not tied to the
// thread that created them.
unsafe impl Send for SceneBuilder {}

impl Drop for SceneBuilder {
    fn drop(&mut self) {
        if !self.raw.is_null() {
            // SAFETY: `raw` is the builder's own live scene reference, not handed to a `Scene`.
            unsafe { ffi::rtcReleaseScene(self.raw) };
        }
    }
}

impl SceneBuilder {
    /// Creates an empty scene on `device`.
    pub fn new(device: &Device) -> Result<SceneBuilder, EmbreeError> {
        device.clear_error();
        // SAFETY: the device is live for as long as `device` (and the clone we keep) exists.
        let raw = unsafe { ffi::rtcNewScene(device.raw()) };
        if let Err(e) = device.check() {
            if !raw.is_null() {
                // SAFETY: releasing the scene we just created and will not use.
                unsafe { ffi::rtcReleaseScene(raw) };
            }
            return Err(e);
        }
        if raw.is_null() {
            return Err(EmbreeError::Embree {
                code: ffi::RTC_ERROR_UNKNOWN,
                name: error_name(ffi::RTC_ERROR_UNKNOWN),
                message: "rtcNewScene returned NULL".into(),
            });
        }
        Ok(SceneBuilder {
            device: device.clone(),
            raw,
            next_id: 0,
        })
    }

    /// Adds a triangle mesh and returns its Embree geometry id. Positions must be finite and
    /// every index must be below `positions.len()`; otherwise nothing is added and
    /// [`EmbreeError::InvalidInput`] is returned.
    pub fn add_triangle_mesh(
        &mut self,
        positions: &[Vec3],
        indices: &[[u32; 3]],
    ) -> Result<u32, EmbreeError> {
        if positions.len() > u32::MAX as usize || indices.len() > u32::MAX as usize {
            return Err(EmbreeError::InvalidInput(
                "more than 2^32 - 1 vertices or triangles".into(),
            ));
        }
        if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
            return Err(EmbreeError::InvalidInput(format!(
                "vertex {i} is not finite: {}",
                positions[i]
            )));
        }
        let n = positions.len() as u32;
        if let Some(t) = indices.iter().position(|tri| tri.iter().any(|&k| k >= n)) {
            return Err(EmbreeError::InvalidInput(format!(
                "triangle {t} has index {:?} out of range for {n} vertices",
                indices[t]
            )));
        }
        self.add_geometry(ffi::RTC_GEOMETRY_TYPE_TRIANGLE, |geom| {
            // SAFETY: `geom` is a live triangle geometry; Embree allocates the buffer (and pads
            // vertex buffers so that 16-byte SSE loads of the last element stay in bounds).
            let vptr = unsafe {
                ffi::rtcSetNewGeometryBuffer(
                    geom,
                    ffi::RTC_BUFFER_TYPE_VERTEX,
                    0,
                    ffi::RTC_FORMAT_FLOAT3,
                    12,
                    positions.len(),
                )
            };
            // SAFETY: as above, for the index buffer.
            let iptr = unsafe {
                ffi::rtcSetNewGeometryBuffer(
                    geom,
                    ffi::RTC_BUFFER_TYPE_INDEX,
                    0,
                    ffi::RTC_FORMAT_UINT3,
                    12,
                    indices.len(),
                )
            };
            if (vptr.is_null() && !positions.is_empty()) || (iptr.is_null() && !indices.is_empty())
            {
                return false;
            }
            for (i, p) in positions.iter().enumerate() {
                // SAFETY: the buffer holds `positions.len()` items of 12 bytes, Embree aligns it to
                // at least 16 bytes, and `[f32; 3]` needs 4.
                unsafe { vptr.cast::<[f32; 3]>().add(i).write(p.to_array()) };
            }
            if !indices.is_empty() {
                // SAFETY: the buffer holds `indices.len()` items of 12 bytes (`[u32; 3]`), is at
                // least 4-byte aligned and cannot overlap our slice.
                unsafe {
                    ptr::copy_nonoverlapping(
                        indices.as_ptr(),
                        iptr.cast::<[u32; 3]>(),
                        indices.len(),
                    )
                };
            }
            true
        })
    }

    /// Adds analytic spheres `(centre, radius)` as one geometry (`RTC_GEOMETRY_TYPE_SPHERE_POINT`)
    /// and returns its geometry id; a hit's `prim_id` is the index into `spheres`. Centres must be
    /// finite and radii finite and positive.
    pub fn add_spheres(&mut self, spheres: &[(Vec3, f32)]) -> Result<u32, EmbreeError> {
        if spheres.len() > u32::MAX as usize {
            return Err(EmbreeError::InvalidInput(
                "more than 2^32 - 1 spheres".into(),
            ));
        }
        if let Some(i) = spheres
            .iter()
            .position(|(c, r)| !c.is_finite() || !r.is_finite() || *r <= 0.0)
        {
            let (c, r) = spheres[i];
            return Err(EmbreeError::InvalidInput(format!(
                "sphere {i} is invalid: centre {c}, radius {r}"
            )));
        }
        self.add_geometry(ffi::RTC_GEOMETRY_TYPE_SPHERE_POINT, |geom| {
            // SAFETY: `geom` is a live sphere geometry; Embree owns and pads the buffer.
            let vptr = unsafe {
                ffi::rtcSetNewGeometryBuffer(
                    geom,
                    ffi::RTC_BUFFER_TYPE_VERTEX,
                    0,
                    ffi::RTC_FORMAT_FLOAT4,
                    16,
                    spheres.len(),
                )
            };
            if vptr.is_null() && !spheres.is_empty() {
                return false;
            }
            for (i, (c, r)) in spheres.iter().enumerate() {
                // SAFETY: the buffer holds `spheres.len()` items of 16 bytes, suitably aligned.
                unsafe { vptr.cast::<[f32; 4]>().add(i).write([c.x, c.y, c.z, *r]) };
            }
            true
        })
    }

    /// Creates a geometry of `kind`, lets `fill` set its buffers, commits it and attaches it under
    /// the next id. Every Embree call is followed by an error check.
    fn add_geometry(
        &mut self,
        kind: ffi::RTCGeometryType,
        fill: impl FnOnce(ffi::RTCGeometry) -> bool,
    ) -> Result<u32, EmbreeError> {
        let device = self.device.raw();
        self.device.clear_error();
        // SAFETY: the device is live (we hold a clone).
        let geom = unsafe { ffi::rtcNewGeometry(device, kind) };
        self.device.check()?;
        if geom.is_null() {
            return Err(EmbreeError::Embree {
                code: ffi::RTC_ERROR_UNKNOWN,
                name: error_name(ffi::RTC_ERROR_UNKNOWN),
                message: "rtcNewGeometry returned NULL".into(),
            });
        }
        let guard = GeometryGuard(geom);
        let filled = fill(guard.0);
        self.device.check()?;
        if !filled {
            return Err(EmbreeError::Embree {
                code: ffi::RTC_ERROR_OUT_OF_MEMORY,
                name: error_name(ffi::RTC_ERROR_OUT_OF_MEMORY),
                message: "rtcSetNewGeometryBuffer returned NULL".into(),
            });
        }
        let id = self.next_id;
        // SAFETY: `guard.0` is a live geometry with all required buffers set; `self.raw` is the
        // builder's live, uncommitted scene. Attaching makes the scene take its own reference,
        // so dropping `guard` afterwards is correct.
        unsafe {
            ffi::rtcSetGeometryBuildQuality(guard.0, ffi::RTC_BUILD_QUALITY_HIGH);
            ffi::rtcCommitGeometry(guard.0);
        }
        self.device.check()?;
        // SAFETY: see above.
        unsafe { ffi::rtcAttachGeometryByID(self.raw, guard.0, id) };
        self.device.check()?;
        self.next_id += 1;
        Ok(id)
    }

    /// Builds the acceleration structure (`RTC_BUILD_QUALITY_HIGH`, `rtcCommitScene`) and returns
    /// the immutable scene. An empty builder gives an empty scene in which every ray misses.
    pub fn build(mut self) -> Result<Scene, EmbreeError> {
        let raw = std::mem::replace(&mut self.raw, ptr::null_mut());
        // Wrap first so the scene is released on every error path.
        let scene = Scene {
            raw,
            device: self.device.clone(),
        };
        scene.device.clear_error();
        // SAFETY: `raw` is the live scene now owned by `scene`; no other thread can see it yet.
        unsafe {
            ffi::rtcSetSceneBuildQuality(raw, ffi::RTC_BUILD_QUALITY_HIGH);
            ffi::rtcCommitScene(raw);
        }
        scene.device.check()?;
        Ok(scene)
    }
}

/// Hint for Embree's packet traversal ([`Scene::intersect16_with`], [`Scene::occluded16_with`]).
/// Results are identical either way; only speed differs. `Coherent` (the default of
/// [`Scene::intersect16`]) suits packets of similar rays such as camera rays of a pixel tile;
/// for packets of unrelated rays (diffuse bounces) `Incoherent` was about 3× faster in
/// `examples/raw_throughput.rs`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Coherence {
    /// `RTC_INTERSECT_CONTEXT_FLAG_COHERENT`.
    #[default]
    Coherent,
    /// `RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT`.
    Incoherent,
}

impl Coherence {
    #[inline(always)]
    fn flags(self) -> ffi::RTCIntersectContextFlags {
        match self {
            Coherence::Coherent => ffi::RTC_INTERSECT_CONTEXT_FLAG_COHERENT,
            Coherence::Incoherent => ffi::RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT,
        }
    }
}

/// A ray–surface intersection.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Ray parameter of the hit: the point is `ray.o + t · ray.d`.
    pub t: f32,
    /// Geometry id as returned by the builder.
    pub geom_id: u32,
    /// Primitive index inside the geometry (triangle or sphere index).
    pub prim_id: u32,
    /// Barycentric coordinate weighting `p1` (triangles; meaningless for spheres).
    pub u: f32,
    /// Barycentric coordinate weighting `p2` (triangles; meaningless for spheres).
    pub v: f32,
    /// Unnormalised, non-zero geometric normal: along `(p1 − p0) × (p2 − p0)` for triangles,
    /// outward for spheres.
    pub ng: Vec3,
}

/// A built, immutable Embree scene. `Send + Sync`: queries may run on any number of threads.
pub struct Scene {
    raw: ffi::RTCScene,
    /// Keeps the device alive for as long as the scene (dropped after `raw` is released).
    device: Device,
}

// SAFETY: after `rtcCommitScene` the scene is never modified; Embree supports concurrent ray
// queries on a committed scene from any thread, and releasing happens once, in `Drop`.
unsafe impl Send for Scene {}
// SAFETY: see `Send`; all `&self` methods are read-only Embree queries.
unsafe impl Sync for Scene {}

impl Drop for Scene {
    fn drop(&mut self) {
        // SAFETY: `raw` is our single reference to a live scene; geometries are released with it.
        unsafe { ffi::rtcReleaseScene(self.raw) };
    }
}

impl std::fmt::Debug for Scene {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Scene")
            .field("raw", &self.raw)
            .field("device", &self.device)
            .finish()
    }
}

/// Converts Embree's normal to the crate convention. Embree's triangle normal is
/// `(p1 − p0) × (p2 − p0)` already (checked by the `triangle_*` tests in `tests/embree.rs`), and sphere normals
/// point outward, so no sign change is needed.
#[inline(always)]
fn make_ng(x: f32, y: f32, z: f32) -> Vec3 {
    Vec3::new(x, y, z)
}

#[inline(always)]
fn rtc_ray(ray: &Ray) -> ffi::RTCRay {
    ffi::RTCRay {
        org_x: ray.o.x,
        org_y: ray.o.y,
        org_z: ray.o.z,
        tnear: ray.t_min,
        dir_x: ray.d.x,
        dir_y: ray.d.y,
        dir_z: ray.d.z,
        time: 0.0,
        tfar: ray.t_max,
        mask: u32::MAX,
        id: 0,
        flags: 0,
    }
}

impl Scene {
    /// Closest hit along `ray` within `[t_min, t_max]` (`rtcIntersect1`, incoherent context);
    /// none for a ray Embree would refuse ([`traceable`]).
    #[inline]
    pub fn intersect(&self, ray: &Ray) -> Option<Hit> {
        if !traceable(ray) {
            return None;
        }
        let mut ctx = ffi::RTCIntersectContext::new(ffi::RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT);
        let mut rh = ffi::RTCRayHit {
            ray: rtc_ray(ray),
            hit: ffi::RTCHit {
                Ng_x: 0.0,
                Ng_y: 0.0,
                Ng_z: 0.0,
                u: 0.0,
                v: 0.0,
                primID: ffi::RTC_INVALID_GEOMETRY_ID,
                geomID: ffi::RTC_INVALID_GEOMETRY_ID,
                instID: [ffi::RTC_INVALID_GEOMETRY_ID; ffi::RTC_MAX_INSTANCE_LEVEL_COUNT],
            },
        };
        // SAFETY: the scene is committed and alive; `ctx` and `rh` are properly laid out and
        // aligned stack values that Embree only accesses during the call.
        unsafe { ffi::rtcIntersect1(self.raw, &mut ctx, &mut rh) };
        let h = &rh.hit;
        (h.geomID != ffi::RTC_INVALID_GEOMETRY_ID).then(|| Hit {
            t: rh.ray.tfar,
            geom_id: h.geomID,
            prim_id: h.primID,
            u: h.u,
            v: h.v,
            ng: make_ng(h.Ng_x, h.Ng_y, h.Ng_z),
        })
    }

    /// Whether anything is hit along `ray` within `[t_min, t_max]` (`rtcOccluded1`); true for a
    /// ray Embree would refuse ([`traceable`]: no light along it).
    #[inline]
    pub fn occluded(&self, ray: &Ray) -> bool {
        if !traceable(ray) {
            return true;
        }
        let mut ctx = ffi::RTCIntersectContext::new(ffi::RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT);
        let mut r = rtc_ray(ray);
        // SAFETY: as in `intersect`.
        unsafe { ffi::rtcOccluded1(self.raw, &mut ctx, &mut r) };
        // Embree sets tfar to -inf on a hit and leaves it untouched otherwise.
        r.tfar < ray.t_max
    }

    /// Traces `rays` in 16-wide packets (`rtcIntersect16`, coherent context); the last packet is
    /// partially filled and masked. Writes `hits[i]` for `i < rays.len()`. Same as
    /// [`Scene::intersect16_with`] with [`Coherence::Coherent`].
    ///
    /// # Panics
    /// If `hits.len() < rays.len()`.
    #[inline]
    pub fn intersect16(&self, rays: &[Ray], hits: &mut [Option<Hit>]) {
        self.intersect16_with(rays, hits, Coherence::Coherent);
    }

    /// [`Scene::intersect16`] with an explicit coherence hint for Embree's traversal.
    ///
    /// # Panics
    /// If `hits.len() < rays.len()`.
    #[inline]
    pub fn intersect16_with(&self, rays: &[Ray], hits: &mut [Option<Hit>], coherence: Coherence) {
        assert!(
            hits.len() >= rays.len(),
            "intersect16: {} hit slots for {} rays",
            hits.len(),
            rays.len()
        );
        for (rays, hits) in rays.chunks(16).zip(hits.chunks_mut(16)) {
            let (valid, ray16) = packet(rays);
            let mut rh = ffi::RTCRayHit16 {
                ray: ray16,
                hit: ffi::RTCHit16 {
                    Ng_x: [0.0; 16],
                    Ng_y: [0.0; 16],
                    Ng_z: [0.0; 16],
                    u: [0.0; 16],
                    v: [0.0; 16],
                    primID: [ffi::RTC_INVALID_GEOMETRY_ID; 16],
                    geomID: [ffi::RTC_INVALID_GEOMETRY_ID; 16],
                    instID: [[ffi::RTC_INVALID_GEOMETRY_ID; 16]; ffi::RTC_MAX_INSTANCE_LEVEL_COUNT],
                },
            };
            let mut ctx = ffi::RTCIntersectContext::new(coherence.flags());
            // SAFETY: committed, live scene; `valid` and `rh` are 64-byte aligned stack values
            // with the header layouts; inactive lanes hold harmless empty rays.
            unsafe { ffi::rtcIntersect16(valid.0.as_ptr(), self.raw, &mut ctx, &mut rh) };
            let h = &rh.hit;
            for (i, out) in hits.iter_mut().enumerate().take(rays.len()) {
                *out = (h.geomID[i] != ffi::RTC_INVALID_GEOMETRY_ID).then(|| Hit {
                    t: rh.ray.tfar[i],
                    geom_id: h.geomID[i],
                    prim_id: h.primID[i],
                    u: h.u[i],
                    v: h.v[i],
                    ng: make_ng(h.Ng_x[i], h.Ng_y[i], h.Ng_z[i]),
                });
            }
        }
    }

    /// Occlusion tests for `rays` in 16-wide packets (`rtcOccluded16`, coherent context). Writes
    /// `occluded[i]` for `i < rays.len()`. Same as [`Scene::occluded16_with`] with
    /// [`Coherence::Coherent`].
    ///
    /// # Panics
    /// If `occluded.len() < rays.len()`.
    #[inline]
    pub fn occluded16(&self, rays: &[Ray], occluded: &mut [bool]) {
        self.occluded16_with(rays, occluded, Coherence::Coherent);
    }

    /// [`Scene::occluded16`] with an explicit coherence hint for Embree's traversal.
    ///
    /// # Panics
    /// If `occluded.len() < rays.len()`.
    #[inline]
    pub fn occluded16_with(&self, rays: &[Ray], occluded: &mut [bool], coherence: Coherence) {
        assert!(
            occluded.len() >= rays.len(),
            "occluded16: {} result slots for {} rays",
            occluded.len(),
            rays.len()
        );
        for (rays, out) in rays.chunks(16).zip(occluded.chunks_mut(16)) {
            let (valid, mut ray16) = packet(rays);
            let mut ctx = ffi::RTCIntersectContext::new(coherence.flags());
            // SAFETY: as in `intersect16`.
            unsafe { ffi::rtcOccluded16(valid.0.as_ptr(), self.raw, &mut ctx, &mut ray16) };
            for (i, (o, r)) in out.iter_mut().zip(rays).enumerate() {
                *o = !traceable(r) || ray16.tfar[i] < r.t_max;
            }
        }
    }

    /// Axis-aligned bounds of the scene (`rtcGetSceneBounds`) as `(lower, upper)`. For an empty
    /// scene Embree reports an empty box (lower > upper).
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let mut b = ffi::RTCBounds::default();
        // SAFETY: committed, live scene; `b` is a 16-byte aligned `RTCBounds`.
        unsafe { ffi::rtcGetSceneBounds(self.raw, &mut b) };
        (
            Vec3::new(b.lower_x, b.lower_y, b.lower_z),
            Vec3::new(b.upper_x, b.upper_y, b.upper_z),
        )
    }
}

/// Whether Embree takes `ray` (its `RayK::valid`): origin and direction within ±1.844e18 in
/// every coordinate, `t_min` and `t_max` numbers. A ray that is not (a numerical failure
/// upstream: a point at infinity, a NaN direction) would stop the whole process in Embree's
/// assertion; it misses, and shadow rays along it are occluded, instead.
#[inline(always)]
#[must_use]
pub fn traceable(ray: &Ray) -> bool {
    const LARGE: f32 = 1.844e18;
    let within = |v: Vec3| v.x.abs() <= LARGE && v.y.abs() <= LARGE && v.z.abs() <= LARGE;
    within(ray.o) && within(ray.d) && !ray.t_min.is_nan() && !ray.t_max.is_nan()
}

/// Builds the SoA packet and valid mask for up to 16 rays; inactive lanes (past the rays, or
/// rays Embree would refuse: [`traceable`]) get an empty ray segment (`tnear = 0 > tfar =
/// -inf`) so they are inert even if Embree reads them.
#[inline(always)]
fn packet(rays: &[Ray]) -> (ffi::Valid16, ffi::RTCRay16) {
    debug_assert!(rays.len() <= 16);
    let mut valid = ffi::Valid16([0; 16]);
    let mut p = ffi::RTCRay16 {
        org_x: [0.0; 16],
        org_y: [0.0; 16],
        org_z: [0.0; 16],
        tnear: [0.0; 16],
        dir_x: [0.0; 16],
        dir_y: [0.0; 16],
        dir_z: [1.0; 16],
        time: [0.0; 16],
        tfar: [f32::NEG_INFINITY; 16],
        mask: [u32::MAX; 16],
        id: [0; 16],
        flags: [0; 16],
    };
    for (i, r) in rays.iter().enumerate().take(16) {
        if !traceable(r) {
            continue;
        }
        valid.0[i] = -1;
        p.org_x[i] = r.o.x;
        p.org_y[i] = r.o.y;
        p.org_z[i] = r.o.z;
        p.tnear[i] = r.t_min;
        p.dir_x[i] = r.d.x;
        p.dir_y[i] = r.d.y;
        p.dir_z[i] = r.d.z;
        p.tfar[i] = r.t_max;
        p.id[i] = i as u32;
    }
    (valid, p)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A real Embree error (an invalid geometry type) comes back as `EmbreeError::Embree` with the
    /// callback's message, consumes no geometry id, and leaves the builder usable.
    #[test]
    fn embree_errors_become_results() {
        let device = Device::new().unwrap();
        let mut b = SceneBuilder::new(&device).unwrap();
        let err = b.add_geometry(9999, |_| true).unwrap_err();
        match &err {
            EmbreeError::Embree { code, message, .. } => {
                // Embree 3.13 reports this one as RTC_ERROR_UNKNOWN with a message.
                assert_ne!(*code, ffi::RTC_ERROR_NONE, "{err}");
                assert!(
                    message.contains("geometry type"),
                    "callback message missing: {err}"
                );
            }
            other => panic!("unexpected {other:?}"),
        }
        assert_eq!(b.add_spheres(&[(Vec3::ZERO, 1.0)]).unwrap(), 0);
        let scene = b.build().unwrap();
        assert!(scene.occluded(&Ray::new(Vec3::new(0.0, 0.0, -5.0), Vec3::Z)));
    }
}
