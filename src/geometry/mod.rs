//! Geometric primitives shared by every backend: rays, bounding boxes, triangle meshes and
//! robust ray-origin offsets.
//!
//! The offset rule follows Wächter & Binder, "A Fast and Robust Method for Avoiding
//! Self-Intersection" (Ray Tracing Gems, ch. 6, 2019): a new ray origin is moved off the surface
//! along the geometric normal by a number of ULPs of each coordinate (integer arithmetic on the
//! float bits), with a small absolute floor near the origin. Unlike a fixed epsilon this works the
//! same at any world scale.

mod aabb;
mod mesh;
mod ray;

pub use aabb::Aabb;
pub use mesh::{MeshError, TriangleMesh};
pub use ray::{offset_ray_origin, Ray};

pub use glam::Vec3;
