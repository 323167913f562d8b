//! Binned SAH construction (Wald, "On fast Construction of SAH-based Bounding Volume
//! Hierarchies", IEEE Symposium on Interactive Ray Tracing 2007).
//!
//! Every node bins its primitives' centroids into [`BINS`] equal slots along each axis of the
//! centroid bounds, sweeps the bins to evaluate the surface area heuristic at the `BINS - 1`
//! planes between them, and either splits at the cheapest plane or makes a leaf when that is
//! cheaper. Primitives whose centroids coincide (no plane separates them), and nodes deeper than
//! [`SAH_DEPTH`], are split at the median instead, which bounds the tree depth.
//!
//! Large subtrees are built in parallel with `rayon::join`, and the binning of very large nodes
//! (the top of the tree, where there is little subtree parallelism) is split into chunks.

use super::node::{leaf_ref, Node4};
use crate::geometry::longest_axis;
use glam::Vec3A;
use rayon::prelude::*;

/// Number of centroid bins per axis.
const BINS: usize = 32;
/// SAH cost of visiting a (binary) node, relative to one triangle test; tuned
/// on incoherent rays with the binary BVH (1.0: 0.7, 2.0: 0.9, 3.0: 1.2 M rays/s); with the 4-wide
/// BVH, 3, 4 and 5 measured within noise of each other (2.7-2.9 M rays/s).
const TRAVERSAL_COST: f32 = 3.0;
/// Leaves never hold more triangles than this (unless centroids coincide and the median split
/// also cannot separate them, which it always can).
pub const MAX_LEAF: usize = 8;
/// Below this depth the SAH decides; deeper nodes use median splits (depth stays below 64 + 32).
const SAH_DEPTH: u32 = 64;
/// Subtrees with more primitives than this are built on another rayon task.
const PARALLEL_SUBTREE: usize = 4096;
/// Nodes with more primitives than this are binned in parallel chunks.
const PARALLEL_BINNING: usize = 1 << 16;
const CHUNK: usize = 1 << 13;

/// A box with SIMD-friendly corners (the fourth lane is unused).
#[derive(Clone, Copy, Debug)]
pub struct Box3 {
    pub min: Vec3A,
    pub max: Vec3A,
}

impl Box3 {
    pub const EMPTY: Box3 = Box3 { min: Vec3A::splat(f32::INFINITY), max: Vec3A::splat(f32::NEG_INFINITY) };

    #[inline]
    fn union(self, o: Box3) -> Box3 {
        Box3 { min: self.min.min(o.min), max: self.max.max(o.max) }
    }

    #[inline]
    fn grow(self, p: Vec3A) -> Box3 {
        Box3 { min: self.min.min(p), max: self.max.max(p) }
    }

    /// Half the surface area (0 for empty or flat-in-two-axes boxes); only ratios matter.
    #[inline]
    fn half_area(&self) -> f32 {
        let e = (self.max - self.min).max(Vec3A::ZERO);
        e.x * e.y + e.y * e.z + e.z * e.x
    }

    pub fn to_aabb(self) -> crate::geometry::Aabb {
        crate::geometry::Aabb { min: self.min.into(), max: self.max.into() }
    }
}

/// A primitive during the build: its bounds and its index into the leaf-order input.
#[derive(Clone, Copy, Debug)]
pub struct PrimRef {
    pub bounds: Box3,
    pub id: u32,
}

impl PrimRef {
    /// Twice the centroid (the factor cancels in the binning).
    #[inline]
    fn centroid2(&self) -> Vec3A {
        self.bounds.min + self.bounds.max
    }
}

/// Per-axis bins: bounds and primitive counts.
#[derive(Clone, Copy)]
struct Bins {
    bounds: [[Box3; BINS]; 3],
    counts: [[u32; BINS]; 3],
}

impl Bins {
    fn new() -> Self {
        Bins { bounds: [[Box3::EMPTY; BINS]; 3], counts: [[0; BINS]; 3] }
    }

    fn merge(mut self, o: &Bins) -> Self {
        for (mine, theirs) in self.bounds.iter_mut().flatten().zip(o.bounds.iter().flatten()) {
            *mine = mine.union(*theirs);
        }
        for (mine, theirs) in self.counts.iter_mut().flatten().zip(o.counts.iter().flatten()) {
            *mine += theirs;
        }
        self
    }
}

/// Maps doubled centroids to bin indices along all three axes at once.
#[derive(Clone, Copy)]
struct Binner {
    origin: Vec3A,
    scale: Vec3A,
}

