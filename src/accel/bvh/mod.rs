//! A pure-Rust bounding volume hierarchy over triangles.
//!
//! * **Build** (`build.rs`): binned SAH after Wald, "On fast Construction of SAH-based Bounding
//!   Volume Hierarchies" (IEEE RT 2007), parallel over subtrees with rayon, giving a binary
//!   tree that is then collapsed into 4-wide [`Node4`]s (each node repeatedly opens its child of
//!   largest surface area until it has four children), stored depth first. A node holds its
//!   four children's boxes in structure-of-arrays layout (`[Vec4; 2]` per axis, 128 bytes), so
//!   one ray is tested against all four boxes with 4-wide SSE operations.
//!   Leaf triangles are copied, in leaf order, into [`Tri4`] packets of four (structure of
//!   arrays; a leaf's last packet is padded by repeating its last triangle), with their
//!   original indices kept for [`Hit::prim`]. Triangles of zero area (or with non-finite
//!   corners) are left out: they can never be hit.
//! * **Traversal**: a stack-based ordered walk. The four children of a node are tested
//!   together; the children hit are sorted by entry distance, the nearest is visited next and
//!   the others are pushed with their entry distance, so they are skipped once a closer hit is
//!   found. The stack lives in a small array that spills into a `Vec` in (never seen) very deep
//!   trees. Occlusion queries return at the first hit.
//! * **Robust box test**: the slab test uses precomputed reciprocals (`1/0 = +inf` after
//!   normalising `-0`), picks near/far planes from the direction's sign, ignores the NaN of
//!   `0 * inf` (origin exactly on a slab plane of a zero direction component, where the ray lies
//!   in the plane and the slab imposes no limit), and enlarges the exit distance by `1 + 2γ₃`
//!   (Ize, "Robust BVH Ray Traversal", JCGT 2(2), 2013; pbrt-v3 §3.9.2) so that rounding never
//!   culls a box the ray truly enters.
//! * **Triangles**: the watertight test of Woop, Benthin and Wald, "Watertight Ray/Triangle
//!   Intersection" (JCGT 2(1), 2013), run on four triangles at once by
//!   [`WatertightRay::intersect4`], which performs the scalar test's operations in the same order
//!   lane by lane, so results agree bit for bit with [`Naive`](super::naive::Naive) (which uses
//!   the scalar [`WatertightRay::intersect`]).
//! * **Cut-outs** ([`Cutouts`]): with them, a lane that hits a transparent point of a cut-out
//!   triangle is dropped and the next closest lane of the packet tried, so the walk goes on to
//!   farther triangles as if the triangle were not there. Without them the walk has no test.

mod build;
mod node;

pub use node::Node4;

use super::triangle::{Tri4, TriHit, WatertightRay};
use super::{Accel, Cutouts, Hit};
use crate::geometry::{Aabb, Ray, TriangleMesh};
use build::{Box3, PrimRef};
use glam::{Vec3, Vec3A, Vec4};
use node::{leaf_range, EMPTY, LEAF};
use rayon::prelude::*;

/// The binary build keeps its depth below `64 + 32`; every 4-wide level consumes at least one
/// binary level (and pushes at most three children).
const MAX_DEPTH: usize = 96;
/// Traversal stack entries kept on the machine stack; deeper entries spill into a `Vec`.
/// (A fixed array for the worst case, `3 * MAX_DEPTH` entries, cost 7% of the incoherent-ray
/// time just in zeroing it per ray; realistic trees never need more than a few dozen.)
const STACK: usize = 64;

/// `1 + 2 γ₃` with `γₙ = n ε / (1 - n ε)`, `ε = 2⁻²⁴`: the conservative scale of exit distances.
const EXIT_SCALE: f32 = 1.0 + 2.0 * (3.0 * f32::EPSILON * 0.5) / (1.0 - 3.0 * f32::EPSILON * 0.5);

/// A 4-wide BVH over one triangle mesh; see the [module docs](self).
#[derive(Clone, Debug, Default)]
pub struct Bvh {
    /// 4-wide nodes, the root first (empty for an empty BVH).
    nodes: Vec<Node4>,
    /// Triangles in leaf order, four per packet.
    tris: Vec<Tri4>,
    /// Original triangle index of each lane of `tris`.
    prim_ids: Vec<[u32; 4]>,
    /// Number of distinct triangles indexed.
    tri_count: usize,
    /// Alpha cut-outs, tested after a lane's triangle test passes (`None`: no test at all).
    cutouts: Option<Cutouts>,
}

/// A ray prepared for testing the four boxes of a node at once.
struct BoxRay {
    org: [Vec4; 3],
    inv: [Vec4; 3],
    /// Per axis, which of a node's `bounds[axis]` (0 = minima, 1 = maxima) is the near plane.
    near: [usize; 3],
    t_min: Vec4,
}

