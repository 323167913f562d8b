//! Agreement between ray-casting backends: the machinery behind `photonmap agree` and the
//! backend tests.
//!
//! [`generate_rays`] makes a deterministic mix of rays that stress different parts of an
//! accelerator ([`RayKind`]): coherent camera rays, random rays through the scene, rays leaving
//! surfaces (self-intersection), grazing rays (nearly parallel to a surface) and shadow segments
//! between two surface points. [`compare`] casts them through two backends and classifies every
//! difference. Watertight triangle tests may legitimately differ where a ray passes within
//! rounding distance of an edge or vertex, or where two triangles are hit at the same distance;
//! such differences are counted as [`edge_ties`](AgreeReport::edge_ties), everything else is a
//! real disagreement. With alpha cut-outs ([`compare_with_cutouts`]), so is a difference on a
//! ray that crosses a cut-out triangle within rounding of where its opacity flips
//! ([`near_cutout_edge`]): the backends' barycentrics differ in their last bits.

use crate::accel::triangle::WatertightRay;
use crate::accel::{Accel, Cutouts, Hit};
use crate::geometry::{Ray, TriangleMesh, Vec3};
use rayon::prelude::*;
use serde::Serialize;
use std::collections::BTreeMap;
use std::fmt;

mod rays;

pub use rays::{generate_rays, CameraLike, RayKind};

/// Tolerance of the edge-tie classification, in ULPs of the coordinates' magnitude.
pub const TIE_ULPS: f32 = 64.0;
/// Barycentric coordinates below this count as "on the edge" whatever the triangle's size.
pub const TIE_BARYCENTRIC: f32 = 1e-5;
/// A cut-out's opacity changing within this barycentric step of a hit makes the hit a tie.
pub const TIE_CUTOUT: f32 = 1e-4;

/// Disagreement counts over a set of rays.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct KindReport {
    pub rays: u64,
    pub hit_miss_disagreements: u64,
    pub edge_ties: u64,
    pub primitive_disagreements: u64,
    pub occlusion_disagreements: u64,
    pub max_rel_dt: f64,
}

impl KindReport {
    fn merge(self, o: KindReport) -> KindReport {
        KindReport {
            rays: self.rays + o.rays,
            hit_miss_disagreements: self.hit_miss_disagreements + o.hit_miss_disagreements,
            edge_ties: self.edge_ties + o.edge_ties,
            primitive_disagreements: self.primitive_disagreements + o.primitive_disagreements,
            occlusion_disagreements: self.occlusion_disagreements + o.occlusion_disagreements,
            max_rel_dt: self.max_rel_dt.max(o.max_rel_dt),
        }
    }
}

/// The result of [`compare`]. Every closest-hit difference is counted exactly once: as an
/// edge tie, else as a hit/miss or a primitive disagreement. Occlusion answers are compared
/// separately.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct AgreeReport {
    /// Names of the two backends compared, in argument order.
    pub backends: Vec<String>,
    pub rays: u64,
    /// One backend hit, the other missed, and the hit is not within rounding of an edge.
    pub hit_miss_disagreements: u64,
    /// Differences (hit/miss, primitive or occlusion) that rounding alone decides: a hit within
    /// [`TIE_ULPS`] ULPs (or [`TIE_BARYCENTRIC`]) of an edge or vertex, two triangles hit at the
    /// same point (coplanar and touching surfaces such as a block standing on the floor), or a
    /// ray starting or ending within rounding distance of the plane of the triangle it hits.
    pub edge_ties: u64,
    /// Both hit, different triangles, not a tie.
    pub primitive_disagreements: u64,
    /// `occluded` answered differently.
    pub occlusion_disagreements: u64,
    /// Largest `|t_a - t_b| / max(t_a, t_b)` where both hit the same triangle.
    pub max_rel_dt: f64,
    pub per_kind: BTreeMap<RayKind, KindReport>,
}

/// How two closest-hit answers relate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Verdict {
    /// Same answer; `rel_dt` when both hit (the same triangle).
    Agree {
        rel_dt: Option<f64>,
    },
    HitMiss,
    Primitive,
    EdgeTie,
}

