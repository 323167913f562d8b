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
//! real disagreement.

use crate::accel::{Accel, Hit};
use crate::geometry::{offset_ray_origin, Aabb, Ray, TriangleMesh, Vec3};
use crate::sampling::{
    sample_cosine_hemisphere, sample_uniform_hemisphere, sample_uniform_sphere, sample_uniform_triangle,
    spherical_direction, Distribution1D, Frame,
};
use crate::scene::Camera;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;
use rayon::prelude::*;
use serde::Serialize;
use std::collections::BTreeMap;
use std::fmt;

/// Tolerance of the edge-tie classification, in ULPs of the coordinates' magnitude.
pub const TIE_ULPS: f32 = 64.0;
/// Barycentric coordinates below this count as "on the edge" whatever the triangle's size.
pub const TIE_BARYCENTRIC: f32 = 1e-5;

/// What a generated ray is meant to exercise.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum RayKind {
    /// A pinhole grid from one eye point: coherent primary rays.
    Camera,
    /// Uniform origins inside the scene bounds, uniform directions: incoherent rays.
    Random,
    /// Leaving a surface point (offset origin), cosine or uniform over the hemisphere.
    Surface,
    /// Leaving a surface point 0.01°–1° above the tangent plane.
    Grazing,
    /// A segment between two surface points, `t_max` just below 1.
    Shadow,
}

impl RayKind {
    pub const ALL: [RayKind; 5] =
        [RayKind::Camera, RayKind::Random, RayKind::Surface, RayKind::Grazing, RayKind::Shadow];

    pub fn name(self) -> &'static str {
        match self {
            RayKind::Camera => "camera",
            RayKind::Random => "random",
            RayKind::Surface => "surface",
            RayKind::Grazing => "grazing",
            RayKind::Shadow => "shadow",
        }
    }
}

/// Eye point and look-at point of the camera rays.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraLike {
    pub eye: Vec3,
    pub target: Vec3,
}

/// Picks surface points uniformly by area: a triangle with probability proportional to its
/// area, then a uniform point on it. Triangles without a normal (zero area) are never picked.
struct SurfaceSampler<'a> {
    mesh: &'a TriangleMesh,
    triangles: Distribution1D,
}

impl<'a> SurfaceSampler<'a> {
    fn new(mesh: &'a TriangleMesh) -> Self {
        let areas: Vec<f32> = (0..mesh.len() as u32)
            .map(|i| if mesh.normal(i).is_some() { mesh.area(i) } else { 0.0 })
            .collect();
        SurfaceSampler { mesh, triangles: Distribution1D::new(&areas) }
    }

    /// A point, its unit geometric normal and its rounding-error bound; `None` without any
    /// area.
    fn sample(&self, rng: &mut Pcg64) -> Option<(Vec3, Vec3, Vec3)> {
        let (prim, _, _) = self.triangles.sample(rng.gen())?;
        let prim = prim as u32;
        // Barycentrics [b0, b1, b2] of the point b0 v0 + b1 v1 + b2 v2, i.e. (u, v) = (b1, b2).
        let [_, u, v] = sample_uniform_triangle([rng.gen(), rng.gen()]);
        let (p, err) = self.mesh.point_and_error(prim, u, v);
        Some((p, self.mesh.normal(prim)?, err))
    }
}

/// Scene bounds, or a unit box for an empty mesh.
fn scene_bounds(mesh: &TriangleMesh) -> Aabb {
    let b = mesh.bounds();
    if b.is_empty() {
        Aabb { min: Vec3::splat(-1.0), max: Vec3::ONE }
    } else {
        b
    }
}

fn random_ray(b: &Aabb, rng: &mut Pcg64) -> Ray {
    let t = Vec3::new(rng.gen(), rng.gen(), rng.gen());
    Ray::new(b.min + t * (b.max - b.min), sample_uniform_sphere([rng.gen(), rng.gen()]))
}

fn camera_rays(b: &Aabb, cam: Option<CameraLike>, n: usize) -> Vec<Ray> {
    let (centre, radius) = b.bounding_sphere();
    let radius = if radius > 0.0 { radius } else { 1.0 };
    let cam = cam.unwrap_or(CameraLike {
        eye: centre + Vec3::new(0.35, 0.5, 1.0).normalize() * 2.5 * radius,
        target: centre,
    });
    let forward = (cam.target - cam.eye).try_normalize().unwrap_or(-Vec3::Z);
    let dist = (cam.target - cam.eye).length();
    // Frame the bounding sphere from outside; 45° half-angle from inside it.
    let tan_half = if dist > radius { 1.1 * radius / (dist * dist - radius * radius).sqrt() } else { 1.0 };
    let vfov = (2.0 * tan_half.atan()).to_degrees().clamp(1e-3, 179.0);
    let up = if forward.y.abs() < 0.99 { Vec3::Y } else { Vec3::X };
    let side = (n as f64).sqrt().ceil().max(1.0) as usize;
    // One ray through the centre of each pixel of a square side x side film. The frame is built
    // at the origin (the eye may be far out, where eye + forward would round) and moved.
    let camera = Camera::look_at(Vec3::ZERO, forward, up, vfov, side as u32, side as u32)
        .map(|c| Camera { eye: cam.eye, ..c })
        .expect("a unit forward, an up not parallel to it and a field of view in (0, 180)");
    (0..n).map(|k| camera.ray((k % side) as f32 + 0.5, (k / side) as f32 + 0.5)).collect()
}

