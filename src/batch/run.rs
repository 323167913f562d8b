//! The batch loop: every image of a [`plan`](super::plan) rendered in turn from one prepared
//! scene, the photon maps shared ([`Shared`](crate::integrator::Shared)), each image written (atomically, with its
//! record in the header, [`super::meta`]) as soon as it is done, and with `--resume` the
//! images already finished skipped.

use super::meta::{ImageMeta, FINISHED};
use super::plan::{Format, Job};
use crate::config::RenderConfig;
use crate::film::partial::PartialFilm;
use crate::film::{Film, ImageError, Tonemap};
use crate::frame::Progress;
use crate::integrator::{Checkpoint, Control, Prepared};
use crate::scene::{Camera, Scene};
use crate::stats::Stats;
use serde::Serialize;
use std::sync::atomic::AtomicBool;
use std::time::Instant;

/// How a batch is steered.
#[derive(Clone, Copy)]
pub struct Options<'a> {
    /// Skip images whose output already holds this very image, finished.
    pub resume: bool,
    /// Set by Ctrl-C: the image under way stops after its pass (progressive renders), is
    /// written marked unfinished, and no further image starts.
    pub cancel: Option<&'a AtomicBool>,
    /// Write each progressive image so far every this many passes.
    pub checkpoint_every: Option<u32>,
    /// The command's start: the first image's time budget counts from it, each later one's
    /// from its own start.
    pub started: Instant,
    /// How PNG outputs and previews show the radiance (the EXRs hold it linear).
    pub preview: Tonemap,
    /// `(a, b)`: render passes `a..b` of the `--passes` render only, and write each output as
    /// a partial film ([`PartialFilm`]) instead of an image.
    pub pass_range: Option<(u32, u32)>,
    /// Add the per-pixel estimated error to each EXR (channel `error`).
    pub error_layer: bool,
}

/// The state a partial film's record says.
pub const PARTIAL_STATE: &str = "partial film";

/// What became of one image of the batch.
#[derive(Debug)]
pub struct Done {
    pub job: Job,
    /// The render's report; `None` if `--resume` found the image finished already.
    pub stats: Option<Stats>,
}

/// Renders `jobs` (each with its configuration in `cfgs`) from `prepared`, whose views
/// [`all_views`](super::plan::all_views) are `views`, writing each image as it is done;
/// `outer` counts the images, `inner` the stages of each. Stops early, with what is done, when
/// a stop request ended an image.
pub fn run(
    prepared: &Prepared<'_>,
    views: &[Camera],
    jobs: &[Job],
    cfgs: &[RenderConfig],
    options: Options<'_>,
    outer: &dyn Progress,
    inner: &dyn Progress,
) -> Result<Vec<Done>, ImageError> {
    let scene = prepared.scene();
    let shared = prepared.shared(jobs.len() > 1);
    let mut done = Vec::with_capacity(jobs.len());
    outer.start("images", jobs.len() as u64);
    for (i, (job, cfg)) in jobs.iter().zip(cfgs).enumerate() {
        let view = super::plan::view_index(scene, job);
        let meta = ImageMeta::new(scene, cfg, &scene.cameras[job.camera].name, job.frame, &views[view]);
        if options.resume && finished(job, &meta, options.preview)? {
            done.push(Done { job: job.clone(), stats: None });
            outer.advance(1);
            continue;
        }
        let checkpoint = |passes: u32, film: &Film| {
            let state = format!("checkpoint after {passes} passes");
            if let Err(e) = write(job, film, None, &meta, &state, options.preview) {
                eprintln!("photonmap: warning: checkpoint after {passes} passes not written: {e}");
            }
        };
        let control = Control {
            cancel: options.cancel,
            checkpoint: options.checkpoint_every.map(|k| (k, &checkpoint as Checkpoint)),
            started: if i == 0 { options.started } else { Instant::now() },
            range: options.pass_range,
        };
        let output = prepared.render_view(&shared, views, view, cfg, inner, control);
        if let Some((a, _)) = options.pass_range {
            // Interrupted, the part holds the passes it finished, and says so.
            let range = a..a + output.stats.passes;
            let total = cfg.passes.unwrap_or(range.end);
            PartialFilm::write(&job.output, &output.sums, range, total, &meta.attributes(PARTIAL_STATE))?;
        } else {
            let state = if output.stats.cancelled {
                format!("interrupted after {} passes", output.stats.passes)
            } else {
                FINISHED.to_string()
            };
            let error = if options.error_layer { output.sums.error_film() } else { None };
            write(job, &output.film, error.as_ref(), &meta, &state, options.preview)?;
        }
        let cancelled = output.stats.cancelled;
        done.push(Done { job: job.clone(), stats: Some(output.stats) });
        outer.advance(1);
        if cancelled {
            break;
        }
    }
    outer.finish();
    Ok(done)
}

