//! Rendering: the scene analysis that decides which stages run, the photon passes, and the
//! camera pass. [`render`] is generic over the accelerator so its inner loops are
//! monomorphised per backend.

pub mod camera;
pub mod direct;
pub mod lights;
pub mod path;
pub mod progressive;
pub mod sppm;

use crate::accel::Accel;
use crate::config::{CausticPass, ColorMode, Component, IndirectMode, Integrator, RenderConfig};
use crate::film::Film;
use crate::photon::irradiance::{self, IrradianceCache};
use crate::photon::map::{GatherParams, MapColor, PhotonMap, PhotonMaps};
use crate::photon::trace::{self, Pass};
use crate::scene::{Camera, Scene};
use crate::stats::{MapStats, RayCounts, Stats};
use camera::Scratch;
use glam::Vec3;
use lights::LightSet;
pub use progressive::Control;
use progressive::Schedule;
use rand::SeedableRng;
use rand_pcg::Pcg32;
use rayon::prelude::*;

/// Everything the camera pass reads, shared by all threads.
pub struct Shared<'a, A: Accel> {
    pub scene: &'a Scene,
    pub scene_camera: Camera,
    pub accel: &'a A,
    pub lights: &'a LightSet,
    pub maps: &'a PhotonMaps,
    pub cfg: &'a RenderConfig,
    pub gather: GatherParams,
    pub caustic_gather: GatherParams,
    /// Precomputed irradiance (empty when disabled or when there is no indirect map).
    pub cache: &'a IrradianceCache,
    /// Index of this pass's first camera sample in each pixel's sample sequence.
    pub first_sample: u64,
    /// The render's seed (not the pass's), for what stays fixed over passes.
    pub pixel_seed: u64,
}

/// Per-thread counters, summed at the end (no atomics in hot loops).
#[derive(Clone, Copy, Debug, Default)]
pub struct Counters {
    pub rays: RayCounts,
    pub queries: u64,
    pub nonfinite: u64,
}

impl std::ops::AddAssign for Counters {
    fn add_assign(&mut self, o: Counters) {
        self.rays += o.rays;
        self.queries += o.queries;
        self.nonfinite += o.nonfinite;
    }
}

/// Reports progress of long stages (a no-op implementation is fine).
pub trait Progress: Sync {
    /// A stage of `total` units begins.
    fn start(&self, _stage: &str, _total: u64) {}
    /// `n` more units are done.
    fn advance(&self, _n: u64) {}
    /// The stage is over.
    fn finish(&self) {}
}

/// Irradiance is precomputed at every this-many-th indirect photon (Christensen uses 4).
const IRRADIANCE_STRIDE: usize = 4;

/// Shadow-ray samples for the direct irradiance of each cache site.
const SITE_LIGHT_SAMPLES: u32 = 16;

/// Progress that reports nothing.
pub struct Quiet;
impl Progress for Quiet {}

/// What the scene needs, decided before any work: each flag comes with the reason printed in
/// the stats.
#[derive(Clone, Debug)]
pub struct Analysis {
    pub has_specular: bool,
    pub has_diffuse: bool,
    pub light_power: Vec3,
}

impl Analysis {
    pub fn of(scene: &Scene, lights: &LightSet) -> Self {
        let used = |f: &dyn Fn(&crate::material::Material) -> bool| {
            let mut seen = vec![false; scene.materials.len()];
            for &m in &scene.tri_material {
                seen[m as usize] = true;
            }
            scene.materials.iter().zip(&seen).any(|(m, &s)| s && f(m))
        };
        Analysis {
            has_specular: used(&|m| m.is_specular()),
            has_diffuse: used(&|m| m.is_diffuse_like()),
            light_power: lights.total_power(),
        }
    }
}

/// The image and the report of a render.
pub struct RenderOutput {
    pub film: Film,
    pub stats: Stats,
}

