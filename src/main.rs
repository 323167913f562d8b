//! The `photonmap` command: render, compare, agree, converge, stress, bench, info. `cli` holds
//! the flags (clap lives here, not in the library), `progress` the terminal's progress bars;
//! everything else is the library's.

mod cli;
mod out;
mod progress;

use anyhow::{anyhow, bail, Context, Result};
use cli::Command;
use out::outln;
use photonmap::accel::AccelOptions;
use photonmap::batch;
use photonmap::config::{ConfigError, RenderSettings};
use photonmap::frame::{Progress, Quiet};
use photonmap::integrator;
use photonmap::scene::Scene;
use photonmap::stats::Stats;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

fn main() -> ExitCode {
    if let Err(missing) = cpu_supported() {
        eprintln!(
            "photonmap: error: this build needs a CPU with {missing} (x86-64-v3, set in \
             .cargo/config.toml); rebuild with RUSTFLAGS=\"-C target-cpu=x86-64\" for this one"
        );
        return ExitCode::FAILURE;
    }
    let cli = cli::parse();
    let result = match cli.command {
        Command::Render(args) => match render(*args) {
            // Stopped by Ctrl-C after writing the image so far: the shell's code for SIGINT.
            Ok(Finished::Interrupted) => return ExitCode::from(130),
            Ok(Finished::Done | Finished::TargetMissed) => Ok(()),
            Err(e) => Err(e),
        },
        Command::Merge(args) => match merge(args) {
            Ok(Finished::TargetMissed) => return ExitCode::from(3),
            Ok(_) => Ok(()),
            Err(e) => Err(e),
        },
        Command::Agree(args) => agree(args),
        Command::Info { scene, json } => info(&scene, json),
        Command::Stress(args) => stress(args),
        Command::Converge(args) => converge(args),
        Command::Bench(args) => bench(*args),
        Command::Compare(args) => compare(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("photonmap: error: {}", message(&e));
            ExitCode::FAILURE
        }
    }
}

/// Whether the CPU has the instruction-set extensions this build was compiled for (the project
/// builds for x86-64-v3: `.cargo/config.toml`), or the first one missing: checked before
/// anything else runs, so an older CPU gets a line saying so instead of an illegal
/// instruction.
#[inline(never)]
fn cpu_supported() -> Result<(), &'static str> {
    #[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
    {
        let features = [
            ("avx2", std::arch::is_x86_feature_detected!("avx2")),
            ("fma", std::arch::is_x86_feature_detected!("fma")),
            ("bmi1", std::arch::is_x86_feature_detected!("bmi1")),
            ("bmi2", std::arch::is_x86_feature_detected!("bmi2")),
            ("lzcnt", std::arch::is_x86_feature_detected!("lzcnt")),
            ("movbe", std::arch::is_x86_feature_detected!("movbe")),
            ("f16c", std::arch::is_x86_feature_detected!("f16c")),
        ];
        if let Some((name, _)) = features.iter().find(|(_, present)| !present) {
            return Err(name);
        }
    }
    Ok(())
}

/// An error and its causes on one line, each cause said once: a cause whose text the message
/// already holds (an error that prints its source, as `thiserror`'s `{source}` does) is not
/// repeated (`x.exr: Is a directory`, not `x.exr: Is a directory: Is a directory`).
fn message(e: &anyhow::Error) -> String {
    let mut text = String::new();
    for cause in e.chain() {
        let cause = cause.to_string();
        if !text.contains(&cause) {
            if !text.is_empty() {
                text.push_str(": ");
            }
            text.push_str(&cause);
        }
    }
    text
}

fn pool(threads: Option<usize>) -> Result<rayon::ThreadPool> {
    let mut b = rayon::ThreadPoolBuilder::new().start_handler(|_| photonmap::accel::init_tracing_thread());
    if let Some(t) = threads {
        if t == 0 || t > 4096 {
            bail!("--threads {t}: must be in 1..=4096");
        }
        b = b.num_threads(t);
    }
    b.build().context("could not start the worker threads")
}

