//! The Embree 3 / Embree 4 query API differences, behind the one `cfg(embree3)` /
//! `cfg(embree4)` pair that `build.rs` sets from the installed headers.
//!
//! | | Embree 3 | Embree 4 |
//! |---|---|---|
//! | query call | `rtcIntersect1(scene, ctx, rayhit)` | `rtcIntersect1(scene, rayhit, args)` |
//! | per-query state | `RTCIntersectContext` (`rtcInitIntersectContext`) | `RTCRayQueryContext` + `RTCIntersectArguments` / `RTCOccludedArguments` |
//! | coherent flag | `RTC_INTERSECT_CONTEXT_FLAG_COHERENT` = 1 | `RTC_RAY_QUERY_FLAG_COHERENT` = 1 << 16 |
//! | default geometry mask | `0xFFFFFFFF` | `0x1` (we always set it explicitly) |
//!
//! The `rtcInit*` functions are `static inline` in the headers, so bindgen cannot bind them;
//! they are re-created here field by field, with compile-time size checks that fail the build if
//! a header's layout differs from the one this code was written against.

use super::sys;

/// Embree's `RTC_INVALID_GEOMETRY_ID` (a cast macro that bindgen does not translate).
pub const INVALID_ID: u32 = u32::MAX;

/// Per-call query state: Embree 3's intersect context.
#[cfg(embree3)]
pub struct Query {
    ctx: sys::RTCIntersectContext,
}

// Our layout expectations: flags, filter pointer, one instance ID (RTC_MAX_INSTANCE_LEVEL_COUNT
// 1, RTC_MIN_WIDTH 0 as Debian builds it).
#[cfg(embree3)]
const _: () = assert!(std::mem::size_of::<sys::RTCIntersectContext>() == 24);

#[cfg(embree3)]
impl Query {
    /// `rtcInitIntersectContext`, plus the coherent flag if asked for.
    pub fn new(coherent: bool) -> Self {
        let mut ctx = sys::RTCIntersectContext {
            flags: sys::RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT,
            filter: None,
            instID: [INVALID_ID; sys::RTC_MAX_INSTANCE_LEVEL_COUNT as usize],
        };
        if coherent {
            ctx.flags = sys::RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
        }
        Query { ctx }
    }

    /// # Safety
    /// `scene` must be a live, committed scene.
    pub unsafe fn intersect1(&mut self, scene: sys::RTCScene, rayhit: &mut sys::RTCRayHit) {
        // SAFETY: the caller guarantees the scene; the context and ray are valid for the call.
        unsafe { sys::rtcIntersect1(scene, &mut self.ctx, rayhit) }
    }

    /// # Safety
    /// `scene` must be a live, committed scene.
    pub unsafe fn occluded1(&mut self, scene: sys::RTCScene, ray: &mut sys::RTCRay) {
        // SAFETY: as for `intersect1`.
        unsafe { sys::rtcOccluded1(scene, &mut self.ctx, ray) }
    }

    /// # Safety
    /// `scene` must be a live, committed scene; `valid` must point to 8 ints aligned to 32 bytes.
    pub unsafe fn intersect8(&mut self, valid: *const i32, scene: sys::RTCScene, rh: &mut sys::RTCRayHit8) {
        // SAFETY: the caller guarantees scene and mask; `RTCRayHit8` is 32-byte aligned by type.
        unsafe { sys::rtcIntersect8(valid, scene, &mut self.ctx, rh) }
    }

    /// # Safety
    /// `scene` must be a live, committed scene; `valid` must point to 8 ints aligned to 32 bytes.
    pub unsafe fn occluded8(&mut self, valid: *const i32, scene: sys::RTCScene, ray: &mut sys::RTCRay8) {
        // SAFETY: the caller guarantees scene and mask; `RTCRay8` is 32-byte aligned by type.
        unsafe { sys::rtcOccluded8(valid, scene, &mut self.ctx, ray) }
    }
}

