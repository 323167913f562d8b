//! The rays the backends are compared on: a deterministic mix that stresses different parts of
//! an accelerator.

use crate::geometry::{offset_ray_origin, Aabb, Ray, TriangleMesh, Vec3};
use crate::sampling::{
    sample_cosine_hemisphere, sample_uniform_hemisphere, sample_uniform_sphere, sample_uniform_triangle,
    spherical_direction, Distribution1D, Frame,
};
use crate::scene::Camera;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;
use serde::Serialize;

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