/// How a render ended.
enum Finished {
    Done,
    /// Ctrl-C stopped a progressive render; the passes done were written.
    Interrupted,
    /// `merge --target-error`: written, but the estimated error is above the target.
    TargetMissed,
}

/// Set by the first Ctrl-C of a progressive render.
static STOP: AtomicBool = AtomicBool::new(false);

/// Ctrl-C stops a progressive render after the pass under way, and the image so far is
/// written; a second Ctrl-C, or one during a single-pass render, quits at once (any existing
/// output file is left as it was: images are written whole or not at all).
fn install_interrupt_handler(progressive: bool) -> Result<()> {
    ctrlc::set_handler(move || {
        if progressive && !STOP.swap(true, Ordering::SeqCst) {
            eprintln!("\nphotonmap: interrupted; finishing this pass to write the image so far (Ctrl-C again to quit without writing)");
        } else {
            eprintln!("\nphotonmap: interrupted: nothing written");
            std::process::exit(130);
        }
    })
    .context("could not install the Ctrl-C handler")
}

fn render(args: cli::RenderArgs) -> Result<Finished> {
    let wall = Instant::now();
    let mut stats = Stats::default();
    let scene = stats.run("load", "parse the scene, OBJ and MTL", |_| Scene::load(&args.scene))?;
    if args.strict && !scene.warnings.is_empty() {
        let more = match scene.warnings.len() - 1 {
            0 => String::new(),
            n => format!(" (and {n} more warning{})", if n == 1 { "" } else { "s" }),
        };
        bail!("--strict: {}{more}", scene.warnings[0]);
    }
    for w in &scene.warnings {
        eprintln!("photonmap: warning: {w}");
    }
    let settings = scene.render.overridden_by(&args.settings.to_settings());
    let frames = match &args.frames {
        Some(list) => Some(
            batch::frames::parse_frames(list, args.frame_step)
                .map_err(|e| anyhow::anyhow!("--frames {list}: {e}"))?,
        ),
        None => None,
    };
    let selection = batch::plan::Selection { cameras: args.cameras.as_deref(), frames: frames.as_deref() };
    let output = match &args.output {
        Some(o) => o.clone(),
        None => batch::plan::default_output(&scene, selection).map_err(anyhow::Error::msg)?,
    };
    let jobs =
        batch::plan::plan(&scene, selection, &output, args.png.as_deref()).map_err(anyhow::Error::msg)?;
    if args.resume {
        if let Some(j) =
            jobs.iter().find(|j| batch::plan::Format::of(&j.output) != Ok(batch::plan::Format::Exr))
        {
            bail!(
                "{}: --resume needs .exr outputs (a PNG holds no record of how it was made)",
                j.output.display()
            );
        }
    }
    let size = |c: usize| {
        let cam = &scene.cameras[c];
        (args.width.unwrap_or(cam.width), args.height.unwrap_or(cam.height))
    };
    let cfgs = jobs
        .iter()
        .map(|job| {
            let (w, h) = size(job.camera);
            let flags = args.settings.to_settings();
            let size_flags = args.width.is_some() || args.height.is_some();
            settings.resolve(w, h).map_err(|e| setting_error(e, &flags, size_flags, &args.scene))
        })
        .collect::<Result<Vec<_>>>()?;
    let pass_range = match &args.pass_range {
        Some(text) => Some(check_pass_range(text, &args, &jobs, &cfgs)?),
        None => None,
    };
    let outputs = jobs.iter().flat_map(|j| std::iter::once(&j.output).chain(&j.png));
    if let Some(stats) = &args.stats {
        if let Some(o) = outputs.clone().find(|o| same_file(o, stats)) {
            bail!("{}: --stats names an image of the render too", o.display());
        }
    }
    check_outputs(outputs.chain(&args.stats))?;
    let pool = pool(args.threads)?;
    let bars = progress::Bars::new(args.quiet);
    // One bar: over the images of a batch, or over the stages of one image.
    let (outer, inner): (&dyn Progress, &dyn Progress) =
        if jobs.len() > 1 { (&bars, &Quiet) } else { (&Quiet, &bars) };
    install_interrupt_handler(cfgs.iter().any(|c| c.is_progressive()))?;
    if args.checkpoint_every == Some(0) {
        bail!("--checkpoint-every 0: must be at least 1");
    }
    let options = batch::run::Options {
        resume: args.resume,
        cancel: Some(&STOP),
        checkpoint_every: args.checkpoint_every,
        started: wall,
        preview: photonmap::film::Tonemap { exposure: args.exposure, curve: args.tonemap },
        pass_range,
        error_layer: args.error_layer,
    };
    let load = stats.stages.clone();
    let (mut done, raw) = pool.install(|| -> Result<_> {
        let prepared = integrator::Prepared::new(&scene, &cfgs[0])?;
        let views = batch::plan::all_views(prepared.scene(), size);
        let done = batch::run::run(&prepared, &views, &jobs, &cfgs, options, outer, inner)?;
        // With --stats, a short measurement of the accelerator alone follows the renders.
        let raw = args.stats.as_ref().map(|_| {
            let rays = photonmap::tools::bench::STATS_CALIBRATION_RAYS;
            photonmap::dispatch!(prepared.accel(), a => {
                photonmap::tools::bench::raw_rays(prepared.scene(), a, &cfgs[0], rays)
            })
        });
        Ok((done, raw))
    })?;
    let peak = photonmap::stats::peak_memory_bytes().unwrap_or(0);
    for (i, d) in done.iter_mut().enumerate() {
        if let Some(s) = &mut d.stats {
            if i == 0 {
                s.stages.splice(0..0, load.iter().cloned());
            }
            s.scene = args.scene.display().to_string();
            s.peak_memory_bytes = peak;
            if let Some(raw) = raw {
                s.set_raw_rays(raw);
            }
        }
    }
    let seconds = wall.elapsed().as_secs_f64();
    if let [only] = &mut done[..] {
        if let Some(s) = &mut only.stats {
            s.wall_seconds = seconds;
        }
    }
    if let Some(path) = &args.stats {
        let json = match &done[..] {
            [only] => serde_json::to_string_pretty(&only.stats)?,
            _ => serde_json::to_string_pretty(&batch::run::BatchReport::new(&scene, &done, seconds))?,
        };
        std::fs::write(path, json)
            .with_context(|| format!("{}: could not write the stats", path.display()))?;
    }
    let rendered: Vec<&Stats> = done.iter().filter_map(|d| d.stats.as_ref()).collect();
    for s in &rendered {
        for w in &s.warnings {
            eprintln!("photonmap: warning: {w}");
        }
    }
    let cancelled = rendered.iter().any(|s| s.cancelled);
    let first = rendered.first().copied();
    if !args.quiet || cancelled {
        let (accel, threads) = first.map_or(("-".to_string(), 0), |s| (s.accel.clone(), s.threads));
        let cfg = &cfgs[0];
        let what = match &done[..] {
            [only] => {
                let passes = first.map_or(0, |s| s.passes);
                let passes = match pass_range {
                    Some((a, _)) => {
                        format!(" a pass, passes {a}..{} of {}", a + passes, cfg.passes.unwrap_or(0))
                    }
                    None if passes > 1 => format!(" a pass, {passes} passes"),
                    None => String::new(),
                };
                let skipped = if only.stats.is_none() { " already finished (--resume)" } else { "" };
                format!(
                    "{}{skipped} ({}x{}, {} spp{passes})",
                    only.job.output.display(),
                    cfg.width,
                    cfg.height,
                    cfg.spp
                )
            }
            _ => {
                let skipped = done.len() - rendered.len();
                let skipped = if skipped > 0 {
                    format!(", {skipped} already finished (--resume)")
                } else {
                    String::new()
                };
                let per_minute = rendered.len() as f64 / seconds * 60.0;
                format!("{} of {} images{skipped} ({per_minute:.1} a minute)", rendered.len(), jobs.len())
            }
        };
        eprintln!(
            "photonmap: {what} in {seconds:.2} s with {accel} on {threads} thread{}{}",
            if threads == 1 { "" } else { "s" },
            if cancelled { " (interrupted)" } else { "" }
        );
        if let (Some(e), 1) = (first.and_then(|s| s.error_estimate), done.len()) {
            eprintln!("photonmap: {}", e.describe());
        }
    }
    Ok(if cancelled { Finished::Interrupted } else { Finished::Done })
}

