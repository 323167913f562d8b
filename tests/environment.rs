//! The environment light (`[[light]] type = "environment"`): the analytic checks of the
//! real-scenes issue, for every integrator.
//!
//! - A white sky (radiance 1) around objects of albedo 1 is the white furnace: every pixel is
//!   exactly 1, the objects invisible, whatever light bounces between them.
//! - A convex object of albedo 0.5 under a constant sky sees only sky: its radiance is 0.5.
//! - Under an image sky with a small bright sun, photon mapping agrees with the path tracer.

use crate::common::render_checked;
use glam::{Vec3, Vec4};
use photonmap::config::{IntegratorKind, RenderSettings};
use photonmap::film::Film;
use photonmap::scene::Scene;
use std::fmt::Write;
use std::path::Path;

/// A UV sphere (outward) of radius `r` at `c`, and an axis-aligned box from `lo` to `hi`, as
/// OBJ text with material `m`.
fn objects(m: &str) -> String {
    let mut s = format!("mtllib m.mtl\nusemtl {m}\n");
    let (c, r, rings, segments) = (Vec3::new(-0.5, 0.0, 0.0), 0.6f32, 16u32, 32u32);
    for i in 0..=rings {
        for j in 0..segments {
            let (t, p) = (
                std::f32::consts::PI * i as f32 / rings as f32,
                std::f32::consts::TAU * j as f32 / segments as f32,
            );
            let q = c + r * Vec3::new(t.sin() * p.cos(), t.cos(), t.sin() * p.sin());
            writeln!(s, "v {} {} {}", q.x, q.y, q.z).unwrap();
        }
    }
    let id = |i: u32, j: u32| 1 + i * segments + j % segments;
    for i in 0..rings {
        for j in 0..segments {
            let (a, b, c2, d) = (id(i, j), id(i, j + 1), id(i + 1, j + 1), id(i + 1, j));
            // Outward: seen from outside, counter-clockwise.
            writeln!(s, "f {a} {c2} {b}\nf {a} {d} {c2}").unwrap();
        }
    }
    let base = (rings + 1) * segments;
    let (lo, hi) = (Vec3::new(0.4, -0.5, -0.4), Vec3::new(1.2, 0.3, 0.4));
    for k in 0..8u32 {
        let p = Vec3::new(
            if k & 1 == 0 { lo.x } else { hi.x },
            if k & 2 == 0 { lo.y } else { hi.y },
            if k & 4 == 0 { lo.z } else { hi.z },
        );
        writeln!(s, "v {} {} {}", p.x, p.y, p.z).unwrap();
    }
    for f in [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]] {
        writeln!(s, "f {} {} {} {}", base + 1 + f[0], base + 1 + f[1], base + 1 + f[2], base + 1 + f[3])
            .unwrap();
    }
    s
}

fn scene(dir: &Path, kd: f32, light: &str) -> Scene {
    std::fs::write(dir.join("m.obj"), objects("m")).unwrap();
    std::fs::write(dir.join("m.mtl"), format!("newmtl m\nKd {kd} {kd} {kd}\n")).unwrap();
    let toml = format!(
        r#"
[camera]
eye = [0.3, 0.9, 3.2]
target = [0.2, -0.1, 0.0]
up = [0.0, 1.0, 0.0]
vfov_deg = 50.0
width = 16
height = 16

[[mesh]]
obj = "m.obj"

[[light]]
type = "environment"
{light}
"#
    );
    std::fs::write(dir.join("s.toml"), toml).unwrap();
    Scene::load(dir.join("s.toml")).unwrap()
}

fn integrators() -> Vec<(&'static str, RenderSettings)> {
    vec![
        (
            "photon",
            RenderSettings { photons: Some(100_000), spp: Some(16), seed: Some(3), ..Default::default() },
        ),
        (
            "sppm",
            RenderSettings {
                integrator: Some(IntegratorKind::Sppm),
                passes: Some(8),
                photons: Some(30_000),
                seed: Some(3),
                ..Default::default()
            },
        ),
        (
            "path",
            RenderSettings {
                integrator: Some(IntegratorKind::Path),
                spp: Some(128),
                seed: Some(3),
                ..Default::default()
            },
        ),
    ]
}

