//! Error against time: `photonmap converge` renders a scene with several methods at several
//! time budgets, measures each image against a reference (RMSE and relative MSE over all
//! pixels and channels), and reports a table, CSV and a log-log plot ([`crate::tools::plot`]).
//!
//! Every method runs with `--time budget`: the progressive ones (progressive photon mapping,
//! the path tracer) refine one image, the two-pass photon-mapping methods average passes of a
//! fixed size (each pass its own photon maps), so their error falls and then levels off at the
//! bias of the pass's photon count. The x axis is the measured wall time of the render
//! (acceleration structure included), which exceeds the budget when one pass takes longer.

use crate::choice::Choice;
use crate::config::{ColorMode, IndirectMode, IntegratorKind, RenderSettings};
use crate::film::sums::Bias;
use crate::film::{compare, Film};
use crate::frame::Quiet;
use crate::integrator::{render_scene_with, Control};
use crate::scene::Scene;
use serde::Serialize;
use std::fmt::Write as _;
use std::time::Instant;

crate::choice! {
    /// A rendering method: an integrator with the settings of one pass.
    pub enum Method {
        /// Two-pass photon mapping, RGB photons, radiance estimate (200k + 50k photons, 16 spp a
        /// pass).
        PhotonRgb = "photon-rgb",
        /// Two-pass photon mapping at its defaults (1M + 300k photons, 64 spp a pass): what
        /// `photonmap render --time` runs.
        PhotonDefault = "photon-default",
        /// The same with the lecture's three per-channel maps.
        PhotonChannel = "photon-channel",
        /// Two-pass photon mapping with final gathering (200k + 50k photons, 4 spp x 16 rays a
        /// pass).
        FinalGather = "final-gather",
        /// Stochastic progressive photon mapping (its defaults: 100k + 30k photons, 4 spp a pass).
        Sppm = "sppm",
        /// Pass-indexed progressive photon mapping (the same defaults).
        Pppm = "pppm",
        /// The path tracer, 4 spp a pass.
        Path = "path",
    }
}

impl Method {
    /// The settings of one pass (the scene's own `[render]` table fills the rest).
    pub fn settings(self) -> RenderSettings {
        let photon = RenderSettings {
            integrator: Some(IntegratorKind::Photon),
            photons: Some(200_000),
            caustic_photons: Some(50_000),
            spp: Some(16),
            color: Some(ColorMode::Rgb),
            indirect: Some(IndirectMode::Estimate),
            ..Default::default()
        };
        match self {
            Method::PhotonRgb => photon,
            Method::PhotonDefault => {
                RenderSettings { integrator: Some(IntegratorKind::Photon), ..Default::default() }
            }
            Method::PhotonChannel => RenderSettings { color: Some(ColorMode::PerChannel), ..photon },
            Method::FinalGather => RenderSettings {
                indirect: Some(IndirectMode::FinalGather),
                final_gather_rays: Some(16),
                spp: Some(4),
                ..photon
            },
            Method::Sppm => RenderSettings { integrator: Some(IntegratorKind::Sppm), ..Default::default() },
            Method::Pppm => RenderSettings { integrator: Some(IntegratorKind::Pppm), ..Default::default() },
            Method::Path => {
                RenderSettings { integrator: Some(IntegratorKind::Path), spp: Some(4), ..Default::default() }
            }
        }
    }
}

/// One render of the study.
#[derive(Clone, Debug, Serialize)]
pub struct Point {
    pub method: Method,
    pub budget: f64,
    /// Measured wall time of the render.
    pub seconds: f64,
    pub passes: u32,
    pub rmse: f64,
    pub rel_mse: f64,
    /// Mean of the image over the reference's, minus one.
    pub bias: f64,
    /// The RMSE against the converged image: `rmse` less the reference's own noise, in
    /// quadrature ([`Study::reference_noise`]).
    pub true_rmse: f64,
    /// The render's own estimate of its RMSE, from its passes alone (`None` from one pass).
    pub estimated_rmse: Option<f64>,
    /// Whether that estimate includes the bias: zero or probed, not unknown.
    pub estimate_has_bias: bool,
}

impl Point {
    /// The estimated RMSE over the true one (`None` without an estimate or a true error).
    pub fn calibration(&self) -> Option<f64> {
        self.estimated_rmse.filter(|_| self.true_rmse > 0.0).map(|e| e / self.true_rmse)
    }
}