/// The passes `--pass-range A..B` asks for, refused unless they can be rendered apart: one
/// image, an integrator whose passes are independent, a pass count to be a part of, no time
/// budget or target error (a part is a fixed set of passes), an EXR output.
fn check_pass_range(
    text: &str,
    args: &cli::RenderArgs,
    jobs: &[batch::plan::Job],
    cfgs: &[photonmap::config::RenderConfig],
) -> Result<(u32, u32)> {
    use photonmap::config::Integrator;
    let range = photonmap::film::partial::parse_range(text)
        .ok_or_else(|| anyhow!("--pass-range {text}: not A..B with A < B (passes A to B-1, from 0)"))?;
    let (cfg, job) = match (cfgs, jobs) {
        ([cfg], [job]) => (cfg, job),
        _ => bail!(
            "--pass-range renders one image, not {}: choose one camera (--cameras) and frame (--frames)",
            jobs.len()
        ),
    };
    if matches!(cfg.integrator, Integrator::Progressive(_)) {
        bail!("--pass-range: sppm carries each pixel's statistics from pass to pass, so its passes cannot be rendered apart; use --integrator pppm");
    }
    let Some(total) = cfg.passes else {
        bail!("--pass-range {text} needs --passes N, the passes of the whole render it is a part of");
    };
    if range.end > total {
        bail!("--pass-range {text}: beyond the render's {total} passes (--passes)");
    }
    for (given, flag) in [
        (cfg.time.is_some(), "--time"),
        (cfg.target_error.is_some(), "--target-error"),
        (args.checkpoint_every.is_some(), "--checkpoint-every"),
        (args.png.is_some(), "--png"),
        (args.error_layer, "--error-layer"),
        (args.resume, "--resume"),
    ] {
        if given {
            bail!("--pass-range with {flag}: a part is a fixed set of passes for `photonmap merge`, which writes the image");
        }
    }
    if batch::plan::Format::of(&job.output) != Ok(batch::plan::Format::Exr) {
        bail!("{}: a partial film is an OpenEXR file (.exr)", job.output.display());
    }
    Ok((range.start, range.end))
}

