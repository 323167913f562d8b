//! The BVH against brute force on procedural meshes: closest hits, occlusion and watertightness.

use photonmap::accel::bvh::Bvh;
use photonmap::accel::naive::Naive;
use photonmap::accel::Accel;
use photonmap::geometry::{Ray, TriangleMesh, Vec3};
use photonmap::tools::agree::{compare, generate_rays, AgreeReport, CameraLike};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;
use rayon::prelude::*;

/// A closed UV sphere: `rings` latitude bands, `segments` longitudes, single-vertex poles.
fn uv_sphere(centre: Vec3, r: f32, rings: u32, segments: u32) -> TriangleMesh {
    TriangleMesh::parametric_sphere(rings, segments, |theta, phi| {
        centre + r * Vec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos())
    })
}

/// A closed box of 12 triangles over 8 shared corners.
fn closed_box(min: Vec3, max: Vec3) -> TriangleMesh {
    let positions = (0..8)
        .map(|k| {
            Vec3::new(
                if k & 1 != 0 { max.x } else { min.x },
                if k & 2 != 0 { max.y } else { min.y },
                if k & 4 != 0 { max.z } else { min.z },
            )
        })
        .collect();
    let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
    let indices = quads.iter().flat_map(|[a, b, c, d]| [[*a, *b, *c], [*a, *c, *d]]).collect();
    TriangleMesh { positions, indices }
}

/// `n` random triangles of random size in the unit cube.
fn soup(n: usize, seed: u64) -> TriangleMesh {
    let mut rng = Pcg64::seed_from_u64(seed);
    let mut m = TriangleMesh::default();
    for i in 0..n as u32 {
        let c = Vec3::new(rng.gen(), rng.gen(), rng.gen());
        let s = 0.002 + 0.05 * rng.gen::<f32>().powi(3);
        for _ in 0..3 {
            m.positions.push(c + s * Vec3::new(rng.gen(), rng.gen(), rng.gen()) - s * 0.5);
        }
        m.indices.push([3 * i, 3 * i + 1, 3 * i + 2]);
    }
    m
}

/// A wavy heightfield of long slivers, with degenerate triangles mixed in (repeated corners,
/// collinear corners, all-equal corners).
fn slivers_and_degenerates(n: u32) -> TriangleMesh {
    let h = |x: f32, y: f32| 0.2 * (3.0 * x).sin() * (2.0 * y).cos();
    let mut m = TriangleMesh::default();
    for i in 0..n {
        for j in 0..n {
            let (x, y) = (i as f32 / n as f32, j as f32 / n as f32);
            let d = 1.0 / n as f32;
            let base = m.positions.len() as u32;
            let p = |x: f32, y: f32| Vec3::new(x, y, h(x, y));
            // Two slivers 1e-3 wide covering the strip, then degenerates on its centre line.
            m.positions.extend([p(x, y), p(x + d, y), p(x + d, y + 1e-3 * d), p(x, y + 1e-3 * d)]);
            m.positions.push(p(x + 0.5 * d, y + 0.5e-3 * d));
            m.indices.extend([[base, base + 1, base + 2], [base, base + 2, base + 3]]);
            m.indices.extend([[base, base, base + 1], [base + 4, base + 4, base + 4]]);
            // Exactly collinear corners along x.
            let z = h(x, y);
            m.positions.extend([Vec3::new(x, y, z), Vec3::new(x + 0.5 * d, y, z), Vec3::new(x + d, y, z)]);
            m.indices.push([base + 5, base + 6, base + 7]);
        }
    }
    m
}

fn scaled(mut m: TriangleMesh, s: f32, shift: Vec3) -> TriangleMesh {
    m.positions.iter_mut().for_each(|p| *p = *p * s + shift);
    m
}

fn check(name: &str, mesh: &TriangleMesh, camera: Option<CameraLike>, n: usize) -> AgreeReport {
    let bvh = Bvh::build(mesh);
    let naive = Naive::new(mesh);
    let rays = generate_rays(mesh, camera, n, 0x5eed ^ mesh.len() as u64);
    let report = compare(&bvh, &naive, &rays, mesh);
    println!("{name}: {} triangles, {} nodes\n{report}", mesh.len(), bvh.node_count());
    assert_eq!(report.hit_miss_disagreements, 0, "{name}\n{report}");
    assert_eq!(report.primitive_disagreements, 0, "{name}\n{report}");
    assert_eq!(report.occlusion_disagreements, 0, "{name}\n{report}");
    assert!(report.edge_ties as f64 <= 1e-3 * report.rays as f64, "{name}\n{report}");
    assert!(report.max_rel_dt < 1e-4, "{name}\n{report}");
    report
}

#[test]
fn agrees_on_uv_sphere() {
    let r = check("sphere", &uv_sphere(Vec3::new(0.5, -1.0, 2.0), 1.5, 32, 64), None, 10_000);
    assert!(r.per_kind.values().all(|k| k.rays > 0));
}