/// What a study needs besides the scene and the reference.
#[derive(Clone, Debug)]
pub struct Study {
    pub methods: Vec<Method>,
    pub budgets: Vec<f64>,
    pub width: u32,
    pub height: u32,
    pub seed: u64,
    /// Settings applied over every method's (e.g. `--accel`).
    pub overrides: RenderSettings,
    /// The reference's own RMSE (its noise), taken out of each render's in quadrature for the
    /// true error the estimate is judged against; 0 for an exact reference.
    pub reference_noise: f64,
}

/// Why a study could not run.
#[derive(Debug, thiserror::Error)]
pub enum ConvergeError {
    #[error("the reference is {0}x{1} but the renders are {2}x{3}")]
    Size(usize, usize, u32, u32),
    #[error("{0}")]
    Config(#[from] crate::config::ConfigError),
    #[error("{0}")]
    Accel(#[from] crate::accel::AccelError),
}

/// Runs every method at every budget, in that order, calling `report` after each render.
pub fn run(
    scene: &Scene,
    reference: &Film,
    study: &Study,
    mut report: impl FnMut(&Point),
) -> Result<Vec<Point>, ConvergeError> {
    if (reference.width, reference.height) != (study.width as usize, study.height as usize) {
        return Err(ConvergeError::Size(reference.width, reference.height, study.width, study.height));
    }
    let mut points = Vec::new();
    for &method in &study.methods {
        for &budget in &study.budgets {
            let run = RenderSettings { time: Some(budget), seed: Some(study.seed), ..Default::default() };
            let settings = scene
                .render
                .overridden_by(&method.settings())
                .overridden_by(&study.overrides)
                .overridden_by(&run);
            let cfg = settings.resolve(study.width, study.height)?;
            let started = Instant::now();
            let control = Control { started, ..Default::default() };
            let out = render_scene_with(scene, &cfg, &Quiet, control)?;
            let seconds = started.elapsed().as_secs_f64();
            let (rmse, rel_mse) = compare(&out.film, reference).expect("sizes checked above");
            let estimate = out.sums.estimate();
            let point = Point {
                method,
                budget,
                seconds,
                passes: out.stats.passes,
                rmse,
                rel_mse,
                bias: out.film.mean() / reference.mean() - 1.0,
                true_rmse: (rmse * rmse - study.reference_noise.powi(2)).max(0.0).sqrt(),
                estimated_rmse: estimate.map(|e| e.rmse),
                estimate_has_bias: estimate.is_some_and(|e| e.bias != Bias::Unknown),
            };
            report(&point);
            points.push(point);
        }
    }
    Ok(points)
}

/// Least-squares slope of log(RMSE) against log(seconds) for `method` (`None` with fewer than
/// two points). An unbiased method falls at -0.5. Progressive photon mapping's photon term
/// falls more slowly in the limit: with radii shrinking as `r² ~ i^(α-1)` over `i` passes its
/// variance goes as `i^-α` and its squared bias as `i^(2(α-1))` (Knaus & Zwicker 2011), so
/// with α = 0.7 its RMSE tends to a slope of -0.3 to -0.35, while the camera samples' noise
/// (direct light, edges) falls at -0.5. A fixed photon count levels off at its bias (slope 0).
pub fn slope(points: &[Point], method: Method) -> Option<f64> {
    slope_of(points, method, |p| p.rmse)
}

/// [`slope`] of the true RMSE ([`Point::true_rmse`]: the reference's own noise taken out in
/// quadrature), which a noisy reference otherwise flattens.
pub fn true_slope(points: &[Point], method: Method) -> Option<f64> {
    slope_of(points, method, |p| p.true_rmse)
}

/// Least-squares slope of log(`error(point)`) against log(seconds) for `method`, over its
/// points with a positive error.
fn slope_of(points: &[Point], method: Method, error: impl Fn(&Point) -> f64) -> Option<f64> {
    let xy: Vec<(f64, f64)> = points
        .iter()
        .filter(|p| p.method == method && p.seconds > 0.0 && error(p) > 0.0)
        .map(|p| (p.seconds.ln(), error(p).ln()))
        .collect();
    if xy.len() < 2 {
        return None;
    }
    let n = xy.len() as f64;
    let (mx, my) = (xy.iter().map(|p| p.0).sum::<f64>() / n, xy.iter().map(|p| p.1).sum::<f64>() / n);
    let sxx: f64 = xy.iter().map(|p| (p.0 - mx) * (p.0 - mx)).sum();
    let sxy: f64 = xy.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    (sxx > 0.0).then(|| sxy / sxx)
}

/// The header of [`table_row`]'s table.
pub const TABLE_HEADER: &str =
    "method           budget s   time s  passes      rmse   rel_mse     mean  est rmse  est/true";

/// One row of the printed table: the estimate over the true error last, marked `*` where the
/// estimate leaves out a bias it cannot see (two-pass photon mapping, sppm).
pub fn table_row(p: &Point) -> String {
    let estimate = p.estimated_rmse.map_or_else(|| format!("{:>9}", "-"), |e| format!("{e:>9.5}"));
    let ratio = p.calibration().map_or_else(|| format!("{:>9}", "-"), |r| format!("{r:>9.2}"));
    let unseen = if p.estimated_rmse.is_some() && !p.estimate_has_bias { "*" } else { "" };
    format!(
        "{:<16} {:>8.2} {:>8.2} {:>7} {:>9.5} {:>9.5} {:>+7.2}% {estimate} {ratio}{unseen}",
        p.method.name(),
        p.budget,
        p.seconds,
        p.passes,
        p.rmse,
        p.rel_mse,
        100.0 * p.bias
    )
}

/// The points as CSV, with a header line.
pub fn csv(points: &[Point]) -> String {
    let mut s = String::from(
        "method,budget_seconds,seconds,passes,rmse,rel_mse,bias,true_rmse,estimated_rmse,estimate_has_bias\n",
    );
    for p in points {
        let estimate = p.estimated_rmse.map_or(String::new(), |e| format!("{e:.6}"));
        let _ = writeln!(
            s,
            "{},{},{:.4},{},{:.6},{:.6},{:.6},{:.6},{estimate},{}",
            p.method.name(),
            p.budget,
            p.seconds,
            p.passes,
            p.rmse,
            p.rel_mse,
            p.bias,
            p.true_rmse,
            p.estimate_has_bias
        );
    }
    s
}

/// An error measured elsewhere, for comparison: another renderer's RMSE against the same
/// reference after `seconds` on the same kind of machine, rendering `width × height` pixels.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Peer {
    pub renderer: String,
    pub width: u32,
    pub height: u32,
    pub seconds: f64,
    pub rmse: f64,
}

/// Why a peers file was refused.
#[derive(Debug, thiserror::Error)]
#[error("line {line}: {msg}")]
pub struct PeersError {
    pub line: usize,
    pub msg: String,
}

/// The header a peers file starts with.
pub const PEERS_HEADER: &str = "scene,renderer,width,height,seconds,rmse";

/// Reads the peers of scene `scene` from CSV text with the header [`PEERS_HEADER`] (rows of
/// other scenes are skipped; `#` starts a comment line). The sizes are checked against the
/// renders' `width × height`: a time measured at another resolution races nothing.
pub fn parse_peers(text: &str, scene: &str, width: u32, height: u32) -> Result<Vec<Peer>, PeersError> {
    let err = |line: usize, msg: String| PeersError { line, msg };
    let mut rows = text.lines().enumerate().filter(|(_, l)| !l.trim().is_empty() && !l.starts_with('#'));
    match rows.next() {
        Some((_, h)) if h.trim() == PEERS_HEADER => {}
        Some((i, h)) if h.trim() == "scene,renderer,seconds,rmse" => {
            return Err(err(
                i + 1,
                format!(
                "the header `{h}` gives no resolution: use `{PEERS_HEADER}` (the size each peer rendered)"
            ),
            ))
        }
        Some((i, h)) => return Err(err(i + 1, format!("expected the header `{PEERS_HEADER}`, found `{h}`"))),
        None => return Err(err(1, "empty file".into())),
    }
    let mut peers = Vec::new();
    for (i, l) in rows {
        let f: Vec<&str> = l.split(',').map(str::trim).collect();
        if f.len() != 6 {
            return Err(err(i + 1, format!("expected 6 fields, found {}", f.len())));
        }
        let num = |k: usize, what: &str| match f[k].parse::<f64>() {
            Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
            _ => Err(err(i + 1, format!("{what} `{}` is not a positive number", f[k]))),
        };
        let side = |k: usize, what: &str| match f[k].parse::<u32>() {
            Ok(v) if v > 0 => Ok(v),
            _ => Err(err(i + 1, format!("{what} `{}` is not a positive whole number", f[k]))),
        };
        let (w, h) = (side(2, "width")?, side(3, "height")?);
        let (seconds, rmse) = (num(4, "seconds")?, num(5, "rmse")?);
        if f[0] == scene {
            if (w, h) != (width, height) {
                return Err(err(
                    i + 1,
                    format!(
                        "{} was measured at {w}x{h} but the renders are {width}x{height}: their times are not comparable",
                        f[1]
                    ),
                ));
            }
            peers.push(Peer { renderer: f[1].to_string(), width: w, height: h, seconds, rmse });
        }
    }
    Ok(peers)
}

/// One line of the equal-time race: a peer's figure and the lowest error any method reached
/// here in at most the same time (`None` when no render was that fast).
#[derive(Clone, Debug, Serialize)]
pub struct Race<'a> {
    pub peer: &'a Peer,
    pub best: Option<&'a Point>,
}

