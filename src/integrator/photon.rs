//! Two-pass photon mapping (Jensen 1996, 2001), the renderer proper. Each pass traces the
//! photon maps ([`super::maps`]), picks the sites of precomputed irradiance among the indirect
//! photons (Christensen 1999; their values are estimated as the camera first reads them), then
//! renders every pixel: primary rays through mirrors and glass, and at
//! the first diffuse or glossy surface the sum the lecture prescribes: direct light by shadow
//! rays, caustics from the caustic map, indirect light from the indirect map (radiance
//! estimate) or by final gathering.

use super::maps::{Analysis, GatherPair, MapStages};
use super::passes::{camera_stage, Pass, PassImage, PassRenderer};
use super::probe;
use crate::accel::Accel;
use crate::config::{Component, IndirectMode, PhotonConfig};
use crate::frame::camera::{for_each_pixel, CameraBatch, SampleMean};
use crate::frame::direct::{direct_light, direct_light_with, ShadowRays, Shadows};
use crate::frame::specular::{through_lobe, walk, Landing, Start, GLOSSY_DEPTH};
use crate::frame::{Counters, Frame, Part, Progress, SurfaceHit};
use crate::geometry::Ray;
use crate::material::{face_forward, Material, TransportMode};
use crate::photon::irradiance::{
    Irradiance, LookupScratch, PrecomputedIrradiance, SiteDirect, SitePoint, SiteProbe, SiteSource, Sites,
};
use crate::photon::kdtree::Neighbor;
use crate::photon::map::PhotonMaps;
use crate::sampling::derive_seed;
use crate::stats::{MapStats, Stats, CAUSTIC_SITES, IRRADIANCE_SITES};
use glam::Vec3;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg32;
use std::cell::RefCell;
use std::rc::Rc;
use std::sync::atomic::{AtomicU64, Ordering};

/// Irradiance is precomputed at a site for about every this-many indirect photons (Christensen
/// uses 4): the hits of photon paths of their own, one for every this-many of the map's
/// ([`MapStages::site_stride`]).
const IRRADIANCE_STRIDE: usize = 4;

/// Shadow-ray samples for the direct irradiance of each precomputed site.
const SITE_LIGHT_SAMPLES: u32 = 16;

/// The indirect estimate (radiance estimate or precomputed irradiance) is read at one camera
/// sample in this many, and at no fewer than [`INDIRECT_AT_LEAST`] of a pixel's samples in a
/// pass (all of them below that): the first ones of the pass, weighted by the pass's samples
/// over those read. They are a stretch of the pixel's Halton sequence, so they cover the pixel
/// evenly. The estimate is smooth over a pixel (the precomputed irradiance is even constant
/// over each site's cell, several pixels wide), so at the default 64 samples 16 readings
/// average it over the pixel almost as well as 64, and the readings were a third of the camera
/// stage: measured on the Cornell box, the bunny and the doorway, 17-21 % off the camera stage
/// for an RMSE against the references up by 0.1-0.5 % (a tenth of the spread between seeds).
/// Direct light, caustics (sharp) and final gathering (a Monte Carlo estimate of its own) are
/// taken at every sample.
pub const INDIRECT_EVERY: u32 = 4;

/// The fewest samples of a pixel's pass that read the indirect estimate ([`INDIRECT_EVERY`]):
/// at few samples a pixel, its readings are what average out the estimate's blotches and
/// rounding.
pub const INDIRECT_AT_LEAST: u32 = 4;

/// Camera samples of a pass of `spp` that read the indirect estimate ([`INDIRECT_EVERY`]).
pub fn indirect_samples(spp: u32) -> u32 {
    spp.div_ceil(INDIRECT_EVERY).max(spp.min(INDIRECT_AT_LEAST))
}

/// The two-pass photon mapper over a render's passes.
pub struct PhotonMapper<'f, 'a, A: Accel> {
    frame: &'f Frame<'a, A>,
    cfg: &'f PhotonConfig,
    analysis: &'f Analysis,
    gathers: GatherPair,
    cache: &'f MapCache,
}

