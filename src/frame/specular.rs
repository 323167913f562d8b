//! The walk through mirrors and glass that camera rays and final-gather rays take: from a ray
//! (or a primary ray's known hit), specular bounces are sampled until the first diffuse or
//! glossy surface, which is where photon maps, shadow rays and gathers take over; and the ray
//! a camera path sends on through a sharp glossy lobe ([`through_lobe`]).

use super::{Counters, Frame, SurfaceHit};
use crate::accel::{Accel, Hit};
use crate::geometry::Ray;
use crate::material::{Material, TransportMode};
use glam::Vec3;
use rand::Rng;
use rand_pcg::Pcg32;

/// Sharp glossy lobes ([`Material::sharp_lobe`]) a camera path traces before the photon maps
/// estimate a lobe's light instead, as they do a diffuse surface's.
pub const GLOSSY_DEPTH: u32 = 3;

/// The first diffuse or glossy surface a walk reaches.
#[derive(Clone, Copy, Debug)]
pub struct Landing {
    pub hit: SurfaceHit,
    /// Unit direction back along the ray that arrived.
    pub wo: Vec3,
    /// The material there, its textures looked up.
    pub m: Material,
    /// Throughput of the specular bounces behind it.
    pub beta: Vec3,
}

/// Where a walk starts.
#[derive(Clone, Copy, Debug)]
pub enum Start {
    /// A primary ray whose closest hit (or miss) is already known.
    Traced(Ray, Option<Hit>),
    /// A ray still to be traced.
    Ray(Ray),
}

/// What a walk's ray reached.
#[derive(Clone, Copy, Debug)]
pub enum Seen<'a> {
    /// A surface, seen from `wo`.
    Surface { hit: &'a SurfaceHit, wo: Vec3, m: &'a Material },
    /// Nothing: the ray left the scene along `dir`.
    Sky { dir: Vec3 },
}

impl Seen<'_> {
    /// The radiance emitted toward the walk: the surface's emission, or the sky's.
    #[inline]
    pub fn emitted(&self, lights: &crate::light::LightSet) -> Vec3 {
        match *self {
            Seen::Surface { hit, wo, m } => m.emitted(hit.n, wo),
            Seen::Sky { dir } => lights.escaped(dir),
        }
    }
}

/// Follows `start`, carrying throughput `beta`, through at most `max_depth` specular bounces.
/// `visit(seen, beta)` sees every surface reached, the landing included, and the sky if the
/// walk leaves the scene (camera paths add the emission seen); `count` counts each ray traced
/// here. Returns the landing, or `None` if the walk leaves the scene, is absorbed, or runs out
/// of depth.
#[allow(clippy::too_many_arguments)]
pub fn walk<'s, A: Accel>(
    frame: &Frame<'s, A>,
    start: Start,
    mut beta: Vec3,
    max_depth: u32,
    rng: &mut Pcg32,
    c: &mut Counters,
    count: fn(&mut Counters),
    mut visit: impl FnMut(Seen, Vec3),
) -> Option<Landing> {
    let (mut ray, mut first) = match start {
        Start::Traced(ray, hit) => (ray, Some(hit)),
        Start::Ray(ray) => (ray, None),
    };
    for depth in 0..=max_depth {
        let hit = match first.take() {
            Some(hit) => hit.and_then(|h| frame.surface(h)),
            None => {
                count(c);
                frame.trace(&ray, c)
            }
        };
        let Some(hit) = hit else {
            visit(Seen::Sky { dir: ray.dir.normalize() }, beta);
            return None;
        };
        let m = frame.scene.material_at(hit.prim, hit.uv, hit.colour);
        let wo = -ray.dir.normalize();
        visit(Seen::Surface { hit: &hit, wo, m: &m }, beta);
        if !m.is_specular() {
            return Some(Landing { hit, wo, m, beta });
        }
        if depth == max_depth {
            return None;
        }
        let s = hit.normals().sample(&m, wo, rng.gen(), [rng.gen(), rng.gen()], TransportMode::Radiance)?;
        beta *= s.weight;
        if beta.max_element() <= 0.0 {
            return None;
        }
        ray = Ray::new(hit.spawn(s.sample.wi), s.sample.wi);
    }
    None
}

/// The ray a camera path sends on from the landing `v` through its sharp glossy lobe `lobe`
/// (one direction sampled from the lobe alone, its throughput times `scale`), walked through
/// any mirrors and glass: the emission it sees past a mirror or glass (emitters and the sky
/// seen straight along it are the direct light the landing's light samples and BSDF samples
/// take), throughput included, and the next landing (`None` as [`walk`] returns it).
#[allow(clippy::too_many_arguments)]
pub fn through_lobe<'s, A: Accel>(
    frame: &Frame<'s, A>,
    v: &Landing,
    lobe: &Material,
    scale: f32,
    max_depth: u32,
    rng: &mut Pcg32,
    c: &mut Counters,
    count: fn(&mut Counters),
) -> (Vec3, Option<Landing>) {
    let Some(s) =
        v.hit.normals().sample(lobe, v.wo, rng.gen(), [rng.gen(), rng.gen()], TransportMode::Radiance)
    else {
        return (Vec3::ZERO, None);
    };
    let start = Start::Ray(Ray::new(v.hit.spawn(s.sample.wi), s.sample.wi));
    let (mut emitted, mut first) = (Vec3::ZERO, true);
    let landing = walk(frame, start, v.beta * s.weight * scale, max_depth, rng, c, count, |seen, beta| {
        if !first {
            emitted += beta * seen.emitted(frame.lights);
        }
        first = false;
    });
    (emitted, landing)
}
