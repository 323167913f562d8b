//! What the scene analysis saves, side by side in one run (criterion, `harness = false`).
//!
//! * **caustics**, the caustic term only (`--component caustic`, 128×128, 16 spp), with the
//!   projection map (`--caustic-aim true`, the default: photons aimed at the bounding spheres of
//!   the mirror and glass spheres) and without (`--caustic-aim false`: photons emitted from the
//!   light as usual, light → specular⁺ → diffuse paths kept), at the default budget and, without
//!   aiming, at as many emission tries as aiming made (so as many photons reach the spheres).
//!   Time of the caustic stage (tracing and balancing the map), per stored photon, and RMSE of
//!   the caustic image against a caustic render made here with ten times the aimed photons and
//!   200 photons per estimate (the same camera samples, so the error is the caustic map's).
//! * **cornell** (no mirror or glass), the whole image at the default settings, 128×128: time
//!   with the caustic stage as the analysis decides (`--caustic-pass auto`: skipped) and forced
//!   on (`--caustic-pass on`).
//!
//! After criterion's own report (on 64×64 renders), a summary table gives medians of
//! `SAVINGS_RUNS` (default 5) runs of each row. Images are deterministic, so their errors are
//! the same in every run; times vary.
//!
//! Environment: `SAVINGS_SUMMARY_ONLY=1` skips criterion and prints only the summary table.

use criterion::Criterion;
use photonmap::config::{CausticPass, Component, RenderSettings};
use photonmap::film::{compare, Film};
use photonmap::frame::Quiet;
use photonmap::integrator::{render_scene, RenderOutput};
use photonmap::scene::Scene;
use photonmap::tools::bench::median;
use std::path::Path;
use std::time::Duration;

const SIZE: u32 = 128;
/// Photons per caustic estimate of the reference.
const REFERENCE_K: u32 = 200;

fn scene(name: &str) -> Scene {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    Scene::load(root.join("scenes").join(name).join(format!("{name}.toml"))).unwrap()
}

fn render(s: &Scene, settings: &RenderSettings, size: u32) -> RenderOutput {
    let cfg = s.render.overridden_by(settings).resolve(size, size).unwrap();
    render_scene(s, &cfg, &Quiet).unwrap()
}

/// Seconds of the caustic photon pass and of balancing its map.
fn caustic_seconds(out: &RenderOutput) -> f64 {
    out.stats.seconds("photons.caustic") + out.stats.seconds("kdtree.caustic")
}

/// One row of the summary: medians over the runs.
struct Row {
    what: String,
    caustic_s: f64,
    total_s: f64,
    emitted: u64,
    stored: u64,
    /// RMSE against the row's reference, and the mean's deviation from it.
    error: Option<(f64, f64)>,
}

/// Renders each of `configs` `runs` times, interleaved (run 1 of every config, then run 2, ...)
/// so that a change in the machine's load hits every row alike; one row per config, with the
/// first run's image.
fn measure(
    configs: &[(String, &Scene, RenderSettings)],
    runs: usize,
    reference: Option<&Film>,
) -> Vec<(Row, Film)> {
    let mut outs: Vec<Vec<RenderOutput>> = configs.iter().map(|_| Vec::new()).collect();
    for _ in 0..runs {
        for ((_, s, settings), o) in configs.iter().zip(&mut outs) {
            o.push(render(s, settings, SIZE));
        }
    }
    configs
        .iter()
        .zip(outs)
        .map(|((what, _, _), outs)| {
            let first = &outs[0];
            let caustic = first.stats.photons.get("caustic");
            let error = reference.map(|r| {
                let (rmse, _) = compare(&first.film, r).unwrap();
                (rmse, first.film.mean() / r.mean() - 1.0)
            });
            let row = Row {
                what: what.clone(),
                caustic_s: median(outs.iter().map(caustic_seconds).collect()),
                total_s: median(
                    outs.iter().map(|o| o.stats.wall_seconds + o.stats.seconds("accel")).collect(),
                ),
                emitted: caustic.map_or(0, |m| m.emitted),
                stored: caustic.map_or(0, |m| m.stored),
                error,
            };
            (row, outs.into_iter().next().unwrap().film)
        })
        .collect()
}

fn print_rows(title: &str, rows: &[Row]) {
    println!("\n{title}");
    println!(
        "{:<44} {:>10} {:>9} {:>11} {:>9} {:>10} {:>9} {:>8}",
        "", "caustic s", "total s", "emitted", "stored", "us/stored", "RMSE", "mean"
    );
    for r in rows {
        let (rmse, bias) = match r.error {
            Some((e, b)) => (format!("{e:.5}"), format!("{:+.2}%", 100.0 * b)),
            None => ("-".into(), "-".into()),
        };
        let per =
            if r.stored > 0 { format!("{:.2}", 1e6 * r.caustic_s / r.stored as f64) } else { "-".into() };
        println!(
            "{:<44} {:>10.3} {:>9.3} {:>11} {:>9} {:>10} {:>9} {:>8}",
            r.what, r.caustic_s, r.total_s, r.emitted, r.stored, per, rmse, bias
        );
    }
}

