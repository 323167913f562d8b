//! Rendering many views and frames from one set of photon maps: the scene's named cameras
//! ([`crate::scene::SceneCamera`]), each at the frames a render-farm frame list names
//! ([`frames::parse_frames`]).

pub mod frames;
