//! What the `photonmap` binary prints, run as a user runs it: `info` as a table and as JSON,
//! `--version`, the summaries' wording, a closed pipe, Ctrl-C during a single-pass render, and
//! errors said once (each case one that a new user met).

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

fn photonmap() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_photonmap"));
    c.env_remove("RUST_BACKTRACE").stdin(Stdio::null());
    c
}

fn scene(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name)
}

fn run(args: &[&str]) -> Output {
    photonmap().args(args).output().expect("photonmap runs")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

#[test]
fn info_prints_a_readable_table() {
    let out = run(&["info", scene("cornell/cornell.toml").to_str().unwrap()]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let t = text(&out.stdout);
    assert!(!t.contains('{') && !t.contains("Vec3"), "Rust debug output: {t}");
    assert!(t.contains("36 triangles"), "{t}");
    let row = t.lines().find(|l| l.contains("white")).expect("a row for the white material");
    let cells: Vec<&str> = row.split_whitespace().collect();
    assert_eq!(cells[..4], ["white", "diffuse", "30", "kd"], "{row}");
    let light = t.lines().find(|l| l.trim_start().starts_with("area")).expect("the area light's row");
    assert!(light.contains("triangles 2"), "{light}");
}

#[test]
fn info_json_holds_the_same_scene() {
    let out = run(&["info", "--json", scene("cornell/cornell.toml").to_str().unwrap()]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("info --json prints JSON");
    assert_eq!(v["triangles"], 36);
    let white = v["materials"].as_array().unwrap().iter().find(|m| m["name"] == "white").unwrap();
    assert_eq!(white["type"], "diffuse");
    assert_eq!(white["triangles"], 30);
    assert_eq!(white["parameters"]["kd"].as_array().unwrap().len(), 3);
    let lights = v["lights"].as_array().unwrap();
    assert_eq!(lights.len(), 1);
    assert_eq!(lights[0]["type"], "area");
    // π ke A: ke = 17 on the 0.13 × 0.105 m ceiling light.
    let power = lights[0]["power"][0].as_f64().unwrap();
    let expected = std::f64::consts::PI * 17.0 * 0.13 * 0.105;
    assert!((power / expected - 1.0).abs() < 0.01, "{power} W, expected {expected}");
}

#[test]
fn version_names_the_ray_caster() {
    let out = run(&["--version"]);
    assert!(out.status.success());
    let t = text(&out.stdout);
    assert!(t.starts_with(&format!("photonmap {}", env!("CARGO_PKG_VERSION"))), "{t}");
    #[cfg(feature = "embree")]
    let expected = format!("Embree {}", photonmap::accel::embree::version());
    #[cfg(not(feature = "embree"))]
    let expected = "BVH only".to_string();
    assert!(t.contains(&expected), "{t}");
}

/// A reader that goes away ends the program quietly: the shell's code for SIGPIPE, no panic.
#[test]
fn a_closed_pipe_ends_info_quietly() {
    // The bunny takes far longer to load than the pipe takes to be closed below.
    let mut child = photonmap()
        .args(["info", scene("bunny/bunny.toml").to_str().unwrap()])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let err = text(&out.stderr);
    assert!(!err.contains("panicked") && !err.contains("Broken pipe"), "{err}");
    assert_eq!(out.status.code(), Some(141), "{err}");
}

/// Whether process `pid` has a handler for SIGINT (Linux: bit 2 of `SigCgt`).
fn catches_sigint(pid: u32) -> bool {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).unwrap_or_default();
    let mask = status.lines().find_map(|l| l.strip_prefix("SigCgt:")).map(str::trim).unwrap_or("0");
    u64::from_str_radix(mask, 16).is_ok_and(|m| m & 0b10 != 0)
}

/// Ctrl-C during a single-pass render quits at once and says so; no image is left.
#[test]
fn ctrl_c_during_a_single_pass_render_says_nothing_was_written() {
    if !Path::new("/proc/self/status").exists() {
        return; // the handler cannot be seen installed without Linux's /proc
    }
    let dir = tempfile::tempdir().unwrap();
    let output = dir.path().join("out.exr");
    let mut child = photonmap()
        .args(["render", scene("cornell/cornell.toml").to_str().unwrap(), "-o"])
        .arg(&output)
        .args(["--photons", "50000000", "--width", "16", "--height", "16"])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while !catches_sigint(child.id()) {
        assert!(start.elapsed() < Duration::from_secs(60), "the Ctrl-C handler was never installed");
        assert!(child.try_wait().unwrap().is_none(), "the render ended before it could be interrupted");
        std::thread::sleep(Duration::from_millis(10));
    }
    let kill = Command::new("kill").args(["-INT", &child.id().to_string()]).status().unwrap();
    assert!(kill.success());
    let out = child.wait_with_output().unwrap();
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(130), "{err}");
    assert!(err.contains("interrupted: nothing written"), "{err}");
    assert!(!output.exists(), "an image was written");
}

#[test]
fn compare_says_when_a_file_is_not_openexr() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("x.png");
    std::fs::write(&png, b"\x89PNG\r\n\x1a\n not really").unwrap();
    let out = run(&["compare", png.to_str().unwrap(), "--exact", "1"]);
    assert!(!out.status.success());
    let err = text(&out.stderr);
    assert!(err.contains("x.png: not an OpenEXR file"), "{err}");
}

