//! Property tests for `photon::kdtree`: every query agrees with a linear scan on random point
//! sets, including degenerate ones (duplicates, planes, lines, empty, single point).

use std::cell::Cell;
use std::sync::atomic::{AtomicUsize, Ordering};

use glam::Vec3;
use photonmap::photon::kdtree::{flattened_metric, KdPoint, KdTree, Neighbor};
use proptest::collection::vec;
use proptest::prelude::*;

/// Coordinates: either continuous or on a coarse grid (the grid produces exact ties and
/// duplicates on single axes).
fn coord() -> impl Strategy<Value = f32> {
    prop_oneof![-10.0f32..10.0, (-16i32..16).prop_map(|i| i as f32 * 0.25)]
}

fn point() -> impl Strategy<Value = Vec3> {
    (coord(), coord(), coord()).prop_map(|(x, y, z)| Vec3::new(x, y, z))
}

const MAX_N: usize = 1500;

fn point_set() -> impl Strategy<Value = Vec<Vec3>> {
    prop_oneof![
        vec(point(), 0..MAX_N),
        // Many duplicates drawn from a small pool.
        (vec(point(), 1..5), vec(0usize..5, 0..MAX_N))
            .prop_map(|(pool, idx)| idx.iter().map(|&i| pool[i % pool.len()]).collect()),
        // Random points plus a heavy pile of one duplicate.
        (vec(point(), 0..500), point(), 0usize..1000).prop_map(|(mut v, p, m)| {
            v.extend(std::iter::repeat_n(p, m));
            v
        }),
        // A plane z = c.
        (coord(), vec((coord(), coord()), 0..MAX_N))
            .prop_map(|(z, xy)| xy.into_iter().map(|(x, y)| Vec3::new(x, y, z)).collect()),
        // A tilted line segment.
        (point(), point(), vec(0.0f32..1.0, 0..MAX_N))
            .prop_map(|(a, b, ts)| ts.into_iter().map(|t| a + (b - a) * t).collect()),
        Just(Vec::new()),
        point().prop_map(|p| vec![p]),
    ]
}

fn radius() -> impl Strategy<Value = f32> {
    prop_oneof![Just(f32::INFINITY), Just(0.0f32), 0.0f32..6.0]
}

/// Queries: random points plus the first and middle data points (exact hits).
fn queries(pts: &[Vec3], extra: &[Vec3]) -> Vec<Vec3> {
    let mut q = extra.to_vec();
    if !pts.is_empty() {
        q.push(pts[0]);
        q.push(pts[pts.len() / 2]);
    }
    q
}

/// Sorted squared metric values of the `k` nearest within `r` by linear scan.
fn scan_knn(pts: &[Vec3], p: Vec3, k: usize, r: f32, metric: impl Fn(Vec3) -> f32) -> Vec<f32> {
    let mut d: Vec<f32> = pts.iter().map(|&x| metric(x - p)).filter(|&d| d <= r * r).collect();
    d.sort_by(f32::total_cmp);
    d.truncate(k);
    d
}

/// Checks a k-NN result against the scan: same multiset of distances, distinct indices, each
/// reported distance equal to the recomputed one, and `out[0]` the farthest.
fn check_knn(
    tree: &KdTree<Vec3>,
    out: &[Neighbor],
    expected: &[f32],
    p: Vec3,
    metric: impl Fn(Vec3) -> f32,
) -> Result<(), TestCaseError> {
    let mut got: Vec<f32> = out.iter().map(|n| n.dist2).collect();
    got.sort_by(f32::total_cmp);
    prop_assert_eq!(&got, expected);
    let mut idx: Vec<u32> = out.iter().map(|n| n.index).collect();
    idx.sort_unstable();
    idx.dedup();
    prop_assert_eq!(idx.len(), out.len());
    for n in out {
        prop_assert_eq!(n.dist2, metric(*tree.get(n.index) - p));
    }
    if let Some(first) = out.first() {
        prop_assert_eq!(first.dist2, *got.last().unwrap());
    }
    Ok(())
}

