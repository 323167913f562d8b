//! k-nearest-neighbour and fixed-radius queries on [`KdTree`].

use glam::Vec3;

use super::{KdPoint, KdTree, Neighbor, CODE_DEGENERATE, LEAF_SIZE};

/// Capacity of the traversal stack. Each internal level pushes at most one frame and a tree of
/// `u32::MAX` items has fewer than 32 internal levels.
const STACK_SIZE: usize = 64;

/// A deferred far subtree: the slice `lo..hi`, its heap number, the query's distance from its
/// cell along each axis (0 where the query lies within the cell's extent) and their squared sum
/// `d2`, a lower bound on the metric for every item in it.
#[derive(Clone, Copy, Default)]
struct Frame {
    lo: u32,
    hi: u32,
    id: u32,
    d2: f32,
    off: [f32; 3],
}

/// The photon-gather metric: `|d|² + (stretch - 1) (n·d)²` for the offset `d`, with the unit
/// surface normal `normal`. With `stretch ≥ 1` it is never below the squared Euclidean distance,
/// so it is valid for [`KdTree::knn_with`]; the search region `metric ≤ r²` is an ellipsoid
/// squashed by `1/√stretch` along the normal (a disc-like region in the surface).
///
/// # Panics
/// In debug builds, if `stretch < 1`.
#[inline]
pub fn flattened_metric(normal: Vec3, stretch: f32) -> impl Fn(Vec3) -> f32 + Copy {
    debug_assert!(stretch >= 1.0, "a flattened metric needs stretch >= 1 to keep pruning exact");
    let s1 = stretch - 1.0;
    move |d: Vec3| {
        let t = normal.dot(d);
        d.length_squared() + s1 * t * t
    }
}

/// The smallest `f32` strictly greater than `x` for finite non-negative `x` (so that `d2 < limit`
/// means `d2 ≤ x`); infinity stays infinity.
#[inline]
fn inclusive_limit(x: f32) -> f32 {
    if x.is_finite() {
        f32::from_bits(x.to_bits() + 1)
    } else {
        x
    }
}

/// Inserts into the bounded max-heap `heap` (capacity `k`, largest `dist2` at index 0), which is
/// only called with `d2 < *limit`, and keeps `*limit` = the heap's top once it is full.
#[inline(always)]
fn heap_insert(heap: &mut Vec<Neighbor>, k: usize, index: usize, d2: f32, limit: &mut f32) {
    let item = Neighbor { index: index as u32, dist2: d2 };
    if heap.len() < k {
        // Sift up.
        let mut i = heap.len();
        heap.push(item);
        while i > 0 {
            let parent = (i - 1) / 2;
            if heap[parent].dist2 >= d2 {
                break;
            }
            heap[i] = heap[parent];
            i = parent;
        }
        heap[i] = item;
        if heap.len() == k {
            *limit = heap[0].dist2;
        }
    } else {
        // Replace the top, sift down.
        let n = heap.len();
        let mut i = 0;
        loop {
            let l = 2 * i + 1;
            if l >= n {
                break;
            }
            let r = l + 1;
            let c = if r < n && heap[r].dist2 > heap[l].dist2 { r } else { l };
            if heap[c].dist2 <= d2 {
                break;
            }
            heap[i] = heap[c];
            i = c;
        }
        heap[i] = item;
        *limit = heap[0].dist2;
    }
}

impl<T: KdPoint> KdTree<T> {
    /// The (up to) `k` items nearest to `p` with distance at most `max_radius`.
    ///
    /// `out` is cleared and receives the result in an unspecified order except that `out[0]` is
    /// the farthest (the radius of the gathered disc, as the density estimate needs). Ties at
    /// the k-th distance are broken arbitrarily. Nothing is allocated once `out` has capacity
    /// `4k` (found items are cut to the `k` nearest by selection each time `4k` are held).
    #[inline]
    pub fn knn(&self, p: Vec3, k: usize, max_radius: f32, out: &mut Vec<Neighbor>) {
        self.knn_with(p, k, max_radius, |d: Vec3| d.length_squared(), out)
    }

