//! `photon::kdtree` vs `kiddo` 4 (`ImmutableKdTree`, `SquaredEuclidean`) on photon-like data:
//! points on the six faces of a unit cube (jittered by ±1e-4 off the face planes, see
//! `photons`), 30% of them in a few tight clusters (caustics).
//!
//! Run: `cargo bench --bench kdtree` (criterion groups `build`, `knn`, then a ratio summary).
//! Queries are single-threaded; our build is measured both on the global rayon pool and on a
//! one-thread pool (kiddo's build is sequential).

use std::hint::black_box;
use std::time::{Duration, Instant};

use criterion::{BenchmarkId, Criterion, Throughput};
use glam::Vec3;
use kiddo::immutable::float::kdtree::ImmutableKdTree;
use kiddo::SquaredEuclidean;
use photonmap::photon::kdtree::{KdTree, Neighbor};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

type KiddoImm = ImmutableKdTree<f32, u32, 3, 32>;
type KiddoMut = kiddo::float::kdtree::KdTree<f32, u32, 3, 32, u32>;

/// kiddo's `ImmutableKdTree` (preferred) or, where its build panics on a data set (kiddo 4.2.1
/// fails with "mid > len" in `optimize_stems` on some inputs), its mutable `KdTree`.
enum Kiddo {
    Immutable(KiddoImm),
    Mutable(KiddoMut),
}

impl Kiddo {
    #[inline]
    fn nearest_n_within(&self, q: &[f32; 3], r2: f32, k: usize) -> Vec<kiddo::NearestNeighbour<f32, u32>> {
        match self {
            Kiddo::Immutable(t) => t.nearest_n_within::<SquaredEuclidean>(q, r2, k, true),
            Kiddo::Mutable(t) => t.nearest_n_within::<SquaredEuclidean>(q, r2, k, true),
        }
    }

    fn name(&self) -> &'static str {
        match self {
            Kiddo::Immutable(_) => "kiddo ImmutableKdTree",
            Kiddo::Mutable(_) => "kiddo KdTree (ImmutableKdTree unusable on this set)",
        }
    }
}

/// Whether kiddo's `ImmutableKdTree` can be built on `pts` (probed once, panic output muted).
/// On the 1M-point set kiddo 4.2.1's `ImmutableKdTree` build runs for over a minute in
/// `update_pivot` and then panics, so it is only tried there with `KIDDO_IMMUTABLE_1M=1`.
fn kiddo_immutable_ok(pts: &[Vec3]) -> bool {
    if pts.len() >= 1_000_000 && std::env::var_os("KIDDO_IMMUTABLE_1M").is_none() {
        eprintln!("note: using kiddo KdTree for {} points (ImmutableKdTree: >1 min, then panics)", pts.len());
        return false;
    }
    let arr: Vec<[f32; 3]> = pts.iter().map(|p| p.to_array()).collect();
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let ok = std::panic::catch_unwind(|| KiddoImm::new_from_slice(&arr)).is_ok();
    std::panic::set_hook(hook);
    if !ok {
        eprintln!("note: kiddo ImmutableKdTree build panicked on {} points; using kiddo KdTree", pts.len());
    }
    ok
}

const QUERIES: usize = 2000;

