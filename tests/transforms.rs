//! Mesh transforms end to end: the Cornell box turned and moved with `rotate` and `translate`,
//! the camera turned and moved with it, and the box mirrored by a `matrix` (negative
//! determinant: the winding must be reversed, or the light, which emits from its front side
//! only, would face the ceiling), each scored against the Mitsuba reference of the untouched
//! box (flipped left to right for the mirror).

use crate::common::{reference, render_checked};
use photonmap::config::RenderSettings;
use photonmap::film::{compare, Film};
use photonmap::scene::Scene;
use std::path::Path;

/// `cornell.toml` with `camera` replacing its eye and target lines and `transform` added to its
/// `[[mesh]]`.
fn cornell(eye_target: &str, transform: &str) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell/cornell.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let text = text
        .replace("eye = [0.278, 0.273, -0.8]\ntarget = [0.278, 0.273, 0.0]", eye_target)
        .replace("obj = \"cornell.obj\"", &format!("obj = \"cornell.obj\"\n{transform}"));
    Scene::from_str(&path, &text).unwrap()
}

fn score(name: &str, s: &Scene, r: &Film) -> f64 {
    let settings = RenderSettings {
        photons: Some(200_000),
        caustic_photons: Some(200_000),
        spp: Some(64),
        seed: Some(3),
        ..Default::default()
    };
    let film = render_checked(s, &settings, 64).film;
    let (rmse, _) = compare(&film, r).unwrap();
    let bias = film.mean() / r.mean() - 1.0;
    eprintln!("{name}: rmse {rmse:.4}, mean {:+.2}%", 100.0 * bias);
    assert!(bias.abs() < 0.03, "{name}: mean off by {:.2}%", 100.0 * bias);
    rmse
}

/// The bound of `tests/accuracy.rs` for the untouched box (measured 0.011 there).
const BOUND: f64 = 0.018;

#[test]
fn a_turned_and_moved_box_seen_from_a_camera_turned_and_moved_alike_is_the_box() {
    // A quarter turn about +Y takes (x, y, z) to (z, y, -x); then (1, 0, 2) is added.
    let s = cornell(
        "eye = [0.2, 0.273, 1.722]\ntarget = [1.0, 0.273, 1.722]",
        "rotate = [{ axis = [0, 1, 0], degrees = 90 }]\ntranslate = [1, 0, 2]",
    );
    let turned = score("turned", &s, &reference("cornell"));
    assert!(turned < BOUND, "turned: RMSE {turned}");
}

#[test]
fn a_mirrored_box_is_the_mirror_image_and_its_light_still_shines_down() {
    // x -> 0.556 - x: the red wall moves to the right of the image, the green to the left.
    let s = cornell(
        "eye = [0.278, 0.273, -0.8]\ntarget = [0.278, 0.273, 0.0]",
        "matrix = [-1, 0, 0, 0.556,  0, 1, 0, 0,  0, 0, 1, 0,  0, 0, 0, 1]",
    );
    let r = reference("cornell");
    let mut flipped = r.clone();
    for y in 0..r.height {
        for x in 0..r.width {
            flipped.pixels[y * r.width + x] = r.get(r.width - 1 - x, y);
        }
    }
    let mirrored = score("mirrored", &s, &flipped);
    assert!(mirrored < BOUND, "mirrored: RMSE {mirrored}");
    let unflipped = score("mirrored against the unflipped reference", &s, &r);
    assert!(unflipped > 3.0 * mirrored, "{unflipped} vs {mirrored}");
}
