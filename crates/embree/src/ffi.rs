//! Hand-written raw declarations for the subset of Embree 3.13's C API that this crate uses.
//!
//! Every layout below was transcribed from Debian's `/usr/include/embree3/*.h` (3.13.5), where
//! `rtcore_config.h` defines `RTC_MAX_INSTANCE_LEVEL_COUNT 1` and `RTC_MIN_WIDTH 0`. With those
//! values `RTCIntersectContext` has no `instStackSize` and no `minWidthDistanceFactor` field.
//! C enums are passed as `u32`/`i32` (they are `int`-sized in the C ABI on every supported
//! platform). Sizes and alignments are checked at compile time at the bottom of this file.

#![allow(non_camel_case_types, non_snake_case, missing_docs, dead_code)]

use std::ffi::{c_char, c_int, c_uint, c_void};

/// `RTC_MAX_INSTANCE_LEVEL_COUNT` from `rtcore_config.h`.
pub const RTC_MAX_INSTANCE_LEVEL_COUNT: usize = 1;
/// `RTC_INVALID_GEOMETRY_ID` from `rtcore_common.h`.
pub const RTC_INVALID_GEOMETRY_ID: c_uint = c_uint::MAX;

#[repr(C)]
pub struct RTCDeviceTy {
    _private: [u8; 0],
}
#[repr(C)]
pub struct RTCSceneTy {
    _private: [u8; 0],
}
#[repr(C)]
pub struct RTCGeometryTy {
    _private: [u8; 0],
}
pub type RTCDevice = *mut RTCDeviceTy;
pub type RTCScene = *mut RTCSceneTy;
pub type RTCGeometry = *mut RTCGeometryTy;

// enum RTCError
pub type RTCError = c_uint;
pub const RTC_ERROR_NONE: RTCError = 0;
pub const RTC_ERROR_UNKNOWN: RTCError = 1;
pub const RTC_ERROR_INVALID_ARGUMENT: RTCError = 2;
pub const RTC_ERROR_INVALID_OPERATION: RTCError = 3;
pub const RTC_ERROR_OUT_OF_MEMORY: RTCError = 4;
pub const RTC_ERROR_UNSUPPORTED_CPU: RTCError = 5;
pub const RTC_ERROR_CANCELLED: RTCError = 6;

// enum RTCGeometryType
pub type RTCGeometryType = c_uint;
pub const RTC_GEOMETRY_TYPE_TRIANGLE: RTCGeometryType = 0;
pub const RTC_GEOMETRY_TYPE_SPHERE_POINT: RTCGeometryType = 50;

// enum RTCBufferType
pub type RTCBufferType = c_uint;
pub const RTC_BUFFER_TYPE_INDEX: RTCBufferType = 0;
pub const RTC_BUFFER_TYPE_VERTEX: RTCBufferType = 1;

// enum RTCFormat
pub type RTCFormat = c_uint;
pub const RTC_FORMAT_UINT3: RTCFormat = 0x5003;
pub const RTC_FORMAT_FLOAT3: RTCFormat = 0x9003;
pub const RTC_FORMAT_FLOAT4: RTCFormat = 0x9004;

// enum RTCBuildQuality
pub type RTCBuildQuality = c_uint;
pub const RTC_BUILD_QUALITY_LOW: RTCBuildQuality = 0;
pub const RTC_BUILD_QUALITY_MEDIUM: RTCBuildQuality = 1;
pub const RTC_BUILD_QUALITY_HIGH: RTCBuildQuality = 2;

// enum RTCIntersectContextFlags
pub type RTCIntersectContextFlags = c_uint;
pub const RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT: RTCIntersectContextFlags = 0;
pub const RTC_INTERSECT_CONTEXT_FLAG_COHERENT: RTCIntersectContextFlags = 1;

/// `RTCFilterFunctionN`; this crate never installs one (always `None`).
pub type RTCFilterFunctionN = Option<unsafe extern "C" fn(args: *const c_void)>;
/// `RTCErrorFunction`.
pub type RTCErrorFunction =
    Option<unsafe extern "C" fn(user_ptr: *mut c_void, code: RTCError, msg: *const c_char)>;

