//! Direct light by shadow rays: lights chosen by power, `n` samples per shading point, and
//! when the scene has area lights or a sky one BSDF sample each as well, the two combined by multiple
//! importance sampling (Veach 1997, power heuristic). Light sampling alone is poor where an
//! emitter is close and large (the 1/d^2 of area sampling near a corner of the furnace) and
//! for narrow glossy lobes; BSDF sampling is poor for small lights; MIS keeps the better of
//! the two everywhere. A BSDF sample whose ray can reach neither an emitter's bounds nor a
//! sky is not cast: it would bring nothing (see `light::bounds`).
//!
//! Where MIS cannot pay, the BSDF sample is not taken at all and the light sample weighs 1 (an
//! unbiased estimate either way; the choice depends on the point, not on the random numbers):
//! at a Lambertian point that sees no sky and from which the emitters subtend less than
//! [`MIS_MIN_SOLID_ANGLE`]. A cosine-distributed direction reaches them there with
//! probability under `Ω / π` (a sixth at the threshold), so the BSDF sample is almost always
//! wasted work (on the default Cornell box, 99.5 % of them met nothing, and sampling and
//! testing them took a fifth of the camera stage); and light sampling, whose weight
//! `cos cos' / d²` varies little over an emitter that subtends so little, is already the
//! better of the two.
//!
//! The camera pass of photon mapping puts the light samples' shadow rays off ([`Shadows`]) and
//! casts a pixel's together as packets of 8: they leave from within a pixel's footprint toward
//! the same lights, so Embree traverses them together (camera stage 7 % shorter on the Cornell
//! box, 11 % on the 69 000-triangle bunny; the image is the same but for the rounding of its
//! sums, taken in another order).

use super::{Counters, Frame, Part, SurfaceHit};
use crate::accel::Accel;
use crate::geometry::Ray;
use crate::light::LightSample;
use crate::material::Material;
use crate::material::TransportMode::Radiance;
use crate::sampling::power_heuristic;
use glam::Vec3;
use rand::Rng;
use rand_pcg::Pcg32;

/// Below this bound on the solid angle of the emitters seen from a Lambertian point
/// (steradians; [`crate::light::LightSet::emitters_subtend_less`]), the point's direct
/// light is sampled from the lights alone (see the module's documentation).
pub const MIS_MIN_SOLID_ANGLE: f32 = 0.5;

/// Whether the direct light at `hit` (material `m`) takes BSDF samples beside its light
/// samples, combined by MIS: when BSDF samples can find light at all (emissive triangles, a
/// sky), unless the point is Lambertian, sees no sky and the emitters subtend less than
/// [`MIS_MIN_SOLID_ANGLE`] from it.
#[inline]
pub fn takes_bsdf_samples<A: Accel>(s: &Frame<'_, A>, hit: &SurfaceHit, m: &Material) -> bool {
    let lights = s.lights;
    if !lights.has_hittable() {
        return false;
    }
    lights.has_sky() || m.lambertian().is_none() || !lights.emitters_subtend_less(hit.p, MIS_MIN_SOLID_ANGLE)
}

/// Shadow rays stop this fraction short of the light sample, so they never hit the emitter
/// itself.
pub const SHADOW_MARGIN: f32 = 1e-4;

/// The shadow ray from the surface at `hit` toward the light sample `ls`. It leaves from a
/// robust origin and stops short of the sampled point by that point's rounding error
/// (`ls.end_error`, as pbrt-v4's `SpawnRayTo` offsets both ends), then by [`SHADOW_MARGIN`]. A
/// light point within rounding distance is visible: nothing between the two can be resolved.
#[inline]
fn shadow_ray(hit: &SurfaceHit, ls: &LightSample) -> Ray {
    let origin = hit.spawn(ls.wi);
    let t_max = if ls.dist.is_finite() {
        (ls.dist - ls.end_error).max(0.0) * (1.0 - SHADOW_MARGIN)
    } else {
        f32::INFINITY
    };
    Ray::segment(origin, ls.wi, 0.0, t_max)
}