/// Writes `job`'s image (with the per-pixel `error` layer if given, and its PNG, mapped by
/// `preview`) with `meta` in the state `state`.
fn write(
    job: &Job,
    film: &Film,
    error: Option<&Film>,
    meta: &ImageMeta,
    state: &str,
    preview: Tonemap,
) -> Result<(), ImageError> {
    match Format::of(&job.output) {
        Ok(Format::Png) => film.write_png_with(&job.output, preview)?,
        _ => film.write_exr_with_error(&job.output, &meta.attributes(state), error)?,
    }
    if let Some(png) = &job.png {
        film.write_png_with(png, preview)?;
    }
    Ok(())
}

/// Whether `job`'s output is this very image, finished and whole (its pixels read back); a
/// missing PNG is made again from it.
fn finished(job: &Job, meta: &ImageMeta, preview: Tonemap) -> Result<bool, ImageError> {
    if !job.output.exists() {
        return Ok(false);
    }
    // A file there that is not this image finished is replaced: said, since it may be a file
    // of the user's that only happens to have the name.
    let again = |why: &str| {
        eprintln!("photonmap: warning: {}: {why}; rendering it again", job.output.display());
        Ok(false)
    };
    let Ok(attributes) = Film::read_exr_meta(&job.output) else {
        return again("not an OpenEXR file of this program's");
    };
    if !meta.is_finished_in(&attributes) {
        return again(
            "not this image finished (another scene, settings, view or version, or an unfinished render)",
        );
    }
    let Ok(film) = Film::read_exr(&job.output) else { return again("its pixels do not read back whole") };
    if let Some(png) = job.png.as_ref().filter(|p| !p.exists()) {
        film.write_png_with(png, preview)?;
    }
    Ok(true)
}

/// The `--stats` report of a batch: its totals and every image's own report.
#[derive(Debug, Serialize)]
pub struct BatchReport<'a> {
    pub scene: String,
    pub images: usize,
    /// Images rendered (the others were finished already: `--resume`).
    pub rendered: usize,
    pub seconds: f64,
    pub images_per_minute: f64,
    /// Seconds in photon stages (tracing, balancing, precomputed irradiance) over the batch:
    /// two-pass photon maps are made once for all the images.
    pub photon_seconds: f64,
    /// Seconds in the images' camera stages.
    pub camera_seconds: f64,
    pub frames: Vec<ImageReport<'a>>,
}

/// One image in a [`BatchReport`].
#[derive(Debug, Serialize)]
pub struct ImageReport<'a> {
    pub camera: &'a str,
    pub frame: u32,
    pub output: String,
    /// `None`: finished already (`--resume`).
    pub stats: Option<&'a Stats>,
}

impl<'a> BatchReport<'a> {
    /// The report of the batch `done` of `scene`, which took `seconds`.
    pub fn new(scene: &'a Scene, done: &'a [Done], seconds: f64) -> Self {
        let rendered: Vec<&Stats> = done.iter().filter_map(|d| d.stats.as_ref()).collect();
        let photon = |s: &Stats| {
            s.stages
                .iter()
                .filter(|st| {
                    st.name.starts_with("photons.")
                        || st.name.starts_with("kdtree.")
                        || st.name == "irradiance"
                        || st.name.starts_with("irradiance.")
                })
                .map(|st| st.seconds)
                .sum::<f64>()
        };
        BatchReport {
            scene: scene.path.display().to_string(),
            images: done.len(),
            rendered: rendered.len(),
            seconds,
            images_per_minute: if seconds > 0.0 { rendered.len() as f64 / seconds * 60.0 } else { 0.0 },
            photon_seconds: rendered.iter().map(|s| photon(s)).sum(),
            camera_seconds: rendered.iter().map(|s| s.seconds("camera")).sum(),
            frames: done
                .iter()
                .map(|d| ImageReport {
                    camera: &scene.cameras[d.job.camera].name,
                    frame: d.job.frame,
                    output: d.job.output.display().to_string(),
                    stats: d.stats.as_ref(),
                })
                .collect(),
        }
    }
}