fn rmse_against(f: &Film, v: f32) -> f64 {
    let sum: f64 = f.pixels.iter().map(|p| (*p - Vec3::splat(v)).length_squared() as f64 / 3.0).sum();
    (sum / f.pixels.len() as f64).sqrt()
}

#[test]
fn a_white_sky_around_white_objects_is_the_white_furnace() {
    let dir = tempfile::tempdir().unwrap();
    let s = scene(dir.path(), 1.0, "radiance = [1.0, 1.0, 1.0]");
    for (name, settings) in integrators() {
        let f = render_checked(&s, &settings, 16).film;
        let (mean, rmse) = (f.mean(), rmse_against(&f, 1.0));
        println!("{name}: mean {mean:.4}, rmse against 1: {rmse:.4}");
        assert!((mean - 1.0).abs() < 0.01, "{name}: mean {mean}, exact 1");
        assert!(rmse < 0.06, "{name}: rmse {rmse} against the exact 1");
    }
}

#[test]
fn a_convex_object_under_a_constant_sky_reflects_its_albedo() {
    let dir = tempfile::tempdir().unwrap();
    // A sky of 2 and albedo 0.5: the sphere's side away from the box reflects exactly 1.
    let s = scene(dir.path(), 0.5, "radiance = [2.0, 2.0, 2.0]");
    for (name, settings) in integrators() {
        let f = render_checked(&s, &settings, 16).film;
        // The sphere's centre pixel column, a few rows about its middle: it sees only sky.
        // The sphere's far side from the box (pixels 2..=4 × 6..=8) sees only sky.
        let block: Vec3 =
            (2..=4).flat_map(|x| (6..=8).map(move |y| (x, y))).map(|(x, y)| f.get(x, y)).sum::<Vec3>() / 9.0;
        println!("{name}: sphere block {block:?}");
        assert!((block - Vec3::ONE).abs().max_element() < 0.03, "{name}: sphere {block}, exact 1.0");
        // Sky pixels (top corners) are the sky.
        assert!((f.get(0, 0) - Vec3::splat(2.0)).abs().max_element() < 1e-4, "{name}: {:?}", f.get(0, 0));
    }
}

#[test]
fn photons_from_an_image_sky_agree_with_the_path_tracer() {
    let dir = tempfile::tempdir().unwrap();
    // A 32 × 16 sky: blue above the horizon, dark ground below, and a small sun.
    let (w, h) = (32u32, 16u32);
    let texels = (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            if (10..12).contains(&x) && (3..5).contains(&y) {
                Vec4::new(200.0, 180.0, 150.0, 1.0)
            } else if y < h / 2 {
                Vec4::new(0.3, 0.5, 1.0, 1.0)
            } else {
                Vec4::new(0.1, 0.08, 0.05, 1.0)
            }
        })
        .collect::<Vec<_>>();
    let sky =
        Film { width: w as usize, height: h as usize, pixels: texels.iter().map(|t| t.truncate()).collect() };
    sky.write_exr(&dir.path().join("sky.exr")).unwrap();
    let s = scene(dir.path(), 0.6, "map = \"sky.exr\"\nrotate = { axis = [0, 1, 0], degrees = 40 }");
    let path = RenderSettings {
        integrator: Some(IntegratorKind::Path),
        spp: Some(2048),
        seed: Some(1),
        ..Default::default()
    };
    let reference = render_checked(&s, &path, 16).film;
    for (name, settings) in integrators().into_iter().filter(|(n, _)| *n != "path") {
        let f = render_checked(&s, &RenderSettings { spp: Some(64), ..settings }, 16).film;
        let (m, r) = (f.mean(), reference.mean());
        let rmse = photonmap::film::compare(&f, &reference).map(|(rmse, _)| rmse).unwrap();
        println!("{name}: mean {m:.4} vs path {r:.4}, rmse {rmse:.4}");
        assert!((m / r - 1.0).abs() < 0.02, "{name}: mean {m} vs path {r}");
    }
}
