//! Textured emission (MTL `map_Ke`, the scene file's `ke_texture`): area lights whose radiance
//! varies over the triangle.
//!
//! - A quad light whose `map_Ke` is white on one half and black on the other gives half the
//!   light of the untextured quad (the scene is symmetric, so exactly half on average), and
//!   the floor under its white half gets more than the floor under its black half.
//! - The photon mapper and the path tracer agree on it.
//! - A black texture makes no light (and no panic); a missing one is a one-line error naming it.

use crate::common;

use crate::common::render_checked;
use glam::Vec3;
use photonmap::config::{IntegratorKind, RenderSettings};
use photonmap::film::Film;
use photonmap::light::{EmissionTextures, LightSet};
use photonmap::scene::Scene;
use rand::{Rng, SeedableRng};
use std::path::Path;

/// A floor `[-1, 1]²` at `y = 0` and a light `[-0.5, 0.5]²` at `y = 1` facing down, its texture
/// coordinates `u = x + 0.5`, `v = z + 0.5`.
const OBJ: &str = "mtllib s.mtl
v -1 0 -1
v -1 0 1
v 1 0 1
v 1 0 -1
v -0.5 1 -0.5
v 0.5 1 -0.5
v 0.5 1 0.5
v -0.5 1 0.5
vt 0 0
vt 1 0
vt 1 1
vt 0 1
usemtl floor
f 1/1 2/1 3/1 4/1
usemtl light
f 5/1 6/2 7/3 8/4
";

const TOML: &str = r#"
[camera]
eye = [0.0, 0.5, -2.5]
target = [0.0, 0.3, 0.0]
up = [0.0, 1.0, 0.0]
vfov_deg = 60.0
width = 32
height = 32

[[mesh]]
obj = "s.obj"
"#;

/// The scene with `light` as the light's MTL statements (and `extra` appended to the scene
/// file), in `dir`.
fn scene(dir: &Path, light: &str, extra: &str) -> Result<Scene, String> {
    std::fs::write(dir.join("s.obj"), OBJ).unwrap();
    std::fs::write(
        dir.join("s.mtl"),
        format!("newmtl floor\nKd 0.5 0.5 0.5\n\nnewmtl light\nKd 0 0 0\n{light}\n"),
    )
    .unwrap();
    std::fs::write(dir.join("s.toml"), format!("{TOML}{extra}")).unwrap();
    Scene::load(dir.join("s.toml")).map_err(|e| e.to_string())
}

/// 64 × 64 PNGs: white where `u < 0.5` (the image's left half), black elsewhere; and all black.
fn write_textures(dir: &Path) {
    image::RgbImage::from_fn(64, 64, |x, _| if x < 32 { image::Rgb([255; 3]) } else { image::Rgb([0; 3]) })
        .save(dir.join("half.png"))
        .unwrap();
    image::RgbImage::from_pixel(8, 8, image::Rgb([0; 3])).save(dir.join("black.png")).unwrap();
}

fn settings(integrator: IntegratorKind) -> RenderSettings {
    RenderSettings {
        integrator: Some(integrator),
        photons: Some(100_000),
        caustic_photons: Some(1_000),
        spp: Some(16),
        seed: Some(5),
        ..Default::default()
    }
}

fn lights(s: &Scene) -> LightSet {
    let maps = s.emission_maps();
    let e =
        maps.as_deref().map(|maps| EmissionTextures { uvs: &s.attributes.uvs, textures: &s.textures, maps });
    LightSet::with_emission(&s.lights, &s.mesh, &s.tri_material, &s.materials, &[], e)
}

/// Irradiance on the floor (normal +y) at `p` from light sampling alone (nothing occludes).
fn irradiance(l: &LightSet, p: Vec3, n: usize) -> f32 {
    let mut rng = rand_pcg::Pcg64::seed_from_u64(9);
    let mut sum = 0.0f64;
    for _ in 0..n {
        if let Some(s) = l.sample_li(p, rng.gen(), [rng.gen(), rng.gen()]) {
            sum += (s.li.x * s.wi.y.max(0.0) / s.pdf) as f64;
        }
    }
    (sum / n as f64) as f32
}

/// Mean of the columns `cols` of `f`.
fn columns_mean(f: &Film, cols: std::ops::Range<usize>) -> f32 {
    let mut sum = 0.0;
    for y in 0..f.height {
        for x in cols.clone() {
            sum += f.get(x, y).x;
        }
    }
    sum / (f.height * (cols.end - cols.start)) as f32
}

