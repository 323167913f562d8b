//! The camera pass: primary rays, mirrors and glass followed recursively, and at the first
//! diffuse or glossy surface the sum the lecture prescribes: direct light by shadow rays,
//! caustics from the caustic map, indirect light from the indirect map (radiance estimate) or
//! by final gathering (Jensen 1996).

use super::direct::direct_light;
use super::{Counters, Shared};
use crate::accel::{Accel, Hit};
use crate::config::{Component, IndirectMode, Integrator};
use crate::geometry::{offset_ray_origin, Ray};
use crate::material::{face_forward, Material};
use crate::photon::irradiance::Irradiance;
use crate::photon::kdtree::Neighbor;
use crate::photon::map::PhotonMaps;
use glam::Vec3;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg32;

/// Per-thread scratch buffers reused across pixels.
#[derive(Default)]
pub struct Scratch {
    pub neighbors: Vec<Neighbor>,
    /// A pixel's primary rays and their hits, traced as one coherent batch.
    pub rays: Vec<Ray>,
    pub hits: Vec<Option<Hit>>,
}

/// A surface point reached by a ray.
#[derive(Clone, Copy, Debug)]
pub struct SurfaceHit {
    pub p: Vec3,
    /// Bound on the rounding error of `p`, for robust ray origins.
    pub err: Vec3,
    /// Unit geometric normal (front side as wound).
    pub n: Vec3,
    pub prim: u32,
    pub t: f32,
}

impl SurfaceHit {
    /// A robust origin for a ray leaving this point toward `w`.
    #[inline]
    pub fn spawn(&self, w: Vec3) -> Vec3 {
        offset_ray_origin(self.p, self.err, face_forward(self.n, w))
    }
}