/// The photon maps of one pass and the irradiance precomputed from them.
struct PassMaps {
    maps: PhotonMaps,
    irradiance: PrecomputedIrradiance,
    /// Caustic irradiance where caustic site paths land (empty when not precomputed).
    caustic: PrecomputedIrradiance,
    /// The seed of the pass that traced them (the direct light at final-gather sites draws
    /// its samples from it, whichever image of a batch first reads a site).
    seed: u64,
}

/// Each pass's maps, kept (when asked) for the images of a batch after the first: the maps
/// do not depend on the view, so a batch traces them once. Memory: every pass's maps at once.
pub struct MapCache {
    keep: bool,
    passes: RefCell<std::collections::BTreeMap<u32, Rc<PassMaps>>>,
}

impl MapCache {
    /// `keep`: keep each pass's maps once traced (a batch); otherwise nothing is kept.
    pub fn new(keep: bool) -> Self {
        MapCache { keep, passes: RefCell::new(Default::default()) }
    }

    fn get(&self, pass: u32) -> Option<Rc<PassMaps>> {
        self.passes.borrow().get(&pass).cloned()
    }

    fn put(&self, pass: u32, maps: &Rc<PassMaps>) {
        if self.keep {
            self.passes.borrow_mut().entry(pass).or_insert_with(|| Rc::clone(maps));
        }
    }
}

impl<'f, 'a, A: Accel> PhotonMapper<'f, 'a, A> {
    pub fn new(
        frame: &'f Frame<'a, A>,
        cfg: &'f PhotonConfig,
        analysis: &'f Analysis,
        cache: &'f MapCache,
    ) -> Self {
        PhotonMapper { frame, cfg, analysis, gathers: GatherPair::new(&cfg.gathers, frame.scene), cache }
    }

    /// The maps of `pass`: traced (and kept if the cache keeps them), or those an earlier
    /// image of the batch traced.
    fn pass_maps(&self, pass: &Pass, stats: &mut Stats, progress: &dyn Progress) -> Rc<PassMaps> {
        if let Some(kept) = self.cache.get(pass.index) {
            let why =
                format!("pass {}'s maps and irradiance were made once for the batch's images", pass.index);
            stats.skip("photons.shared", why);
            return kept;
        }
        let (maps, sites) = self.stages().trace(self.frame, self.analysis, pass, stats, progress);
        let irradiance = self.precompute(stats, sites.indirect);
        let caustic = self.precompute_caustic(stats, &maps, sites.caustic);
        let made = Rc::new(PassMaps { maps, irradiance, caustic, seed: pass.seed });
        self.cache.put(pass.index, &made);
        made
    }

    fn stages(&self) -> MapStages<'f> {
        let cfg = self.cfg;
        // Camera hits read the caustic map for the caustic term, final-gather hits for the
        // indirect one.
        let caustics_shown = match cfg.component {
            Component::All | Component::Caustic => true,
            Component::Indirect => cfg.indirect == IndirectMode::FinalGather,
            Component::Emitted | Component::Direct => false,
        };
        MapStages {
            passes: &cfg.maps,
            indirect_unused: (!cfg.component.shows(Component::Indirect))
                .then_some("the render does not show indirect light (--component)"),
            caustic_unused: (!caustics_shown).then_some("the render does not show caustics (--component)"),
            site_stride: cfg.irradiance_cache.then_some(IRRADIANCE_STRIDE),
            // Camera hits read caustics at every sample (final-gather hits read the indirect
            // sites' caustic part).
            caustic_sites: cfg.irradiance_cache && cfg.component.shows(Component::Caustic),
        }
    }

    /// Caustic irradiance precomputed at `sites` (stage `irradiance.caustic`), for camera hits
    /// on Lambertian surfaces: one search for the nearest site instead of a gather of `k`
    /// photons at every camera sample. The sites are where caustic paths of their own land
    /// ([`super::maps::CAUSTIC_SITE_SHARE`]), so they are as dense as the caustic is bright
    /// and the value read lies within about a photon's spacing of the point, a small fraction
    /// of the gather's radius. The stage indexes them; their values are estimated as the
    /// camera first reads them.
    fn precompute_caustic(
        &self,
        stats: &mut Stats,
        maps: &PhotonMaps,
        sites: Vec<SitePoint>,
    ) -> PrecomputedIrradiance {
        if sites.is_empty() {
            if !maps.caustic.is_empty() {
                let why = match self.cfg.irradiance_cache {
                    true => "no caustic site path landed on a surface",
                    false => "disabled (--irradiance-cache false)",
                };
                stats.skip("irradiance.caustic", why);
            }
            return PrecomputedIrradiance::default();
        }
        let reason = format!("{} sites where caustic paths land, estimated as read", sites.len());
        let radius = self.gathers.caustic.max_radius;
        index_sites(stats, "irradiance.caustic", CAUSTIC_SITES, reason, || {
            PrecomputedIrradiance::new(sites, radius, false)
        })
    }

    /// Precomputed irradiance at `sites` (empty when there are none), indexed (stage
    /// `irradiance`); the values are estimated as the camera first reads them.
    fn precompute(&self, stats: &mut Stats, sites: Vec<SitePoint>) -> PrecomputedIrradiance {
        if sites.is_empty() {
            let why = if self.cfg.irradiance_cache {
                "no indirect photons"
            } else {
                "disabled (--irradiance-cache false)"
            };
            stats.skip("irradiance", why);
            return PrecomputedIrradiance::default();
        }
        let reason =
            format!("{} sites, one per {IRRADIANCE_STRIDE} photon paths, estimated as read", sites.len());
        let radius = self.gathers.indirect.max_radius;
        // The probes of the sites' footprints leave from them (and final gathering's shadow rays).
        index_sites(stats, "irradiance", IRRADIANCE_SITES, reason, || {
            PrecomputedIrradiance::new(sites, radius, true)
        })
    }
}