impl BoxRay {
    #[inline(always)]
    fn new(ray: &Ray) -> Self {
        // `+ 0.0` turns `-0` into `+0`, so zero components give `+inf` and the min plane is near.
        let dir = Vec3A::from(ray.dir) + Vec3A::ZERO;
        let inv = Vec3A::ONE / dir;
        let o = ray.origin;
        BoxRay {
            org: [Vec4::splat(o.x), Vec4::splat(o.y), Vec4::splat(o.z)],
            inv: [Vec4::splat(inv.x), Vec4::splat(inv.y), Vec4::splat(inv.z)],
            near: [usize::from(dir.x < 0.0), usize::from(dir.y < 0.0), usize::from(dir.z < 0.0)],
            t_min: Vec4::splat(ray.t_min),
        }
    }

    /// Which of the node's four boxes the ray enters within `(t_min, t_max)` (a bit per child),
    /// and the entry distances.
    ///
    /// `max`/`min` are SSE's `maxps`/`minps` (glam), which return their second operand when a
    /// lane is NaN (`0 * inf`: the origin on a slab plane of a zero direction component, where
    /// the slab imposes no limit). Each chain ends with a non-NaN operand (`t_min`, `t_max`), so
    /// a NaN only ever loosens the test. The exit distance is enlarged by `1 + 2γ₃`.
    #[inline(always)]
    fn hit(&self, node: &Node4, t_max: f32) -> (u32, Vec4) {
        let b = &node.bounds;
        let slab = |k: usize| {
            let n = self.near[k] & 1;
            ((b[k][n] - self.org[k]) * self.inv[k], (b[k][n ^ 1] - self.org[k]) * self.inv[k])
        };
        let (nx, fx) = slab(0);
        let (ny, fy) = slab(1);
        let (nz, fz) = slab(2);
        let near = nx.max(ny).max(nz).max(self.t_min);
        let far = fx.min(fy).min(fz).min(Vec4::splat(t_max)) * EXIT_SCALE;
        // `!(near > far)`: NaN passes (conservative).
        (!near.cmpgt(far).bitmask() & 0xf, near)
    }
}

impl Bvh {
    /// [`Bvh::build`] with alpha cut-outs: a lane whose triangle test passes on a transparent
    /// point of a cut-out triangle counts as a miss, and the walk goes on to farther triangles.
    pub fn build_with_cutouts(mesh: &TriangleMesh, cutouts: Option<Cutouts>) -> Bvh {
        Bvh { cutouts: cutouts.filter(|c| c.count() > 0), ..Bvh::build(mesh) }
    }

    /// Builds the hierarchy (in parallel on the current rayon pool). Triangles of zero area or
    /// with non-finite corners are skipped; an empty mesh gives an empty BVH that hits nothing.
    pub fn build(mesh: &TriangleMesh) -> Bvh {
        let mut prims: Vec<PrimRef> = (0..mesh.len() as u32)
            .into_par_iter()
            .filter_map(|i| {
                let [a, b, c] = mesh.triangle(i);
                if !(a.is_finite() && b.is_finite() && c.is_finite()) || is_degenerate(a, b, c) {
                    return None;
                }
                let (a, b, c) = (Vec3A::from(a), Vec3A::from(b), Vec3A::from(c));
                Some(PrimRef { bounds: Box3 { min: a.min(b).min(c), max: a.max(b).max(c) }, id: i })
            })
            .collect();
        let tri_count = prims.len();
        let bvh = match build::build(&mut prims) {
            None => Bvh::default(),
            Some(flat) => {
                let tris =
                    flat.packets.par_iter().map(|ids| Tri4::new(&ids.map(|i| mesh.triangle(i)))).collect();
                Bvh { nodes: flat.nodes, tris, prim_ids: flat.packets, tri_count, cutouts: None }
            }
        };
        if cfg!(debug_assertions) {
            if let Err(e) = bvh.validate(mesh) {
                panic!("invalid BVH: {e}");
            }
        }
        bvh
    }

    /// Number of 4-wide nodes.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Number of triangles indexed (the mesh's triangles minus the degenerate ones).
    pub fn triangle_count(&self) -> usize {
        self.tri_count
    }

    /// The 4-wide nodes in depth-first order, the root first.
    pub fn nodes(&self) -> &[Node4] {
        &self.nodes
    }

