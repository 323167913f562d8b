//! Rendering many views and frames from one set of photon maps: the scene's named cameras
//! ([`crate::scene::SceneCamera`]), each at the frames a render-farm frame list names
//! ([`frames::parse_frames`]); which images that makes and their output names ([`plan`]);
//! the loop that renders them with the photon maps shared and writes each as it is done
//! ([`run`]); the record in each image's header that `--resume` checks ([`meta`]); and the
//! exact merge of partial films, passes rendered apart ([`merge`]).

pub mod frames;
pub mod merge;
pub mod meta;
pub mod plan;
pub mod run;
