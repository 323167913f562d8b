//! A committed Embree scene (`RTCScene`) holding one triangle geometry whose vertex and index
//! buffers are shared with Embree (`rtcSetSharedGeometryBuffer`) and owned by the scene, plus
//! the single-ray queries `rtcIntersect1` / `rtcOccluded1`.
//!
//! **Cut-outs.** With [`Cutouts`], the triangles with a cut-out material go into a second
//! geometry (ID 1, the others stay in ID 0) that has intersection and occlusion filter
//! functions (`rtcSetGeometryIntersectFilterFunction` / `OccludedFilterFunction`): they reject
//! (`valid[i] = 0`) every candidate hit on a transparent point, and Embree goes on looking. Each
//! geometry keeps the scene triangle index of its primitives, so [`Hit::prim`] stays the mesh's.
//! Without cut-outs there is one geometry, no filter and no index map.
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
use crate::accel::{AccelError, AccelOptions, Cutouts, Hit};
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
    /// Triangle indices, three per triangle, plus one padding element for the same rule
    /// (the triangles without a cut-out if there are cut-outs).
    indices: Vec<u32>,
    /// With cut-outs, the scene triangle of each primitive of geometry 0; empty: the identity.
    opaque_prims: Vec<u32>,
    /// With cut-outs, geometry 1's indices (as `indices`), its triangles and the opacity
    /// test; its address is the geometry's user pointer, read by [`cutout_filter`].
    filter: Option<Box<FilterData>>,
    /// Dropped after the scene is released (field order), keeping the device alive until then.
    device: Arc<Device>,
}

/// What the filter functions of the cut-out geometry read (through its user pointer).
struct FilterData {
    indices: Vec<u32>,
    /// The scene triangle of each primitive of the cut-out geometry.
    prims: Vec<u32>,
    cutouts: Cutouts,
}

// SAFETY: a committed Embree scene is documented as safe to query (rtcIntersect*/rtcOccluded*)
// from any number of threads at once, and `Scene` offers no way to modify it. The shared
// buffers are never written after the commit, and the scene is released only in `Drop`.
unsafe impl Send for Scene {}
// SAFETY: as above.
unsafe impl Sync for Scene {}

/// The build quality of every scene and its geometry: high, not Embree's default (medium).
/// Measured by the instructions inside Embree (`valgrind --tool=callgrind --toggle-collect='rtc*'
/// photonmap render SCENE --threads 1 --width 64 --height 64`): 2.8 % fewer on the 69 000-
/// triangle bunny, the same on the caustics box; the build of a million-triangle sphere
/// (`scripts/make_big_obj.py`) took as long (0.2-0.3 s) and the process's peak memory the same
/// (376 MB).
const QUALITY: sys::RTCBuildQuality = sys::RTC_BUILD_QUALITY_HIGH;

impl Scene {
    /// Builds and commits a scene for `mesh`. The mesh is validated here, next to the unsafe
    /// code that relies on it: Embree does not check indices. An empty mesh gives a valid empty
    /// scene.
    pub fn commit(
        device: Arc<Device>,
        mesh: &TriangleMesh,
        cutouts: Option<Cutouts>,
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
        vertices.shrink_to_fit();
        let packed = |prims: &[u32]| {
            let mut ix: Vec<u32> = prims.iter().flat_map(|&p| mesh.indices[p as usize]).collect();
            ix.push(0);
            ix.shrink_to_fit();
            ix
        };
        let (indices, opaque_prims, filter) = match cutouts.filter(|c| c.count() > 0) {
            None => {
                let mut indices: Vec<u32> = mesh.indices.iter().flatten().copied().collect();
                indices.push(0);
                indices.shrink_to_fit();
                (indices, Vec::new(), None)
            }
            Some(cutouts) => {
                let (cut, opaque): (Vec<u32>, Vec<u32>) =
                    (0..mesh.len() as u32).partition(|&p| cutouts.is_cutout(p));
                let data = FilterData { indices: packed(&cut), prims: cut, cutouts };
                (packed(&opaque), opaque, Some(Box::new(data)))
            }
        };
        // From here on, `Drop` releases the scene if anything fails.
        let scene = Scene { raw, vertices, indices, opaque_prims, filter, device };
        let flags = if options.robust { sys::RTC_SCENE_FLAG_ROBUST } else { sys::RTC_SCENE_FLAG_NONE };
        // SAFETY: `raw` is a live, not yet committed scene.
        unsafe {
            sys::rtcSetSceneFlags(raw, flags);
            sys::rtcSetSceneBuildQuality(raw, QUALITY);
        }
        scene.device.check("scene flags and build quality")?;
        let opaque_count = (scene.indices.len() - 1) / 3;
        if opaque_count > 0 {
            scene.attach_triangles(mesh.positions.len(), &scene.indices, None)?;
        }
        if let Some(data) = &scene.filter {
            scene.attach_triangles(mesh.positions.len(), &data.indices, Some(data))?;
        }
        // SAFETY: `raw` is live and its geometry's buffers are owned by `scene`.
        unsafe { sys::rtcCommitScene(raw) };
        scene.device.check("rtcCommitScene")?;
        Ok(scene)
    }

