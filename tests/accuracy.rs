//! Accuracy against the independent references (Mitsuba 3 path tracer, `tests/data/refs/`),
//! and determinism across thread counts.
//!
//! Renders are 64x64 (the references are box-downsampled by 4 to match), 64 spp, 200k photons
//! per map, fixed seed. Bounds: the RMSE measured with these settings (cornell 0.011,
//! caustics 0.014, pointlight 0.019, furnace 0.067 against the exact 2.0) is made of the
//! photon map's bias (darkening at corners and edges, about -0.3 % of the mean on cornell and
//! pointlight), its low-frequency noise, the camera samples' noise (mostly at the edges of the
//! 17 W/m^2/sr light) and the references' own noise (a quarter of 0.0009-0.009 at this size).
//! The bounds are about 1.6 times the measurement: loose enough for the small
//! differences between backends and platforms, tight enough that a lost light path (a missing
//! map, a wrong kernel normalisation, a broken Fresnel term: each at least doubles the error,
//! as measured while developing) fails.

use crate::common;
use photonmap::config::{ColorMode, IndirectMode, RenderSettings};
use photonmap::film::{compare, Film};
use photonmap::scene::Scene;

use crate::common::{reference, render_checked, scene};

fn settings() -> RenderSettings {
    RenderSettings {
        photons: Some(200_000),
        caustic_photons: Some(200_000),
        spp: Some(64),
        seed: Some(3),
        ..Default::default()
    }
}

fn render(s: &Scene, settings: &RenderSettings) -> Film {
    render_checked(s, settings, 64).film
}

fn check(name: &str, settings: &RenderSettings, bound: f64) {
    let s = scene(name);
    let film = render(&s, settings);
    let r = reference(name);
    let (rmse, _) = compare(&film, &r).unwrap();
    let bias = film.mean() / r.mean() - 1.0;
    eprintln!("{name}: rmse {rmse:.4} (bound {bound}), mean {:+.2}%", 100.0 * bias);
    assert!(rmse < bound, "{name}: RMSE {rmse} >= {bound}");
    assert!(bias.abs() < 0.03, "{name}: mean off by {:.2}%", 100.0 * bias);
}

#[test]
fn cornell_matches_the_reference() {
    check("cornell", &settings(), 0.018);
}

#[test]
fn caustics_match_the_reference() {
    check("caustics", &settings(), 0.023);
}

#[test]
fn pointlight_matches_the_reference() {
    check("pointlight", &settings(), 0.03);
}

/// The white furnace: every pixel converges to exactly 2.0 (Le / (1 - albedo)).
#[test]
fn furnace_is_two_everywhere() {
    let film = render(&scene("furnace"), &settings());
    let mean = film.mean();
    assert!((mean - 2.0).abs() < 0.02, "furnace mean {mean}");
    let exact = Film { pixels: vec![glam::Vec3::splat(2.0); film.pixels.len()], ..film.clone() };
    let (rmse, _) = compare(&film, &exact).unwrap();
    eprintln!("furnace: mean {mean:.4}, rmse {rmse:.4}");
    assert!(rmse < 0.11, "furnace RMSE {rmse}");
}

/// Every option of the CLI still gives a sane Cornell box (three per-channel maps, final gathering, no
/// irradiance cache, other kernels).
#[test]
fn every_mode_stays_close_to_the_reference() {
    use photonmap::config::Kernel;
    let s = scene("cornell");
    let r = reference("cornell");
    let base = RenderSettings { photons: Some(100_000), ..settings() };
    let modes = [
        ("per-channel", RenderSettings { color: Some(ColorMode::PerChannel), ..base.clone() }, 0.019),
        ("no cache", RenderSettings { irradiance_cache: Some(false), ..base.clone() }, 0.019),
        ("box", RenderSettings { kernel: Some(Kernel::Box), ..base.clone() }, 0.019),
        ("gaussian", RenderSettings { kernel: Some(Kernel::Gaussian), ..base.clone() }, 0.019),
        (
            "final gather",
            RenderSettings {
                indirect: Some(IndirectMode::FinalGather),
                final_gather_rays: Some(16),
                spp: Some(16),
                ..base.clone()
            },
            0.045,
        ),
    ];
    for (name, settings, bound) in modes {
        let film = render(&s, &settings);
        let (rmse, _) = compare(&film, &r).unwrap();
        let bias = film.mean() / r.mean() - 1.0;
        eprintln!("cornell {name}: rmse {rmse:.4} (bound {bound}), mean {:+.2}%", 100.0 * bias);
        assert!(rmse < bound, "{name}: RMSE {rmse}");
        assert!(bias.abs() < 0.03, "{name}: mean off by {:.2}%", 100.0 * bias);
    }
}

/// A fixed seed gives the same image, bit for bit, on one thread and on several, with the
/// radiance estimate and with final gathering (whose rays read the sites' direct light too,
/// estimated by whichever thread reads a site first).
#[test]
fn same_seed_same_image_for_any_thread_count() {
    let s = scene("caustics");
    let settings =
        RenderSettings { spp: Some(2), photons: Some(20_000), caustic_photons: Some(20_000), ..settings() };
    let gathered = RenderSettings {
        indirect: Some(IndirectMode::FinalGather),
        final_gather_rays: Some(4),
        ..settings.clone()
    };
    for settings in [settings, gathered] {
        let run = |threads| common::on_threads(threads, || render(&s, &settings));
        let one = run(1);
        assert_eq!(one, run(2));
        assert_eq!(one, run(3));
    }
}
