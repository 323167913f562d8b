//! Textures from MTL `map_Kd`/`map_Ks` and the scene file's `kd_texture`: the analytic checks
//! of the real-scenes issue.
//!
//! - A constant texture gives the image of the constant, bit for bit: an EXR of 0.5 on the
//!   white furnace is the furnace of `kd = 0.5` (exactly 2.0), and an 8-bit PNG is decoded
//!   from sRGB to the `kd` its value stands for.
//! - Photons read the textures too: a box with a textured wall bleeds the texture's colour onto
//!   the floor as the path tracer sees it.

use crate::common::render_checked;
use glam::Vec3;
use photonmap::config::{IntegratorKind, RenderSettings};
use photonmap::film::Film;
use photonmap::scene::Scene;
use std::fmt::Write;
use std::path::Path;

/// The cube `[-1, 1]^3` as OBJ text, faces wound inward, each face's corners at texture
/// coordinates (0,0) (1,0) (1,1) (0,1), all of material `m`.
fn cube_obj(mtllib: &str, m: &str) -> String {
    let mut s = format!("mtllib {mtllib}\nusemtl {m}\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n");
    // Each face: an axis, a side, and two tangent axes wound so the normal points inward.
    let mut v = 0;
    for axis in 0..3 {
        for side in [-1.0f32, 1.0] {
            let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
            let corner = |x: f32, y: f32| {
                let mut p = [0.0f32; 3];
                p[axis] = side;
                p[a] = x;
                p[b] = y;
                p
            };
            let quad = if side > 0.0 {
                [corner(-1.0, -1.0), corner(-1.0, 1.0), corner(1.0, 1.0), corner(1.0, -1.0)]
            } else {
                [corner(-1.0, -1.0), corner(1.0, -1.0), corner(1.0, 1.0), corner(-1.0, 1.0)]
            };
            for p in quad {
                writeln!(s, "v {} {} {}", p[0], p[1], p[2]).unwrap();
            }
            writeln!(s, "f {}/1 {}/2 {}/3 {}/4", v + 1, v + 2, v + 3, v + 4).unwrap();
            v += 4;
        }
    }
    s
}

const FURNACE_TOML: &str = r#"
[camera]
eye = [0.1, -0.2, 0.05]
target = [0.4, 0.3, 1.0]
up = [0.0, 1.0, 0.0]
vfov_deg = 90.0
width = 16
height = 16

[[mesh]]
obj = "cube.obj"
"#;

/// The furnace with `mtl` as its material file, plus `files` written beside it.
fn furnace(dir: &Path, mtl: &str) -> Scene {
    std::fs::write(dir.join("cube.obj"), cube_obj("cube.mtl", "furnace")).unwrap();
    std::fs::write(dir.join("cube.mtl"), mtl).unwrap();
    std::fs::write(dir.join("s.toml"), FURNACE_TOML).unwrap();
    Scene::load(dir.join("s.toml")).unwrap()
}

fn same_pixels(a: &Film, b: &Film) -> bool {
    (0..a.height).all(|y| {
        (0..a.width)
            .all(|x| a.get(x, y).to_array().map(f32::to_bits) == b.get(x, y).to_array().map(f32::to_bits))
    })
}

fn settings() -> RenderSettings {
    RenderSettings {
        photons: Some(20_000),
        caustic_photons: Some(2_000),
        spp: Some(4),
        seed: Some(7),
        ..Default::default()
    }
}

