//! BVH build time and ray throughput (criterion, `harness = false`).
//!
//! Scenes are procedural: a noisy UV sphere of ~100k and ~1M triangles. Ray sets (100k rays
//! each, on the 100k scene): incoherent random rays (origins uniform in the bounds, uniform
//! directions), coherent camera rays (a pinhole grid in scan order) and shadow segments between
//! surface points. Every backend goes through [`bench_backend`], generic over [`Accel`], so a
//! second backend (Embree) slots in with one call in `main`. After criterion's own report, a
//! summary of M rays/s (1 thread and all threads) is printed.

use criterion::{BenchmarkId, Criterion, Throughput};
use photonmap::accel::bvh::Bvh;
use photonmap::accel::Accel;
use photonmap::agree::{generate_rays, RayKind};
use photonmap::geometry::{Ray, TriangleMesh, Vec3};
use rayon::prelude::*;
use std::hint::black_box;
use std::time::{Duration, Instant};

/// A UV sphere of about `2 n²` triangles with a smooth radial bump field.
fn noisy_sphere(n: u32) -> TriangleMesh {
    let (rings, segments) = (n, n);
    let bump = |p: Vec3| 1.0 + 0.05 * (7.0 * p.x).sin() * (9.0 * p.y).sin() * (11.0 * p.z).sin();
    let mut positions = vec![Vec3::Z * bump(Vec3::Z)];
    for i in 1..rings {
        let theta = std::f32::consts::PI * i as f32 / rings as f32;
        for j in 0..segments {
            let phi = std::f32::consts::TAU * j as f32 / segments as f32;
            let p = Vec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos());
            positions.push(p * bump(p));
        }
    }
    let south = positions.len() as u32;
    positions.push(-Vec3::Z * bump(-Vec3::Z));
    let ring = |i: u32, j: u32| 1 + (i - 1) * segments + j % segments;
    let mut indices = Vec::new();
    for j in 0..segments {
        indices.push([0, ring(1, j), ring(1, j + 1)]);
        indices.push([south, ring(rings - 1, j + 1), ring(rings - 1, j)]);
    }
    for i in 1..rings - 1 {
        for j in 0..segments {
            let (a, b, c, d) = (ring(i, j), ring(i, j + 1), ring(i + 1, j), ring(i + 1, j + 1));
            indices.push([a, c, d]);
            indices.push([a, d, b]);
        }
    }
    TriangleMesh { positions, indices }
}

struct RaySets {
    sets: Vec<(&'static str, bool, Vec<Ray>)>,
}

impl RaySets {
    fn new(mesh: &TriangleMesh, per_set: usize) -> Self {
        let all = generate_rays(mesh, None, 5 * per_set, 42);
        let pick = |k: RayKind| all.iter().filter(|(kind, _)| *kind == k).map(|(_, r)| *r).collect();
        RaySets {
            sets: vec![
                ("incoherent", false, pick(RayKind::Random)),
                ("coherent", false, pick(RayKind::Camera)),
                ("shadow", true, pick(RayKind::Shadow)),
            ],
        }
    }
}

/// Casts every ray once (closest hit, or occlusion for shadow rays); returns the hit count.
fn cast<A: Accel>(accel: &A, rays: &[Ray], occlusion: bool, parallel: bool) -> usize {
    let one = |r: &Ray| usize::from(if occlusion { accel.occluded(r) } else { accel.intersect(r).is_some() });
    if parallel {
        rays.par_iter().with_min_len(256).map(one).sum()
    } else {
        rays.iter().map(one).sum()
    }
}

/// Rays per second over repeated passes for at least `min_time`.
fn rate<A: Accel>(accel: &A, rays: &[Ray], occlusion: bool, parallel: bool, min_time: Duration) -> f64 {
    cast(accel, rays, occlusion, parallel);
    let start = Instant::now();
    let mut n = 0usize;
    while start.elapsed() < min_time {
        black_box(cast(accel, rays, occlusion, parallel));
        n += rays.len();
    }
    n as f64 / start.elapsed().as_secs_f64()
}

/// Criterion benchmarks of one backend on the ray sets, then its M rays/s summary rows.
fn bench_backend<A: Accel>(c: &mut Criterion, accel: &A, rays: &RaySets, summary: &mut Vec<String>) {
    let mut g = c.benchmark_group(format!("trace/{}", accel.name()));
    g.sample_size(10).measurement_time(Duration::from_secs(3));
    for (name, occlusion, set) in &rays.sets {
        g.throughput(Throughput::Elements(set.len() as u64));
        for (threads, parallel) in [("1t", false), ("all", true)] {
            g.bench_function(BenchmarkId::new(*name, threads), |b| {
                b.iter(|| cast(accel, set, *occlusion, parallel))
            });
        }
    }
    g.finish();
    for (name, occlusion, set) in &rays.sets {
        let one = rate(accel, set, *occlusion, false, Duration::from_secs(1));
        let all = rate(accel, set, *occlusion, true, Duration::from_secs(1));
        summary.push(format!(
            "{:<8} {:<11} {:>9.2} {:>11.2}  (threads: {})",
            accel.name(),
            name,
            one / 1e6,
            all / 1e6,
            rayon::current_num_threads()
        ));
    }
}

fn main() {
    let small = noisy_sphere(224); // 99,904 triangles
                                   // `BVH_PROFILE=<set>`: only trace that set for a few seconds, for profilers.
    if let Ok(set) = std::env::var("BVH_PROFILE") {
        let bvh = Bvh::build(&small);
        let rays = RaySets::new(&small, 100_000);
        let (_, occ, r) = rays.sets.iter().find(|s| s.0 == set).expect("incoherent, coherent or shadow");
        let secs = std::env::var("BVH_PROFILE_SECS").map_or(3.0, |s| s.parse().unwrap_or(3.0));
        println!("{set}: {:.2} M rays/s", rate(&bvh, r, *occ, false, Duration::from_secs_f64(secs)) / 1e6);
        return;
    }
    let mut c = Criterion::default().configure_from_args();
    let large = noisy_sphere(708); // 1,001,112 triangles
    let mut summary = Vec::new();

    let mut g = c.benchmark_group("build/bvh");
    g.sample_size(10);
    for (label, mesh) in [("100k", &small), ("1M", &large)] {
        g.throughput(Throughput::Elements(mesh.len() as u64));
        g.bench_function(label, |b| b.iter(|| Bvh::build(black_box(mesh))));
    }
    g.finish();
    for (label, mesh) in [("100k", &small), ("1M", &large)] {
        let t = Instant::now();
        let bvh = Bvh::build(mesh);
        summary.push(format!(
            "bvh build {label}: {} triangles, {} nodes, {:.1} ms",
            mesh.len(),
            bvh.node_count(),
            t.elapsed().as_secs_f64() * 1e3
        ));
    }

    let rays = RaySets::new(&small, 100_000);
    let bvh = Bvh::build(&small);
    bench_backend(&mut c, &bvh, &rays, &mut summary);
    // A second backend goes here, e.g. `bench_backend(&mut c, &EmbreeAccel::build(..), ..)`.

    c.final_summary();
    println!("\nM rays/s on {} triangles ({} rays per set)", small.len(), rays.sets[0].2.len());
    println!("{:<8} {:<11} {:>9} {:>11}", "backend", "rays", "1 thread", "all threads");
    for line in summary {
        println!("{line}");
    }
}
