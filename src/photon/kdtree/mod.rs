//! A generic, balanced, implicit (pointer-free) point kd-tree for k-nearest-neighbour and
//! fixed-radius queries in 3-D, in the style of pbrt-v2's `KdTree` and Mitsuba 0.6's
//! `PointKDTree`. It knows nothing about photons: anything that implements [`KdPoint`] can be
//! stored.
//!
//! # Algorithm
//!
//! * **Structure.** The kd-tree of Bentley ("Multidimensional binary search trees used for
//!   associative searching", CACM 18(9), 1975), balanced by median splits as in Jensen's photon
//!   map ("Realistic Image Synthesis Using Photon Mapping", 2001, ch. 6). The tree is stored
//!   *implicitly* in the item array itself using the median-in-place layout: the subtree over a
//!   slice `items[lo..hi]` has its split item at `mid = lo + (hi - lo) / 2`, its left subtree is
//!   `items[lo..mid]` and its right subtree is `items[mid + 1..hi]`. No child pointers and no
//!   split values are stored; every subtree is a contiguous slice, which keeps the bottom of a
//!   query (where most of the time goes) cache-friendly.
//! * **Leaf buckets.** Slices of at most [`LEAF_SIZE`] items are not ordered further; queries scan
//!   them linearly. This saves the bottom levels of the build and most of the branchy traversal.
//! * **Split codes.** Only internal nodes carry a split code (2 bits: axis 0/1/2, or 3 =
//!   "every item of this subtree is at the same position"). Codes are packed four per byte and
//!   indexed by the node's *heap number* (root 0, children `2i + 1` and `2i + 2`), which is
//!   tracked during traversal. Since median splits keep the tree balanced, the internal nodes
//!   form an almost complete binary tree, so the code array holds about `2n / LEAF_SIZE` nodes,
//!   i.e. well under 0.1 byte per point (about 32 KiB for a million points, so it stays in cache).
//! * **Split axis** is the largest extent of the subtree's *tight* bounding box (recomputed for
//!   both children after each split; one linear pass per level, like the median selection).
//!   A zero-extent box marks the subtree as degenerate (code 3); it is not subdivided further and
//!   queries treat it as one point with a multiplicity. This is what keeps huge piles of
//!   duplicate points (photons hitting the exact same spot, or a test with a million identical
//!   points) at O(n) build and O(k) k-NN cost instead of degrading.
//! * **Build** uses `select_nth_unstable_by` (introselect, O(n) per level, robust to duplicates)
//!   and forks both halves with `rayon::join` while they are large, so the build is O(n log n)
//!   work with O(n) span. (Wald & Havran 2006, "On building fast kd-trees for ray tracing, and on
//!   doing that in O(N log N)", motivates the O(n log n) target; their SAH sweep is not needed for
//!   points, where the median split is the right answer for k-NN.)
//! * **Queries** are iterative with a small explicit stack (fixed array, depth ≤ 64), use squared
//!   distances only, test the per-node plane distance before pushing the far child, and re-check
//!   it against the (possibly shrunk) radius when popping. k-NN puts what it finds in the
//!   caller's output `Vec` as it comes, and each time that holds `4k` items cuts it to the `k`
//!   nearest by selection and shrinks the search radius to the `k`-th: a bounded max-heap, the
//!   textbook way, spent most of a gather's time on its unpredictable branches (a third of
//!   the irradiance precompute went away without it). No query allocates, once the caller's
//!   buffer has grown to `4k` (or to the number of results for radius queries).
//!
//! # Custom metrics (flattened gather)
//!
//! [`KdTree::knn_with`] and [`KdTree::for_each_within_with`] take a squared "distance" function
//! of the offset `item - query`. Pruning compares the squared Euclidean distance from the query
//! to a subtree's cell (the box its splitting planes cut out) against the current search
//! radius. That is only correct if for every offset `d`: `metric(d) ≥ |d|²` as
//! `Vec3::length_squared` computes it; **a metric that is never smaller than the squared
//! Euclidean distance** (computed as `length_squared`, or added to it) satisfies this. The photon-gather metric of
//! [`flattened_metric`], `|d|² + (s - 1)(n·d)²` with `s ≥ 1`, is such a metric: it stretches
//! distances along the surface normal `n`, which flattens the search region into a disc lying in
//! the surface (Jensen 2001, §7.2 uses the same idea to avoid collecting photons from nearby
//! surfaces). A metric that shrinks distances (e.g. `s < 1`) would silently miss neighbours.
//!
//! Positions must be finite (NaN or infinite coordinates give unspecified query results).