    /// Creates a triangle geometry over the scene's vertices and `indices` (owned by `self`, three
    /// per triangle plus one padding element) and attaches it: as geometry 0 without `filter`, as
    /// geometry 1 with `filter` as its user data and the cut-out filter functions.
    fn attach_triangles(
        &self,
        vertex_count: usize,
        indices: &[u32],
        filter: Option<&FilterData>,
    ) -> Result<(), AccelError> {
        let triangle_count = (indices.len() - 1) / 3;
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
        // The filter data is boxed and owned by `self` (its address is stable and outlives the
        // scene, which is released before the fields drop); `cutout_filter` only reads it and
        // never unwinds.
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
                indices.as_ptr() as *const c_void,
                0,
                3 * std::mem::size_of::<u32>(),
                triangle_count,
            );
            // Embree 4's default geometry mask is 1 (Embree 3's all ones): set it explicitly.
            sys::rtcSetGeometryMask(geom, u32::MAX);
            sys::rtcSetGeometryBuildQuality(geom, QUALITY);
            if let Some(data) = filter {
                sys::rtcSetGeometryUserData(geom, data as *const FilterData as *mut c_void);
                sys::rtcSetGeometryIntersectFilterFunction(geom, Some(cutout_filter));
                sys::rtcSetGeometryOccludedFilterFunction(geom, Some(cutout_filter));
            }
            sys::rtcCommitGeometry(geom);
            sys::rtcAttachGeometryByID(self.raw, geom, u32::from(filter.is_some()));
            sys::rtcReleaseGeometry(geom);
        }
        device.check("triangle geometry")
    }

    /// The scene triangle of primitive `prim` of geometry `geom` (as Embree reports a hit).
    #[inline]
    pub fn scene_prim(&self, geom: u32, prim: u32) -> u32 {
        match &self.filter {
            None => prim,
            Some(data) if geom == 1 => data.prims[prim as usize],
            Some(_) => self.opaque_prims[prim as usize],
        }
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
        // A hit outside the ray's interval (never seen; Embree promises none) is dropped.
        let t = rh.ray.tfar;
        let inside = t >= ray.t_min && t <= ray.t_max && t.is_finite();
        (rh.hit.geomID != INVALID_ID && inside).then(|| Hit {
            t,
            prim: self.scene_prim(rh.hit.geomID, rh.hit.primID),
            u: rh.hit.u,
            v: rh.hit.v,
        })
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

/// The intersection and occlusion filter of the cut-out geometry: rejects (`valid[i] = 0`) each
/// active candidate hit on a transparent point. Never unwinds into Embree: a panic of the
/// opacity test is caught and leaves the hit in place (the triangle counts as opaque there).
unsafe extern "C" fn cutout_filter(args: *const sys::RTCFilterFunctionNArguments) {
    let run = std::panic::AssertUnwindSafe(|| {
        // SAFETY: Embree passes valid arguments for the duration of the call: `valid` holds `N`
        // ints, `hit` is an `RTCHitN` of `N` lanes (structure of arrays: Ng x, y, z, then u, v,
        // primID, geomID, ... as `RTCHitN_u` etc. in rtcore_ray.h index it), and the user
        // pointer is the `FilterData` that `attach_triangles` set, alive as long as the scene.
        unsafe {
            let args = &*args;
            let n = args.N as usize;
            let data = &*(args.geometryUserPtr as *const FilterData);
            let valid = std::slice::from_raw_parts_mut(args.valid, n);
            let floats = args.hit as *const f32;
            let uints = args.hit as *const u32;
            for (i, lane) in valid.iter_mut().enumerate() {
                if *lane != -1 {
                    continue;
                }
                let (u, v) = (*floats.add(3 * n + i), *floats.add(4 * n + i));
                let prim = *uints.add(5 * n + i);
                if let Some(&p) = data.prims.get(prim as usize) {
                    if !data.cutouts.test(p, u, v) {
                        *lane = 0;
                    }
                }
            }
        }
    });
    let _ = std::panic::catch_unwind(run);
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
