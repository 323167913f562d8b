//! Ray-casting backends behind one interface.
//!
//! Two accelerators answer the same two questions, *what does this ray hit first* and *is this
//! segment blocked*: Debian's Embree (feature `embree`, the default) through the safe wrapper in
//! [`embree`], and a pure-Rust binned-SAH BVH with a watertight triangle test in [`bvh`]. A
//! brute-force [`naive::Naive`] is the ground truth for tests. The rest of the renderer is written
//! against [`Accel`] and monomorphised once per backend through [`dispatch!`](crate::dispatch).
//!
//! [`Hit`] is minimal (distance, triangle, barycentrics): normals and materials come from shared
//! code so the backends cannot drift apart.

pub mod bvh;
#[cfg(feature = "embree")]
pub mod embree; // the Embree helper adds src/accel/embree/
pub mod naive;
pub mod triangle;

use crate::geometry::{MeshError, Ray, TriangleMesh};
use std::sync::Arc;

/// The first hit along a ray. The point is `(1 - u - v) v0 + u v1 + v v2` of triangle `prim`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub t: f32,
    pub prim: u32,
    pub u: f32,
    pub v: f32,
}

/// A ray-casting backend over one triangle mesh. Implementations are immutable once built and
/// safe to query from many threads at once.
pub trait Accel: Send + Sync {
    /// Short name for reports (`"embree"`, `"bvh"`, `"naive"`).
    fn name(&self) -> &'static str;

    /// The closest hit with `t` strictly inside `(ray.t_min, ray.t_max)`, or `None`.
    fn intersect(&self, ray: &Ray) -> Option<Hit>;

    /// Whether any triangle is hit with `t` inside `(ray.t_min, ray.t_max)`; may stop at the first.
    fn occluded(&self, ray: &Ray) -> bool;

    /// Closest hits of a batch of coherent rays (e.g. a tile of camera rays), `hits[i]` for
    /// `rays[i]`. Backends with packet tracing override this.
    fn intersect_batch(&self, rays: &[Ray], hits: &mut [Option<Hit>]) {
        assert_eq!(rays.len(), hits.len(), "one hit slot per ray");
        for (r, h) in rays.iter().zip(hits.iter_mut()) {
            *h = self.intersect(r);
        }
    }

    /// Whether each ray of a batch of coherent rays (e.g. a pixel's shadow rays) is blocked,
    /// `blocked[i]` for `rays[i]`, as [`Accel::occluded`] says. Backends with packet tracing
    /// override this.
    fn occluded_batch(&self, rays: &[Ray], blocked: &mut [bool]) {
        assert_eq!(rays.len(), blocked.len(), "one answer per ray");
        for (r, b) in rays.iter().zip(blocked.iter_mut()) {
            *b = self.occluded(r);
        }
    }
}

crate::choice! {
    /// Which backend to build.
    pub enum AccelKind {
        /// Intel Embree through the system library (the default when built with the `embree`
        /// feature).
        Embree = "embree",
        /// The pure-Rust BVH.
        Bvh = "bvh",
        /// Brute force; for tiny scenes and tests.
        Naive = "naive",
    }
}

impl AccelKind {
    /// Embree when the crate was built with it, otherwise the BVH.
    pub fn default_kind() -> Self {
        if cfg!(feature = "embree") {
            AccelKind::Embree
        } else {
            AccelKind::Bvh
        }
    }
}

/// "Is triangle `prim` opaque at barycentrics `(u, v)`?" (the convention of [`Hit`]).
pub type Opacity = dyn Fn(u32, f32, f32) -> bool + Send + Sync;

/// Alpha cut-outs (leaves, fences): which triangles have a cut-out material, and a test of
/// whether a point of one of them is opaque. Every backend treats a transparent point as if the
/// triangle were not there, for closest hits and occlusion alike: Embree through intersection
/// filter functions on a second geometry holding the cut-out triangles, the BVH and brute force
/// by the same test after their triangle test. Without cut-outs (`None` to
/// [`AnyAccel::build`]) no filter is installed and nothing is evaluated. Cheap to clone.
#[derive(Clone)]
pub struct Cutouts {
    /// A bit per triangle: set if it has a cut-out material.
    bits: Arc<[u64]>,
    count: usize,
    opaque: Arc<Opacity>,
}

impl Cutouts {
    /// Cut-outs on the triangles `is_cutout` marks (one flag per triangle of the mesh), tested
    /// by `opaque`, which is only called for marked triangles.
    pub fn new(is_cutout: &[bool], opaque: Arc<Opacity>) -> Cutouts {
        let mut bits = vec![0u64; is_cutout.len().div_ceil(64)];
        for (i, _) in is_cutout.iter().enumerate().filter(|(_, &c)| c) {
            bits[i / 64] |= 1 << (i % 64);
        }
        let count = is_cutout.iter().filter(|&&c| c).count();
        Cutouts { bits: bits.into(), count, opaque }
    }