/// Generates `n` rays, about a fifth of each [`RayKind`], deterministically from `seed`.
/// `camera_like` sets the camera rays' eye and target; by default the eye is outside the
/// bounds looking at their centre. Meshes without any area get random rays instead of the
/// surface-based kinds.
pub fn generate_rays(
    mesh: &TriangleMesh,
    camera_like: Option<CameraLike>,
    n: usize,
    seed: u64,
) -> Vec<(RayKind, Ray)> {
    let bounds = scene_bounds(mesh);
    let surf = SurfaceSampler::new(mesh);
    let mut out = Vec::with_capacity(n);
    for (k, kind) in RayKind::ALL.into_iter().enumerate() {
        let count = n / 5 + usize::from(k < n % 5);
        let mut rng = Pcg64::seed_from_u64(seed ^ (0x9e37_79b9_7f4a_7c15u64.wrapping_mul(k as u64 + 1)));
        if kind == RayKind::Camera {
            out.extend(camera_rays(&bounds, camera_like, count).into_iter().map(|r| (kind, r)));
            continue;
        }
        for _ in 0..count {
            let ray = match kind {
                RayKind::Surface => surf.sample(&mut rng).map(|(p, n, err)| {
                    let n = if rng.gen::<bool>() { n } else { -n };
                    let u = [rng.gen(), rng.gen()];
                    // Cosine-weighted half the time, uniform over the hemisphere otherwise.
                    let local = if rng.gen::<bool>() {
                        sample_cosine_hemisphere(u)
                    } else {
                        sample_uniform_hemisphere(u)
                    };
                    Ray::new(offset_ray_origin(p, err, n), Frame::from_z(n).from_local(local))
                }),
                RayKind::Grazing => surf.sample(&mut rng).map(|(p, n, err)| {
                    let n = if rng.gen::<bool>() { n } else { -n };
                    let phi = std::f32::consts::TAU * rng.gen::<f32>();
                    // Log-uniform elevation between 0.01° and 1° (the polar angle's complement).
                    let elev = (0.01f32 * 100f32.powf(rng.gen::<f32>())).to_radians();
                    let local = spherical_direction(elev.cos(), elev.sin(), phi);
                    Ray::new(offset_ray_origin(p, err, n), Frame::from_z(n).from_local(local))
                }),
                RayKind::Shadow => {
                    surf.sample(&mut rng).zip(surf.sample(&mut rng)).and_then(|((p, np, ep), (q, nq, eq))| {
                        let d = q - p;
                        let o = offset_ray_origin(p, ep, if np.dot(d) >= 0.0 { np } else { -np });
                        let e = offset_ray_origin(q, eq, if nq.dot(d) <= 0.0 { nq } else { -nq });
                        let dir = e - o;
                        (dir != Vec3::ZERO).then(|| Ray::segment(o, dir, 0.0, 0.999))
                    })
                }
                RayKind::Camera | RayKind::Random => None,
            };
            out.push((kind, ray.unwrap_or_else(|| random_ray(&bounds, &mut rng))));
        }
    }
    out
}

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
    let empty = || [KindReport::default(); 5];
    let per = rays
        .par_iter()
        .fold(empty, |mut acc, (kind, ray)| {
            let r = &mut acc[*kind as usize];
            r.rays += 1;
            let (ha, hb) = (a.intersect(ray), b.intersect(ray));
            let verdict = classify_ray(mesh, Some(ray), ha, hb);
            match verdict {
                Verdict::Agree { rel_dt } => r.max_rel_dt = r.max_rel_dt.max(rel_dt.unwrap_or(0.0)),
                Verdict::HitMiss => r.hit_miss_disagreements += 1,
                Verdict::Primitive => r.primitive_disagreements += 1,
                Verdict::EdgeTie => r.edge_ties += 1,
            }
            let (oa, ob) = (a.occluded(ray), b.occluded(ray));
            if oa != ob {
                let occluder = if oa { ha } else { hb };
                if occluder.is_some_and(|h| ambiguous(mesh, Some(ray), &h)) {
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
) -> Vec<AgreeReport> {
    let mut out = vec![compare(a, b, rays, mesh)];
    if let Some(r) = reference {
        out.push(compare(a, r, rays, mesh));
        out.push(compare(b, r, rays, mesh));
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
/// camera) and compares them.
pub fn agree_scene(
    scene: &crate::scene::Scene,
    n: usize,
    seed: u64,
    options: crate::accel::AccelOptions,
) -> Result<SceneAgreement, crate::accel::AccelError> {
    let eye = scene.camera.eye;
    let camera = CameraLike { eye, target: eye + scene.camera.forward };
    agree_mesh(&scene.mesh, Some(camera), n, seed, options, NAIVE_BUDGET)
}

/// [`agree_scene`] on a mesh, with brute force held to `budget` triangles × rays.
fn agree_mesh(
    mesh: &TriangleMesh,
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
    let bvh = Bvh::build(mesh);
    #[cfg(feature = "embree")]
    {
        let naive_ok = mesh.len() as u64 * rays.len() as u64 <= budget;
        let naive = naive_ok.then(|| Naive::new(mesh));
        let embree = crate::accel::embree::EmbreeAccel::build(mesh, options)?;
        let mut reports =
            compare_with_reference(&embree, &bvh, naive.as_ref().map(|n| n as &dyn Accel), &rays, mesh);
        let main = reports.remove(0);
        Ok(SceneAgreement { main, against_naive: reports, generated_rays })
    }
    #[cfg(not(feature = "embree"))]
    {
        let _ = options;
        // Never the BVH against itself: brute force, on as many of the rays as the budget allows.
        let main = compare(&bvh, &Naive::new(mesh), &within_budget(&rays, mesh.len(), budget), mesh);
        Ok(SceneAgreement { main, against_naive: Vec::new(), generated_rays })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::naive::Naive;

    fn tri(scale: f32) -> TriangleMesh {
        TriangleMesh {
            positions: vec![Vec3::ZERO, Vec3::X * scale, Vec3::Y * scale, Vec3::X * 2.0 * scale],
            indices: vec![[0, 1, 2], [0, 1, 3]],
        }
    }

    fn hit(prim: u32, t: f32, u: f32, v: f32) -> Hit {
        Hit { t, prim, u, v }
    }

    #[test]
    fn near_edge_interior_edges_vertices_and_degenerate() {
        for s in [1e-3, 1.0, 1e4] {
            let m = tri(s);
            assert!(!near_edge(&m, &hit(0, 1.0, 0.3, 0.3)), "centre at scale {s}");
            assert!(!near_edge(&m, &hit(0, 1.0, 0.01, 0.5)), "1% from an edge at scale {s}");
            assert!(near_edge(&m, &hit(0, 1.0, 0.5, 0.5)), "hypotenuse at scale {s}");
            assert!(near_edge(&m, &hit(0, 1.0, 0.0, 0.4)), "edge u = 0 at scale {s}");
            assert!(near_edge(&m, &hit(0, 1.0, 3e-6, 0.4)), "within 1e-5 at scale {s}");
            assert!(near_edge(&m, &hit(0, 1.0, 1.0, 0.0)), "vertex at scale {s}");
            assert!(near_edge(&m, &hit(1, 1.0, 0.3, 0.3)), "degenerate at scale {s}");
        }
        // Far from the origin, a few ULPs of the coordinates is more than 1e-5 of a small triangle.
        let mut m = tri(1.0);
        m.positions.iter_mut().for_each(|p| *p += Vec3::splat(1e4));
        assert!(near_edge(&m, &hit(0, 1.0, 1e-4, 0.4)));
        assert!(!near_edge(&m, &hit(0, 1.0, 0.2, 0.4)));
    }

    #[test]
    fn classify_verdicts() {
        let m = tri(1.0);
        let inner = hit(0, 2.0, 0.3, 0.3);
        assert_eq!(classify(&m, None, None), Verdict::Agree { rel_dt: None });
        assert_eq!(classify(&m, Some(inner), None), Verdict::HitMiss);
        assert_eq!(classify(&m, None, Some(hit(0, 2.0, 0.5, 0.5))), Verdict::EdgeTie);
        assert_eq!(
            classify(&m, Some(inner), Some(hit(0, 2.0, 0.3, 0.3))),
            Verdict::Agree { rel_dt: Some(0.0) }
        );
        let other = TriangleMesh {
            positions: [
                m.positions.clone(),
                vec![Vec3::Z, Vec3::new(1.0, 0.0, 1.0), Vec3::new(0.0, 1.0, 1.0)],
            ]
            .concat(),
            indices: vec![[0, 1, 2], [0, 1, 3], [4, 5, 6]],
        };
        assert_eq!(classify(&other, Some(inner), Some(hit(2, 3.0, 0.3, 0.3))), Verdict::Primitive);
        // Same distance, different triangles (coplanar overlap): a tie.
        assert_eq!(classify(&other, Some(inner), Some(hit(2, 2.0, 0.3, 0.3))), Verdict::EdgeTie);
    }

    #[test]
    fn rays_are_deterministic_finite_and_mixed() {
        let m = tri(1.0);
        let a = generate_rays(&m, None, 1003, 7);
        assert_eq!(a, generate_rays(&m, None, 1003, 7));
        assert_ne!(a, generate_rays(&m, None, 1003, 8));
        assert_eq!(a.len(), 1003);
        for kind in RayKind::ALL {
            assert!(a.iter().filter(|(k, _)| *k == kind).count() >= 200);
        }
        for (kind, r) in &a {
            assert!(r.origin.is_finite() && r.dir.is_finite() && r.dir != Vec3::ZERO, "{kind:?}");
            if *kind == RayKind::Shadow {
                assert!(r.t_max < 1.0);
            }
        }
        let naive = Naive::new(&m);
        let report = compare(&naive, &naive, &a, &m);
        assert!(report.clean() && report.edge_ties == 0, "{report}");
        let json = serde_json::to_value(&report).unwrap();
        for key in ["rays", "hit_miss_disagreements", "edge_ties", "primitive_disagreements"] {
            assert!(json.get(key).is_some(), "{key}");
        }
        assert!(json["per_kind"]["camera"]["rays"].as_u64().unwrap() > 0);
        // Empty meshes still get rays (random ones).
        assert_eq!(generate_rays(&TriangleMesh::default(), None, 10, 1).len(), 10);
    }

    /// Brute force that loses every hit on triangle 0: a backend that is wrong on purpose.
    struct LosesTriangle0(Naive);

    impl Accel for LosesTriangle0 {
        fn name(&self) -> &'static str {
            "loses-triangle-0"
        }

        fn intersect(&self, ray: &Ray) -> Option<Hit> {
            self.0.intersect(ray).filter(|h| h.prim != 0)
        }

        fn occluded(&self, ray: &Ray) -> bool {
            self.intersect(ray).is_some()
        }
    }

    #[test]
    fn a_wrong_backend_disagrees_and_one_compared_with_itself_never_does() {
        // A tetrahedron: every kind of ray hits its faces, triangle 0 among them.
        let m = TriangleMesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z],
            indices: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        };
        let rays = generate_rays(&m, None, 1000, 3);
        let (naive, wrong) = (Naive::new(&m), LosesTriangle0(Naive::new(&m)));
        let r = compare(&wrong, &naive, &rays, &m);
        assert!(!r.clean(), "{r}");
        assert!(r.hit_miss_disagreements > 20 && r.occlusion_disagreements > 20, "{r}");
        // The same wrong backend against itself finds nothing: such a check cannot fail.
        assert!(compare(&wrong, &wrong, &rays, &m).clean());
    }

    #[test]
    fn within_budget_spreads_the_subset_over_every_kind() {
        let rays = generate_rays(&tri(1.0), None, 1000, 5);
        assert_eq!(within_budget(&rays, 2, 2000), rays);
        assert_eq!(within_budget(&rays, 0, 0), rays);
        let sub = within_budget(&rays, 2, 200);
        assert_eq!(sub.len(), 100);
        for kind in RayKind::ALL {
            assert_eq!(sub.iter().filter(|(k, _)| *k == kind).count(), 20, "{kind:?}");
        }
        assert!(within_budget(&rays, 2, 1).is_empty());
    }

    /// However large the scene, the main comparison is of two different backends and casts
    /// rays, or it is not run and not clean. Without Embree it is the BVH against brute force,
    /// on a subset of the rays when brute force's budget is short.
    #[test]
    fn scene_agreement_never_compares_a_backend_with_itself() {
        let m = tri(1.0);
        let options = crate::accel::AccelOptions::default();
        for budget in [NAIVE_BUDGET, 2 * 100] {
            let r = agree_mesh(&m, None, 1000, 9, options, budget).unwrap();
            assert_ne!(r.main.backends[0], r.main.backends[1], "{r}");
            assert_eq!(r.generated_rays, 1000);
            assert!(r.ran() && r.clean(), "{r}");
            if cfg!(not(feature = "embree")) {
                assert_eq!(r.main.backends, ["bvh", "naive"]);
                let expected = if budget == NAIVE_BUDGET { 1000 } else { 100 };
                assert_eq!(r.main.rays, expected, "{r}");
            }
        }
        if cfg!(not(feature = "embree")) {
            let r = agree_mesh(&m, None, 1000, 9, options, 1).unwrap();
            assert!(!r.ran() && !r.clean(), "{r}");
            assert!(r.to_string().contains("not run"), "{r}");
        }
    }
}
