//! Passes, for every integrator alike: the image rendered again with fresh random numbers and
//! averaged (progressive photon mapping also refines its radii), until a pass count, a time
//! budget or a request to stop (Ctrl-C) ends it, with the image so far handed out every few
//! passes. [`run`] is the loop; an integrator only says what one pass does ([`PassRenderer`]).

use crate::config::RenderConfig;
use crate::film::sums::{Bias, PassSums, Quarter};
use crate::film::Film;
use crate::frame::camera::PixelSamples;
use crate::frame::{Counters, Progress, Quiet};
use crate::sampling::derive_seed;
use crate::stats::{Stats, SITE_RECORDS};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

/// What one pass gives: its image and, where the integrator probes the bias of its photon
/// estimate ([`Bias::Probed`]), the probe per pixel.
pub struct PassImage {
    pub film: Film,
    pub bias_probe: Option<Film>,
}

impl From<Film> for PassImage {
    fn from(film: Film) -> Self {
        PassImage { film, bias_probe: None }
    }
}

/// One pass of a render, as an integrator sees it.
#[derive(Clone, Copy, Debug)]
pub struct Pass {
    /// Passes finished before this one.
    pub index: u32,
    /// This pass's seed: the render's own for the first pass, so that one pass gives the same
    /// image as a render without passes.
    pub seed: u64,
    /// The camera samples of this pass.
    pub samples: PixelSamples,
}

/// What an integrator does in each pass.
pub trait PassRenderer {
    /// Renders `pass` (its photon stages, if any, then its camera stage, each recorded in
    /// `stats`): the pass's image, which [`run`] averages over passes, and its counters.
    fn render_pass(
        &mut self,
        pass: &Pass,
        stats: &mut Stats,
        progress: &dyn Progress,
    ) -> (PassImage, Counters);

    /// What the passes say of their bias (for the error estimate): unknown unless the
    /// integrator says otherwise.
    fn bias(&self) -> Bias {
        Bias::Unknown
    }

    /// Whether each pass's image depends only on the seed and the pass index, so that passes
    /// rendered apart and summed give the render's image (all but stochastic progressive
    /// photon mapping, whose passes carry per-pixel statistics).
    fn independent_passes(&self) -> bool {
        true
    }

    /// The image after `passes` passes, given the mean of their images (progressive photon
    /// mapping adds its photon term here).
    fn finish(&self, mean: Film, _passes: u32) -> Film {
        mean
    }
}

/// What a run of passes gives: the image, the exact sums of its passes (which
/// `--pass-range` writes and `photonmap merge` adds up) and the counters of every pass.
pub struct Rendered {
    pub film: Film,
    pub sums: PassSums,
    pub counters: Counters,
}

/// Passes before the estimated error may stop a render (`--target-error`): fewer say too
/// little of their own spread.
pub const TARGET_ERROR_MIN_PASSES: u32 = 4;

/// Renders passes with `integrator` until `cfg` and `control` say to stop (only the passes of
/// `control.range`, if it gives one); returns the image, the sums of the passes and the
/// counters of every pass. Records the passes done, whether a stop request ended the render
/// and the estimated error (when the passes are independent) in `stats`.
pub fn run(
    cfg: &RenderConfig,
    control: Control<'_>,
    progress: &dyn Progress,
    stats: &mut Stats,
    integrator: &mut impl PassRenderer,
) -> Rendered {
    let mut schedule = Schedule::new(cfg, control);
    let progressive = schedule.is_progressive();
    let first = control.range.map_or(0, |r| r.0);
    // In a progressive render one bar counts the passes; the stages of each pass stay quiet.
    let inner: &dyn Progress = if progressive { &Quiet } else { progress };
    let independent = integrator.independent_passes();
    let mut sums = PassSums::new(cfg.width as usize, cfg.height as usize, integrator.bias());
    let mut counters = Counters::default();
    if progressive {
        progress.start("passes", schedule.progress_total());
    }
    let mut batches = Batches::new(cfg, control);
    while schedule.start_pass() {
        let index = first + schedule.done();
        let samples = PixelSamples { spp: cfg.spp, first: index as u64 * cfg.spp as u64, seed: cfg.seed };
        let pass = Pass { index, seed: pass_seed(cfg.seed, index), samples };
        let (image, c) = integrator.render_pass(&pass, stats, inner);
        sums.add_pass(&image.film, image.bias_probe.as_ref(), batches.quarter(index));
        batches.after_pass(&sums);
        counters += c;
        let (units, due) = schedule.finish_pass();
        if progressive {
            progress.message(&pass_message(schedule.done(), stats));
        }
        progress.advance(if progressive { units } else { 0 });
        if due {
            schedule.checkpoint(&integrator.finish(sums.mean(), schedule.done()));
        }
        if let (Some(target), true) = (cfg.target_error, independent) {
            // Checked after 4, 8, 16, … passes: then the first half is a batch of its own.
            let n = schedule.done();
            if n >= TARGET_ERROR_MIN_PASSES && n.is_power_of_two() {
                let mut halves = sums.clone();
                batches.name_first(&mut halves);
                if halves.estimate().is_some_and(|e| e.relative_rmse <= target) {
                    schedule.reached_target();
                }
            }
        }
    }
    if progressive {
        progress.finish();
    }
    batches.name_first(&mut sums);
    stats.passes = schedule.done();
    stats.cancelled = schedule.cancelled();
    stats.error_estimate = if independent { sums.estimate() } else { None };
    Rendered { film: integrator.finish(sums.mean(), schedule.done()), sums, counters }
}