#[test]
fn a_constant_texture_renders_as_its_constant_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // An EXR of 0.5 is kd = 0.5: the furnace's exact 2.0.
    let half = Film { width: 3, height: 5, pixels: vec![Vec3::splat(0.5); 15] };
    half.write_exr(&d.join("half.exr")).unwrap();
    let textured = furnace(d, "newmtl furnace\nKd 0.9 0.1 0.3\nKe 1 1 1\nmap_Kd half.exr\n");
    assert!(textured.textured && textured.warnings.is_empty(), "{:?}", textured.warnings);
    let plain = furnace(d, "newmtl furnace\nKd 0.5 0.5 0.5\nKe 1 1 1\n");
    for integrator in [IntegratorKind::Photon, IntegratorKind::Sppm, IntegratorKind::Path] {
        let s = RenderSettings { integrator: Some(integrator), passes: Some(2), ..settings() };
        let a = render_checked(&textured, &s, 16).film;
        let b = render_checked(&plain, &s, 16).film;
        assert!(same_pixels(&a, &b), "{integrator:?}: the textured furnace differs from kd = 0.5");
        assert!((a.mean() - 2.0).abs() < 0.03, "{integrator:?}: mean {}", a.mean());
    }
    // An 8-bit PNG of sRGB 188 is kd = 0.5029 (the sRGB curve), not 188/255 = 0.737.
    image::RgbImage::from_pixel(4, 4, image::Rgb([188, 188, 188])).save(d.join("grey.png")).unwrap();
    let kd = (((188.0f64 / 255.0 + 0.055) / 1.055).powf(2.4)) as f32;
    let png = furnace(d, "newmtl furnace\nKd 1 1 1\nKe 1 1 1\nmap_Kd grey.png\n");
    let plain = furnace(d, &format!("newmtl furnace\nKd {kd:?} {kd:?} {kd:?}\nKe 1 1 1\n"));
    let (a, b) = (render_checked(&png, &settings(), 16).film, render_checked(&plain, &settings(), 16).film);
    assert!(same_pixels(&a, &b), "the sRGB PNG differs from kd = {kd}");
    // The scene file's kd_texture replaces the MTL's map.
    std::fs::write(
        d.join("s.toml"),
        format!("{FURNACE_TOML}\n[materials.furnace]\ntype = \"emissive\"\nkd = [0.2, 0.2, 0.2]\nke = [1.0, 1.0, 1.0]\nkd_texture = \"half.exr\"\n"),
    )
    .unwrap();
    std::fs::write(d.join("cube.mtl"), "newmtl furnace\nKd 0.1 0.1 0.1\nKe 1 1 1\nmap_Kd grey.png\n")
        .unwrap();
    let overridden = Scene::load(d.join("s.toml")).unwrap();
    let half_again = furnace(d, "newmtl furnace\nKd 0.5 0.5 0.5\nKe 1 1 1\n");
    let (a, b) = (
        render_checked(&overridden, &settings(), 16).film,
        render_checked(&half_again, &settings(), 16).film,
    );
    assert!(same_pixels(&a, &b), "kd_texture did not replace map_Kd");
}

/// A closed white room 2 m on a side lit by a small ceiling light, its +X wall textured
/// half red (lower half) and half blue (upper half); the camera looks at the floor by that wall.
fn bleeding_room(dir: &Path) -> Scene {
    let mut room = cube_obj("room.mtl", "white");
    // The +X wall (axis 0, side +1) is the second face: give it its own material.
    room = room.replacen("f 5/1 6/2 7/3 8/4", "usemtl wall\nf 5/1 6/2 7/3 8/4\nusemtl white", 1);
    std::fs::write(dir.join("room.obj"), room).unwrap();
    // The light: a small quad just under the ceiling, facing down.
    std::fs::write(
        dir.join("light.obj"),
        "mtllib room.mtl\nusemtl light\nv -0.2 0.98 -0.2\nv 0.2 0.98 -0.2\nv 0.2 0.98 0.2\nv -0.2 0.98 0.2\nf 1 2 3 4\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("room.mtl"),
        "newmtl white\nKd 0.7 0.7 0.7\nnewmtl wall\nKd 1 1 1\nmap_Kd wall.png\nnewmtl light\nKd 0 0 0\nKe 30 30 30\n",
    )
    .unwrap();
    // Texture rows from the top: blue above, red below (v up).
    let wall = image::RgbImage::from_fn(8, 8, |_, y| {
        if y < 4 {
            image::Rgb([20, 40, 230])
        } else {
            image::Rgb([230, 30, 20])
        }
    });
    wall.save(dir.join("wall.png")).unwrap();
    std::fs::write(
        dir.join("s.toml"),
        r#"
[camera]
eye = [-0.6, 0.2, 0.9]
target = [0.7, -0.8, -0.2]
up = [0.0, 1.0, 0.0]
vfov_deg = 70.0
width = 16
height = 16

[[mesh]]
obj = "room.obj"

[[mesh]]
obj = "light.obj"
"#,
    )
    .unwrap();
    Scene::load(dir.join("s.toml")).unwrap()
}

