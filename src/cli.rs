//! Command-line interface: clap definitions, validated once into library configs.

use clap::builder::TypedValueParser;
use clap::{Args, Parser, Subcommand};
use photonmap::accel::AccelKind;
use photonmap::choice::Choice;
use photonmap::config::RenderSettings;
use photonmap::film::ToneCurve;
use std::path::PathBuf;

/// A photon-mapping renderer: Jensen's two-pass method with Embree or a pure-Rust BVH.
#[derive(Parser, Debug)]
#[command(name = "photonmap", version = version_text(), about)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

/// What `--version` prints after the name: the version, the ray casters this build has (the
/// Embree version its bindings were made from, or "BVH only"), the features and the threads.
fn version_text() -> &'static str {
    static TEXT: std::sync::OnceLock<String> = std::sync::OnceLock::new();
    TEXT.get_or_init(|| {
        #[cfg(feature = "embree")]
        let (rays, features) = (
            format!("Embree {} (the default) and the pure-Rust BVH", photonmap::accel::embree::version()),
            "embree",
        );
        #[cfg(not(feature = "embree"))]
        let (rays, features) = ("the pure-Rust BVH only (built without Embree)".to_string(), "none");
        let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
        format!(
            "{}\nrays:     {rays}\nfeatures: {features}\nthreads:  {threads} available here",
            env!("CARGO_PKG_VERSION")
        )
    })
}

/// The command line, parsed; every subcommand takes negative numbers as values (`--time -1`
/// reaches the range check that names the flag instead of being read as a flag itself).
pub fn parse() -> Cli {
    use clap::{CommandFactory, FromArgMatches};
    let command = Cli::command().mut_subcommands(|c| c.allow_negative_numbers(true));
    let parsed = command.try_get_matches().and_then(|m| Cli::from_arg_matches(&m));
    parsed.unwrap_or_else(|e| refuse(e))
}

/// Help and `--version` as clap prints them; a usage error as the one line every other error
/// is (`photonmap: error: invalid value '-5' for '--width <WIDTH>': …`), exit code 2.
fn refuse(e: clap::Error) -> ! {
    use clap::error::ErrorKind;
    if matches!(e.kind(), ErrorKind::DisplayHelp | ErrorKind::DisplayVersion)
        || matches!(e.kind(), ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand)
    {
        e.exit()
    }
    let text = e.render().to_string();
    let first: Vec<&str> = text.lines().take_while(|l| !l.trim().is_empty()).map(str::trim).collect();
    eprintln!("photonmap: error: {}", first.join(" ").trim_start_matches("error: "));
    std::process::exit(2)
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Render a scene to OpenEXR (and optionally a PNG preview).
    Render(Box<RenderArgs>),
    /// Cast the same rays through Embree, the BVH (and brute force on small scenes) and report
    /// how often they disagree.
    Agree(AgreeArgs),
    /// Compare two EXR images: RMSE and relative MSE over all pixels and channels, means.
    Compare(CompareArgs),
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
    /// Add up partial films (`render --pass-range`) into the image one process rendering
    /// every pass would have made, bit for bit, and report its estimated error.
    Merge(MergeArgs),
    /// Print what a scene holds: geometry, bounds, cameras, textures, materials (with the
    /// triangles using each), lights with their power, portals.
    Info {
        /// Scene file (TOML, or a glTF).
        scene: PathBuf,
        /// Print JSON instead of tables.
        #[arg(long)]
        json: bool,
    },
}