/// Which passes make the two batches the error estimate compares, and their halves, the
/// quarters ([`PassSums::estimate`], [`PassSums::convergence`]): with a pass count known in
/// advance (and always for a `--pass-range` part, so that parts rendered apart agree), those
/// before its half way and each batch's own half way ([`PassSums::quarter`]); otherwise (a time
/// budget, a target error) the passes up to a power of two, the one of the last two powers that
/// splits the passes done most evenly (the camera's sample sequence is best spread over a power
/// of two), kept as a snapshot of the sums, and for the quarters the snapshots (of `R + G + B`)
/// at the power of two or 1.5 times one nearest each batch's middle.
enum Batches {
    /// The render's pass count.
    Fixed(u32),
    /// Snapshots at the last two powers of two, (passes, sums), and of the totals at the last
    /// six powers of two or 1.5 times powers of two (1, 2, 3, 4, 6, 8, 12, …).
    Open { firsts: Vec<(u32, Vec<[i128; 3]>)>, totals: Vec<(u32, Vec<i128>)> },
}

impl Batches {
    fn new(cfg: &RenderConfig, control: Control<'_>) -> Self {
        match (control.range, cfg.passes) {
            (Some(_), Some(n)) => Batches::Fixed(n),
            (None, Some(n)) if cfg.time.is_none() && cfg.target_error.is_none() => Batches::Fixed(n),
            _ => Batches::Open { firsts: Vec::new(), totals: Vec::new() },
        }
    }

    fn quarter(&self, index: u32) -> Quarter {
        match self {
            Batches::Fixed(n) => Some(PassSums::quarter(index, *n)),
            Batches::Open { .. } => None,
        }
    }

    fn after_pass(&mut self, sums: &PassSums) {
        if let Batches::Open { firsts, totals } = self {
            let n = sums.passes;
            if n.is_power_of_two() {
                firsts.push((n, sums.snapshot()));
                if firsts.len() > 2 {
                    firsts.remove(0);
                }
            }
            // 1, 2, 3, 4, 6, 8, 12, 16, …: the powers of two and 1.5 times them.
            if n.is_power_of_two() || (n % 3 == 0 && (n / 3).is_power_of_two()) {
                totals.push((n, sums.total_snapshot()));
                if totals.len() > 6 {
                    totals.remove(0);
                }
            }
        }
    }

    /// Names the batches in `sums` (an open split's snapshots nearest half way and quarter
    /// ways).
    fn name_first(&self, sums: &mut PassSums) {
        if let Batches::Open { firsts, totals } = self {
            let n = sums.passes;
            let best =
                firsts.iter().filter(|(m, _)| *m < n).min_by_key(|(m, _)| (2 * *m as i64 - n as i64).abs());
            if let Some((m, snap)) = best {
                let m = *m;
                let q1 = totals
                    .iter()
                    .filter(|(q, _)| *q < m)
                    .min_by_key(|(q, _)| (2 * *q as i64 - m as i64).abs())
                    .map(|(q, t)| (t.as_slice(), *q));
                let q3 = totals
                    .iter()
                    .filter(|(q, _)| *q > m && *q < n)
                    .min_by_key(|(q, _)| (2 * *q as i64 - (m + n) as i64).abs())
                    .map(|(q, t)| (t.as_slice(), *q));
                sums.set_batches((snap, m), q1, q3);
            }
        }
    }
}