#[test]
fn photons_bleed_the_texture_colour_as_the_path_tracer_does() {
    let dir = tempfile::tempdir().unwrap();
    let scene = bleeding_room(dir.path());
    assert!(scene.textured);
    let path = RenderSettings {
        integrator: Some(IntegratorKind::Path),
        spp: Some(1024),
        seed: Some(1),
        ..Default::default()
    };
    let photon =
        RenderSettings { photons: Some(400_000), spp: Some(16), seed: Some(1), ..Default::default() };
    let (p, q) = (render_checked(&scene, &path, 16).film, render_checked(&scene, &photon, 16).film);
    // Red over blue in the light bounced onto the floor: the photons carried the texture.
    let mean = |f: &Film| -> Vec3 { f.pixels.iter().copied().sum::<Vec3>() / f.pixels.len() as f32 };
    let (mp, mq) = (mean(&p), mean(&q));
    println!("path {mp:?}, photon {mq:?}");
    for c in 0..3 {
        assert!((mq[c] - mp[c]).abs() < 0.03 * mp[c] + 0.002, "channel {c}: photon {mq:?} vs path {mp:?}");
    }
    // The red the floor shows is the texture's, not the wall's Kd (white).
    assert!(mp.x > 1.1 * mp.z, "the floor by the wall should be reddish: {mp:?}");
}

/// A floor (y = 0, `u` along +X) with a normal map that leans every normal `tilt` degrees
/// toward +u, lit by a distant light from `toward_light` (unit), seen from above.
fn mapped_floor(dir: &Path, tilt: Option<f32>, toward_light: Vec3) -> Scene {
    let mut mtl = "newmtl floor\nKd 0.5 0.5 0.5\n".to_string();
    if let Some(deg) = tilt {
        let (s, c) = deg.to_radians().sin_cos();
        // Linear data in an EXR: exactly (sin, 0, cos) after 2 c - 1.
        let texel = Vec3::new(0.5 * s + 0.5, 0.5, 0.5 * c + 0.5);
        Film { width: 2, height: 2, pixels: vec![texel; 4] }.write_exr(&dir.join("normal.exr")).unwrap();
        mtl += "norm normal.exr\n";
    }
    std::fs::write(dir.join("floor.mtl"), mtl).unwrap();
    std::fs::write(
        dir.join("floor.obj"),
        "mtllib floor.mtl\nusemtl floor\nv -1 0 1\nv 1 0 1\nv 1 0 -1\nv -1 0 -1\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nf 1/1 2/2 3/3 4/4\n",
    )
    .unwrap();
    let d = -toward_light;
    std::fs::write(
        dir.join("s.toml"),
        format!(
            "[camera]\neye = [0.0, 3.0, 0.001]\ntarget = [0.0, 0.0, 0.0]\nup = [0.0, 0.0, -1.0]\nvfov_deg = 20.0\nwidth = 8\nheight = 8\n\n[[mesh]]\nobj = \"floor.obj\"\n\n[[light]]\ntype = \"distant\"\ndirection = [{}, {}, {}]\nirradiance = [3.14159265, 3.14159265, 3.14159265]\n",
            d.x, d.y, d.z
        ),
    )
    .unwrap();
    Scene::load(dir.join("s.toml")).unwrap()
}

#[test]
fn a_normal_map_leans_the_shading_normal_its_way() {
    let dir = tempfile::tempdir().unwrap();
    let s = RenderSettings { spp: Some(4), photons: Some(1000), seed: Some(1), ..Default::default() };
    let mean = |tilt, light: Vec3| {
        render_checked(&mapped_floor(dir.path(), tilt, light.normalize()), &s, 8).film.mean()
    };
    // Lambertian: radiance kd E cos / π = 0.5 cos(angle between the bent normal and the light).
    let from_east = Vec3::new(1.0, 1.0, 0.0);
    let from_west = Vec3::new(-1.0, 1.0, 0.0);
    let cases = [
        (None, from_east, 0.5 * 45f32.to_radians().cos()),
        (Some(30.0), Vec3::Y, 0.5 * 30f32.to_radians().cos()),
        (Some(30.0), from_east, 0.5 * 15f32.to_radians().cos()),
        (Some(30.0), from_west, 0.5 * 75f32.to_radians().cos()),
    ];
    for (tilt, light, expected) in cases {
        let m = mean(tilt, light);
        println!("tilt {tilt:?}, light from {light}: {m:.5}, expected {expected:.5}");
        assert!((m - expected as f64).abs() < 2e-3, "tilt {tilt:?}, light {light}: {m} vs {expected}");
    }
    assert!(render_checked(&mapped_floor(dir.path(), Some(30.0), Vec3::Y), &s, 8)
        .film
        .pixels
        .iter()
        .all(|p| p.is_finite()));
}