mod query;

use std::sync::atomic::{AtomicU8, Ordering};

use glam::Vec3;
use rayon::prelude::*;

use crate::geometry::{longest_axis, Aabb};

pub use query::flattened_metric;

/// Subtrees of at most this many items are leaf buckets: not subdivided, scanned linearly.
pub const LEAF_SIZE: usize = 8;

/// Split code of a subtree whose items all sit at the same position.
const CODE_DEGENERATE: u8 = 3;

/// Slices longer than this are split with `rayon::join` (both the bounds passes and the
/// recursion).
const PAR_THRESHOLD: usize = 16 * 1024;

/// Bounding-box passes over slices longer than this are themselves parallel.
const PAR_BOUNDS_THRESHOLD: usize = 256 * 1024;

/// Something with a position in 3-D space that a [`KdTree`] can index.
pub trait KdPoint {
    /// The point's position. Called often during build and queries: keep it cheap.
    fn position(&self) -> Vec3;
}

impl KdPoint for Vec3 {
    #[inline(always)]
    fn position(&self) -> Vec3 {
        *self
    }
}

impl KdPoint for [f32; 3] {
    #[inline(always)]
    fn position(&self) -> Vec3 {
        Vec3::from_array(*self)
    }
}

/// One query result: the index of an item in [`KdTree::items`] and its squared distance (or
/// squared metric value, for the `_with` queries) from the query point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Neighbor {
    /// Index into [`KdTree::items`] (tree order, not the order given to [`KdTree::build`]).
    pub index: u32,
    /// Squared distance from the query point.
    pub dist2: f32,
}

/// A balanced point kd-tree stored implicitly in its item array (see the [module docs](self)).
#[derive(Clone, Debug)]
pub struct KdTree<T> {
    /// The items, reordered into the median-in-place tree layout.
    items: Vec<T>,
    /// 2-bit split codes of the internal nodes, heap-numbered, four per byte.
    codes: Vec<u8>,
    /// Tight bounds of all items.
    bounds: Aabb,
}

impl<T> Default for KdTree<T> {
    fn default() -> Self {
        KdTree { items: Vec::new(), codes: Vec::new(), bounds: Aabb::EMPTY }
    }
}

impl<T: KdPoint + Send + Sync> KdTree<T> {
    /// Builds a balanced tree over `items` (reordering them), in parallel on the current rayon
    /// pool.
    ///
    /// # Panics
    /// If there are more than `u32::MAX` items.
    pub fn build(mut items: Vec<T>) -> Self {
        let n = items.len();
        assert!(n <= u32::MAX as usize, "KdTree holds at most u32::MAX items");
        let levels = internal_levels(n);
        let nodes = (1usize << levels) - 1;
        let codes: Vec<AtomicU8> = (0..nodes.div_ceil(4)).map(|_| AtomicU8::new(0)).collect();
        let bounds = bounds_of(&items);
        build_rec(&mut items, 0, bounds, &codes);
        let codes = codes.into_iter().map(AtomicU8::into_inner).collect();
        KdTree { items, codes, bounds }
    }
}

impl<T> KdTree<T> {
    /// Number of items.
    #[inline]
    pub fn len(&self) -> usize {
        self.items.len()
    }

    /// Whether the tree holds no items.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.items.is_empty()
    }

    /// The items in tree order; [`Neighbor::index`] indexes this slice.
    #[inline]
    pub fn items(&self) -> &[T] {
        &self.items
    }

    /// The item with tree index `index` (as found in a [`Neighbor`]).
    #[inline]
    pub fn get(&self, index: u32) -> &T {
        &self.items[index as usize]
    }

    /// Tight bounding box of all items ([`Aabb::EMPTY`] for an empty tree).
    #[inline]
    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// Memory held by the tree in bytes: the item array (by capacity), the split codes and the
    /// struct itself. The tree's own overhead beyond the items is [`KdTree::overhead_bytes`].
    pub fn bytes(&self) -> usize {
        std::mem::size_of::<Self>() + self.items.capacity() * std::mem::size_of::<T>() + self.codes.capacity()
    }

    /// Memory the tree needs on top of the items themselves (split codes and the struct).
    pub fn overhead_bytes(&self) -> usize {
        std::mem::size_of::<Self>() + self.codes.capacity()
    }

    /// Split code of internal node `id` (heap numbering).
    #[inline(always)]
    fn code(&self, id: usize) -> u8 {
        (self.codes[id >> 2] >> ((id & 3) * 2)) & 3
    }
}