fn caustic_settings(aim: bool, photons: u64) -> RenderSettings {
    RenderSettings {
        component: Some(Component::Caustic),
        spp: Some(16),
        caustic_aim: Some(aim),
        caustic_photons: Some(photons),
        ..Default::default()
    }
}

fn criterion_benches(caustics: &Scene, cornell: &Scene) {
    let mut c = Criterion::default().configure_from_args();
    let mut g = c.benchmark_group("savings");
    g.sample_size(10).warm_up_time(Duration::from_millis(500)).measurement_time(Duration::from_secs(5));
    for aim in [true, false] {
        let settings = caustic_settings(aim, 100_000);
        g.bench_function(format!("caustics caustic term, aim {aim}"), |b| {
            b.iter(|| render(caustics, &settings, 64))
        });
    }
    for pass in [CausticPass::Auto, CausticPass::On] {
        let settings =
            RenderSettings { caustic_pass: Some(pass), photons: Some(200_000), ..Default::default() };
        g.bench_function(format!("cornell, caustic pass {pass:?}"), |b| {
            b.iter(|| render(cornell, &settings, 64))
        });
    }
    g.finish();
    c.final_summary();
}

fn main() {
    rayon::ThreadPoolBuilder::new()
        .start_handler(|_| photonmap::accel::init_tracing_thread())
        .build_global()
        .ok();
    let runs: usize = std::env::var("SAVINGS_RUNS").ok().and_then(|v| v.parse().ok()).unwrap_or(5).max(1);
    let summary_only = std::env::var("SAVINGS_SUMMARY_ONLY").is_ok_and(|v| !v.is_empty() && v != "0");
    let (caustics, cornell) = (scene("caustics"), scene("cornell"));
    if !summary_only {
        criterion_benches(&caustics, &cornell);
    }

    let defaults = RenderSettings::default().resolve(1, 1).unwrap();
    let budget = defaults.integrator.photon_passes().expect("photon mapping by default").caustic_photons;
    // Ten times the photons and a wider gather (k = 200, so a radius ~0.55 of the default's
    // and half its noise): a reference better than every row on both counts. It has the rows'
    // seed, so the same camera samples (its photons differ: the budget changes every emitter's
    // share and strata), and the RMSE is the error of the caustic map's estimate alone.
    let reference = render(
        &caustics,
        &RenderSettings { caustic_gather_photons: Some(REFERENCE_K), ..caustic_settings(true, 10 * budget) },
        SIZE,
    );
    // The number of emission tries aiming makes for the default budget.
    let tries = render(&caustics, &caustic_settings(true, budget), SIZE).stats.photons["caustic"].emitted;
    let configs = [
        (format!("aim on  (--caustic-aim true), {budget} aimed"), &caustics, caustic_settings(true, budget)),
        (format!("aim off (--caustic-aim false), {budget}"), &caustics, caustic_settings(false, budget)),
        (format!("aim off (--caustic-aim false), {tries}"), &caustics, caustic_settings(false, tries)),
    ];
    let rows = measure(&configs, runs, Some(&reference.film));
    let threads = rayon::current_num_threads();
    print_rows(
        &format!(
            "caustics, --component caustic, {SIZE}x{SIZE}, 16 spp, {threads} threads; median of {runs} runs; \
             RMSE against {} aimed photons, k = {REFERENCE_K}, same camera samples",
            10 * budget
        ),
        &rows.into_iter().map(|(r, _)| r).collect::<Vec<_>>(),
    );

    let configs = [
        ("caustic pass auto (skipped: no mirror or glass)".to_string(), &cornell, RenderSettings::default()),
        (
            "caustic pass on  (--caustic-pass on)".to_string(),
            &cornell,
            RenderSettings { caustic_pass: Some(CausticPass::On), ..Default::default() },
        ),
    ];
    let rows = measure(&configs, runs, None);
    print_rows(
        &format!("cornell, defaults, {SIZE}x{SIZE}, {threads} threads; median of {runs} runs"),
        &rows.iter().map(|(r, _)| Row { what: r.what.clone(), error: None, ..*r }).collect::<Vec<_>>(),
    );
    let (auto_film, on_film) = (&rows[0].1, &rows[1].1);
    println!("cornell images identical: {}", if auto_film.pixels == on_film.pixels { "yes" } else { "no" });
}
