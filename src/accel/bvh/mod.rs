//! A pure-Rust bounding volume hierarchy over triangles.
//!
//! * **Build** ([`build`]): binned SAH after Wald, "On fast Construction of SAH-based Bounding
//!   Volume Hierarchies" (IEEE RT 2007), parallel over subtrees with rayon, flattened into
//!   32-byte [`Node`]s. Siblings are stored together as a 64-byte [`NodePair`] (one cache line,
//!   so both children are tested with one fetch); pairs are in depth-first order.
//!   Triangles are copied into leaf order as vertex triples, so a leaf's triangles are contiguous
//!   in memory; their original indices are kept for [`Hit::prim`]. Triangles of zero area (or
//!   with non-finite corners) are left out: they can never be hit.
//! * **Traversal**: a stack-based ordered walk. Both children of an interior node are tested
//!   together, the nearer (by entry distance) is visited first and the farther pushed with its
//!   entry distance, so it is skipped once a closer hit is found. Occlusion queries return at the
//!   first hit.
//! * **Robust box test**: the slab test uses precomputed reciprocals (`1/0 = +inf` after
//!   normalising `-0`), picks near/far planes from the direction's sign, ignores the NaN of
//!   `0 * inf` (origin exactly on a slab plane of a zero direction component, where the ray lies
//!   in the plane and the slab imposes no limit), and enlarges the exit distance by `1 + 2γ₃`
//!   (Ize, "Robust BVH Ray Traversal", JCGT 2(2), 2013; pbrt-v3 §3.9.2) so that rounding never
//!   culls a box the ray truly enters.
//! * **Triangles**: the watertight test of Woop, Benthin and Wald, "Watertight Ray/Triangle
//!   Intersection" (JCGT 2(1), 2013), shared with the other backends in
//!   [`triangle`](super::triangle), so results agree bit for bit with [`Naive`](super::naive::Naive).

mod build;
mod node;

pub use node::{Node, NodePair};

use super::triangle::{TriHit, WatertightRay};
use super::{Accel, Hit};
use crate::geometry::{Ray, TriangleMesh};
use build::{Box3, PrimRef};
use glam::{BVec3A, Vec3, Vec3A};
use rayon::prelude::*;

/// Traversal stack capacity; the build keeps the depth below `64 + 32`.
const STACK: usize = 128;

/// `1 + 2 γ₃` with `γₙ = n ε / (1 - n ε)`, `ε = 2⁻²⁴`: the conservative scale of exit distances.
const EXIT_SCALE: f32 = 1.0 + 2.0 * (3.0 * f32::EPSILON * 0.5) / (1.0 - 3.0 * f32::EPSILON * 0.5);

/// A binary BVH over one triangle mesh; see the [module docs](self).
#[derive(Clone, Debug, Default)]
pub struct Bvh {
    /// The root (`None` for an empty BVH); interior nodes point at their children's pair.
    root: Option<Node>,
    pairs: Vec<NodePair>,
    /// Triangle corners in leaf order.
    tris: Vec<[Vec3; 3]>,
    /// Original triangle index of each entry of `tris`.
    prim_ids: Vec<u32>,
}

/// A ray prepared for box tests.
struct BoxRay {
    org: Vec3A,
    inv: Vec3A,
    neg: BVec3A,
    t_min: Vec3A,
}

impl BoxRay {
    fn new(ray: &Ray) -> Self {
        // `+ 0.0` turns `-0` into `+0`, so zero components give `+inf` and the min plane is near.
        let dir = Vec3A::from(ray.dir) + Vec3A::ZERO;
        let inv = Vec3A::ONE / dir;
        BoxRay { org: ray.origin.into(), inv, neg: dir.cmplt(Vec3A::ZERO), t_min: Vec3A::splat(ray.t_min) }
    }

    /// Whether the ray enters `node` within `(t_min, t_max)`, and its entry distance.
    // `!(near > far)`: a NaN must pass the test (conservative), which `near <= far` would not.
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    #[inline(always)]
    fn hit(&self, node: &Node, t_max: f32) -> (bool, f32) {
        let t0 = (node.min_a() - self.org) * self.inv;
        let t1 = (node.max_a() - self.org) * self.inv;
        // `max`/`min` return their argument when a lane is NaN (SSE semantics and `f32::max`),
        // so NaN slabs impose no limit; on other targets a NaN makes the test pass (conservative).
        let near = Vec3A::select(self.neg, t1, t0).max(self.t_min).max_element();
        let far = Vec3A::select(self.neg, t0, t1).min(Vec3A::splat(t_max)).min_element() * EXIT_SCALE;
        (!(near > far), near)
    }
}