/// `compare --region` judges only the pixels asked for: two images that differ in one pixel
/// compare equal over a region without it, and a region that is empty, malformed or off the
/// image is refused with a line naming it.
#[test]
fn compare_judges_a_region() {
    use photonmap::film::Film;
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a.exr"), dir.path().join("b.exr"));
    let mut film = Film::new(4, 4);
    film.pixels.fill(glam::Vec3::ONE);
    film.write_exr(&a).unwrap();
    film.pixels[0] = glam::Vec3::splat(5.0);
    film.write_exr(&b).unwrap();
    let compare = |extra: &[&str]| {
        let mut args = vec!["compare", b.to_str().unwrap(), a.to_str().unwrap()];
        args.extend_from_slice(extra);
        run(&args)
    };
    let whole = compare(&[]);
    assert!(whole.status.success());
    assert!(text(&whole.stdout).contains("mean 1.25000 vs 1.00000 (+25.00%)"), "{}", text(&whole.stdout));
    let region = compare(&["--region", "1,0,4,4"]);
    assert!(region.status.success(), "{}", text(&region.stderr));
    assert!(text(&region.stdout).starts_with("rmse 0.00000"), "{}", text(&region.stdout));
    assert!(text(&region.stdout).contains("mean 1.00000 vs 1.00000"), "{}", text(&region.stdout));
    let corner = compare(&["--region", "0,0,1,1", "--json"]);
    let v: serde_json::Value = serde_json::from_slice(&corner.stdout).unwrap();
    assert_eq!(v["mean"].as_f64(), Some(5.0), "{v}");
    for (bad, says) in
        [("2,0,2,4", "the region is empty"), ("1,2,3", "four numbers"), ("0,0,5,4", "does not fit")]
    {
        let out = compare(&["--region", bad]);
        assert!(!out.status.success(), "{bad}");
        let err = text(&out.stderr);
        assert!(err.contains(says) && err.lines().count() == 1, "{bad}: {err}");
    }
}

#[test]
fn a_cause_is_said_once() {
    let dir = tempfile::tempdir().unwrap();
    let out = run(&["compare", dir.path().to_str().unwrap(), "--exact", "1"]);
    let err = text(&out.stderr);
    assert_eq!(err.matches("Is a directory").count(), 1, "{err}");
    let out = run(&["compare", dir.path().join("nosuch.exr").to_str().unwrap(), "--exact", "1"]);
    let err = text(&out.stderr);
    assert_eq!(err.matches("No such file").count(), 1, "{err}");
}