/// What a progressive render's bar says after `passes` passes: the passes and the photons
/// traced over them (`12 passes, 1.2M photons`).
fn pass_message(passes: u32, stats: &Stats) -> String {
    let photons: u64 = stats
        .photons
        .iter()
        .filter(|(name, _)| !SITE_RECORDS.contains(&name.as_str()))
        .map(|(_, m)| m.emitted)
        .sum();
    let count = |n: u64| match n {
        0..=9_999 => n.to_string(),
        10_000..=999_999 => format!("{:.0}k", n as f64 / 1e3),
        _ => format!("{:.1}M", n as f64 / 1e6),
    };
    let passes = if passes == 1 { "1 pass".to_string() } else { format!("{passes} passes") };
    if photons == 0 {
        passes
    } else {
        format!("{passes}, {} photons", count(photons))
    }
}

/// The camera stage of a pass: `f` under the stage name `camera` in `stats`, with a progress
/// bar counting `rows`.
pub fn camera_stage<R>(
    stats: &mut Stats,
    progress: &dyn Progress,
    rows: u32,
    reason: &str,
    f: impl FnOnce() -> R,
) -> R {
    progress.start("camera", rows as u64);
    let out = stats.run("camera", reason, |_| f());
    progress.finish();
    out
}

/// The seed of pass `pass`.
fn pass_seed(seed: u64, pass: u32) -> u64 {
    if pass == 0 {
        seed
    } else {
        derive_seed(seed, 0x9A55E5, pass as u64)
    }
}

/// Called with the number of passes done and the image so far.
pub type Checkpoint<'a> = &'a (dyn Fn(u32, &Film) + Sync);

/// How a caller steers a render while it runs.
#[derive(Clone, Copy)]
pub struct Control<'a> {
    /// When set (by a Ctrl-C handler, say), no further pass starts; the image of the passes
    /// done is returned.
    pub cancel: Option<&'a AtomicBool>,
    /// `(k, f)`: `f` gets the image so far after every `k`-th pass (not after the last of a
    /// fixed pass count, whose image the render returns).
    pub checkpoint: Option<(u32, Checkpoint<'a>)>,
    /// When the time budget started (the process start, for `photonmap render`).
    pub started: Instant,
    /// `(a, b)`: render passes `a..b` only (of the `cfg.passes` of the whole render), as
    /// `--pass-range` asks; `None`: every pass from the first.
    pub range: Option<(u32, u32)>,
}

impl Default for Control<'_> {
    fn default() -> Self {
        Control { cancel: None, checkpoint: None, started: Instant::now(), range: None }
    }
}

impl Control<'_> {
    fn cancelled(&self) -> bool {
        self.cancel.is_some_and(|c| c.load(Ordering::Relaxed))
    }
}

/// Decides whether another pass starts.
struct Schedule<'a> {
    passes: Option<u32>,
    time: Option<f64>,
    control: Control<'a>,
    done: u32,
    /// Time the passes took (setup excluded), to predict the next one.
    pass_seconds: f64,
    pass_start: Option<Instant>,
    progressive: bool,
    /// A target error is set: without a pass count or a time budget, passes go on until the
    /// estimate reaches it.
    target: bool,
    /// The estimated error reached `--target-error`.
    reached: bool,
}

impl<'a> Schedule<'a> {
    pub fn new(cfg: &RenderConfig, control: Control<'a>) -> Self {
        let passes = match control.range {
            Some((a, b)) => Some(b.saturating_sub(a).max(1)),
            None => cfg.passes,
        };
        let progressive = passes.is_some_and(|p| p > 1) || cfg.is_progressive() && control.range.is_none();
        Schedule {
            passes,
            time: cfg.time,
            control,
            done: 0,
            pass_seconds: 0.0,
            pass_start: None,
            progressive,
            target: cfg.target_error.is_some(),
            reached: false,
        }
    }

