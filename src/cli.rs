//! Command-line interface: clap definitions, validated once into library configs.

use clap::{Args, Parser, Subcommand};
use photonmap::accel::AccelKind;
use photonmap::config::{
    CausticPass, ColorMode, Component, IndirectMode, Integrator, Kernel, RenderSettings,
};
use std::path::PathBuf;

/// A photon-mapping renderer: Jensen's two-pass method with Embree or a pure-Rust BVH.
#[derive(Parser, Debug)]
#[command(name = "photonmap", version, about)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Render a scene to OpenEXR (and optionally a PNG preview).
    Render(Box<RenderArgs>),
    /// Cast the same rays through Embree, the BVH (and brute force on small scenes) and report
    /// how often they disagree.
    Agree(AgreeArgs),
    /// Compare two EXR images: RMSE and relative MSE over all pixels and channels, means.
    Compare {
        /// The image to judge.
        image: PathBuf,
        /// The reference.
        reference: PathBuf,
        /// Box-downsample the reference by this factor first (when the image is smaller).
        #[arg(long)]
        downsample: Option<usize>,
        /// Print one JSON object.
        #[arg(long)]
        json: bool,
        /// Write the absolute difference, scaled by this factor, as a PNG.
        #[arg(long, value_name = "PNG")]
        diff: Option<PathBuf>,
        /// Scale of the difference image.
        #[arg(long, default_value_t = 10.0)]
        diff_scale: f32,
    },
    /// Error against time: render a scene with several methods at several time budgets and
    /// compare each image with a reference (table, CSV, log-log SVG plot).
    Converge(ConvergeArgs),
    /// Run the stress suite (numerical stability: extreme scales, grazing light, coplanar
    /// surfaces, closed boxes, extreme powers, a million photons on a point, a million slivers)
    /// and print a table; exits non-zero if any check fails.
    Stress(StressArgs),
    /// Speed: render a scene several times on one thread and on all threads, and report medians
    /// of photons, gather queries and rays per second against the raw ray rate of the same
    /// accelerator measured in the same run.
    Bench(Box<BenchArgs>),
    /// Print what a scene holds: triangles, materials, lights, bounds.
    Info {
        /// Scene file (TOML).
        scene: PathBuf,
    },
}

#[derive(Args, Debug)]
pub struct RenderArgs {
    /// Scene file (TOML).
    pub scene: PathBuf,
    /// Output image, float RGB OpenEXR.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Also write a tone-mapped sRGB PNG preview here.
    #[arg(long)]
    pub png: Option<PathBuf>,
    /// Write a JSON report (stages, photons, rays, timings) here.
    #[arg(long)]
    pub stats: Option<PathBuf>,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// No progress bars.
    #[arg(short, long)]
    pub quiet: bool,
    /// Image width (default: the scene's camera).
    #[arg(long)]
    pub width: Option<u32>,
    /// Image height (default: the scene's camera).
    #[arg(long)]
    pub height: Option<u32>,
    /// Write the image so far (EXR, and PNG if asked) every this many passes.
    #[arg(long, value_name = "K")]
    pub checkpoint_every: Option<u32>,
    #[command(flatten)]
    pub settings: SettingsArgs,
}