#[test]
fn summaries_count_in_words_that_agree() {
    let dir = tempfile::tempdir().unwrap();
    let out = photonmap()
        .current_dir(dir.path())
        .args(["render", scene("cornell/cornell.toml").to_str().unwrap(), "-o", "c.exr"])
        .args(["--width", "8", "--height", "8", "--spp", "1", "--photons", "2000", "--threads", "1"])
        .args(["--integrator", "sppm", "--passes", "2"])
        .output()
        .unwrap();
    let err = text(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(err.contains("on 1 thread\n") || err.ends_with("on 1 thread"), "{err}");
    assert!(err.contains("1 spp a pass, 2 passes"), "{err}");

    let out = run(&[
        "bench",
        scene("cornell/cornell.toml").to_str().unwrap(),
        "--width",
        "8",
        "--height",
        "8",
        "--runs",
        "1",
        "--threads",
        "1",
        "--photons",
        "2000",
        "--spp",
        "1",
        "--raw-rays",
        "1000",
    ]);
    let t = text(&out.stdout);
    assert!(out.status.success(), "{}", text(&out.stderr));
    // The Cornell box has no mirror or glass: no caustic photons are traced, whatever the budget.
    assert!(t.contains("no caustic pass"), "{t}");
    assert!(t.contains("one run each") && !t.contains("1 runs"), "{t}");
    assert!(t.contains(" 1 thread") && !t.contains("1 threads"), "{t}");
}

/// Reads an 8-bit RGB PNG's bytes.
fn png_bytes(path: &Path) -> Vec<u8> {
    let decoder = png::Decoder::new(std::fs::File::open(path).unwrap());
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).unwrap();
    buf.truncate(info.buffer_size());
    buf
}

/// `--exposure` and `--tonemap` change the PNG preview, never the EXR.
#[test]
fn exposure_and_tone_curve_shape_the_png_only() {
    let dir = tempfile::tempdir().unwrap();
    let render = |name: &str, flags: &[&str]| {
        let out = photonmap()
            .current_dir(dir.path())
            .args(["render", scene("sunroom/sunroom.toml").to_str().unwrap()])
            .args(["-o", &format!("{name}.exr"), "--png", &format!("{name}.png"), "--quiet"])
            .args(["--width", "24", "--height", "24", "--spp", "2", "--photons", "20000", "--threads", "2"])
            .args(flags)
            .output()
            .unwrap();
        assert!(out.status.success(), "{}", text(&out.stderr));
        let exr = photonmap::film::Film::read_exr(&dir.path().join(format!("{name}.exr"))).unwrap();
        (exr, png_bytes(&dir.path().join(format!("{name}.png"))))
    };
    let mean = |b: &[u8]| b.iter().map(|&v| v as f64).sum::<f64>() / b.len() as f64;
    let white = |b: &[u8]| b.iter().filter(|&&v| v == 255).count();
    let (exr, plain) = render("plain", &[]);
    let (exr_dark, dark) = render("dark", &["--exposure", "-2"]);
    let (exr_aces, aces) = render("aces", &["--exposure", "6", "--tonemap", "aces"]);
    let (_, bright) = render("bright", &["--exposure", "6"]);
    assert!(exr == exr_dark, "--exposure changed the EXR");
    assert!(exr == exr_aces, "--tonemap changed the EXR");
    assert!(mean(&dark) < 0.8 * mean(&plain), "{} vs {}", mean(&dark), mean(&plain));
    // Six stops up the room clips when clamped; the ACES curve keeps most of it below white.
    assert!(white(&bright) > white(&plain) + 100, "{} white bytes vs {}", white(&bright), white(&plain));
    assert!(white(&aces) < white(&bright) / 2, "{} white bytes vs {}", white(&aces), white(&bright));
}