    /// No further pass starts: the estimated error is below the target.
    pub fn reached_target(&mut self) {
        self.reached = true;
    }

    /// Passes finished so far.
    pub fn done(&self) -> u32 {
        self.done
    }

    /// Whether the render is progressive (more than one pass possible): inner stages then
    /// report no progress of their own.
    pub fn is_progressive(&self) -> bool {
        self.progressive
    }

    /// The total the progress bar counts to: passes, or milliseconds of the time budget.
    pub fn progress_total(&self) -> u64 {
        match (self.passes, self.time) {
            (Some(p), None) => p as u64,
            (_, Some(t)) => (t * 1000.0) as u64,
            (None, None) => 1,
        }
    }

    /// Progress units one finished pass adds.
    fn progress_units(&self, seconds: f64) -> u64 {
        if self.time.is_some() {
            (seconds * 1000.0) as u64
        } else {
            1
        }
    }

    /// Whether pass number `done()` should start: the first always does; later ones unless
    /// the pass count is reached, a stop was requested, or the pass would probably end after
    /// the time budget.
    pub fn start_pass(&mut self) -> bool {
        let go = if self.done == 0 {
            true
        } else if self.control.cancelled() || self.reached {
            false
        } else {
            let count_ok = match self.passes {
                Some(p) => self.done < p,
                None => self.time.is_some() || self.target,
            };
            let time_ok = match self.time {
                Some(t) => {
                    let mean = self.pass_seconds / self.done as f64;
                    self.control.started.elapsed().as_secs_f64() + mean <= t
                }
                None => true,
            };
            count_ok && time_ok
        };
        if go {
            self.pass_start = Some(Instant::now());
        }
        go
    }

    /// Records the end of a pass; returns the progress units it adds and whether the image so
    /// far is due at a checkpoint.
    pub fn finish_pass(&mut self) -> (u64, bool) {
        let seconds = self.pass_start.take().map_or(0.0, |s| s.elapsed().as_secs_f64());
        self.pass_seconds += seconds;
        self.done += 1;
        // Not after the last of a fixed number of passes: the render's own image follows.
        let last = self.passes == Some(self.done);
        let due = !last && self.control.checkpoint.is_some_and(|(k, _)| k > 0 && self.done % k == 0);
        (self.progress_units(seconds), due)
    }

    /// Hands `film` to the checkpoint callback.
    pub fn checkpoint(&self, film: &Film) {
        if let Some((_, f)) = self.control.checkpoint {
            f(self.done, film);
        }
    }

