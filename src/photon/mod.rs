//! Photon maps (Jensen, "Realistic Image Synthesis Using Photon Mapping", 2001, ch. 6).
//!
//! So far: [`kdtree`], a generic balanced point kd-tree (implicit, pointer-free, parallel build,
//! k-NN with a flattened gather metric), and [`pack`], the bit-packing helpers for the photon
//! record designed below.
//!
//! # Photon record (design note)
//!
//! Jensen's record is 28 bytes: position 3×f32, power as 4×u8 RGBE, incoming direction as
//! 2×u8 spherical θ/φ, and a 16-bit flag holding the split axis. The plan here is **20 bytes**:
//!
//! | field | encoding | bytes |
//! |-------|----------|-------|
//! | position | 3×f32 (the kd-tree needs exact coordinates) | 12 |
//! | incoming direction | octahedral 2×u16, [`pack::encode_dir_oct`] (error < 1e-4 rad, vs ≈ 0.6° for Jensen's 2×u8 θ/φ) | 4 |
//! | power, RGB mode | shared-exponent RGB9E5, [`pack::rgb9e5_encode`] (≤ max/512 per channel) | 4 |
//! | power, per-channel (spectral/hero) mode | all photons of a pass carry equal power, so only the channel index (u8) is stored and the common power lives in the map; or f32 if powers differ (then 21 → padded) | 1–4 |
//! | split axis | not in the record: [`kdtree::KdTree`] keeps 2-bit codes for internal nodes only, in heap order | ≈ 0.03–0.06 amortised |
//!
//! So 20 B per photon in RGB mode (`#[repr(C)] struct { pos: [f32; 3], dir: u32, power: u32 }`,
//! align 4, no padding), ≤ 20 B in per-channel mode, plus the tree's 2 bits per *internal* node:
//! with leaf buckets of [`kdtree::LEAF_SIZE`] = 8 items there are about n/4–n/8 internal nodes,
//! i.e. ≈ 0.03–0.06 B per photon (≈ 32–64 KiB for a million photons). Compared with Jensen's
//! 28 B that is ~29% less memory and bandwidth for the gather, which is memory-bound.
//! (Putting the 2-bit axis in the record instead, e.g. 2×15-bit octahedral + 2 bits, would give
//! exactly 20 B; not worth it, since the separate code array is tiny and stays in cache.)

pub mod irradiance;
pub mod kdtree;
pub mod map;
pub mod pack;
pub mod trace;