/// Whether a hit lies within rounding distance of an edge or vertex of its triangle: some
/// barycentric below [`TIE_BARYCENTRIC`], or a distance to an edge line (from barycentrics and
/// the triangle's heights) below [`TIE_ULPS`] ULPs of the largest coordinate. A hit on a
/// zero-area triangle (all edge) always qualifies.
pub fn near_edge(mesh: &TriangleMesh, hit: &Hit) -> bool {
    if hit.prim as usize >= mesh.len() {
        return false;
    }
    let [a, b, c] = mesh.triangle(hit.prim);
    let area2 = (b - a).cross(c - a).length();
    if !(area2 > 0.0 && area2.is_finite()) {
        return true;
    }
    let bary = [1.0 - hit.u - hit.v, hit.u, hit.v];
    let opposite = [(c - b).length(), (c - a).length(), (b - a).length()];
    let magnitude = a.abs().max(b.abs()).max(c.abs()).max_element();
    let tol = TIE_ULPS * f32::EPSILON * magnitude;
    bary.iter().zip(opposite).any(|(&w, len)| w.abs() < TIE_BARYCENTRIC || w.abs() * area2 / len <= tol)
}

/// Whether two hits on different triangles are the same point up to rounding of the world
/// coordinates (coplanar or touching surfaces: either answer is right).
fn same_point(mesh: &TriangleMesh, a: &Hit, b: &Hit) -> bool {
    let pa = mesh.point(a.prim, a.u, a.v);
    let pb = mesh.point(b.prim, b.u, b.v);
    let magnitude = pa.abs().max(pb.abs()).max_element();
    (pa - pb).length() <= TIE_ULPS * f32::EPSILON * magnitude
}

/// Whether `x` lies within rounding distance of the plane of the triangle `hit` is on.
fn near_plane(mesh: &TriangleMesh, hit: &Hit, x: Vec3) -> bool {
    let Some(n) = mesh.normal(hit.prim) else { return true };
    let [a, b, c] = mesh.triangle(hit.prim);
    let magnitude = a.abs().max(b.abs()).max(c.abs()).max(x.abs()).max_element();
    n.dot(x - a).abs() <= TIE_ULPS * f32::EPSILON * magnitude
}

/// Whether either answer about `hit` is right up to rounding: the hit is at an edge or vertex,
/// or the ray starts (or, for a segment, ends) within rounding distance of the hit triangle's
/// plane, where whether it touches that triangle is decided by rounding alone (a shadow ray
/// running along a wall, a ray leaving a point that lies exactly in a neighbour's plane).
pub fn ambiguous(mesh: &TriangleMesh, ray: Option<&Ray>, hit: &Hit) -> bool {
    near_edge(mesh, hit)
        || ray.is_some_and(|r| {
            near_plane(mesh, hit, r.origin) || (r.t_max.is_finite() && near_plane(mesh, hit, r.at(r.t_max)))
        })
}

/// Whether the opacity of cut-out triangle `prim` changes within [`TIE_CUTOUT`] of `(u, v)`
/// (probed a step either way along `u` and `v`): which side a backend sees is rounding. False
/// for a triangle without a cut-out.
pub fn near_cutout_edge(cutouts: &Cutouts, prim: u32, u: f32, v: f32) -> bool {
    if !cutouts.is_cutout(prim) {
        return false;
    }
    let here = cutouts.test(prim, u, v);
    let d = TIE_CUTOUT;
    [(d, 0.0), (-d, 0.0), (0.0, d), (0.0, -d)]
        .iter()
        .any(|&(du, dv)| cutouts.test(prim, u + du, v + dv) != here)
}

/// Whether `ray` crosses some cut-out triangle (opaque or not) within rounding of where its
/// opacity flips ([`near_cutout_edge`]), by brute force over the cut-out triangles.
pub fn cutout_ambiguous(mesh: &TriangleMesh, cutouts: &Cutouts, ray: &Ray) -> bool {
    let wr = WatertightRay::new(ray.origin, ray.dir);
    (0..mesh.len() as u32).filter(|&p| cutouts.is_cutout(p)).any(|p| {
        let [a, b, c] = mesh.triangle(p);
        wr.intersect(a, b, c, ray.t_min, ray.t_max).is_some_and(|h| near_cutout_edge(cutouts, p, h.u, h.v))
    })
}