/// Whether the segment from the surface at `hit` toward the light sample `ls` is unblocked: from
/// a robust origin to just short of the sampled point (by its rounding error, then by
/// [`SHADOW_MARGIN`]).
#[inline]
pub fn visible<A: Accel>(s: &Frame<'_, A>, hit: &SurfaceHit, ls: &LightSample, c: &mut Counters) -> bool {
    c.rays.shadow += 1;
    let ray = shadow_ray(hit, ls);
    !c.timed(Part::Rays, || s.accel.occluded(&ray))
}

/// Shadow rays put off, to be cast together: a camera pixel's samples land within a pixel's
/// footprint of each other and their shadow rays head for the same lights, so they are traced
/// as packets ([`Accel::occluded_batch`]) once the pixel's samples are shaded. Each ray
/// carries what it brings if unblocked and the sample it is added to.
#[derive(Debug, Default)]
pub struct Shadows {
    rays: Vec<Ray>,
    values: Vec<(Vec3, u32)>,
    blocked: Vec<bool>,
}

impl Shadows {
    /// Casts the rays put off and adds what each unblocked one brings to `totals[its sample]`;
    /// none is left after.
    pub fn resolve<A: Accel>(&mut self, s: &Frame<'_, A>, totals: &mut [Vec3], c: &mut Counters) {
        self.blocked.clear();
        self.blocked.resize(self.rays.len(), false);
        let (rays, blocked) = (&self.rays, &mut self.blocked);
        c.timed(Part::Rays, || s.accel.occluded_batch(rays, blocked));
        for (&(value, sample), &blocked) in self.values.iter().zip(&self.blocked) {
            if !blocked {
                totals[sample as usize] += value;
            }
        }
        self.rays.clear();
        self.values.clear();
    }
}

/// When a shading point's shadow rays are cast: at once, or put off into `shadows`, what they
/// bring weighted `weight` (the path's throughput to the point) and added to camera sample
/// `sample`'s total when resolved.
pub enum ShadowRays<'a> {
    Now,
    Later { shadows: &'a mut Shadows, sample: u32, weight: Vec3 },
}

/// One light sample at `hit`: a light picked by power, a point on it, and if the shadow ray
/// finds it unblocked `f Li |cos| / pdf`, MIS-weighted against the BSDF density when the light
/// is not a delta light (`mis`: whether BSDF samples can find emitters at all).
#[inline]
#[allow(clippy::too_many_arguments)]
pub fn light_sample<A: Accel>(
    s: &Frame<'_, A>,
    hit: &SurfaceHit,
    wo: Vec3,
    m: &Material,
    mis: bool,
    rng: &mut Pcg32,
    c: &mut Counters,
) -> Vec3 {
    light_sample_with(s, hit, wo, m, mis, 1.0, &mut ShadowRays::Now, rng, c)
}

/// [`light_sample`] with its shadow ray cast as `shadow` says (put off: zero returned, and
/// what it brings, times `scale`, put off with it).
#[inline]
#[allow(clippy::too_many_arguments)]
fn light_sample_with<A: Accel>(
    s: &Frame<'_, A>,
    hit: &SurfaceHit,
    wo: Vec3,
    m: &Material,
    mis: bool,
    scale: f32,
    shadow: &mut ShadowRays<'_>,
    rng: &mut Pcg32,
    c: &mut Counters,
) -> Vec3 {
    let Some(ls) = s.lights.sample_li(hit.p, rng.gen(), [rng.gen(), rng.gen()]) else { return Vec3::ZERO };
    let normals = hit.normals();
    let (f, cos) = normals.eval_parts(m, wo, ls.wi);
    if f == Vec3::ZERO || ls.li == Vec3::ZERO {
        return Vec3::ZERO;
    }
    let value = || {
        let w =
            if mis && !ls.delta { power_heuristic(1.0, ls.pdf, 1.0, normals.pdf(m, wo, ls.wi)) } else { 1.0 };
        f * ls.li * (cos * w / ls.pdf)
    };
    match shadow {
        ShadowRays::Now => {
            if !visible(s, hit, &ls, c) {
                return Vec3::ZERO;
            }
            value()
        }
        ShadowRays::Later { shadows, sample, weight } => {
            c.rays.shadow += 1;
            shadows.rays.push(shadow_ray(hit, &ls));
            shadows.values.push((*weight * (value() * scale), *sample));
            Vec3::ZERO
        }
    }
}

