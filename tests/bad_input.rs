//! The `photonmap` binary on bad input: each case runs `photonmap render SCENE -o out.exr` in
//! a temporary directory holding the Cornell box (altered as the case says) and checks the
//! project rule: a non-zero exit, one line on stderr starting `photonmap: error:` that names
//! the file and line or the field at fault, no panic, and nothing left behind (no image, no
//! temporary file; an existing image untouched).

use photonmap::config::RenderSettings;
use std::collections::BTreeMap;
use std::fs;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

const TOML: &str = include_str!("../scenes/cornell/cornell.toml");
const OBJ: &str = include_str!("../scenes/cornell/cornell.obj");
const MTL: &str = include_str!("../scenes/cornell/cornell.mtl");
/// A small glTF (a floor quad, a camera, a point light) with its buffer in `quad.bin`, written
/// beside the Cornell box for the cases that use it.
const GLTF: &str = include_str!("data/gltf/quad.gltf");
const GLTF_BIN: &[u8] = include_bytes!("data/gltf/quad.bin");

/// Settings that keep a render that is (wrongly) not refused short; a case may override any.
const QUICK: &[(&str, &str)] = &[
    ("--width", "16"),
    ("--height", "16"),
    ("--spp", "1"),
    ("--photons", "2000"),
    ("--caustic-photons", "2000"),
];

/// Longest a run is waited for before it is killed (so a render that wrongly goes ahead cannot
/// hang the suite; how fast a refusal comes is not measured).
const LIMIT: Duration = Duration::from_secs(60);

struct Case {
    name: &'static str,
    /// Scene file passed to `render` (relative to the directory).
    scene: &'static str,
    /// Output passed to `-o`.
    output: &'static str,
    /// Flags, overriding those of `QUICK` with the same name (a value of `"!"` drops the flag).
    flags: &'static [(&'static str, &'static str)],
    /// Changes to the Cornell box files: (file, text to find, replacement).
    edits: &'static [(&'static str, &'static str, &'static str)],
    /// What the error line must contain (the file and line, or the field).
    expect: &'static [&'static str],
}