#[test]
fn a_half_black_emission_texture_gives_half_the_light_from_its_white_side() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_textures(d);
    let plain = scene(d, "Ke 4 4 4", "").unwrap();
    let half = scene(d, "Ke 4 4 4\nmap_Ke half.png", "").unwrap();
    assert!(half.textured && half.warnings.is_empty(), "{:?}", half.warnings);
    // Light sampling: half the power; under the white half (x < 0) more light than under the
    // black half, the two adding up to the plain light's (the scene is symmetric).
    let (lp, lh) = (lights(&plain), lights(&half));
    let ratio = lh.total_power().x / lp.total_power().x;
    assert!((ratio - 0.5).abs() < 0.01, "power ratio {ratio}");
    let n = 400_000;
    let (c_plain, c_half) = (irradiance(&lp, Vec3::ZERO, n), irradiance(&lh, Vec3::ZERO, n));
    eprintln!("irradiance at the centre: plain {c_plain:.4}, half-white {c_half:.4}");
    assert!((c_half / c_plain - 0.5).abs() < 0.01, "{c_half} vs {c_plain}");
    let (white, black) =
        (irradiance(&lh, Vec3::new(-0.5, 0.0, 0.0), n), irradiance(&lh, Vec3::new(0.5, 0.0, 0.0), n));
    let side = irradiance(&lp, Vec3::new(0.5, 0.0, 0.0), n);
    eprintln!("under the white half {white:.4}, under the black half {black:.4}, plain {side:.4}");
    assert!(white > 1.5 * black, "{white} vs {black}");
    assert!(((white + black) / side - 1.0).abs() < 0.01, "{white} + {black} vs {side}");
    // Rendered: half the image on average, for both estimators, and brighter on the white
    // side (x < 0 is the image's right: the camera looks along +z).
    for integrator in [IntegratorKind::Photon, IntegratorKind::Path] {
        let a = render_checked(&plain, &settings(integrator), 32).film;
        let b = render_checked(&half, &settings(integrator), 32).film;
        let r = (b.mean() / a.mean()) as f32;
        let (left, right) = (columns_mean(&b, 0..16), columns_mean(&b, 16..32));
        eprintln!("{integrator:?}: mean ratio {r:.4}, image left {left:.4}, right {right:.4}");
        assert!((r - 0.5).abs() < 0.03, "{integrator:?}: textured / plain = {r}");
        assert!(right > 1.5 * left, "{integrator:?}: white side {right} vs black side {left}");
    }
}

#[test]
fn photons_and_paths_agree_on_a_textured_light() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_textures(d);
    // A colour ramp: red across u, green across v, over a white base.
    image::RgbImage::from_fn(32, 32, |x, y| image::Rgb([(x * 8) as u8, (y * 8) as u8, 64]))
        .save(d.join("ramp.png"))
        .unwrap();
    let s = scene(d, "Ke 3 3 3\nmap_Ke ramp.png", "").unwrap();
    let photon = render_checked(&s, &settings(IntegratorKind::Photon), 32).film;
    let path = render_checked(&s, &settings(IntegratorKind::Path), 32).film;
    for c in 0..3 {
        let mean = |f: &Film| f.pixels.iter().map(|p| p[c]).sum::<f32>() / f.pixels.len() as f32;
        let (a, b) = (mean(&photon), mean(&path));
        eprintln!("channel {c}: photon {a:.5}, path {b:.5} ({:+.2} %)", 100.0 * (a / b - 1.0));
        assert!((a / b - 1.0).abs() < 0.03, "channel {c}: photon {a} vs path {b}");
    }
}

#[test]
fn the_scene_file_ke_texture_replaces_map_ke_and_ke_defaults_to_one() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_textures(d);
    // No Ke in the MTL: map_Ke alone makes an emitter of radiance 1 × the texel.
    let alone = scene(d, "map_Ke half.png", "").unwrap();
    let l = lights(&alone);
    assert!((l.total_power().x - 0.5 * std::f32::consts::PI).abs() < 0.01, "{}", l.total_power());
    // ke_texture replaces it: black, nothing emits.
    let s =
        scene(d, "Ke 4 4 4\nmap_Ke half.png", "\n[materials.light]\nke_texture = \"black.png\"\n").unwrap();
    let l = lights(&s);
    assert!(l.is_empty() && l.emitters().is_empty(), "a black texture has no power");
    let out = render_checked(&s, &settings(IntegratorKind::Photon), 16);
    assert_eq!(out.film.mean(), 0.0, "no light");
    let out = render_checked(&s, &settings(IntegratorKind::Path), 16);
    assert_eq!(out.film.mean(), 0.0, "no light");
    // A diffuse material's ke texture is warned and dropped.
    let s =
        scene(d, "Ke 4 4 4", "\n[materials.floor]\nke_texture = \"half.png\"\ntype = \"diffuse\"\n").unwrap();
    assert!(s.warnings.iter().any(|w| w.contains("ke texture is not used")), "{:?}", s.warnings);
}

#[test]
fn a_missing_emission_texture_is_a_one_line_error_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let e = scene(d, "Ke 4 4 4\nmap_Ke gone.png", "").unwrap_err();
    assert!(e.contains("gone.png") && e.contains("s.mtl") && !e.trim_end().contains('\n'), "{e}");
    let e = scene(d, "Ke 4 4 4", "\n[materials.light]\nke_texture = \"missing.png\"\n").unwrap_err();
    assert!(e.contains("missing.png") && e.contains("ke_texture") && !e.trim_end().contains('\n'), "{e}");
}

#[test]
fn textured_light_renders_are_the_same_on_any_thread_count() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_textures(d);
    let s = scene(d, "Ke 4 4 4\nmap_Ke half.png", "").unwrap();
    let set = RenderSettings { photons: Some(20_000), spp: Some(2), ..settings(IntegratorKind::Photon) };
    let one = common::on_threads(1, || render_checked(&s, &set, 16).film);
    let two = common::on_threads(3, || render_checked(&s, &set, 16).film);
    assert!(one
        .pixels
        .iter()
        .zip(&two.pixels)
        .all(|(a, b)| a.to_array().map(f32::to_bits) == b.to_array().map(f32::to_bits)));
}