/// `photonmap merge`: the parts added up, the image written with the parts' record, the
/// estimated error said (and written with `--stats`).
fn merge(args: cli::MergeArgs) -> Result<Finished> {
    let wall = Instant::now();
    if batch::plan::Format::of(&args.output) != Ok(batch::plan::Format::Exr) {
        bail!("{}: the merged image is an OpenEXR file (.exr); --png adds a preview", args.output.display());
    }
    if let Some(e) = args.target_error {
        if !(e.is_finite() && e > 0.0) {
            bail!("--target-error: {e} must be a finite relative error above 0 (0.01: 1 %)");
        }
    }
    check_outputs(std::iter::once(&args.output).chain(&args.png).chain(&args.stats))?;
    for part in &args.parts {
        if [Some(&args.output), args.png.as_ref(), args.stats.as_ref()]
            .into_iter()
            .flatten()
            .any(|o| same_file(o, part))
        {
            bail!("{}: a part is also an output of the merge", part.display());
        }
    }
    use batch::merge::Coverage;
    let coverage = match (args.part, args.partial) {
        (true, _) => Coverage::Contiguous,
        (false, true) => Coverage::Partial,
        (false, false) => Coverage::Whole,
    };
    let merged = batch::merge::merge(&args.parts, coverage).map_err(anyhow::Error::msg)?;
    if args.part {
        let record: Vec<(&str, String)> = merged
            .record
            .iter()
            .map(|(k, v)| {
                (*k, if *k == batch::meta::STATE { batch::run::PARTIAL_STATE.to_string() } else { v.clone() })
            })
            .collect();
        photonmap::film::partial::PartialFilm::write(
            &args.output,
            &merged.sums,
            merged.range.clone(),
            merged.total,
            &record,
        )?;
    } else {
        let film = merged.sums.mean();
        let error = if args.error_layer { merged.sums.error_film() } else { None };
        film.write_exr_with_error(&args.output, &merged.record, error.as_ref())?;
        if let Some(png) = &args.png {
            film.write_png_with(
                png,
                photonmap::film::Tonemap { exposure: args.exposure, curve: args.tonemap },
            )?;
        }
    }
    let estimate = merged.sums.estimate();
    if let Some(path) = &args.stats {
        #[derive(serde::Serialize)]
        struct Report<'a> {
            output: String,
            width: usize,
            height: usize,
            passes: u32,
            total_passes: u32,
            missing: Vec<String>,
            parts: &'a [batch::merge::PartReport],
            error_estimate: Option<photonmap::film::sums::ErrorEstimate>,
            seconds: f64,
        }
        let report = Report {
            output: args.output.display().to_string(),
            width: merged.sums.width,
            height: merged.sums.height,
            passes: merged.sums.passes,
            total_passes: merged.total,
            missing: merged.missing.iter().map(|r| format!("{}..{}", r.start, r.end)).collect(),
            parts: &merged.parts,
            error_estimate: estimate,
            seconds: wall.elapsed().as_secs_f64(),
        };
        std::fs::write(path, serde_json::to_string_pretty(&report)?)
            .with_context(|| format!("{}: could not write the stats", path.display()))?;
    }
    let described = estimate.map_or("no error estimate from one pass".to_string(), |e| e.describe());
    eprintln!(
        "photonmap: {} from {} parts ({} of {} passes) in {:.2} s; {described}",
        args.output.display(),
        args.parts.len(),
        merged.sums.passes,
        merged.total,
        wall.elapsed().as_secs_f64()
    );
    if let Some(target) = args.target_error {
        let reached = estimate.is_some_and(|e| e.relative_rmse <= target);
        if !reached {
            eprintln!("photonmap: estimated relative RMSE above the target {target}: render more passes");
            return Ok(Finished::TargetMissed);
        }
    }
    Ok(Finished::Done)
}