/// Settings that may also be given in the scene's `[render]` table; flags win.
#[derive(Args, Debug, Default)]
pub struct SettingsArgs {
    /// Ray-casting backend [default: embree when built with it, else bvh].
    #[arg(long, value_enum)]
    pub accel: Option<AccelKind>,
    /// Use Embree's robust (watertight) mode [default: true].
    #[arg(long)]
    pub robust: Option<bool>,
    /// Photons emitted for the indirect map [default: 1000000].
    #[arg(long)]
    pub photons: Option<u64>,
    /// Photons aimed at specular objects for the caustic map [default: 300000].
    #[arg(long)]
    pub caustic_photons: Option<u64>,
    /// Camera samples per pixel [default: 64].
    #[arg(long)]
    pub spp: Option<u32>,
    /// Random seed; the same seed gives the same image for any thread count [default: 1].
    #[arg(long)]
    pub seed: Option<u64>,
    /// Longest photon path [default: 64].
    #[arg(long)]
    pub max_bounces: Option<u32>,
    /// Longest camera path through mirrors and glass [default: 16].
    #[arg(long)]
    pub max_depth: Option<u32>,
    /// Photons per indirect radiance estimate [default: 100].
    #[arg(long)]
    pub gather_photons: Option<u32>,
    /// Largest indirect gather radius, scene units [default: a tenth of the scene radius].
    #[arg(long)]
    pub gather_radius: Option<f32>,
    /// Photons per caustic radiance estimate [default: 60].
    #[arg(long)]
    pub caustic_gather_photons: Option<u32>,
    /// Largest caustic gather radius [default: a quarter of the indirect one].
    #[arg(long)]
    pub caustic_gather_radius: Option<f32>,
    /// Indirect light from the map's estimate or by final gathering [default: estimate].
    #[arg(long, value_enum)]
    pub indirect: Option<IndirectMode>,
    /// Rays per final gather [default: 32].
    #[arg(long)]
    pub final_gather_rays: Option<u32>,
    /// Photons carry one colour channel (three maps, the lecture's way) or RGB [default: rgb].
    #[arg(long, value_enum)]
    pub color: Option<ColorMode>,
    /// Density-estimation kernel [default: cone].
    #[arg(long, value_enum)]
    pub kernel: Option<Kernel>,
    /// Shadow-ray samples per shading point [default: 1].
    #[arg(long)]
    pub light_samples: Option<u32>,
    /// Precompute irradiance at photon positions and read it at diffuse surfaces instead of
    /// gathering photons there (Christensen 1999) [default: true].
    #[arg(long)]
    pub irradiance_cache: Option<bool>,
    /// Render only one term of the sum: emitted, direct, caustic or indirect [default: all].
    #[arg(long, value_enum)]
    pub component: Option<Component>,
    /// Photon mapping, or the path tracer (next-event estimation and MIS) as a cross-check; the
    /// path tracer ignores the photon settings and uses --max-depth for every bounce
    /// [default: photon].
    #[arg(long, value_enum)]
    pub integrator: Option<Integrator>,
    /// Render this many passes and average them (progressive photon mapping shrinks its radii
    /// between passes) [default: 1; sppm: 64 unless --time is given].
    #[arg(long)]
    pub passes: Option<u32>,
    /// Time budget in seconds from the start of the command: passes stop before the budget
    /// would be exceeded and the image so far is written.
    #[arg(long, value_name = "SECONDS")]
    pub time: Option<f64>,
    /// Progressive photon mapping's alpha, the fraction of new photons kept when the radius
    /// shrinks, in (0, 1) [default: 0.7].
    #[arg(long)]
    pub alpha: Option<f32>,
    /// Aim caustic photons at the mirrors and glass (bounding-sphere projection map); false:
    /// emit them from the lights as usual and keep the light-specular-diffuse paths
    /// [default: true].
    #[arg(long)]
    pub caustic_aim: Option<bool>,
    /// Run the caustic photon pass when the scene analysis says it is needed (auto), always
    /// (on) or never (off) [default: auto].
    #[arg(long, value_enum)]
    pub caustic_pass: Option<CausticPass>,
}

impl SettingsArgs {
    pub fn to_settings(&self) -> RenderSettings {
        RenderSettings {
            accel: self.accel,
            photons: self.photons,
            caustic_photons: self.caustic_photons,
            spp: self.spp,
            seed: self.seed,
            max_bounces: self.max_bounces,
            max_depth: self.max_depth,
            gather_photons: self.gather_photons,
            gather_radius: self.gather_radius,
            caustic_gather_photons: self.caustic_gather_photons,
            caustic_gather_radius: self.caustic_gather_radius,
            indirect: self.indirect,
            final_gather_rays: self.final_gather_rays,
            color: self.color,
            kernel: self.kernel,
            light_samples: self.light_samples,
            robust: self.robust,
            irradiance_cache: self.irradiance_cache,
            component: self.component,
            integrator: self.integrator,
            passes: self.passes,
            time: self.time,
            alpha: self.alpha,
            caustic_aim: self.caustic_aim,
            caustic_pass: self.caustic_pass,
        }
    }
}