/// `struct RTCIntersectContext` (rtcore_common.h) for `RTC_MAX_INSTANCE_LEVEL_COUNT == 1`,
/// `RTC_MIN_WIDTH == 0`: `{ enum flags; RTCFilterFunctionN filter; unsigned instID[1]; }`.
#[repr(C)]
#[derive(Clone, Copy)]
pub struct RTCIntersectContext {
    pub flags: RTCIntersectContextFlags,
    pub filter: RTCFilterFunctionN,
    pub instID: [c_uint; RTC_MAX_INSTANCE_LEVEL_COUNT],
}

impl RTCIntersectContext {
    /// Rust version of the inline C function `rtcInitIntersectContext`, with the flags chosen
    /// by the caller (the C function always writes `INCOHERENT`, callers then override it).
    #[inline(always)]
    pub const fn new(flags: RTCIntersectContextFlags) -> RTCIntersectContext {
        RTCIntersectContext {
            flags,
            filter: None,
            instID: [RTC_INVALID_GEOMETRY_ID; RTC_MAX_INSTANCE_LEVEL_COUNT],
        }
    }
}

/// `struct RTC_ALIGN(16) RTCBounds`.
#[repr(C, align(16))]
#[derive(Clone, Copy, Default)]
pub struct RTCBounds {
    pub lower_x: f32,
    pub lower_y: f32,
    pub lower_z: f32,
    pub align0: f32,
    pub upper_x: f32,
    pub upper_y: f32,
    pub upper_z: f32,
    pub align1: f32,
}

/// `struct RTC_ALIGN(16) RTCRay`.
#[repr(C, align(16))]
#[derive(Clone, Copy)]
pub struct RTCRay {
    pub org_x: f32,
    pub org_y: f32,
    pub org_z: f32,
    pub tnear: f32,
    pub dir_x: f32,
    pub dir_y: f32,
    pub dir_z: f32,
    pub time: f32,
    pub tfar: f32,
    pub mask: c_uint,
    pub id: c_uint,
    pub flags: c_uint,
}

/// `struct RTC_ALIGN(16) RTCHit`.
#[repr(C, align(16))]
#[derive(Clone, Copy)]
pub struct RTCHit {
    pub Ng_x: f32,
    pub Ng_y: f32,
    pub Ng_z: f32,
    pub u: f32,
    pub v: f32,
    pub primID: c_uint,
    pub geomID: c_uint,
    pub instID: [c_uint; RTC_MAX_INSTANCE_LEVEL_COUNT],
}

/// `struct RTCRayHit { RTCRay ray; RTCHit hit; }` (16-byte aligned through its members).
#[repr(C)]
#[derive(Clone, Copy)]
pub struct RTCRayHit {
    pub ray: RTCRay,
    pub hit: RTCHit,
}

/// `struct RTC_ALIGN(64) RTCRay16`.
#[repr(C, align(64))]
#[derive(Clone, Copy)]
pub struct RTCRay16 {
    pub org_x: [f32; 16],
    pub org_y: [f32; 16],
    pub org_z: [f32; 16],
    pub tnear: [f32; 16],
    pub dir_x: [f32; 16],
    pub dir_y: [f32; 16],
    pub dir_z: [f32; 16],
    pub time: [f32; 16],
    pub tfar: [f32; 16],
    pub mask: [c_uint; 16],
    pub id: [c_uint; 16],
    pub flags: [c_uint; 16],
}

/// `struct RTC_ALIGN(64) RTCHit16`.
#[repr(C, align(64))]
#[derive(Clone, Copy)]
pub struct RTCHit16 {
    pub Ng_x: [f32; 16],
    pub Ng_y: [f32; 16],
    pub Ng_z: [f32; 16],
    pub u: [f32; 16],
    pub v: [f32; 16],
    pub primID: [c_uint; 16],
    pub geomID: [c_uint; 16],
    pub instID: [[c_uint; 16]; RTC_MAX_INSTANCE_LEVEL_COUNT],
}

/// `struct RTCRayHit16 { RTCRay16 ray; RTCHit16 hit; }` (64-byte aligned through its members).
#[repr(C)]
#[derive(Clone, Copy)]
pub struct RTCRayHit16 {
    pub ray: RTCRay16,
    pub hit: RTCHit16,
}