    /// Checks the structure: every indexed triangle in exactly one leaf (padding lanes repeat
    /// their packet's last triangle), child bounds inside their parent's, triangles inside
    /// their leaf's bounds and equal to the mesh's, every node reached once, depth within the
    /// traversal stack. Run after every build in debug builds.
    pub fn validate(&self, mesh: &TriangleMesh) -> Result<(), String> {
        if self.nodes.is_empty() {
            return if self.tris.is_empty() && self.tri_count == 0 {
                Ok(())
            } else {
                Err("triangles but no nodes".into())
            };
        }
        if self.tris.len() != self.prim_ids.len() {
            return Err("packets and prim ids differ in length".into());
        }
        let mut ids = vec![false; mesh.len()];
        let mut packets_seen = vec![false; self.tris.len()];
        let mut nodes_seen = vec![false; self.nodes.len()];
        let everything = Aabb { min: Vec3::NEG_INFINITY, max: Vec3::INFINITY };
        let mut todo = vec![(0usize, everything, 1usize)];
        let mut distinct = 0;
        while let Some((ni, parent, depth)) = todo.pop() {
            if depth > MAX_DEPTH {
                return Err(format!("depth {depth} exceeds the traversal stack"));
            }
            if std::mem::replace(&mut nodes_seen[ni], true) {
                return Err(format!("node {ni} has two parents"));
            }
            let n = &self.nodes[ni];
            for (slot, &c) in n.child.iter().enumerate() {
                if c == EMPTY {
                    if !n.child_bounds(slot).is_empty() {
                        return Err(format!("empty slot {slot} of node {ni} has bounds"));
                    }
                    continue;
                }
                let b = n.child_bounds(slot);
                if !(parent.contains(b.min) && parent.contains(b.max)) {
                    return Err(format!("child {slot} of node {ni} is not inside its parent"));
                }
                if c & LEAF == 0 {
                    if c as usize >= self.nodes.len() || c == 0 {
                        return Err(format!("child {c} of node {ni} out of range"));
                    }
                    todo.push((c as usize, b, depth + 1));
                    continue;
                }
                let (first, count) = leaf_range(c);
                for p in first..first + count {
                    let seen = packets_seen.get_mut(p).ok_or(format!("packet {p} out of range"))?;
                    if std::mem::replace(seen, true) {
                        return Err(format!("packet {p} in two leaves"));
                    }
                    let lanes = self.prim_ids[p];
                    for (lane, &id) in lanes.iter().enumerate() {
                        let tri = self.tris[p].get(lane);
                        if tri != mesh.triangle(id) {
                            return Err(format!("packet {p} lane {lane} does not match mesh prim {id}"));
                        }
                        let tb = Aabb::from_points(tri);
                        if !(b.contains(tb.min) && b.contains(tb.max)) {
                            return Err(format!("packet {p} lane {lane} outside its leaf"));
                        }
                        let padding = lane > 0 && lanes[lane..].iter().all(|&l| l == lanes[lane - 1]);
                        if padding {
                            continue;
                        }
                        let slot = ids.get_mut(id as usize).ok_or(format!("prim id {id} out of range"))?;
                        if std::mem::replace(slot, true) {
                            return Err(format!("prim {id} appears twice"));
                        }
                        distinct += 1;
                    }
                }
            }
        }
        if let Some(p) = nodes_seen.iter().position(|s| !s) {
            return Err(format!("node {p} unreachable"));
        }
        if let Some(p) = packets_seen.iter().position(|s| !s) {
            return Err(format!("packet {p} unreachable"));
        }
        if distinct != self.tri_count {
            return Err(format!("{distinct} triangles in leaves, {} indexed", self.tri_count));
        }
        Ok(())
    }

    /// Ray validity shared by both queries: a finite origin and a finite non-zero direction.
    #[inline]
    fn usable(&self, ray: &Ray) -> bool {
        !self.nodes.is_empty()
            && ray.origin.is_finite()
            && ray.dir.is_finite()
            && ray.dir != Vec3::ZERO
            && ray.t_min <= ray.t_max
    }