/// A setting that cannot be honoured, named where it was given: the flag when the command line
/// set it (`--spp: 0 is not in …`), else the scene file's `[render]` field; the image size is
/// the flags' when `size_flags`, else the camera's.
fn setting_error(e: ConfigError, flags: &RenderSettings, size_flags: bool, scene: &Path) -> anyhow::Error {
    let flag = |name: &str| format!("--{}", name.replace('_', "-"));
    match e.field {
        "width/height" if size_flags => anyhow!("--width/--height: {}", e.message),
        "width/height" => anyhow!("{}: field `camera.width`/`camera.height`: {}", scene.display(), e.message),
        field if flags.is_set(field) => anyhow!("{}: {}", flag(field), e.message),
        field => anyhow!("{}: field `render.{field}`: {}", scene.display(), e.message),
    }
}

/// Whether two output paths name the same file (as written, or the same existing file).
fn same_file(a: &Path, b: &Path) -> bool {
    a == b || matches!((a.canonicalize(), b.canonicalize()), (Ok(x), Ok(y)) if x == y)
}

/// Refuses, before any work is done, output paths that could not be written at the end: a
/// directory that does not exist or where no file can be made (`/proc`, read-only), or a
/// path that is a directory. Each directory is probed once, with a file made and removed.
fn check_outputs<'a>(paths: impl IntoIterator<Item = &'a PathBuf>) -> Result<()> {
    let mut checked = std::collections::HashSet::new();
    for out in paths {
        if out.is_dir() {
            bail!("{}: is a directory, not a file", out.display());
        }
        let dir = out.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
        if !checked.insert(dir.to_path_buf()) {
            continue;
        }
        if !dir.is_dir() {
            bail!("{}: the directory {} does not exist", out.display(), dir.display());
        }
        let probe = dir.join(format!(".photonmap-probe-{}", std::process::id()));
        match std::fs::OpenOptions::new().write(true).create_new(true).open(&probe) {
            Ok(_) => {
                let _ = std::fs::remove_file(&probe);
            }
            Err(e) => bail!("{}: cannot write in {}: {e}", out.display(), dir.display()),
        }
    }
    Ok(())
}

