//! TEMPORARY scaffold, replaced by the binned-SAH BVH.
use super::naive::Naive;
use super::{Accel, Hit};
use crate::geometry::{Ray, TriangleMesh};
pub struct Bvh(Naive);
impl Bvh {
    pub fn build(mesh: &TriangleMesh) -> Self {
        Bvh(Naive::new(mesh))
    }
}
impl Accel for Bvh {
    fn name(&self) -> &'static str {
        "bvh"
    }
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        self.0.intersect(ray)
    }
    fn occluded(&self, ray: &Ray) -> bool {
        self.0.occluded(ray)
    }
}
