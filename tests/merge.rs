//! Passes rendered apart and merged (`render --pass-range`, `photonmap merge`), run as a user
//! runs them: the merged image is bit for bit the one-process render however the passes are
//! split and in whatever order the parts are given, for the pass-indexed progressive mapper, the
//! two-pass photon mapper and the path tracer; the error estimate's layer and `--target-error`;
//! and every part that does not belong refused in one line, exit status 1, nothing written.

use photonmap::batch::meta::VERSION;
use photonmap::film::partial::PartialFilm;
use photonmap::film::Film;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

fn photonmap(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_photonmap"))
        .args(args)
        .env_remove("RUST_BACKTRACE")
        .stdin(Stdio::null())
        .output()
        .expect("photonmap runs")
}

fn scene(name: &str) -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name).join(format!("{name}.toml"));
    path.to_str().unwrap().to_string()
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

fn ok(out: Output) -> Output {
    assert!(out.status.success(), "{}", text(&out.stderr));
    out
}

/// The stderr of a run that must fail with status 1, as one line (a trailing summary aside).
fn refused(out: Output) -> String {
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    let errors: Vec<&str> = err.lines().filter(|l| l.contains("error")).collect();
    assert_eq!(errors.len(), 1, "one error line: {err}");
    errors[0].to_string()
}

/// Small settings of `integrator`, `passes` passes in all.
fn settings(integrator: &str, passes: u32) -> Vec<String> {
    let mut s: Vec<String> = ["--integrator", integrator, "--width", "24", "--height", "20", "--spp", "2"]
        .map(String::from)
        .to_vec();
    if integrator != "path" {
        s.extend(["--photons", "6000"].map(String::from));
    }
    s.extend(["--passes".to_string(), passes.to_string(), "--seed".into(), "11".into()]);
    s
}

/// Renders `scene`'s passes `range` (all of them when `None`) to `out`.
fn render(scene: &str, settings: &[String], range: Option<&str>, out: &Path) -> Output {
    let mut args: Vec<String> = vec!["render".into(), scene.into()];
    args.extend(settings.iter().cloned());
    if let Some(r) = range {
        args.extend(["--pass-range".to_string(), r.to_string()]);
    }
    args.extend(["-o".to_string(), out.to_str().unwrap().to_string()]);
    photonmap(&args.iter().map(String::as_str).collect::<Vec<_>>())
}

fn merge(parts: &[&Path], out: &Path, extra: &[&str]) -> Output {
    let mut args: Vec<&str> = vec!["merge"];
    args.extend(parts.iter().map(|p| p.to_str().unwrap()));
    args.extend(["-o", out.to_str().unwrap()]);
    args.extend(extra);
    photonmap(&args)
}

fn bits(path: &Path) -> Vec<u32> {
    let film = Film::read_exr(path).unwrap_or_else(|e| panic!("{e}"));
    film.pixels.iter().flat_map(|p| [p.x, p.y, p.z]).map(f32::to_bits).collect()
}

/// Renders the parts `ranges` of `settings` in `dir`, named by their ranges.
fn parts(dir: &Path, scene: &str, settings: &[String], ranges: &[&str]) -> Vec<PathBuf> {
    ranges
        .iter()
        .map(|r| {
            let path = dir.join(format!("part-{}.exr", r.replace("..", "-")));
            ok(render(scene, settings, Some(r), &path));
            path
        })
        .collect()
}

/// One process against 4 parts in two splits, each merged in two orders.
fn merged_equals_one_process(integrator: &str) {
    let dir = tempfile::tempdir().unwrap();
    let cornell = scene("cornell");
    let s = settings(integrator, 8);
    let single = dir.path().join("single.exr");
    ok(render(&cornell, &s, None, &single));
    let want = bits(&single);
    assert!(want.iter().any(|&b| f32::from_bits(b) > 0.0), "a black image proves nothing");
    for (split, orders) in [
        (["0..2", "2..4", "4..6", "6..8"], [[0, 1, 2, 3], [3, 1, 0, 2]]),
        (["0..1", "1..4", "4..7", "7..8"], [[2, 0, 3, 1], [1, 3, 2, 0]]),
    ] {
        let split_dir = dir.path().join(split.join("_").replace("..", "-"));
        std::fs::create_dir(&split_dir).unwrap();
        let files = parts(&split_dir, &cornell, &s, &split);
        for order in orders {
            let given: Vec<&Path> = order.iter().map(|&i| files[i].as_path()).collect();
            let out = split_dir.join(format!("merged-{order:?}.exr"));
            ok(merge(&given, &out, &[]));
            let got = bits(&out);
            let differing = want.iter().zip(&got).filter(|(a, b)| a != b).count();
            assert_eq!(
                differing, 0,
                "{integrator}: split {split:?} merged as {order:?}: {differing} values differ"
            );
        }
    }
}

#[test]
fn pppm_parts_merge_to_the_one_process_image_bit_for_bit() {
    merged_equals_one_process("pppm");
}

