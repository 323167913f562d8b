//! libFuzzer target: a small glTF (or, when the bytes start `glTF`, a GLB) from arbitrary bytes.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| photonmap_fuzz::check_gltf(data));