/// `n` photon-like points (see the file docs), deterministic in `seed`.
fn photons(n: usize, seed: u64) -> Vec<Vec3> {
    let mut rng = Pcg64::seed_from_u64(seed);
    let clusters: Vec<(usize, f32, f32, f32)> = (0..8)
        .map(|_| {
            (rng.gen_range(0..6), rng.gen_range(0.1..0.9), rng.gen_range(0.1..0.9), rng.gen_range(0.01..0.05))
        })
        .collect();
    (0..n)
        .map(|_| {
            let (face, u, v) = if rng.gen::<f32>() < 0.3 {
                let (f, cu, cv, s) = clusters[rng.gen_range(0..clusters.len())];
                // Sum of three uniforms: a cheap bell curve with standard deviation `s`.
                let mut g = || (rng.gen::<f32>() + rng.gen::<f32>() + rng.gen::<f32>() - 1.5) * 2.0 * s;
                (f, (cu + g()).rem_euclid(1.0), (cv + g()).rem_euclid(1.0))
            } else {
                (rng.gen_range(0..6), rng.gen::<f32>(), rng.gen::<f32>())
            };
            // Jitter off the exact face plane: kiddo 4.2.1's `ImmutableKdTree` build panics
            // ("mid > len") when huge numbers of points share one coordinate value exactly (as
            // photons on an axis-aligned wall do). Our tree handles exact planes (see tests).
            let (axis, side) = (face / 2, (face % 2) as f32 + rng.gen_range(-1e-4..1e-4));
            match axis {
                0 => Vec3::new(side, u, v),
                1 => Vec3::new(u, side, v),
                _ => Vec3::new(u, v, side),
            }
        })
        .collect()
}

/// Radius that holds about `k` points at the average density (`n` points over area 6).
fn radius_for(n: usize, k: usize) -> f32 {
    (6.0 * k as f32 / (std::f32::consts::PI * n as f32)).sqrt()
}

fn build_kiddo(pts: &[Vec3], immutable: bool) -> Kiddo {
    if immutable {
        let arr: Vec<[f32; 3]> = pts.iter().map(|p| p.to_array()).collect();
        Kiddo::Immutable(KiddoImm::new_from_slice(&arr))
    } else {
        let mut t = KiddoMut::with_capacity(pts.len());
        for (i, p) in pts.iter().enumerate() {
            t.add(&p.to_array(), i as u32);
        }
        Kiddo::Mutable(t)
    }
}

fn one_thread_pool() -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap()
}

fn run_ours(tree: &KdTree<Vec3>, qs: &[Vec3], k: usize, r: f32, out: &mut Vec<Neighbor>) -> usize {
    let mut total = 0;
    for &q in qs {
        tree.knn(q, k, r, out);
        total += out.len();
    }
    total
}

fn run_kiddo(tree: &Kiddo, qs: &[Vec3], k: usize, r: f32) -> usize {
    let mut total = 0;
    for q in qs {
        total += tree.nearest_n_within(&q.to_array(), r * r, k).len();
    }
    total
}

/// Both trees must agree before we time them.
fn cross_check(ours: &KdTree<Vec3>, kiddo: &Kiddo, qs: &[Vec3], k: usize, r: f32) {
    let mut out = Vec::new();
    for &q in qs.iter().take(200) {
        ours.knn(q, k, r, &mut out);
        let mut a: Vec<f32> = out.iter().map(|n| n.dist2).collect();
        a.sort_by(f32::total_cmp);
        let b = kiddo.nearest_n_within(&q.to_array(), r * r, k);
        assert_eq!(a.len(), b.len(), "result counts differ at {q}");
        for (x, y) in a.iter().zip(&b) {
            assert!((x - y.distance).abs() <= 1e-6 * y.distance.max(1e-6), "{x} vs {}", y.distance);
        }
    }
}

fn bench_build(c: &mut Criterion) {
    let mut g = c.benchmark_group("build");
    g.sample_size(10).measurement_time(Duration::from_secs(4)).warm_up_time(Duration::from_secs(1));
    let pool = one_thread_pool();
    for n in [100_000usize, 1_000_000] {
        let pts = photons(n, 1);
        let imm = kiddo_immutable_ok(&pts);
        g.throughput(Throughput::Elements(n as u64));
        g.bench_with_input(BenchmarkId::new("kdtree", n), &pts, |b, pts| {
            b.iter(|| KdTree::build(black_box(pts.clone())))
        });
        g.bench_with_input(BenchmarkId::new("kdtree_1thread", n), &pts, |b, pts| {
            b.iter(|| pool.install(|| KdTree::build(black_box(pts.clone()))))
        });
        g.bench_with_input(BenchmarkId::new("kiddo", n), &pts, |b, pts| {
            b.iter(|| build_kiddo(black_box(pts), imm))
        });
    }
    g.finish();
}