/// Classifies the closest hits `a` and `b` of one ray.
pub fn classify(mesh: &TriangleMesh, a: Option<Hit>, b: Option<Hit>) -> Verdict {
    classify_ray(mesh, None, a, b)
}

/// [`classify`], also counting as ties the hits that [`ambiguous`] finds ambiguous for `ray`.
pub fn classify_ray(mesh: &TriangleMesh, ray: Option<&Ray>, a: Option<Hit>, b: Option<Hit>) -> Verdict {
    match (a, b) {
        (None, None) => Verdict::Agree { rel_dt: None },
        (Some(h), None) | (None, Some(h)) => {
            if ambiguous(mesh, ray, &h) {
                Verdict::EdgeTie
            } else {
                Verdict::HitMiss
            }
        }
        (Some(ha), Some(hb)) => {
            let scale = ha.t.abs().max(hb.t.abs()) as f64;
            let dt = (ha.t as f64 - hb.t as f64).abs();
            if ha.prim == hb.prim {
                Verdict::Agree { rel_dt: Some(if scale > 0.0 { dt / scale } else { 0.0 }) }
            } else if dt <= (TIE_ULPS * f32::EPSILON) as f64 * scale
                || same_point(mesh, &ha, &hb)
                || ambiguous(mesh, ray, &ha)
                || ambiguous(mesh, ray, &hb)
            {
                Verdict::EdgeTie
            } else {
                Verdict::Primitive
            }
        }
    }
}

/// Casts `rays` through `a` and `b` (closest hit and occlusion) in parallel and counts the
/// differences. The result does not depend on the thread count. Each ray is counted once: a
/// differing occlusion answer is a tie when the occluding backend's closest hit is
/// [`ambiguous`], and a disagreement otherwise.
pub fn compare(a: &dyn Accel, b: &dyn Accel, rays: &[(RayKind, Ray)], mesh: &TriangleMesh) -> AgreeReport {
    compare_with_cutouts(a, b, rays, mesh, None)
}

/// [`compare`] of two backends built with `cutouts`: a difference on a ray that
/// [`cutout_ambiguous`] finds ambiguous is a tie too.
pub fn compare_with_cutouts(
    a: &dyn Accel,
    b: &dyn Accel,
    rays: &[(RayKind, Ray)],
    mesh: &TriangleMesh,
    cutouts: Option<&Cutouts>,
) -> AgreeReport {
    let alpha_tie = |ray: &Ray| cutouts.is_some_and(|c| cutout_ambiguous(mesh, c, ray));
    let empty = || [KindReport::default(); 5];
    let per = rays
        .par_iter()
        .fold(empty, |mut acc, (kind, ray)| {
            let r = &mut acc[*kind as usize];
            r.rays += 1;
            let (ha, hb) = (a.intersect(ray), b.intersect(ray));
            let mut verdict = classify_ray(mesh, Some(ray), ha, hb);
            if matches!(verdict, Verdict::HitMiss | Verdict::Primitive) && alpha_tie(ray) {
                verdict = Verdict::EdgeTie;
            }
            match verdict {
                Verdict::Agree { rel_dt } => r.max_rel_dt = r.max_rel_dt.max(rel_dt.unwrap_or(0.0)),
                Verdict::HitMiss => r.hit_miss_disagreements += 1,
                Verdict::Primitive => r.primitive_disagreements += 1,
                Verdict::EdgeTie => r.edge_ties += 1,
            }
            let (oa, ob) = (a.occluded(ray), b.occluded(ray));
            if oa != ob {
                let occluder = if oa { ha } else { hb };
                if occluder.is_some_and(|h| ambiguous(mesh, Some(ray), &h)) || alpha_tie(ray) {
                    r.edge_ties += u64::from(verdict != Verdict::EdgeTie);
                } else {
                    r.occlusion_disagreements += 1;
                }
            }
            acc
        })
        .reduce(empty, |x, y| std::array::from_fn(|k| x[k].merge(y[k])));
    let total = per.iter().fold(KindReport::default(), |t, k| t.merge(*k));
    AgreeReport {
        backends: vec![a.name().to_string(), b.name().to_string()],
        rays: total.rays,
        hit_miss_disagreements: total.hit_miss_disagreements,
        edge_ties: total.edge_ties,
        primitive_disagreements: total.primitive_disagreements,
        occlusion_disagreements: total.occlusion_disagreements,
        max_rel_dt: total.max_rel_dt,
        per_kind: RayKind::ALL.into_iter().zip(per).filter(|(_, r)| r.rays > 0).collect(),
    }
}

