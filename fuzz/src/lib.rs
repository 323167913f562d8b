//! What every fuzz target checks: loading the Cornell box with one of its three files replaced
//! by the fuzzer's bytes never panics, and either gives a sound scene or an error of one line
//! that starts with the file it is about (the rule of `tests/fuzz_inputs.rs`, which runs the
//! same check under proptest in CI).

use photonmap::scene::{Scene, SceneError};
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

const TOML: &str = include_str!("../../scenes/cornell/cornell.toml");
const OBJ: &str = include_str!("../../scenes/cornell/cornell.obj");
const MTL: &str = include_str!("../../scenes/cornell/cornell.mtl");
const FILES: [&str; 3] = ["cornell.toml", "cornell.obj", "cornell.mtl"];
const GLTF_BIN: &[u8] = include_bytes!("../../tests/data/gltf/quad.bin");

/// A private directory per process holding the Cornell box (the fuzzer overwrites one file of
/// it each run, the others stay as shipped).
fn dir() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let d = std::env::temp_dir().join(format!("photonmap-fuzz-{}", std::process::id()));
        std::fs::create_dir_all(&d).expect("create the fuzz directory");
        d
    })
}

/// Loads the Cornell box with `FILES[which]` replaced by `bytes` and panics (a finding) if the
/// loader breaks the rule.
pub fn check(which: usize, bytes: &[u8]) {
    let d = dir();
    for (i, (name, text)) in FILES.iter().zip([TOML, OBJ, MTL]).enumerate() {
        let content = if i == which { bytes } else { text.as_bytes() };
        std::fs::write(d.join(name), content).expect("write a fuzz input");
    }
    match Scene::load(d.join(FILES[0])) {
        Ok(scene) => sound(&scene),
        Err(e) => one_line_naming_a_file(&e),
    }
}

/// Loads the small glTF of `tests/data/gltf/` with its JSON (or GLB) replaced by `bytes`
/// (its buffer `quad.bin` beside it, as shipped) and panics if the loader breaks the rule.
pub fn check_gltf(bytes: &[u8]) {
    let d = dir();
    std::fs::write(d.join("quad.bin"), GLTF_BIN).expect("write the glTF buffer");
    let ext = if bytes.starts_with(b"glTF") { "glb" } else { "gltf" };
    let path = d.join(format!("quad.{ext}"));
    std::fs::write(&path, bytes).expect("write a fuzz input");
    match Scene::load(&path) {
        Ok(scene) => sound(&scene),
        Err(e) => one_line_naming_a_file(&e),
    }
}

fn sound(scene: &Scene) {
    if let Err(e) = scene.mesh.validate() {
        panic!("the loaded mesh does not validate: {e}");
    }
    assert_eq!(scene.tri_material.len(), scene.mesh.len(), "a material id per triangle");
    assert!(
        scene.tri_material.iter().all(|&m| (m as usize) < scene.materials.len()),
        "material ids in range"
    );
    let numbers = format!("{:?} {:?} {:?}", scene.camera, scene.materials, scene.lights);
    assert!(!numbers.contains("NaN") && !numbers.contains("inf"), "a non-finite number: {numbers}");
    if let Err(e) = scene.render.resolve(scene.camera.width, scene.camera.height) {
        assert!(!e.to_string().contains('\n'), "a render-settings error of several lines: {e}");
    }
}

fn one_line_naming_a_file(e: &SceneError) {
    let shown = e.to_string();
    assert!(!shown.contains('\n'), "an error of several lines: {shown:?}");
    let named = photonmap::scene::one_line(e.path().display());
    assert!(shown.starts_with(&named), "an error not naming its file {named:?} first: {shown:?}");
}
