//! A committed Embree scene (`RTCScene`) holding one triangle geometry whose vertex and index
//! buffers are shared with Embree (`rtcSetSharedGeometryBuffer`) and owned by the scene, plus
//! the single-ray queries `rtcIntersect1` / `rtcOccluded1`.
//!
//! **Ray interval.** Embree accepts hits with `tnear <= t <= tfar`; the [`Accel`] contract is
//! the open interval `(t_min, t_max)`. We pass `tnear = next_float_up(t_min)` and
//! `tfar = next_float_down(t_max)`, the neighbouring floats, which makes the closed interval Embree
//! tests exactly the open one. One caveat: with denormals-are-zero set (as Embree recommends,
//! see [`set_flush_denormals`](super::set_flush_denormals)) a subnormal `tnear` would read as
//! 0, so a positive subnormal `tnear` is raised to `f32::MIN_POSITIVE` (it only drops hits
//! closer than 1.2e-38). Empty or NaN intervals miss without calling Embree.
//!
//! [`Accel`]: crate::accel::Accel

use super::api::{Query, INVALID_ID};
use super::device::Device;
use super::sys;
use crate::accel::{AccelError, AccelOptions, Hit};
use crate::geometry::{next_float_down, next_float_up, Ray, TriangleMesh};
use std::ffi::c_void;
use std::sync::Arc;

/// A scene that has been committed: only [`Scene::commit`] makes one, so every `Scene` can be
/// queried. Immutable afterwards.
pub struct Scene {
    raw: sys::RTCScene,
    /// Vertex positions as `[x, y, z, 0]`: 16-byte records, so the last vertex can be read with
    /// a 16-byte load as Embree requires of vertex buffers. Read by Embree; never touched again.
    vertices: Vec<[f32; 4]>,
    /// Triangle indices, three per triangle, plus one padding element for the same rule.
    indices: Vec<u32>,
    /// Dropped after the scene is released (field order), keeping the device alive until then.
    device: Arc<Device>,
}

// SAFETY: a committed Embree scene is documented as safe to query (rtcIntersect*/rtcOccluded*)
// from any number of threads at once, and `Scene` offers no way to modify it. The shared
// buffers are never written after the commit, and the scene is released only in `Drop`.
unsafe impl Send for Scene {}
// SAFETY: as above.
unsafe impl Sync for Scene {}

/// The build quality of every scene and its geometry: Embree's default (medium) trade-off
/// between build and trace speed.
const QUALITY: sys::RTCBuildQuality = sys::RTC_BUILD_QUALITY_MEDIUM;

impl Scene {
    /// Builds and commits a scene for `mesh`. The mesh is validated here, next to the unsafe
    /// code that relies on it: Embree does not check indices. An empty mesh gives a valid empty
    /// scene.
    pub fn commit(
        device: Arc<Device>,
        mesh: &TriangleMesh,
        options: AccelOptions,
    ) -> Result<Self, AccelError> {
        mesh.validate()?;
        // SAFETY: the device is live (we hold an Arc).
        let raw = unsafe { sys::rtcNewScene(device.raw()) };
        if raw.is_null() {
            device.check("rtcNewScene")?;
            return Err(AccelError::Embree("rtcNewScene returned null".into()));
        }
        let mut vertices: Vec<[f32; 4]> = mesh.positions.iter().map(|p| [p.x, p.y, p.z, 0.0]).collect();
        let mut indices: Vec<u32> = mesh.indices.iter().flatten().copied().collect();
        indices.push(0);
        vertices.shrink_to_fit();
        indices.shrink_to_fit();
        // From here on, `Drop` releases the scene if anything fails.
        let scene = Scene { raw, vertices, indices, device };
        let flags = if options.robust { sys::RTC_SCENE_FLAG_ROBUST } else { sys::RTC_SCENE_FLAG_NONE };
        // SAFETY: `raw` is a live, not yet committed scene.
        unsafe {
            sys::rtcSetSceneFlags(raw, flags);
            sys::rtcSetSceneBuildQuality(raw, QUALITY);
        }
        scene.device.check("scene flags and build quality")?;
        if !mesh.is_empty() {
            scene.attach_triangles(mesh.positions.len(), mesh.len())?;
        }
        // SAFETY: `raw` is live and its geometry's buffers are owned by `scene`.
        unsafe { sys::rtcCommitScene(raw) };
        scene.device.check("rtcCommitScene")?;
        Ok(scene)
    }

