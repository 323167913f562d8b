//! photonmap: a photon-mapping renderer (Jensen's two-pass method) with Debian's Embree or a
//! pure-Rust BVH for ray casting.
//!
//! Layout, from the bottom up (each layer imports only those below it; `docs/ARCHITECTURE.md`
//! draws it):
//!
//! * [`geometry`] (rays, boxes, meshes, robust offsets), [`sampling`] (warps, distributions,
//!   low-discrepancy sequences, seeds), [`choice`](mod@choice) (enums chosen by name), [`film`] (images,
//!   EXR/PNG, error metrics), [`stats`] (what a render reports), [`texture`] (image textures);
//! * [`accel`] (ray casting: Embree, the BVH, brute force, behind one trait), [`material`],
//!   [`light`] (the lights and the [`light::LightSet`] renders sample), [`config`] (settings
//!   resolved into a per-integrator config), [`scene`] (TOML scene files with OBJ/MTL
//!   geometry);
//! * [`frame`]: what the photon pass and every integrator stand on (scene, accelerator and
//!   lights together, surface hits, camera samples, the specular walk, direct light);
//! * [`photon`]: the photon pass, the photon maps and their kd-tree, precomputed irradiance;
//! * [`integrator`]: two-pass photon mapping, progressive photon mapping, the path tracer, and
//!   the pass loop they share;
//! * [`batch`]: many views and frames rendered from one set of photon maps (frame lists);
//! * [`tools`]: what measures the renderer (agreement of backends, stress suite, error against
//!   time, speed, the lecture's Monte Carlo examples).
//!
//! All `unsafe` code lives in `accel::embree`; everything else is safe Rust.
#![deny(unsafe_code)]
// `!(x > 0.0)` is how this crate rejects NaN along with the out-of-range values; keep it.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod accel;
pub mod batch;
pub mod choice;
pub mod config;
pub mod film;
pub mod frame;
pub mod geometry;
pub mod integrator;
pub mod light;
pub mod material;
pub mod photon;
pub mod sampling;
pub mod scene;
pub mod stats;
pub mod texture;
pub mod tools;
