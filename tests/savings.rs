//! No work a scene does not need: the scene analysis skips stages (and says why in the stats),
//! skipping changes nothing in the image, caustic photons emitted without aiming give the same
//! estimate as aimed ones, and the raw ray rates of `--stats` and `photonmap bench`.

#[allow(dead_code)] // the reference images are not needed here
use crate::common::{render_checked, scene};
use photonmap::accel::{AccelKind, AccelOptions, AnyAccel};
use photonmap::config::{CausticPass, Component, RenderSettings};
use photonmap::frame::Quiet;
use photonmap::integrator::{render_scene, Control, RenderOutput};
use photonmap::light::LightSet;
use photonmap::photon::trace::{self, Pass, PassSpec};
use photonmap::scene::Scene;
use photonmap::stats::Stage;
use photonmap::tools::bench::render_calibrated;
use std::path::Path;

/// Small budgets: these tests are about which stages run, not about the image.
fn quick() -> RenderSettings {
    RenderSettings {
        photons: Some(20_000),
        caustic_photons: Some(10_000),
        spp: Some(2),
        accel: Some(AccelKind::Bvh),
        ..Default::default()
    }
}

fn stage<'a>(out: &'a RenderOutput, name: &str) -> &'a Stage {
    out.stats.stages.iter().find(|s| s.name == name).unwrap_or_else(|| panic!("no stage {name}"))
}

/// The Cornell box has no mirror or glass: the caustic pass is skipped with the reason; forced
/// on, it runs, stores nothing, is never looked up, and the image is the same bit for bit.
#[test]
fn forced_caustic_pass_on_cornell_changes_nothing() {
    let s = scene("cornell");
    let auto = render_checked(&s, &quick(), 24);
    let st = stage(&auto, "photons.caustic");
    assert!(!st.ran && st.reason.contains("no specular"), "{st:?}");
    let forced = RenderSettings { caustic_pass: Some(CausticPass::On), ..quick() };
    let on = render_checked(&s, &forced, 24);
    let st = stage(&on, "photons.caustic");
    assert!(st.ran && st.reason.contains("nothing to aim at"), "{st:?}");
    assert_eq!(on.stats.photons["caustic"].emitted, 10_000);
    assert_eq!(on.stats.photons["caustic"].stored, 0);
    assert!(!stage(&on, "lookups.caustic").ran);
    assert_eq!(auto.film.pixels, on.film.pixels);
}

/// `--caustic-pass off` skips the pass even where caustics exist; `--component` skips the maps
/// the shown term does not read (and the image of that term does not change).
#[test]
fn caustic_pass_off_and_component_skip_their_stages() {
    let s = scene("caustics");
    let off = render_checked(&s, &RenderSettings { caustic_pass: Some(CausticPass::Off), ..quick() }, 16);
    let st = stage(&off, "photons.caustic");
    assert!(!st.ran && st.reason.contains("--caustic-pass off"), "{st:?}");

    let direct = RenderSettings { component: Some(Component::Direct), ..quick() };
    let out = render_checked(&s, &direct, 16);
    for name in ["photons.indirect", "photons.caustic"] {
        let st = stage(&out, name);
        assert!(!st.ran && st.reason.contains("--component"), "{st:?}");
    }
    assert_eq!(out.stats.rays.photon, 0);
    // The same direct term as a render that traced both maps and did not show them.
    let all_maps = RenderSettings { caustic_pass: Some(CausticPass::On), ..direct.clone() };
    assert_eq!(render_checked(&s, &all_maps, 16).film.pixels, out.film.pixels);

    let caustic = render_checked(&s, &RenderSettings { component: Some(Component::Caustic), ..quick() }, 16);
    assert!(!stage(&caustic, "photons.indirect").ran);
    assert!(stage(&caustic, "photons.caustic").ran);
}

/// A light of zero power is reported and emits nothing: the image equals the scene without it.
#[test]
fn zero_power_light_is_reported_and_does_nothing() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell/cornell.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let dark = format!(
        "{text}\n[[light]]\ntype = \"point\"\nposition = [0.3, 0.3, 0.3]\nintensity = [0.0, 0.0, 0.0]\n"
    );
    let with = Scene::from_str(&path, &dark).unwrap();
    let out = render_checked(&with, &quick(), 16);
    let st = stage(&out, "emission.zero_power");
    assert!(!st.ran && st.reason.starts_with("1 of 2 lights"), "{st:?}");
    let without = render_checked(&scene("cornell"), &quick(), 16);
    assert!(without.stats.stages.iter().all(|s| s.name != "emission.zero_power"));
    assert_eq!(out.film.pixels, without.film.pixels);
}