/// `--photons 0` is a render of the direct light (the README says so): no indirect map is made.
#[test]
fn zero_photons_render_the_direct_light() {
    let dir = tempfile::tempdir().unwrap();
    let out = photonmap()
        .current_dir(dir.path())
        .args(["render", scene("cornell/cornell.toml").to_str().unwrap(), "-o", "d.exr", "--quiet"])
        .args(["--width", "8", "--height", "8", "--spp", "4", "--photons", "0", "--stats", "d.json"])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", text(&out.stderr));
    let stats: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("d.json")).unwrap()).unwrap();
    let stage = stats["stages"].as_array().unwrap().iter().find(|s| s["name"] == "photons.indirect").unwrap();
    assert_eq!(stage["ran"], false, "{stage}");
    assert_eq!(stage["reason"], "photon budget is 0", "{stage}");
    let film = photonmap::film::Film::read_exr(&dir.path().join("d.exr")).unwrap();
    assert!(film.mean() > 0.01, "no direct light: mean {}", film.mean());
}

/// `converge --peers` refuses figures timed at another resolution than the renders'.
#[test]
fn converge_refuses_peers_measured_at_another_size() {
    let dir = tempfile::tempdir().unwrap();
    let peers = dir.path().join("peers.csv");
    std::fs::write(&peers, "scene,renderer,width,height,seconds,rmse\nfurnace,Other,64,64,5,0.01\n").unwrap();
    let out = run(&[
        "converge",
        scene("furnace/furnace.toml").to_str().unwrap(),
        "--exact",
        "2",
        "--budgets",
        "0.1",
        "--peers",
        peers.to_str().unwrap(),
    ]);
    let err = text(&out.stderr);
    assert!(!out.status.success(), "{err}");
    assert!(
        err.contains("peers.csv: line 2: Other was measured at 64x64 but the renders are 256x256"),
        "{err}"
    );
}

/// What `args` draws on a terminal (run under `script`, which gives it one), escapes and all;
/// `None` where `script` (util-linux) is missing.
fn on_a_terminal(dir: &Path, args: &[&str]) -> Option<String> {
    let quote = |a: &str| format!("'{}'", a.replace('\'', r"'\''"));
    let line: Vec<String> =
        std::iter::once(env!("CARGO_BIN_EXE_photonmap")).chain(args.iter().copied()).map(quote).collect();
    let out = Command::new("script")
        .current_dir(dir)
        .args(["-qec", &line.join(" "), "/dev/null"])
        .stdin(Stdio::null())
        .output()
        .ok()?;
    assert!(out.status.success(), "{}", text(&out.stdout));
    Some(text(&out.stdout))
}

/// Every stage longer than a moment has a bar: the photons, the camera (the precomputed
/// irradiance, estimated as the camera reads it, has none of its own); a progressive
/// render's bar counts passes and photons; `converge` has one bar over all its renders.
#[test]
fn long_stages_show_bars_with_counts() {
    let dir = tempfile::tempdir().unwrap();
    let cornell = scene("cornell/cornell.toml");
    let cornell = cornell.to_str().unwrap();
    let small = ["--width", "16", "--height", "16", "--spp", "1"];
    let Some(plain) = on_a_terminal(dir.path(), &[&["render", cornell, "-o", "a.exr"][..], &small].concat())
    else {
        eprintln!("no `script` here: the bars cannot be seen");
        return;
    };
    for bar in ["indirect photons [", "camera ["] {
        assert!(plain.contains(bar), "no bar {bar:?}: {plain:?}");
    }
    let sppm =
        [&["render", cornell, "-o", "b.exr", "--integrator", "sppm", "--passes", "3"][..], &small].concat();
    let sppm = on_a_terminal(dir.path(), &sppm).unwrap();
    assert!(sppm.contains("3 passes, 300k photons"), "the sppm bar does not count: {sppm:?}");
    let furnace = scene("furnace/furnace.toml");
    let converge = ["converge", furnace.to_str().unwrap(), "--exact", "2"];
    let converge = [&converge[..], &["--budgets", "0.2", "--methods", "path,sppm"]].concat();
    let converge = on_a_terminal(dir.path(), &converge).unwrap();
    assert!(converge.contains("converge [") && converge.contains("of 2 renders"), "{converge:?}");
}