/// A render of 16 passes or more without `--spp` lets pppm's pilot choose the camera samples of
/// a pass and widen the first radii (`src/integrator/balance.rs`, `bandwidth.rs`): each part's
/// pilot makes the same choices from the render's seed, so the parts still merge bit for bit.
#[test]
fn pppm_parts_with_the_pilots_choices_merge_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let cornell = scene("cornell");
    let s: Vec<String> = settings("pppm", 16).into_iter().filter(|a| a != "--spp" && a != "2").collect();
    assert!(!s.contains(&"--spp".to_string()), "{s:?}");
    let single = dir.path().join("single.exr");
    ok(render(&cornell, &s, None, &single));
    let files = parts(dir.path(), &cornell, &s, &["0..5", "5..16"]);
    let out = dir.path().join("merged.exr");
    ok(merge(&[&files[1], &files[0]], &out, &[]));
    assert_eq!(bits(&out), bits(&single));
}

#[test]
fn photon_map_parts_merge_to_the_one_process_image_bit_for_bit() {
    merged_equals_one_process("photon");
}

#[test]
fn path_traced_parts_merge_to_the_one_process_image_bit_for_bit() {
    merged_equals_one_process("path");
}

#[test]
fn the_error_layer_and_the_target_error() {
    let dir = tempfile::tempdir().unwrap();
    let cornell = scene("cornell");
    let s = settings("pppm", 6);
    let files = parts(dir.path(), &cornell, &s, &["0..3", "3..6"]);
    let given: Vec<&Path> = files.iter().map(PathBuf::as_path).collect();
    let out = dir.path().join("merged.exr");
    let stats = dir.path().join("stats.json");
    ok(merge(&given, &out, &["--error-layer", "--stats", stats.to_str().unwrap()]));
    let report: serde_json::Value = serde_json::from_slice(&std::fs::read(&stats).unwrap()).unwrap();
    let estimate = &report["error_estimate"];
    let (rmse, relative) = (estimate["rmse"].as_f64().unwrap(), estimate["relative_rmse"].as_f64().unwrap());
    assert!(rmse > 0.0 && relative > 0.0 && relative.is_finite(), "{report}");
    // The layer is the per-pixel estimate: its mean square is the image's estimated MSE.
    let layer = error_layer(&out);
    assert_eq!(layer.len(), 24 * 20);
    assert!(layer.iter().all(|e| e.is_finite() && *e >= 0.0));
    let mse = layer.iter().map(|&e| (e as f64).powi(2)).sum::<f64>() / layer.len() as f64;
    assert!((mse.sqrt() / rmse - 1.0).abs() < 0.05, "layer RMS {} vs estimated RMSE {rmse}", mse.sqrt());
    // A target the estimate misses exits 3 (the image is still written); one it meets exits 0.
    let missed =
        merge(&given, &dir.path().join("missed.exr"), &["--target-error", &(relative / 2.0).to_string()]);
    assert_eq!(missed.status.code(), Some(3), "{}", text(&missed.stderr));
    assert!(dir.path().join("missed.exr").exists());
    ok(merge(&given, &dir.path().join("met.exr"), &["--target-error", &(relative * 2.0).to_string()]));
}

/// The `error` channel of an EXR.
fn error_layer(path: &Path) -> Vec<f32> {
    use exr::prelude::*;
    let image =
        read().no_deep_data().largest_resolution_level().all_channels().first_valid_layer().all_attributes();
    let image = image.from_file(path).unwrap();
    let channel = image.layer_data.channel_data.list.iter().find(|c| c.name.to_string() == "error");
    let channel = channel.expect("an error channel");
    match &channel.sample_data {
        FlatSamples::F32(v) => v.clone(),
        other => panic!("error channel of another type: {other:?}"),
    }
}