/// What every stage of a render reads.
struct Ctx<'a, A: Accel> {
    scene: &'a Scene,
    accel: &'a A,
    /// The settings of the pass being rendered (its own seed).
    cfg: RenderConfig,
    /// The pass being rendered and the render's seed.
    pass: u32,
    seed: u64,
    progress: &'a dyn Progress,
    lights: LightSet,
    analysis: Analysis,
    gather: GatherParams,
    caustic_gather: GatherParams,
}

/// Why a stage is skipped by the path tracer.
const PATH_TRACER: &str = "path tracer";

/// Renders `scene` with `accel` as `cfg` says, in as many passes as `cfg` and `control` allow.
/// `stats` arrives with the stages already run (loading, acceleration build) and is completed
/// here.
pub fn render<A: Accel>(
    scene: &Scene,
    accel: &A,
    cfg: &RenderConfig,
    progress: &dyn Progress,
    control: Control<'_>,
    mut stats: Stats,
) -> RenderOutput {
    let start = std::time::Instant::now();
    let lights = stats.run("lights", "prepare emitters and light sampling", |_| LightSet::new(scene));
    let analysis = Analysis::of(scene, &lights);
    let dark = lights.lights().iter().filter(|l| !(l.power().max_element() > 0.0)).count();
    if dark > 0 {
        let why =
            format!("{dark} of {} lights have no power: no photons, no shadow rays", lights.lights().len());
        stats.skip("emission.zero_power", why);
    }
    let auto_radius = 0.1 * scene.bounds().bounding_sphere().1;
    let params = |k: u32, radius: Option<f32>, default: f32| GatherParams {
        k: k as usize,
        max_radius: radius.unwrap_or(default),
        kernel: cfg.kernel,
        flatten: 8.0,
    };
    let mut schedule = Schedule::new(cfg, control);
    let progressive = schedule.is_progressive();
    // In a progressive render one bar counts the passes; the stages of each pass stay quiet.
    let inner: &dyn Progress = if progressive { &Quiet } else { progress };
    let sppm = cfg.integrator == Integrator::Sppm;
    let mut ctx = Ctx {
        scene,
        accel,
        // Progressive photon mapping gathers photons at visible points, not at cached sites.
        cfg: RenderConfig { irradiance_cache: cfg.irradiance_cache && !sppm, ..cfg.clone() },
        progress: inner,
        pass: 0,
        seed: cfg.seed,
        lights,
        analysis,
        gather: params(cfg.gather_photons, cfg.gather_radius, auto_radius),
        caustic_gather: params(cfg.caustic_gather_photons, cfg.caustic_gather_radius, 0.25 * auto_radius),
    };
    let camera = scene.camera.with_resolution(cfg.width, cfg.height);
    let (w, h) = (cfg.width as usize, cfg.height as usize);
    let mut image = Image {
        sum: if sppm { Film::new(0, 0) } else { Film::new(w, h) },
        sppm: if sppm { vec![sppm::PixelState::default(); w * h] } else { Vec::new() },
        width: w,
        height: h,
    };
    let why_camera = match cfg.integrator {
        Integrator::Path => "always (path tracer)",
        Integrator::Photon => "always",
        Integrator::Sppm => "visible points, direct light and progressive radius updates",
    };
    let mut counters = Counters::default();
    if progressive {
        progress.start("passes", schedule.progress_total());
    }
    while schedule.start_pass() {
        ctx.pass = schedule.done();
        ctx.cfg.seed = pass_seed(cfg.seed, ctx.pass);
        let (indirect, sites) = ctx.indirect_pass(&mut stats);
        let maps = PhotonMaps { indirect, caustic: ctx.caustic_pass(&mut stats) };
        let cache = ctx.irradiance_cache(&mut stats, &maps, sites);
        let shared = ctx.shared(&maps, &cache, camera);
        inner.start("camera", cfg.height as u64);
        counters += stats.run("camera", why_camera, |_| {
            if sppm {
                sppm::camera_pass(&shared, &mut image.sppm, cfg.alpha, inner)
            } else {
                let (film, c) = camera_pass(&shared, inner);
                image.add(&film);
                c
            }
        });
        inner.finish();
        let (units, due) = schedule.finish_pass();
        progress.advance(if progressive { units } else { 0 });
        if due {
            schedule.checkpoint(&image.film(schedule.done()));
        }
    }
    if progressive {
        progress.finish();
    }
    let film = image.film(schedule.done());
    stats.passes = schedule.done();
    stats.cancelled = schedule.cancelled();
    stats.merge_repeated_stages();
    let photon_seconds = stats.seconds("photons.indirect") + stats.seconds("photons.caustic");
    if photon_seconds > 0.0 {
        let paths: u64 = stats.photons.values().map(|m| m.emitted).sum();
        stats.photons_traced_per_second = paths as f64 / photon_seconds;
    }
    stats.rays += counters.rays;
    stats.gather_queries = counters.queries;
    let camera_seconds = stats.seconds("camera");
    if camera_seconds > 0.0 {
        stats.gather_queries_per_second = counters.queries as f64 / camera_seconds;
    }
    stats.nonfinite_samples = counters.nonfinite;
    stats.width = cfg.width;
    stats.height = cfg.height;
    stats.wall_seconds += start.elapsed().as_secs_f64();
    let traced_seconds: f64 = camera_seconds + photon_seconds;
    if traced_seconds > 0.0 {
        stats.rays_per_second = stats.rays.total() as f64 / traced_seconds;
    }
    RenderOutput { film, stats }
}

