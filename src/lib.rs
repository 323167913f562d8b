//! photonmap: a photon-mapping renderer (Jensen's two-pass method) with Debian's Embree or a
//! pure-Rust BVH for ray casting.
//!
//! Layout: [`geometry`] (rays, boxes, meshes, robust offsets), [`accel`] (ray-casting backends
//! behind one trait), [`scene`] (TOML scene files with OBJ/MTL geometry), [`material`] and
//! [`light`] (what surfaces and emitters do).
//!
//! All `unsafe` code lives in `accel::embree`; everything else is safe Rust.
#![deny(unsafe_code)]
// `!(x > 0.0)` is how this crate rejects NaN along with the out-of-range values; keep it.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod accel;
pub mod agree;
pub mod bench;
pub mod choice;
pub mod config;
pub mod converge;
pub mod film;
pub mod frame;
pub mod geometry;
pub mod integrator;
pub mod light;
pub mod material;
pub mod montecarlo;
pub mod photon;
pub mod plot;
pub mod sampling;
pub mod scene;
pub mod stats;
pub mod stress;