/// What a scene asks for that changes nothing is warned, once, on stderr; the render goes on.
#[test]
fn an_unused_material_and_a_scene_without_light_are_warned() {
    let dir = tempfile::tempdir().unwrap();
    for f in ["cornell.toml", "cornell.obj", "cornell.mtl"] {
        std::fs::copy(scene("cornell").join(f), dir.path().join(f)).unwrap();
    }
    let toml = std::fs::read_to_string(dir.path().join("cornell.toml")).unwrap();
    let toml =
        toml.replacen("[materials.white]", "[materials.whte]\ntype = \"diffuse\"\n\n[materials.white]", 1);
    let dark = toml.replacen("ke = [17.0, 12.0, 4.0]", "ke = [0.0, 0.0, 0.0]", 1);
    std::fs::write(dir.path().join("typo.toml"), &toml).unwrap();
    std::fs::write(dir.path().join("dark.toml"), &dark).unwrap();
    let render = |name: &str| {
        photonmap()
            .current_dir(dir.path())
            .args([
                "render",
                name,
                "--quiet",
                "--width",
                "8",
                "--height",
                "8",
                "--spp",
                "1",
                "--photons",
                "1000",
            ])
            .output()
            .unwrap()
    };
    let out = render("typo.toml");
    let err = text(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert_eq!(err.matches("warning:").count(), 1, "{err}");
    assert!(err.contains("typo.toml: [materials.whte] is used by no triangle"), "{err}");
    assert!(err.contains("green, light, red, white"), "the materials in use are not named: {err}");
    let out = render("dark.toml");
    let err = text(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains("dark.toml: no [[light]] and no emissive material: the image will be black"),
        "{err}"
    );
    // The shipped scenes warn of nothing.
    let shipped = std::fs::read_dir(scene(""))
        .unwrap()
        .flat_map(|d| std::fs::read_dir(d.unwrap().path()).into_iter().flatten());
    for entry in shipped {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "toml") {
            let out = run(&["info", path.to_str().unwrap()]);
            assert!(
                out.status.success() && out.stderr.is_empty(),
                "{}: {}",
                path.display(),
                text(&out.stderr)
            );
        }
    }
}

