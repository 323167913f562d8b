//! Ray throughput and build time of the backends on the same rays (criterion, `harness = false`).
//!
//! The scene is procedural and deterministic: a noisy UV sphere (~100k triangles; ~1M for the
//! large build) inside a closed box, like an object in a room. Ray sets, generated once by
//! [`generate_rays`] and shared by every backend:
//!
//! * **coherent**: a pinhole grid from an eye inside the box, in scan order, traced one ray at a
//!   time (`intersect`) and in batches (`intersect_batch`, Embree's 8-wide packets);
//! * **incoherent**: uniform origins inside the bounds, uniform directions (`intersect`), with
//!   Embree's robust mode on (the renderer's default) and off;
//! * **shadow**: segments between surface points (`occluded`).
//!
//! Each set is traced on one thread and on all threads (rayon). Build times are for 100k and 1M
//! triangles.
//!
//! After criterion's own report (on 10k-ray subsets), a summary table in M rays/s with the
//! BVH/Embree ratio per row is printed; it comes from a fixed-iteration loop (each run traces the
//! whole 100k-ray set once) and reports the median of 5 runs.
//!
//! Environment:
//! * `RAYS_SUMMARY_ONLY=1`: skip criterion, print only the summary table;
//! * `RAYS_PROFILE=<incoherent|coherent|shadow>`: trace only that set with the BVH on one thread
//!   for `RAYS_PROFILE_SECS` (default 5) seconds, for `perf record` / callgrind.

use criterion::{BenchmarkId, Criterion, Throughput};
use photonmap::accel::bvh::Bvh;
use photonmap::accel::{init_tracing_thread, Accel, Hit};
use photonmap::geometry::{Ray, TriangleMesh, Vec3};
use photonmap::tools::agree::{generate_rays, CameraLike, RayKind};
use photonmap::tools::bench::median;
use rayon::prelude::*;
use std::hint::black_box;
use std::time::{Duration, Instant};

#[cfg(feature = "embree")]
use photonmap::accel::{embree::EmbreeAccel, AccelOptions};

/// Rays per set in the summary table.
const RAYS: usize = 100_000;
/// Rays per set in criterion's benchmarks.
const CRITERION_RAYS: usize = 10_000;
/// Runs per summary row; the median is reported.
const RUNS: usize = 5;
/// Rays per `intersect_batch` call in the batched rows (a run of 64 rays of one scanline).
const BATCH: usize = 64;
/// Rays per rayon task in the multi-threaded rows.
const PAR_CHUNK: usize = 1024;

/// A UV sphere of about `2 n²` triangles with a smooth radial bump field.
fn noisy_sphere(n: u32) -> TriangleMesh {
    let bump = |p: Vec3| 1.0 + 0.05 * (7.0 * p.x).sin() * (9.0 * p.y).sin() * (11.0 * p.z).sin();
    TriangleMesh::parametric_sphere(n, n, |theta, phi| {
        let p = Vec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos());
        p * bump(p)
    })
}

/// A closed box (the room), each face split into `2 n²` triangles.
fn room(min: Vec3, max: Vec3, n: u32) -> TriangleMesh {
    let mut m = TriangleMesh::default();
    let e = max - min;
    // (corner, edge u, edge v) of each face.
    let faces = [
        (min, Vec3::new(e.x, 0.0, 0.0), Vec3::new(0.0, e.y, 0.0)),
        (min, Vec3::new(0.0, e.y, 0.0), Vec3::new(0.0, 0.0, e.z)),
        (min, Vec3::new(0.0, 0.0, e.z), Vec3::new(e.x, 0.0, 0.0)),
        (max, Vec3::new(-e.x, 0.0, 0.0), Vec3::new(0.0, -e.y, 0.0)),
        (max, Vec3::new(0.0, -e.y, 0.0), Vec3::new(0.0, 0.0, -e.z)),
        (max, Vec3::new(0.0, 0.0, -e.z), Vec3::new(-e.x, 0.0, 0.0)),
    ];
    for (o, u, v) in faces {
        let base = m.positions.len() as u32;
        for j in 0..=n {
            for i in 0..=n {
                m.positions.push(o + u * (i as f32 / n as f32) + v * (j as f32 / n as f32));
            }
        }
        let at = |i: u32, j: u32| base + j * (n + 1) + i;
        for j in 0..n {
            for i in 0..n {
                m.indices.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
                m.indices.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
            }
        }
    }
    m
}

/// The noisy sphere (radius ~1 at the origin) inside a room of half-size 2.
fn scene(sphere_n: u32) -> TriangleMesh {
    let mut m = room(Vec3::splat(-2.0), Vec3::splat(2.0), 8);
    m.append(&noisy_sphere(sphere_n));
    m
}

