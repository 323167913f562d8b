//! Bias of the progressive photon mappers (sppm, pppm), one cause at a time, on scenes whose
//! answer is known exactly: furnace-like closed boxes whose walls have albedo 0.5 and emit 1
//! (radiance exactly 2 everywhere, in corners and on thin walls too), and a box that emits
//! nothing beside one that does (exactly 0 in it: whatever shows there leaked in).
//!
//! In a furnace of albedo 0.5 emission and direct light are 1.5 of the 2: the photon term is
//! 0.5, a quarter of the image, so a bias of x in the photon estimate moves the mean by x / 4.

use photonmap::config::{IntegratorKind, RenderSettings};
use photonmap::film::Film;
use photonmap::frame::Quiet;
use photonmap::geometry::Vec3;
use photonmap::integrator::render_scene;
use photonmap::material::Material;
use photonmap::scene::Scene;
use photonmap::tools::stress::scenes::{camera, Builder, Facing};

/// The furnace's material: albedo 0.5, emitted radiance 1.
fn furnace_material(b: &mut Builder) -> u32 {
    b.material("furnace", Material::Emissive { kd: Vec3::splat(0.5), ke: Vec3::ONE })
}

/// The furnace cube `[-1, 1]³` seen from its centre toward `target` with a `fov_deg` view.
fn furnace_view(target: Vec3, fov_deg: f32) -> Scene {
    let mut b = Builder::default();
    let m = furnace_material(&mut b);
    b.cuboid(-Vec3::ONE, Vec3::ONE, Facing::Inward, m);
    b.build("furnace-view", camera(Vec3::ZERO, target, Vec3::Y, fov_deg))
}

fn progressive(kind: IntegratorKind, passes: u32, photons: u64, seed: u64) -> RenderSettings {
    RenderSettings {
        integrator: Some(kind),
        passes: Some(passes),
        photons: Some(photons),
        seed: Some(seed),
        ..Default::default()
    }
}

fn render(scene: &Scene, settings: &RenderSettings, size: u32) -> Film {
    let cfg = scene.render.overridden_by(settings).resolve(size, size).unwrap();
    let out = render_scene(scene, &cfg, &Quiet).unwrap();
    assert_eq!(out.stats.nonfinite_samples, 0, "non-finite samples");
    out.film
}

/// The mean of `seeds` renders (seeds 1, 2, ...).
fn mean_of(scene: &Scene, settings: &RenderSettings, size: u32, seeds: u64) -> f64 {
    let total: f64 = (1..=seeds)
        .map(|seed| render(scene, &RenderSettings { seed: Some(seed), ..settings.clone() }, size).mean())
        .sum();
    total / seeds as f64
}

/// The first radius of both progressive kinds is the distance from the visible point to its
/// k-th nearest photon of the first pass, and that pass's photons are then counted inside it:
/// the k-th, on the disc's edge, must be left out, or the first pass is `k / (k - 1)` too
/// bright. Here k = 5 (+25 % of the photon term before the fix, measured +0.10 on the mean of
/// 2 with the k-th counted whenever the square root of its distance squared back to it or
/// above, about 4 times in 5), on a wall seen far from any edge, in one pass.
/// After the fix: 2.000 ± 0.01.
#[test]
fn first_pass_leaves_out_the_kth_photon() {
    let scene = furnace_view(Vec3::new(0.0, 0.0, 1.0), 40.0);
    for kind in [IntegratorKind::Sppm, IntegratorKind::Pppm] {
        let settings = RenderSettings { gather_photons: Some(5), ..progressive(kind, 1, 100_000, 1) };
        let mean = mean_of(&scene, &settings, 48, 2);
        eprintln!("{kind:?}: one pass, k = 5: mean {mean:.4} (exact 2)");
        assert!((mean - 2.0).abs() < 0.03, "{kind:?}: mean {mean}, exact 2");
    }
}
