//! Alpha cut-outs end to end (MTL `map_d`, the scene file's `alpha_texture` / `alpha_cutoff`):
//!
//! - A fence textured with fine stripes of alpha 1 and 0 (bilinear, cut at 0.5: half of it is
//!   there) lets half the light through, seen by camera rays (an emitter behind it) and by
//!   shadow rays and photons (the floor it shades).
//! - An alpha texture opaque everywhere gives the image of no alpha texture, bit for bit.
//! - A missing alpha texture is refused, naming the file.

use crate::common::{on_threads, render_checked};
use photonmap::accel::AccelKind;
use photonmap::config::RenderSettings;
use photonmap::film::Film;
use photonmap::scene::Scene;
use std::path::Path;

/// A quad at height `y` over `[-h, h]²` in x and z, facing up (or down), texture coordinates
/// over the unit square, of material `m`; `base` is the count of vertices before it.
fn quad_y(y: f32, h: f32, up: bool, m: &str, base: usize) -> String {
    let mut corners = [(-h, h), (h, h), (h, -h), (-h, -h)];
    if !up {
        corners.reverse();
    }
    let mut s = format!("usemtl {m}\n");
    for (x, z) in corners {
        s += &format!("v {x} {y} {z}\n");
    }
    let f: Vec<String> = (1..=4).map(|k| format!("{}/{k}", base + k)).collect();
    s + &format!("f {}\n", f.join(" "))
}

/// The floor scene: a grey floor lit by a point light 1 m above it, a fence of material
/// `fence` (black) halfway between, the camera between fence and floor looking down.
fn floor_scene(dir: &Path, mtl_fence: &str, with_fence: bool, extra_toml: &str) -> Scene {
    let mut obj = "mtllib s.mtl\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n".to_string();
    obj += &quad_y(0.0, 2.0, true, "floor", 0);
    if with_fence {
        obj += &quad_y(0.5, 2.0, false, "fence", 4);
    }
    std::fs::write(dir.join("s.obj"), obj).unwrap();
    std::fs::write(
        dir.join("s.mtl"),
        format!("newmtl floor\nKd 0.5 0.5 0.5\nnewmtl fence\nKd 0 0 0\n{mtl_fence}\n"),
    )
    .unwrap();
    let toml = format!(
        "[camera]\neye = [0.0, 0.3, 0.0]\ntarget = [0.0, 0.0, 0.0]\nup = [0.0, 0.0, -1.0]\nvfov_deg = 60.0\nwidth = 16\nheight = 16\n\n[[mesh]]\nobj = \"s.obj\"\n\n[[light]]\ntype = \"point\"\nposition = [0.0, 1.0, 0.0]\nintensity = [1.0, 1.0, 1.0]\n{extra_toml}"
    );
    std::fs::write(dir.join("s.toml"), toml).unwrap();
    Scene::load(dir.join("s.toml")).unwrap()
}

/// The emitter scene: the camera looks down at an emitting quad (radiance 1) through the fence.
fn emitter_scene(dir: &Path, mtl_fence: &str) -> Scene {
    let mut obj = "mtllib e.mtl\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n".to_string();
    obj += &quad_y(0.0, 2.0, true, "light", 0);
    obj += &quad_y(0.5, 2.0, true, "fence", 4);
    std::fs::write(dir.join("e.obj"), obj).unwrap();
    std::fs::write(
        dir.join("e.mtl"),
        format!("newmtl light\nKd 0 0 0\nKe 1 1 1\nnewmtl fence\nKd 0 0 0\n{mtl_fence}\n"),
    )
    .unwrap();
    let toml = "[camera]\neye = [0.0, 1.5, 0.0]\ntarget = [0.0, 0.0, 0.0]\nup = [0.0, 0.0, -1.0]\nvfov_deg = 30.0\nwidth = 16\nheight = 16\n\n[[mesh]]\nobj = \"e.obj\"\n";
    std::fs::write(dir.join("e.toml"), toml).unwrap();
    Scene::load(dir.join("e.toml")).unwrap()
}

/// 2048 × 1 texels of alpha 1, 0, 1, 0, ... (white): bilinear filtering cut at 0.5 keeps
/// exactly half of each period.
fn stripes(path: &Path) {
    image::RgbaImage::from_fn(2048, 1, |x, _| image::Rgba([255, 255, 255, if x % 2 == 0 { 255 } else { 0 }]))
        .save(path)
        .unwrap();
}

fn settings(accel: AccelKind) -> RenderSettings {
    RenderSettings {
        photons: Some(20_000),
        caustic_photons: Some(2_000),
        spp: Some(16),
        seed: Some(3),
        accel: Some(accel),
        ..Default::default()
    }
}

fn accels() -> Vec<AccelKind> {
    if cfg!(feature = "embree") {
        vec![AccelKind::Embree, AccelKind::Bvh]
    } else {
        vec![AccelKind::Bvh]
    }
}

fn same_pixels(a: &Film, b: &Film) -> bool {
    a.pixels
        .iter()
        .zip(&b.pixels)
        .all(|(p, q)| p.to_array().map(f32::to_bits) == q.to_array().map(f32::to_bits))
}

