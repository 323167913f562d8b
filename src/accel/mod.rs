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
    /// Validates the mesh and builds the requested backend (and only that one).
    pub fn build(kind: AccelKind, mesh: &TriangleMesh, options: AccelOptions) -> Result<Self, AccelError> {
        mesh.validate()?;
        match kind {
            #[cfg(feature = "embree")]
            AccelKind::Embree => Ok(AnyAccel::Embree(embree::EmbreeAccel::build(mesh, options)?)),
            #[cfg(not(feature = "embree"))]
            AccelKind::Embree => {
                let _ = options; // only Embree uses the options
                Err(AccelError::EmbreeNotBuilt)
            }
            AccelKind::Bvh => Ok(AnyAccel::Bvh(bvh::Bvh::build(mesh))),
            AccelKind::Naive => Ok(AnyAccel::Naive(naive::Naive::new(mesh))),
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