fn euclid(d: Vec3) -> f32 {
    d.length_squared()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 200, ..ProptestConfig::default() })]

    #[test]
    fn knn_matches_linear_scan(pts in point_set(), qs in vec(point(), 1..6), k in 0usize..70, r in radius()) {
        let tree = KdTree::build(pts.clone());
        prop_assert_eq!(tree.len(), pts.len());
        let mut out = Vec::new();
        for p in queries(&pts, &qs) {
            tree.knn(p, k, r, &mut out);
            prop_assert!(out.len() <= k);
            prop_assert!(out.iter().all(|n| n.dist2 <= r * r));
            check_knn(&tree, &out, &scan_knn(&pts, p, k, r, euclid), p, euclid)?;
        }
    }

    #[test]
    fn knn_with_k_larger_than_n_returns_all_within_radius(pts in point_set(), q in point(), r in radius()) {
        let tree = KdTree::build(pts.clone());
        let mut out = Vec::new();
        let k = pts.len() + 10;
        tree.knn(q, k, r, &mut out);
        let expected = scan_knn(&pts, q, k, r, euclid);
        prop_assert_eq!(out.len(), expected.len());
        check_knn(&tree, &out, &expected, q, euclid)?;
    }

    #[test]
    fn within_radius_matches_linear_scan(pts in point_set(), qs in vec(point(), 1..6), r in radius()) {
        let tree = KdTree::build(pts.clone());
        let mut out = Vec::new();
        for p in queries(&pts, &qs) {
            tree.within_radius(p, r, &mut out);
            // Compare as multisets of positions (indices differ: the tree reorders its items).
            let mut got: Vec<[u32; 3]> =
                out.iter().map(|n| tree.get(n.index).to_array().map(f32::to_bits)).collect();
            let mut want: Vec<[u32; 3]> = pts
                .iter()
                .filter(|&&x| (x - p).length_squared() <= r * r)
                .map(|x| x.to_array().map(f32::to_bits))
                .collect();
            got.sort_unstable();
            want.sort_unstable();
            prop_assert_eq!(got, want);
            for n in &out {
                prop_assert_eq!(n.dist2, (*tree.get(n.index) - p).length_squared());
            }
        }
    }

    #[test]
    fn flattened_knn_matches_linear_scan(
        pts in point_set(),
        qs in vec(point(), 1..6),
        n in (-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0),
        stretch in prop_oneof![Just(1.0f32), 1.0f32..50.0],
        k in 1usize..70,
        r in radius(),
    ) {
        let normal = Vec3::new(n.0, n.1, n.2).try_normalize().unwrap_or(Vec3::Z);
        let metric = flattened_metric(normal, stretch);
        let tree = KdTree::build(pts.clone());
        let mut out = Vec::new();
        for p in queries(&pts, &qs) {
            tree.knn_with(p, k, r, metric, &mut out);
            check_knn(&tree, &out, &scan_knn(&pts, p, k, r, metric), p, metric)?;
            // The same metric through the radius query.
            let mut count = 0usize;
            tree.for_each_within_with(p, r, metric, |i, d| {
                assert_eq!(d, metric(*tree.get(i) - p));
                count += 1;
            });
            prop_assert_eq!(count, pts.iter().filter(|&&x| metric(x - p) <= r * r).count());
        }
    }

    /// A first search within a guessed radius finds the same neighbours as one search from the
    /// full radius, whether the guess is too small (searched again), about right, or too large.
    #[test]
    fn knn_with_a_guessed_radius_matches_linear_scan(
        pts in point_set(),
        qs in vec(point(), 1..6),
        n in (-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0),
        stretch in prop_oneof![Just(1.0f32), 1.0f32..50.0],
        k in 1usize..70,
        r in radius(),
        guess in prop_oneof![Just(0.0f32), 1e-6f32..1.0, 1.0f32..1e4],
    ) {
        let normal = Vec3::new(n.0, n.1, n.2).try_normalize().unwrap_or(Vec3::Z);
        let metric = flattened_metric(normal, stretch);
        let tree = KdTree::build(pts.clone());
        let mut out = Vec::new();
        for p in queries(&pts, &qs) {
            tree.knn_with_guess(p, k, r, guess * r * r, metric, &mut out);
            check_knn(&tree, &out, &scan_knn(&pts, p, k, r, metric), p, metric)?;
        }
    }
}