    /// The shared traversal: calls `leaf` for each packet of each visited leaf, in near-to-far
    /// order of the children's entry; `leaf` returns the new `t_max` and whether to stop.
    #[allow(clippy::neg_cmp_op_on_partial_ord)] // NaN entry distances are visited, not skipped
    #[inline(always)]
    fn traverse(&self, ray: &Ray, mut leaf: impl FnMut(usize, &Tri4, f32) -> (f32, bool)) {
        let br = BoxRay::new(ray);
        let mut t_max = ray.t_max;
        let nodes = &self.nodes[..];
        // Child references and their entry distances.
        let mut stack = [(0u32, 0f32); STACK];
        let mut spill: Vec<(u32, f32)> = Vec::new(); // allocates only if `stack` overflows
        let mut sp = 0usize;
        let mut cur = 0u32; // the root
        'walk: loop {
            if cur & LEAF == 0 {
                let node = &nodes[cur as usize];
                let (mask, near) = br.hit(node, t_max);
                if mask != 0 {
                    if mask & (mask - 1) == 0 {
                        cur = node.child[mask.trailing_zeros() as usize];
                        continue 'walk;
                    }
                    // Two or more: sort by entry distance, far to near, push all but the nearest.
                    let near = near.to_array();
                    let mut hits = [(0u32, 0f32); 4];
                    let mut n = 0;
                    let mut m = mask;
                    while m != 0 {
                        let i = m.trailing_zeros() as usize;
                        m &= m - 1;
                        let e = (node.child[i], near[i]);
                        // Insertion into `hits[..n]`, kept in decreasing distance.
                        let mut j = n;
                        while j > 0 && hits[j - 1].1 < e.1 {
                            hits[j] = hits[j - 1];
                            j -= 1;
                        }
                        hits[j] = e;
                        n += 1;
                    }
                    for &e in &hits[..n - 1] {
                        if sp < STACK {
                            stack[sp] = e;
                            sp += 1;
                        } else {
                            spill.push(e);
                        }
                    }
                    cur = hits[n - 1].0;
                    continue 'walk;
                }
            } else {
                let (first, count) = leaf_range(cur);
                for (k, tri) in self.tris[first..first + count].iter().enumerate() {
                    let (t, stop) = leaf(first + k, tri, t_max);
                    if stop {
                        return;
                    }
                    t_max = t;
                }
            }
            // Pop the next subtree that may still hold something closer than `t_max`.
            loop {
                let (e, t_near) = if let Some(e) = spill.pop() {
                    e
                } else if sp > 0 {
                    sp -= 1;
                    stack[sp]
                } else {
                    return;
                };
                if !(t_near > t_max * EXIT_SCALE) {
                    cur = e;
                    continue 'walk;
                }
            }
        }
    }
}

/// Zero area: the edge cross product, in double precision, is exactly zero.
fn is_degenerate(a: Vec3, b: Vec3, c: Vec3) -> bool {
    let (a, b, c) = (a.as_dvec3(), b.as_dvec3(), c.as_dvec3());
    (b - a).cross(c - a) == glam::DVec3::ZERO
}

impl Accel for Bvh {
    fn name(&self) -> &'static str {
        "bvh"
    }

    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        if !self.usable(ray) {
            return None;
        }
        let wr = WatertightRay::new(ray.origin, ray.dir);
        let mut best: Option<(usize, usize, TriHit)> = None;
        // Two copies of the walk, so that a scene without cut-outs pays nothing for them.
        match &self.cutouts {
            None => self.traverse(ray, |p, tri, t_max| {
                let h = wr.intersect4(tri, ray.t_min, t_max);
                match h.closest() {
                    Some(lane) => {
                        let hit = h.get(lane);
                        best = Some((p, lane, hit));
                        (hit.t, false)
                    }
                    None => (t_max, false),
                }
            }),
            Some(cut) => self.traverse(ray, |p, tri, t_max| {
                let h = wr.intersect4(tri, ray.t_min, t_max);
                // The closest lane on an opaque point; transparent lanes are dropped one by one.
                let mut mask = h.mask;
                while let Some(lane) = h.closest_in(mask) {
                    let hit = h.get(lane);
                    if cut.opaque(self.prim_ids[p][lane], hit.u, hit.v) {
                        best = Some((p, lane, hit));
                        return (hit.t, false);
                    }
                    mask &= !(1 << lane);
                }
                (t_max, false)
            }),
        }
        best.map(|(p, lane, h)| Hit { t: h.t, prim: self.prim_ids[p][lane], u: h.u, v: h.v })
    }

    fn occluded(&self, ray: &Ray) -> bool {
        if !self.usable(ray) {
            return false;
        }
        let wr = WatertightRay::new(ray.origin, ray.dir);
        let mut hit = false;
        match &self.cutouts {
            None => self.traverse(ray, |_, tri, t_max| {
                hit = wr.intersect4(tri, ray.t_min, t_max).mask != 0;
                (t_max, hit)
            }),
            Some(cut) => self.traverse(ray, |p, tri, t_max| {
                let h = wr.intersect4(tri, ray.t_min, t_max);
                let mut m = h.mask;
                while m != 0 {
                    let lane = m.trailing_zeros() as usize;
                    m &= m - 1;
                    let th = h.get(lane);
                    if cut.opaque(self.prim_ids[p][lane], th.u, th.v) {
                        hit = true;
                        break;
                    }
                }
                (t_max, hit)
            }),
        }
        hit
    }
}

#[cfg(test)]
mod tests;