/// The seed of pass `pass`: the first pass uses the render's own seed, so one pass gives the
/// same image as a render without passes.
fn pass_seed(seed: u64, pass: u32) -> u64 {
    if pass == 0 {
        seed
    } else {
        trace::mix(seed, 0x9A55E5, pass as u64)
    }
}

/// The image being built: the sum of the passes' images, or progressive photon mapping's
/// per-pixel statistics.
struct Image {
    sum: Film,
    sppm: Vec<sppm::PixelState>,
    width: usize,
    height: usize,
}

impl Image {
    fn add(&mut self, film: &Film) {
        for (s, p) in self.sum.pixels.iter_mut().zip(&film.pixels) {
            *s += *p;
        }
    }

    /// The image after `passes` passes.
    fn film(&self, passes: u32) -> Film {
        if !self.sppm.is_empty() {
            return sppm::film(&self.sppm, self.width, self.height, passes);
        }
        let mut film = self.sum.clone();
        let scale = 1.0 / passes.max(1) as f32;
        for p in &mut film.pixels {
            *p *= scale;
        }
        film
    }
}

impl<'a, A: Accel> Ctx<'a, A> {
    fn shared<'b>(
        &'b self,
        maps: &'b PhotonMaps,
        cache: &'b IrradianceCache,
        camera: Camera,
    ) -> Shared<'b, A> {
        Shared {
            scene: self.scene,
            scene_camera: camera,
            accel: self.accel,
            lights: &self.lights,
            maps,
            cfg: &self.cfg,
            gather: self.gather,
            caustic_gather: self.caustic_gather,
            cache,
            first_sample: self.pass as u64 * self.cfg.spp as u64,
            pixel_seed: self.seed,
        }
    }

    fn lit(&self) -> bool {
        self.analysis.light_power.max_element() > 0.0
    }

    /// The indirect map, and the photon positions chosen for precomputed irradiance.
    fn indirect_pass(&self, stats: &mut Stats) -> (Vec<PhotonMap>, Vec<irradiance::SitePoint>) {
        let cfg = &self.cfg;
        let why_not = if cfg.integrator == Integrator::Path {
            Some(PATH_TRACER)
        } else if !self.lit() {
            Some("no light has power")
        } else if !self.analysis.has_diffuse {
            Some("nothing diffuse or glossy: no surface stores photons")
        } else if cfg.photons == 0 {
            Some("photon budget is 0")
        } else if !cfg.component.shows(Component::Indirect) {
            Some("the render does not show indirect light (--component)")
        } else {
            None
        };
        if let Some(why) = why_not {
            stats.skip("photons.indirect", why);
            return (Vec::new(), Vec::new());
        }
        self.progress.start("indirect photons", cfg.photons);
        let out = stats.run("photons.indirect", "diffuse surfaces and lit scene", |_| {
            let spec = trace::PassSpec {
                pass: Pass::Indirect,
                n: cfg.photons,
                color: cfg.color,
                max_bounces: cfg.max_bounces,
                targets: &[],
                aim: false,
                seed: cfg.seed,
            };
            trace::trace_pass(self.scene, self.accel, &self.lights, &spec, self.progress)
        });
        self.progress.finish();
        stats.rays.photon += out.rays;
        // The same density of sites whatever the colour mode: per-channel maps split the photons
        // three ways, so each contributes a third as many sites.
        let sites = if cfg.irradiance_cache {
            irradiance::pick_sites(&out.maps, IRRADIANCE_STRIDE * out.maps.len())
        } else {
            Vec::new()
        };
        let maps = stats.run("kdtree.indirect", "balance the indirect map", |_| build_maps(out, cfg.color));
        record_maps(stats, "indirect", &maps);
        (drop_empty(stats, "indirect", maps), sites)
    }

    /// Why the caustic pass does not run, if it does not: the scene analysis, overridden by
    /// `--caustic-pass on|off`.
    fn caustic_skip_reason(&self) -> Option<&'static str> {
        let cfg = &self.cfg;
        // Camera hits read the caustic map for the caustic term, final-gather hits for the
        // indirect one.
        let shown = match cfg.component {
            Component::All | Component::Caustic => true,
            Component::Indirect => cfg.indirect == IndirectMode::FinalGather,
            Component::Emitted | Component::Direct => false,
        };
        if cfg.integrator == Integrator::Path {
            Some(PATH_TRACER)
        } else if cfg.caustic_photons == 0 {
            Some("caustic photon budget is 0")
        } else if cfg.caustic_pass == CausticPass::On {
            None
        } else if cfg.caustic_pass == CausticPass::Off {
            Some("off (--caustic-pass off)")
        } else if !self.analysis.has_specular {
            Some("no specular (mirror or glass) material")
        } else if !self.analysis.has_diffuse {
            Some("nothing diffuse or glossy to receive caustics")
        } else if !self.lit() {
            Some("no light has power")
        } else if !shown {
            Some("the render does not show caustics (--component)")
        } else {
            None
        }
    }

    /// The caustic map: photons aimed at the specular objects (or, with `--caustic-aim false`
    /// or nothing to aim at, emitted as usual) that reach a diffuse surface through mirrors and
    /// glass only.
    fn caustic_pass(&self, stats: &mut Stats) -> Vec<PhotonMap> {
        let cfg = &self.cfg;
        if let Some(why) = self.caustic_skip_reason() {
            stats.skip("photons.caustic", why);
            return Vec::new();
        }
        let forced = if cfg.caustic_pass == CausticPass::On { " (--caustic-pass on)" } else { "" };
        let targets = if cfg.caustic_aim { trace::specular_targets(self.scene) } else { Vec::new() };
        let acceptance = if targets.is_empty() {
            0.0
        } else {
            trace::target_acceptance(&self.lights, &targets, 1 << 16, cfg.seed)
        };
        let aim = acceptance > 0.0;
        let (tries, reason) = if aim {
            // Tries such that about `caustic_photons` photons are aimed at the targets.
            let tries = ((cfg.caustic_photons as f64 / acceptance).ceil() as u64)
                .min(cfg.caustic_photons.saturating_mul(1000));
            let reason = format!(
                "{} specular targets, {:.2}% of emission aimed at them{forced}",
                targets.len(),
                100.0 * acceptance
            );
            (tries, reason)
        } else if cfg.caustic_aim && cfg.caustic_pass != CausticPass::On {
            stats.skip("photons.caustic", "no emitted photon is aimed at a specular object");
            return Vec::new();
        } else {
            let why = if cfg.caustic_aim { "nothing to aim at" } else { "aiming off (--caustic-aim false)" };
            let reason = format!("{why}: photons emitted from the lights, specular paths kept{forced}");
            (cfg.caustic_photons, reason)
        };
        self.progress.start("caustic photons", tries);
        let out = stats.run("photons.caustic", reason, |_| {
            let spec = trace::PassSpec {
                pass: Pass::Caustic,
                n: tries,
                color: cfg.color,
                max_bounces: cfg.max_bounces,
                targets: &targets,
                aim,
                seed: cfg.seed ^ 0x5EED,
            };
            trace::trace_pass(self.scene, self.accel, &self.lights, &spec, self.progress)
        });
        self.progress.finish();
        stats.rays.photon += out.rays;
        let maps = stats.run("kdtree.caustic", "balance the caustic map", |_| build_maps(out, cfg.color));
        record_maps(stats, "caustic", &maps);
        drop_empty(stats, "caustic", maps)
    }

    /// Precomputed irradiance at `sites` (empty when there are none).
    fn irradiance_cache(
        &self,
        stats: &mut Stats,
        maps: &PhotonMaps,
        sites: Vec<irradiance::SitePoint>,
    ) -> IrradianceCache {
        let cfg = &self.cfg;
        if sites.is_empty() {
            let why = if cfg.integrator == Integrator::Path {
                PATH_TRACER
            } else if cfg.integrator == Integrator::Sppm {
                "progressive photon mapping gathers at visible points"
            } else if cfg.irradiance_cache {
                "no indirect photons"
            } else {
                "disabled (--irradiance-cache false)"
            };
            stats.skip("irradiance", why);
            return IrradianceCache::default();
        }
        let reason = format!("{} sites, one per {IRRADIANCE_STRIDE} photon paths", sites.len());
        let cache = stats.run("irradiance", reason, |_| {
            let (gather, caustic_gather) = (&self.gather, &self.caustic_gather);
            if cfg.indirect != IndirectMode::FinalGather {
                // Only final gathering reads the direct part.
                // Nor the caustic part: camera hits read the caustic map itself.
                return IrradianceCache::build(sites, &maps.indirect, &[], gather, caustic_gather, |_, _| {
                    Vec3::ZERO
                });
            }
            // Direct irradiance at each site: the shading of a white Lambertian surface (MIS of
            // light and cosine sampling), times pi.
            let empty = IrradianceCache::default();
            let shared = self.shared(maps, &empty, self.scene.camera);
            let white = crate::material::Material::Diffuse { kd: Vec3::ONE };
            let direct = |i: usize, site: &irradiance::SitePoint| {
                let mut rng = Pcg32::seed_from_u64(trace::mix(cfg.seed, 0xD12EC7, i as u64));
                let mut c = Counters::default();
                let hit = camera::SurfaceHit { p: site.pos, err: site.err, n: site.n, prim: 0, t: 0.0 };
                let l =
                    direct::direct_light(&shared, &hit, site.n, &white, SITE_LIGHT_SAMPLES, &mut rng, &mut c);
                std::f32::consts::PI * l
            };
            IrradianceCache::build(sites, &maps.indirect, &maps.caustic, gather, caustic_gather, direct)
        });
        let bytes = cache.bytes() as u64;
        stats
            .photons
            .insert("irradiance_cache".into(), MapStats { emitted: 0, stored: cache.len() as u64, bytes });
        cache
    }
}