impl Binner {
    fn new(cbounds: &Box3) -> Self {
        let extent = cbounds.max - cbounds.min;
        // Slightly less than BINS so the maximum lands in the last bin, not one past it.
        let k = BINS as f32 * (1.0 - 1e-5);
        let scale = Vec3A::select(extent.cmpgt(Vec3A::ZERO), Vec3A::splat(k) / extent, Vec3A::ZERO);
        Binner { origin: cbounds.min, scale }
    }

    #[inline]
    fn bins(&self, c2: Vec3A) -> [usize; 3] {
        // `as usize` saturates (NaN becomes 0), and the min keeps the index in range.
        let f = ((c2 - self.origin) * self.scale).to_array();
        f.map(|x| (x as usize).min(BINS - 1))
    }

    fn bin(&self, prims: &[PrimRef]) -> Bins {
        let mut bins = Bins::new();
        for p in prims {
            let b = self.bins(p.centroid2());
            for ((bounds, counts), k) in bins.bounds.iter_mut().zip(&mut bins.counts).zip(b) {
                bounds[k] = bounds[k].union(p.bounds);
                counts[k] += 1;
            }
        }
        bins
    }
}

/// The bounds of the primitives and of their (doubled) centroids.
fn bounds_of(prims: &[PrimRef]) -> (Box3, Box3) {
    let seq = |ps: &[PrimRef]| {
        ps.iter().fold((Box3::EMPTY, Box3::EMPTY), |(b, c), p| (b.union(p.bounds), c.grow(p.centroid2())))
    };
    if prims.len() > PARALLEL_BINNING {
        prims
            .par_chunks(CHUNK)
            .map(seq)
            .reduce(|| (Box3::EMPTY, Box3::EMPTY), |(a, b), (c, d)| (a.union(c), b.union(d)))
    } else {
        seq(prims)
    }
}

/// The cheapest SAH plane: `(axis, last bin on the left, cost relative to the node's area)`.
fn best_split(prims: &[PrimRef], bounds: &Box3, cbounds: &Box3) -> Option<(usize, usize, f32, Binner)> {
    let binner = Binner::new(cbounds);
    let bins = if prims.len() > PARALLEL_BINNING {
        prims.par_chunks(CHUNK).map(|c| binner.bin(c)).reduce(Bins::new, |a, b| a.merge(&b))
    } else {
        binner.bin(prims)
    };
    let mut best: Option<(usize, usize, f32)> = None;
    for a in 0..3 {
        if binner.scale[a] == 0.0 {
            continue;
        }
        // Right-to-left sweep: area * count of everything right of each plane.
        let mut right_cost = [0.0f32; BINS];
        let (mut b, mut n) = (Box3::EMPTY, 0u32);
        for i in (1..BINS).rev() {
            b = b.union(bins.bounds[a][i]);
            n += bins.counts[a][i];
            right_cost[i - 1] = if n > 0 { b.half_area() * n as f32 } else { f32::INFINITY };
        }
        let (mut b, mut n) = (Box3::EMPTY, 0u32);
        for (i, rc) in right_cost.iter().enumerate().take(BINS - 1) {
            b = b.union(bins.bounds[a][i]);
            n += bins.counts[a][i];
            if n == 0 || !rc.is_finite() {
                continue;
            }
            let cost = b.half_area() * n as f32 + rc;
            if best.is_none_or(|(_, _, c)| cost < c) {
                best = Some((a, i, cost));
            }
        }
    }
    let area = bounds.half_area();
    best.map(|(a, i, cost)| {
        let rel = if area > 0.0 { cost / area } else { prims.len() as f32 };
        (a, i, rel, binner)
    })
}

/// Moves the primitives satisfying `left` to the front; returns how many there are.
fn partition(prims: &mut [PrimRef], left: impl Fn(&PrimRef) -> bool) -> usize {
    let mut i = 0;
    let mut j = prims.len();
    loop {
        while i < j && left(&prims[i]) {
            i += 1;
        }
        while i < j && !left(&prims[j - 1]) {
            j -= 1;
        }
        if i >= j {
            return i;
        }
        prims.swap(i, j - 1);
        i += 1;
        j -= 1;
    }
}

/// The build's intermediate tree, flattened afterwards into depth-first order.
enum BuildNode {
    Leaf { bounds: Box3, first: u32, count: u32 },
    Inner { bounds: Box3, kids: Box<(BuildNode, BuildNode)> },
}

