//! The integration tests, one binary (each file below is a module; `cargo test --test all NAME::`
//! runs one file's tests). One binary instead of one per file: linking the library and its
//! dependencies into some thirty test executables was most of the suite's build time.

mod common;

mod accuracy;
mod agree_bvh;
mod agree_cutouts;
mod agree_scenes;
mod alpha;
mod bad_input;
mod batch;
mod bias;
mod caustic_aim;
mod chi_square;
mod commands;
mod emission;
mod environment;
mod fuzz_inputs;
mod glossy;
mod gltf;
mod golden;
mod guide;
mod kdtree_props;
mod merge;
mod monte_carlo;
mod path_tracer;
mod progressive;
mod savings;
mod shading;
mod slurm;
mod stress;
mod textures;
mod thin_lens;
mod transforms;
