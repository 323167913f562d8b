//! The frame of a render: what the photon pass and every integrator stand on. The scene, its
//! accelerator and its lights ([`Frame`]); the surface point a ray reaches ([`SurfaceHit`]);
//! the camera's samples ([`camera`]); the walk through mirrors and glass ([`specular`]); direct
//! light by shadow rays ([`direct`]); per-thread counters ([`Counters`]) and progress reports
//! ([`Progress`]).

pub mod camera;
pub mod direct;
pub mod hit;
pub mod specular;

pub use hit::SurfaceHit;

use crate::accel::{Accel, Hit};
use crate::geometry::Ray;
use crate::light::LightSet;
use crate::scene::{Camera, Scene};
use crate::stats::RayCounts;

/// What every stage of a render reads, shared by all threads.
pub struct Frame<'a, A: Accel> {
    pub scene: &'a Scene,
    pub accel: &'a A,
    pub lights: &'a LightSet,
    /// The camera of the image being rendered, at the render's resolution.
    pub camera: Camera,
    /// Every view the photon stages serve: all the images a batch renders from the same photon
    /// maps (the guide's pilot looks through them, and a portal's inside is the side of the
    /// first one's eye); for one image, its camera alone. Never empty.
    pub views: &'a [Camera],
}

impl<'a, A: Accel> Frame<'a, A> {
    /// Closest surface along `ray`, with a usable normal (degenerate triangles are skipped as
    /// misses, which they are for every backend).
    #[inline]
    pub fn trace(&self, ray: &Ray) -> Option<SurfaceHit> {
        self.surface(self.accel.intersect(ray)?)
    }

    /// The surface point of a backend's hit (`None` on a degenerate triangle).
    #[inline]
    pub fn surface(&self, hit: Hit) -> Option<SurfaceHit> {
        let n = self.scene.mesh.normal(hit.prim)?;
        let (p, err) = self.scene.mesh.point_and_error(hit.prim, hit.u, hit.v);
        Some(SurfaceHit { p, err, n, prim: hit.prim, t: hit.t })
    }
}

/// Per-thread counters, summed at the end (no atomics in hot loops).
#[derive(Clone, Copy, Debug, Default)]
pub struct Counters {
    pub rays: RayCounts,
    /// Photon-map (and precomputed-irradiance) lookups.
    pub queries: u64,
    /// Camera samples whose radiance was NaN or infinite (dropped).
    pub nonfinite: u64,
}

impl std::ops::AddAssign for Counters {
    fn add_assign(&mut self, o: Counters) {
        self.rays += o.rays;
        self.queries += o.queries;
        self.nonfinite += o.nonfinite;
    }
}

/// Reports progress of long stages (a no-op implementation is fine).
pub trait Progress: Sync {
    /// A stage of `total` units begins.
    fn start(&self, _stage: &str, _total: u64) {}
    /// `n` more units are done.
    fn advance(&self, _n: u64) {}
    /// The stage is over.
    fn finish(&self) {}
}

/// Progress that reports nothing.
pub struct Quiet;
impl Progress for Quiet {}