/// How a set is traced.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Mode {
    /// `intersect`, one ray at a time.
    Single,
    /// `intersect_batch` on runs of [`BATCH`] rays.
    Batch,
    /// `occluded`, one ray at a time.
    Occluded,
}

struct RaySet {
    name: &'static str,
    mode: Mode,
    rays: Vec<Ray>,
}

fn ray_sets(mesh: &TriangleMesh, per_set: usize) -> Vec<RaySet> {
    // The eye inside the room, looking at the sphere.
    let cam = CameraLike { eye: Vec3::new(0.6, 0.9, 1.9), target: Vec3::ZERO };
    let all = generate_rays(mesh, Some(cam), 5 * per_set, 42);
    let pick = |k: RayKind| all.iter().filter(|(kind, _)| *kind == k).map(|(_, r)| *r).collect::<Vec<_>>();
    vec![
        RaySet { name: "coherent", mode: Mode::Single, rays: pick(RayKind::Camera) },
        RaySet { name: "coherent batch", mode: Mode::Batch, rays: pick(RayKind::Camera) },
        RaySet { name: "incoherent", mode: Mode::Single, rays: pick(RayKind::Random) },
        RaySet { name: "shadow", mode: Mode::Occluded, rays: pick(RayKind::Shadow) },
    ]
}

/// Traces `rays` once on the calling thread; returns the number of hits.
fn cast_seq<A: Accel>(accel: &A, rays: &[Ray], mode: Mode) -> usize {
    match mode {
        Mode::Single => rays.iter().filter(|r| accel.intersect(r).is_some()).count(),
        Mode::Occluded => rays.iter().filter(|r| accel.occluded(r)).count(),
        Mode::Batch => {
            let mut hits = [None::<Hit>; BATCH];
            rays.chunks(BATCH)
                .map(|c| {
                    let h = &mut hits[..c.len()];
                    accel.intersect_batch(c, h);
                    h.iter().filter(|h| h.is_some()).count()
                })
                .sum()
        }
    }
}

/// Traces `rays` once, on one thread or on all of rayon's; returns the number of hits.
fn cast<A: Accel>(accel: &A, rays: &[Ray], mode: Mode, parallel: bool) -> usize {
    if parallel {
        rays.par_chunks(PAR_CHUNK).map(|c| cast_seq(accel, c, mode)).sum()
    } else {
        cast_seq(accel, rays, mode)
    }
}

/// Median over [`RUNS`] runs of M rays/s, after one warm-up run.
fn rate<A: Accel>(accel: &A, set: &RaySet, parallel: bool) -> f64 {
    black_box(cast(accel, &set.rays, set.mode, parallel));
    median(
        (0..RUNS)
            .map(|_| {
                let t = Instant::now();
                black_box(cast(accel, &set.rays, set.mode, parallel));
                set.rays.len() as f64 / t.elapsed().as_secs_f64() / 1e6
            })
            .collect(),
    )
}

/// Median build time in ms over `runs` builds.
fn build_ms<T>(runs: usize, build: impl Fn() -> T) -> f64 {
    median(
        (0..runs)
            .map(|_| {
                let t = Instant::now();
                black_box(build());
                t.elapsed().as_secs_f64() * 1e3
            })
            .collect(),
    )
}

/// Criterion benchmarks of one backend on the (criterion-sized) ray sets.
fn bench_backend<A: Accel>(c: &mut Criterion, label: &str, accel: &A, sets: &[RaySet]) {
    let mut g = c.benchmark_group(format!("trace/{label}"));
    g.sample_size(10).warm_up_time(Duration::from_millis(300)).measurement_time(Duration::from_secs(1));
    for set in sets {
        g.throughput(Throughput::Elements(set.rays.len() as u64));
        for (threads, parallel) in [("1t", false), ("all", true)] {
            g.bench_function(BenchmarkId::new(set.name, threads), |b| {
                b.iter(|| cast(accel, &set.rays, set.mode, parallel))
            });
        }
    }
    g.finish();
}

/// One row of the summary: the BVH's and (if built) Embree's figure.
struct Row {
    what: String,
    bvh: f64,
    embree: Option<f64>,
}

fn print_table(title: &str, unit: &str, rows: &[Row], ratio_note: &str) {
    println!("\n{title}");
    println!(
        "{:<34} {:>10} {:>10} {:>10}",
        "",
        format!("bvh {unit}"),
        format!("embree {unit}"),
        "bvh/embree"
    );
    for r in rows {
        match r.embree {
            Some(e) => println!("{:<34} {:>10.2} {:>10.2} {:>10.2}", r.what, r.bvh, e, r.bvh / e),
            None => println!("{:<34} {:>10.2} {:>10} {:>10}", r.what, r.bvh, "-", "-"),
        }
    }
    println!("{ratio_note}");
}

