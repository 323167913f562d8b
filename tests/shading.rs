//! Shading normals from OBJ `vn`: the analytic checks of the real-scenes issue.
//!
//! - A furnace made of a coarse sphere with smooth (inward) vertex normals still gives its
//!   exact 2.0, for the photon mapper, sppm and the path tracer.
//! - A coarse sphere with smooth normals under a distant light matches the analytic
//!   Lambertian sphere at its terminator: no black facets where the smooth surface is lit.

use crate::common::render_checked;
use glam::Vec3;
use photonmap::config::{IntegratorKind, RenderSettings};
use photonmap::film::Film;
use photonmap::scene::Scene;
use std::fmt::Write;

/// A UV sphere of `rings` × `segments` around the origin, radius `r`, as OBJ text with one
/// vertex normal per vertex (pointing outward times `sign`), or none; wound outward, or
/// inward with `inward`.
fn sphere_obj(
    rings: u32,
    segments: u32,
    r: f32,
    normals: Option<f32>,
    inward: bool,
    material: &str,
) -> String {
    let mut s = format!("mtllib m.mtl\nusemtl {material}\n");
    let point = |i: u32, j: u32| {
        let theta = std::f32::consts::PI * i as f32 / rings as f32;
        let phi = std::f32::consts::TAU * j as f32 / segments as f32;
        Vec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin())
    };
    for i in 0..=rings {
        for j in 0..segments {
            let p = point(i, j);
            writeln!(s, "v {} {} {}", r * p.x, r * p.y, r * p.z).unwrap();
            if let Some(sign) = normals {
                writeln!(s, "vn {} {} {}", sign * p.x, sign * p.y, sign * p.z).unwrap();
            }
        }
    }
    let id = |i: u32, j: u32| 1 + i * segments + j % segments;
    for i in 0..rings {
        for j in 0..segments {
            let (a, b, c, d) = (id(i, j), id(i, j + 1), id(i + 1, j + 1), id(i + 1, j));
            for t in [[a, b, c], [a, c, d]] {
                let t = if inward { [t[0], t[2], t[1]] } else { t };
                if normals.is_some() {
                    writeln!(s, "f {0}//{0} {1}//{1} {2}//{2}", t[0], t[1], t[2]).unwrap();
                } else {
                    writeln!(s, "f {} {} {}", t[0], t[1], t[2]).unwrap();
                }
            }
        }
    }
    s
}

fn load(dir: &tempfile::TempDir, toml: &str, obj: &str, mtl: &str) -> Scene {
    std::fs::write(dir.path().join("m.obj"), obj).unwrap();
    std::fs::write(dir.path().join("m.mtl"), mtl).unwrap();
    let path = dir.path().join("s.toml");
    std::fs::write(&path, toml).unwrap();
    Scene::load(&path).unwrap()
}

/// The furnace inside a 6 × 12 sphere: faces 30° apart, so the shading normals lean up to 15°
/// off the faces. The camera sits near the wall and looks along it, where they lean most.
fn smooth_furnace(normals: Option<f32>) -> Scene {
    let dir = tempfile::tempdir().unwrap();
    let toml = r#"
[camera]
eye = [0.55, -0.3, 0.2]
target = [0.0, 0.4, -1.0]
up = [0.0, 1.0, 0.0]
vfov_deg = 100.0
width = 16
height = 16

[[mesh]]
obj = "m.obj"
"#;
    let mtl = "newmtl furnace\nKd 0.5 0.5 0.5\nKe 1 1 1\n";
    let s = load(&dir, toml, &sphere_obj(6, 12, 1.0, normals, normals.is_none(), "furnace"), mtl);
    assert_eq!(s.attributes.has_normals(), normals.is_some());
    s
}