/// [`compare`] of `a` with `b`, and with the brute-force `reference` of each when given
/// (`[a-b]` or `[a-b, a-reference, b-reference]`).
pub fn compare_with_reference(
    a: &dyn Accel,
    b: &dyn Accel,
    reference: Option<&dyn Accel>,
    rays: &[(RayKind, Ray)],
    mesh: &TriangleMesh,
    cutouts: Option<&Cutouts>,
) -> Vec<AgreeReport> {
    let mut out = vec![compare_with_cutouts(a, b, rays, mesh, cutouts)];
    if let Some(r) = reference {
        out.push(compare_with_cutouts(a, r, rays, mesh, cutouts));
        out.push(compare_with_cutouts(b, r, rays, mesh, cutouts));
    }
    out
}

impl AgreeReport {
    /// No disagreement beyond edge ties (occlusion included).
    pub fn clean(&self) -> bool {
        self.hit_miss_disagreements == 0
            && self.primitive_disagreements == 0
            && self.occlusion_disagreements == 0
    }
}

impl fmt::Display for AgreeReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "agreement: {} ({} rays)", self.backends.join(" vs "), self.rays)?;
        writeln!(
            f,
            "{:<8} {:>10} {:>9} {:>9} {:>9} {:>9} {:>11}",
            "kind", "rays", "hit/miss", "prim", "ties", "occluded", "max rel dt"
        )?;
        let row = |f: &mut fmt::Formatter<'_>, name: &str, r: &KindReport| {
            writeln!(
                f,
                "{:<8} {:>10} {:>9} {:>9} {:>9} {:>9} {:>11.3e}",
                name,
                r.rays,
                r.hit_miss_disagreements,
                r.primitive_disagreements,
                r.edge_ties,
                r.occlusion_disagreements,
                r.max_rel_dt
            )
        };
        for (k, r) in &self.per_kind {
            row(f, k.name(), r)?;
        }
        let total = KindReport {
            rays: self.rays,
            hit_miss_disagreements: self.hit_miss_disagreements,
            edge_ties: self.edge_ties,
            primitive_disagreements: self.primitive_disagreements,
            occlusion_disagreements: self.occlusion_disagreements,
            max_rel_dt: self.max_rel_dt,
        };
        row(f, "total", &total)
    }
}

/// Brute force joins the comparison up to this many triangles × rays.
pub const NAIVE_BUDGET: u64 = 400_000_000;

/// An evenly spread subset of `rays` (every kind in proportion, as [`generate_rays`] groups
/// them by kind) on which brute force over `triangles` triangles stays within `budget`
/// triangles × rays: all of them when they fit, none when not even one ray does.
pub fn within_budget(rays: &[(RayKind, Ray)], triangles: usize, budget: u64) -> Vec<(RayKind, Ray)> {
    let fit = budget.checked_div(triangles as u64).unwrap_or(u64::MAX);
    let (len, m) = (rays.len() as u64, (rays.len() as u64).min(fit));
    (0..m).map(|i| rays[(i * len / m) as usize]).collect()
}

