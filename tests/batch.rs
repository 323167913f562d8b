//! Many images from one command (`render --frames`): a batch gives each image exactly what a
//! render of that image alone gives, `--resume` skips the finished images and redoes a
//! damaged one, and outputs that would overwrite each other are refused before any work. The
//! output's format is its extension's, and a render without `-o` is named after its scene.

use photonmap::film::Film;
use std::fs;
use std::path::Path;
use std::process::Command;

const OBJ: &str = include_str!("../scenes/cornell/cornell.obj");
const MTL: &str = include_str!("../scenes/cornell/cornell.mtl");

/// The Cornell box with a turntable camera of 3 frames (a 30° sweep around the box's centre)
/// and a still one, written into `dir`.
fn scene(dir: &Path) -> std::path::PathBuf {
    fs::write(dir.join("cornell.obj"), OBJ).unwrap();
    fs::write(dir.join("cornell.mtl"), MTL).unwrap();
    let toml = r#"
[[camera]]
name = "orbit"
eye = [0.278, 0.273, -0.8]
target = [0.278, 0.273, 0.28]
up = [0.0, 1.0, 0.0]
vfov_deg = 39.3
width = 20
height = 20
turntable = { frames = 3, center = [0.278, 0.273, 0.28], degrees = 30.0 }

[[camera]]
name = "still"
eye = [0.278, 0.4, -0.6]
target = [0.278, 0.2, 0.3]
up = [0.0, 1.0, 0.0]
vfov_deg = 45.0
width = 16
height = 12

[[mesh]]
obj = "cornell.obj"

[materials.white]
type = "diffuse"
kd = [0.725, 0.71, 0.68]

[materials.red]
type = "diffuse"
kd = [0.63, 0.065, 0.05]

[materials.green]
type = "diffuse"
kd = [0.14, 0.45, 0.091]

[materials.light]
type = "emissive"
kd = [0.78, 0.78, 0.78]
ke = [17.0, 12.0, 4.0]
"#;
    let path = dir.join("turn.toml");
    fs::write(&path, toml).unwrap();
    path
}

/// Runs `photonmap render SCENE ARGS…` with small budgets, in the scene's directory; returns
/// (success, stderr).
fn render(scene: &Path, args: &[&str]) -> (bool, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_photonmap"))
        .current_dir(scene.parent().unwrap())
        .arg("render")
        .arg(scene)
        .args(["--photons", "20000", "--spp", "4", "--threads", "2", "-q"])
        .args(args)
        .output()
        .expect("photonmap runs");
    (out.status.success(), String::from_utf8_lossy(&out.stderr).into_owned())
}

fn pixels(path: &Path) -> Vec<f32> {
    Film::read_exr(path).unwrap().pixels.iter().flat_map(|p| p.to_array()).collect()
}

#[test]
fn a_batch_gives_each_image_what_a_render_of_it_alone_gives() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene(dir.path());
    let pattern = dir.path().join("batch_{camera}_{frame:02}.exr");
    let (ok, err) = render(&scene, &["-o", pattern.to_str().unwrap()]);
    assert!(ok, "{err}");
    // Every camera's own frames: the turntable's 0..=2 and the still camera's 0.
    for name in ["orbit_00", "orbit_01", "orbit_02", "still_00"] {
        assert!(dir.path().join(format!("batch_{name}.exr")).exists(), "{name}");
    }
    let a = pixels(&dir.path().join("batch_orbit_00.exr"));
    let b = pixels(&dir.path().join("batch_orbit_01.exr"));
    assert_ne!(a, b, "the turntable's frames are different views");
    for frame in ["0", "1", "2"] {
        let single = dir.path().join(format!("single_{frame}.exr"));
        let args = ["--cameras", "orbit", "--frames", frame, "-o", single.to_str().unwrap()];
        let (ok, err) = render(&scene, &args);
        assert!(ok, "{err}");
        let batch = dir.path().join(format!("batch_orbit_0{frame}.exr"));
        assert_eq!(pixels(&single), pixels(&batch), "frame {frame}");
    }
    let still = dir.path().join("single_still.exr");
    let (ok, err) = render(&scene, &["--cameras", "still", "-o", still.to_str().unwrap()]);
    assert!(ok, "{err}");
    assert_eq!(pixels(&still), pixels(&dir.path().join("batch_still_00.exr")));
}