    /// Whether the render stopped because of a cancel request.
    pub fn cancelled(&self) -> bool {
        self.control.cancelled()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::RenderSettings;

    fn cfg(passes: Option<u32>, time: Option<f64>) -> RenderConfig {
        RenderSettings { passes, time, ..Default::default() }.resolve(4, 4).unwrap()
    }

    fn run(s: &mut Schedule) -> u32 {
        while s.start_pass() {
            s.finish_pass();
        }
        s.done()
    }

    #[test]
    fn counts_passes() {
        assert_eq!(run(&mut Schedule::new(&cfg(None, None), Control::default())), 1);
        assert_eq!(run(&mut Schedule::new(&cfg(Some(5), None), Control::default())), 5);
    }

    #[test]
    fn stops_at_the_time_budget_and_on_cancel() {
        // A budget already spent: only the first pass runs.
        let started = Instant::now() - std::time::Duration::from_secs(10);
        let control = Control { started, ..Default::default() };
        assert_eq!(run(&mut Schedule::new(&cfg(Some(100), Some(1.0)), control)), 1);
        let stop = AtomicBool::new(true);
        let control = Control { cancel: Some(&stop), ..Default::default() };
        assert_eq!(run(&mut Schedule::new(&cfg(Some(100), None), control)), 1);
    }

    #[test]
    fn checkpoints_every_k_passes() {
        let seen = std::sync::Mutex::new(Vec::new());
        let f = |n: u32, _: &Film| seen.lock().unwrap().push(n);
        let control = Control { checkpoint: Some((2, &f)), ..Default::default() };
        let mut s = Schedule::new(&cfg(Some(7), None), control);
        let film = Film::new(1, 1);
        while s.start_pass() {
            if s.finish_pass().1 {
                s.checkpoint(&film);
            }
        }
        assert_eq!(*seen.lock().unwrap(), vec![2, 4, 6]);
    }

    /// A stand-in integrator: pass `i` renders every pixel as `i + 1` and records the pass it
    /// saw; `finish` adds 100, as progressive photon mapping adds its photon term.
    struct Counting {
        seen: Vec<(u32, u64, u64)>,
    }

    impl PassRenderer for Counting {
        fn render_pass(&mut self, pass: &Pass, _: &mut Stats, _: &dyn Progress) -> (PassImage, Counters) {
            self.seen.push((pass.index, pass.samples.first, pass.seed));
            let mut film = Film::new(4, 4);
            film.pixels.iter_mut().for_each(|p| *p = glam::Vec3::splat((pass.index + 1) as f32));
            (film.into(), Counters { queries: 1, ..Default::default() })
        }

        fn finish(&self, mean: Film, _passes: u32) -> Film {
            Film { pixels: mean.pixels.iter().map(|p| *p + 100.0).collect(), ..mean }
        }
    }

    #[test]
    fn a_render_of_unknown_length_names_its_batches_and_quarters_at_the_end() {
        // A target error it never meets: the length is not known in advance, the batches are
        // named from the snapshots: of 6 passes the first 2, the quarters 0..1 and 2..4.
        for (passes, first, quarters) in [(6, 2, [1, 2]), (8, 4, [2, 2]), (13, 8, [4, 4]), (4, 2, [1, 1])] {
            let c = RenderSettings { passes: Some(passes), target_error: Some(1e-12), ..Default::default() };
            let c = c.resolve(4, 4).unwrap();
            let mut integrator = Counting { seen: Vec::new() };
            let rendered = super::run(&c, Control::default(), &Quiet, &mut Stats::default(), &mut integrator);
            let sums = rendered.sums;
            assert_eq!((sums.passes, sums.first_passes, sums.quarter_passes), (passes, first, quarters));
            // The same sums as passes added with their quarters known: pass i is worth i + 1.
            let mut known = PassSums::new(4, 4, sums.bias);
            let q = |i: u32| match i {
                _ if i < quarters[0] => 0,
                _ if i < first => 1,
                _ if i < first + quarters[1] => 2,
                _ => 3,
            };
            for i in 0..passes {
                let film = Film { width: 4, height: 4, pixels: vec![glam::Vec3::splat((i + 1) as f32); 16] };
                known.add_pass(&film, None, Some(q(i)));
            }
            assert_eq!(sums, known, "{passes} passes");
        }
    }

    #[test]
    fn the_loop_averages_the_passes_and_lets_the_integrator_finish() {
        let shown = std::sync::Mutex::new(Vec::new());
        let f = |n: u32, film: &Film| shown.lock().unwrap().push((n, film.pixels[0].x));
        let control = Control { checkpoint: Some((2, &f)), ..Default::default() };
        let c = cfg(Some(4), None);
        let mut stats = Stats::default();
        let mut integrator = Counting { seen: Vec::new() };
        let Rendered { film, sums, counters } = super::run(&c, control, &Quiet, &mut stats, &mut integrator);
        assert_eq!((sums.passes, sums.first_passes), (4, 2));
        // Passes 1..=4 average to 2.5; the integrator's finish is applied to the image and to
        // every checkpoint (after 2 passes: mean 1.5).
        assert!(film.pixels.iter().all(|p| *p == glam::Vec3::splat(102.5)), "{:?}", film.pixels[0]);
        assert_eq!(*shown.lock().unwrap(), vec![(2, 101.5)]);
        assert_eq!((stats.passes, counters.queries), (4, 4));
        // Each pass continues the pixels' sample sequences and has its own seed; the first
        // pass has the render's own.
        let spp = c.spp as u64;
        let firsts: Vec<u64> = integrator.seen.iter().map(|s| s.1).collect();
        assert_eq!(firsts, vec![0, spp, 2 * spp, 3 * spp]);
        assert_eq!(integrator.seen[0].2, c.seed);
        let seeds: std::collections::BTreeSet<u64> = integrator.seen.iter().map(|s| s.2).collect();
        assert_eq!(seeds.len(), 4);
    }
}