    /// [`KdTree::knn`] with a custom squared metric `dist2(item - p)`; `max_radius²` bounds the
    /// metric and [`Neighbor::dist2`] holds metric values.
    ///
    /// **Correctness requirement:** `dist2(d) ≥ |d|²` (as `Vec3::length_squared` computes it),
    /// as [`flattened_metric`] with `stretch ≥ 1` is; otherwise results may miss items that a
    /// linear scan would find.
    #[inline]
    pub fn knn_with<F: Fn(Vec3) -> f32>(
        &self,
        p: Vec3,
        k: usize,
        max_radius: f32,
        dist2: F,
        out: &mut Vec<Neighbor>,
    ) {
        out.clear();
        if k == 0 || max_radius.is_nan() || max_radius < 0.0 {
            return;
        }
        let limit = inclusive_limit(max_radius * max_radius);
        self.nearest_by_selection(p, k, limit, dist2, out);
    }

    /// [`KdTree::knn_with`], searching first within the squared metric `guess` only (when it
    /// is below `max_radius²`): if `k` items lie strictly inside it, they are the `k` nearest
    /// and the search never looked farther; otherwise it searches again out to `max_radius`. A
    /// good guess (the radius of a nearby query's result, with a margin) skips the first,
    /// wide part of a k-NN search, where the heap holds items that later ones evict. The items
    /// found are the same as [`KdTree::knn_with`]'s (ties at the `k`-th distance aside), in
    /// another order but for the farthest, first in both.
    #[inline]
    pub fn knn_with_guess<F: Fn(Vec3) -> f32 + Copy>(
        &self,
        p: Vec3,
        k: usize,
        max_radius: f32,
        guess: f32,
        dist2: F,
        out: &mut Vec<Neighbor>,
    ) {
        out.clear();
        if k == 0 || max_radius.is_nan() || max_radius < 0.0 {
            return;
        }
        let full = inclusive_limit(max_radius * max_radius);
        if guess > 0.0 && guess < full {
            // The k nearest within the guess: if there are k, they are the k nearest.
            self.nearest_by_selection(p, k, guess, dist2, out);
            if out.len() == k {
                return;
            }
            out.clear();
        }
        self.nearest_by_selection(p, k, full, dist2, out);
    }

    /// The (up to) `k` items whose metric is below `limit`, nearest first, into `out` (cleared),
    /// the farthest of them at `out[0]`, the rest in no order. Items found go into `out` as they
    /// come; every time it holds `4k`, it is cut by selection to its `k` nearest and the search
    /// narrowed to the `k`-th (a max-heap updated at every item, the textbook way, spent most
    /// of a gather's time on its unpredictable branches).
    #[inline]
    fn nearest_by_selection<F: Fn(Vec3) -> f32>(
        &self,
        p: Vec3,
        k: usize,
        limit: f32,
        dist2: F,
        out: &mut Vec<Neighbor>,
    ) {
        out.clear();
        let by_distance = |a: &Neighbor, b: &Neighbor| a.dist2.total_cmp(&b.dist2);
        self.descend(p, limit, dist2, |index, d2, limit| {
            out.push(Neighbor { index: index as u32, dist2: d2 });
            if out.len() == 4 * k {
                out.select_nth_unstable_by(k - 1, by_distance);
                out.truncate(k);
                *limit = out[k - 1].dist2;
            }
        });
        if out.len() > k {
            out.select_nth_unstable_by(k - 1, by_distance);
            out.truncate(k);
        }
        let farthest = (0..out.len()).max_by(|&a, &b| by_distance(&out[a], &out[b]));
        if let Some(f) = farthest {
            out.swap(0, f);
        }
    }