/// An MTL whose Phong fields add up past 1 (`Kd 0.8`, `Ks 0.5`, `illum 2`, as Blender's export
/// writes them, but from another program) renders, its Kd and
/// Ks scaled to conserve energy with a warning naming the MTL line; `d 0.3` and `illum 9` are
/// warned as not rendered as written, and so are the PBR extension's `Pr` and `Pm`.
#[test]
fn an_mtl_past_energy_renders_with_warnings_naming_its_lines() {
    let dir = tempfile::tempdir().unwrap();
    let obj = "mtllib t2.mtl\nv -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\nv -1 0 2\nv 1 0 2\n\
               usemtl white\nf 1 3 2\nf 1 4 3\nusemtl odd\nf 4 6 3\nf 4 5 6\n";
    let mtl = "# Some exporter\nnewmtl white\nNs 250.000000\nKa 1.0 1.0 1.0\nKd 0.800000 0.800000 0.800000\n\
               Ks 0.500000 0.500000 0.500000\nKe 0.0 0.0 0.0\nNi 1.45\nd 1.0\nillum 2\n\n\
               newmtl odd\nKd 0.5 0.5 0.5\nd 0.3\nillum 9\nPr 0.5\nPm 1.0\n";
    let toml = "[camera]\neye = [0, 3, -3]\ntarget = [0, 0, 0]\nup = [0, 1, 0]\nvfov_deg = 60\nwidth = 8\nheight = 8\n\n\
                [[mesh]]\nobj = \"t2.obj\"\n\n[[light]]\ntype = \"point\"\nposition = [0, 2, 0]\nintensity = [1, 1, 1]\n";
    std::fs::write(dir.path().join("t2.obj"), obj).unwrap();
    std::fs::write(dir.path().join("t2.mtl"), mtl).unwrap();
    std::fs::write(dir.path().join("t2.toml"), toml).unwrap();
    let out = photonmap()
        .current_dir(dir.path())
        .args(["render", "t2.toml", "--quiet", "--spp", "1", "--photons", "1000"])
        .output()
        .unwrap();
    let err = text(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(dir.path().join("t2.exr").exists());
    assert!(
        err.contains("t2.mtl:6: material white: Kd 0.8 + Ks 0.5 exceeds 1; both scaled by 0.769"),
        "{err}"
    );
    assert!(err.contains("Kd 0.61538464, Ks 0.3846154") || err.contains("(Kd 0.615"), "{err}");
    assert!(err.contains("t2.mtl:14: material odd: d 0.3 (dissolve) is not rendered"), "{err}");
    assert!(err.contains("t2.mtl:15: material odd: illum 9 is not a model"), "{err}");
    assert!(err.contains("t2.mtl:16: material odd: Pr, Pm (MTL's PBR extension) not rendered"), "{err}");
    // The scaled material reflects what it receives at most.
    let info = run(&["info", "--json", dir.path().join("t2.toml").to_str().unwrap()]);
    let v: serde_json::Value = serde_json::from_slice(&info.stdout).unwrap();
    let white = v["materials"].as_array().unwrap().iter().find(|m| m["name"] == "white").unwrap();
    assert_eq!(white["type"], "glossy");
    let kd = white["parameters"]["kd"][0].as_f64().unwrap();
    let ks = white["parameters"]["ks"][0].as_f64().unwrap();
    assert!((kd + ks - 1.0).abs() < 1e-5 && (kd / ks - 1.6).abs() < 1e-4, "kd {kd} ks {ks}");
}

/// The materials `info --json` reports for an OBJ of four triangles, the first two of
/// material `a`, the others of `b`, with the MTL `mtl`, and what a render of it writes on
/// stderr (the render must succeed).
fn mtl_materials(mtl: &str) -> (Vec<serde_json::Value>, String) {
    let dir = tempfile::tempdir().unwrap();
    let obj = "mtllib m.mtl\nv -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\nv -1 0 2\nv 1 0 2\n\
               usemtl a\nf 1 3 2\nf 1 4 3\nusemtl b\nf 4 6 3\nf 4 5 6\n";
    let toml = "[camera]\neye = [0, 3, -3]\ntarget = [0, 0, 0]\nup = [0, 1, 0]\nvfov_deg = 60\nwidth = 8\nheight = 8\n\n\
                [[mesh]]\nobj = \"m.obj\"\n\n[[light]]\ntype = \"point\"\nposition = [0, 2, 0]\nintensity = [1, 1, 1]\n";
    std::fs::write(dir.path().join("m.obj"), obj).unwrap();
    std::fs::write(dir.path().join("m.mtl"), mtl).unwrap();
    std::fs::write(dir.path().join("m.toml"), toml).unwrap();
    let out = run(&["info", "--json", dir.path().join("m.toml").to_str().unwrap()]);
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let rendered = photonmap()
        .current_dir(dir.path())
        .args(["render", "m.toml", "--quiet", "--spp", "1", "--photons", "1000"])
        .output()
        .unwrap();
    let err = text(&rendered.stderr);
    assert!(rendered.status.success(), "{err}");
    (v["materials"].as_array().unwrap().clone(), err)
}

/// Material `name` of [`mtl_materials`]' list.
fn material<'a>(list: &'a [serde_json::Value], name: &str) -> &'a serde_json::Value {
    list.iter().find(|m| m["name"] == name).unwrap()
}

/// Parameter `key` of material `m`: the number, or component `i` of the colour.
fn parameter(m: &serde_json::Value, key: &str, i: usize) -> f64 {
    let p = &m["parameters"][key];
    p.as_f64().unwrap_or_else(|| p[i].as_f64().unwrap())
}