/// The floor of [`mapped_floor`] with a height map that rises along +u (`h = u`, texel centres
/// at `(i + 1/2) / 8`, clamped), scaled by `-bm slope`, given in the MTL or in the scene file.
fn bumped_floor(dir: &Path, slope: f32, toward_light: Vec3, in_toml: bool) -> Scene {
    let ramp = (0..16).map(|i| Vec3::splat(((i % 8) as f32 + 0.5) / 8.0)).collect();
    Film { width: 8, height: 2, pixels: ramp }.write_exr(&dir.join("ramp.exr")).unwrap();
    let scene = mapped_floor(dir, None, toward_light);
    let toml = std::fs::read_to_string(dir.join("s.toml")).unwrap();
    if in_toml {
        let entry = format!(
            "\n[materials.floor]\nkd = [0.5, 0.5, 0.5]\nbump_texture = \"ramp.exr\"\nbump_scale = {slope}\n"
        );
        std::fs::write(dir.join("s.toml"), toml + &entry).unwrap();
    } else {
        std::fs::write(
            dir.join("floor.mtl"),
            format!("newmtl floor\nKd 0.5 0.5 0.5\nmap_Bump -bm {slope} -clamp on ramp.exr\n"),
        )
        .unwrap();
    }
    drop(scene);
    Scene::load(dir.join("s.toml")).unwrap()
}

#[test]
fn a_height_map_tilts_the_shading_normal_down_its_slope() {
    let dir = tempfile::tempdir().unwrap();
    let s = RenderSettings { spp: Some(4), photons: Some(1000), seed: Some(1), ..Default::default() };
    // The floor is 2 units across u: height u * slope has slope/2 per unit length, so the
    // normal leans atan(slope / 2) toward -u (away from the rise).
    let slope = 2.0 * 30f32.to_radians().tan();
    let from_east = Vec3::new(1.0, 1.0, 0.0).normalize();
    let from_west = Vec3::new(-1.0, 1.0, 0.0).normalize();
    let cases = [
        (Vec3::Y, 0.5 * 30f32.to_radians().cos()),
        (from_west, 0.5 * 15f32.to_radians().cos()),
        (from_east, 0.5 * 75f32.to_radians().cos()),
    ];
    for (light, expected) in cases {
        let scene = bumped_floor(dir.path(), slope, light, false);
        assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
        let m = render_checked(&scene, &s, 8).film.mean();
        println!("bump, light from {light}: {m:.5}, expected {expected:.5}");
        assert!((m - expected as f64).abs() < 2e-3, "light {light}: {m} vs {expected}");
    }
    // The scene file's bump_texture and bump_scale say the same as the MTL's map_Bump -bm.
    let mtl = render_checked(&bumped_floor(dir.path(), slope, from_west, false), &s, 8).film;
    let toml = render_checked(&bumped_floor(dir.path(), slope, from_west, true), &s, 8).film;
    assert!(same_pixels(&mtl, &toml));
    // A flat height map (no slope anywhere) leaves the floor exactly as it is without one.
    let flat = render_checked(&bumped_floor(dir.path(), 0.0, from_west, false), &s, 8).film;
    let plain = render_checked(&mapped_floor(dir.path(), None, from_west), &s, 8).film;
    assert!(same_pixels(&flat, &plain));
}

#[test]
fn bump_scale_needs_a_bump_map() {
    let dir = tempfile::tempdir().unwrap();
    mapped_floor(dir.path(), None, Vec3::Y);
    let toml = std::fs::read_to_string(dir.path().join("s.toml")).unwrap();
    let entry = "\n[materials.floor]\nbump_scale = 2.0\n";
    std::fs::write(dir.path().join("s.toml"), toml + entry).unwrap();
    let e = Scene::load(dir.path().join("s.toml")).unwrap_err().to_string();
    assert!(e.contains("materials.floor.bump_scale") && e.contains("no bump map"), "{e}");
}

#[test]
fn the_scene_files_normal_texture_is_the_mtls_norm() {
    let dir = tempfile::tempdir().unwrap();
    let s = RenderSettings { spp: Some(2), photons: Some(500), seed: Some(3), ..Default::default() };
    let light = Vec3::new(1.0, 1.0, 0.0).normalize();
    let mtl = render_checked(&mapped_floor(dir.path(), Some(30.0), light), &s, 8).film;
    // The same map, named by the scene file over an MTL without it.
    std::fs::write(dir.path().join("floor.mtl"), "newmtl floor\nKd 0.5 0.5 0.5\n").unwrap();
    let toml = std::fs::read_to_string(dir.path().join("s.toml")).unwrap();
    let entry = "\n[materials.floor]\nkd = [0.5, 0.5, 0.5]\nnormal_texture = \"normal.exr\"\n";
    std::fs::write(dir.path().join("s.toml"), toml.clone() + entry).unwrap();
    let file = render_checked(&Scene::load(dir.path().join("s.toml")).unwrap(), &s, 8).film;
    assert!(same_pixels(&mtl, &file));
    // Both at once are refused, by field.
    let both = format!("{entry}bump_texture = \"normal.exr\"\n");
    std::fs::write(dir.path().join("s.toml"), toml + &both).unwrap();
    let e = Scene::load(dir.path().join("s.toml")).unwrap_err().to_string();
    assert!(e.contains("materials.floor.bump_texture"), "{e}");
}

