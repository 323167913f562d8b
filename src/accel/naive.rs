//! Brute force: every ray against every triangle. Kept as the ground truth of the agreement
//! tests (Mitsuba's `ray_intersect_naive` plays the same role).

use super::triangle::WatertightRay;
use super::{Accel, Cutouts, Hit};
use crate::geometry::{Ray, TriangleMesh};

/// Tests every triangle; O(n) per ray, for small scenes and tests only.
pub struct Naive {
    mesh: TriangleMesh,
    cutouts: Option<Cutouts>,
}

impl Naive {
    pub fn new(mesh: &TriangleMesh) -> Self {
        Naive { mesh: mesh.clone(), cutouts: None }
    }

    /// With alpha cut-outs: a hit on a transparent point is no hit.
    pub fn with_cutouts(mesh: &TriangleMesh, cutouts: Option<Cutouts>) -> Self {
        Naive { mesh: mesh.clone(), cutouts: cutouts.filter(|c| c.count() > 0) }
    }

    #[inline]
    fn opaque(&self, prim: u32, u: f32, v: f32) -> bool {
        self.cutouts.as_ref().is_none_or(|c| c.opaque(prim, u, v))
    }
}

impl Accel for Naive {
    fn name(&self) -> &'static str {
        "naive"
    }

    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        let wr = WatertightRay::new(ray.origin, ray.dir);
        let mut best: Option<Hit> = None;
        let mut t_max = ray.t_max;
        for prim in 0..self.mesh.len() as u32 {
            let [a, b, c] = self.mesh.triangle(prim);
            if let Some(h) = wr.intersect(a, b, c, ray.t_min, t_max).filter(|h| self.opaque(prim, h.u, h.v)) {
                t_max = h.t;
                best = Some(Hit { t: h.t, prim, u: h.u, v: h.v });
            }
        }
        best
    }

    fn occluded(&self, ray: &Ray) -> bool {
        let wr = WatertightRay::new(ray.origin, ray.dir);
        (0..self.mesh.len() as u32).any(|prim| {
            let [a, b, c] = self.mesh.triangle(prim);
            wr.intersect(a, b, c, ray.t_min, ray.t_max).is_some_and(|h| self.opaque(prim, h.u, h.v))
        })
    }
}
