//! The integrators: two-pass photon mapping ([`photon`]), stochastic and pass-indexed
//! progressive photon mapping ([`sppm`], [`pppm`]) and the path tracer ([`path`]), each a [`passes::PassRenderer`] with its own
//! settings ([`Integrator`]'s variants), picked by one `match` in [`render`]. The pass loop,
//! time budget, checkpoints and stop requests are [`passes`]'s, the same for all; the photon
//! stages shared by the two photon mappers are [`maps`]'s. Everything below them — scene,
//! accelerator, lights, camera samples, the specular walk, direct light — is the
//! [`frame`](crate::frame).

pub mod balance;
pub mod bandwidth;
pub mod maps;
pub mod openings;
pub mod passes;
pub mod path;
pub mod photon;
pub mod pppm;
pub mod probe;
pub mod sppm;

pub use passes::{Checkpoint, Control};

use crate::accel::{Accel, AccelError, AccelOptions, AnyAccel};
use crate::config::{Integrator, RenderConfig};
use crate::film::sums::PassSums;
use crate::film::Film;
use crate::frame::{Counters, Frame, Progress};
use crate::light::LightSet;
use crate::scene::{Camera, Scene};
use crate::stats::Stats;
use std::borrow::Cow;

/// The image and the report of a render, and the exact sums of its passes (what a
/// `--pass-range` part holds).
pub struct RenderOutput {
    pub film: Film,
    pub sums: PassSums,
    pub stats: Stats,
}

/// What the images of a batch share, built once for all of them: the scene analysis (the
/// caustic photons' aim, the photon guide and the portals, worked out at the first photon pass
/// for every view of the batch) and, for two-pass photon mapping, each pass's photon maps and
/// precomputed irradiance. Used with the [`Prepared`] scene that made it only.
pub struct Shared {
    analysis: maps::Analysis,
    maps: photon::MapCache,
}

/// Renders `frame` as `cfg` says, in as many passes as `cfg` and `control` allow, with what
/// the batch shares. `stats` arrives with the stages already run (loading, lights,
/// acceleration build) and is completed here. Generic over the accelerator so the inner loops
/// are monomorphised per backend.
pub fn render<A: Accel>(
    frame: &Frame<'_, A>,
    shared: &Shared,
    cfg: &RenderConfig,
    progress: &dyn Progress,
    control: Control<'_>,
    mut stats: Stats,
) -> RenderOutput {
    let start = std::time::Instant::now();
    let analysis = &shared.analysis;
    let rendered = match &cfg.integrator {
        Integrator::Photon(c) => {
            let mut mapper = photon::PhotonMapper::new(frame, c, analysis, &shared.maps);
            passes::run(cfg, control, progress, &mut stats, &mut mapper)
        }
        Integrator::Progressive(c) => {
            let mut sppm = sppm::Progressive::new(frame, c, analysis);
            passes::run(cfg, control, progress, &mut stats, &mut sppm)
        }
        Integrator::PassIndexed(c) => {
            let mut pppm = pppm::PassIndexed::new(frame, c, analysis, bandwidth::pays(cfg));
            passes::run(cfg, control, progress, &mut stats, &mut pppm)
        }
        Integrator::Path(c) => {
            passes::run(cfg, control, progress, &mut stats, &mut path::PathTracer::new(frame, c))
        }
    };
    let passes::Rendered { film, sums, counters } = rendered;
    finish_stats(&mut stats, &counters, cfg);
    stats.wall_seconds += start.elapsed().as_secs_f64();
    RenderOutput { film, sums, stats }
}

/// Totals and rates of a finished render.
fn finish_stats(stats: &mut Stats, counters: &Counters, cfg: &RenderConfig) {
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
    let clock = &counters.clock;
    stats.camera_time =
        crate::stats::CameraTime::new(clock.pixels_ns, clock.rays_ns, clock.gathers_ns, clock.estimate_ns);
    stats.width = cfg.width;
    stats.height = cfg.height;
    // The camera stage's time estimating precomputed irradiance is the irradiance stage's work,
    // done where it is needed: it is left out as that stage is, and so are its probe rays.
    let traced_seconds = stats.tracing_seconds() - camera_seconds * stats.camera_time.estimate_share;
    stats.traced_rays = stats.rays;
    stats.traced_rays.gather -= clock.estimate_rays.min(stats.traced_rays.gather);
    if traced_seconds > 0.0 {
        stats.rays_per_second = stats.traced_rays.total() as f64 / traced_seconds;
    }
}

/// A scene made ready to render: moved onto the origin if it lies far from it (see
/// [`Scene::recentred`]), its accelerator built, its lights prepared.
pub struct Prepared<'s> {
    scene: Cow<'s, Scene>,
    accel: AnyAccel,
    lights: LightSet,
    stats: Stats,
}

