//! libFuzzer target: the Cornell box with its OBJ file replaced by arbitrary bytes.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| photonmap_fuzz::check(1, data));