/// For each peer figure, the best point measured within the peer's time.
pub fn race<'a>(points: &'a [Point], peers: &'a [Peer]) -> Vec<Race<'a>> {
    peers
        .iter()
        .map(|peer| Race {
            peer,
            best: points
                .iter()
                .filter(|p| p.seconds <= peer.seconds)
                .min_by(|a, b| a.rmse.total_cmp(&b.rmse)),
        })
        .collect()
}

/// The header of [`race_row`]'s table.
pub const RACE_HEADER: &str =
    "peer                                 s   peer rmse   best here          s      rmse   peer/here";

/// One row of the equal-time race table.
pub fn race_row(r: &Race<'_>) -> String {
    let head = format!("{:<32} {:>6.1} {:>11.4}", r.peer.renderer, r.peer.seconds, r.peer.rmse);
    match r.best {
        Some(p) => format!(
            "{head}   {:<14} {:>6.2} {:>9.4} {:>10.2}x",
            p.method.name(),
            p.seconds,
            p.rmse,
            r.peer.rmse / p.rmse
        ),
        None => format!("{head}   (no render was this fast)"),
    }
}

/// The log-log plot of RMSE against seconds, one line per method, and one dashed line per
/// peer renderer.
pub fn plot(points: &[Point], peers: &[Peer], title: &str) -> String {
    let mut series: Vec<crate::tools::plot::Series> = Method::ALL
        .iter()
        .filter(|&&m| points.iter().any(|p| p.method == m))
        .map(|&m| crate::tools::plot::Series {
            name: match slope(points, m) {
                Some(s) => format!("{} (slope {s:.2})", m.name()),
                None => m.name().to_string(),
            },
            points: points.iter().filter(|p| p.method == m).map(|p| (p.seconds, p.rmse)).collect(),
            dashed: false,
        })
        .collect();
    let mut names: Vec<&str> = peers.iter().map(|p| p.renderer.as_str()).collect();
    names.dedup();
    for name in names {
        series.push(crate::tools::plot::Series {
            name: name.to_string(),
            points: peers.iter().filter(|p| p.renderer == name).map(|p| (p.seconds, p.rmse)).collect(),
            dashed: true,
        });
    }
    crate::tools::plot::log_log_svg(title, "seconds", "RMSE", &series)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::{Integrator, RenderConfig};

    /// `photon-default` is what `photonmap render --time` runs: the defaults, nothing else;
    /// `photon-rgb` its smaller passes.
    #[test]
    fn photon_default_is_the_render_default() {
        let resolve = |s: RenderSettings| -> RenderConfig { s.resolve(64, 64).unwrap() };
        let default = resolve(RenderSettings::default());
        assert_eq!(resolve(Method::PhotonDefault.settings()), default);
        let Integrator::Photon(small) = resolve(Method::PhotonRgb.settings()).integrator else {
            panic!("photon-rgb is two-pass photon mapping")
        };
        let Integrator::Photon(full) = default.integrator else { panic!("the default is two-pass") };
        assert!(small.maps.photons < full.maps.photons);
    }

    fn point(method: Method, seconds: f64, rmse: f64) -> Point {
        Point {
            method,
            budget: seconds,
            seconds,
            passes: 1,
            rmse,
            rel_mse: 0.0,
            bias: 0.0,
            true_rmse: rmse,
            estimated_rmse: None,
            estimate_has_bias: false,
        }
    }

    #[test]
    fn slope_of_a_power_law() {
        let pts: Vec<Point> =
            [1.0, 2.0, 4.0, 8.0].iter().map(|&t| point(Method::Path, t, 0.1 * f64::powf(t, -0.5))).collect();
        assert!((slope(&pts, Method::Path).unwrap() + 0.5).abs() < 1e-9);
        assert_eq!(slope(&pts, Method::Sppm), None);
    }

    /// A render whose error falls as `t^-0.5` against a reference with noise of its own: the
    /// RMSE against the reference falls more slowly, the true one as the render's.
    #[test]
    fn true_slope_takes_the_references_noise_out() {
        let noise = 0.02;
        let pts: Vec<Point> = [20.0, 45.0]
            .iter()
            .map(|&t: &f64| {
                let own = 0.1 * t.powf(-0.5);
                Point { true_rmse: own, ..point(Method::Pppm, t, (own * own + noise * noise).sqrt()) }
            })
            .collect();
        assert!(slope(&pts, Method::Pppm).unwrap() > -0.4);
        assert!((true_slope(&pts, Method::Pppm).unwrap() + 0.5).abs() < 1e-9);
    }

    #[test]
    fn csv_and_plot_hold_every_point() {
        let pts = vec![point(Method::Sppm, 1.0, 0.05), point(Method::Sppm, 2.0, 0.03)];
        let c = csv(&pts);
        assert_eq!(c.lines().count(), 3);
        assert!(c.lines().nth(2).unwrap().starts_with("sppm,2,2.0000,1,0.030000"));
        let peers = vec![Peer { renderer: "other".into(), width: 8, height: 8, seconds: 1.5, rmse: 0.1 }];
        let svg = plot(&pts, &peers, "t");
        assert!(svg.starts_with("<svg") && svg.contains("sppm (slope -0.74)"), "{svg}");
        assert!(svg.contains(">other</text>") && svg.contains("stroke-dasharray"), "{svg}");
    }

    #[test]
    fn peers_are_read_for_one_scene_and_bad_rows_are_named() {
        let text = "# measured elsewhere\nscene,renderer,width,height,seconds,rmse\ncornell,A,64,48,5,0.02\n\
                    caustics,A,256,256,5,0.09\ncornell,A,64,48,20,0.01\n";
        let peers = parse_peers(text, "cornell", 64, 48).unwrap();
        assert_eq!(peers.len(), 2);
        assert_eq!(peers[1], Peer { renderer: "A".into(), width: 64, height: 48, seconds: 20.0, rmse: 0.01 });
        let h = "scene,renderer,width,height,seconds,rmse\n";
        let e = parse_peers(&format!("{h}cornell,A,64,48,five,0.02\n"), "cornell", 64, 48).unwrap_err();
        assert_eq!((e.line, e.msg.contains("`five`")), (2, true), "{e}");
        assert_eq!(parse_peers("a,b\n", "cornell", 64, 48).unwrap_err().line, 1);
        assert_eq!(parse_peers(&format!("{h}cornell,A,1\n"), "cornell", 64, 48).unwrap_err().line, 2);
        // A peer timed at another resolution is refused, naming both sizes.
        let e = parse_peers(text, "cornell", 256, 256).unwrap_err();
        assert!(e.line == 3 && e.msg.contains("64x48") && e.msg.contains("256x256"), "{e}");
        // Rows of other scenes are not checked against this one's size.
        assert_eq!(parse_peers(text, "caustics", 256, 256).unwrap().len(), 1);
        let old =
            parse_peers("scene,renderer,seconds,rmse\ncornell,A,5,0.02\n", "cornell", 64, 48).unwrap_err();
        assert!(old.msg.contains("gives no resolution"), "{old}");
    }

    #[test]
    fn the_race_takes_the_best_point_within_the_peers_time() {
        let pts = vec![
            point(Method::Sppm, 1.0, 0.05),
            point(Method::Path, 4.0, 0.02),
            point(Method::Sppm, 6.0, 0.01),
        ];
        let peers = vec![
            Peer { renderer: "A".into(), width: 8, height: 8, seconds: 5.0, rmse: 0.04 },
            Peer { renderer: "A".into(), width: 8, height: 8, seconds: 0.5, rmse: 0.5 },
        ];
        let r = race(&pts, &peers);
        assert_eq!(r[0].best.map(|p| (p.method, p.rmse)), Some((Method::Path, 0.02)));
        assert!(race_row(&r[0]).ends_with("2.00x"), "{}", race_row(&r[0]));
        assert!(r[1].best.is_none());
        assert!(race_row(&r[1]).contains("no render"));
    }
}