    /// The nearest item that `accept` takes among the `k` items nearest to `p` within
    /// `max_radius`: what [`KdTree::knn`] followed by a scan of its results for the nearest
    /// accepted one returns (but for ties at equal distances), at about the cost of a nearest-
    /// neighbour search where most items are accepted: the search radius shrinks to the first
    /// accepted item found. `hint`, the index of an item likely to be near `p` (the answer to
    /// the previous, nearby query), starts the search at its distance if `accept` takes it:
    /// the answer is the same, found sooner. `rejected` is scratch space (it holds the nearest
    /// rejected items).
    #[inline]
    pub fn nearest_among<A: Fn(&T) -> bool>(
        &self,
        p: Vec3,
        k: usize,
        max_radius: f32,
        accept: A,
        hint: Option<u32>,
        rejected: &mut Vec<Neighbor>,
    ) -> Option<Neighbor> {
        rejected.clear();
        if k == 0 || max_radius.is_nan() || max_radius < 0.0 {
            return None;
        }
        let items = &self.items[..];
        let mut limit = inclusive_limit(max_radius * max_radius);
        let mut best: Option<Neighbor> = None;
        if let Some(h) = hint.filter(|&h| (h as usize) < items.len() && accept(&items[h as usize])) {
            let d2 = (items[h as usize].position() - p).length_squared();
            if d2 < limit {
                // Items at the hint's own distance are still visited (ties, as in `knn`).
                best = Some(Neighbor { index: h, dist2: d2 });
                limit = inclusive_limit(d2);
            }
        }
        self.descend(
            p,
            limit,
            |d: Vec3| d.length_squared(),
            |index, d2, limit| {
                if accept(&items[index]) {
                    // `d2 < limit` and the limit never exceeds the best: a nearer item.
                    best = Some(Neighbor { index: index as u32, dist2: d2 });
                    *limit = d2;
                } else {
                    // Once `k` rejected items are nearer than some distance, nothing beyond it is
                    // among the `k` nearest.
                    let mut bound = *limit;
                    heap_insert(rejected, k, index, d2, &mut bound);
                    if rejected.len() == k {
                        *limit = limit.min(bound);
                    }
                }
            },
        );
        // An item accepted early may have been outnumbered by `k` rejected ones found later.
        let outnumbered = |b: &Neighbor| rejected.len() == k && rejected[0].dist2 < b.dist2;
        best.filter(|b| !outnumbered(b))
    }

    /// All items within distance `radius` of `p` (inclusive), in unspecified order; `out` is
    /// cleared first.
    pub fn within_radius(&self, p: Vec3, radius: f32, out: &mut Vec<Neighbor>) {
        out.clear();
        self.for_each_within(p, radius, |index, dist2| out.push(Neighbor { index, dist2 }));
    }

    /// Calls `f(index, dist2)` for every item within distance `radius` of `p` (inclusive).
    #[inline]
    pub fn for_each_within<G: FnMut(u32, f32)>(&self, p: Vec3, radius: f32, f: G) {
        self.for_each_within_with(p, radius, |d: Vec3| d.length_squared(), f)
    }

    /// [`KdTree::for_each_within`] with a custom squared metric of `item - p`; the same
    /// requirement as for [`KdTree::knn_with`] applies (`dist2(d) ≥ |d|²`).
    #[inline]
    pub fn for_each_within_with<F: Fn(Vec3) -> f32, G: FnMut(u32, f32)>(
        &self,
        p: Vec3,
        radius: f32,
        dist2: F,
        f: G,
    ) {
        if radius.is_nan() || radius < 0.0 {
            return;
        }
        self.for_each_below_with(p, inclusive_limit(radius * radius), dist2, f)
    }

    /// Calls `f(index, dist2)` for every item whose metric `dist2(item - p)` is strictly below
    /// `limit` (a squared radius), in unspecified order; the requirement of
    /// [`KdTree::knn_with`] on the metric applies. The query of an estimate whose disc is drawn
    /// through a photon found earlier (its squared distance as `limit`), which must leave that
    /// photon out: [`KdTree::for_each_within_with`] at `√limit` would count it whenever the
    /// square root and its square round back to `limit` or above.
    pub fn for_each_below_with<F: Fn(Vec3) -> f32, G: FnMut(u32, f32)>(
        &self,
        p: Vec3,
        limit: f32,
        dist2: F,
        mut f: G,
    ) {
        self.for_each_below_until(p, limit, dist2, |index, d2| {
            f(index, d2);
            false
        });
    }