fn main() {
    rayon::ThreadPoolBuilder::new().start_handler(|_| init_tracing_thread()).build_global().ok();
    init_tracing_thread();
    let threads = rayon::current_num_threads();
    let small = scene(224);

    if let Ok(name) = std::env::var("RAYS_PROFILE") {
        let bvh = Bvh::build(&small);
        let sets = ray_sets(&small, RAYS);
        let set = sets.iter().find(|s| s.name == name).expect("incoherent, coherent or shadow");
        let secs: f64 = std::env::var("RAYS_PROFILE_SECS").ok().and_then(|s| s.parse().ok()).unwrap_or(5.0);
        let (t, mut n) = (Instant::now(), 0usize);
        while t.elapsed().as_secs_f64() < secs {
            black_box(cast(&bvh, &set.rays, set.mode, false));
            n += set.rays.len();
        }
        println!("bvh {name}: {:.2} M rays/s", n as f64 / t.elapsed().as_secs_f64() / 1e6);
        return;
    }

    let summary_only = std::env::var("RAYS_SUMMARY_ONLY").is_ok_and(|v| !v.is_empty() && v != "0");
    let large = scene(708);
    let sets = ray_sets(&small, RAYS);
    let bvh = Bvh::build(&small);
    #[cfg(feature = "embree")]
    let (embree, embree_fast) = {
        let robust = AccelOptions::default();
        let fast = AccelOptions { robust: false };
        (EmbreeAccel::build(&small, robust).unwrap(), EmbreeAccel::build(&small, fast).unwrap())
    };

    if !summary_only {
        let mut c = Criterion::default().configure_from_args();
        let sub: Vec<RaySet> = sets
            .iter()
            .map(|s| RaySet { name: s.name, mode: s.mode, rays: s.rays[..CRITERION_RAYS].to_vec() })
            .collect();
        bench_backend(&mut c, "bvh", &bvh, &sub);
        #[cfg(feature = "embree")]
        {
            bench_backend(&mut c, "embree", &embree, &sub);
            bench_backend(&mut c, "embree-nonrobust", &embree_fast, &sub[2..3]);
        }
        let mut g = c.benchmark_group("build");
        g.sample_size(10).warm_up_time(Duration::from_millis(300)).measurement_time(Duration::from_secs(2));
        g.throughput(Throughput::Elements(small.len() as u64));
        g.bench_function(BenchmarkId::new("bvh", "100k"), |b| b.iter(|| Bvh::build(black_box(&small))));
        #[cfg(feature = "embree")]
        g.bench_function(BenchmarkId::new("embree", "100k"), |b| {
            b.iter(|| EmbreeAccel::build(black_box(&small), AccelOptions::default()).unwrap())
        });
        g.finish();
        c.final_summary();
    }

    let mut rows = Vec::new();
    for set in &sets {
        for parallel in [false, true] {
            let what = format!(
                "{:<16} {}",
                set.name,
                if parallel { format!("{threads} threads") } else { "1 thread".into() }
            );
            let bvh_rate = rate(&bvh, set, parallel);
            #[cfg(feature = "embree")]
            let embree_rate = Some(rate(&embree, set, parallel));
            #[cfg(not(feature = "embree"))]
            let embree_rate = None;
            rows.push(Row { what, bvh: bvh_rate, embree: embree_rate });
            #[cfg(feature = "embree")]
            if set.name == "incoherent" {
                rows.push(Row {
                    what: format!(
                        "{:<16} {}",
                        "incoherent*",
                        if parallel { format!("{threads} threads") } else { "1 thread".into() }
                    ),
                    bvh: bvh_rate,
                    embree: Some(rate(&embree_fast, set, parallel)),
                });
            }
        }
    }
    let mut builds = Vec::new();
    for (label, mesh, runs) in [("100k", &small, 5), ("1M", &large, 3)] {
        let what = format!("{label} ({} triangles, {threads} threads)", mesh.len());
        let b = build_ms(runs, || Bvh::build(mesh));
        #[cfg(feature = "embree")]
        let e = Some(build_ms(runs, || EmbreeAccel::build(mesh, AccelOptions::default()).unwrap()));
        #[cfg(not(feature = "embree"))]
        let e = None;
        builds.push(Row { what, bvh: b, embree: e });
    }

    println!(
        "\nScene: noisy sphere in a box, {} triangles; {} rays per set; median of {RUNS} runs; {} BVH nodes",
        small.len(),
        RAYS,
        bvh.node_count()
    );
    print_table(
        "Ray throughput",
        "M/s",
        &rows,
        "(embree: robust mode, the renderer's default; * = embree non-robust; batch = intersect_batch, Embree packets of 8)",
    );
    print_table("Build time", "ms", &builds, "(embree: medium quality, robust; the 1M scene: median of 3)");
}