fn bench_knn(c: &mut Criterion) {
    let mut g = c.benchmark_group("knn");
    g.sample_size(20).measurement_time(Duration::from_secs(3)).warm_up_time(Duration::from_secs(1));
    for n in [100_000usize, 1_000_000] {
        let pts = photons(n, 1);
        let qs = photons(QUERIES, 2);
        let ours = KdTree::build(pts.clone());
        let kiddo = build_kiddo(&pts, kiddo_immutable_ok(&pts));
        for k in [50usize, 100] {
            let r = radius_for(n, k);
            cross_check(&ours, &kiddo, &qs, k, r);
            g.throughput(Throughput::Elements(qs.len() as u64));
            let mut out = Vec::with_capacity(k);
            g.bench_function(BenchmarkId::new(format!("kdtree/k={k}"), n), |b| {
                b.iter(|| run_ours(&ours, black_box(&qs), k, r, &mut out))
            });
            g.bench_function(BenchmarkId::new(format!("kiddo/k={k}"), n), |b| {
                b.iter(|| run_kiddo(&kiddo, black_box(&qs), k, r))
            });
        }
    }
    g.finish();
}

/// Best of `reps` wall-clock runs.
fn best_of<R>(reps: usize, mut f: impl FnMut() -> R) -> Duration {
    (0..reps)
        .map(|_| {
            let t = Instant::now();
            black_box(f());
            t.elapsed()
        })
        .min()
        .unwrap()
}

/// Prints `kdtree/kiddo` speed ratios (> 1 means our tree is faster) from its own best-of-N
/// timings, plus memory use.
fn summary(n: usize) {
    let pts = photons(n, 1);
    let qs = photons(20_000, 3);
    let pool = one_thread_pool();
    let t_ours = best_of(3, || KdTree::build(pts.clone()));
    let t_ours1 = best_of(3, || pool.install(|| KdTree::build(pts.clone())));
    let imm = kiddo_immutable_ok(&pts);
    let t_kiddo = best_of(3, || build_kiddo(&pts, imm));
    let ours = KdTree::build(pts.clone());
    let kiddo = build_kiddo(&pts, imm);
    let mut line = format!(
        "kdtree/kiddo build {}k: {:.2}x ({} threads; {:.2}x on 1 thread)",
        n / 1000,
        t_kiddo.as_secs_f64() / t_ours.as_secs_f64(),
        rayon::current_num_threads(),
        t_kiddo.as_secs_f64() / t_ours1.as_secs_f64()
    );
    let mut details = format!(
        "  build {}k: kdtree {:.1} ms, kdtree 1 thread {:.1} ms, kiddo {:.1} ms\n",
        n / 1000,
        t_ours.as_secs_f64() * 1e3,
        t_ours1.as_secs_f64() * 1e3,
        t_kiddo.as_secs_f64() * 1e3
    );
    for k in [50usize, 100] {
        let r = radius_for(n, k);
        let mut out = Vec::with_capacity(k);
        let a = best_of(3, || run_ours(&ours, &qs, k, r, &mut out));
        let b = best_of(3, || run_kiddo(&kiddo, &qs, k, r));
        let qps = |d: Duration| qs.len() as f64 / d.as_secs_f64();
        line += &format!(", knn k={k}: {:.2}x", b.as_secs_f64() / a.as_secs_f64());
        details += &format!(
            "  knn {}k k={k} (r = {r:.4}): kdtree {:.0} q/s, kiddo {:.0} q/s (1 thread)\n",
            n / 1000,
            qps(a),
            qps(b)
        );
    }
    println!(
        "\n{line}\n  (vs {})\n{details}  memory: kdtree {:.3} B/point on top of the 12-B points ({} B total for {n})",
        kiddo.name(),
        ours.overhead_bytes() as f64 / n as f64,
        ours.bytes()
    );
}

fn main() {
    let mut c = Criterion::default().configure_from_args();
    bench_build(&mut c);
    bench_knn(&mut c);
    c.final_summary();
    summary(100_000);
    summary(1_000_000);
}