#[derive(Args, Debug)]
pub struct RenderArgs {
    /// Scene file (TOML).
    pub scene: PathBuf,
    /// Output image, its format from the extension: .exr (float RGB OpenEXR, with the record
    /// --resume reads) or .png (8-bit sRGB, linear radiance clamped at 1). For many images a
    /// pattern: {camera}, {frame} and {frame:04} (zero-padded) are replaced, e.g.
    /// out/{camera}_{frame:04}.exr [default: the scene's name in the working directory, SCENE.exr,
    /// or SCENE_{camera}_{frame:04}.exr with what tells many images apart]
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Also write an 8-bit sRGB PNG preview here (.png; --exposure and --tonemap say how the
    /// radiance is shown); a pattern like -o's
    #[arg(long)]
    pub png: Option<PathBuf>,
    /// Exposure of PNG outputs in stops: +1 doubles the radiance before the tone curve (the
    /// EXR stays linear)
    #[arg(long, value_name = "EV", default_value_t = 0.0, value_parser = exposure)]
    pub exposure: f32,
    /// Tone curve of PNG outputs: clamp (radiance above 1 is white), filmic (Hable) or aces
    /// (Narkowicz's fit), the latter two keeping highlights from clipping
    #[arg(long, value_name = "CURVE", default_value = "clamp", value_parser = choice::<ToneCurve>())]
    pub tonemap: ToneCurve,
    /// Write a JSON report (stages, photons, rays, timings) here; for many images, one report
    /// with the batch's totals and every image's own
    #[arg(long)]
    pub stats: Option<PathBuf>,
    /// Frames to render, as render farms write them: 1-30,40,50-60 (ranges inclusive; A-BxK or
    /// A-B:K takes every K-th) [default: each camera's animation, or frame 0 of a still camera]
    #[arg(long, value_name = "LIST")]
    pub frames: Option<String>,
    /// Step for the --frames ranges that give none
    #[arg(long, value_name = "K", default_value_t = 1)]
    pub frame_step: u32,
    /// Cameras to render, by name (comma-separated) [default: every camera of the scene]
    #[arg(long, value_name = "NAMES", value_delimiter = ',')]
    pub cameras: Option<Vec<String>>,
    /// Skip images whose output already holds that very image, finished (same scene, settings,
    /// camera and frame, as recorded in its header): a stopped batch goes on where it stopped
    #[arg(long)]
    pub resume: bool,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// No progress bars.
    #[arg(short, long)]
    pub quiet: bool,
    /// Treat every warning about the scene (an unused material, no light, a texture or MTL
    /// statement not rendered as written) as an error: stop before any work
    #[arg(long)]
    pub strict: bool,
    /// Image width (default: the scene's camera).
    #[arg(long)]
    pub width: Option<u32>,
    /// Image height (default: the scene's camera).
    #[arg(long)]
    pub height: Option<u32>,
    /// Write the image so far (EXR, and PNG if asked) every this many passes.
    #[arg(long, value_name = "K")]
    pub checkpoint_every: Option<u32>,
    /// Render only passes A to B-1 of the --passes N render and write them as a partial film
    /// (.exr: the exact sums of the passes) for `photonmap merge`; any split of 0..N merges
    /// into the image of one process (pppm, photon and path; not sppm)
    #[arg(long, value_name = "A..B")]
    pub pass_range: Option<String>,
    /// Add the estimated error of each pixel to the EXR as a channel `error` (its RMSE over
    /// the three channels, estimated from the spread of the passes: 2 passes at least)
    #[arg(long)]
    pub error_layer: bool,
    #[command(flatten)]
    pub settings: SettingsArgs,
}

#[derive(Args, Debug)]
pub struct MergeArgs {
    /// Partial films written by `photonmap render --pass-range`, in any order.
    #[arg(required = true)]
    pub parts: Vec<PathBuf>,
    /// The image (.exr), with the record `render` writes (so `--resume` knows it).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Also write an 8-bit sRGB PNG preview here.
    #[arg(long)]
    pub png: Option<PathBuf>,
    /// Exposure of the PNG in stops.
    #[arg(long, value_name = "EV", default_value_t = 0.0, value_parser = exposure)]
    pub exposure: f32,
    /// Tone curve of the PNG: clamp, filmic or aces.
    #[arg(long, value_name = "CURVE", default_value = "clamp", value_parser = choice::<ToneCurve>())]
    pub tonemap: ToneCurve,
    /// Write a JSON report (the parts, the passes, the estimated error) here.
    #[arg(long)]
    pub stats: Option<PathBuf>,
    /// Merge what is there when passes are missing (the image of the passes present, marked
    /// partial in its header) instead of refusing.
    #[arg(long)]
    pub partial: bool,
    /// Add the per-pixel estimated error as a channel `error`.
    #[arg(long)]
    pub error_layer: bool,
    /// Write a partial film of the parts' passes (consecutive, not necessarily all) instead of
    /// the image: a larger part, for merging in a tree (each node its own parts, then the
    /// nodes' parts).
    #[arg(long, conflicts_with_all = ["png", "error_layer", "partial", "target_error"])]
    pub part: bool,
    /// Exit with status 3 (after writing) unless the estimated relative RMSE is at most this:
    /// a loop that renders more parts until the image is good enough stops on status 0.
    #[arg(long, value_name = "E")]
    pub target_error: Option<f64>,
}

/// Settings that may also be given in the scene's `[render]` table; flags win. One flag per
/// field of [`RenderSettings`] (`--gather-photons` for `gather_photons`), with its doc comment
/// as help and its own parser, so the flags and the file keys cannot drift apart.
#[derive(Debug, Default, Clone)]
pub struct SettingsArgs(pub RenderSettings);

impl SettingsArgs {
    pub fn to_settings(&self) -> RenderSettings {
        self.0.clone()
    }
}

/// `--gather-photons` for `gather_photons`.
fn flag(name: &str) -> String {
    name.replace('_', "-")
}

impl clap::FromArgMatches for SettingsArgs {
    fn from_arg_matches(m: &clap::ArgMatches) -> Result<Self, clap::Error> {
        let mut settings = RenderSettings::default();
        for f in RenderSettings::FIELDS {
            if let Some(text) = m.get_one::<String>(f.name) {
                // Values were checked by each flag's parser; this cannot fail.
                settings.set(f.name, text).map_err(|e| {
                    clap::Error::raw(
                        clap::error::ErrorKind::ValueValidation,
                        format!("--{}: {e}\n", flag(f.name)),
                    )
                })?;
            }
        }
        Ok(SettingsArgs(settings))
    }