impl<'s> Prepared<'s> {
    /// Builds the accelerator `cfg` asks for (and only that one) and the light set.
    pub fn new(scene: &'s Scene, cfg: &RenderConfig) -> Result<Self, AccelError> {
        let scene = match scene.recentred() {
            Some(moved) => Cow::Owned(moved),
            None => Cow::Borrowed(scene),
        };
        let mut stats = Stats::default();
        let options = AccelOptions { robust: cfg.robust };
        let reason =
            format!("{:?} over {} triangles (the only ray caster built)", cfg.accel, scene.mesh.len());
        let accel = stats.run("accel", reason, |_| {
            AnyAccel::build(cfg.accel, &scene.mesh, scene.cutouts().as_ref(), options)
        })?;
        stats.accel = accel.name().to_string();
        // Where the scene declares no portal, the openings a sun shines in through.
        let found = if cfg.portals && scene.portals.is_empty() && scene.has_distant_light() {
            let found = stats.run("portals.found", "", |stats| {
                let found = crate::dispatch!(&accel, a => openings::find(&scene, a, &scene.camera));
                stats.rays.photon += found.rays;
                found
            });
            if let Some(stage) = stats.stages.last_mut() {
                stage.reason = found.reason.clone();
            }
            found.portals
        } else {
            Vec::new()
        };
        let lights = stats.run("lights", "prepare emitters and light sampling", |_| {
            let portals = match cfg.portals {
                false => &[][..],
                true if scene.portals.is_empty() => &found[..],
                true => &scene.portals[..],
            };
            scene.with_emission(|emission| {
                LightSet::with_emission(
                    &scene.lights,
                    &scene.mesh,
                    &scene.tri_material,
                    &scene.materials,
                    portals,
                    emission,
                )
            })
        });
        let dark = lights.lights().iter().filter(|l| !(l.power().max_element() > 0.0)).count();
        if dark > 0 {
            let why = format!(
                "{dark} of {} lights have no power: no photons, no shadow rays",
                lights.lights().len()
            );
            stats.skip("emission.zero_power", why);
        }
        Ok(Prepared { scene, accel, lights, stats })
    }

    /// The scene as rendered (moved onto the origin if it was far from it).
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    pub fn accel(&self) -> &AnyAccel {
        &self.accel
    }

    /// What a batch of images of this scene shares ([`Shared`]); `batch`: keep each pass's
    /// two-pass photon maps for the images after the first (one image: nothing is kept).
    pub fn shared(&self, batch: bool) -> Shared {
        Shared { analysis: maps::Analysis::of(&self.scene, &self.lights), maps: photon::MapCache::new(batch) }
    }

    /// Renders the scene's camera on the current rayon pool's threads.
    pub fn render(&self, cfg: &RenderConfig, progress: &dyn Progress, control: Control<'_>) -> RenderOutput {
        let camera = self.scene.camera.with_resolution(cfg.width, cfg.height);
        self.render_view(&self.shared(false), std::slice::from_ref(&camera), 0, cfg, progress, control)
    }

    /// Renders `views[view]` (at `cfg`'s resolution) on the current rayon pool's threads, one
    /// image of a batch that renders every one of `views` with the photon maps in `shared`.
    ///
    /// # Panics
    /// If `view` is out of range.
    pub fn render_view(
        &self,
        shared: &Shared,
        views: &[Camera],
        view: usize,
        cfg: &RenderConfig,
        progress: &dyn Progress,
        control: Control<'_>,
    ) -> RenderOutput {
        let mut stats = self.stats.clone();
        stats.threads = rayon::current_num_threads();
        let camera = views[view].with_resolution(cfg.width, cfg.height);
        crate::dispatch!(&self.accel, a => {
            let frame = Frame { scene: &self.scene, accel: a, lights: &self.lights, camera, views };
            render(&frame, shared, cfg, progress, control, stats)
        })
    }
}

/// Builds the accelerator `cfg` asks for and renders: the whole pipeline behind `photonmap
/// render`, for library users and tests.
pub fn render_scene(
    scene: &Scene,
    cfg: &RenderConfig,
    progress: &dyn Progress,
) -> Result<RenderOutput, AccelError> {
    render_scene_with(scene, cfg, progress, Control::default())
}

/// [`render_scene`] steered by `control` (cancel flag, checkpoints, start of the time budget).
pub fn render_scene_with(
    scene: &Scene,
    cfg: &RenderConfig,
    progress: &dyn Progress,
    control: Control<'_>,
) -> Result<RenderOutput, AccelError> {
    Ok(Prepared::new(scene, cfg)?.render(cfg, progress, control))
}
