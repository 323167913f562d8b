//! Helpers shared by the integration tests that render the canonical scenes.

use photonmap::config::RenderSettings;
use photonmap::film::Film;
use photonmap::frame::Quiet;
use photonmap::integrator::{render_scene, RenderOutput};
use photonmap::scene::Scene;
use std::path::Path;

/// The shipped scene `scenes/<name>/<name>.toml`.
pub fn scene(name: &str) -> Scene {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    Scene::load(root.join("scenes").join(name).join(format!("{name}.toml"))).unwrap()
}

/// The 64x64 reference `tests/data/refs/<name>-64.exr`.
pub fn reference(name: &str) -> Film {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    Film::read_exr(&root.join("tests/data/refs").join(format!("{name}-64.exr"))).unwrap()
}

/// Renders `s` at `size`x`size` with `settings` over the scene's own, asserting that no sample
/// or pixel is NaN or infinite.
pub fn render_checked(s: &Scene, settings: &RenderSettings, size: u32) -> RenderOutput {
    let cfg = s.render.overridden_by(settings).resolve(size, size).unwrap();
    let out = render_scene(s, &cfg, &Quiet).unwrap();
    assert_eq!(out.stats.nonfinite_samples, 0, "non-finite samples");
    assert_eq!(out.film.nonfinite_count(), 0, "non-finite pixels");
    out
}

/// `f` run on a pool of `threads` threads (for the determinism tests: same seed, same image
/// whatever the thread count).
pub fn on_threads<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> T {
    rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap().install(f)
}
