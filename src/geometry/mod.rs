//! Geometric primitives shared by every backend: rays, bounding boxes, triangle meshes and
//! robust ray-origin offsets.
//!
//! The offset rule follows pbrt-v4: every surface point carries a conservative bound on its
//! rounding error, and a new ray origin is moved off the surface along the geometric normal by
//! that bound (then one float further). Unlike a fixed epsilon this works the same at any world
//! scale and any distance from the origin.

mod aabb;
mod attributes;
mod mesh;
mod ray;

pub use aabb::{longest_axis, Aabb};
pub use attributes::{ShadingPoint, VertexAttributes};
pub use mesh::{MeshError, TriangleMesh};
pub use ray::{
    barycentric_error, gamma, next_float_down, next_float_up, offset_distance, offset_ray_origin, Ray,
};

pub use glam::Vec3;