#[test]
fn a_half_open_fence_lets_half_the_light_through() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    stripes(&d.join("fence.png"));
    for accel in accels() {
        // Camera rays: the emitter of radiance 1 seen through the fence.
        let seen = emitter_scene(d, "map_d fence.png");
        assert!(seen.cutouts().is_some() && seen.warnings.is_empty(), "{:?}", seen.warnings);
        let mean = render_checked(&seen, &settings(accel), 16).film.mean();
        println!("{accel:?}: emitter through the fence: {mean:.4}");
        assert!((mean - 0.5).abs() < 0.02, "{accel:?}: {mean}");
        // Shadow rays and photons: the floor under the fence against the open floor.
        let shaded = floor_scene(d, "map_d fence.png", true, "");
        let open = floor_scene(d, "", false, "");
        let (a, b) = (
            render_checked(&shaded, &settings(accel), 16).film,
            render_checked(&open, &settings(accel), 16).film,
        );
        let ratio = a.mean() / b.mean();
        println!("{accel:?}: floor under the fence / open floor: {ratio:.4}");
        assert!((ratio - 0.5).abs() < 0.03, "{accel:?}: {ratio}");
        // The scene file's alpha_texture and alpha_cutoff: cut at 0.0, the fence is whole (black).
        let closed = floor_scene(
            d,
            "",
            true,
            "\n[materials.fence]\nalpha_texture = \"fence.png\"\nalpha_cutoff = 0.0\n",
        );
        let c = render_checked(&closed, &settings(accel), 16).film.mean();
        assert!(c < 0.02 * b.mean(), "{accel:?}: closed fence {c} vs open {}", b.mean());
    }
}

#[test]
fn cutouts_render_the_same_on_any_number_of_threads() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    stripes(&d.join("fence.png"));
    let s = floor_scene(d, "map_d fence.png", true, "");
    for accel in accels() {
        let one = on_threads(1, || render_checked(&s, &settings(accel), 16).film);
        let two = on_threads(2, || render_checked(&s, &settings(accel), 16).film);
        assert!(same_pixels(&one, &two), "{accel:?}: 1 and 2 threads differ");
    }
}

#[test]
fn an_opaque_alpha_texture_changes_no_pixel() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    image::RgbaImage::from_pixel(8, 8, image::Rgba([255, 255, 255, 255])).save(d.join("solid.png")).unwrap();
    // A grey mask without alpha is read from its red channel: white is opaque.
    image::GrayImage::from_pixel(8, 8, image::Luma([255])).save(d.join("grey.png")).unwrap();
    let plain = floor_scene(d, "", true, "");
    for accel in accels() {
        let reference = render_checked(&plain, &settings(accel), 16).film;
        for map in ["map_d solid.png", "map_d grey.png"] {
            let opaque = floor_scene(d, map, true, "");
            assert!(opaque.maps.iter().any(|m| m.alpha.is_some()), "{map}");
            assert!(opaque.cutouts().is_none(), "{map}: an opaque map cuts nothing");
            let film = render_checked(&opaque, &settings(accel), 16).film;
            assert!(same_pixels(&film, &reference), "{accel:?}, {map}: the image changed");
        }
    }
}

#[test]
fn a_missing_alpha_texture_is_one_line_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(
        d.join("s.obj"),
        format!("mtllib s.mtl\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n{}", quad_y(0.0, 1.0, true, "fence", 0)),
    )
    .unwrap();
    std::fs::write(d.join("s.mtl"), "newmtl fence\nKd 0.5 0.5 0.5\nmap_d nosuch.png\n").unwrap();
    let toml = "[camera]\neye = [0.0, 1.0, 0.0]\ntarget = [0.0, 0.0, 0.0]\nup = [0.0, 0.0, -1.0]\nvfov_deg = 60.0\nwidth = 8\nheight = 8\n\n[[mesh]]\nobj = \"s.obj\"\n";
    std::fs::write(d.join("s.toml"), toml).unwrap();
    let e = Scene::load(d.join("s.toml")).unwrap_err().to_string();
    assert!(e.contains("s.mtl:3") && e.contains("nosuch.png") && !e.contains('\n'), "{e}");
    std::fs::write(d.join("s.mtl"), "newmtl fence\nKd 0.5 0.5 0.5\n").unwrap();
    std::fs::write(d.join("s.toml"), format!("{toml}\n[materials.fence]\nalpha_texture = \"gone.png\"\n"))
        .unwrap();
    let e = Scene::load(d.join("s.toml")).unwrap_err().to_string();
    assert!(
        e.contains("materials.fence.alpha_texture") && e.contains("gone.png") && !e.contains('\n'),
        "{e}"
    );
    std::fs::write(d.join("s.toml"), format!("{toml}\n[materials.fence]\nalpha_cutoff = 0.3\n")).unwrap();
    let e = Scene::load(d.join("s.toml")).unwrap_err().to_string();
    assert!(e.contains("materials.fence.alpha_cutoff") && e.contains("no alpha texture"), "{e}");
}