/// Builds the accelerator `cfg` asks for and renders: the whole pipeline behind `photonmap
/// render`, for library users and tests.
pub fn render_scene(
    scene: &Scene,
    cfg: &RenderConfig,
    progress: &dyn Progress,
) -> Result<RenderOutput, crate::accel::AccelError> {
    render_scene_with(scene, cfg, progress, Control::default())
}

/// [`render_scene`] steered by `control` (cancel flag, checkpoints, start of the time budget).
pub fn render_scene_with(
    scene: &Scene,
    cfg: &RenderConfig,
    progress: &dyn Progress,
    control: Control<'_>,
) -> Result<RenderOutput, crate::accel::AccelError> {
    render_scene_measured(scene, cfg, progress, control, None)
}

/// [`render_scene_with`], then, when `calibrate` gives a number of rays per kind, the raw rate
/// of the same accelerator on rays like the render's, on the same threads
/// ([`crate::bench::raw_rays`], recorded by [`Stats::set_raw_rays`]).
pub fn render_scene_measured(
    scene: &Scene,
    cfg: &RenderConfig,
    progress: &dyn Progress,
    control: Control<'_>,
    calibrate: Option<usize>,
) -> Result<RenderOutput, crate::accel::AccelError> {
    // Far from the origin, render a copy centred on it (see `Scene::recentred`).
    let moved = scene.recentred();
    let scene = moved.as_ref().unwrap_or(scene);
    let mut stats = Stats::default();
    let options = crate::accel::AccelOptions { robust: cfg.robust, ..Default::default() };
    let reason = format!("{:?} over {} triangles (the only ray caster built)", cfg.accel, scene.mesh.len());
    let accel =
        stats.run("accel", reason, |_| crate::accel::AnyAccel::build(cfg.accel, &scene.mesh, options))?;
    stats.accel = accel.name().to_string();
    stats.threads = rayon::current_num_threads();
    Ok(crate::dispatch!(&accel, a => {
        let mut out = render(scene, a, cfg, progress, control, stats);
        if let Some(n) = calibrate {
            out.stats.set_raw_rays(crate::bench::raw_rays(scene, a, cfg, n));
        }
        out
    }))
}

