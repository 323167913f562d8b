//! The thin-lens camera end to end, on `scenes/cornell/cornell-dof.toml` (the Cornell box
//! focused on the short block): a zero aperture is the pinhole image bit for bit, the image does
//! not depend on the thread count, and the light seen out of focus spreads over more pixels the
//! wider the lens while keeping its power.

use crate::common;
use photonmap::accel::AccelKind;
use photonmap::config::{Component, IntegratorKind, RenderSettings};
use photonmap::film::Film;
use photonmap::scene::Scene;
use std::path::Path;

use crate::common::{on_threads, render_checked, scene};

/// `cornell-dof.toml` with its `aperture_radius` replaced by `aperture` metres.
fn dof(aperture: f32) -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell/cornell-dof.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let line = text.lines().find(|l| l.starts_with("aperture_radius =")).unwrap();
    Scene::from_str(&path, &text.replace(line, &format!("aperture_radius = {aperture:?}"))).unwrap()
}

fn quick() -> RenderSettings {
    RenderSettings {
        accel: Some(AccelKind::Bvh),
        photons: Some(20_000),
        caustic_photons: Some(2_000),
        spp: Some(4),
        seed: Some(5),
        ..Default::default()
    }
}

#[test]
fn a_zero_aperture_renders_the_pinhole_image_bit_for_bit() {
    let pinhole = render_checked(&scene("cornell"), &quick(), 24).film;
    assert_eq!(render_checked(&dof(0.0), &quick(), 24).film, pinhole);
    assert_ne!(render_checked(&dof(0.05), &quick(), 24).film, pinhole);
}

#[test]
fn a_thin_lens_image_does_not_depend_on_the_thread_count() {
    let s = dof(0.05);
    let sppm = RenderSettings { integrator: Some(IntegratorKind::Sppm), passes: Some(2), ..quick() };
    for settings in [quick(), sppm] {
        let run = |threads| on_threads(threads, || render_checked(&s, &settings, 24).film);
        let one = run(1);
        assert_eq!(one, run(2), "{:?}", settings.integrator);
    }
}

/// Pixels that see some of the light, and the light's total in the image.
fn light_spread(film: &Film) -> (usize, f64) {
    let lit = film.pixels.iter().filter(|p| p.max_element() > 1e-3).count();
    (lit, film.pixels.iter().map(|p| f64::from(p.x)).sum())
}

#[test]
fn the_light_out_of_focus_spreads_wider_with_a_wider_lens() {
    // The light (about 1.1 m ahead, the focus at 0.89 m) seen directly: its image through a
    // lens is the pinhole's blurred by the circle of confusion, 2 A |z - F| / F.
    let emitted = RenderSettings { component: Some(Component::Emitted), spp: Some(64), ..quick() };
    let spreads: Vec<(usize, f64)> = [0.0, 0.02, 0.05]
        .iter()
        .map(|&a| light_spread(&render_checked(&dof(a), &emitted, 64).film))
        .collect();
    eprintln!("lit pixels and the light's red total for apertures 0, 0.02, 0.05 m: {spreads:?}");
    assert!(spreads[0].0 < spreads[1].0 && spreads[1].0 < spreads[2].0, "{spreads:?}");
    for s in &spreads[1..] {
        assert!((s.1 / spreads[0].1 - 1.0).abs() < 0.02, "the light's power moved: {spreads:?}");
    }
}

/// Against Mitsuba's `thinlens` reference (`tests/data/refs/cornell-dof-64.exr`, noise RMSE
/// 0.004 at 256x256, about a quarter of it at 64x64), with `tests/accuracy.rs`'s settings but
/// 256 spp: the error is the lens samples' noise where the light's blurred edge covers part
/// of a pixel (RMSE measured 0.0346, 0.0139 and 0.0052 at 64, 256 and 1024 spp; the worst
/// pixels all at the light), and the bound about 1.6 times the measurement at 256.
#[test]
fn cornell_dof_matches_the_mitsuba_thinlens_reference() {
    let settings = RenderSettings {
        photons: Some(200_000),
        caustic_photons: Some(200_000),
        spp: Some(256),
        seed: Some(3),
        ..Default::default()
    };
    let r = common::reference("cornell-dof");
    let film = render_checked(&dof(0.05), &settings, 64).film;
    let (rmse, _) = photonmap::film::compare(&film, &r).unwrap();
    let bias = film.mean() / r.mean() - 1.0;
    eprintln!("cornell-dof: rmse {rmse:.4}, mean {:+.2}%", 100.0 * bias);
    // The pinhole image is farther from it: the lens is what the reference sees.
    let pinhole = render_checked(&dof(0.0), &settings, 64).film;
    let (pinhole_rmse, _) = photonmap::film::compare(&pinhole, &r).unwrap();
    eprintln!("cornell-dof through a pinhole: rmse {pinhole_rmse:.4}");
    assert!(rmse < 0.022, "RMSE {rmse}");
    assert!(bias.abs() < 0.03, "mean off by {:.2}%", 100.0 * bias);
    assert!(pinhole_rmse > 3.0 * rmse, "pinhole {pinhole_rmse} vs lens {rmse}");
}
