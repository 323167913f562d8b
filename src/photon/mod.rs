//! Photon maps (placeholder).
pub mod kdtree;
