//! Intel Embree 3 as a peer of the reference: the same shadow rays from the same view
//! samples, traced through Embree's BVH (`rtcOccluded1`), so benchmarks can set `afsm`
//! against the fastest CPU ray tracer as well as against the crate's own reference.
//!
//! Built only with the cargo feature `embree`, which links the system's `libembree3`
//! (Debian: `apt-get install libembree-dev`). The binding is the handful of C functions
//! used here, declared by hand from `embree3/rtcore*.h` (3.13).
//!
//! Rays are those of [`Reference::transmittance`](crate::reference::Reference::transmittance):
//! origin offset by the surface point's error bound, segment up to the light. Embree's
//! occlusion query answers hit or miss, so every caster counts as opaque (semi-transparent
//! materials are not modulated), and its own triangle-intersection test is used rather than
//! the crate's watertight one: answers agree with the reference up to numerical ties, which
//! [`EmbreeScene::visibility`]'s callers measure.

use crate::error::{Error, Result};
use crate::frame::{Frame, Visibility};
use crate::math::Vec3;
use crate::scene::Scene;
use rayon::prelude::*;
use std::ffi::{c_char, c_uint, c_void, CStr};
use std::time::Instant;

#[allow(non_camel_case_types)]
type RTCDevice = *mut c_void;
#[allow(non_camel_case_types)]
type RTCScene = *mut c_void;
#[allow(non_camel_case_types)]
type RTCGeometry = *mut c_void;

const RTC_GEOMETRY_TYPE_TRIANGLE: c_uint = 0;
const RTC_BUFFER_TYPE_INDEX: c_uint = 0;
const RTC_BUFFER_TYPE_VERTEX: c_uint = 1;
const RTC_FORMAT_UINT3: c_uint = 0x5003;
const RTC_FORMAT_FLOAT3: c_uint = 0x9003;
const RTC_BUILD_QUALITY_MEDIUM: c_uint = 1;
const RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT: c_uint = 0;
const RTC_INVALID_GEOMETRY_ID: c_uint = u32::MAX;
const RTC_ERROR_NONE: c_uint = 0;

/// `struct RTCIntersectContext` for `RTC_MAX_INSTANCE_LEVEL_COUNT == 1` and
/// `RTC_MIN_WIDTH == 0`, as Debian's build configures it.
#[repr(C)]
struct RTCIntersectContext {
    flags: c_uint,
    filter: *const c_void,
    inst_id: [c_uint; 1],
}

/// `struct RTC_ALIGN(16) RTCRay`.
#[repr(C, align(16))]
struct RTCRay {
    org: [f32; 3],
    tnear: f32,
    dir: [f32; 3],
    time: f32,
    tfar: f32,
    mask: c_uint,
    id: c_uint,
    flags: c_uint,
}

#[link(name = "embree3")]
extern "C" {
    fn rtcNewDevice(config: *const c_char) -> RTCDevice;
    fn rtcReleaseDevice(device: RTCDevice);
    fn rtcGetDeviceError(device: RTCDevice) -> c_uint;
    fn rtcNewScene(device: RTCDevice) -> RTCScene;
    fn rtcReleaseScene(scene: RTCScene);
    fn rtcSetSceneBuildQuality(scene: RTCScene, quality: c_uint);
    fn rtcCommitScene(scene: RTCScene);
    fn rtcNewGeometry(device: RTCDevice, kind: c_uint) -> RTCGeometry;
    fn rtcSetNewGeometryBuffer(
        geometry: RTCGeometry,
        kind: c_uint,
        slot: c_uint,
        format: c_uint,
        byte_stride: usize,
        item_count: usize,
    ) -> *mut c_void;
    fn rtcCommitGeometry(geometry: RTCGeometry);
    fn rtcAttachGeometry(scene: RTCScene, geometry: RTCGeometry) -> c_uint;
    fn rtcReleaseGeometry(geometry: RTCGeometry);
    fn rtcOccluded1(scene: RTCScene, context: *mut RTCIntersectContext, ray: *mut RTCRay);
}

/// An Embree device and scene over a copy of a [`Scene`]'s triangles, ready for occlusion
/// rays.
pub struct EmbreeScene {
    device: RTCDevice,
    handle: RTCScene,
    /// BVH build time (geometry upload and commit) in milliseconds.
    pub build_ms: f64,
}

// Embree scenes are safe to query from many threads at once once committed; the device
// and scene handles are only released in `drop`.
unsafe impl Send for EmbreeScene {}
unsafe impl Sync for EmbreeScene {}

fn device_error(device: RTCDevice, what: &str) -> Result<()> {
    // SAFETY: `device` is a live device handle.
    let code = unsafe { rtcGetDeviceError(device) };
    if code == RTC_ERROR_NONE {
        Ok(())
    } else {
        Err(Error::param(format!(
            "Embree failed to {what} (error code {code})"
        )))
    }
}

