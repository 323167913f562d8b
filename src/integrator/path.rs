//! An independent unidirectional path tracer (`--integrator path`), a cross-check of the photon
//! mapper that shares only the scene, materials, lights and accelerator with it: no photon map,
//! no precomputed irradiance, no final gather.
//!
//! At each vertex: emission, counted in full when seen by the camera or through a delta
//! (mirror, glass) bounce, and otherwise weighted by the power heuristic against the density
//! with which light sampling from the previous vertex would have picked the same point; next
//! event estimation at non-delta vertices (one light sample and a shadow ray, MIS-weighted
//! against the BSDF density for area lights, weight 1 for delta lights); then a BSDF sample
//! continues the path. Russian roulette starts after the third bounce, survival
//! `min(max throughput component, 0.95)`.
//!
//! Depth: `max_depth` bounds every bounce (diffuse, glossy and specular alike), counted
//! after the camera ray, so emission is gathered at vertices `0..=max_depth` and light is
//! sampled at vertices `0..max_depth`. In the white furnace (albedo `a`, emission `Le`
//! everywhere) the estimate converges to `Le (1 - a^(d+1)) / (1 - a)`. Russian roulette ends
//! diffuse paths long before the default depth (`config::DEFAULT_DEPTH`), which only stops
//! light trapped in glass.

use super::passes::{camera_stage, Pass, PassImage, PassRenderer};
use crate::accel::{Accel, Hit};
use crate::config::PathConfig;
use crate::frame::camera::{for_each_pixel, CameraBatch, SampleMean};
use crate::frame::direct::light_sample;
use crate::frame::{Counters, Frame, Progress};
use crate::geometry::Ray;
use crate::material::TransportMode::Radiance;
use crate::sampling::power_heuristic;
use crate::stats::Stats;
use glam::Vec3;
use rand::Rng;
use rand_pcg::Pcg32;

/// Bounces before Russian roulette may end a path.
pub const RR_START_DEPTH: u32 = 3;

/// Highest survival probability of Russian roulette (so every path ends eventually).
pub const RR_MAX_SURVIVAL: f32 = 0.95;

/// Why the photon stages are skipped.
const PATH_TRACER: &str = "path tracer";

/// The path tracer over a render's passes.
pub struct PathTracer<'f, 'a, A: Accel> {
    frame: &'f Frame<'a, A>,
    cfg: &'f PathConfig,
}

impl<'f, 'a, A: Accel> PathTracer<'f, 'a, A> {
    pub fn new(frame: &'f Frame<'a, A>, cfg: &'f PathConfig) -> Self {
        PathTracer { frame, cfg }
    }
}

impl<A: Accel> PassRenderer for PathTracer<'_, '_, A> {
    fn render_pass(
        &mut self,
        pass: &Pass,
        stats: &mut Stats,
        progress: &dyn Progress,
    ) -> (PassImage, Counters) {
        for stage in ["photons.indirect", "photons.caustic", "irradiance"] {
            stats.skip(stage, PATH_TRACER);
        }
        let frame = self.frame;
        let max_depth = self.cfg.max_depth;
        let mut pixels = vec![(); frame.camera.width as usize * frame.camera.height as usize];
        let (film, c) = camera_stage(stats, progress, frame.camera.height, "always (path tracer)", || {
            let width = frame.camera.width as usize;
            for_each_pixel(
                width,
                &mut pixels,
                pass.seed,
                progress,
                |x, y, _, rng, batch: &mut CameraBatch, c| {
                    frame.camera_rays(&pass.samples, x, y, batch, c);
                    let mut mean = SampleMean::default();
                    for (ray, hit) in batch.rays.iter().zip(&batch.hits) {
                        mean.add(radiance(frame, max_depth, *ray, *hit, rng, c), c);
                    }
                    mean.mean()
                },
            )
        });
        (film.into(), c)
    }

    /// The path tracer's estimate is unbiased.
    fn bias(&self) -> crate::film::sums::Bias {
        crate::film::sums::Bias::Zero
    }
}

/// Radiance arriving along a camera ray whose first hit `first` is already known (traced and
/// counted by the caller, as in a batch of primary rays).
pub fn radiance<A: Accel>(
    s: &Frame<'_, A>,
    max_depth: u32,
    ray: Ray,
    first: Option<Hit>,
    rng: &mut Pcg32,
    c: &mut Counters,
) -> Vec3 {
    trace_radiance(s, max_depth, ray, first, false, rng, c)
}

/// Radiance coming in through a portal from outside, for the photons it emits
/// ([`crate::photon::portal`]): the path tracer from the portal outward, counting only light
/// that met a diffuse or glossy surface (emission seen directly or through mirrors and glass
/// is left out: the lights' own photons bring it in).
pub struct Outside<'f, 'a, A: Accel> {
    pub frame: &'f Frame<'a, A>,
    pub max_depth: u32,
}

impl<A: Accel> crate::photon::portal::Outside for Outside<'_, '_, A> {
    fn incoming(&self, p: Vec3, out: Vec3, rng: &mut Pcg32) -> (Vec3, u64) {
        let mut c = Counters::default();
        let ray = Ray::new(p, out);
        let first = self.frame.accel.intersect(&ray);
        let l = trace_radiance(self.frame, self.max_depth, ray, first, true, rng, &mut c);
        (l, 1 + c.rays.path + c.rays.shadow)
    }
}

/// The path tracer's loop; `bounced_only`: emission counts only after a diffuse or glossy
/// vertex.
fn trace_radiance<A: Accel>(
    s: &Frame<'_, A>,
    max_depth: u32,
    mut ray: Ray,
    first: Option<Hit>,
    bounced_only: bool,
    rng: &mut Pcg32,
    c: &mut Counters,
) -> Vec3 {
    let mut diffuse_behind = !bounced_only;
    let mis = s.lights.has_hittable();
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
            s.trace(&ray, c)
        };
        let Some(hit) = hit else {
            // The sky, reached by the camera ray or the previous vertex's BSDF sample.
            let dir = ray.dir.normalize();
            let le = s.lights.escaped(dir);
            if le != Vec3::ZERO && diffuse_behind {
                let w = if specular || !mis {
                    1.0
                } else {
                    power_heuristic(1.0, prev_pdf, 1.0, s.lights.pdf_li_escaped(dir))
                };
                l += beta * le * w;
            }
            break;
        };
        let m = &s.scene.material_at(hit.prim, hit.uv, hit.colour);
        let wo = -ray.dir.normalize();

        // Emission reached by the camera ray or by the previous vertex's BSDF sample.
        let le = m.emitted(hit.n, wo);
        if le != Vec3::ZERO && diffuse_behind {
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
            l += beta * light_sample(s, &hit, wo, m, true, rng, c);
        }

        // Continue by sampling the BSDF.
        let Some(scattered) = hit.normals().sample(m, wo, rng.gen(), [rng.gen(), rng.gen()], Radiance) else {
            break;
        };
        let bs = scattered.sample;
        if !(bs.pdf > 0.0) {
            break;
        }
        beta *= scattered.weight;
        if !(beta.max_element() > 0.0) || !beta.is_finite() {
            break;
        }
        specular = bs.delta;
        diffuse_behind |= !bs.delta;
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
