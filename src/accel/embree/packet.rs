//! Packet tracing for batches of coherent rays: closest hits by `rtcIntersect8` on `RTCRayHit8`
//! and occlusion by `rtcOccluded8` on `RTCRay8` (structure-of-arrays, 32-byte aligned) with a
//! valid mask, 8 rays at a time. A batch whose length is not a multiple of 8 leaves the tail lanes of its last packet
//! inactive (mask 0), and lanes whose interval is empty are inactive too.
//!
//! Eight lanes rather than sixteen: Embree traces 8-wide natively with AVX/AVX2 and emulates
//! other widths, so 8 is the packet size that is native on most x86-64 CPUs.

use super::api::{Query, INVALID_ID};
use super::scene::{interval, Scene};
use super::sys;
use crate::accel::Hit;
use crate::geometry::Ray;

/// Rays per packet.
pub const WIDTH: usize = 8;

/// Embree's valid mask for an 8-wide packet: -1 = active, 0 = inactive, 32-byte aligned.
#[repr(C, align(32))]
struct ValidMask([i32; WIDTH]);

// Embree requires the packet structures (and the mask) to be aligned to 32 bytes; bindgen
// carries `RTC_ALIGN(32)` over as `#[repr(align(32))]`, which these checks pin down.
const _: () = {
    assert!(std::mem::align_of::<sys::RTCRay8>() >= 32);
    assert!(std::mem::align_of::<sys::RTCRayHit8>() >= 32);
    assert!(std::mem::align_of::<ValidMask>() >= 32);
    assert!(std::mem::size_of::<sys::RTCRay8>() == 12 * 4 * WIDTH);
};

/// Fills the ray part of a packet from up to [`WIDTH`] rays and returns the valid mask.
fn load(rays: &[Ray], packet: &mut sys::RTCRay8) -> ValidMask {
    debug_assert!(rays.len() <= WIDTH);
    let mut valid = ValidMask([0; WIDTH]);
    for (lane, ray) in rays.iter().enumerate() {
        let Some((tnear, tfar)) = interval(ray) else { continue };
        valid.0[lane] = -1;
        packet.org_x[lane] = ray.origin.x;
        packet.org_y[lane] = ray.origin.y;
        packet.org_z[lane] = ray.origin.z;
        packet.dir_x[lane] = ray.dir.x;
        packet.dir_y[lane] = ray.dir.y;
        packet.dir_z[lane] = ray.dir.z;
        packet.tnear[lane] = tnear;
        packet.tfar[lane] = tfar;
        packet.mask[lane] = u32::MAX;
        packet.id[lane] = lane as u32;
    }
    valid
}

impl Scene {
    /// Closest hits for a batch, `hits[i]` for `rays[i]`, in packets of [`WIDTH`].
    pub fn intersect_batch(&self, rays: &[Ray], hits: &mut [Option<Hit>]) {
        assert_eq!(rays.len(), hits.len(), "one hit slot per ray");
        let mut query = Query::new(true);
        for (rays, hits) in rays.chunks(WIDTH).zip(hits.chunks_mut(WIDTH)) {
            let mut rh = sys::RTCRayHit8::default();
            let valid = load(rays, &mut rh.ray);
            rh.hit.geomID = [INVALID_ID; WIDTH];
            rh.hit.primID = [INVALID_ID; WIDTH];
            for level in rh.hit.instID.iter_mut() {
                *level = [INVALID_ID; WIDTH];
            }
            // SAFETY: `self.raw()` is a live committed scene; `valid` and `rh` are 32-byte
            // aligned (checked above) and every active lane holds a finite interval.
            unsafe { query.intersect8(valid.0.as_ptr(), self.raw(), &mut rh) };
            for (lane, hit) in hits.iter_mut().enumerate() {
                let found = valid.0[lane] != 0 && rh.hit.geomID[lane] != INVALID_ID;
                // A hit outside the ray's interval (never seen; Embree promises none) is dropped.
                let t = rh.ray.tfar[lane];
                let ray = &rays[lane];
                *hit = (found && t >= ray.t_min && t <= ray.t_max && t.is_finite()).then(|| Hit {
                    t: rh.ray.tfar[lane],
                    prim: self.scene_prim(rh.hit.geomID[lane], rh.hit.primID[lane]),
                    u: rh.hit.u[lane],
                    v: rh.hit.v[lane],
                });
            }
        }
    }

    /// Whether each ray of a batch is blocked in `(t_min, t_max)`, `blocked[i]` for `rays[i]`,
    /// in packets of [`WIDTH`] (`rtcOccluded8` sets an occluded lane's `tfar` to -inf).
    pub fn occluded_batch(&self, rays: &[Ray], blocked: &mut [bool]) {
        assert_eq!(rays.len(), blocked.len(), "one answer per ray");
        let mut query = Query::new(true);
        for (rays, blocked) in rays.chunks(WIDTH).zip(blocked.chunks_mut(WIDTH)) {
            let mut packet = sys::RTCRay8::default();
            let valid = load(rays, &mut packet);
            // SAFETY: `self.raw()` is a live committed scene; `valid` and `packet` are 32-byte
            // aligned (checked above) and every active lane holds a finite interval.
            unsafe { query.occluded8(valid.0.as_ptr(), self.raw(), &mut packet) };
            for (lane, b) in blocked.iter_mut().enumerate() {
                *b = valid.0[lane] != 0 && packet.tfar[lane] == f32::NEG_INFINITY;
            }
        }
    }
}