fn agree(args: cli::AgreeArgs) -> Result<()> {
    let scene = load_scene(&args.scene)?;
    let options = AccelOptions { robust: args.robust };
    let report = photonmap::tools::agree::agree_scene(&scene, args.rays, args.seed, options)?;
    if args.json {
        outln!("{}", serde_json::to_string(&report)?);
    } else {
        outln!("{report}");
    }
    Ok(())
}

fn compare(args: &cli::CompareArgs) -> Result<()> {
    use photonmap::film::Film;
    let cli::CompareArgs { exact, downsample, region, json, diff_scale, .. } = *args;
    let (image, reference, diff) = (args.image.as_path(), args.reference.as_deref(), args.diff.as_deref());
    let a = Film::read_exr(image)?;
    let mut b = match (reference, exact) {
        (Some(path), _) => Film::read_exr(path)?,
        (None, Some(v)) => exact_film(v, a.width, a.height)?,
        (None, None) => bail!("give a reference image or --exact"),
    };
    if let Some(f) = downsample {
        if f == 0 || b.width % f != 0 || b.height % f != 0 {
            bail!("--downsample {f} does not divide the reference's {}x{}", b.width, b.height);
        }
        b = b.downsample(f);
    }
    // Images of different sizes are refused below, region or not.
    let (a, b) = match region {
        Some([x0, y0, x1, y1]) if (a.width, a.height) == (b.width, b.height) => {
            if x1 > a.width || y1 > a.height {
                bail!(
                    "--region {x0},{y0},{x1},{y1} does not fit {} ({}x{})",
                    image.display(),
                    a.width,
                    a.height
                );
            }
            (a.crop(x0, y0, x1, y1), b.crop(x0, y0, x1, y1))
        }
        _ => (a, b),
    };
    let Some((rmse, rel_mse)) = photonmap::film::compare(&a, &b) else {
        bail!(
            "{} is {}x{} but {} is {}x{}",
            image.display(),
            a.width,
            a.height,
            reference.map_or("--exact".into(), |r| r.display().to_string()),
            b.width,
            b.height
        );
    };
    if let Some(path) = diff {
        let mut d = a.clone();
        for (p, q) in d.pixels.iter_mut().zip(&b.pixels) {
            *p = (*p - *q).abs() * diff_scale;
        }
        d.write_png(path)?;
    }
    let (ma, mb) = (a.mean(), b.mean());
    let nonfinite = a.nonfinite_count();
    if json {
        let v = serde_json::json!({"rmse": rmse, "rel_mse": rel_mse, "mean": ma, "reference_mean": mb,
            "bias": ma / mb - 1.0, "nonfinite_pixels": nonfinite});
        outln!("{v}");
    } else {
        outln!("rmse {rmse:.5}  rel_mse {rel_mse:.5}  mean {ma:.5} vs {mb:.5} ({:+.2}%)  non-finite pixels {nonfinite}", 100.0 * (ma / mb - 1.0));
    }
    Ok(())
}

/// A reference image of one radiance everywhere (`--exact`).
fn exact_film(v: f32, width: usize, height: usize) -> Result<photonmap::film::Film> {
    if !(v.is_finite() && v >= 0.0) {
        bail!("--exact: {v} is not a finite radiance of at least 0");
    }
    let mut film = photonmap::film::Film::new(width, height);
    film.pixels.fill(glam::Vec3::splat(v));
    Ok(film)
}