/// An MTL of Blender's export is read as the principled BSDF it was written from, as its glTF
/// export is: the default material (`Ns 250`: roughness 0.5, `Ks 0.5`: a 4 % coat) is diffuse
/// with its `Kd` (it was a 38 % Phong lobe), and a metallic one (`illum 3`, `Ka 1`: metallic
/// 1; `Ns 360`: roughness 0.4) a principled metal of its base colour (it was a perfect mirror
/// of `Ks`), with one line saying so; a smooth one (`Ns 810`: roughness 0.1) a principled
/// dielectric (a 4 % lobe).
#[test]
fn a_blender_mtl_is_read_as_its_principled_bsdf() {
    let header = "# Blender 4.2.0 MTL File: 'None'\n# www.blender.org\n\n";
    let blender = |name: &str, ns: f32, kd: &str, illum: u8| {
        format!("newmtl {name}\nNs {ns}\nKa 1.0 1.0 1.0\nKd {kd}\nKs 0.5 0.5 0.5\nKe 0 0 0\nNi 1.45\nd 1.0\nillum {illum}\n\n")
    };
    let mtl =
        format!("{header}{}{}", blender("a", 250.0, "0.8 0.8 0.8", 2), blender("b", 360.0, "0.9 0.7 0.3", 3));
    let (list, err) = mtl_materials(&mtl);
    let white = material(&list, "a");
    assert_eq!(white["type"], "diffuse", "{white}");
    assert!((parameter(white, "kd", 0) - 0.8).abs() < 1e-6, "{white}");
    let gold = material(&list, "b");
    assert_eq!(gold["type"], "principled", "{gold}");
    assert!((parameter(gold, "kd", 1) - 0.7).abs() < 1e-6 && parameter(gold, "metallic", 0) == 1.0, "{gold}");
    // Roughness 1 - sqrt(0.36) = 0.4.
    assert!((parameter(gold, "roughness", 0) - 0.4).abs() < 1e-4, "{gold}");
    let note = "written by Blender: its materials are read as Blender's principled BSDF";
    assert_eq!(err.matches(note).count(), 1, "{err}");
    assert!(!err.contains("exceeds 1"), "{err}");
    let (list, _) = mtl_materials(&format!(
        "{header}{}{}",
        blender("a", 810.0, "0.2 0.4 0.6", 2),
        blender("b", 0.0, "1 1 1", 1)
    ));
    let smooth = material(&list, "a");
    assert_eq!(smooth["type"], "principled", "{smooth}");
    assert!(parameter(smooth, "metallic", 0) == 0.0 && (parameter(smooth, "kd", 2) - 0.6).abs() < 1e-6);
    assert!((parameter(smooth, "roughness", 0) - 0.1).abs() < 1e-4, "{smooth}");
    assert_eq!(material(&list, "b")["type"], "diffuse");
    // With its PBR option Blender writes `Pr` and `Pm` too, which say a metal of specular 0
    // (written `illum 1`) is one.
    let pbr = format!(
        "{header}{}Pr 0.2\nPm 1\n{}",
        blender("a", 640.0, "0.9 0.9 0.9", 1),
        blender("b", 0.0, "1 1 1", 1)
    );
    let (list, err) = mtl_materials(&pbr);
    assert_eq!(material(&list, "a")["type"], "principled", "{err}");
}

/// An MTL with the PBR extension's roughness and metallic values (`Pr`, `Pm`) is read by them
/// as a glTF material is, from any program: a metal of roughness 0.3 is a principled metal of
/// its `Kd`, a rough dielectric (`Pr 0.7`) is diffuse; neither value is
/// warned as not rendered, while the extension's sheen (`Ps`) still is.
#[test]
fn an_mtl_with_pr_and_pm_is_read_as_metallic_roughness() {
    let mtl = "newmtl a\nKd 0.9 0.6 0.2\nKs 0.5 0.5 0.5\nNs 100\nillum 2\nPr 0.3\nPm 1\n\n\
               newmtl b\nKd 0.3 0.5 0.7\nKs 0.5 0.5 0.5\nNs 100\nillum 2\nPr 0.7\nPm 0\nPs 0.5\n";
    let (list, err) = mtl_materials(mtl);
    let metal = material(&list, "a");
    assert_eq!(metal["type"], "principled", "{metal}");
    assert!((parameter(metal, "kd", 1) - 0.6).abs() < 1e-6, "{metal}");
    assert!((parameter(metal, "roughness", 0) - 0.3).abs() < 1e-4, "{metal}");
    assert_eq!(material(&list, "b")["type"], "diffuse");
    assert!(err.contains("m.mtl:16: material b: Ps (MTL's PBR extension) not rendered"), "{err}");
    assert!(!err.contains("Pr") && !err.contains("Pm"), "{err}");
    assert!(!err.contains("written by Blender"), "{err}");
}