const fn case(name: &'static str, expect: &'static [&'static str]) -> Case {
    Case { name, scene: "cornell.toml", output: "out.exr", flags: &[], edits: &[], expect }
}

fn cases() -> Vec<Case> {
    vec![
        Case { scene: "nosuch.toml", ..case("missing scene file", &["nosuch.toml", "No such file"]) },
        Case {
            edits: &[("cornell.toml", "obj = \"cornell.obj\"", "obj = \"missing.obj\"")],
            ..case("missing OBJ", &["missing.obj", "No such file"])
        },
        Case {
            edits: &[("cornell.obj", "v 0.556 0.5488 0.0\n", "v 0.556 x 0.0\n")],
            ..case("malformed OBJ line", &["cornell.obj:13:", "`x` is not a number"])
        },
        Case {
            edits: &[("cornell.obj", "f 5 6 7\n", "f 5 6 700\n")],
            ..case("index out of range", &["cornell.obj:18:", "vertex index 700 out of range"])
        },
        Case {
            edits: &[("cornell.obj", "v 0.556 0.5488 0.0\n", "v 0.556 nan 0.0\n")],
            ..case("NaN coordinate", &["cornell.obj:13:", "not finite"])
        },
        Case {
            edits: &[("cornell.mtl", "Kd 0.63 0.065 0.05\n", "Kd 0.63 0.065 0.05\nmap_Kd nosuch.png\n")],
            ..case("missing texture", &["cornell.mtl:13:", "nosuch.png"])
        },
        Case {
            edits: &[("cornell.mtl", "Kd 0.63 0.065 0.05\n", "Kd 0.63 0.065 0.05\nmap_Kd cornell.obj\n")],
            ..case("texture that is not an image", &["cornell.mtl:13:", "cornell.obj", "not an image"])
        },
        Case {
            edits: &[("cornell.mtl", "Kd 0.63 0.065 0.05\n", "Kd 0.63 0.065 0.05\nmap_Kd -q 1 red.png\n")],
            ..case("unknown texture option", &["cornell.mtl:13:", "unknown option `-q`"])
        },
        Case {
            edits: &[("cornell.toml", "[materials.red]\n", "[materials.red]\nkd_texture = \"gone.png\"\n")],
            ..case("missing scene-file texture", &["cornell.toml", "materials.red.kd_texture", "gone.png"])
        },
        Case {
            edits: &[("cornell.mtl", "Kd 0.63 0.065 0.05\n", "Kd 0.63 0.065 0.05\nmap_d nosuch-alpha.png\n")],
            ..case("missing alpha texture", &["cornell.mtl:13:", "nosuch-alpha.png"])
        },
        Case {
            edits: &[("cornell.toml", "[materials.red]\n", "[materials.red]\nalpha_texture = \"gone-alpha.png\"\n")],
            ..case("missing scene-file alpha texture", &["cornell.toml", "materials.red.alpha_texture", "gone-alpha.png"])
        },
        Case {
            edits: &[("cornell.toml", "[materials.red]\n", "[materials.red]\nalpha_cutoff = 0.5\n")],
            ..case("alpha cutoff without alpha texture", &["cornell.toml", "materials.red.alpha_cutoff", "no alpha texture"])
        },
        Case {
            edits: &[(
                "cornell.toml",
                "[materials.white]\n",
                "[[light]]\ntype = \"environment\"\nmap = \"nosky.exr\"\n\n[materials.white]\n",
            )],
            ..case("missing environment map", &["cornell.toml", "light[0].map", "nosky.exr"])
        },
        Case {
            edits: &[(
                "cornell.toml",
                "[materials.white]\n",
                "[[light]]\ntype = \"environment\"\nradiance = [1.0, -1.0, 1.0]\n\n[materials.white]\n",
            )],
            ..case("negative sky radiance", &["cornell.toml", "light[0].radiance"])
        },
        Case {
            edits: &[("cornell.toml", "width = 256", "width = 256\nfocal_length = 35")],
            ..case("unknown TOML key", &["cornell.toml", "line 12", "unknown field `focal_length`"])
        },
        Case {
            edits: &[("cornell.toml", "[materials.white]\ntype = \"diffuse\"", "[materials.white]\ntype = \"plastic\"")],
            ..case("unknown material type", &["cornell.toml", "line 18", "unknown variant `plastic`"])
        },
        Case {
            edits: &[(
                "cornell.toml",
                "[camera]",
                "[[portal]]\ncorners = [[0, 0, 0], [1, 0, 0], [1.2, 1, 0], [0, 1, 0]]\n\n[camera]",
            )],
            ..case("portal not a parallelogram", &["cornell.toml", "portal[0].corners", "parallelogram"])
        },
        Case {
            edits: &[(
                "cornell.toml",
                "[camera]",
                "[[camera]]\nname = \"front\"\neye = [0.278, 0.273, -0.9]\ntarget = [0.278, 0.273, 0.0]\n\
                 up = [0.0, 1.0, 0.0]\nvfov_deg = 40\nwidth = 16\nheight = 16\n\n[[camera]]\nname = \"front\"",
            )],
            ..case(
                "two cameras of one name",
                &["cornell.toml", "field `camera[1].name`", "duplicate camera name \"front\""],
            )
        },
        Case {
            edits: &[("cornell.toml", "height = 256", "height = 256\n\n[[camera.key]]\nframe = 3")],
            ..case("an animation of one key", &["cornell.toml", "field `camera.key`", "needs at least 2"])
        },
        Case {
            edits: &[("cornell.toml", "height = 256", "height = 256\naperture_radius = -0.01")],
            ..case("a negative aperture", &["cornell.toml", "field `camera.aperture_radius`", "-0.01"])
        },
        Case {
            edits: &[("cornell.toml", "height = 256", "height = 256\naperture_radius = 0.01\nfocus_distance = 0")],
            ..case("focus at the lens", &["cornell.toml", "field `camera.focus_distance`", "> 0"])
        },
        Case {
            edits: &[("cornell.toml", "obj = \"cornell.obj\"", "obj = \"cornell.obj\"\nrotate = { axis = [0, 0, 0], degrees = 30 }")],
            ..case("a rotation about no axis", &["cornell.toml", "field `mesh[0].rotate.axis`", "zero"])
        },
        Case {
            edits: &[(
                "cornell.toml",
                "obj = \"cornell.obj\"",
                "obj = \"cornell.obj\"\nmatrix = [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0.1, 1]",
            )],
            ..case("a projective matrix", &["cornell.toml", "field `mesh[0].matrix`", "affine"])
        },
        Case {
            edits: &[(
                "cornell.toml",
                "obj = \"cornell.obj\"",
                "obj = \"cornell.obj\"\nmatrix = [1, 2, 3, 0, 2, 4, 6, 0, 0, 0, 1, 0]",
            )],
            ..case("a singular matrix", &["cornell.toml", "field `mesh[0].matrix`", "singular"])
        },
        // A setting is named where it was given: the flag, or the scene file's field.
        Case { flags: &[("--width", "0")], ..case("--width 0", &["--width/--height: 0x16"]) },
        Case {
            flags: &[("--width", "1000000")],
            ..case("--width 1000000", &["--width/--height: 1000000x16", "GB"])
        },
        Case { flags: &[("--width", "-5")], ..case("--width -5", &["'-5'", "--width"]) },
        Case {
            flags: &[("--photons", "1000000000000")],
            ..case("--photons 10^12", &["--photons: 1000000000000", "GB"])
        },
        Case { flags: &[("--photons", "-3")], ..case("--photons -3", &["'-3'", "--photons"]) },
        Case { flags: &[("--spp", "0")], ..case("--spp 0", &["--spp: 0 is not in"]) },
        Case { flags: &[("--time", "-1")], ..case("--time -1", &["--time: -1", "seconds"]) },
        Case { flags: &[("--bogus", "")], ..case("an unknown flag", &["'--bogus'"]) },
        Case {
            flags: &[("--spp", "!")],
            edits: &[("cornell.toml", "[[mesh]]", "[render]\nspp = 0\n\n[[mesh]]")],
            ..case("spp = 0 in the scene file", &["cornell.toml", "field `render.spp`", "0 is not in"])
        },
        Case {
            flags: &[("--width", "!"), ("--height", "!")],
            edits: &[("cornell.toml", "width = 256", "width = 0")],
            ..case("a camera of width 0", &["cornell.toml", "field `camera.width`", "0 is not in"])
        },
        Case { flags: &[("--threads", "0")], ..case("--threads 0", &["--threads 0"]) },
        // --strict: a warning stops the render before any work.
        Case {
            flags: &[("--strict", "")],
            edits: &[("cornell.toml", "[materials.white]", "[materials.whte]\ntype = \"diffuse\"\n\n[materials.white]")],
            ..case("an unused material with --strict", &["cornell.toml", "--strict", "[materials.whte] is used by no triangle"])
        },
        Case {
            flags: &[("--strict", "")],
            edits: &[("cornell.toml", "ke = [17.0, 12.0, 4.0]", "ke = [0.0, 0.0, 0.0]")],
            ..case("no light with --strict", &["cornell.toml", "--strict", "no [[light]] and no emissive material"])
        },
        // The keys a user tries in `[render]` get a hint before the list of those allowed.
        Case {
            edits: &[("cornell.toml", "[[mesh]]", "[render]\nthreads = 2\n\n[[mesh]]")],
            ..case("threads in [render]", &["cornell.toml:", "unknown field `threads` (a command-line flag only: --threads)"])
        },
        Case {
            edits: &[("cornell.toml", "[[mesh]]", "[render]\nwidth = 64\n\n[[mesh]]")],
            ..case("width in [render]", &["cornell.toml:", "`[camera] width`"])
        },
        Case {
            edits: &[("cornell.toml", "[[mesh]]", "[render]\ncaustic-photons = 2\n\n[[mesh]]")],
            ..case("a flag's spelling in [render]", &["cornell.toml:", "spelt with underscores: `caustic_photons`"])
        },
        Case { output: "missing/out.exr", ..case("output into a missing directory", &["missing"]) },
        Case { output: "/proc/out.exr", ..case("output where no file can be made", &["/proc/out.exr", "cannot write in /proc"]) },
        Case { output: "out.jpg", ..case("output of an unknown format", &["out.jpg", "`.jpg` is not an image format"]) },
        Case { output: "out", ..case("output without an extension", &["out", "no extension"]) },
        Case { flags: &[("--png", "out.exr")], ..case("--png on the -o image", &["out.exr", "--png names a PNG file"]) },
        Case { flags: &[("--stats", "out.exr")], ..case("--stats on the -o image", &["out.exr", "--stats names an image"]) },
        Case { flags: &[("--stats", "/proc/s.json")], ..case("--stats where no file can be made", &["/proc/s.json", "cannot write"]) },
        Case { flags: &[("--stats", ".")], ..case("--stats on a directory", &[".: is a directory, not a file"]) },
        Case { output: "out.png", flags: &[("--resume", "")], ..case("--resume with a PNG output", &["out.png", "--resume needs .exr"]) },
        // glTF: each error names the file and the JSON path at fault.
        Case {
            scene: "quad.gltf",
            edits: &[("quad.gltf", "\"uri\": \"quad.bin\"", "\"uri\": \"nosuch.bin\"")],
            ..case("missing glTF buffer", &["quad.gltf", "buffers[0].uri", "nosuch.bin", "No such file"])
        },
        Case {
            scene: "quad.gltf",
            edits: &[("quad.gltf", "\"scene\": 0,", "\"scene\": 0,,")],
            ..case("malformed glTF JSON", &["quad.gltf", "malformed glTF JSON", "line 23"])
        },
        Case {
            scene: "quad.gltf",
            edits: &[("quad.gltf", "\"POSITION\": 0,", "\"POSITION\": 7,")],
            ..case(
                "glTF accessor index out of range",
                &["quad.gltf", "meshes[0].primitives[0].attributes[\"POSITION\"]", "index 7 out of range"],
            )
        },
        Case {
            scene: "quad.gltf",
            edits: &[("quad.gltf", "\"count\": 6,", "\"count\": 60,")],
            ..case(
                "glTF accessor past its buffer view",
                &["quad.gltf", "meshes[0].primitives[0].indices (accessor 3)", "do not fit in bufferView 3"],
            )
        },
        Case {
            scene: "quad.gltf",
            edits: &[("quad.gltf", "\"translation\": [\n    0,\n    1,\n    3", "\"translation\": [\n    0,\n    1e39,\n    3")],
            ..case("non-finite glTF transform", &["quad.gltf", "nodes[1].translation", "not finite"])
        },
        Case {
            scene: "quad.gltf",
            edits: &[(
                "quad.gltf",
                "\"metallicFactor\": 0,",
                "\"baseColorTexture\": {\"index\": 0}, \"metallicFactor\": 0,",
            ), ("quad.gltf", "\"accessors\": [", "\"textures\": [{\"source\": 0}], \"images\": [{\"uri\": \"nosuch.png\"}],\n \"accessors\": [")],
            ..case(
                "missing glTF image",
                &["quad.gltf", "materials[0].pbrMetallicRoughness.baseColorTexture", "nosuch.png"],
            )
        },
        Case {
            // A glTF alone gets a camera made up; a scene file must have one or bring one.
            edits: &[
                ("quad.gltf", "\"camera\": 0,", ""),
                ("cornell.toml", "[camera]\neye = [0.278, 0.273, -0.8]\ntarget = [0.278, 0.273, 0.0]\nup = [0.0, 1.0, 0.0]\nvfov_deg = 39.30764811610662  # full vertical field of view\nwidth = 256\nheight = 256\n", ""),
                ("cornell.toml", "obj = \"cornell.obj\"", "gltf = \"quad.gltf\""),
            ],
            ..case("scene file and glTF without a camera", &["cornell.toml", "camera", "no perspective camera"])
        },
        Case {
            edits: &[("cornell.toml", "obj = \"cornell.obj\"", "obj = \"cornell.obj\"\ngltf = \"quad.gltf\"")],
            ..case("[[mesh]] with obj and gltf", &["cornell.toml", "mesh[0]", "exactly one of `obj` and `gltf`"])
        },
    ]
}

/// A directory holding the Cornell box with the case's edits applied.
fn setup(case: &Case) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    for (file, text) in [("cornell.toml", TOML), ("cornell.obj", OBJ), ("cornell.mtl", MTL)] {
        let mut text = text.to_owned();
        for &(f, find, replace) in case.edits {
            if f == file {
                assert!(text.contains(find), "{}: `{find}` not in {file}", case.name);
                text = text.replacen(find, replace, 1);
            }
        }
        fs::write(dir.path().join(file), text).unwrap();
    }
    let uses_gltf = case.scene.ends_with(".gltf") || case.edits.iter().any(|e| e.2.contains("quad.gltf"));
    if uses_gltf {
        let mut text = GLTF.to_owned();
        for &(f, find, replace) in case.edits.iter().filter(|e| e.0 == "quad.gltf") {
            assert!(text.contains(find), "{}: `{find}` not in {f}", case.name);
            text = text.replacen(find, replace, 1);
        }
        fs::write(dir.path().join("quad.gltf"), text).unwrap();
        fs::write(dir.path().join("quad.bin"), GLTF_BIN).unwrap();
    }
    dir
}