fn converge(args: cli::ConvergeArgs) -> Result<()> {
    use photonmap::choice::Choice;
    use photonmap::film::Film;
    use photonmap::tools::converge::{self, Method, Study};
    let scene = load_scene(&args.scene)?;
    let mut reference = match (&args.reference, args.exact) {
        (Some(path), _) => Film::read_exr(path)?,
        (None, Some(v)) => exact_film(v, scene.camera.width as usize, scene.camera.height as usize)?,
        (None, None) => bail!("give --reference or --exact"),
    };
    if let Some(f) = args.downsample {
        if f == 0 || reference.width % f != 0 || reference.height % f != 0 {
            bail!(
                "--downsample {f} does not divide the reference's {}x{}",
                reference.width,
                reference.height
            );
        }
        reference = reference.downsample(f);
    }
    if let Some(b) = args.budgets.iter().find(|b| !(b.is_finite() && **b > 0.0 && **b <= 1e6)) {
        bail!("--budgets: {b} is not a number of seconds in (0, 1e6]");
    }
    let reference_noise = args.reference_noise.unwrap_or(0.0);
    if !(reference_noise.is_finite() && reference_noise >= 0.0) {
        bail!("--reference-noise: {reference_noise} is not an RMSE (a number, 0 or more)");
    }
    check_outputs([args.csv.as_ref(), args.plot.as_ref()].into_iter().flatten())?;
    let stem = args.scene.file_stem().unwrap_or_default().to_string_lossy().into_owned();
    let (w, h) = (reference.width as u32, reference.height as u32);
    let peers = match &args.peers {
        Some(path) => {
            let text = std::fs::read_to_string(path).with_context(|| format!("{}", path.display()))?;
            converge::parse_peers(&text, &stem, w, h).with_context(|| format!("{}", path.display()))?
        }
        None => Vec::new(),
    };
    let study = Study {
        methods: if args.methods.is_empty() { Method::ALL.to_vec() } else { args.methods.clone() },
        budgets: args.budgets.clone(),
        width: reference.width as u32,
        height: reference.height as u32,
        seed: args.seed,
        overrides: photonmap::config::RenderSettings { accel: args.accel, ..Default::default() },
        reference_noise,
    };
    let pool = pool(args.threads)?;
    outln!("{}", converge::TABLE_HEADER);
    // One bar over the whole study, in milliseconds of budget (each run takes about its own).
    let bars = progress::Bars::new(false);
    let runs = study.methods.len() * study.budgets.len();
    let total: f64 = study.budgets.iter().sum::<f64>() * study.methods.len() as f64;
    bars.start("converge", (total * 1000.0) as u64);
    let finished = std::sync::atomic::AtomicUsize::new(0);
    let points = pool.install(|| {
        converge::run(&scene, &reference, &study, |p| {
            bars.suspend(|| outln!("{}", converge::table_row(p)));
            let k = finished.fetch_add(1, Ordering::Relaxed) + 1;
            bars.message(&format!("{k} of {runs} renders"));
            bars.advance((p.budget * 1000.0) as u64);
        })
    });
    bars.finish();
    let points = points?;
    outln!();
    for &m in &study.methods {
        if let Some(s) = converge::slope(&points, m) {
            let less_noise = match converge::true_slope(&points, m) {
                Some(t) if study.reference_noise > 0.0 => {
                    format!(" ({t:+.2} with the reference's noise taken out)")
                }
                _ => String::new(),
            };
            outln!("{:<16} log-log slope of RMSE against time {s:+.2}{less_noise}", m.name());
        }
    }
    for &m in &study.methods {
        let ratios: Vec<&converge::Point> =
            points.iter().filter(|p| p.method == m && p.calibration().is_some()).collect();
        if let Some(first) = ratios.first() {
            let (lo, hi) = ratios
                .iter()
                .filter_map(|p| p.calibration())
                .fold((f64::MAX, 0.0f64), |(lo, hi), r| (lo.min(r), hi.max(r)));
            let unseen =
                if first.estimate_has_bias { "" } else { " (noise only: its bias is not estimated)" };
            outln!("{:<16} estimated / true RMSE {lo:.2} to {hi:.2}{unseen}", m.name());
        }
    }
    if !peers.is_empty() {
        outln!("\nequal time: the lowest error of any method here within each peer's time");
        outln!("{}", converge::RACE_HEADER);
        for r in converge::race(&points, &peers) {
            outln!("{}", converge::race_row(&r));
        }
    }
    if let Some(path) = &args.csv {
        std::fs::write(path, converge::csv(&points))
            .with_context(|| format!("{}: could not write the CSV", path.display()))?;
    }
    if let Some(path) = &args.plot {
        let title = format!("{stem} {}x{}: RMSE against time", study.width, study.height);
        std::fs::write(path, converge::plot(&points, &peers, &title))
            .with_context(|| format!("{}: could not write the plot", path.display()))?;
    }
    Ok(())
}