    fn update_from_arg_matches(&mut self, m: &clap::ArgMatches) -> Result<(), clap::Error> {
        *self = Self::from_arg_matches(m)?;
        Ok(())
    }
}

impl clap::Args for SettingsArgs {
    fn augment_args(cmd: clap::Command) -> clap::Command {
        RenderSettings::FIELDS.iter().fold(cmd, |cmd, f| {
            let help: String = f.help.split_whitespace().collect::<Vec<_>>().join(" ");
            let help = help.trim_end_matches('.').to_string();
            let check = f.check;
            let arg = clap::Arg::new(f.name)
                .long(flag(f.name))
                .value_name(f.value_name)
                .help(help)
                .value_parser(move |text: &str| check(text).map(|()| text.to_string()));
            let arg = if f.choices.is_empty() {
                arg
            } else {
                let names = f.choices.iter().map(|&c| clap::builder::PossibleValue::new(c));
                let choices = clap::builder::PossibleValuesParser::new(names);
                arg.value_parser(choices)
            };
            cmd.arg(arg)
        })
    }

    fn augment_args_for_update(cmd: clap::Command) -> clap::Command {
        Self::augment_args(cmd)
    }
}

/// An exposure in stops: finite, within ±64 (beyond, every pixel is black or white).
fn exposure(text: &str) -> Result<f32, String> {
    let ev: f32 = text.parse().map_err(|_| format!("`{text}` is not a number of stops"))?;
    if ev.is_finite() && ev.abs() <= 64.0 {
        Ok(ev)
    } else {
        Err(format!("{text} is not a finite number of stops in -64..=64"))
    }
}

/// A flag taking the name of one variant of `T`.
fn choice<T: Choice + Send + Sync>() -> impl clap::builder::TypedValueParser<Value = T> {
    clap::builder::PossibleValuesParser::new(T::NAMES)
        .map(|name| T::from_name(&name).expect("clap accepts only the possible values"))
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

/// `photonmap compare`.
#[derive(Args, Debug)]
pub struct CompareArgs {
    /// The image to judge.
    pub image: PathBuf,
    /// The reference (or give --exact).
    #[arg(required_unless_present = "exact")]
    pub reference: Option<PathBuf>,
    /// Judge against this exact radiance everywhere instead of a reference image (the white
    /// furnace: 2).
    #[arg(long, value_name = "RADIANCE", conflicts_with_all = ["reference", "downsample"])]
    pub exact: Option<f32>,
    /// Box-downsample the reference by this factor first (when the image is smaller).
    #[arg(long)]
    pub downsample: Option<usize>,
    /// Judge only the pixels x0 <= x < x1, y0 <= y < y1 (of the image, from its top left
    /// corner): a region of interest, such as an object the bias sits on.
    #[arg(long, value_name = "X0,Y0,X1,Y1", value_parser = parse_region)]
    pub region: Option<[usize; 4]>,
    /// Print one JSON object.
    #[arg(long)]
    pub json: bool,
    /// Write the absolute difference, scaled by this factor, as a PNG.
    #[arg(long, value_name = "PNG")]
    pub diff: Option<PathBuf>,
    /// Scale of the difference image.
    #[arg(long, default_value_t = 10.0)]
    pub diff_scale: f32,
}

#[derive(Args, Debug)]
pub struct ConvergeArgs {
    /// Scene file (TOML).
    pub scene: PathBuf,
    /// Reference image (EXR); the renders take its size (after --downsample).
    #[arg(long, required_unless_present = "exact")]
    pub reference: Option<PathBuf>,
    /// Judge against this exact radiance everywhere instead of a reference image (the white
    /// furnace: 2); the renders take the scene camera's size.
    #[arg(long, value_name = "RADIANCE", conflicts_with_all = ["reference", "downsample"])]
    pub exact: Option<f32>,
    /// The reference's own noise (its RMSE against the converged image, as its notes say):
    /// taken out of each render's RMSE in quadrature for the true error that the estimated
    /// error (the `est/true` column) is judged against [default: 0, and 0 with --exact].
    #[arg(long, value_name = "RMSE", conflicts_with = "exact")]
    pub reference_noise: Option<f64>,
    /// Box-downsample the reference by this factor first (renders get the smaller size).
    #[arg(long)]
    pub downsample: Option<usize>,
    /// Time budgets in seconds.
    #[arg(long, value_delimiter = ',', default_value = "1,2,4,8,16,32")]
    pub budgets: Vec<f64>,
    /// Methods to compare [default: all].
    #[arg(long, value_parser = choice::<photonmap::tools::converge::Method>(), value_delimiter = ',')]
    pub methods: Vec<photonmap::tools::converge::Method>,
    /// Write the points as CSV here.
    #[arg(long)]
    pub csv: Option<PathBuf>,
    /// Write the log-log plot of RMSE against seconds as SVG here.
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Other renderers' errors against the same reference (CSV:
    /// scene,renderer,width,height,seconds,rmse; rows for this scene file's name are used, and
    /// refused unless measured at the renders' size): drawn dashed on the plot, and raced at
    /// equal time in a second table.
    #[arg(long, value_name = "CSV")]
    pub peers: Option<PathBuf>,
    /// Random seed of every render.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Ray-casting backend [default: embree when built with it, else bvh].
    #[arg(long, value_parser = choice::<AccelKind>())]
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
    #[arg(long, value_parser = choice::<AccelKind>(), value_delimiter = ',')]
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

/// `--region X0,Y0,X1,Y1`: four pixel coordinates, the first corner strictly before the second.
fn parse_region(text: &str) -> Result<[usize; 4], String> {
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    let numbers: Vec<usize> = parts
        .iter()
        .map(|p| p.parse::<usize>().map_err(|_| format!("`{p}` is not a pixel coordinate")))
        .collect::<Result<_, _>>()?;
    match numbers[..] {
        [x0, y0, x1, y1] if x0 < x1 && y0 < y1 => Ok([x0, y0, x1, y1]),
        [_, _, _, _] => Err(format!("{text}: the region is empty (X0 < X1 and Y0 < Y1 are needed)")),
        _ => Err(format!("{text}: four numbers X0,Y0,X1,Y1 are needed")),
    }
}