/// Every file under `dir` with its content.
fn snapshot(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    let mut files = BTreeMap::new();
    let mut stack = vec![dir.to_owned()];
    while let Some(d) = stack.pop() {
        for entry in fs::read_dir(&d).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else {
                let name = path.strip_prefix(dir).unwrap().display().to_string();
                files.insert(name, fs::read(&path).unwrap());
            }
        }
    }
    files
}

struct Run {
    code: Option<i32>,
    stderr: String,
}

/// Runs `photonmap render` in `dir`, killing it if it outlives `LIMIT`.
fn render(dir: &Path, case: &Case) -> Run {
    let mut flags: Vec<(&str, &str)> =
        QUICK.iter().filter(|(f, _)| !case.flags.iter().any(|(g, _)| g == f)).copied().collect();
    flags.extend(case.flags.iter().filter(|(_, v)| *v != "!"));
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_photonmap"));
    cmd.current_dir(dir).args(["render", case.scene, "-o", case.output, "--quiet"]);
    for (flag, value) in flags {
        cmd.arg(flag);
        if !value.is_empty() {
            cmd.arg(value); // "": a switch
        }
    }
    cmd.stdin(Stdio::null()).stdout(Stdio::null()).stderr(Stdio::piped()).env_remove("RUST_BACKTRACE");
    let start = Instant::now();
    let mut child = cmd.spawn().expect("photonmap could not be started");
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if start.elapsed() > LIMIT {
            child.kill().unwrap();
            child.wait().unwrap();
            panic!("{}: photonmap still running after {LIMIT:?}", case.name);
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    let mut stderr = String::new();
    std::io::Read::read_to_string(&mut child.stderr.take().unwrap(), &mut stderr).unwrap();
    Run { code: status.code(), stderr }
}

/// `Err(reason)` if the run broke the rule for bad input.
fn check(case: &Case, run: &Run) -> Result<(), String> {
    let err = &run.stderr;
    if run.code == Some(0) {
        return Err(format!("exit status 0; stderr: {err:?}"));
    }
    if run.code.is_none() {
        return Err(format!("killed by a signal; stderr: {err:?}"));
    }
    if err.contains("panicked") {
        return Err(format!("panicked: {err:?}"));
    }
    let line = err.strip_suffix('\n').unwrap_or(err);
    if line.contains('\n') || line.is_empty() {
        return Err(format!("stderr is not one line: {err:?}"));
    }
    if !line.starts_with("photonmap: error:") {
        return Err(format!("stderr does not start `photonmap: error:`: {err:?}"));
    }
    for want in case.expect {
        if !line.contains(want) {
            return Err(format!("error does not say `{want}`: {err:?}"));
        }
    }
    Ok(())
}

#[test]
fn bad_input_is_refused_with_one_line_and_no_output() {
    let mut failures = Vec::new();
    for case in cases() {
        let dir = setup(&case);
        let before = snapshot(dir.path());
        let run = render(dir.path(), &case);
        let mut problems: Vec<String> = check(&case, &run).err().into_iter().collect();
        let after = snapshot(dir.path());
        if after.keys().ne(before.keys()) {
            problems.push(format!(
                "files left behind: {:?}",
                after.keys().filter(|k| !before.contains_key(*k)).collect::<Vec<_>>()
            ));
        }
        for p in problems {
            failures.push(format!("{}: {p}", case.name));
        }
    }
    assert!(failures.is_empty(), "\n{}", failures.join("\n"));
}

/// A budget of 10^12 photons (about 20 TB) is refused up front, with an estimate, before
/// anything is allocated: the error is the one that resolving the render settings gives on its
/// own, with no scene, photon or image in existence (and the renderer cannot start without the
/// resolved settings).
#[test]
fn an_absurd_photon_budget_is_refused_up_front_with_an_estimate() {
    let case = Case { flags: &[("--photons", "1000000000000")], ..case("--photons 10^12", &["photons"]) };
    let dir = setup(&case);
    let run = render(dir.path(), &case);
    check(&case, &run).unwrap();
    assert!(run.stderr.contains("GB"), "no memory estimate: {}", run.stderr);
    let settings = RenderSettings { photons: Some(1_000_000_000_000), ..Default::default() };
    let refusal = settings.resolve(16, 16).expect_err("10^12 photons are refused").to_string();
    assert!(run.stderr.contains(&refusal), "not the settings check's refusal ({refusal}): {}", run.stderr);
}

/// A failed render leaves an existing image as it was.
#[test]
fn a_failed_render_leaves_the_old_image_untouched() {
    for case in cases().into_iter().filter(|c| c.output == "out.exr") {
        let dir = setup(&case);
        fs::write(dir.path().join("out.exr"), b"the previous image").unwrap();
        let before = snapshot(dir.path());
        let run = render(dir.path(), &case);
        check(&case, &run).unwrap_or_else(|e| panic!("{}: {e}", case.name));
        assert_eq!(snapshot(dir.path()), before, "{}: the directory changed", case.name);
    }
}

/// The harness itself: the unaltered scene renders, so the cases above fail for their input.
#[test]
fn the_unaltered_scene_renders() {
    let case = case("valid", &[]);
    let dir = setup(&case);
    let run = render(dir.path(), &case);
    assert_eq!(run.code, Some(0), "stderr: {}", run.stderr);
    assert!(dir.path().join("out.exr").is_file());
    let names: Vec<String> = snapshot(dir.path()).into_keys().collect();
    assert_eq!(names, ["cornell.mtl", "cornell.obj", "cornell.toml", "out.exr"], "stray files");
}

/// `photonmap info` lists the scene's cameras, and refuses (as `render` does) a camera whose
/// animation passes through a degenerate view, naming the field and the frame.
#[test]
fn info_lists_the_cameras_and_refuses_a_degenerate_animation() {
    let keys =
        "height = 256\n\n[[camera.key]]\nframe = 0\n\n[[camera.key]]\nframe = 48\neye = [0.3, 0.3, -0.7]\n\n\
                [[camera.key]]\nframe = 96\n";
    let turntable = "\n[[camera]]\nname = \"orbit\"\neye = [0.278, 0.273, -0.8]\ntarget = [0.278, 0.273, 0.28]\n\
                     up = [0.0, 1.0, 0.0]\nvfov_deg = 40\nwidth = 64\nheight = 48\nturntable = { frames = 90 }\n\n[[mesh]]";
    let dir = setup(&case("two cameras", &[]));
    let toml = TOML.replacen("[camera]", "[[camera]]\nname = \"front\"", 1).replacen("height = 256", keys, 1);
    fs::write(dir.path().join("cornell.toml"), toml.replacen("\n[[mesh]]", turntable, 1)).unwrap();
    let out = info(dir.path());
    assert_eq!(out.status.code(), Some(0), "stderr: {}", String::from_utf8_lossy(&out.stderr));
    let stdout = String::from_utf8_lossy(&out.stdout);
    let rows: Vec<Vec<&str>> = stdout.lines().map(|l| l.split_whitespace().collect()).collect();
    assert!(rows.contains(&vec!["front", "256x256", "frames", "0..=96"]), "{stdout}");
    assert!(rows.contains(&vec!["orbit", "64x48", "frames", "0..=89"]), "{stdout}");

    // Eye and target swap places between frames 0 and 2, meeting at frame 1.
    let swap =
        "height = 256\n\n[[camera.key]]\nframe = 0\neye = [0.1, 0.273, 0.0]\ntarget = [0.5, 0.273, 0.0]\n\n\
                [[camera.key]]\nframe = 2\neye = [0.5, 0.273, 0.0]\ntarget = [0.1, 0.273, 0.0]\n";
    fs::write(dir.path().join("cornell.toml"), TOML.replacen("height = 256", swap, 1)).unwrap();
    let out = info(dir.path());
    let run = Run { code: out.status.code(), stderr: String::from_utf8_lossy(&out.stderr).into_owned() };
    let bad = case(
        "degenerate frame",
        &["cornell.toml", "field `camera.key`", "frame 1: the interpolated view is degenerate"],
    );
    check(&bad, &run).unwrap();
}

/// Runs `photonmap info cornell.toml` in `dir`.
fn info(dir: &Path) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_photonmap"))
        .current_dir(dir)
        .args(["info", "cornell.toml"])
        .stdin(Stdio::null())
        .env_remove("RUST_BACKTRACE")
        .output()
        .expect("photonmap could not be started")
}