impl Bvh {
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
        let (root, pairs) = build::build(&mut prims).unzip();
        let prim_ids: Vec<u32> = prims.iter().map(|p| p.id).collect();
        let tris = prim_ids.par_iter().map(|&i| mesh.triangle(i)).collect();
        let bvh = Bvh { root, pairs: pairs.unwrap_or_default(), tris, prim_ids };
        if cfg!(debug_assertions) {
            if let Err(e) = bvh.validate(mesh) {
                panic!("invalid BVH: {e}");
            }
        }
        bvh
    }

    /// Number of nodes (interior and leaves).
    pub fn node_count(&self) -> usize {
        self.root.map_or(0, |_| 1 + 2 * self.pairs.len())
    }

    /// Number of triangles indexed (the mesh's triangles minus the degenerate ones).
    pub fn triangle_count(&self) -> usize {
        self.tris.len()
    }

    /// The root node, or `None` for an empty BVH.
    pub fn root(&self) -> Option<&Node> {
        self.root.as_ref()
    }

    /// The sibling pairs in depth-first order; an interior node's `offset` indexes this.
    pub fn pairs(&self) -> &[NodePair] {
        &self.pairs
    }

    /// Checks the structure: every indexed triangle in exactly one leaf, child bounds inside
    /// their parent's, triangles inside their leaf's bounds, depth within the traversal stack.
    /// Run after every build in debug builds.
    pub fn validate(&self, mesh: &TriangleMesh) -> Result<(), String> {
        let mut seen = vec![0u8; self.tris.len()];
        let mut ids = vec![false; mesh.len()];
        for &id in &self.prim_ids {
            let slot = ids.get_mut(id as usize).ok_or(format!("prim id {id} out of range"))?;
            if std::mem::replace(slot, true) {
                return Err(format!("prim {id} appears twice"));
            }
        }
        let Some(root) = self.root else {
            return if self.tris.is_empty() { Ok(()) } else { Err("triangles but no nodes".into()) };
        };
        let inside = |inner: &Node, outer: &Node| {
            (0..3).all(|k| inner.min[k] >= outer.min[k] && inner.max[k] <= outer.max[k])
        };
        let mut todo = vec![(root, 1usize)];
        let mut pairs_seen = vec![false; self.pairs.len()];
        while let Some((n, depth)) = todo.pop() {
            if depth >= STACK {
                return Err(format!("depth {depth} exceeds the traversal stack"));
            }
            if n.is_leaf() {
                let (s, c) = (n.offset as usize, n.count() as usize);
                for k in s..s + c {
                    let slot = seen.get_mut(k).ok_or(format!("leaf range {s}+{c} out of bounds"))?;
                    *slot += 1;
                    let b = crate::geometry::Aabb::from_points(self.tris[k]);
                    if !(n.bounds().contains(b.min) && n.bounds().contains(b.max)) {
                        return Err(format!("triangle {k} outside its leaf"));
                    }
                    if self.tris[k] != mesh.triangle(self.prim_ids[k]) {
                        return Err(format!("triangle {k} does not match mesh prim {}", self.prim_ids[k]));
                    }
                }
            } else {
                let p = n.offset as usize;
                let seen_pair = pairs_seen.get_mut(p).ok_or(format!("pair {p} out of range"))?;
                if std::mem::replace(seen_pair, true) {
                    return Err(format!("pair {p} has two parents"));
                }
                for child in self.pairs[p].0 {
                    if !inside(&child, &n) {
                        return Err(format!("a child in pair {p} is not inside its parent"));
                    }
                    todo.push((child, depth + 1));
                }
            }
        }
        if let Some(p) = pairs_seen.iter().position(|s| !s) {
            return Err(format!("pair {p} unreachable"));
        }
        if let Some(k) = seen.iter().position(|&s| s != 1) {
            return Err(format!("triangle {k} is in {} leaves", seen[k]));
        }
        Ok(())
    }

    /// Ray validity shared by both queries: a finite origin and a finite non-zero direction.
    #[inline]
    fn usable(&self, ray: &Ray) -> bool {
        self.root.is_some()
            && ray.origin.is_finite()
            && ray.dir.is_finite()
            && ray.dir != Vec3::ZERO
            && ray.t_min <= ray.t_max
    }

    /// The shared traversal: calls `leaf` for each triangle of each visited leaf, in near-to-far
    /// order of the leaves' entry; `leaf` returns the new `t_max` and whether to stop.
    #[allow(clippy::neg_cmp_op_on_partial_ord)] // NaN entry distances are visited, not skipped
    #[inline(always)]
    fn traverse(&self, ray: &Ray, mut leaf: impl FnMut(usize, &[Vec3; 3], f32) -> (f32, bool)) {
        let br = BoxRay::new(ray);
        let mut t_max = ray.t_max;
        let Some(root) = &self.root else { return };
        if !br.hit(root, t_max).0 {
            return;
        }
        let pairs = &self.pairs[..];
        // Entries are `2 * pair + slot` and the entry distance.
        let mut stack = [(0u32, 0f32); STACK];
        let mut sp = 0usize;
        let mut node = root;
        'walk: loop {
            if node.is_leaf() {
                let first = node.offset as usize;
                let count = node.count() as usize;
                for (k, tri) in self.tris[first..first + count].iter().enumerate() {
                    let (t, stop) = leaf(first + k, tri, t_max);
                    if stop {
                        return;
                    }
                    t_max = t;
                }
            } else {
                let p = node.offset as usize;
                let [l, r] = &pairs[p].0;
                let (hl, tl) = br.hit(l, t_max);
                let (hr, tr) = br.hit(r, t_max);
                match (hl, hr) {
                    (true, true) => {
                        let (near, far, t_far) = if tl <= tr { (l, 1, tr) } else { (r, 0, tl) };
                        stack[sp] = ((2 * p + far) as u32, t_far);
                        sp += 1;
                        node = near;
                        continue 'walk;
                    }
                    (true, false) => {
                        node = l;
                        continue 'walk;
                    }
                    (false, true) => {
                        node = r;
                        continue 'walk;
                    }
                    (false, false) => {}
                }
            }
            // Pop the next subtree that may still hold something closer than `t_max`.
            loop {
                if sp == 0 {
                    return;
                }
                sp -= 1;
                let (e, t_near) = stack[sp];
                if !(t_near > t_max * EXIT_SCALE) {
                    node = &pairs[(e >> 1) as usize].0[(e & 1) as usize];
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
        let mut best: Option<(usize, TriHit)> = None;
        self.traverse(ray, |k, [a, b, c], t_max| match wr.intersect(*a, *b, *c, ray.t_min, t_max) {
            Some(h) => {
                best = Some((k, h));
                (h.t, false)
            }
            None => (t_max, false),
        });
        best.map(|(k, h)| Hit { t: h.t, prim: self.prim_ids[k], u: h.u, v: h.v })
    }

    fn occluded(&self, ray: &Ray) -> bool {
        if !self.usable(ray) {
            return false;
        }
        let wr = WatertightRay::new(ray.origin, ray.dir);
        let mut hit = false;
        self.traverse(ray, |_, [a, b, c], t_max| {
            hit = wr.intersect(*a, *b, *c, ray.t_min, t_max).is_some();
            (t_max, hit)
        });
        hit
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::naive::Naive;

    fn quad_mesh() -> TriangleMesh {
        TriangleMesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y, Vec3::X * 2.0],
            // Two real triangles and a degenerate one.
            indices: vec![[0, 1, 2], [0, 2, 3], [0, 1, 4]],
        }
    }

    #[test]
    fn empty_mesh_misses_everything() {
        let bvh = Bvh::build(&TriangleMesh::default());
        assert_eq!(bvh.node_count(), 0);
        assert!(bvh.intersect(&Ray::new(Vec3::ZERO, Vec3::X)).is_none());
        assert!(!bvh.occluded(&Ray::new(Vec3::ZERO, Vec3::X)));
    }

    #[test]
    fn skips_degenerate_and_matches_naive() {
        let m = quad_mesh();
        let bvh = Bvh::build(&m);
        assert_eq!(bvh.triangle_count(), 2);
        let naive = Naive::new(&m);
        let r = Ray::new(Vec3::new(0.25, 0.5, -1.0), Vec3::Z);
        assert_eq!(bvh.intersect(&r), naive.intersect(&r));
        assert_eq!(bvh.intersect(&r).unwrap().prim, 1);
        // Along the degenerate triangle's line, in its plane: nothing to hit, no NaN.
        assert!(bvh.intersect(&Ray::new(Vec3::new(-1.0, 0.0, 0.0), Vec3::X)).is_none());
    }

    #[test]
    fn zero_direction_components_on_box_planes() {
        // Rays with exact zero components whose origins lie on the bounding planes.
        let m = quad_mesh();
        let bvh = Bvh::build(&m);
        for (o, d) in [
            (Vec3::new(0.0, 0.5, -1.0), Vec3::Z),
            (Vec3::new(1.0, 0.25, -1.0), Vec3::new(-0.0, 0.0, 1.0)),
            (Vec3::new(0.5, 1.0, 1.0), Vec3::new(0.0, -0.0, -2.0)),
        ] {
            let r = Ray::new(o, d);
            let want = Naive::new(&m).intersect(&r);
            assert!(want.is_some(), "{o} {d}");
            assert_eq!(bvh.intersect(&r), want, "{o} {d}");
            assert!(bvh.occluded(&r));
        }
    }
}
