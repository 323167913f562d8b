//! Progressive rendering: stochastic progressive photon mapping converges to the references as
//! passes are added, a fixed seed gives the same image for any thread count, passes of the
//! other integrators average, and Ctrl-C writes the image so far.

use crate::common;
use photonmap::config::{IntegratorKind, RenderSettings};
use photonmap::film::{compare, Film};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use crate::common::{reference, render_checked, scene};

fn sppm(passes: u32) -> RenderSettings {
    RenderSettings {
        integrator: Some(IntegratorKind::Sppm),
        passes: Some(passes),
        photons: Some(20_000),
        caustic_photons: Some(10_000),
        seed: Some(5),
        ..Default::default()
    }
}

fn rmse(name: &str, settings: &RenderSettings) -> (f64, f64) {
    let film = render_checked(&scene(name), settings, 64).film;
    let r = reference(name);
    let (rmse, _) = compare(&film, &r).unwrap();
    (rmse, film.mean() / r.mean() - 1.0)
}

/// More passes, less error: on both scenes the error after 32 passes is well below that after
/// 2, and both the final error and the mean are close to the reference. (Measured at 64x64
/// with 20k photons per pass: cornell 0.052 → 0.0072, caustics 0.062 → 0.011; a lost path or a
/// radius update that keeps old flux at the wrong scale stops the fall or shifts the mean by
/// several per cent.)
#[test]
fn sppm_error_falls_with_passes() {
    for (name, bound) in [("cornell", 0.012), ("caustics", 0.018)] {
        let (early, _) = rmse(name, &sppm(2));
        let (late, bias) = rmse(name, &sppm(32));
        eprintln!("{name}: rmse {early:.4} after 2 passes, {late:.4} after 32 (mean {:+.2}%)", 100.0 * bias);
        assert!(late < 0.3 * early, "{name}: {early} -> {late}");
        assert!(late < bound, "{name}: rmse {late} >= {bound}");
        assert!(bias.abs() < 0.03, "{name}: mean off by {:.2}%", 100.0 * bias);
    }
}

/// The white furnace is 2.0 everywhere with progressive photon mapping too.
#[test]
fn sppm_furnace_is_two() {
    let film = render_checked(&scene("furnace"), &sppm(16), 32).film;
    let mean = film.mean();
    eprintln!("furnace sppm mean {mean:.4}");
    assert!((mean - 2.0).abs() < 0.02, "furnace mean {mean}");
}

/// A fixed seed gives the same progressive image, bit for bit, on one thread and on two.
#[test]
fn sppm_is_deterministic_across_thread_counts() {
    let s = scene("caustics");
    let settings = RenderSettings { photons: Some(5_000), caustic_photons: Some(5_000), ..sppm(3) };
    let run = |threads| common::on_threads(threads, || render_checked(&s, &settings, 32).film);
    assert_eq!(run(1), run(2));
}

/// Pass-indexed progressive photon mapping converges as the stochastic kind does: the error
/// after 32 passes is well below that after 2 and the mean is close to the reference. (Measured
/// at 64x64 with 20k photons a pass, as for sppm above.)
#[test]
fn pppm_error_falls_with_passes() {
    let pppm = |passes| RenderSettings { integrator: Some(IntegratorKind::Pppm), ..sppm(passes) };
    for (name, bound) in [("cornell", 0.012), ("caustics", 0.018)] {
        let (early, _) = rmse(name, &pppm(2));
        let (late, bias) = rmse(name, &pppm(32));
        eprintln!(
            "{name} pppm: rmse {early:.4} after 2 passes, {late:.4} after 32 (mean {:+.2}%)",
            100.0 * bias
        );
        assert!(late < 0.3 * early, "{name}: {early} -> {late}");
        assert!(late < bound, "{name}: rmse {late} >= {bound}");
        assert!(bias.abs() < 0.03, "{name}: mean off by {:.2}%", 100.0 * bias);
    }
}

/// A fixed seed gives the same pass-indexed image, bit for bit, on one thread and on two.
#[test]
fn pppm_is_deterministic_across_thread_counts() {
    let s = scene("cornell");
    let settings = RenderSettings {
        integrator: Some(IntegratorKind::Pppm),
        photons: Some(5_000),
        caustic_photons: Some(5_000),
        ..sppm(3)
    };
    let run = |threads| common::on_threads(threads, || render_checked(&s, &settings, 32).film);
    assert_eq!(run(1), run(2));
}