/// The `const int* valid` mask of the 16-wide calls (-1 = active lane, 0 = inactive), kept
/// 64-byte aligned like the packet itself.
#[repr(C, align(64))]
#[derive(Clone, Copy)]
pub struct Valid16(pub [c_int; 16]);

extern "C" {
    pub fn rtcNewDevice(config: *const c_char) -> RTCDevice;
    pub fn rtcReleaseDevice(device: RTCDevice);
    pub fn rtcGetDeviceError(device: RTCDevice) -> RTCError;
    pub fn rtcSetDeviceErrorFunction(
        device: RTCDevice,
        error: RTCErrorFunction,
        user_ptr: *mut c_void,
    );

    pub fn rtcNewScene(device: RTCDevice) -> RTCScene;
    pub fn rtcReleaseScene(scene: RTCScene);
    pub fn rtcAttachGeometryByID(scene: RTCScene, geometry: RTCGeometry, geom_id: c_uint);
    pub fn rtcSetSceneBuildQuality(scene: RTCScene, quality: RTCBuildQuality);
    pub fn rtcCommitScene(scene: RTCScene);
    pub fn rtcGetSceneBounds(scene: RTCScene, bounds_o: *mut RTCBounds);

    pub fn rtcNewGeometry(device: RTCDevice, type_: RTCGeometryType) -> RTCGeometry;
    pub fn rtcReleaseGeometry(geometry: RTCGeometry);
    pub fn rtcCommitGeometry(geometry: RTCGeometry);
    pub fn rtcSetGeometryBuildQuality(geometry: RTCGeometry, quality: RTCBuildQuality);
    pub fn rtcSetNewGeometryBuffer(
        geometry: RTCGeometry,
        type_: RTCBufferType,
        slot: c_uint,
        format: RTCFormat,
        byte_stride: usize,
        item_count: usize,
    ) -> *mut c_void;

    pub fn rtcIntersect1(
        scene: RTCScene,
        context: *mut RTCIntersectContext,
        rayhit: *mut RTCRayHit,
    );
    pub fn rtcOccluded1(scene: RTCScene, context: *mut RTCIntersectContext, ray: *mut RTCRay);
    pub fn rtcIntersect16(
        valid: *const c_int,
        scene: RTCScene,
        context: *mut RTCIntersectContext,
        rayhit: *mut RTCRayHit16,
    );
    pub fn rtcOccluded16(
        valid: *const c_int,
        scene: RTCScene,
        context: *mut RTCIntersectContext,
        ray: *mut RTCRay16,
    );
}

// Compile-time layout checks against the C headers (x86-64 / aarch64 LP64).
const _: () = {
    use std::mem::{align_of, offset_of, size_of};
    assert!(size_of::<RTCIntersectContext>() == 24 && align_of::<RTCIntersectContext>() == 8);
    assert!(offset_of!(RTCIntersectContext, filter) == 8);
    assert!(offset_of!(RTCIntersectContext, instID) == 16);
    assert!(size_of::<RTCBounds>() == 32 && align_of::<RTCBounds>() == 16);
    assert!(size_of::<RTCRay>() == 48 && align_of::<RTCRay>() == 16);
    assert!(offset_of!(RTCRay, tfar) == 32 && offset_of!(RTCRay, flags) == 44);
    assert!(size_of::<RTCHit>() == 32 && align_of::<RTCHit>() == 16);
    assert!(offset_of!(RTCHit, primID) == 20 && offset_of!(RTCHit, instID) == 28);
    assert!(size_of::<RTCRayHit>() == 80 && align_of::<RTCRayHit>() == 16);
    assert!(offset_of!(RTCRayHit, hit) == 48);
    assert!(size_of::<RTCRay16>() == 12 * 64 && align_of::<RTCRay16>() == 64);
    assert!(size_of::<RTCHit16>() == 8 * 64 && align_of::<RTCHit16>() == 64);
    assert!(size_of::<RTCRayHit16>() == 20 * 64 && align_of::<RTCRayHit16>() == 64);
    assert!(offset_of!(RTCRayHit16, hit) == 12 * 64);
    assert!(size_of::<Valid16>() == 64 && align_of::<Valid16>() == 64);
};