#[test]
fn parts_that_do_not_belong_are_refused_in_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (cornell, caustics) = (scene("cornell"), scene("caustics"));
    let s = settings("pppm", 6);
    let files = parts(d, &cornell, &s, &["0..2", "2..4", "4..6"]);
    let out = d.join("out.exr");
    let refuse = |parts: &[&Path], extra: &[&str], says: &[&str]| {
        let line = refused(merge(parts, &out, extra));
        for s in says {
            assert!(line.contains(s), "{line:?} should say {s:?}");
        }
        assert!(!out.exists(), "{line}: an output was written");
    };
    // Another scene, other settings, overlapping passes, missing passes.
    let other_scene = d.join("caustics.exr");
    ok(render(&caustics, &s, Some("4..6"), &other_scene));
    refuse(&[&files[0], &files[1], &other_scene], &[], &["caustics.exr", "another scene"]);
    let more_photons: Vec<String> =
        s.iter().map(|a| if a == "6000" { "7000".into() } else { a.clone() }).collect();
    let other_settings = d.join("photons.exr");
    ok(render(&cornell, &more_photons, Some("4..6"), &other_settings));
    refuse(&[&files[0], &files[1], &other_settings], &[], &["photons.exr", "other settings"]);
    let overlapping = d.join("overlap.exr");
    ok(render(&cornell, &s, Some("3..6"), &overlapping));
    refuse(&[&files[0], &files[1], &overlapping], &[], &["overlap.exr", "3..6", "overlap", "2..4"]);
    refuse(&[&files[0], &files[2]], &[], &["passes 2..4 of 6 are missing", "--partial"]);
    // A truncated part, a plain image, a part from another version.
    let truncated = d.join("truncated.exr");
    let bytes = std::fs::read(&files[2]).unwrap();
    std::fs::write(&truncated, &bytes[..bytes.len() / 2]).unwrap();
    refuse(&[&files[0], &files[1], &truncated], &[], &["truncated.exr"]);
    let plain = d.join("plain.exr");
    ok(render(&cornell, &settings("pppm", 2), None, &plain));
    refuse(&[&files[0], &plain], &[], &["plain.exr", "not a partial film"]);
    let old = d.join("old.exr");
    let mut part = PartialFilm::read(&files[2]).unwrap();
    part.attributes.insert(VERSION.into(), "0.0.1".into());
    let record: Vec<(&str, String)> = part.attributes.iter().map(|(k, v)| (k.as_str(), v.clone())).collect();
    PartialFilm::write(&old, &part.sums, part.range.clone(), part.total, &record).unwrap();
    refuse(&[&files[0], &files[1], &old], &[], &["old.exr", "0.0.1"]);
    // A part given twice overlaps itself; a part that is also the output is refused before
    // anything is read.
    refuse(&[&files[0], &files[1], &files[1]], &[], &["overlap"]);
    let line = refused(merge(&[&files[0]], &files[0], &[]));
    assert!(line.contains("also an output"), "{line}");
    assert!(PartialFilm::read(&files[0]).is_ok(), "the part was overwritten");
    // What there is, merged when asked: the state says which passes it holds.
    ok(merge(&[&files[0], &files[2]], &out, &["--partial"]));
    let meta = Film::read_exr_meta(&out).unwrap();
    assert_eq!(meta.get("photonmap.state").map(String::as_str), Some("partial: 4 of 6 passes"), "{meta:?}");
}

#[test]
fn pass_ranges_that_cannot_be_parts_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("part.exr");
    let cornell = scene("cornell");
    let cases: [(&[&str], &str, &str); 7] = [
        (&["--integrator", "pppm", "--passes", "4"], "5..3", "not A..B"),
        (&["--integrator", "pppm", "--passes", "4"], "2..6", "beyond the render's 4 passes"),
        (&["--integrator", "path"], "0..2", "needs --passes"),
        (&["--integrator", "sppm", "--passes", "4"], "0..2", "use --integrator pppm"),
        (&["--integrator", "pppm", "--passes", "4", "--time", "3"], "0..2", "--time"),
        (&["--integrator", "pppm", "--passes", "4", "--error-layer"], "0..2", "--error-layer"),
        (&["--integrator", "pppm", "--passes", "4", "--png", "p.png"], "0..2", "--png"),
    ];
    for (flags, range, says) in cases {
        let mut args =
            vec!["render", cornell.as_str(), "--width", "8", "--height", "8", "--pass-range", range];
        args.extend(flags);
        args.extend(["-o", out.to_str().unwrap()]);
        let line = refused(photonmap(&args));
        assert!(line.contains(says), "{args:?}: {line:?} should say {says:?}");
        assert!(!out.exists());
    }
}

#[test]
fn parts_merged_in_a_tree_give_the_same_image() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let cornell = scene("cornell");
    let s = settings("pppm", 8);
    let single = d.join("single.exr");
    ok(render(&cornell, &s, None, &single));
    let files = parts(d, &cornell, &s, &["0..2", "2..3", "3..5", "5..8"]);
    // Two nodes, each merging its own parts into one, then the two merged.
    let (left, right) = (d.join("left.exr"), d.join("right.exr"));
    ok(merge(&[&files[1], &files[0]], &left, &["--part"]));
    ok(merge(&[&files[2], &files[3]], &right, &["--part"]));
    let node = PartialFilm::read(&right).unwrap();
    assert_eq!((node.range.clone(), node.total), (3..8, 8));
    let out = d.join("tree.exr");
    ok(merge(&[&right, &left], &out, &[]));
    assert!(bits(&out) == bits(&single), "the tree's image differs from one process's");
    // A part holds consecutive passes: a gap is refused, and so are the image's options.
    let line = refused(merge(&[&files[0], &files[3]], &d.join("gap.exr"), &["--part"]));
    assert!(line.contains("passes 2..5 are missing between 0..8"), "{line}");
    assert!(!d.join("gap.exr").exists());
    let out = merge(&[&files[0], &files[1]], &d.join("png.exr"), &["--part", "--png", "p.png"]);
    assert_eq!(out.status.code(), Some(2), "{}", text(&out.stderr));
}