/// Without `--spp`, a long pppm render's pilot chooses the camera samples of a pass from where
/// the noise is (`src/integrator/balance.rs`): many where its photon term is quiet and costly
/// (many photons a pass, wide gathers), few where it is noisy and cheap; the passes take them;
/// `--spp` given, or a short render, keeps the samples asked for. The choice depends on the
/// seed only: the same image on one thread and on two.
#[test]
fn pppm_chooses_its_camera_samples_where_the_noise_is() {
    let s = scene("cornell");
    let pppm = |photons: u64, k: u32| RenderSettings {
        integrator: Some(IntegratorKind::Pppm),
        passes: Some(16),
        photons: Some(photons),
        gather_photons: Some(k),
        seed: Some(3),
        ..Default::default()
    };
    let run = |settings: &RenderSettings| render_checked(&s, settings, 32);
    let quiet = run(&pppm(40_000, 200));
    let noisy = run(&pppm(2_000, 5));
    let (many, few) = (quiet.stats.pass_plan.unwrap(), noisy.stats.pass_plan.unwrap());
    eprintln!("quiet photons: {many:?}\nnoisy photons: {few:?}");
    assert!(many.spp > 2 * few.spp && few.spp >= 4, "{} against {}", many.spp, few.spp);
    assert!(many.camera_share > 0.0 && many.camera_share < 1.0, "{many:?}");
    assert!(many.fixed_in_samples > few.fixed_in_samples, "{many:?} {few:?}");
    // The passes take them: 16 passes of `spp` camera rays and one visible point a pixel, and
    // the pilot's 4 and one.
    for (out, spp) in [(&quiet, many.spp), (&noisy, few.spp)] {
        let pixels = 32 * 32;
        assert_eq!(out.stats.rays.camera, (16 * (spp as u64 + 1) + 5) * pixels, "spp {spp}");
    }
    // Asked for, or too short to measure: not chosen.
    let asked = RenderSettings { spp: Some(4), ..pppm(40_000, 200) };
    assert_eq!(run(&asked).stats.pass_plan, None);
    assert_eq!(run(&RenderSettings { passes: Some(8), ..pppm(40_000, 200) }).stats.pass_plan, None);
    let image = |threads| common::on_threads(threads, || run(&pppm(2_000, 5)).film);
    assert_eq!(image(1), image(2));
}

/// Without `--photons` or `--caustic-photons`, a long pppm render's pilot chooses the photons
/// of a pass too (`src/integrator/balance.rs`): on the point-lit box, whose photon term is most
/// of the image and whose pixels at 32x32 are far wider than their discs, more than the
/// render's own; the passes trace them; `--photons` given keeps them; the same image on one
/// thread and on two.
#[test]
fn pppm_chooses_its_photons_a_pass() {
    let s = scene("pointlight");
    let pppm = RenderSettings {
        integrator: Some(IntegratorKind::Pppm),
        passes: Some(16),
        spp: Some(4),
        seed: Some(3),
        ..Default::default()
    };
    let run = |settings: &RenderSettings| render_checked(&s, settings, 32);
    let out = run(&pppm);
    let plan = out.stats.pass_plan.expect("the pilot chose the photons");
    eprintln!("{plan:?}");
    let m = plan.photons / 100_000;
    assert_eq!((plan.photons, plan.caustic_photons, plan.spp), (m * 100_000, m * 30_000, 4));
    assert!([2, 4, 8].contains(&m), "{plan:?}");
    // The pilot's photons, then 16 passes' of m times as many (within the rounding of the
    // photons' split over the lights).
    let emitted = out.stats.photons["indirect"].emitted as i64;
    assert!((emitted - (100_000 + 16 * plan.photons) as i64).abs() <= 64, "{emitted}");
    // Asked for: kept (and, with --spp too, nothing chosen).
    let asked = RenderSettings { photons: Some(100_000), ..pppm.clone() };
    assert_eq!(run(&asked).stats.pass_plan, None);
    // The render above ran on the default pool's threads (2 or more).
    assert_eq!(common::on_threads(1, || run(&pppm).film), out.film);
}