    /// Whether triangle `prim` has a cut-out material (false past the end).
    #[inline]
    pub fn is_cutout(&self, prim: u32) -> bool {
        self.bits.get(prim as usize / 64).is_some_and(|w| w >> (prim % 64) & 1 != 0)
    }

    /// Number of triangles with a cut-out material.
    pub fn count(&self) -> usize {
        self.count
    }

    /// Whether the point `(u, v)` of triangle `prim` stops rays: always for a triangle without
    /// a cut-out, else as the opacity test says.
    #[inline]
    pub fn opaque(&self, prim: u32, u: f32, v: f32) -> bool {
        !self.is_cutout(prim) || (self.opaque)(prim, u, v)
    }

    /// The opacity test alone (for triangles known to be cut-outs).
    #[inline]
    pub fn test(&self, prim: u32, u: f32, v: f32) -> bool {
        (self.opaque)(prim, u, v)
    }
}

impl std::fmt::Debug for Cutouts {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Cutouts({} triangles)", self.count)
    }
}

/// Options shared by the backends. The BVH's triangle test is always watertight, so `robust`
/// only changes Embree (its `RTC_SCENE_FLAG_ROBUST`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AccelOptions {
    pub robust: bool,
}

impl Default for AccelOptions {
    fn default() -> Self {
        AccelOptions { robust: true }
    }
}

/// Why a backend could not be built.
#[derive(Debug, thiserror::Error)]
pub enum AccelError {
    #[error("invalid mesh: {0}")]
    Mesh(#[from] MeshError),
    #[error("Embree: {0}")]
    Embree(String),
    #[error("this build has no Embree (built without the `embree` feature); use --accel bvh")]
    EmbreeNotBuilt,
}

/// Any backend, built at run time from an [`AccelKind`]. Use [`dispatch!`](crate::dispatch) to
/// run a generic function on the concrete type, so inner loops are monomorphised.
pub enum AnyAccel {
    #[cfg(feature = "embree")]
    Embree(embree::EmbreeAccel),
    Bvh(bvh::Bvh),
    Naive(naive::Naive),
}

impl AnyAccel {
    /// Validates the mesh and builds the requested backend (and only that one), with the
    /// scene's alpha cut-outs if it has any (a [`Cutouts`] marking no triangle counts as none).
    pub fn build(
        kind: AccelKind,
        mesh: &TriangleMesh,
        cutouts: Option<&Cutouts>,
        options: AccelOptions,
    ) -> Result<Self, AccelError> {
        mesh.validate()?;
        let cutouts = cutouts.filter(|c| c.count() > 0).cloned();
        match kind {
            #[cfg(feature = "embree")]
            AccelKind::Embree => {
                Ok(AnyAccel::Embree(embree::EmbreeAccel::build_with_cutouts(mesh, cutouts, options)?))
            }
            #[cfg(not(feature = "embree"))]
            AccelKind::Embree => {
                let _ = options; // only Embree uses the options
                Err(AccelError::EmbreeNotBuilt)
            }
            AccelKind::Bvh => Ok(AnyAccel::Bvh(bvh::Bvh::build_with_cutouts(mesh, cutouts))),
            AccelKind::Naive => Ok(AnyAccel::Naive(naive::Naive::with_cutouts(mesh, cutouts))),
        }
    }

    pub fn name(&self) -> &'static str {
        crate::dispatch!(self, a => a.name())
    }
}

/// Runs `$body` with `$a` bound to the concrete accelerator inside an [`AnyAccel`], so that
/// generic code is instantiated once per backend: `dispatch!(any, a => render(a, &scene))`.
#[macro_export]
macro_rules! dispatch {
    ($any:expr, $a:ident => $body:expr) => {
        match $any {
            #[cfg(feature = "embree")]
            $crate::accel::AnyAccel::Embree($a) => $body,
            $crate::accel::AnyAccel::Bvh($a) => $body,
            $crate::accel::AnyAccel::Naive($a) => $body,
        }
    };
}

/// Prepares the calling thread for tracing: with Embree, sets flush-to-zero and
/// denormals-are-zero as Embree recommends. Call it on every worker thread (the renderer does
/// so in its rayon pool's start handler).
pub fn init_tracing_thread() {
    #[cfg(feature = "embree")]
    embree::set_flush_denormals();
}