/// Total power of a caustic pass's stored photons and how many there are.
fn caustic_flux(s: &Scene, accel: &AnyAccel, aim: bool, n: u64, seed: u64) -> (f64, usize, u64) {
    let lights = LightSet::new(&s.lights, &s.mesh, &s.tri_material, &s.materials);
    let targets = trace::specular_targets(s);
    let spec = PassSpec {
        pass: Pass::Caustic,
        n,
        color: photonmap::config::ColorMode::Rgb,
        max_bounces: 64,
        targets: &targets,
        aim,
        guide: None,
        portals: None,
        seed,
    };
    let out = photonmap::dispatch!(accel, a => trace::trace_pass(s, a, &lights, &spec, &Quiet));
    let photons = &out.maps[0];
    let flux: f64 = photons.iter().map(|p| (p.power.x + p.power.y + p.power.z) as f64).sum();
    (flux, photons.len(), out.paths)
}

/// Aimed and unaimed caustic photons estimate the same thing. Every stored photon of a pass
/// carries the same power, so the stored flux is that power times a count whose relative
/// standard deviation is about `1/sqrt(count)`: the two fluxes must agree within four combined
/// deviations (measured: 2.0 of them, seeds 11 and 12). Aiming stores as many photons per
/// emission try as plain emission but traces only the tries that head for a specular object
/// (measured: a quarter of them on this scene).
#[test]
fn aiming_keeps_the_caustic_estimate() {
    let s = scene("caustics");
    let accel =
        AnyAccel::build(AccelKind::Bvh, &s.mesh, s.cutouts().as_ref(), AccelOptions::default()).unwrap();
    let lights = LightSet::new(&s.lights, &s.mesh, &s.tri_material, &s.materials);
    let acceptance = trace::target_acceptance(&lights, &trace::specular_targets(&s), 1 << 16, 1);
    let aimed_tries = (20_000.0 / acceptance).ceil() as u64;
    let (on, n_on, paths_on) = caustic_flux(&s, &accel, true, aimed_tries, 11);
    let (off, n_off, paths_off) = caustic_flux(&s, &accel, false, aimed_tries, 12);
    let sigma = (1.0 / n_on as f64 + 1.0 / n_off as f64).sqrt();
    let diff = off / on - 1.0;
    eprintln!(
        "acceptance {acceptance:.4}: aimed {on:.5} W ({n_on} photons of {paths_on} paths), unaimed {off:.5} W ({n_off} of {paths_off}), {diff:+.4} = {:.2} sigma",
        diff.abs() / sigma
    );
    assert!(diff.abs() < 4.0 * sigma, "aimed {on} vs unaimed {off}: {diff:+.4} ({sigma:.4} sigma)");
    // Plain emission traces every try (counts are rounded stochastically per emitter).
    assert!(paths_off.abs_diff(aimed_tries) < aimed_tries / 100, "{paths_off} of {aimed_tries}");
    assert!((paths_on as f64 - acceptance * aimed_tries as f64).abs() < 0.02 * paths_on as f64, "{paths_on}");

    // The same through the whole renderer: the caustic term, aimed with 20k photons and unaimed
    // with as many emission tries as that took. With the same seed the unaimed pass draws the
    // same emission samples, and the tries aiming rejects land on a diffuse surface first and
    // store nothing, so the image is the same bit for bit.
    let base = RenderSettings {
        component: Some(Component::Caustic),
        caustic_photons: Some(20_000),
        spp: Some(4),
        accel: Some(AccelKind::Bvh),
        ..Default::default()
    };
    let aimed = render_checked(&s, &base, 32);
    let tries = aimed.stats.photons["caustic"].emitted;
    let plain = RenderSettings { caustic_aim: Some(false), caustic_photons: Some(tries), ..base.clone() };
    let same = render_checked(&s, &plain, 32);
    assert!(stage(&same, "photons.caustic").reason.contains("--caustic-aim false"));
    assert_eq!(same.stats.photons["caustic"], aimed.stats.photons["caustic"]);
    assert_eq!(same.film.pixels, aimed.film.pixels);

    // With twice the tries the unaimed photons are other samples (the camera samples stay the
    // same): the image means must agree within the photons' noise. That noise is about twice
    // the relative deviation of the stored counts (measured over seeds 1-6 with 20k photons:
    // spread 3.3 %, counts 1.6 %), so the bound is 4 x 2.5 count deviations; with 100k photons
    // the measured difference is +0.7 %.
    let aimed = render_checked(&s, &RenderSettings { caustic_photons: Some(100_000), ..base }, 32);
    let tries = aimed.stats.photons["caustic"].emitted;
    let unaimed = render_checked(&s, &RenderSettings { caustic_photons: Some(2 * tries), ..plain }, 32);
    let (m_on, m_off) = (aimed.film.mean(), unaimed.film.mean());
    let stored = |o: &RenderOutput| o.stats.photons["caustic"].stored as f64;
    let sigma = 2.5 * (1.0 / stored(&aimed) + 1.0 / stored(&unaimed)).sqrt();
    let diff = m_off / m_on - 1.0;
    eprintln!("caustic image mean: aimed {m_on:.5}, unaimed {m_off:.5} ({diff:+.4}, sigma {sigma:.4})");
    assert!(diff.abs() < 4.0 * sigma, "image means {m_on} vs {m_off}: {diff:+.4}");
}