/// Passes of the path tracer average (4 passes of 4 samples: measured 0.130 → 0.049, the
/// camera samples of the passes together staying stratified), and the stats count them.
#[test]
fn path_passes_average() {
    let s = scene("cornell");
    let base = RenderSettings {
        integrator: Some(IntegratorKind::Path),
        spp: Some(4),
        seed: Some(9),
        ..Default::default()
    };
    let one = render_checked(&s, &base, 32);
    let four = render_checked(&s, &RenderSettings { passes: Some(4), ..base.clone() }, 32);
    assert_eq!(one.stats.passes, 1);
    assert_eq!(four.stats.passes, 4);
    let r = reference("cornell").downsample(2);
    let (e1, _) = compare(&one.film, &r).unwrap();
    let (e4, _) = compare(&four.film, &r).unwrap();
    eprintln!("path: rmse {e1:.4} with 1 pass, {e4:.4} with 4");
    assert!(e4 < 0.5 * e1, "{e1} -> {e4}");
}

fn scene_path(name: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("scenes/{name}/{name}.toml"))
}

/// Ctrl-C during a progressive render writes the image of the passes done, whole, and exits
/// with 130.
#[test]
fn ctrl_c_writes_the_image_so_far() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.exr");
    let child = Command::new(env!("CARGO_BIN_EXE_photonmap"))
        .arg("render")
        .arg(scene_path("cornell"))
        .args(["--integrator", "sppm", "--time", "120", "--width", "32", "--height", "32", "--quiet"])
        .args(["--photons", "2000", "--checkpoint-every", "1", "-o"])
        .arg(&out)
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Wait for the first checkpoint, so the handler is installed and a pass is done.
    let start = Instant::now();
    while !out.exists() {
        assert!(start.elapsed() < Duration::from_secs(60), "no checkpoint written");
        std::thread::sleep(Duration::from_millis(20));
    }
    let status = Command::new("kill").args(["-INT", &child.id().to_string()]).status().unwrap();
    assert!(status.success());
    let output = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(130), "{stderr}");
    assert!(stderr.contains("interrupted"), "{stderr}");
    let film = Film::read_exr(&out).unwrap();
    assert_eq!((film.width, film.height), (32, 32));
    assert!(film.mean() > 0.05, "{}", film.mean());
}

/// `photonmap converge` renders every method at every budget and writes the table, the CSV
/// and the plot.
#[test]
fn converge_writes_table_csv_and_plot() {
    let dir = tempfile::tempdir().unwrap();
    let (csv, svg) = (dir.path().join("c.csv"), dir.path().join("c.svg"));
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let output = Command::new(env!("CARGO_BIN_EXE_photonmap"))
        .arg("converge")
        .arg(scene_path("cornell"))
        .arg("--reference")
        .arg(root.join("tests/data/refs/cornell-64.exr"))
        .args(["--downsample", "4", "--budgets", "0.05,0.2", "--methods", "sppm,path", "--csv"])
        .arg(&csv)
        .arg("--plot")
        .arg(&svg)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(output.status.success(), "{stdout}{}", String::from_utf8_lossy(&output.stderr));
    assert!(stdout.contains("sppm") && stdout.contains("slope"), "{stdout}");
    let csv = std::fs::read_to_string(&csv).unwrap();
    assert_eq!(csv.lines().count(), 5, "{csv}");
    for line in csv.lines().skip(1) {
        let rmse: f64 = line.split(',').nth(4).unwrap().parse().unwrap();
        assert!(rmse > 0.0 && rmse < 0.3, "{line}");
    }
    let svg = std::fs::read_to_string(&svg).unwrap();
    assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
    assert_eq!(svg.matches("<polyline").count(), 2);
}

