//! Probing a surface for a gather disc's [`Footprint`]: rays cast down onto the surface around
//! a point find the walls standing on it and the edges where it ends within the disc.
//!
//! Where a wall stands on the surface within the gather radius (a room's corners and edges, a
//! block on the floor, a thin wall standing on it), or the surface ends (a block's top, a
//! slab's edge, a column curving away), the disc reaches past it: its part beyond holds no
//! photons of this surface, so photons over `π r²` made every edge too dark, and it may hold
//! photons of the surface on a thin wall's far side (light leaked under the wall).
//!
//! In each of `PROBES` evenly spaced directions, turned by a random angle, a ray from a point
//! `r / √8` above the surface point is aimed at the surface where the disc's rim should be,
//! and goes on to as deep below it. It meets a wall (a surface at more than 60° to this one) at
//! or before the rim: the footprint ends at the wall's foot (pulled back by `r / 1000`, so that
//! the wall's own photons, over its foot, stay out). It meets a surface (within 60°) there:
//! the surface reaches the rim in that direction. It meets nothing, or a wall beyond the rim:
//! the surface ends before the rim, and the aim is halved (then moved a quarter back out if
//! that finds it), two more rays at most. The footprint is the disc within the polygon of the
//! probes' end points; photons count only over it and the estimate divides by its area. Every
//! end point lies on the surface, so on a surface bounded by straight walls and convex edges
//! the polygon stays on it, whatever the number of probes, and the photons counted and the
//! area agree exactly; what it does not see are walls and edges between two probes that miss
//! them. The progressive modes probe at their visible points, two-pass photon mapping at its
//! irradiance sites and radiance estimates.

use crate::accel::Accel;
use crate::frame::{Counters, Frame, SurfaceHit};
use crate::geometry::{offset_ray_origin, Ray};
use crate::photon::footprint::{Footprint, LEAST_SHARE, PROBES};
use glam::{Vec2, Vec3};
use rand::Rng;
use rand_pcg::Pcg32;

/// What a probe found along one direction.
enum Reach {
    /// The surface reaches this far (as aimed).
    Surface,
    /// A wall stands on the surface at this distance.
    Wall(f32),
    /// The surface ends before the aim.
    Edge,
}

/// Probes the surface of `hit` (unit normal `ns` on the viewer's side) within the squared
/// radius `r2`. Where less than a quarter of the disc lies on the surface (a strip narrower
/// than the disc, such as the side of a thin slab), the footprint is also cut from a disc
/// of a quarter of the radius, and again if need be, and the largest kept: an estimate over
/// a small footprint is noisy, but skipping it would leave such surfaces dark. Eight probes
/// keep two in the open quarter of a right-angled corner, so that a footprint there is
/// never less than an eighth of the disc (with six, one probe in it made the footprint
/// vanish: nothing counted there, or, cut from ever smaller discs, a few photons weighted
/// by thousands).
pub(super) fn probe<A: Accel>(
    frame: &Frame<'_, A>,
    hit: &SurfaceHit,
    ns: Vec3,
    r2: f32,
    rng: &mut Pcg32,
    c: &mut Counters,
) -> Footprint {
    let mut fp = cut_from(frame, hit, ns, r2, rng, c);
    let mut shrink = 1.0;
    while fp.share < 0.25 && shrink < 256.0 {
        shrink *= 16.0;
        let small = cut_from(frame, hit, ns, r2 / shrink, rng, c);
        // The largest footprint, for the most photons: near a corner the smaller disc is cut
        // the same way (and would only be noisier), in a narrow strip it is cut far less.
        if small.share / shrink > fp.share {
            fp = Footprint { share: small.share / shrink, ..small };
        }
    }
    // A footprint filling almost none of its own disc (a visible point on the very edge
    // where two surfaces meet, whose lifted probe origin lands past the other surface) would
    // weigh its few photons by thousands: a pixel of the Cornell box's top edge came out 9,000
    // times too bright in one pass at k = 60. Its area is taken as no less than
    // `LEAST_SHARE` of the disc: a bounded weight, and a little light lost on such points.
    let least = LEAST_SHARE * fp.r2 / r2;
    if fp.share < least {
        fp.share = least;
    }
    fp
}

/// Whether the probes find the surface of `hit` filling the whole disc of squared radius
/// `r2` (no wall standing on it and no edge within it).
pub(super) fn clear<A: Accel>(
    frame: &Frame<'_, A>,
    hit: &SurfaceHit,
    ns: Vec3,
    r2: f32,
    rng: &mut Pcg32,
    c: &mut Counters,
) -> bool {
    !cut_from(frame, hit, ns, r2, rng, c).cut
}