#[test]
fn resume_skips_finished_images_and_redoes_a_damaged_one() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene(dir.path());
    let pattern = dir.path().join("{frame}.exr");
    let pattern = pattern.to_str().unwrap();
    let args = ["--cameras", "orbit", "-o", pattern];
    let (ok, err) = render(&scene, &args);
    assert!(ok, "{err}");
    let path = |f: u32| dir.path().join(format!("{f}.exr"));
    let original: Vec<Vec<f32>> = (0..3).map(|f| pixels(&path(f))).collect();
    let modified = |f: u32| fs::metadata(path(f)).unwrap().modified().unwrap();
    let before = [modified(0), modified(2)];
    // Frame 1 cut short, as by a crash of the disk or a copy.
    let bytes = fs::read(path(1)).unwrap();
    fs::write(path(1), &bytes[..bytes.len() / 2]).unwrap();
    std::thread::sleep(std::time::Duration::from_millis(20));
    let (ok, err) = render(&scene, &[&args[..], &["--resume"]].concat());
    assert!(ok, "{err}");
    assert_eq!([modified(0), modified(2)], before, "finished images are not rendered again");
    assert_eq!(pixels(&path(1)), original[1], "the damaged image is made again, the same");
    // Said once, naming the file, and only for it.
    assert_eq!(err.matches("rendering it again").count(), 1, "{err}");
    assert!(err.contains("1.exr: its pixels do not read back whole"), "{err}");
    // Another seed is another image: nothing is skipped, and each file replaced is named, as
    // is one that is not an image at all.
    fs::write(path(2), "notes, not an image").unwrap();
    let (ok, err) = render(&scene, &[&args[..], &["--resume", "--seed", "5"]].concat());
    assert!(ok, "{err}");
    assert_ne!(pixels(&path(0)), original[0]);
    assert_eq!(err.matches("rendering it again").count(), 3, "{err}");
    assert_eq!(err.matches("not this image finished").count(), 2, "{err}");
    assert!(err.contains("2.exr: not an OpenEXR file"), "{err}");
}

#[test]
fn outputs_that_would_overwrite_each_other_are_refused_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene(dir.path());
    let out = dir.path().join("one.exr");
    let (ok, err) = render(&scene, &["--cameras", "orbit", "-o", out.to_str().unwrap()]);
    assert!(!ok);
    assert!(err.contains("{frame"), "{err}");
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(!out.exists());
    let (ok, err) =
        render(&scene, &["--frames", "0-1", "-o", dir.path().join("{frame}.exr").to_str().unwrap()]);
    assert!(!ok);
    assert!(err.contains("{camera}"), "{err}");
    let (ok, err) =
        render(&scene, &["--frames", "7", "-o", dir.path().join("x{frame}.exr").to_str().unwrap()]);
    assert!(!ok);
    assert!(err.contains("outside camera orbit"), "{err}");
    let (ok, err) = render(&scene, &["--cameras", "nope", "-o", dir.path().join("y.exr").to_str().unwrap()]);
    assert!(!ok);
    assert!(err.contains("orbit, still"), "{err}");
}

#[test]
fn the_output_format_is_the_extensions() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene(dir.path());
    let d = dir.path();
    let (ok, err) = render(&scene, &["--cameras", "still", "-o", "a.PNG"]);
    assert!(ok, "{err}");
    let (ok, err) = render(&scene, &["--cameras", "still", "-o", "b.exr", "--png", "c.png"]);
    assert!(ok, "{err}");
    let a = fs::read(d.join("a.PNG")).unwrap();
    assert_eq!(&a[..8], b"\x89PNG\r\n\x1a\n");
    // The same image as the preview beside an EXR, byte for byte.
    assert_eq!(a, fs::read(d.join("c.png")).unwrap());
    assert_eq!(&fs::read(d.join("b.exr")).unwrap()[..4], &[0x76, 0x2f, 0x31, 0x01]);
}

#[test]
fn without_o_the_images_are_named_after_the_scene_in_the_working_directory() {
    let dir = tempfile::tempdir().unwrap();
    let scene = scene(dir.path());
    let listing = |d: &Path| {
        let mut names: Vec<String> = fs::read_dir(d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.ends_with(".exr"))
            .collect();
        names.sort();
        names
    };
    // One image: the scene's name.
    let (ok, err) = render(&scene, &["--cameras", "still"]);
    assert!(ok, "{err}");
    assert_eq!(listing(dir.path()), ["turn.exr"]);
    assert_eq!(pixels(&dir.path().join("turn.exr")).len(), 16 * 12 * 3);
    // Many: what tells them apart is added, and nothing else.
    fs::remove_file(dir.path().join("turn.exr")).unwrap();
    let (ok, err) = render(&scene, &["--cameras", "orbit"]);
    assert!(ok, "{err}");
    assert_eq!(listing(dir.path()), ["turn_0000.exr", "turn_0001.exr", "turn_0002.exr"]);
    for f in listing(dir.path()) {
        fs::remove_file(dir.path().join(f)).unwrap();
    }
    let (ok, err) = render(&scene, &[]);
    assert!(ok, "{err}");
    assert_eq!(
        listing(dir.path()),
        ["turn_orbit_0000.exr", "turn_orbit_0001.exr", "turn_orbit_0002.exr", "turn_still_0000.exr"]
    );
}