/// A reference of another size, or a bad budget, is refused with a clear error.
#[test]
fn converge_refuses_bad_input() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let run = |args: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_photonmap"))
            .arg("converge")
            .arg(scene_path("cornell"))
            .arg("--reference")
            .arg(root.join("tests/data/refs/cornell-64.exr"))
            .args(args)
            .output()
            .unwrap()
    };
    let out = run(&["--downsample", "3"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--downsample 3"));
    let out = run(&["--budgets=1,0"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--budgets"));
}

/// The progressive modes' bias, a tested property: on every shipped scene, after a fixed
/// photon budget (24 passes of 80k photons and 16 camera samples a pixel, at 32x32 against the
/// 64x64 reference box-downsampled) the image mean is within 0.3 % of the reference's, and the
/// error keeps falling from 6 passes to 24. The references' own noise is far below that in
/// the mean (0.0009-0.021 a pixel at 256x256, at most 0.004 % of the mean over 65 536
/// pixels); ours, from seed to seed at this budget, is about 0.05 % on cornell and 0.1 % on
/// pointlight (whose photon term is most of the image). With 4 camera samples a pass the
/// direct light alone made the mean of one render wander by 0.25 %, so the budget has 16.
/// Before the footprint probes and the strict first-pass count, sppm's means at 32 passes of
/// 50k were cornell -0.30 %, caustics -0.22 %, pointlight -0.81 %, furnace -0.18 %; after,
/// +0.11 %, -0.07 %, -0.11 %, +0.04 %.
///
/// Of the hard scenes of our own, the doorway and the Cornell box moved far from the origin are
/// held to it too (pppm -0.07 % and -0.09 %, sppm the same). The others miss it at this budget
/// (pppm, seed 3, `photonmap render S --integrator pppm --passes 24 --photons 80000
/// --caustic-photons 20000 --spp 16 --seed 3 --width 32 --height 32`): the sunroom -0.42 %, the
/// glass knot -0.54 %, the atrium +1.17 %, the fluted column -0.41 % (docs/accuracy.md); all
/// but the column are held to it at a larger budget (`pppm_means_match_the_hard_scenes_references`).
fn progressive_means_match(kind: IntegratorKind) {
    for name in ["cornell", "caustics", "pointlight", "furnace", "doorway", "faraway"] {
        let s = scene(name);
        let r = reference(name).downsample(2);
        let settings = |passes| RenderSettings {
            integrator: Some(kind),
            passes: Some(passes),
            photons: Some(80_000),
            caustic_photons: Some(20_000),
            spp: Some(16),
            seed: Some(3),
            ..Default::default()
        };
        let early = render_checked(&s, &settings(6), 32).film;
        let late = render_checked(&s, &settings(24), 32).film;
        let (e_early, _) = compare(&early, &r).unwrap();
        let (e_late, _) = compare(&late, &r).unwrap();
        let bias = late.mean() / r.mean() - 1.0;
        eprintln!(
            "{kind:?} {name}: rmse {e_early:.4} after 6 passes, {e_late:.4} after 24; mean {:+.3} %",
            100.0 * bias
        );
        assert!(bias.abs() < 0.003, "{kind:?} {name}: mean off by {:+.3} %", 100.0 * bias);
        assert!(e_late < 0.8 * e_early, "{kind:?} {name}: rmse {e_early} -> {e_late}");
    }
}

#[test]
fn sppm_means_match_the_references() {
    progressive_means_match(IntegratorKind::Sppm);
}

#[test]
fn pppm_means_match_the_references() {
    progressive_means_match(IntegratorKind::Pppm);
}

/// The hard scenes of our own, at a budget where their discs are past the size of their
/// detail: 64×64, 24 passes of 300 000 + 75 000 photons and 16 samples (seed 3). Means: the
/// atrium +0.07 % (+0.56 % before pppm's image took off half the bias its passes probe, so
/// this fails on the old code), the sunroom −0.01 %, the bunny −0.21 %, the glass knot
/// +0.03 %. The fluted column is left out: at such budgets its discs are about a flute wide
/// and its mean is −0.3 % to −1 %; at 45 s and 256² it is within the bound, −0.13 % to
/// −0.20 % over three seeds (docs/accuracy.md).
#[test]
fn pppm_means_match_the_hard_scenes_references() {
    let settings = RenderSettings {
        integrator: Some(IntegratorKind::Pppm),
        passes: Some(24),
        photons: Some(300_000),
        caustic_photons: Some(75_000),
        spp: Some(16),
        seed: Some(3),
        ..Default::default()
    };
    for name in ["atrium", "sunroom", "bunny", "glassknot"] {
        let (rmse, bias) = rmse(name, &settings);
        eprintln!("pppm {name}: rmse {rmse:.4}, mean {:+.3} %", 100.0 * bias);
        assert!(bias.abs() < 0.003, "{name}: mean off by {:+.3} %", 100.0 * bias);
    }
}