/// MTL's PBR maps (`map_Pr`, `map_Pm`: their red channel, linear) replace `Pr` and `Pm` texel
/// by texel, as glTF's `metallicRoughnessTexture` does: a polished metal texel is a principled
/// metal, a rough dielectric one diffuse, the base colour `Kd` (times `map_Kd`) on both. They
/// were warned as not rendered, and the whole surface drawn with the constants.
#[test]
fn mtl_pbr_maps_decide_each_texels_material() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // Left texel: roughness 0.2, metallic 1; right: roughness 0.8, metallic 0.
    image::GrayImage::from_fn(2, 1, |x, _| image::Luma([if x == 0 { 51 } else { 204 }]))
        .save(d.join("r.png"))
        .unwrap();
    image::GrayImage::from_fn(2, 1, |x, _| image::Luma([if x == 0 { 255 } else { 0 }]))
        .save(d.join("m.png"))
        .unwrap();
    let mtl = "newmtl furnace\nKd 0.9 0.6 0.2\nPr 0.5\nPm 0\nillum 2\nmap_Pr r.png\nmap_Pm m.png\n";
    let s = furnace(d, mtl);
    assert!(s.warnings.iter().all(|w| !w.contains("map_P")), "{:?}", s.warnings);
    let at = |u: f32| s.material_at(0, glam::Vec2::new(u, 0.5), Vec3::ONE);
    let base = Vec3::new(0.9, 0.6, 0.2);
    assert_eq!(at(0.25), photonmap::material::Material::principled(base, 1.0, 51.0 / 255.0));
    assert_eq!(at(0.75), photonmap::material::Material::Diffuse { kd: base });
    // Without `Pr` or `Pm`, `map_Pr` alone makes the material principled.
    let s = furnace(d, "newmtl furnace\nKd 0.9 0.6 0.2\nillum 2\nmap_Pr r.png\n");
    assert_eq!(
        s.material_at(0, glam::Vec2::new(0.25, 0.5), Vec3::ONE),
        photonmap::material::Material::principled(base, 0.0, 51.0 / 255.0)
    );
    render_checked(&s, &settings(), 8);
}

/// OBJ vertex colours (`v x y z r g b`, sRGB-decoded as 8-bit textures are) multiply the
/// diffuse colour: the white furnace (`Kd 1`, `Ke 1`) whose every vertex is coloured 0.5 is
/// the furnace of `kd` = 0.214, `1 / (1 − 0.214)` everywhere. They were read and dropped.
#[test]
fn obj_vertex_colours_multiply_the_diffuse_colour() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mtl = "newmtl furnace\nKd 1 1 1\nKe 1 1 1\n";
    std::fs::write(d.join("cube.mtl"), mtl).unwrap();
    let coloured: String = cube_obj("cube.mtl", "furnace")
        .lines()
        .map(|l| if l.starts_with("v ") { format!("{l} 0.5 0.5 0.5\n") } else { format!("{l}\n") })
        .collect();
    std::fs::write(d.join("cube.obj"), coloured).unwrap();
    std::fs::write(d.join("s.toml"), FURNACE_TOML).unwrap();
    let s = Scene::load(d.join("s.toml")).unwrap();
    assert!(s.attributes.has_colours() && s.textured);
    let kd = ((0.5f64 + 0.055) / 1.055).powf(2.4);
    let exact = 1.0 / (1.0 - kd);
    let mean = render_checked(&s, &settings(), 16).film.mean();
    assert!((mean / exact - 1.0).abs() < 0.01, "mean {mean}, exact {exact}");
    // A colour outside [0, 1] is refused, naming the line.
    let bad = cube_obj("cube.mtl", "furnace").replacen("v -1 -1 -1", "v -1 -1 -1 2 0 0", 1);
    std::fs::write(d.join("cube.obj"), bad).unwrap();
    let err = Scene::load(d.join("s.toml")).err().unwrap().to_string();
    assert!(err.contains("cube.obj:") && err.contains("vertex colour values must be in [0, 1]"), "{err}");
}