/// `--stats` (and `photonmap bench`) measure the accelerator alone after the render: positive
/// rates per kind, a mixed rate between the slowest and the fastest, and the ratio to it.
#[test]
fn raw_ray_rates_are_measured_when_asked() {
    let s = scene("cornell");
    let cfg = s.render.overridden_by(&quick()).resolve(16, 16).unwrap();
    let plain = render_scene(&s, &cfg, &Quiet).unwrap();
    assert!(plain.stats.raw_rays.is_none() && plain.stats.rays_to_raw_ratio == 0.0);
    let out = render_calibrated(&s, &cfg, &Quiet, Control::default(), 4096).unwrap();
    let raw = out.stats.raw_rays.expect("raw rates");
    let rates = [raw.camera, raw.incoherent, raw.shadow];
    assert!(rates.iter().all(|r| r.is_finite() && *r > 0.0), "{raw:?}");
    let mixed = out.stats.raw_rays_per_second;
    let (lo, hi) = rates.iter().fold((f64::INFINITY, 0.0f64), |(l, h), &r| (l.min(r), h.max(r)));
    assert!(mixed >= lo * 0.999 && mixed <= hi * 1.001, "{mixed} not in [{lo}, {hi}]");
    let ratio = out.stats.rays_to_raw_ratio;
    assert!(ratio > 0.0 && ratio.is_finite(), "{ratio}");
    assert!((ratio - out.stats.rays_per_second / mixed).abs() < 1e-9 * ratio.max(1.0));
    assert_eq!(out.film.pixels, plain.film.pixels);
    // The rate counts the rays of the stages that cast them (photon stages of every kind, the
    // sites' paths included, and the camera stage) over those stages' time, but for the
    // estimate of the precomputed irradiance: its time is left out, and so are its probe rays.
    let st = &out.stats;
    let (all, traced) = (st.rays, st.traced_rays);
    assert!(traced.gather < all.gather, "the sites' probes are counted: {all:?} {traced:?}");
    assert_eq!(all.total() - traced.total(), all.gather - traced.gather);
    assert!(st.seconds("photons.indirect_sites") > 0.0 && st.seconds("photons.guide") > 0.0);
    let traced_seconds = st.tracing_seconds() - st.seconds("camera") * st.camera_time.estimate_share;
    let rate = traced.total() as f64 / traced_seconds;
    assert!((st.rays_per_second - rate).abs() < 1e-9 * rate, "{} vs {rate}", st.rays_per_second);
}