    /// [`KdTree::for_each_below_with`] until `f` returns `true`: then the traversal stops.
    pub fn for_each_below_until<F: Fn(Vec3) -> f32, G: FnMut(u32, f32) -> bool>(
        &self,
        p: Vec3,
        limit: f32,
        dist2: F,
        mut f: G,
    ) {
        if limit.is_nan() || limit <= 0.0 {
            return;
        }
        // A limit of 0 leaves no item and no subtree below it.
        self.descend(p, limit, dist2, |index, d2, limit| {
            if f(index as u32, d2) {
                *limit = 0.0;
            }
        });
    }

    /// The traversal every query shares: calls `visit(index, d2, &mut limit)` for every item
    /// whose metric `d2 = dist2(item - p)` is strictly below the running `limit`, nearer
    /// subtrees first; `visit` may shrink the limit (a k-NN heap that filled up), and subtrees
    /// the shrunk limit no longer reaches are skipped. The requirement of
    /// [`KdTree::knn_with`] on the metric applies.
    ///
    /// A subtree is skipped by the squared distance from `p` to its cell, the box its splitting
    /// planes and the tree's bounds cut out, kept axis by axis as the walk crosses planes
    /// (Arya and Mount's incremental distance): the distance to the last plane crossed alone
    /// (pbrt-v2's and Jensen's test) knows nothing of the planes crossed before it, and a query
    /// far from a dense cluster of items (the room outside a closed lamp, every photon inside
    /// it) then visited almost the whole tree. The items visited, and in what order, are the
    /// same either way: a skipped subtree holds none below the limit.
    #[inline(always)]
    fn descend<F: Fn(Vec3) -> f32, V: FnMut(usize, f32, &mut f32)>(
        &self,
        p: Vec3,
        mut limit: f32,
        dist2: F,
        mut visit: V,
    ) {
        let items = &self.items[..];
        if items.is_empty() {
            return;
        }
        let mut stack = [Frame::default(); STACK_SIZE];
        let mut sp = 0usize;
        let (mut lo, mut hi, mut id) = (0usize, items.len(), 0usize);
        // The query's distance from the current cell along each axis.
        let outside = (self.bounds.min - p).max(p - self.bounds.max).max(Vec3::ZERO);
        let mut off = outside.to_array();
        if !(outside.length_squared() < limit) {
            return;
        }
        'walk: loop {
            let n = hi - lo;
            if n <= LEAF_SIZE {
                for (i, it) in items[lo..hi].iter().enumerate() {
                    let d2 = dist2(it.position() - p);
                    if d2 < limit {
                        visit(lo + i, d2, &mut limit);
                    }
                }
            } else {
                let mid = lo + n / 2;
                let s = items[mid].position();
                let d2 = dist2(s - p);
                let code = self.code(id);
                if code == CODE_DEGENERATE {
                    // Every item of lo..hi is at `s`: one point with a multiplicity.
                    let mut i = lo;
                    while i < hi && d2 < limit {
                        visit(i, d2, &mut limit);
                        i += 1;
                    }
                } else {
                    if d2 < limit {
                        visit(mid, d2, &mut limit);
                    }
                    let a = code as usize;
                    let diff = p[a] - s[a];
                    let (l, r) = (2 * id + 1, 2 * id + 2);
                    let (near, far) = if diff < 0.0 {
                        ((lo, mid, l), (mid + 1, hi, r))
                    } else {
                        ((mid + 1, hi, r), (lo, mid, l))
                    };
                    // The far cell lies across the plane: along its axis the query is `|diff|`
                    // from it; the near cell keeps the distances of the one it is cut from.
                    // Summed afresh, in `length_squared`'s order: rounding is monotonic, so no
                    // item of the cell has a smaller `|item - p|²` as the metric computes it.
                    let mut far_off = off;
                    far_off[a] = diff.abs();
                    let far_rd = Vec3::from_array(far_off).length_squared();
                    if far_rd < limit {
                        stack[sp] = Frame {
                            lo: far.0 as u32,
                            hi: far.1 as u32,
                            id: far.2 as u32,
                            d2: far_rd,
                            off: far_off,
                        };
                        sp += 1;
                    }
                    (lo, hi, id) = near;
                    continue 'walk;
                }
            }
            // Pop the next far subtree that the (possibly shrunk) limit still reaches.
            loop {
                if sp == 0 {
                    return;
                }
                sp -= 1;
                let f = stack[sp];
                if f.d2 < limit {
                    (lo, hi, id, off) = (f.lo as usize, f.hi as usize, f.id as usize, f.off);
                    continue 'walk;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn heap_keeps_k_smallest() {
        let mut h = Vec::new();
        let mut limit = f32::INFINITY;
        let ds = [5.0, 1.0, 9.0, 3.0, 7.0, 2.0, 8.0, 0.5];
        for (i, &d) in ds.iter().enumerate() {
            if d < limit {
                heap_insert(&mut h, 3, i, d, &mut limit);
            }
        }
        let mut got: Vec<f32> = h.iter().map(|n| n.dist2).collect();
        assert_eq!(h[0].dist2, 2.0);
        got.sort_by(f32::total_cmp);
        assert_eq!(got, vec![0.5, 1.0, 2.0]);
        assert_eq!(limit, 2.0);
    }

    /// `nearest_among` answers what `knn` and a scan of its results for the nearest accepted
    /// item answer, with and without hints (good, bad and rejected ones), on clustered points.
    #[test]
    fn nearest_among_matches_knn_and_a_scan() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_pcg::Pcg32::seed_from_u64(7);
        let pts: Vec<Vec3> =
            (0..5000).map(|_| Vec3::new(rng.gen(), rng.gen::<f32>() * 0.1, rng.gen())).collect();
        let t = KdTree::build(pts);
        // Accept about two items in three, by position (so the same item always answers alike).
        let accept = |q: &Vec3| (q.x * 1000.0) as u32 % 3 != 0;
        let (mut out, mut rejected) = (Vec::new(), Vec::new());
        let mut last = None;
        let mut answered = 0;
        for i in 0..2000 {
            let p = Vec3::new(rng.gen(), rng.gen::<f32>() * 0.1, rng.gen());
            let (k, radius) = ([1, 2, 8][i % 3], [0.02, 0.05, 1.0][i % 3]);
            t.knn(p, k, radius, &mut out);
            let expected = out
                .iter()
                .filter(|nb| accept(t.get(nb.index)))
                .min_by(|a, b| a.dist2.total_cmp(&b.dist2))
                .map(|nb| nb.index);
            let hints = [None, last, Some(rng.gen_range(0..5000)), Some(u32::MAX)];
            for hint in hints {
                let got = t.nearest_among(p, k, radius, accept, hint, &mut rejected);
                assert_eq!(got.map(|nb| nb.index), expected, "query {i}, hint {hint:?}");
            }
            last = expected.or(last);
            answered += expected.is_some() as u32;
        }
        assert!(answered > 500 && answered < 1990, "{answered}");
    }

    #[test]
    fn inclusive_radius() {
        let t = KdTree::build(vec![Vec3::new(1.0, 0.0, 0.0), Vec3::ZERO]);
        let mut out = Vec::new();
        t.knn(Vec3::ZERO, 5, 1.0, &mut out);
        assert_eq!(out.len(), 2);
        t.within_radius(Vec3::ZERO, 1.0, &mut out);
        assert_eq!(out.len(), 2);
        t.within_radius(Vec3::ZERO, 0.999, &mut out);
        assert_eq!(out.len(), 1);
    }

    /// The strict query leaves out an item exactly at the limit, as a disc drawn through the
    /// k-th nearest photon must, on small trees (a leaf) and large ones (internal nodes).
    #[test]
    fn below_is_strict() {
        for n in [3usize, 1000] {
            let pts: Vec<Vec3> = (0..n).map(|i| Vec3::new(0.01 * i as f32, 0.0, 0.0)).collect();
            let t = KdTree::build(pts.clone());
            let metric = |d: Vec3| d.length_squared();
            for &limit_index in &[1usize, 2] {
                let limit = metric(pts[limit_index]);
                let (mut strict, mut inclusive) = (0, 0);
                t.for_each_below_with(Vec3::ZERO, limit, metric, |_, d2| {
                    assert!(d2 < limit);
                    strict += 1;
                });
                t.for_each_within_with(Vec3::ZERO, limit.sqrt(), metric, |_, _| inclusive += 1);
                assert_eq!(strict, limit_index, "n {n}");
                assert!(inclusive >= limit_index, "n {n}");
            }
        }
    }
}