fn build_rec(prims: &mut [PrimRef], first: u32, depth: u32) -> BuildNode {
    let n = prims.len();
    let (bounds, cbounds) = bounds_of(prims);
    let leaf = || BuildNode::Leaf { bounds, first, count: n as u32 };
    if n <= 1 {
        return leaf();
    }
    let split = if depth < SAH_DEPTH { best_split(prims, &bounds, &cbounds) } else { None };
    let mid = match split {
        Some((axis, bin, rel_cost, binner)) => {
            // Leaf cost n (one test per triangle) against traversal plus the expected tests.
            if n <= MAX_LEAF && (n as f32) <= TRAVERSAL_COST + rel_cost {
                return leaf();
            }
            partition(prims, |p| binner.bins(p.centroid2())[axis] <= bin)
        }
        None => {
            if n <= MAX_LEAF && depth < SAH_DEPTH {
                return leaf();
            }
            // Median split along the longest centroid axis (arbitrary if the centroids coincide).
            let axis = longest_axis((cbounds.max - cbounds.min).into());
            prims.select_nth_unstable_by(n / 2, |a, b| a.centroid2()[axis].total_cmp(&b.centroid2()[axis]));
            n / 2
        }
    };
    debug_assert!(mid > 0 && mid < n, "a split leaves both sides non-empty");
    let (l, r) = prims.split_at_mut(mid);
    let rfirst = first + mid as u32;
    let kids = if n > PARALLEL_SUBTREE {
        rayon::join(|| build_rec(l, first, depth + 1), || build_rec(r, rfirst, depth + 1))
    } else {
        (build_rec(l, first, depth + 1), build_rec(r, rfirst, depth + 1))
    };
    BuildNode::Inner { bounds, kids: Box::new(kids) }
}

impl BuildNode {
    fn bounds(&self) -> &Box3 {
        match self {
            BuildNode::Leaf { bounds, .. } | BuildNode::Inner { bounds, .. } => bounds,
        }
    }
}

/// The flattened tree: 4-wide nodes in depth-first order (the root first) and the leaves'
/// packets of up to four triangles, as original triangle indices (padded by repeating the
/// packet's last triangle).
pub struct Flat {
    pub nodes: Vec<Node4>,
    pub packets: Vec<[u32; 4]>,
}

/// Collapses the binary tree into 4-wide nodes: a node's children are found by repeatedly
/// opening the interior child of largest surface area until there are four (or only leaves).
/// Every 4-wide level consumes at least one binary level, so the depth does not grow.
fn fill(ni: usize, mut kids: Vec<BuildNode>, prims: &[PrimRef], flat: &mut Flat) {
    while kids.len() < 4 {
        let widest = kids
            .iter()
            .enumerate()
            .filter(|(_, k)| matches!(k, BuildNode::Inner { .. }))
            .max_by(|a, b| a.1.bounds().half_area().total_cmp(&b.1.bounds().half_area()))
            .map(|(i, _)| i);
        let Some(i) = widest else { break };
        let BuildNode::Inner { kids: k, .. } = kids.swap_remove(i) else { unreachable!("filtered above") };
        let (l, r) = *k;
        kids.push(l);
        kids.push(r);
    }
    for (slot, k) in kids.into_iter().enumerate() {
        match k {
            BuildNode::Leaf { bounds, first, count } => {
                let p0 = flat.packets.len();
                let tris = &prims[first as usize..(first + count) as usize];
                for c in tris.chunks(4) {
                    flat.packets.push(std::array::from_fn(|i| c[i.min(c.len() - 1)].id));
                }
                let r = leaf_ref(p0 as u32, (flat.packets.len() - p0) as u32);
                flat.nodes[ni].set(slot, bounds.to_aabb(), r);
            }
            BuildNode::Inner { bounds, kids, .. } => {
                let ci = flat.nodes.len();
                flat.nodes.push(Node4::default());
                let (l, r) = *kids;
                fill(ci, vec![l, r], prims, flat);
                flat.nodes[ni].set(slot, bounds.to_aabb(), ci as u32);
            }
        }
    }
}

/// Builds the tree over `prims`, reordering them into leaf order (`None` for no primitives).
pub fn build(prims: &mut [PrimRef]) -> Option<Flat> {
    if prims.is_empty() {
        return None;
    }
    let tree = build_rec(prims, 0, 0);
    let mut flat =
        Flat { nodes: Vec::with_capacity(prims.len() / 4), packets: Vec::with_capacity(prims.len() / 3) };
    flat.nodes.push(Node4::default());
    let kids = match tree {
        leaf @ BuildNode::Leaf { .. } => vec![leaf],
        BuildNode::Inner { kids, .. } => {
            let (l, r) = *kids;
            vec![l, r]
        }
    };
    fill(0, kids, prims, &mut flat);
    Some(flat)
}
