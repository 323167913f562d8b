//! The stress suite: numerical stability of the whole renderer under extreme scenes.
//!
//! Each [`Case`] builds its scenes in memory ([`scenes`]), renders them with the real renderer
//! ([`render_scene`](crate::integrator::render_scene())) on every backend asked for, and checks a
//! result known in advance: the white furnace (radiance 2 everywhere) at world scales 10⁻⁴, 1,
//! 10⁴ and moved by 10⁵; a plane lit at 1° and 0.1° by a distant light (the analytic
//! `E cos θ ρ / π`); coplanar and touching surfaces, a camera inside a box, a light inside a
//! box, a back-facing area light, lights of power 10⁻¹² and 10¹² (the image scales linearly),
//! a million photons on one point (the kd-tree with duplicates), a scene where no photon is
//! stored, one triangle, and a million slivers. Every render must report no non-finite sample
//! and no non-finite pixel, and for every scene Embree and the BVH must agree on the rays of
//! [`agree_scene`](crate::tools::agree::agree_scene) (no hit/miss, primitive or occlusion
//! disagreement outside ties).
//!
//! [`run`] gives one [`Row`] per check; `photonmap stress` prints them as a table and
//! `tests/stress.rs` asserts that every row passes.

mod cases;
pub mod scenes;

use crate::accel::{AccelError, AccelKind, AccelOptions};
use crate::config::{ConfigError, RenderSettings};
use crate::frame::Quiet;
use crate::integrator::{render_scene, RenderOutput};
use crate::scene::Scene;
use serde::Serialize;
use std::time::Instant;

/// One check of the suite.
#[derive(Clone, Debug, Serialize)]
pub struct Row {
    /// Case and variant, e.g. `furnace x1e-4`.
    pub case: String,
    /// Backend rendered with, or `embree=bvh` for an agreement check.
    pub accel: String,
    /// What is checked.
    pub check: String,
    pub expected: String,
    pub measured: String,
    /// Non-finite samples (render stats) plus non-finite pixels (film), over the row's renders.
    pub nonfinite: u64,
    pub seconds: f64,
    pub pass: bool,
}

/// How the suite runs.
#[derive(Clone, Debug)]
pub struct StressOptions {
    /// Backends every scene is rendered with.
    pub accels: Vec<AccelKind>,
    /// Rays per agreement check (0: skip the agreement checks).
    pub agree_rays: usize,
    /// Smaller renders (fewer samples and photons) for the test profile; every case still runs.
    pub quick: bool,
}

impl Default for StressOptions {
    fn default() -> Self {
        let mut accels = Vec::new();
        if cfg!(feature = "embree") {
            accels.push(AccelKind::Embree);
        }
        accels.push(AccelKind::Bvh);
        StressOptions { accels, agree_rays: 10_000, quick: false }
    }
}

/// A named group of checks.
pub struct Case {
    pub name: &'static str,
    /// One line on what it stresses.
    pub about: &'static str,
    run: fn(&StressOptions) -> Vec<Row>,
}

impl Case {
    /// Runs every check of the case.
    pub fn run(&self, opts: &StressOptions) -> Vec<Row> {
        (self.run)(opts)
    }
}

/// Every case, in the order of the issue.
pub fn cases() -> Vec<Case> {
    cases::all()
}

/// Runs the cases whose name contains `filter` (all without one), calling `on_row` as each
/// row is done, and returns the rows.
pub fn run(filter: Option<&str>, opts: &StressOptions, mut on_row: impl FnMut(&Row)) -> Vec<Row> {
    let mut rows = Vec::new();
    for case in cases().iter().filter(|c| filter.is_none_or(|f| c.name.contains(f))) {
        for row in case.run(opts) {
            on_row(&row);
            rows.push(row);
        }
    }
    rows
}

/// The table's header line.
pub fn table_header() -> String {
    format!(
        "{:<22} {:<10} {:<34} {:<30} {:<46} {:>9} {:>7}  result",
        "case", "accel", "check", "expected", "measured", "nonfinite", "seconds"
    )
}

/// One line of the table.
pub fn table_row(r: &Row) -> String {
    format!(
        "{:<22} {:<10} {:<34} {:<30} {:<46} {:>9} {:>7.2}  {}",
        r.case,
        r.accel,
        r.check,
        r.expected,
        r.measured,
        r.nonfinite,
        r.seconds,
        if r.pass { "pass" } else { "FAIL" }
    )
}

/// Why a check could not run.
#[derive(Debug, thiserror::Error)]
pub enum StressError {
    #[error(transparent)]
    Accel(#[from] AccelError),
    #[error(transparent)]
    Config(#[from] ConfigError),
}

/// Renders of one row: counts what is not finite.
#[derive(Default)]
struct Probe {
    nonfinite: u64,
}

impl Probe {
    /// Renders `scene` at `size`² with `settings` and `accel`, counting non-finite samples and
    /// pixels.
    fn render(
        &mut self,
        scene: &Scene,
        settings: &RenderSettings,
        size: u32,
        accel: AccelKind,
    ) -> Result<RenderOutput, StressError> {
        let settings = RenderSettings { accel: Some(accel), ..settings.clone() };
        let cfg = scene.render.overridden_by(&settings).resolve(size, size)?;
        let out = render_scene(scene, &cfg, &Quiet)?;
        self.nonfinite += out.stats.nonfinite_samples + out.film.nonfinite_count() as u64;
        Ok(out)
    }
}

/// Runs `f` as one row: its result is `(measured, pass)`; an error fails the row, and so does
/// any non-finite value.
fn row(
    case: &str,
    accel: &str,
    check: &str,
    expected: String,
    f: impl FnOnce(&mut Probe) -> Result<(String, bool), StressError>,
) -> Row {
    let start = Instant::now();
    let mut probe = Probe::default();
    let (measured, pass) = f(&mut probe).unwrap_or_else(|e| (format!("error: {e}"), false));
    Row {
        case: case.to_owned(),
        accel: accel.to_owned(),
        check: check.to_owned(),
        expected,
        measured,
        nonfinite: probe.nonfinite,
        seconds: start.elapsed().as_secs_f64(),
        pass: pass && probe.nonfinite == 0,
    }
}

/// The agreement row of a scene: Embree against the BVH on the rays of
/// [`agree_scene`](crate::tools::agree::agree_scene); without Embree the BVH against brute force, on
/// as many of those rays as brute force's budget allows (a scene too large for even one ray
/// fails the row as not run).
fn agreement(case: &str, scene: &Scene, opts: &StressOptions) -> Option<Row> {
    if opts.agree_rays == 0 {
        return None;
    }
    let pair = if cfg!(feature = "embree") { "embree=bvh" } else { "bvh=naive" };
    Some(row(case, pair, "backends agree (outside ties)", "0 disagreements".into(), |_| {
        let r = crate::tools::agree::agree_scene(scene, opts.agree_rays, 1, AccelOptions::default())?;
        let m = &r.main;
        if !r.ran() {
            let why = format!("not run: {} triangles, too many for brute force", scene.mesh.len());
            return Ok((why, false));
        }
        let bad = m.hit_miss_disagreements + m.primitive_disagreements + m.occlusion_disagreements;
        let of = if m.rays < r.generated_rays { format!(" of {}", r.generated_rays) } else { String::new() };
        Ok((format!("{bad} of {} rays{of} ({} ties)", m.rays, m.edge_ties), r.clean()))
    }))
}
