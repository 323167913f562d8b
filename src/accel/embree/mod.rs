//! Intel Embree (3 or 4, whichever `build.rs` found) behind the [`Accel`] trait.
//!
//! This module wraps Embree's C API (`rtcore.h`): devices (`RTCDevice`, `device`), committed
//! scenes with one shared-buffer triangle geometry (`RTCScene`, `scene`), single-ray queries
//! (`rtcIntersect1` / `rtcOccluded1`) and 8-wide packets of closest-hit queries (`rtcIntersect8`,
//! `packet`), with alpha cut-outs as intersection filter functions on a second geometry
//! (`scene`). The version differences live in `api`, the raw bindings in `sys`.
//!
//! All of the crate's `unsafe` code is in this module; every block states why it is sound.
//!
//! **One device per accelerator.** Each [`EmbreeAccel`] creates its own `RTCDevice`. Embree
//! reports errors per device (and `rtcGetDeviceError` per thread), so a private device makes
//! every error message belong to the build that caused it, also when tests or tools build
//! several scenes concurrently; dropping the accelerator frees everything it used. A renderer
//! builds one accelerator per scene, so the cost of a device (a few milliseconds) is paid once.
#![allow(unsafe_code)]

mod api;
mod device;
mod packet;
mod scene;
mod sys;
#[cfg(test)]
mod tests;

use super::{Accel, AccelError, AccelOptions, Cutouts, Hit};
use crate::geometry::{Ray, TriangleMesh};
use device::Device;
use scene::Scene;
use std::sync::Arc;

/// Embree configuration string for the devices we create.
const DEVICE_CONFIG: &std::ffi::CStr = c"verbose=0";

/// Embree's version, as read from the headers the bindings were generated from (`"3.13.5"`).
pub fn version() -> &'static str {
    env!("PHOTONMAP_EMBREE_VERSION")
}

/// A committed Embree scene over one triangle mesh, with its own device. Immutable and safe to
/// query from many threads at once.
pub struct EmbreeAccel {
    scene: Scene,
}

impl EmbreeAccel {
    /// Validates `mesh` (Embree itself does not check indices), copies its vertices and
    /// indices into buffers shared with Embree, and commits a scene at Embree's medium build
    /// quality with, if `options.robust`, `RTC_SCENE_FLAG_ROBUST`. An empty mesh gives an empty
    /// scene that every ray misses.
    pub fn build(mesh: &TriangleMesh, options: AccelOptions) -> Result<EmbreeAccel, AccelError> {
        EmbreeAccel::build_with_cutouts(mesh, None, options)
    }

    /// [`EmbreeAccel::build`] with alpha cut-outs: the cut-out triangles get a geometry of
    /// their own with intersection and occlusion filters (see [`Cutouts`]).
    pub fn build_with_cutouts(
        mesh: &TriangleMesh,
        cutouts: Option<Cutouts>,
        options: AccelOptions,
    ) -> Result<EmbreeAccel, AccelError> {
        let device = Arc::new(Device::new(DEVICE_CONFIG)?);
        let scene = Scene::commit(device, mesh, cutouts, options)?;
        Ok(EmbreeAccel { scene })
    }
}

impl Accel for EmbreeAccel {
    fn name(&self) -> &'static str {
        "embree"
    }

    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        self.scene.intersect(ray)
    }

    fn occluded(&self, ray: &Ray) -> bool {
        self.scene.occluded(ray)
    }

    fn intersect_batch(&self, rays: &[Ray], hits: &mut [Option<Hit>]) {
        self.scene.intersect_batch(rays, hits)
    }

    fn occluded_batch(&self, rays: &[Ray], blocked: &mut [bool]) {
        self.scene.occluded_batch(rays, blocked)
    }
}

/// Sets flush-to-zero and denormals-are-zero in the calling thread's MXCSR, as Embree
/// recommends for every thread that traces rays (denormals slow its traversal down a lot).
/// A no-op on targets other than x86-64.
pub fn set_flush_denormals() {
    #[cfg(target_arch = "x86_64")]
    {
        // `_mm_getcsr`/`_mm_setcsr` are deprecated because changing the floating-point
        // environment can surprise the optimiser (it assumes the default mode when it folds
        // constants). FTZ/DAZ only affect subnormal results and inputs, which is what we ask for.
        #[allow(deprecated)]
        use std::arch::x86_64::{_mm_getcsr, _mm_setcsr};
        const FTZ_DAZ: u32 = 0x8000 | 0x0040;
        // SAFETY: SSE is part of the x86-64 baseline; reading and writing MXCSR has no memory
        // effects, and setting FTZ (bit 15) and DAZ (bit 6) leaves every other control bit as is.
        #[allow(deprecated)]
        unsafe {
            _mm_setcsr(_mm_getcsr() | FTZ_DAZ)
        };
    }
}