impl EmbreeScene {
    /// Creates a device (`threads` build threads; 0 lets Embree choose) and builds its BVH
    /// over every triangle of `scene`.
    pub fn build(scene: &Scene, threads: usize) -> Result<Self> {
        let config = format!("threads={threads}\0");
        let config = CStr::from_bytes_with_nul(config.as_bytes()).expect("one trailing NUL");
        // SAFETY: a NUL-terminated configuration string.
        let device = unsafe { rtcNewDevice(config.as_ptr()) };
        if device.is_null() {
            return Err(Error::param("Embree could not create a device".to_string()));
        }
        let t0 = Instant::now();
        // SAFETY: every handle below comes from the live `device`; buffers are written
        // within the sizes Embree allocated for them.
        let handle = unsafe {
            let handle = rtcNewScene(device);
            rtcSetSceneBuildQuality(handle, RTC_BUILD_QUALITY_MEDIUM);
            let n = scene.len();
            if n > 0 {
                let geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
                let vertices = rtcSetNewGeometryBuffer(
                    geometry,
                    RTC_BUFFER_TYPE_VERTEX,
                    0,
                    RTC_FORMAT_FLOAT3,
                    12,
                    3 * n,
                ) as *mut f32;
                let indices = rtcSetNewGeometryBuffer(
                    geometry,
                    RTC_BUFFER_TYPE_INDEX,
                    0,
                    RTC_FORMAT_UINT3,
                    12,
                    n,
                ) as *mut u32;
                if vertices.is_null() || indices.is_null() {
                    rtcReleaseGeometry(geometry);
                    rtcReleaseScene(handle);
                    rtcReleaseDevice(device);
                    return Err(Error::param(format!(
                        "Embree could not allocate buffers for {n} triangles"
                    )));
                }
                let vertices = std::slice::from_raw_parts_mut(vertices, 9 * n);
                let indices = std::slice::from_raw_parts_mut(indices, 3 * n);
                for i in 0..n {
                    for (j, p) in scene.triangle(i).iter().enumerate() {
                        vertices[9 * i + 3 * j..9 * i + 3 * j + 3].copy_from_slice(&p.to_array());
                        indices[3 * i + j] = (3 * i + j) as u32;
                    }
                }
                rtcCommitGeometry(geometry);
                rtcAttachGeometry(handle, geometry);
                rtcReleaseGeometry(geometry);
            }
            rtcCommitScene(handle);
            handle
        };
        let built = EmbreeScene {
            device,
            handle,
            build_ms: t0.elapsed().as_secs_f64() * 1e3,
        };
        device_error(device, "build its BVH")?;
        Ok(built)
    }

    /// True when something blocks the segment `o + t·dir`, `t ∈ (0, t_max)`.
    pub fn occluded(&self, o: Vec3, dir: Vec3, t_max: f32) -> bool {
        let mut context = RTCIntersectContext {
            flags: RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT,
            filter: std::ptr::null(),
            inst_id: [RTC_INVALID_GEOMETRY_ID],
        };
        let mut ray = RTCRay {
            org: o.to_array(),
            tnear: 0.0,
            dir: dir.to_array(),
            time: 0.0,
            tfar: t_max,
            mask: u32::MAX,
            id: 0,
            flags: 0,
        };
        // SAFETY: a committed scene, an initialized context and an aligned ray.
        unsafe { rtcOccluded1(self.handle, &mut context, &mut ray) };
        ray.tfar == f32::NEG_INFINITY
    }

    /// The shadow term of every covered pixel of a frame (one ray from each camera-pass
    /// sample), as 0 or 1: the same rays [`crate::reference::Reference`] traces.
    pub fn visibility(&self, frame: &Frame) -> Visibility {
        let view = frame.view;
        let light = frame.light;
        let value = (0..view.triangle.len())
            .into_par_iter()
            .map(|k| {
                if !view.covered(k) {
                    return Vec3::ONE;
                }
                let (p, n) = (view.position[k], view.normal[k]);
                if !light.illuminates(p, n) {
                    return Vec3::ZERO;
                }
                let sp = view.surface_point(k);
                let (l, _) = light.shadow_ray(p);
                let o = sp.offset_origin(n, l);
                let (dir, t_max) = light.shadow_ray(o);
                if self.occluded(o, dir, t_max) {
                    Vec3::ZERO
                } else {
                    Vec3::ONE
                }
            })
            .collect();
        Visibility {
            width: view.width,
            height: view.height,
            value,
        }
    }
}

impl Drop for EmbreeScene {
    fn drop(&mut self) {
        // SAFETY: both handles are live and released once.
        unsafe {
            rtcReleaseScene(self.handle);
            rtcReleaseDevice(self.device);
        }
    }
}