/// Runs the stage `name` that indexes sites (`index`) and records them among the maps as
/// `record`.
fn index_sites(
    stats: &mut Stats,
    name: &str,
    record: &str,
    reason: String,
    index: impl FnOnce() -> PrecomputedIrradiance,
) -> PrecomputedIrradiance {
    let made = stats.run(name, reason, |_| index());
    let entry = MapStats { stored: made.len() as u64, bytes: made.bytes() as u64, ..Default::default() };
    stats.photons.insert(record.into(), entry);
    made
}

/// After a camera pass: how many of `cache`'s sites have been estimated (as `seen`, of the
/// `stored` ones) and the memory they hold now, in the record `record`; returns the thread
/// seconds estimating them took in all.
fn record_estimated(stats: &mut Stats, record: &str, cache: &PrecomputedIrradiance) -> f64 {
    let (sites, seconds) = cache.estimated();
    if let Some(entry) = stats.photons.get_mut(record) {
        entry.seen = sites;
        entry.efficiency = if entry.stored > 0 { sites as f64 / entry.stored as f64 } else { 0.0 };
        entry.bytes = cache.bytes() as u64;
    }
    seconds
}

impl<A: Accel> PassRenderer for PhotonMapper<'_, '_, A> {
    fn render_pass(
        &mut self,
        pass: &Pass,
        stats: &mut Stats,
        progress: &dyn Progress,
    ) -> (PassImage, Counters) {
        let made = self.pass_maps(pass, stats, progress);
        let (frame, g) = (self.frame, &self.gathers);
        let final_gather = self.cfg.indirect == IndirectMode::FinalGather;
        // Direct irradiance at a site, which only final gathering reads: the shading of a
        // white Lambertian surface (MIS of light and cosine sampling), times pi.
        let white = Material::Diffuse { kd: Vec3::ONE };
        let seed = made.seed;
        let direct = |i: usize, site: &SitePoint| {
            let mut rng = Pcg32::seed_from_u64(derive_seed(seed, 0xD12EC7, i as u64));
            let mut c = Counters::default();
            let hit = SurfaceHit::flat(site.pos, site.err, site.n);
            let l = direct_light(frame, &hit, site.n, &white, SITE_LIGHT_SAMPLES, &mut rng, &mut c);
            std::f32::consts::PI * l
        };
        // The footprint of a site's indirect gather, probed on the side asked for; the probes'
        // rays are counted with the camera stage's (sites are estimated as the camera reads them).
        let site_rays = AtomicU64::new(0);
        let site_probe = |i: usize, site: &SitePoint, back: bool, r2: f32| {
            let mut rng = Pcg32::seed_from_u64(derive_seed(seed, 0xF007, 2 * i as u64 + u64::from(back)));
            let mut c = Counters::default();
            let n = if back { -site.n } else { site.n };
            let fp = probe::probe(frame, &SurfaceHit::flat(site.pos, site.err, n), n, r2, &mut rng, &mut c);
            site_rays.fetch_add(c.rays.gather, Ordering::Relaxed);
            fp
        };
        let shading = Shading {
            frame,
            cfg: self.cfg,
            maps: &made.maps,
            // Camera hits read the caustic map itself, final-gather hits the sites' caustic part.
            irradiance: made.irradiance.sites(SiteSource {
                indirect: &made.maps.indirect,
                caustic: if final_gather { &made.maps.caustic } else { &[] },
                gather: &g.indirect,
                caustic_gather: &g.caustic,
                direct: final_gather.then_some(&direct as &SiteDirect<'_>),
                probe: Some(&site_probe as &SiteProbe<'_>),
            }),
            caustic: made.caustic.sites(SiteSource {
                indirect: &[],
                caustic: &made.maps.caustic,
                gather: &g.caustic,
                caustic_gather: &g.caustic,
                direct: None,
                probe: None,
            }),
            gathers: self.gathers,
        };
        let camera = &self.frame.camera;
        let mut pixels = vec![(); camera.width as usize * camera.height as usize];
        // Sites estimated by earlier images of a batch are not this one's work.
        let before = made.irradiance.estimated().1 + made.caustic.estimated().1;
        let spp = pass.samples.spp;
        let lookups = indirect_samples(spp) as usize;
        let indirect_weight = spp as f32 / lookups.max(1) as f32;
        let (film, c) = camera_stage(stats, progress, camera.height, "always", || {
            for_each_pixel(
                camera.width as usize,
                &mut pixels,
                pass.seed,
                progress,
                |x, y, _, rng, scratch: &mut Scratch, c| {
                    self.frame.camera_rays(&pass.samples, x, y, &mut scratch.batch, c);
                    let batch = std::mem::take(&mut scratch.batch);
                    if let Some((centre, radius)) = batch.hit_bounds() {
                        scratch.sites.expect(centre, radius);
                        scratch.caustic_sites.expect(centre, radius);
                    }
                    // Each sample's radiance but for its light samples' shadow rays, which are
                    // put off and cast together as packets (`Shadows`), then added in.
                    let mut totals = std::mem::take(&mut scratch.totals);
                    totals.clear();
                    for (j, (ray, hit)) in batch.rays.iter().zip(&batch.hits).enumerate() {
                        let indirect = if j < lookups { indirect_weight } else { 0.0 };
                        totals.push(shading.radiance(*ray, *hit, indirect, j as u32, rng, scratch, c));
                    }
                    scratch.shadows.resolve(self.frame, &mut totals, c);
                    let mut mean = SampleMean::default();
                    for &l in &totals {
                        mean.add(l, c);
                    }
                    scratch.totals = totals;
                    scratch.batch = batch;
                    mean.mean()
                },
            )
        });
        let mut c = c;
        c.clock.estimate_rays = site_rays.into_inner();
        c.rays.gather += c.clock.estimate_rays;
        let after = record_estimated(stats, IRRADIANCE_SITES, &made.irradiance)
            + record_estimated(stats, CAUSTIC_SITES, &made.caustic);
        c.clock.estimate_ns = ((after - before).max(0.0) * 1e9) as u64;
        (film.into(), c)
    }
}

/// Per-thread scratch buffers reused across pixels.
#[derive(Default)]
struct Scratch {
    batch: CameraBatch,
    neighbors: Vec<Neighbor>,
    sites: LookupScratch,
    caustic_sites: LookupScratch,
    /// The pixel's shadow rays put off, and its samples' radiance.
    shadows: Shadows,
    totals: Vec<Vec3>,
}

/// What the camera pass of one pass reads.
struct Shading<'s, 'a, A: Accel> {
    frame: &'s Frame<'a, A>,
    cfg: &'s PhotonConfig,
    maps: &'s PhotonMaps,
    /// Precomputed irradiance (empty when disabled or when there is no indirect map).
    irradiance: Sites<'s>,
    /// Precomputed caustic irradiance (empty when disabled or when there is no caustic map).
    caustic: Sites<'s>,
    gathers: GatherPair,
}

impl<A: Accel> Shading<'_, '_, A> {
    /// Radiance arriving along a camera ray whose first hit `first` is already known:
    /// emission seen directly or through mirrors and glass (direct light at diffuse surfaces
    /// comes from shadow rays instead), then the shading of the first diffuse or glossy
    /// surface, its indirect estimate weighted `indirect` (0: not read; [`INDIRECT_EVERY`]).
    /// The light samples' shadow rays are put off into `scratch.shadows` for camera sample
    /// `sample`: what they bring is not in the result.
    #[allow(clippy::too_many_arguments)]
    fn radiance(
        &self,
        ray: Ray,
        first: Option<crate::accel::Hit>,
        indirect: f32,
        sample: u32,
        rng: &mut Pcg32,
        scratch: &mut Scratch,
        c: &mut Counters,
    ) -> Vec3 {
        let emitted = self.cfg.component.shows(Component::Emitted);
        let mut l = Vec3::ZERO;
        let start = Start::Traced(ray, first);
        let count = |c: &mut Counters| c.rays.specular += 1;
        let landing = walk(self.frame, start, Vec3::ONE, self.cfg.max_depth, rng, c, count, |seen, beta| {
            if emitted {
                l += beta * seen.emitted(self.frame.lights);
            }
        });
        if let Some(v) = landing {
            let later = Some((sample, v.beta));
            let only = self.cfg.component;
            l += v.beta * self.shade(&v.hit, v.wo, &v.m, indirect, later, only, 0, rng, scratch, c);
        }
        l
    }

    /// Reflected radiance toward `wo` at a diffuse or glossy surface, the terms `only` names, the
    /// indirect estimate weighted `weight` (0: not read; final gathering ignores it). `later`:
    /// the camera sample and the path's throughput to this point, for light samples whose
    /// shadow rays are put off into `scratch.shadows` (left out of the result); `None`: cast at
    /// once.
    ///
    /// On a sharp glossy surface ([`Material::sharp_lobe`]) reached after fewer than
    /// [`GLOSSY_DEPTH`] such bounces, the photon maps estimate the Lambertian part's light
    /// alone and the Phong lobe's is traced ([`Shading::glossy_lobe`]), as Jensen (2001, §9.1)
    /// splits the rendering equation: estimated from the photons, a lobe holding less than
    /// about one of them is a few specks (a sharp metal sphere reflected each photon near its
    /// mirror direction as a bright blotch), where a sampled ray sees what the lobe sees.
    /// Wider lobes hold several photons and are estimated from them, as are all lobes deeper:
    /// a traced ray that lands on a wide lobe seeing a sharp one's highlight (a rough metal
    /// beside a chrome ball) is a rare bright sample, which the photons reflected by the sharp
    /// lobe bring as a smooth estimate.
    #[allow(clippy::too_many_arguments)]
    fn shade(
        &self,
        hit: &SurfaceHit,
        wo: Vec3,
        m: &Material,
        weight: f32,
        later: Option<(u32, Vec3)>,
        only: Component,
        depth: u32,
        rng: &mut Pcg32,
        scratch: &mut Scratch,
        c: &mut Counters,
    ) -> Vec3 {
        let mut l = Vec3::ZERO;
        if only.shows(Component::Direct) {
            let mut shadow = match later {
                Some((sample, weight)) => ShadowRays::Later { shadows: &mut scratch.shadows, sample, weight },
                None => ShadowRays::Now,
            };
            l += direct_light_with(self.frame, hit, wo, m, self.cfg.light_samples, &mut shadow, rng, c);
        }
        let traced = self.cfg.indirect == IndirectMode::Estimate && depth < GLOSSY_DEPTH;
        let lobes = if traced { m.sharp_lobe() } else { None };
        if let Some((_, lobe)) = lobes {
            if only.shows(Component::Indirect) {
                l += self.glossy_lobe(hit, wo, m, &lobe, weight, later, depth, rng, scratch, c);
            }
        }
        // What the maps estimate: the Lambertian part alone where the lobe is traced (nothing
        // for a metal).
        let diffuse_part = lobes.map(|(diffuse, _)| diffuse);
        if diffuse_part.is_some_and(|d| d.albedo() == Vec3::ZERO) {
            return l;
        }
        let m = diffuse_part.as_ref().unwrap_or(m);
        if !self.maps.caustic.is_empty() && only.shows(Component::Caustic) {
            l += match self.precomputed_caustic(hit, wo, m, scratch, c) {
                Some(e) => e,
                None => {
                    c.queries += self.maps.caustic.len() as u64;
                    let (maps, g) = (&self.maps.caustic, &self.gathers.caustic);
                    let nb = &mut scratch.neighbors;
                    c.timed(Part::Gathers, || PhotonMaps::radiance(maps, hit.p, hit.normals(), wo, m, g, nb))
                }
            };
        }
        if !self.maps.indirect.is_empty() && only.shows(Component::Indirect) {
            match self.cfg.indirect {
                IndirectMode::Estimate if weight == 0.0 => {}
                IndirectMode::Estimate => {
                    let e = match self.precomputed_indirect(hit, wo, m, scratch, c) {
                        Some(e) => e,
                        None => self.indirect_estimate(hit, wo, m, scratch, c),
                    };
                    l += if weight == 1.0 { e } else { e * weight };
                }
                IndirectMode::FinalGather => l += self.final_gather(hit, wo, m, rng, scratch, c),
            }
        }
        l
    }

    /// The light a glossy surface's Phong lobe `lobe` reflects toward `wo` at `hit` (material
    /// `m`) but for its direct light (light samples and BSDF samples take that): one ray
    /// through the lobe ([`through_lobe`]) and the radiance leaving the surface it lands on,
    /// shaded as the camera's first surface is ([`Shading::shade`], one glossy bounce deeper;
    /// every term); emitters and the sky count only past a mirror or glass. `later` as for
    /// `shade`, the lobe's throughput carried.
    #[allow(clippy::too_many_arguments)]
    fn glossy_lobe(
        &self,
        hit: &SurfaceHit,
        wo: Vec3,
        m: &Material,
        lobe: &Material,
        weight: f32,
        later: Option<(u32, Vec3)>,
        depth: u32,
        rng: &mut Pcg32,
        scratch: &mut Scratch,
        c: &mut Counters,
    ) -> Vec3 {
        let here = Landing { hit: *hit, wo, m: *m, beta: Vec3::ONE };
        let count = |c: &mut Counters| c.rays.specular += 1;
        let (mut l, landing) = through_lobe(self.frame, &here, lobe, 1.0, self.cfg.max_depth, rng, c, count);
        if let Some(v) = landing {
            let later = later.map(|(sample, beta)| (sample, beta * v.beta));
            l += v.beta
                * self.shade(&v.hit, v.wo, &v.m, weight, later, Component::All, depth + 1, rng, scratch, c);
        }
        l
    }

    /// Whether the sites of `cache` answer at `hit` seen from `wo`: the Lambertian BRDF
    /// `kd / π` there and the normal on the viewer's side, counting the lookup to come; `None`
    /// (not Lambertian, or nothing precomputed).
    #[inline]
    fn site_query(
        cache: &Sites<'_>,
        hit: &SurfaceHit,
        wo: Vec3,
        m: &Material,
        c: &mut Counters,
    ) -> Option<(Vec3, Vec3)> {
        let kd = m.lambertian()?;
        if cache.is_empty() {
            return None;
        }
        c.queries += 1;
        Some((kd * std::f32::consts::FRAC_1_PI, face_forward(hit.n, wo)))
    }

    /// Reflected radiance at a Lambertian surface from the precomputed irradiance, by kind of
    /// path, or `None` (not Lambertian, nothing precomputed, or no site near enough).
    #[inline]
    fn precomputed(
        &self,
        hit: &SurfaceHit,
        wo: Vec3,
        m: &Material,
        scratch: &mut Scratch,
        c: &mut Counters,
    ) -> Option<Irradiance> {
        let (f, ns) = Self::site_query(&self.irradiance, hit, wo, m, c)?;
        let site = c.timed(Part::Gathers, || self.irradiance.find(hit.p, ns, &mut scratch.sites))?;
        let e = self.irradiance.irradiance(site);
        Some(Irradiance { direct: f * e.direct, indirect: f * e.indirect, caustic: f * e.caustic })
    }

    /// Reflected caustic radiance at a Lambertian surface from the caustic sites, or `None`
    /// (not Lambertian, nothing precomputed, or no site near enough facing the same way: the
    /// caller gathers).
    #[inline]
    fn precomputed_caustic(
        &self,
        hit: &SurfaceHit,
        wo: Vec3,
        m: &Material,
        scratch: &mut Scratch,
        c: &mut Counters,
    ) -> Option<Vec3> {
        let (f, ns) = Self::site_query(&self.caustic, hit, wo, m, c)?;
        let sites = &mut scratch.caustic_sites;
        let site = c.timed(Part::Gathers, || self.caustic.find_caustic(hit.p, ns, sites))?;
        Some(f * self.caustic.caustic(site))
    }

    /// Reflected indirect radiance at a Lambertian surface from the precomputed irradiance
    /// (either side of a site: [`Sites::find_indirect`]), or `None`.
    #[inline]
    fn precomputed_indirect(
        &self,
        hit: &SurfaceHit,
        wo: Vec3,
        m: &Material,
        scratch: &mut Scratch,
        c: &mut Counters,
    ) -> Option<Vec3> {
        let (f, ns) = Self::site_query(&self.irradiance, hit, wo, m, c)?;
        let site = c.timed(Part::Gathers, || self.irradiance.find_indirect(hit.p, ns, &mut scratch.sites))?;
        Some(f * self.irradiance.indirect(site, ns))
    }

    /// Reflected indirect radiance at `hit` toward `wo` from the indirect maps themselves, over
    /// the footprint of each gather's disc ([`PhotonMaps::radiance_over`], probed here).
    fn indirect_estimate(
        &self,
        hit: &SurfaceHit,
        wo: Vec3,
        m: &Material,
        scratch: &mut Scratch,
        c: &mut Counters,
    ) -> Vec3 {
        c.queries += self.maps.indirect.len() as u64;
        let (maps, g, frame) = (&self.maps.indirect, &self.gathers.indirect, self.frame);
        let nb = &mut scratch.neighbors;
        let ns = face_forward(hit.n, wo);
        let mut probes = Counters::default();
        // The probes' turn is drawn from the hit's position, not the camera sample's generator,
        // which the samples after this one go on drawing from.
        let (x, y, z) = (hit.p.x.to_bits(), hit.p.y.to_bits(), hit.p.z.to_bits());
        let mut turn = Pcg32::seed_from_u64(derive_seed(u64::from(x) << 32 | u64::from(y), 0xF007, z.into()));
        let mut at = |_back: bool, r2: f32| probe::probe(frame, hit, ns, r2, &mut turn, &mut probes);
        let e = c.timed(Part::Gathers, || {
            PhotonMaps::radiance_over(maps, hit.p, hit.normals(), wo, m, g, nb, &mut at)
        });
        c.rays.gather += probes.rays.gather;
        e
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
            let Some(s) =
                hit.normals().sample(m, wo, rng.gen(), [rng.gen(), rng.gen()], TransportMode::Radiance)
            else {
                continue;
            };
            let start = Start::Ray(Ray::new(hit.spawn(s.sample.wi), s.sample.wi));
            let count = |c: &mut Counters| c.rays.gather += 1;
            let walked = walk(self.frame, start, s.weight, self.cfg.max_depth, rng, c, count, |_, _| {});
            let Some(Landing { hit: y, wo: wy, m: ref my, beta }) = walked else { continue };
            let ly = if let Some(e) = self.precomputed(&y, wy, my, scratch, c) {
                e.direct + e.indirect + e.caustic
            } else {
                let mut ly = direct_light(self.frame, &y, wy, my, 1, rng, c);
                c.queries += self.maps.caustic.len() as u64;
                let nb = &mut scratch.neighbors;
                let g = &self.gathers;
                let caustic = &self.maps.caustic;
                ly += c.timed(Part::Gathers, || {
                    PhotonMaps::radiance(caustic, y.p, y.normals(), wy, my, &g.caustic, nb)
                });
                ly + self.indirect_estimate(&y, wy, my, scratch, c)
            };
            sum += beta * ly;
        }
        sum / n_rays as f32
    }
}
