//! An independent unidirectional path tracer (`--integrator path`), a cross-check of the photon
//! mapper that shares only the scene, materials, lights and accelerator with it: no photon map,
//! no irradiance cache, no final gather.
//!
//! At each vertex: emission, counted in full when seen by the camera or through a delta
//! (mirror, glass) bounce, and otherwise weighted by the power heuristic against the density
//! with which light sampling from the previous vertex would have picked the same point; next
//! event estimation at non-delta vertices (one light sample and a shadow ray, MIS-weighted
//! against the BSDF density for area lights, weight 1 for delta lights); then a BSDF sample
//! continues the path. Russian roulette starts after the third bounce, survival
//! `min(max throughput component, 0.95)`.
//!
//! Depth: `cfg.max_depth` bounds every bounce (diffuse, glossy and specular alike), counted
//! after the camera ray, so emission is gathered at vertices `0..=max_depth` and light is
//! sampled at vertices `0..max_depth`. In the white furnace (albedo `a`, emission `Le`
//! everywhere) the estimate converges to `Le (1 - a^(d+1)) / (1 - a)`; the default depth 16 is
//! within 8e-6 relative of the infinite-depth value there, so path mode keeps that default.

use super::camera::SurfaceHit;
use super::direct::visible;
use super::{Counters, Shared};
use crate::accel::{Accel, Hit};
use crate::geometry::Ray;
use crate::sampling::power_heuristic;
use glam::Vec3;
use rand::Rng;
use rand_pcg::Pcg32;

/// Bounces before Russian roulette may end a path.
pub const RR_START_DEPTH: u32 = 3;

/// Highest survival probability of Russian roulette (so every path ends eventually).
pub const RR_MAX_SURVIVAL: f32 = 0.95;

/// Radiance arriving along a camera ray (the camera ray is traced and counted here).
pub fn radiance_path<A: Accel>(s: &Shared<'_, A>, ray: Ray, rng: &mut Pcg32, c: &mut Counters) -> Vec3 {
    c.rays.camera += 1;
    radiance_path_from(s, ray, s.accel.intersect(&ray), rng, c)
}

/// Radiance arriving along a camera ray whose first hit `first` is already known (traced and
/// counted by the caller, as in a batch of primary rays).
pub fn radiance_path_from<A: Accel>(
    s: &Shared<'_, A>,
    mut ray: Ray,
    first: Option<Hit>,
    rng: &mut Pcg32,
    c: &mut Counters,
) -> Vec3 {
    let max_depth = s.cfg.max_depth;
    let mis = s.lights.has_area();
    let mut beta = Vec3::ONE;
    let mut l = Vec3::ZERO;
    // The previous vertex, for the MIS weight of emission found by BSDF sampling: whether it was
    // a delta bounce (or the camera), its BSDF density toward this vertex, and its position.
    let mut specular = true;
    let mut prev_pdf = 0.0f32;
    let mut prev_p = Vec3::ZERO;
    for depth in 0..=max_depth {
        let hit = if depth == 0 {
            first.and_then(|h| s.surface(h))
        } else {
            c.rays.path += 1;
            s.trace(&ray)
        };
        let Some(hit) = hit else { break };
        let m = s.scene.material(hit.prim);
        let wo = -ray.dir.normalize();

        // Emission reached by the camera ray or by the previous vertex's BSDF sample.
        let le = m.emitted(hit.n, wo);
        if le != Vec3::ZERO {
            let w = if specular || !mis {
                1.0
            } else {
                power_heuristic(1.0, prev_pdf, 1.0, s.lights.pdf_li_hit(prev_p, hit.prim, hit.p, hit.n))
            };
            l += beta * le * w;
        }
        if depth == max_depth {
            break;
        }

        // Next-event estimation.
        if !m.is_specular() && !s.lights.is_empty() {
            l += beta * light_sample(s, &hit, wo, m, rng, c);
        }

        // Continue by sampling the BSDF.
        let Some(bs) = m.sample(hit.n, wo, rng.gen(), [rng.gen(), rng.gen()]) else { break };
        if !(bs.pdf > 0.0) {
            break;
        }
        beta *= bs.weight(hit.n);
        if !(beta.max_element() > 0.0) || !beta.is_finite() {
            break;
        }
        specular = bs.delta;
        prev_pdf = bs.pdf;
        prev_p = hit.p;
        ray = Ray::new(hit.spawn(bs.wi), bs.wi);

        if depth >= RR_START_DEPTH {
            let q = beta.max_element().min(RR_MAX_SURVIVAL);
            if rng.gen::<f32>() >= q {
                break;
            }
            beta /= q;
        }
    }
    l
}

/// One light sample at a non-delta vertex: `f Li |cos| / pdf`, MIS-weighted against the BSDF
/// density for area lights.
fn light_sample<A: Accel>(
    s: &Shared<'_, A>,
    hit: &SurfaceHit,
    wo: Vec3,
    m: &crate::material::Material,
    rng: &mut Pcg32,
    c: &mut Counters,
) -> Vec3 {
    let Some(ls) = s.lights.sample_li(hit.p, rng.gen(), [rng.gen(), rng.gen()]) else { return Vec3::ZERO };
    let f = m.eval(hit.n, wo, ls.wi);
    if f == Vec3::ZERO || ls.li == Vec3::ZERO || !visible(s, hit, &ls, c) {
        return Vec3::ZERO;
    }
    let w = if ls.delta { 1.0 } else { power_heuristic(1.0, ls.pdf, 1.0, m.pdf(hit.n, wo, ls.wi)) };
    f * ls.li * (hit.n.dot(ls.wi).abs() * w / ls.pdf)
}