#[test]
fn agrees_on_boxes_at_all_scales() {
    let b = closed_box(Vec3::new(-1.0, -0.5, -2.0), Vec3::new(1.0, 0.5, 2.0));
    check("box", &b, None, 20_000);
    // Camera inside the box.
    let inside = CameraLike { eye: Vec3::new(0.2, 0.1, 0.3), target: Vec3::new(1.0, 0.0, -2.0) };
    check("box from inside", &b, Some(inside), 5_000);
    check("box 1e-3", &scaled(b.clone(), 1e-3, Vec3::new(3e-3, 0.0, -1e-3)), None, 20_000);
    check("box 1e4", &scaled(b, 1e4, Vec3::new(2e4, -3e4, 0.0)), None, 20_000);
}

#[test]
fn agrees_on_triangle_soup() {
    check("soup", &soup(20_000, 3), None, 2_000);
}

#[test]
fn agrees_on_slivers_and_degenerates() {
    let m = slivers_and_degenerates(40);
    let bvh = Bvh::build(&m);
    assert_eq!(bvh.triangle_count(), 2 * 40 * 40, "zero-area triangles are not indexed");
    check("slivers", &m, None, 4_000);
    // Rays straight down along the degenerate triangles' lines never report them.
    for i in 0..m.len() as u32 {
        if m.normal(i).is_none() {
            let [a, _, c] = m.triangle(i);
            let ray = Ray::new(a.lerp(c, 0.3) + Vec3::Z, -Vec3::Z);
            assert!(bvh.intersect(&ray).is_none_or(|h| m.normal(h.prim).is_some()));
        }
    }
}

/// Rays from random points inside a closed mesh must all hit it, from the front or back.
fn assert_watertight(name: &str, mesh: &TriangleMesh, inside: impl Fn(&mut Pcg64) -> Vec3 + Sync, n: usize) {
    let bvh = Bvh::build(mesh);
    let leaks: usize = (0..n as u64)
        .into_par_iter()
        .map(|i| {
            let mut rng = Pcg64::seed_from_u64(i);
            let o = inside(&mut rng);
            let z = 1.0 - 2.0 * rng.gen::<f32>();
            let phi = std::f32::consts::TAU * rng.gen::<f32>();
            let r = (1.0 - z * z).max(0.0).sqrt();
            let ray = Ray::new(o, Vec3::new(r * phi.cos(), r * phi.sin(), z));
            let hit = bvh.intersect(&ray);
            assert!(hit.is_none_or(|h| h.t.is_finite() && h.u.is_finite() && h.v.is_finite()));
            usize::from(hit.is_none() || !bvh.occluded(&ray))
        })
        .sum();
    assert_eq!(leaks, 0, "{name}: {leaks} of {n} rays escaped");
}

#[test]
fn closed_meshes_do_not_leak() {
    let b = closed_box(Vec3::new(-1.0, -2.0, -0.5), Vec3::new(3.0, 0.5, 0.5));
    let in_box = |rng: &mut Pcg64| {
        Vec3::new(rng.gen_range(-1.0..3.0), rng.gen_range(-2.0..0.5), rng.gen_range(-0.5..0.5))
    };
    assert_watertight("box", &b, in_box, 200_000);
    let centre = Vec3::new(1.0, 2.0, -3.0);
    let s = uv_sphere(centre, 2.0, 32, 64);
    let in_ball = move |rng: &mut Pcg64| loop {
        let p = Vec3::new(rng.gen(), rng.gen(), rng.gen()) * 2.0 - 1.0;
        if p.length() < 0.95 {
            return centre + 2.0 * p;
        }
    };
    assert_watertight("sphere", &s, in_ball, 200_000);
}

#[test]
fn large_mesh_agrees_and_is_watertight() {
    // About 500k triangles: naive is O(n) per ray, so only a few hundred rays against it.
    let centre = Vec3::new(-2.0, 0.5, 1.0);
    let m = uv_sphere(centre, 3.0, 500, 500);
    assert!(m.len() > 490_000);
    check("sphere 500k", &m, None, 400);
    let in_ball = move |rng: &mut Pcg64| loop {
        let p = Vec3::new(rng.gen(), rng.gen(), rng.gen()) * 2.0 - 1.0;
        if p.length() < 0.99 {
            return centre + 3.0 * p;
        }
    };
    assert_watertight("sphere 500k", &m, in_ball, 100_000);
}

#[test]
fn empty_mesh_misses() {
    let m = TriangleMesh::default();
    let bvh = Bvh::build(&m);
    let rays = generate_rays(&m, None, 100, 1);
    assert!(rays.iter().all(|(_, r)| bvh.intersect(r).is_none() && !bvh.occluded(r)));
    assert!(compare(&bvh, &Naive::new(&m), &rays, &m).clean());
}