impl<A: Accel> Shared<'_, A> {
    /// Closest surface along `ray`, with a usable normal (degenerate triangles are skipped as
    /// misses, which they are for every backend).
    #[inline]
    pub fn trace(&self, ray: &Ray) -> Option<SurfaceHit> {
        self.surface(self.accel.intersect(ray)?)
    }

    /// The surface point of a backend's hit (`None` on a degenerate triangle).
    #[inline]
    pub fn surface(&self, hit: Hit) -> Option<SurfaceHit> {
        let n = self.scene.mesh.normal(hit.prim)?;
        let (p, err) = self.scene.mesh.point_and_error(hit.prim, hit.u, hit.v);
        Some(SurfaceHit { p, err, n, prim: hit.prim, t: hit.t })
    }

    /// Mean radiance of the samples of pixel `(px, py)`, by the photon mapper or, with
    /// `--integrator path`, the path tracer ([`super::path`]).
    pub fn pixel(&self, px: u32, py: u32, rng: &mut Pcg32, scratch: &mut Scratch, c: &mut Counters) -> Vec3 {
        let mut rays = std::mem::take(&mut scratch.rays);
        let mut hits = std::mem::take(&mut scratch.hits);
        self.camera_rays(px, py, &mut rays, &mut hits, c);
        let mut sum = Vec3::ZERO;
        let mut good = 0u32;
        let path = self.cfg.integrator == Integrator::Path;
        for (ray, hit) in rays.iter().zip(&hits) {
            let l = if path {
                super::path::radiance_path_from(self, *ray, *hit, rng, c)
            } else {
                self.radiance_from(*ray, *hit, rng, scratch, c)
            };
            if l.is_finite() {
                sum += l;
                good += 1;
            } else {
                c.nonfinite += 1;
            }
        }
        scratch.rays = rays;
        scratch.hits = hits;
        if good == 0 {
            Vec3::ZERO
        } else {
            sum / good as f32
        }
    }

    /// The `spp` primary rays of pixel `(px, py)` and their hits, traced as one coherent batch
    /// (Embree traces them as packets). The positions in the pixel are the pass's stretch of a
    /// Halton sequence rotated per pixel (the rotation depends on the render's seed and the
    /// pixel only), so the samples of all passes together stay stratified.
    pub fn camera_rays(
        &self,
        px: u32,
        py: u32,
        rays: &mut Vec<Ray>,
        hits: &mut Vec<Option<Hit>>,
        c: &mut Counters,
    ) {
        let pixel = py as u64 * self.scene_camera.width as u64 + px as u64;
        let mut rotation = Pcg32::seed_from_u64(crate::photon::trace::mix(self.pixel_seed, 0x5A3D1E, pixel));
        let offset = [rotation.gen(), rotation.gen()];
        rays.clear();
        for s in 0..self.cfg.spp as u64 {
            let [jx, jy] = crate::sampling::halton2(self.first_sample + s, offset);
            rays.push(self.scene_camera.ray(px as f32 + jx, py as f32 + jy));
        }
        hits.clear();
        hits.resize(rays.len(), None);
        self.accel.intersect_batch(rays, hits);
        c.rays.camera += rays.len() as u64;
    }

    /// Radiance arriving along a camera ray.
    pub fn radiance(&self, ray: Ray, rng: &mut Pcg32, scratch: &mut Scratch, c: &mut Counters) -> Vec3 {
        c.rays.camera += 1;
        self.radiance_from(ray, self.accel.intersect(&ray), rng, scratch, c)
    }

    /// Radiance arriving along a camera ray whose first hit `first` is already known.
    pub fn radiance_from(
        &self,
        mut ray: Ray,
        first: Option<Hit>,
        rng: &mut Pcg32,
        scratch: &mut Scratch,
        c: &mut Counters,
    ) -> Vec3 {
        let mut beta = Vec3::ONE;
        let mut l = Vec3::ZERO;
        for depth in 0..=self.cfg.max_depth {
            let hit = if depth == 0 {
                first.and_then(|h| self.surface(h))
            } else {
                c.rays.specular += 1;
                self.trace(&ray)
            };
            let Some(hit) = hit else { break };
            let m = self.scene.material(hit.prim);
            let wo = -ray.dir.normalize();
            // Emission seen directly or through mirrors and glass (direct light at diffuse
            // surfaces comes from shadow rays instead).
            if self.cfg.component.shows(Component::Emitted) {
                l += beta * m.emitted(hit.n, wo);
            }
            if m.is_specular() {
                if depth == self.cfg.max_depth {
                    break;
                }
                let Some(s) = m.sample(hit.n, wo, rng.gen(), [rng.gen(), rng.gen()]) else { break };
                beta *= s.weight(hit.n);
                if beta.max_element() <= 0.0 {
                    break;
                }
                ray = Ray::new(hit.spawn(s.wi), s.wi);
                continue;
            }
            l += beta * self.shade(&hit, wo, m, rng, scratch, c);
            break;
        }
        l
    }

    /// Reflected radiance toward `wo` at a diffuse or glossy surface.
    fn shade(
        &self,
        hit: &SurfaceHit,
        wo: Vec3,
        m: &Material,
        rng: &mut Pcg32,
        scratch: &mut Scratch,
        c: &mut Counters,
    ) -> Vec3 {
        let only = self.cfg.component;
        let mut l = Vec3::ZERO;
        if only.shows(Component::Direct) {
            l += direct_light(self, hit, wo, m, self.cfg.light_samples, rng, c);
        }
        if !self.maps.caustic.is_empty() && only.shows(Component::Caustic) {
            c.queries += self.maps.caustic.len() as u64;
            l += PhotonMaps::radiance(
                &self.maps.caustic,
                hit.p,
                hit.n,
                wo,
                m,
                &self.caustic_gather,
                &mut scratch.neighbors,
            );
        }
        if !self.maps.indirect.is_empty() && only.shows(Component::Indirect) {
            l += match self.cfg.indirect {
                IndirectMode::Estimate => match self.cached_irradiance(hit, wo, m, scratch, c) {
                    Some(e) => e.indirect,
                    None => {
                        c.queries += self.maps.indirect.len() as u64;
                        let (maps, g) = (&self.maps.indirect, &self.gather);
                        PhotonMaps::radiance(maps, hit.p, hit.n, wo, m, g, &mut scratch.neighbors)
                    }
                },
                IndirectMode::FinalGather => self.final_gather(hit, wo, m, rng, scratch, c),
            };
        }
        l
    }

    /// Reflected radiance at a Lambertian surface from the precomputed irradiance, by kind of
    /// path, or `None` (not Lambertian, no cache, or no site near enough).
    #[inline]
    fn cached_irradiance(
        &self,
        hit: &SurfaceHit,
        wo: Vec3,
        m: &Material,
        scratch: &mut Scratch,
        c: &mut Counters,
    ) -> Option<Irradiance> {
        let kd = m.lambertian()?;
        if self.cache.is_empty() {
            return None;
        }
        c.queries += 1;
        let e = self.cache.lookup(hit.p, face_forward(hit.n, wo), &mut scratch.neighbors)?;
        let f = kd * std::f32::consts::FRAC_1_PI;
        Some(Irradiance { direct: f * e.direct, indirect: f * e.indirect, caustic: f * e.caustic })
    }

    /// Jensen's final gather: `final_gather_rays` BRDF-sampled rays; where each lands on a
    /// diffuse or glossy surface (after any mirrors and glass), the radiance leaving it toward
    /// the gather point: on Lambertian surfaces from the precomputed direct, indirect and caustic
    /// irradiance (one lookup, no shadow ray), elsewhere from one shadow ray plus the maps'
    /// estimates. Emission is not counted there: it is direct light at the gather point,
    /// already sampled.
    fn final_gather(
        &self,
        hit: &SurfaceHit,
        wo: Vec3,
        m: &Material,
        rng: &mut Pcg32,
        scratch: &mut Scratch,
        c: &mut Counters,
    ) -> Vec3 {
        let n_rays = self.cfg.final_gather_rays;
        let mut sum = Vec3::ZERO;
        for _ in 0..n_rays {
            let Some(s) = m.sample(hit.n, wo, rng.gen(), [rng.gen(), rng.gen()]) else { continue };
            let mut beta = s.weight(hit.n);
            let mut ray = Ray::new(hit.spawn(s.wi), s.wi);
            for depth in 0..=self.cfg.max_depth {
                c.rays.gather += 1;
                let Some(y) = self.trace(&ray) else { break };
                let my = self.scene.material(y.prim);
                let wy = -ray.dir;
                if my.is_specular() {
                    if depth == self.cfg.max_depth {
                        break;
                    }
                    let Some(s) = my.sample(y.n, wy, rng.gen(), [rng.gen(), rng.gen()]) else { break };
                    beta *= s.weight(y.n);
                    ray = Ray::new(y.spawn(s.wi), s.wi);
                    continue;
                }
                let ly = if let Some(e) = self.cached_irradiance(&y, wy, my, scratch, c) {
                    e.direct + e.indirect + e.caustic
                } else {
                    let mut ly = direct_light(self, &y, wy, my, 1, rng, c);
                    c.queries += (self.maps.caustic.len() + self.maps.indirect.len()) as u64;
                    let nb = &mut scratch.neighbors;
                    ly +=
                        PhotonMaps::radiance(&self.maps.caustic, y.p, y.n, wy, my, &self.caustic_gather, nb);
                    ly += PhotonMaps::radiance(&self.maps.indirect, y.p, y.n, wy, my, &self.gather, nb);
                    ly
                };
                sum += beta * ly;
                break;
            }
        }
        sum / n_rays as f32
    }
}