/// Per-call query state: Embree 4's ray-query context and argument structs.
#[cfg(embree4)]
pub struct Query {
    ctx: sys::RTCRayQueryContext,
    iargs: sys::RTCIntersectArguments,
    oargs: sys::RTCOccludedArguments,
}

// Instance stack of one level (+ instPrimID with RTC_GEOMETRY_INSTANCE_ARRAY, as Debian 13
// builds it); the argument structs are flags, feature mask and three pointers (RTC_MIN_WIDTH 0).
#[cfg(embree4)]
const _: () = {
    let levels = sys::RTC_MAX_INSTANCE_LEVEL_COUNT as usize;
    assert!(std::mem::size_of::<sys::RTCRayQueryContext>() == 8 * levels);
    assert!(std::mem::size_of::<sys::RTCIntersectArguments>() == 32);
    assert!(std::mem::size_of::<sys::RTCOccludedArguments>() == 32);
};

#[cfg(embree4)]
impl Query {
    /// `rtcInitRayQueryContext`, `rtcInitIntersectArguments` and `rtcInitOccludedArguments`,
    /// plus the coherent flag if asked for.
    pub fn new(coherent: bool) -> Self {
        // `Default` zeroes every field (the instance stack size, if configured); the instance
        // IDs and instance primitive IDs become invalid, as in `rtcInitRayQueryContext`.
        let mut ctx = sys::RTCRayQueryContext::default();
        ctx.instID.fill(INVALID_ID);
        ctx.instPrimID.fill(INVALID_ID);
        let flags =
            if coherent { sys::RTC_RAY_QUERY_FLAG_COHERENT } else { sys::RTC_RAY_QUERY_FLAG_INCOHERENT };
        let iargs = sys::RTCIntersectArguments {
            flags,
            feature_mask: sys::RTC_FEATURE_FLAG_ALL,
            context: std::ptr::null_mut(),
            filter: None,
            intersect: None,
        };
        let oargs = sys::RTCOccludedArguments {
            flags,
            feature_mask: sys::RTC_FEATURE_FLAG_ALL,
            context: std::ptr::null_mut(),
            filter: None,
            occluded: None,
        };
        Query { ctx, iargs, oargs }
    }

    /// The argument structs point at `ctx`; set just before each call, as `self` may have moved.
    fn link(&mut self) {
        self.iargs.context = &mut self.ctx;
        self.oargs.context = &mut self.ctx;
    }

    /// # Safety
    /// `scene` must be a live, committed scene.
    pub unsafe fn intersect1(&mut self, scene: sys::RTCScene, rayhit: &mut sys::RTCRayHit) {
        self.link();
        // SAFETY: the caller guarantees the scene; arguments, context and ray are valid and
        // exclusively borrowed for the call.
        unsafe { sys::rtcIntersect1(scene, rayhit, &mut self.iargs) }
    }

    /// # Safety
    /// `scene` must be a live, committed scene.
    pub unsafe fn occluded1(&mut self, scene: sys::RTCScene, ray: &mut sys::RTCRay) {
        self.link();
        // SAFETY: as for `intersect1`.
        unsafe { sys::rtcOccluded1(scene, ray, &mut self.oargs) }
    }

    /// # Safety
    /// `scene` must be a live, committed scene; `valid` must point to 8 ints aligned to 32 bytes.
    pub unsafe fn intersect8(&mut self, valid: *const i32, scene: sys::RTCScene, rh: &mut sys::RTCRayHit8) {
        self.link();
        // SAFETY: the caller guarantees scene and mask; `RTCRayHit8` is 32-byte aligned by type.
        unsafe { sys::rtcIntersect8(valid, scene, rh, &mut self.iargs) }
    }

    /// # Safety
    /// `scene` must be a live, committed scene; `valid` must point to 8 ints aligned to 32 bytes.
    pub unsafe fn occluded8(&mut self, valid: *const i32, scene: sys::RTCScene, ray: &mut sys::RTCRay8) {
        self.link();
        // SAFETY: the caller guarantees scene and mask; `RTCRay8` is 32-byte aligned by type.
        unsafe { sys::rtcOccluded8(valid, scene, ray, &mut self.oargs) }
    }
}