    /// Creates the triangle geometry over the scene's own buffers and attaches it.
    fn attach_triangles(&self, vertex_count: usize, triangle_count: usize) -> Result<(), AccelError> {
        let device = &self.device;
        // SAFETY: the device is live.
        let geom = unsafe { sys::rtcNewGeometry(device.raw(), sys::RTC_GEOMETRY_TYPE_TRIANGLE) };
        if geom.is_null() {
            device.check("rtcNewGeometry")?;
            return Err(AccelError::Embree("rtcNewGeometry returned null".into()));
        }
        // SAFETY: `geom` is live. The buffers are heap allocations owned by `self` that are
        // never reallocated or written again and outlive the scene (dropped after its release);
        // the vertex buffer holds `vertex_count` 16-byte records (readable with 16-byte loads),
        // the index buffer `3 * triangle_count` u32s plus padding, all indices < vertex_count
        // (validated mesh). Attaching takes a reference, so our release leaves the scene's.
        unsafe {
            sys::rtcSetSharedGeometryBuffer(
                geom,
                sys::RTC_BUFFER_TYPE_VERTEX,
                0,
                sys::RTC_FORMAT_FLOAT3,
                self.vertices.as_ptr() as *const c_void,
                0,
                std::mem::size_of::<[f32; 4]>(),
                vertex_count,
            );
            sys::rtcSetSharedGeometryBuffer(
                geom,
                sys::RTC_BUFFER_TYPE_INDEX,
                0,
                sys::RTC_FORMAT_UINT3,
                self.indices.as_ptr() as *const c_void,
                0,
                3 * std::mem::size_of::<u32>(),
                triangle_count,
            );
            // Embree 4's default geometry mask is 1 (Embree 3's all ones): set it explicitly.
            sys::rtcSetGeometryMask(geom, u32::MAX);
            sys::rtcSetGeometryBuildQuality(geom, QUALITY);
            sys::rtcCommitGeometry(geom);
            sys::rtcAttachGeometry(self.raw, geom);
            sys::rtcReleaseGeometry(geom);
        }
        device.check("triangle geometry")
    }

    /// The raw handle of this committed scene, valid as long as `self` lives.
    pub fn raw(&self) -> sys::RTCScene {
        self.raw
    }

    /// Closest hit in `(t_min, t_max)` (`rtcIntersect1`).
    pub fn intersect(&self, ray: &Ray) -> Option<Hit> {
        let (tnear, tfar) = interval(ray)?;
        let mut rh = sys::RTCRayHit { ray: to_rtc_ray(ray, tnear, tfar), hit: empty_hit() };
        // SAFETY: `self.raw` is a live committed scene.
        unsafe { Query::new(false).intersect1(self.raw, &mut rh) };
        let hit = Hit { t: rh.ray.tfar, prim: rh.hit.primID, u: rh.hit.u, v: rh.hit.v };
        // A hit outside the ray's interval (never seen; Embree promises none) is dropped.
        let inside = hit.t >= ray.t_min && hit.t <= ray.t_max && hit.t.is_finite();
        (rh.hit.geomID != INVALID_ID && inside).then_some(hit)
    }

    /// Whether anything is hit in `(t_min, t_max)` (`rtcOccluded1` sets `tfar` to -inf then).
    pub fn occluded(&self, ray: &Ray) -> bool {
        let Some((tnear, tfar)) = interval(ray) else { return false };
        let mut r = to_rtc_ray(ray, tnear, tfar);
        // SAFETY: `self.raw` is a live committed scene.
        unsafe { Query::new(false).occluded1(self.raw, &mut r) };
        r.tfar == f32::NEG_INFINITY
    }
}

impl Drop for Scene {
    fn drop(&mut self) {
        // SAFETY: `self.raw` is live and ours; this releases the geometry too, before the
        // buffers and then the device (fields) are dropped.
        unsafe { sys::rtcReleaseScene(self.raw) };
    }
}

/// An Embree ray with all-ones mask, time 0, and the given closed interval.
pub fn to_rtc_ray(ray: &Ray, tnear: f32, tfar: f32) -> sys::RTCRay {
    sys::RTCRay {
        org_x: ray.origin.x,
        org_y: ray.origin.y,
        org_z: ray.origin.z,
        tnear,
        dir_x: ray.dir.x,
        dir_y: ray.dir.y,
        dir_z: ray.dir.z,
        time: 0.0,
        tfar,
        mask: u32::MAX,
        id: 0,
        flags: 0,
    }
}

fn empty_hit() -> sys::RTCHit {
    let mut hit = sys::RTCHit { geomID: INVALID_ID, primID: INVALID_ID, ..Default::default() };
    hit.instID.fill(INVALID_ID);
    hit
}

/// Embree's closed `[tnear, tfar]` equal to the ray's open `(t_min, t_max)`, or `None` if empty.
pub fn interval(ray: &Ray) -> Option<(f32, f32)> {
    let mut tnear = next_float_up(ray.t_min);
    if tnear > 0.0 && tnear < f32::MIN_POSITIVE {
        tnear = f32::MIN_POSITIVE; // a subnormal would read as 0 under denormals-are-zero
    }
    let tfar = next_float_down(ray.t_max);
    (tnear <= tfar).then_some((tnear, tfar))
}