/// The shipped scenes cite the conventions file the repository holds, and no script it lacks.
#[test]
fn the_shipped_scenes_cite_files_the_repository_holds() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    assert!(root.join("scenes/SCENES.md").is_file());
    for dir in std::fs::read_dir(root.join("scenes")).unwrap() {
        let dir = dir.unwrap().path();
        for file in std::fs::read_dir(&dir).into_iter().flatten() {
            let file = file.unwrap().path();
            let Ok(text) = std::fs::read_to_string(&file) else { continue };
            for cited in ["eval/scenes.py", "scripts/make_scenes.py", "scenes/SCENES.md"] {
                if text.lines().take(5).any(|l| l.starts_with('#') && l.contains(cited)) {
                    assert!(
                        root.join(cited).is_file(),
                        "{} cites {cited}, which is not here",
                        file.display()
                    );
                }
            }
        }
    }
}

/// The README's quick start renders a user's own OBJ as written.
#[test]
fn the_readme_quick_start_renders_an_obj() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    let start = readme.find("cat > room.toml <<'TOML'\n").expect("the quick start") + 25;
    let toml = &readme[start..start + readme[start..].find("TOML\n").unwrap()];
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("room.toml"), toml).unwrap();
    std::fs::copy(root.join("scenes/cornell/cornell.obj"), dir.path().join("room.obj")).unwrap();
    std::fs::copy(root.join("scenes/cornell/cornell.mtl"), dir.path().join("cornell.mtl")).unwrap();
    let out = photonmap()
        .current_dir(dir.path())
        .args(["render", "room.toml", "--png", "room.png", "--quiet", "--width", "32", "--height", "24"])
        .args(["--spp", "1", "--photons", "5000"])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(dir.path().join("room.exr").is_file() && dir.path().join("room.png").is_file());
}

/// Every relative link of the README and the docs names a file that exists, and every
/// `#anchor` a heading of its page.
#[test]
fn the_readme_and_docs_links_resolve() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let anchor = |h: &str| -> String {
        let h = h.trim_start_matches('#').trim().to_lowercase();
        h.chars()
            .filter(|c| c.is_alphanumeric() || *c == '-' || *c == '_' || *c == ' ')
            .collect::<String>()
            .replace(' ', "-")
    };
    let headings = |page: &Path| -> Vec<String> {
        let text = std::fs::read_to_string(page).unwrap();
        let mut code = false;
        let mut out = Vec::new();
        for l in text.lines() {
            if l.starts_with("```") {
                code = !code;
            } else if !code && l.starts_with('#') {
                out.push(anchor(l));
            }
        }
        out
    };
    let mut pages = vec![root.join("README.md")];
    pages.extend(
        std::fs::read_dir(root.join("docs"))
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|e| e == "md")),
    );
    let mut bad = Vec::new();
    for page in &pages {
        let text = std::fs::read_to_string(page).unwrap();
        for (i, _) in text.match_indices("](") {
            let rest = &text[i + 2..];
            let Some(end) = rest.find(')') else { continue };
            let link = &rest[..end];
            if link.starts_with("http") || link.contains(' ') || link.is_empty() {
                continue;
            }
            let (file, frag) = link.split_once('#').map_or((link, None), |(f, a)| (f, Some(a)));
            let target = if file.is_empty() { page.clone() } else { page.parent().unwrap().join(file) };
            if !target.exists() {
                bad.push(format!("{}: {link}: no such file", page.display()));
            } else if let Some(a) = frag {
                if target.extension().is_some_and(|e| e == "md") && !headings(&target).iter().any(|h| h == a)
                {
                    bad.push(format!("{}: {link}: no such heading", page.display()));
                }
            }
        }
    }
    assert!(bad.is_empty(), "{}", bad.join("\n"));
}