#[test]
fn a_furnace_with_smooth_normals_still_gives_two() {
    // Inward normals: the sphere's winding is outward, so the loader turns every face round.
    let scene = smooth_furnace(Some(-1.0));
    let cases = [
        ("photon", RenderSettings { photons: Some(200_000), spp: Some(16), ..Default::default() }),
        (
            "sppm",
            RenderSettings {
                integrator: Some(IntegratorKind::Sppm),
                passes: Some(16),
                photons: Some(40_000),
                ..Default::default()
            },
        ),
        (
            "path",
            RenderSettings { integrator: Some(IntegratorKind::Path), spp: Some(256), ..Default::default() },
        ),
    ];
    for (name, settings) in cases {
        let mean = render_checked(&scene, &RenderSettings { seed: Some(3), ..settings }, 16).film.mean();
        println!("{name}: mean {mean:.4}");
        assert!((mean - 2.0).abs() < 0.02, "{name}: smooth furnace mean {mean}, exact 2.0");
    }
}

/// A 8 × 16 sphere of white Lambertian faces (22.5° apart, so the shading normals lean up to
/// 11° off them) under a distant light coming from `to_light`, seen from +Z.
fn terminator_scene(normals: bool, to_light: Vec3) -> Scene {
    let dir = tempfile::tempdir().unwrap();
    let d = -to_light;
    let toml = format!(
        r#"
[camera]
eye = [0.0, 0.0, 6.0]
target = [0.0, 0.0, 0.0]
up = [0.0, 1.0, 0.0]
vfov_deg = 22.0
width = 64
height = 64

[[mesh]]
obj = "m.obj"

[[light]]
type = "distant"
direction = [{}, {}, {}]
irradiance = [3.14159265, 3.14159265, 3.14159265]
"#,
        d.x, d.y, d.z
    );
    let mtl = "newmtl white\nKd 0.8 0.8 0.8\n";
    load(&dir, &toml, &sphere_obj(8, 16, 1.0, normals.then_some(1.0), false, "white"), mtl)
}

/// How many pixels are black (below 30 % of the value) where the analytic Lambertian sphere
/// lit from `to_light` is lit at more than 5 % of its peak, away from its silhouette: black
/// facets.
fn black_facets(film: &Film, to_light: Vec3) -> usize {
    let (w, h) = (film.width, film.height);
    let eye = Vec3::new(0.0, 0.0, 6.0);
    let tan = (22.0f32.to_radians() / 2.0).tan();
    let mut black = 0;
    for y in 0..h {
        for x in 0..w {
            let px = (2.0 * (x as f32 + 0.5) / w as f32 - 1.0) * tan;
            let py = (1.0 - 2.0 * (y as f32 + 0.5) / h as f32) * tan;
            let d = Vec3::new(px, py, -1.0).normalize();
            // The ray against a sphere a little inside the polygon, so every such pixel is on it.
            let b = eye.dot(d);
            let disc = b * b - (eye.length_squared() - 0.92 * 0.92);
            if disc <= 0.0 {
                continue;
            }
            let p = eye + (-b - disc.sqrt()) * d;
            // Away from the silhouette, where the polygon and the sphere part ways.
            if p.normalize().dot(-d) < 0.5 {
                continue;
            }
            let analytic = 0.8 * p.normalize().dot(to_light).max(0.0);
            if analytic > 0.05 * 0.8 && film.get(x, y).max_element() < 0.3 * analytic {
                black += 1;
            }
        }
    }
    black
}

#[test]
fn a_smooth_sphere_has_no_black_facets_at_its_terminator() {
    // Lights from the side and a little behind, so the terminator crosses the faces the camera
    // sees at several phases (facets just past it are lit by the smooth normals alone).
    let settings = RenderSettings { spp: Some(8), seed: Some(2), ..Default::default() };
    let mut total = 0;
    for deg in [96.0f32, 101.0, 106.0, 111.0] {
        let to_light = Vec3::new(deg.to_radians().sin(), 0.15, deg.to_radians().cos()).normalize();
        let smooth = render_checked(&terminator_scene(true, to_light), &settings, 64).film;
        let black = black_facets(&smooth, to_light);
        println!("light at {deg}°: {black} black pixels where the smooth sphere is lit");
        total += black;
    }
    // Shading the face flat where the light is behind it, or casting the shadow ray from the
    // face instead of the lifted point, gives 198 such pixels here.
    assert!(total <= 10, "{total} pixels of the smooth sphere are black where it is lit");
}