#[derive(Args, Debug)]
pub struct AgreeArgs {
    /// Scene file (TOML).
    pub scene: PathBuf,
    /// Rays in all, split evenly among the kinds (camera, random, surface, grazing, shadow).
    #[arg(long, default_value_t = 100_000)]
    pub rays: usize,
    /// Random seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Print one JSON object instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Use Embree's robust mode.
    #[arg(long, default_value_t = true, action = clap::ArgAction::Set)]
    pub robust: bool,
}

#[derive(Args, Debug)]
pub struct ConvergeArgs {
    /// Scene file (TOML).
    pub scene: PathBuf,
    /// Reference image (EXR); the renders take its size unless --width/--height are given.
    #[arg(long)]
    pub reference: PathBuf,
    /// Box-downsample the reference by this factor first (renders get the smaller size).
    #[arg(long)]
    pub downsample: Option<usize>,
    /// Time budgets in seconds.
    #[arg(long, value_delimiter = ',', default_value = "1,2,4,8,16,32")]
    pub budgets: Vec<f64>,
    /// Methods to compare [default: all].
    #[arg(long, value_enum, value_delimiter = ',')]
    pub methods: Vec<photonmap::converge::Method>,
    /// Write the points as CSV here.
    #[arg(long)]
    pub csv: Option<PathBuf>,
    /// Write the log-log plot of RMSE against seconds as SVG here.
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Other renderers' errors against the same reference (CSV: scene,renderer,seconds,rmse;
    /// rows for this scene file's name are used): drawn dashed on the plot, and raced at equal
    /// time in a second table.
    #[arg(long, value_name = "CSV")]
    pub peers: Option<PathBuf>,
    /// Random seed of every render.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Ray-casting backend [default: embree when built with it, else bvh].
    #[arg(long, value_enum)]
    pub accel: Option<AccelKind>,
}

#[derive(Args, Debug)]
pub struct StressArgs {
    /// Run only the cases whose name contains this (furnace, grazing, coplanar, touching,
    /// camera-inside, light-inside, back-facing, power, duplicates, zero-photons, one-triangle,
    /// slivers).
    #[arg(long)]
    pub filter: Option<String>,
    /// Render with these backends only [default: embree and bvh, or bvh without Embree].
    #[arg(long, value_enum, value_delimiter = ',')]
    pub accel: Vec<AccelKind>,
    /// Rays per backend-agreement check (0 skips them).
    #[arg(long, default_value_t = 10_000)]
    pub agree_rays: usize,
    /// Fewer samples and photons (what `tests/stress.rs` runs).
    #[arg(long)]
    pub quick: bool,
    /// Print the rows as JSON lines instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
}

#[derive(Args, Debug)]
pub struct BenchArgs {
    /// Scene file (TOML).
    pub scene: PathBuf,
    /// Image width.
    #[arg(long, default_value_t = 128)]
    pub width: u32,
    /// Image height.
    #[arg(long, default_value_t = 128)]
    pub height: u32,
    /// Renders per thread count; the table shows medians.
    #[arg(long, default_value_t = 3)]
    pub runs: usize,
    /// Thread counts to compare [default: 1 and all cores].
    #[arg(long, value_delimiter = ',')]
    pub threads: Vec<usize>,
    /// Rays per kind (camera, incoherent, shadow) of the raw-rate measurement after each render.
    #[arg(long, default_value_t = 200_000)]
    pub raw_rays: usize,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub settings: SettingsArgs,
}