/// `photonmap bench --json` and `photonmap render --stats` from the real binary: one row per
/// thread count with positive rates, and the raw-rate keys in the render's stats.
#[test]
fn bench_command_and_render_stats_report_raw_rates() {
    let dir = tempfile::tempdir().unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let scene = root.join("scenes/cornell/cornell.toml");
    let quick = [
        "--width",
        "16",
        "--height",
        "16",
        "--spp",
        "1",
        "--photons",
        "2000",
        "--caustic-photons",
        "1000",
        "--accel",
        "bvh",
    ];
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_photonmap"))
        .arg("bench")
        .arg(&scene)
        .args(["--runs", "1", "--threads", "1,2", "--raw-rays", "2000", "--json"])
        .args(quick)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let rows = v["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 2);
    for (row, threads) in rows.iter().zip([1, 2]) {
        assert_eq!(row["threads"], threads);
        for key in [
            "seconds",
            "photons_traced_per_second",
            "rays_per_second",
            "raw_rays_per_second",
            "rays_to_raw_ratio",
            "bytes_per_photon",
            "speedup",
        ] {
            assert!(row[key].as_f64().unwrap() > 0.0, "{key}: {row}");
        }
    }
    assert_eq!(rows[0]["speedup"], 1.0);

    let stats = dir.path().join("stats.json");
    let status = std::process::Command::new(env!("CARGO_BIN_EXE_photonmap"))
        .arg("render")
        .arg(&scene)
        .arg("-o")
        .arg(dir.path().join("out.exr"))
        .arg("--stats")
        .arg(&stats)
        .arg("--quiet")
        .args(quick)
        .status()
        .unwrap();
    assert!(status.success());
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
    assert!(v["raw_rays_per_second"].as_f64().unwrap() > 0.0, "{v}");
    assert!(v["rays_to_raw_ratio"].as_f64().unwrap() > 0.0);
    assert!(v["raw_rays"]["shadow"].as_f64().unwrap() > 0.0);
}

/// The indirect estimate is read at a quarter of a pixel's samples (at least 4): on the Cornell
/// box, pixels of 64 samples (16 readings, weighted 4) average to what pixels that read it at
/// each of their 4 samples give, and the count follows the rule.
#[test]
fn the_indirect_estimate_at_a_quarter_of_the_samples_keeps_its_mean() {
    use photonmap::integrator::photon::indirect_samples;
    let counts: Vec<u32> = [1, 3, 4, 8, 16, 17, 64].into_iter().map(indirect_samples).collect();
    assert_eq!(counts, [1, 3, 4, 4, 4, 5, 16]);
    let s = scene("cornell");
    let indirect = |spp| {
        let r = RenderSettings { component: Some(Component::Indirect), spp: Some(spp), ..quick() };
        render_checked(&s, &r, 32).film.mean()
    };
    let (every, quarter) = (indirect(4), indirect(64));
    assert!(every > 0.0 && ((quarter - every) / every).abs() < 0.01, "{quarter} vs {every}");
}

/// Precomputed irradiance is estimated where the camera reads it: in the doorway scene the
/// camera looks through the door into the lit room and reads a fraction of the sites (on the
/// default render, 21 % of them, a block of 32 at a time); the stats say how many
/// (`irradiance_cache.seen` of `stored`) and what share of the camera stage it took.
#[test]
fn precomputed_irradiance_is_estimated_where_the_camera_reads_it() {
    let out = render_checked(&scene("doorway"), &quick(), 32);
    let st = stage(&out, "irradiance");
    assert!(st.ran && st.reason.contains("estimated as read"), "{st:?}");
    let sites = &out.stats.photons["irradiance_cache"];
    assert!(sites.stored > 1000, "{sites:?}");
    assert!(sites.seen > 0 && sites.seen * 2 < sites.stored, "{sites:?}");
    assert!((sites.efficiency - sites.seen as f64 / sites.stored as f64).abs() < 1e-12);
    let share = out.stats.camera_time.estimate_share;
    assert!(share > 0.0 && share < 1.0, "{share}");
}

/// The caustic term read from precomputed caustic irradiance (the default) has the mean of the
/// caustic map's gathers at every sample (`--irradiance-cache false`), from the same map: the
/// sites are points of their own, not the map's photons (at the photons, counting each site's
/// own photon made it 5.6 % too bright, leaving it out 6.6 % too dark).
#[test]
fn precomputed_caustics_keep_the_mean_of_the_gathers() {
    let s = scene("caustics");
    let caustic = |cache| {
        let r = RenderSettings {
            component: Some(Component::Caustic),
            caustic_photons: Some(200_000),
            spp: Some(4),
            irradiance_cache: Some(cache),
            ..quick()
        };
        render_checked(&s, &r, 48)
    };
    let (cached, gathered) = (caustic(true), caustic(false));
    let st = stage(&cached, "irradiance.caustic");
    assert!(st.ran && st.reason.contains("sites where caustic paths land"), "{st:?}");
    assert!(stage(&cached, "photons.caustic_sites").ran);
    let st = stage(&gathered, "irradiance.caustic");
    assert!(!st.ran && st.reason.contains("--irradiance-cache false"), "{st:?}");
    let (a, b) = (cached.film.mean(), gathered.film.mean());
    assert!(b > 0.0 && ((a - b) / b).abs() < 0.03, "{a} vs {b}");
}