#[test]
fn empty_and_single() {
    let mut out = vec![Neighbor { index: 7, dist2: 1.0 }];
    let empty: KdTree<Vec3> = KdTree::build(Vec::new());
    empty.knn(Vec3::ZERO, 10, f32::INFINITY, &mut out);
    assert!(out.is_empty());
    empty.within_radius(Vec3::ZERO, 1e9, &mut out);
    assert!(out.is_empty());

    let one = KdTree::build(vec![Vec3::ONE]);
    one.knn(Vec3::ZERO, 10, f32::INFINITY, &mut out);
    assert_eq!(out, vec![Neighbor { index: 0, dist2: 3.0 }]);
    one.knn(Vec3::ZERO, 10, 1.0, &mut out);
    assert!(out.is_empty());
    one.knn(Vec3::ZERO, 0, f32::INFINITY, &mut out);
    assert!(out.is_empty());
    one.knn(Vec3::ZERO, 1, f32::NAN, &mut out);
    assert!(out.is_empty());
}

#[test]
fn ten_thousand_identical_points() {
    let p = Vec3::new(0.5, -0.25, 2.0);
    let tree = KdTree::build(vec![p; 10_000]);
    let mut out = Vec::new();
    for q in [p, p + Vec3::new(0.1, 0.2, -0.3)] {
        tree.knn(q, 50, f32::INFINITY, &mut out);
        assert_eq!(out.len(), 50);
        assert!(out.iter().all(|n| n.dist2 == (p - q).length_squared()));
        tree.within_radius(q, 1.0, &mut out);
        assert_eq!(out.len(), 10_000);
    }
    tree.within_radius(p + Vec3::X, 0.5, &mut out);
    assert!(out.is_empty());
}

/// Position reads per item and tree level that a build may take: one bounds pass and one median
/// selection per level read each position about 1.3 times on the mostly-duplicates set below
/// (26 reads per point over its 20 levels); a selection that went quadratic on duplicates would
/// read millions of times more.
const BUILD_READS_PER_LEVEL: usize = 4;

/// A point that counts how often the tree reads its position (the tree's unit of work: every
/// bounds pass, median selection and query reads positions), in a counter of its own test.
#[derive(Clone, Copy)]
struct Counted<'a> {
    p: Vec3,
    reads: &'a AtomicUsize,
}

impl KdPoint for Counted<'_> {
    fn position(&self) -> Vec3 {
        self.reads.fetch_add(1, Ordering::Relaxed);
        self.p
    }
}

/// `knn` through `knn_with` and the Euclidean metric, counting the items it examines.
fn counted_knn<T: KdPoint>(tree: &KdTree<T>, q: Vec3, k: usize, out: &mut Vec<Neighbor>) -> usize {
    let examined = Cell::new(0usize);
    tree.knn_with(
        q,
        k,
        f32::INFINITY,
        |d: Vec3| {
            examined.set(examined.get() + 1);
            d.length_squared()
        },
        out,
    );
    examined.get()
}

/// A million identical points must build in linear time and answer k-NN in O(k), not O(n):
/// the build reads each position a bounded number of times and a query examines O(k) items.
#[test]
fn million_identical_points_build_and_query_in_bounded_work() {
    let n = 1_000_000;
    let p = Vec3::new(0.25, 0.5, 0.75);
    let reads = AtomicUsize::new(0);
    let tree = KdTree::build(vec![Counted { p, reads: &reads }; n]);
    let build_reads = reads.load(Ordering::Relaxed);
    assert!(build_reads <= 2 * n, "the build read {build_reads} positions for {n} points");
    let mut out = Vec::with_capacity(100);
    let mut examined = 0;
    for i in 0..10_000 {
        let q = p + Vec3::new(i as f32 * 1e-4, 0.1, -0.05);
        examined = examined.max(counted_knn(&tree, q, 100, &mut out));
        assert_eq!(out.len(), 100);
    }
    assert!(examined <= 2 * 100, "a 100-NN query examined {examined} of {n} items");
}