/// The agreement of a scene's backends: the main pair at the top level, and each backend of
/// the main pair against brute force when the scene is small enough for it on every ray.
///
/// The main pair is Embree against the BVH when built with Embree. Without Embree it is the
/// BVH against brute force, on every ray when the scene is small enough and otherwise on the
/// evenly spread subset of them that [`within_budget`] gives for [`NAIVE_BUDGET`] (on none, for
/// a scene of more triangles than the budget: the check is then not run, and not clean).
#[derive(Clone, Debug, Serialize)]
pub struct SceneAgreement {
    #[serde(flatten)]
    pub main: AgreeReport,
    /// The backends against brute force (empty when the scene is too large for it).
    pub against_naive: Vec<AgreeReport>,
    /// Rays generated; the main comparison cast `main.rays` of them.
    pub generated_rays: u64,
}

impl SceneAgreement {
    /// Whether the main comparison cast any ray.
    pub fn ran(&self) -> bool {
        self.main.rays > 0
    }

    /// The main comparison cast rays and found no disagreement beyond edge ties, and neither
    /// did any other comparison.
    pub fn clean(&self) -> bool {
        self.ran() && self.main.clean() && self.against_naive.iter().all(AgreeReport::clean)
    }
}

impl fmt::Display for SceneAgreement {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.main)?;
        if !self.ran() && self.generated_rays > 0 {
            writeln!(
                f,
                "not run: brute force exceeds its budget of {NAIVE_BUDGET} triangles x rays on one ray"
            )?;
        } else if self.main.rays < self.generated_rays {
            writeln!(
                f,
                "(an evenly spread {} of the {} rays: brute force's budget is {NAIVE_BUDGET} triangles x rays)",
                self.main.rays, self.generated_rays
            )?;
        }
        for r in &self.against_naive {
            write!(f, "\n{r}")?;
        }
        Ok(())
    }
}

/// Casts `n` rays of every kind through the backends built for `scene` (camera rays from its
/// camera), with its alpha cut-outs, and compares them.
pub fn agree_scene(
    scene: &crate::scene::Scene,
    n: usize,
    seed: u64,
    options: crate::accel::AccelOptions,
) -> Result<SceneAgreement, crate::accel::AccelError> {
    let eye = scene.camera.eye;
    let camera = CameraLike { eye, target: eye + scene.camera.forward };
    agree_mesh(&scene.mesh, scene.cutouts().as_ref(), Some(camera), n, seed, options, NAIVE_BUDGET)
}

/// [`agree_scene`] on a mesh, with brute force held to `budget` triangles × rays.
fn agree_mesh(
    mesh: &TriangleMesh,
    cutouts: Option<&Cutouts>,
    camera: Option<CameraLike>,
    n: usize,
    seed: u64,
    options: crate::accel::AccelOptions,
    budget: u64,
) -> Result<SceneAgreement, crate::accel::AccelError> {
    use crate::accel::{bvh::Bvh, naive::Naive};
    mesh.validate()?;
    let rays = generate_rays(mesh, camera, n, seed);
    let generated_rays = rays.len() as u64;
    let bvh = Bvh::build_with_cutouts(mesh, cutouts.cloned());
    #[cfg(feature = "embree")]
    {
        let naive_ok = mesh.len() as u64 * rays.len() as u64 <= budget;
        let naive = naive_ok.then(|| Naive::with_cutouts(mesh, cutouts.cloned()));
        let embree = crate::accel::embree::EmbreeAccel::build_with_cutouts(mesh, cutouts.cloned(), options)?;
        let naive = naive.as_ref().map(|n| n as &dyn Accel);
        let mut reports = compare_with_reference(&embree, &bvh, naive, &rays, mesh, cutouts);
        let main = reports.remove(0);
        Ok(SceneAgreement { main, against_naive: reports, generated_rays })
    }
    #[cfg(not(feature = "embree"))]
    {
        let _ = options;
        // Never the BVH against itself: brute force, on as many of the rays as the budget allows.
        let naive = Naive::with_cutouts(mesh, cutouts.cloned());
        let main =
            compare_with_cutouts(&bvh, &naive, &within_budget(&rays, mesh.len(), budget), mesh, cutouts);
        Ok(SceneAgreement { main, against_naive: Vec::new(), generated_rays })
    }
}

#[cfg(test)]
mod tests;
