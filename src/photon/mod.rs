//! Photon maps (Jensen, "Realistic Image Synthesis Using Photon Mapping", 2001, ch. 5-7).
//!
//! * [`trace`]: the photon pass. Photons leave the lights (split among them by power), bounce by
//!   Russian roulette, and are stored at diffuse and glossy hits, the first hit from the light
//!   excepted; one pass fills the indirect map, another the caustic map.
//! * [`map`]: a photon map and its radiance estimate (k nearest photons on a flattened disc,
//!   box, cone or Gaussian kernel: [`kernel`]), over the whole disc or over its
//!   [`footprint`], the part the surface at its centre fills.
//! * [`kdtree`]: the balanced point kd-tree under the maps and the precomputed irradiance
//!   (implicit, pointer-free, parallel build, k-NN with a flattened gather metric).
//! * [`irradiance`]: irradiance precomputed at a subset of the photons (Christensen 1999).
//! * [`pack`]: the bit-packing of the photon record.
//!
//! # Photon record
//!
//! Jensen's record is 28 bytes: position 3×f32, power as 4×u8 RGBE, incoming direction as
//! 2×u8 spherical θ/φ, and a 16-bit flag holding the split axis. Here it is **20 bytes**
//! ([`map::Photon`], `#[repr(C)]`, align 4, no padding):
//!
//! | field | encoding | bytes |
//! |-------|----------|-------|
//! | position | 3×f32 (the kd-tree needs exact coordinates) | 12 |
//! | incoming direction | octahedral 2×u16, [`pack::encode_dir_oct`] (error < 1e-4 rad, vs ≈ 0.6° for Jensen's 2×u8 θ/φ) | 4 |
//! | power, RGB maps | shared-exponent RGB9E5 of the power over a per-map power of two, [`pack::rgb9e5_encode`] (≤ max/512 per channel) | 4 |
//! | power, per-channel maps (the lecture's three maps) | the `f32` bits of the map's channel | 4 |
//! | split axis | not in the record: [`kdtree::KdTree`] keeps 2-bit codes for internal nodes only, in heap order | ≈ 0.03–0.06 amortised |
//!
//! With leaf buckets of [`kdtree::LEAF_SIZE`] = 8 items there are about n/4–n/8 internal
//! nodes, so the axis codes cost ≈ 0.03–0.06 B per photon (≈ 32–64 KiB for a million photons).
//! Compared with Jensen's 28 B that is ~29% less memory and bandwidth for the gather, which is
//! memory-bound.

pub mod footprint;
pub mod guide;
pub mod irradiance;
pub mod kdtree;
pub mod kernel;
pub mod map;
pub mod pack;
pub mod portal;
pub mod trace;