/// Mostly duplicates with some spread: the median selection must not go quadratic either,
/// and queries stay far below a linear scan.
#[test]
fn million_points_mostly_duplicates() {
    let mut pts = vec![Vec3::new(1.0, 1.0, 0.0); 900_000];
    pts.extend((0..100_000).map(|i| Vec3::new((i % 317) as f32 * 0.01, (i % 101) as f32 * 0.02, 0.0)));
    let n = pts.len();
    let reads = AtomicUsize::new(0);
    let counted: Vec<Counted> = pts.iter().map(|&p| Counted { p, reads: &reads }).collect();
    let tree = KdTree::build(counted);
    let build_reads = reads.load(Ordering::Relaxed);
    let log_n = (n as f64).log2().ceil() as usize;
    assert!(build_reads <= BUILD_READS_PER_LEVEL * n * log_n, "the build read {build_reads} positions");
    let mut out = Vec::new();
    let mut examined = 0;
    for i in 0..1000 {
        let q = Vec3::new((i % 37) as f32 * 0.1, (i % 13) as f32 * 0.2, 0.01);
        examined = examined.max(counted_knn(&tree, q, 50, &mut out));
        assert_eq!(out.len(), 50);
    }
    assert!(examined <= n / 100, "a 50-NN query examined {examined} of {n} items");
    // Spot-check one query against a scan.
    let q = Vec3::new(0.9, 1.1, 0.0);
    tree.knn(q, 50, f32::INFINITY, &mut out);
    let mut got: Vec<f32> = out.iter().map(|n| n.dist2).collect();
    got.sort_by(f32::total_cmp);
    assert_eq!(got, scan_knn(&pts, q, 50, f32::INFINITY, euclid));
}

/// A guess holding many times `k` items (the search cuts what it found to the `k` nearest every
/// `4k`, narrowing as it goes) finds what the linear scan finds.
#[test]
fn a_guess_far_too_wide_still_finds_the_nearest() {
    let pts: Vec<Vec3> = (0..6000)
        .map(|i| Vec3::new((i % 20) as f32, ((i / 20) % 20) as f32, (i / 400) as f32 * 0.7))
        .collect();
    let tree = KdTree::build(pts.clone());
    let mut out = Vec::new();
    for (k, p) in [(1, Vec3::splat(3.3)), (10, Vec3::new(10.2, 9.7, 4.1)), (64, Vec3::new(-2.0, 5.0, 1.0))] {
        tree.knn_with_guess(p, k, 1e3, 1e5, euclid, &mut out);
        assert!(
            check_knn(&tree, &out, &scan_knn(&pts, p, k, 1e3, euclid), p, euclid).is_ok(),
            "k {k} at {p}"
        );
    }
}

/// A query far from a dense cluster (the room about a closed lamp, every photon inside it)
/// examines a few items, not the cluster: subtrees are skipped by the distance to their cell,
/// not to their last splitting plane alone, which from far off lies nearer than every item
/// (the query's offset along one axis is less than its distance). With the plane alone, a
/// query of this test examined most of the 200 000 items.
#[test]
fn a_query_far_from_a_dense_cluster_examines_few_items() {
    let mut rng = 0x2545_F491_4F6C_DD1Du64;
    let mut unit = move || {
        rng ^= rng << 13;
        rng ^= rng >> 7;
        rng ^= rng << 17;
        (rng >> 40) as f32 / (1u64 << 24) as f32
    };
    // A 5 cm cube of points at (0.3, 0.5, 0.3), queries about half a metre off on every side.
    let pts: Vec<Vec3> =
        (0..200_000).map(|_| Vec3::new(0.3, 0.5, 0.3) + 0.05 * Vec3::new(unit(), unit(), unit())).collect();
    let tree = KdTree::build(pts);
    let mut out = Vec::new();
    let mut worst = 0;
    for i in 0..200 {
        let dir = Vec3::new(unit() - 0.5, unit() - 0.5, unit() - 0.5).normalize_or(Vec3::X);
        let q = Vec3::new(0.325, 0.525, 0.325) + (0.3 + 0.01 * i as f32) * dir;
        worst = worst.max(counted_knn(&tree, q, 8, &mut out));
        assert_eq!(out.len(), 8);
    }
    assert!(worst <= 2_000, "an 8-NN query from afar examined {worst} of 200 000 items");
}
