//! The surface point a ray reaches, and rays leaving it.

use crate::geometry::offset_ray_origin;
use crate::material::face_forward;
use glam::Vec3;

/// A surface point reached by a ray.
#[derive(Clone, Copy, Debug)]
pub struct SurfaceHit {
    pub p: Vec3,
    /// Bound on the rounding error of `p`, for robust ray origins.
    pub err: Vec3,
    /// Unit geometric normal (front side as wound).
    pub n: Vec3,
    pub prim: u32,
    pub t: f32,
}

impl SurfaceHit {
    /// A robust origin for a ray leaving this point toward `w`.
    #[inline]
    pub fn spawn(&self, w: Vec3) -> Vec3 {
        offset_ray_origin(self.p, self.err, face_forward(self.n, w))
    }
}