fn stress(args: cli::StressArgs) -> Result<()> {
    use photonmap::tools::stress;
    let mut opts =
        stress::StressOptions { agree_rays: args.agree_rays, quick: args.quick, ..Default::default() };
    if !args.accel.is_empty() {
        opts.accels = args.accel.clone();
    }
    let filter = args.filter.as_deref();
    if let Some(f) = filter {
        if !stress::cases().iter().any(|c| c.name.contains(f)) {
            bail!("--filter {f}: no case matches");
        }
    }
    if !args.json {
        outln!("{}", stress::table_header());
    }
    let wall = Instant::now();
    let rows = pool(args.threads)?.install(|| {
        stress::run(filter, &opts, |row| {
            if args.json {
                outln!("{}", serde_json::to_string(row).unwrap_or_default());
            } else {
                outln!("{}", stress::table_row(row));
            }
        })
    });
    let failed = rows.iter().filter(|r| !r.pass).count();
    if !args.json {
        outln!("{} checks, {failed} failed, {:.1} s", rows.len(), wall.elapsed().as_secs_f64());
    }
    if failed > 0 {
        bail!("{failed} of {} stress checks failed", rows.len());
    }
    Ok(())
}

fn bench(args: cli::BenchArgs) -> Result<()> {
    use photonmap::tools::bench::{self, BenchSpec};
    let scene = load_scene(&args.scene)?;
    let settings = scene.render.overridden_by(&args.settings.to_settings());
    let cfg = settings
        .resolve(args.width, args.height)
        .map_err(|e| setting_error(e, &args.settings.to_settings(), true, &args.scene))?;
    let all = std::thread::available_parallelism().map_or(1, |n| n.get());
    let threads = if !args.threads.is_empty() {
        args.threads.clone()
    } else if all > 1 {
        vec![1, all]
    } else {
        vec![1]
    };
    let spec = BenchSpec { runs: args.runs, threads, raw_rays_per_kind: args.raw_rays };
    let name = args.scene.display().to_string();
    let report = bench::run(&scene, &name, &cfg, &spec, |t, run, s| {
        eprintln!("photonmap bench: {t} thread{}, run {}: {s:.3} s", if t == 1 { "" } else { "s" }, run + 1)
    })?;
    if args.json {
        outln!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        outln!("{}", report.to_string().trim_end());
    }
    Ok(())
}

fn info(path: &std::path::Path, json: bool) -> Result<()> {
    let info = photonmap::tools::info::SceneInfo::of(&load_scene(path)?);
    if json {
        outln!("{}", serde_json::to_string_pretty(&info)?);
    } else {
        outln!("{}", info.to_string().trim_end());
    }
    Ok(())
}

/// Loads a scene, saying on stderr what it asks for that is not rendered as asked.
fn load_scene(path: &std::path::Path) -> Result<Scene, photonmap::scene::SceneError> {
    let scene = Scene::load(path)?;
    for w in &scene.warnings {
        eprintln!("photonmap: warning: {w}");
    }
    Ok(scene)
}