/// The footprint within the disc of squared radius `r2`, probed once.
fn cut_from<A: Accel>(
    frame: &Frame<'_, A>,
    hit: &SurfaceHit,
    ns: Vec3,
    r2: f32,
    rng: &mut Pcg32,
    c: &mut Counters,
) -> Footprint {
    let r = r2.sqrt();
    let step = std::f32::consts::TAU / PROBES as f32;
    // The polygon of probes that reach the rim circumscribes the disc.
    let far = r / (0.5 * step).cos();
    let lift = r * std::f32::consts::FRAC_1_SQRT_2 * 0.5;
    let (t1, t2) = ns.any_orthonormal_pair();
    let theta0 = rng.gen::<f32>() * step;
    let origin = offset_ray_origin(hit.p, hit.err, ns) + lift * ns;
    let mut probe = |t: Vec3, aim: f32| {
        c.rays.gather += 1;
        // At parameter 1 the ray reaches the surface's plane at `aim`, at 2 as far below.
        let ray = Ray::segment(origin, aim * t - lift * ns, 0.0, 2.0);
        match frame.trace(&ray, c) {
            None => Reach::Edge,
            Some(h) => {
                let along = (h.p - hit.p).dot(t);
                if h.n.dot(ns).abs() >= 0.5 {
                    Reach::Surface
                } else if along <= aim {
                    Reach::Wall(along)
                } else {
                    Reach::Edge
                }
            }
        }
    };
    let mut ends = [Vec2::ZERO; PROBES];
    let mut cut = false;
    for (j, end) in ends.iter_mut().enumerate() {
        let (sin, cos) = (theta0 + step * j as f32).sin_cos();
        let t = cos * t1 + sin * t2;
        let reach = match probe(t, far) {
            Reach::Surface => far,
            Reach::Wall(d) => (d - 1e-3 * r).max(0.0),
            Reach::Edge => match probe(t, 0.5 * far) {
                Reach::Surface => match probe(t, 0.75 * far) {
                    Reach::Surface => 0.75 * far,
                    Reach::Wall(d) => (d - 1e-3 * r).max(0.5 * far),
                    Reach::Edge => 0.5 * far,
                },
                Reach::Wall(d) => (d - 1e-3 * r).max(0.0),
                Reach::Edge => match probe(t, 0.25 * far) {
                    Reach::Surface => 0.25 * far,
                    Reach::Wall(d) => (d - 1e-3 * r).max(0.0),
                    Reach::Edge => 0.0,
                },
            },
        };
        cut |= reach < far;
        *end = Vec2::new(cos, sin) * reach;
    }
    if !cut {
        return Footprint::whole(r2);
    }
    Footprint::cut([t1, t2], theta0, ends, r2)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    /// A visible point on the very edge where a wall meets the ceiling, a hair above the
    /// ceiling's plane (as rounding put one on the Cornell box's top edge), lifts its probes'
    /// origin past the ceiling: every probe meets the ceiling's back at once and the footprint
    /// fills next to nothing of its disc. Its photons must not be weighed by thousands (that
    /// pixel came out 9,000 times too bright in one pass at k = 60).
    #[test]
    fn a_footprint_on_an_edge_weighs_its_photons_boundedly() {
        use crate::accel::bvh::Bvh;
        use crate::geometry::TriangleMesh;
        use crate::light::LightSet;
        use crate::material::Material;
        use crate::scene::{Camera, Scene, SceneCamera};
        // A wall x = 1 and a ceiling y = 1 meeting along an edge (two-sided diffuse).
        let positions = vec![
            Vec3::new(1.0, -1.0, -1.0),
            Vec3::new(1.0, 1.0, -1.0),
            Vec3::new(1.0, 1.0, 1.0),
            Vec3::new(1.0, -1.0, 1.0),
            Vec3::new(-1.0, 1.0, -1.0),
            Vec3::new(-1.0, 1.0, 1.0),
        ];
        let indices = vec![[0, 1, 2], [0, 2, 3], [4, 1, 2], [4, 2, 5]];
        let cam = Camera::look_at(Vec3::ZERO, Vec3::X, Vec3::Y, 60.0, 8, 8).unwrap();
        let scene = Scene {
            path: "edge".into(),
            camera: cam,
            cameras: vec![SceneCamera::still("camera", cam)],
            mesh: TriangleMesh { positions, indices },
            attributes: Default::default(),
            tri_material: vec![0; 4],
            materials: vec![Material::Diffuse { kd: Vec3::splat(0.5) }],
            maps: vec![Default::default()],
            textured: false,
            textures: Default::default(),
            warnings: Vec::new(),
            material_names: vec!["white".into()],
            lights: Vec::new(),
            portals: Vec::new(),
            render: Default::default(),
        };
        let accel = Bvh::build(&scene.mesh);
        let lights = LightSet::new(&scene.lights, &scene.mesh, &scene.tri_material, &scene.materials);
        let frame = Frame {
            scene: &scene,
            accel: &accel,
            lights: &lights,
            camera: cam,
            views: std::slice::from_ref(&cam),
        };
        // The wall x = 1 (facing -x), its point on the edge with the ceiling y = 1.
        let ray = Ray::new(Vec3::new(0.0, 1.0 - 1e-3, 0.0), Vec3::X);
        let mut c = Counters::default();
        let mut hit = frame.trace(&ray, &mut c).expect("the wall");
        hit.p = Vec3::new(1.0, 1.0 + 2e-6, 0.0);
        let ns = -Vec3::X;
        let r2 = 0.01;
        let mut rng = Pcg32::seed_from_u64(5);
        for _ in 0..20 {
            let fp = probe(&frame, &hit, ns, r2, &mut rng, &mut c);
            let own = fp.share * r2 / fp.r2;
            assert!(own >= LEAST_SHARE, "the footprint fills {own} of its disc");
        }
    }
}