/// Number of levels of internal nodes for `n` items. The left child of a slice of length `m` has
/// `m / 2` items and the right one `m - m / 2 - 1 ≤ m / 2`, so the left spine is the deepest.
fn internal_levels(n: usize) -> u32 {
    let mut size = n;
    let mut levels = 0;
    while size > LEAF_SIZE {
        size /= 2;
        levels += 1;
    }
    levels
}

#[inline]
fn set_code(codes: &[AtomicU8], id: usize, code: u8) {
    codes[id >> 2].fetch_or(code << ((id & 3) * 2), Ordering::Relaxed);
}

fn bounds_seq<T: KdPoint>(items: &[T]) -> Aabb {
    let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    for it in items {
        let p = it.position();
        lo = lo.min(p);
        hi = hi.max(p);
    }
    Aabb { min: lo, max: hi }
}

fn bounds_of<T: KdPoint + Sync>(items: &[T]) -> Aabb {
    if items.len() > PAR_BOUNDS_THRESHOLD {
        items.par_chunks(PAR_BOUNDS_THRESHOLD / 4).map(bounds_seq).reduce(|| Aabb::EMPTY, Aabb::union)
    } else {
        bounds_seq(items)
    }
}

fn build_rec<T: KdPoint + Send + Sync>(items: &mut [T], id: usize, bounds: Aabb, codes: &[AtomicU8]) {
    let n = items.len();
    if n <= LEAF_SIZE {
        return;
    }
    let e = bounds.extent();
    if e.x <= 0.0 && e.y <= 0.0 && e.z <= 0.0 {
        // All items coincide: nothing to order. Queries treat the slice as one point.
        set_code(codes, id, CODE_DEGENERATE);
        return;
    }
    let axis = longest_axis(e);
    set_code(codes, id, axis as u8);
    let mid = n / 2;
    items.select_nth_unstable_by(mid, |a, b| a.position()[axis].total_cmp(&b.position()[axis]));
    let (left, rest) = items.split_at_mut(mid);
    let right = &mut rest[1..];
    let child_bounds = |s: &[T]| if s.len() > LEAF_SIZE { bounds_of(s) } else { Aabb::EMPTY };
    if n > PAR_THRESHOLD {
        let (lb, rb) = rayon::join(|| child_bounds(left), || child_bounds(right));
        rayon::join(|| build_rec(left, 2 * id + 1, lb, codes), || build_rec(right, 2 * id + 2, rb, codes));
    } else {
        let (lb, rb) = (child_bounds(left), child_bounds(right));
        build_rec(left, 2 * id + 1, lb, codes);
        build_rec(right, 2 * id + 2, rb, codes);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Checks the median-in-place invariant: every item left of a split is ≤ the split value on
    /// the split axis, every item right of it is ≥.
    fn check<T: KdPoint>(t: &KdTree<T>, lo: usize, hi: usize, id: usize) {
        if hi - lo <= LEAF_SIZE {
            return;
        }
        let mid = lo + (hi - lo) / 2;
        let c = t.code(id);
        let s = t.items[mid].position();
        if c == CODE_DEGENERATE {
            assert!(t.items[lo..hi].iter().all(|p| p.position() == s));
            return;
        }
        let a = c as usize;
        assert!(t.items[lo..mid].iter().all(|p| p.position()[a] <= s[a]));
        assert!(t.items[mid + 1..hi].iter().all(|p| p.position()[a] >= s[a]));
        check(t, lo, mid, 2 * id + 1);
        check(t, mid + 1, hi, 2 * id + 2);
    }

    #[test]
    fn layout_invariant_holds() {
        for n in [0usize, 1, 8, 9, 17, 100, 1000, 40_000] {
            let pts: Vec<Vec3> = (0..n)
                .map(|i| {
                    let f = i as f32;
                    Vec3::new((f * 0.618).fract(), (f * 0.377).fract(), ((i % 7) as f32) * 0.1)
                })
                .collect();
            let t = KdTree::build(pts);
            assert_eq!(t.len(), n);
            check(&t, 0, n, 0);
        }
    }

    #[test]
    fn overhead_is_small() {
        let pts: Vec<Vec3> = (0..1 << 20).map(|i| Vec3::new(i as f32, (i % 1000) as f32, 0.0)).collect();
        let t = KdTree::build(pts);
        let per_point = t.overhead_bytes() as f64 / t.len() as f64;
        assert!(per_point < 0.1, "{per_point}");
    }
}