/// Packs and balances the maps of one pass.
fn build_maps(out: trace::PassOutput, color: ColorMode) -> Vec<PhotonMap> {
    out.maps
        .into_iter()
        .zip(out.emitted)
        .enumerate()
        .map(|(i, (hits, emitted))| {
            let c = match color {
                ColorMode::Rgb => MapColor::Rgb,
                ColorMode::PerChannel => MapColor::Channel(i),
            };
            PhotonMap::build(hits, c, emitted)
        })
        .collect()
}

/// `maps` without its empty maps (an empty map is never queried); when none is left, the
/// lookups of `kind` are recorded as skipped.
fn drop_empty(stats: &mut Stats, kind: &str, mut maps: Vec<PhotonMap>) -> Vec<PhotonMap> {
    maps.retain(|m| !m.is_empty());
    if maps.is_empty() {
        stats.skip(&format!("lookups.{kind}"), format!("the {kind} map is empty: no photon was stored"));
    }
    maps
}

fn record_maps(stats: &mut Stats, kind: &str, maps: &[PhotonMap]) {
    let names = ["r", "g", "b"];
    for (i, m) in maps.iter().enumerate() {
        let name = if maps.len() == 1 { kind.to_string() } else { format!("{kind}.{}", names[i]) };
        // Over passes: photons add up; memory is that of the largest map held at once.
        let e = stats.photons.entry(name).or_default();
        e.emitted += m.emitted;
        e.stored += m.len() as u64;
        e.bytes = e.bytes.max(m.bytes() as u64);
    }
}