/// Direct radiance reflected toward `wo` at `hit`, averaged over `n` light samples (plus, when
/// the scene has area lights, as many BSDF samples, the two weighted by MIS).
pub fn direct_light<A: Accel>(
    s: &Frame<'_, A>,
    hit: &SurfaceHit,
    wo: Vec3,
    m: &Material,
    n: u32,
    rng: &mut Pcg32,
    c: &mut Counters,
) -> Vec3 {
    direct_light_with(s, hit, wo, m, n, &mut ShadowRays::Now, rng, c)
}

/// [`direct_light`] with the light samples' shadow rays cast as `shadow` says: put off, they
/// are left out of the result and bring their part (over `n`, times the weight) when resolved.
#[allow(clippy::too_many_arguments)]
pub fn direct_light_with<A: Accel>(
    s: &Frame<'_, A>,
    hit: &SurfaceHit,
    wo: Vec3,
    m: &Material,
    n: u32,
    shadow: &mut ShadowRays<'_>,
    rng: &mut Pcg32,
    c: &mut Counters,
) -> Vec3 {
    if s.lights.is_empty() {
        return Vec3::ZERO;
    }
    let hittable = s.lights.has_hittable();
    let mis = takes_bsdf_samples(s, hit, m);
    let mut sum = Vec3::ZERO;
    for _ in 0..n {
        sum += light_sample_with(s, hit, wo, m, mis, 1.0 / n as f32, shadow, rng, c);
        if hittable && !mis {
            // The BSDF sample's numbers are drawn all the same, so that the rest of the camera
            // path and the pixel's later samples take the numbers they would take with it.
            let _: [f32; 3] = [rng.gen(), rng.gen(), rng.gen()];
        }
        // BSDF sampling toward area lights and the sky.
        if mis {
            let Some(scattered) = hit.normals().sample(m, wo, rng.gen(), [rng.gen(), rng.gen()], Radiance)
            else {
                continue;
            };
            let bs = scattered.sample;
            if bs.delta || bs.pdf <= 0.0 {
                continue;
            }
            let ray = Ray::new(hit.spawn(bs.wi), bs.wi);
            // A ray that cannot reach an emitter or the sky brings nothing: not cast.
            if !s.lights.may_find_light(ray.origin, ray.dir) {
                continue;
            }
            c.rays.shadow += 1;
            let found = c.timed(Part::Rays, || s.accel.intersect(&ray));
            // Most BSDF rays land on surfaces that do not emit: known from the triangle's
            // material, before the surface point is worked out.
            if found.is_some_and(|h| s.scene.material(h.prim).emission() == Vec3::ZERO) {
                continue;
            }
            let (le, light_pdf) = match found.and_then(|h| s.surface(h)) {
                Some(y) => {
                    let mut le = s.scene.material(y.prim).emitted(y.n, -bs.wi);
                    if le == Vec3::ZERO {
                        continue;
                    }
                    if s.scene.textured {
                        // An emission texture varies it.
                        le = s.scene.material_at(y.prim, y.uv, y.colour).emitted(y.n, -bs.wi);
                    }
                    (le, s.lights.pdf_li_hit(hit.p, y.prim, y.p, y.n))
                }
                None => (s.lights.escaped(bs.wi), s.lights.pdf_li_escaped(bs.wi)),
            };
            if le == Vec3::ZERO {
                continue;
            }
            let w = power_heuristic(1.0, bs.pdf, 1.0, light_pdf);
            sum += scattered.weight * le * w;
        }
    }
    sum / n as f32
}