/// Renders every pixel; rows in parallel, each pixel with its own generator seeded from
/// (seed, pixel), so the image does not depend on the thread count.
fn camera_pass<A: Accel>(s: &Shared<'_, A>, progress: &dyn Progress) -> (Film, Counters) {
    let (w, h) = (s.cfg.width as usize, s.cfg.height as usize);
    let rows: Vec<(Vec<Vec3>, Counters)> = (0..h)
        .into_par_iter()
        .map_init(
            || {
                crate::accel::init_tracing_thread();
                Scratch::default()
            },
            |scratch, y| {
                let mut c = Counters::default();
                let row = (0..w)
                    .map(|x| {
                        let pixel = (y * w + x) as u64;
                        let mut rng = Pcg32::seed_from_u64(trace::mix(s.cfg.seed, 0xCA3E7A, pixel));
                        s.pixel(x as u32, y as u32, &mut rng, scratch, &mut c)
                    })
                    .collect();
                progress.advance(1);
                (row, c)
            },
        )
        .collect();
    let mut film = Film::new(w, h);
    let mut total = Counters::default();
    for (y, (row, c)) in rows.into_iter().enumerate() {
        film.pixels[y * w..(y + 1) * w].copy_from_slice(&row);
        total += c;
    }
    (film, total)
}
