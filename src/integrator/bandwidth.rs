//! How wide each pixel's first radius should be: the `k`-th nearest photon's distance `r_1`,
//! widened (up to twice, `WIDEST2` in area) where the pilot finds the light flat about the
//! pixel, so that there the passes gather more photons for the same bias.
//!
//! Pass `i` gathers within `r²_i = u r²_1 σ_i` (`σ_i`, the [`radius2_scale`], shrinks as
//! `i^(α-1)`; `u` is the widening, in area). Where the light varies smoothly over a whole disc
//! the estimate's bias grows with the disc's area (the second-order term of its Taylor
//! expansion; the first cancels over the symmetric disc): `u σ_i b`, `b` the bias at `r_1`; its
//! variance falls as the photons in it grow: `V / (u σ_i)`, `V` at `r_1`. The camera samples'
//! variance `C` (emission and direct light) does not change, but a wider gather takes longer:
//! passes take `T = 1 + GATHER_COST (ū − 1)` times as long (`ū` the image's mean widening), and
//! fewer fit in the time. The image's squared error, the mean over its pixels `p` of the
//! passes a time allows (`n = PASSES` unwidened), is then
//!
//! ```text
//! MSE = mean_p [ (u_p σ̄ b_p)² + (C_p + V_p ρ̄ / u_p) T / n ],   σ̄ = mean σ_i,  ρ̄ = mean 1/σ_i
//! ```
//!
//! A pixel's widening lengthens every pixel's passes: given the others', its best `u` is the
//! least over `[1, WIDEST2]` (the root of its convex slope, by Newton's method) of
//! `(u σ̄ b)² + V ρ̄ T / (n u) + GATHER_COST Ē u / n`, `Ē` the image's mean variance per pass;
//! `ROUNDS` rounds of every pixel's choice settle it. For passes of `m` times the pilot's
//! photons ([`super::balance`]) `V` is `V / m`, the gathers' price is counted from the pass's
//! work, and pixels not measured keep a pass's own `k`-th nearest photon (`u = 1 / m`).
//! (Alone, with no cost, `u³ = V ρ̄ / (2 n σ̄² b²)`.) `n` is fixed: `ρ̄ / (n σ̄²)` goes as
//! `n^(2 - 3α)`, so `u` moves as `n^(-0.03)` at α = 0.7, and it must not depend on how many
//! passes a render happens to make, or the parts of a split render would not agree.
//!
//! The pilot measures `b`, `V` and `C` at each pixel's visible point, from its own photons and
//! camera samples. `b` comes from the indirect photons (caustics keep their radius: their
//! light is focused, and sharp at any scale) within the disc of radius `R = 3 r_1`
//! (`MEASURE2`; cut to the surface's footprint as the passes' gathers are) and the disc of half
//! its area: `2 (L_R − L_{R/√2})` is the bias at `R` (as in the passes' own bias probe,
//! [`super::pppm`]) and a ninth of it the bias at `r_1`; `V` comes from the photons within
//! `r_1`, `Σ flux² / area²`; `C` from the spread of the pixel's camera samples (what is random in them after the camera
//! ray, `sppm::camera_noise`). From `b`'s
//! estimate `b̂`, `b̂² − var(b̂)` estimates `b²` without bias; its noise at one pixel is still
//! about `V / 130` where the radius widens fully below `b² = V / 600` and not at all above
//! `V / 10`, so each pixel pools `b²` and `V` over the pixels of a square window about it
//! (`WINDOW` pixels each way): `u` is the best for the window, and changes smoothly across the
//! image.
//!
//! Next to a wall or an edge the disc is cut off centre and the first-order term no longer
//! cancels: the bias grows as the radius, not its square, and the two discs understate it (a
//! scanned bunny's foot on the floor came out bright in the blocks around it, and the image's
//! RMSE rose 5 %). So a pixel
//! widens only as far as its disc, `CLEAR` times wider for the next passes' visible points
//! about the pilot's, stays on the part of its surface the measuring disc's probes found whole.
//! `u` is at least 1 (the `k`-th nearest photon) and at most `WIDEST2` (and never past
//! `--gather-radius`). A pixel that may not widen is not measured, and a measuring gather that
//! meets more than twice the photons even light would put in its disc gives up (the light
//! crowds there: not flat; a dim floor running on through a doorway onto a lit one made the
//! doorway's pilot take 1.3 s, now 0.6 s, against 0.13 s without the measuring).

use super::probe;
use super::sppm::for_each_flux;
use crate::accel::Accel;
use crate::config::RenderConfig;
use crate::film::windows::Windows;
use crate::frame::specular::Landing;
use crate::frame::{Counters, Frame};
use crate::photon::footprint::{Footprint, CLEAR};
use crate::photon::map::PhotonMaps;
use crate::stats::Widening;
use glam::Vec3;
use rand_pcg::Pcg32;

use super::maps::GatherPair;

/// `r²_i / r²_1` for the pass with 0-based index `pass` (Knaus and Zwicker's schedule):
/// `Π_{j=1}^{pass} (j + α) / (j + 1)`.
pub fn radius2_scale(pass: u32, alpha: f32) -> f32 {
    let alpha = alpha as f64;
    (1..=pass as u64).map(|j| (j as f64 + alpha) / (j as f64 + 1.0)).product::<f64>() as f32
}

/// Whether a render is long enough for the pilot's measuring (about 0.4 s on the shipped
/// scenes at 256², against 0.13 s for the first radii alone) to pay: 16 passes or more, or a
/// time budget of 10 s or more, or a target error (as many passes as it takes). At 2 s the
/// measuring took a third of the passes and the error rose (Cornell box 0.0082 → 0.0116).
pub fn pays(cfg: &RenderConfig) -> bool {
    // The render stops at whichever of its pass count and time comes first.
    let few_passes = cfg.passes.is_some_and(|p| p < 16);
    let little_time = cfg.time.is_some_and(|t| t < 10.0);
    let many = cfg.passes.is_some() || cfg.time.is_some() || cfg.target_error.is_some();
    many && !few_passes && !little_time
}

/// The widest first radius, over the `k`-th nearest photon's, squared.
pub(super) const WIDEST2: f32 = 4.0;

/// The squared radius of the disc the pilot measures the bias over, over the `k`-th nearest
/// photon's: wider than the widest first radius, for an estimate of the bias with
/// `MEASURE2³` (729) times less variance than one at `r_1` would have (the light must be flat over it
/// for the radius to widen much).
const MEASURE2: f32 = 9.0;

/// How many pixels each way a pixel's window reaches.
const WINDOW: usize = 8;

/// The passes the widening is chosen for (it hardly depends on them; see the module's notes).
const PASSES: u32 = 64;

/// What the pilot found about one pixel's photon estimate at its first radius.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(super) struct Spread {
    /// An unbiased estimate of the squared bias at `r_1` (summed over the channels).
    pub bias2: f64,
    /// An estimate of one pass's variance at `r_1` (summed over the channels).
    pub var: f64,
    /// An estimate of the variance of one pass's camera samples' mean (emission and direct
    /// light; summed over the channels), from what is random after the camera rays
    /// (`sppm::camera_noise`): what widening does not reduce.
    pub camera: f64,
    /// The most the squared radius may widen before the disc reaches a wall or an edge
    /// (`WIDEST2` where the measured disc lay whole on the surface).
    pub room: f32,
    /// Whether the pixel was measured (a visible point with photons near it, on a surface at
    /// least as wide as the widest disc's footprint allows).
    pub measured: bool,
    /// An unbiased estimate of the squared bias at `r_1`, from the photons within it (summed
    /// over the channels; 0 where nothing was seen): of the caustic maps where measured, of the
    /// whole photon term where not: what keeps a pass's own `k`-th nearest photon, `m` times
    /// nearer in area when a pass traces `m` times the photons. Its square is taken to fall as
    /// `1 / m`, as the bias of a disc cut by a wall or an edge does (it grows with the radius,
    /// not the area): measured, the doorway's pixels by its walls lost 0.46 of it at 4× the
    /// photons, the atrium's 0.69.
    pub fixed2: f64,
    /// The variance at `r_1` of what keeps a pass's own `k`-th nearest photon where measured
    /// (the caustic maps: their discs hold `k` photons whatever the photons a pass, and their
    /// variance does not fall with more; summed over the channels). Where not measured, `var`
    /// is all of it.
    pub fixed_var: f64,
}

impl Spread {
    /// Measures the photons of `maps` about the visible point `v` (surface normal `ns`, first
    /// radius `r²_1 = r2`) within the widest disc.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn measure<A: Accel>(
        frame: &Frame<'_, A>,
        maps: &PhotonMaps,
        gathers: &GatherPair,
        v: &Landing,
        ns: Vec3,
        r2: f32,
        rng: &mut Pcg32,
        c: &mut Counters,
    ) -> Spread {
        let cap2 = gathers.indirect.max_radius * gathers.indirect.max_radius;
        let wide2 = MEASURE2 * r2;
        if r2 >= cap2 {
            return Spread::default();
        }
        let wide = probe::probe(frame, &v.hit, ns, wide2, rng, c);
        // A surface narrower than the measured disc (the probes fell back on a smaller one), or
        // none of it: not measured.
        if wide.r2 != wide2 || wide.share <= 0.0 {
            return Spread::default();
        }
        // Widening must not carry the disc over a wall or an edge (there the disc is cut off
        // centre, its bias grows as the radius, not its square, and the two discs below
        // understate it), nor past the largest gather radius asked for (`--gather-radius`).
        let room = (wide.reach() * wide.reach() / (CLEAR * CLEAR * r2)).min(cap2 / r2).clamp(1.0, WIDEST2);
        if room <= 1.0 {
            // It may not widen at all: nothing to measure.
            return Spread::default();
        }
        let half = wide.half();
        let first = wide.within(1.0 / MEASURE2);
        let (mut all, mut inner) = ((Vec3::ZERO, Vec3::ZERO), (Vec3::ZERO, Vec3::ZERO));
        let mut first_sq = Vec3::ZERO;
        // The indirect maps only: caustics keep their radius (see `fluxes_within`).
        let none = Footprint::whole(0.0);
        // Where the photons crowd into the disc far beyond the `MEASURE2 k` of even light (a
        // dim floor running on through a doorway onto a lit one), the light is not flat, and
        // the pilot need not visit them all.
        let most = (2.0 * MEASURE2) as u32 * gathers.indirect.k as u32;
        let m = for_each_flux(maps, gathers, v, ns, [&wide, &none], None, Some(most), c, |flux, d2, _| {
            let sq = flux * flux;
            all.0 += flux;
            all.1 += sq;
            if d2 < half.r2 {
                inner.0 += flux;
                inner.1 += sq;
            }
            if d2 < first.r2 {
                first_sq += sq;
            }
        });
        if m.is_none_or(|m| m == 0) || half.share <= 0.0 || first.share <= 0.0 {
            return Spread::default();
        }
        let pi = std::f64::consts::PI as f32;
        let (area, area_half, area_first) =
            (pi * wide2 * wide.share, pi * half.r2 * half.share, pi * first.r2 * first.share);
        let beta2 = v.beta * v.beta;
        // The bias at R, 2 (L_R − L_h), and its variance: each photon's flux weighs
        // 2 (1/A_R − 1/A_h) inside the half disc and 2/A_R outside it.
        let bias_wide = 2.0 * v.beta * (all.0 / area - inner.0 / area_half);
        let w_in = 2.0 * (1.0 / area - 1.0 / area_half);
        let w_out = 2.0 / area;
        let var_wide = beta2 * (w_in * w_in * inner.1 + w_out * w_out * (all.1 - inner.1));
        // At r_1 the bias is 1/MEASURE2 of that, its estimate's variance 1/MEASURE2².
        let b = bias_wide / MEASURE2;
        let var_b = var_wide / (MEASURE2 * MEASURE2);
        let bias2 = (b * b - var_b).element_sum() as f64;
        let var = (beta2 * first_sq / (area_first * area_first)).element_sum() as f64;
        if !(bias2.is_finite() && var.is_finite()) {
            return Spread::default();
        }
        Spread { bias2, var, camera: 0.0, room, measured: true, fixed2: 0.0, fixed_var: 0.0 }
    }
}

/// Each pixel's widening `u` of its squared first radius (over the pilot's `k`-th nearest
/// photon's), from the spreads of the pixels in its window (row-major, `width` wide), for the
/// passes of `model`; and the image's mean squared error the model predicts with them. A pixel
/// measured widens up to its `room`, and never narrows below the pilot's radius (its bias is
/// measured over a disc nine times as wide: too coarse to narrow by); any other keeps a pass's
/// own `k`-th nearest photon (`1 / m`), as caustics do: near a wall or an edge, where the bias
/// grows with the radius itself and the pilot cannot measure it, more photons a pass are what
/// shrinks it.
pub(super) fn widenings(spreads: &[Spread], width: usize, model: &Model) -> Widened {
    let height = spreads.len() / width.max(1);
    // Window sums over the measured pixels (the squared bias, the photons' variance, the
    // caustics' squared bias, how many) and over the others seen (the squared bias, the
    // variance, how many).
    let windows = Windows::new(width, height, |x, y| {
        let s = &spreads[y * width + x];
        if s.measured {
            [s.bias2, s.var, s.fixed2, 1.0, 0.0, 0.0, 0.0]
        } else if s.var > 0.0 {
            [0.0, 0.0, 0.0, 0.0, s.fixed2, s.var, 1.0]
        } else {
            [0.0; 7]
        }
    });
    // Each pixel's window means over the pixels of its own kind.
    let mut pooled = vec![Pooled::default(); spreads.len()];
    for y in 0..height {
        for x in 0..width {
            let (sum, _) = windows.around(x, y, WINDOW);
            let s = &spreads[y * width + x];
            pooled[y * width + x] = if s.measured {
                let n = sum[3].max(1.0);
                Pooled { bias2: sum[0] / n, var: sum[1] / n, fixed2: sum[2] / n, least: 1.0, most: s.room }
            } else if s.var > 0.0 {
                let n = sum[6].max(1.0);
                let least = model.least();
                Pooled { bias2: 0.0, var: sum[5] / n, fixed2: sum[4] / n, least, most: least }
            } else {
                Pooled { least: model.least(), most: model.least(), ..Pooled::default() }
            };
        }
    }
    let mut out: Vec<f32> = pooled.iter().map(|p| p.least).collect();
    // The widening of one pixel slows every pixel's passes: each pixel's choice weighs the
    // image's mean variance, which depends on every choice; a few rounds settle it.
    for _ in 0..ROUNDS {
        let image = model.image(spreads, &out);
        out = pooled
            .iter()
            .map(|p| model.widening(p.bias2, p.var, image, p.least, p.most.max(p.least)))
            .collect();
    }
    let image = model.image(spreads, &out);
    let n = spreads.len().max(1) as f64;
    let (sigma, m) = (model.sigma, model.passes.photons);
    let bias2 = pooled
        .iter()
        .zip(&out)
        .map(|(p, &u)| (u as f64 * sigma).powi(2) * p.bias2.max(0.0) + sigma * sigma / m * p.fixed2.max(0.0))
        .sum::<f64>()
        / n;
    Widened { mse: bias2 + image.var * image.slower / model.passes.n, u: out }
}

/// A pixel's window's means: the squared bias at `r_1` of what its radius changes, its
/// photons' variance, the squared bias of what keeps a pass's own `k`-th nearest photon (the
/// caustics), and the narrowest and widest its squared radius may be (over `r²_1`).
#[derive(Clone, Copy, Debug, Default)]
struct Pooled {
    bias2: f64,
    var: f64,
    fixed2: f64,
    least: f32,
    most: f32,
}

/// Each pixel's widening and what the model predicts of the image with them.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Widened {
    /// Each pixel's squared first radius over the pilot's `k`-th nearest photon's.
    pub u: Vec<f32>,
    /// The image's mean squared error (summed over the channels) after the reference time.
    pub mse: f64,
}

/// Rounds of [`widenings`]' choice (each pixel's given the others').
const ROUNDS: usize = 4;

/// What the widenings came to, for `--stats`: their mean (of the radius over a pass's own
/// `k`-th nearest photon's, `√(m u)`) and how many pixels were widest, over the pixels
/// measured.
pub(super) fn summary(widen: &[f32], spreads: &[Spread], photons: f64) -> Widening {
    let measured: Vec<f64> =
        widen.iter().zip(spreads).filter(|(_, s)| s.measured).map(|(u, _)| *u as f64 * photons).collect();
    let n = measured.len().max(1) as f64;
    Widening {
        pixels: measured.len() as u64,
        mean: measured.iter().map(|u| u.sqrt()).sum::<f64>() / n,
        widest: measured.iter().filter(|u| **u >= WIDEST2 as f64 * photons * 0.999).count() as f64 / n,
    }
}

/// The passes the widening is chosen for, in the reference time (`PASSES` passes of the
/// pilot's own kind, unwidened).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Passes {
    /// How many fit in the reference time, their gathers at the `k`-th nearest photon.
    pub n: f64,
    /// The photons each traces over the pilot's, `m`: the `k`-th nearest photon lies `m`
    /// times nearer in area, and a disc of the same radius gathers `m` times the photons.
    pub photons: f64,
    /// How much longer a pass takes per unit of `m ū − 1` (`ū` the image's mean widening):
    /// its indirect gathers' time at the `k`-th nearest photon over the pass's.
    pub gather: f64,
}

impl Passes {
    /// The pilot's own passes: `PASSES` of its photons, their gathers' price [`GATHER_COST`].
    pub(super) fn pilot() -> Passes {
        Passes::new(1.0, 1.0, GATHER_COST)
    }

    /// The passes that fit in the reference time when each takes `slower` times as long as
    /// the pilot's, traces `photons` times its photons, and gathers at a price `gather`.
    pub(super) fn new(slower: f64, photons: f64, gather: f64) -> Passes {
        Passes { n: PASSES as f64 / slower, photons, gather }
    }
}

/// How much longer a pass takes per unit of widening where the pass's prices were not counted:
/// a widened gather visits `u` times the photons, and a pass takes `1 + GATHER_COST (u − 1)`
/// times as long. Measured with `--stats` on 20–30 passes before and after widening nearly
/// every pixel fully (`u` about 3.8): the white furnace's passes took 1.16× as long per unit of
/// `u − 1` in the camera stage (0.12 over the whole pass, photons and kd-tree included), the
/// caustics scene's 1.10× (0.06).
const GATHER_COST: f64 = 0.1;

/// The squared error of the mean of the passes a time allows as a function of the widening.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Model {
    passes: Passes,
    /// `σ̄`, the mean of `r²_i / r²_1` over the passes.
    sigma: f64,
    /// `ρ̄`, the mean of `r²_1 / r²_i`.
    pub(super) rho: f64,
}

/// What every pixel's choice shares: how much longer the passes take, and the image's mean
/// variance (per pass) that each unit of that costs.
#[derive(Clone, Copy, Debug)]
struct Image {
    /// The passes' time over the passes' at the `k`-th nearest photon (`1 + g (m ū − 1)`).
    slower: f64,
    /// The mean over the image of one pass's variance (camera samples and photons).
    var: f64,
}

impl Model {
    /// The model of `passes` whose radii shrink with `alpha`.
    pub(super) fn new(alpha: f32, passes: Passes) -> Self {
        let count = passes.n.round().clamp(1.0, 1e6) as u32;
        let n = count as f64;
        let (mut sigma, mut rho) = (0.0, 0.0);
        for i in 0..count {
            let s = radius2_scale(i, alpha) as f64;
            sigma += s / n;
            rho += 1.0 / (s * n);
        }
        Model { passes, sigma, rho }
    }

    /// The narrowest widening: a pass's own `k`-th nearest photon, `1 / m`.
    fn least(&self) -> f32 {
        (1.0 / self.passes.photons) as f32
    }

    /// What the widenings `u` make of the whole image.
    fn image(&self, spreads: &[Spread], u: &[f32]) -> Image {
        let n = spreads.len().max(1) as f64;
        let m = self.passes.photons;
        let mean_u = u.iter().map(|&u| u as f64).sum::<f64>() / n;
        let var = spreads.iter().zip(u).map(|(s, &u)| s.camera + self.photon_var(s, u)).sum::<f64>() / n;
        Image { slower: 1.0 + self.passes.gather * (m * mean_u - 1.0), var }
    }

    /// The variance of one pass's photon term at a pixel of spread `s` widened `u` times.
    pub(super) fn photon_var(&self, s: &Spread, u: f32) -> f64 {
        (s.var / (self.passes.photons * u as f64) + s.fixed_var) * self.rho
    }

    /// A pixel's part of the image's squared error at widening `u` (`n` passes in the time at
    /// the `k`-th nearest photon), for its squared bias `bias2` and its photons' variance `var`
    /// at the pilot's `r_1`: its bias, its photons' noise, and what its wider gathers take from
    /// every pixel's passes (`image.var` per pass more of the time, for each unit of `m u`).
    #[cfg(test)]
    fn mse(&self, u: f64, bias2: f64, var: f64, image: Image) -> f64 {
        let (a, b, d) = self.terms(bias2, var, image);
        a * u * u + b / u + d * u
    }

    /// [`Self::mse`] as `a u² + b / u + d u`.
    fn terms(&self, bias2: f64, var: f64, image: Image) -> (f64, f64, f64) {
        let Passes { n, photons: m, gather } = self.passes;
        let a = self.sigma * self.sigma * bias2.max(0.0);
        let b = var * self.rho * image.slower / (m * n);
        let d = gather * m * image.var / n;
        (a, b, d)
    }

    /// The widening in `[least, most]` of least squared error for the pooled `bias2` and
    /// `var`: `a u² + b / u + d u` is convex, and its slope `2 a u + d − b / u²` has one root
    /// on `u > 0`, found by Newton's method from above (where the slope is convex and
    /// increasing, it never overshoots).
    fn widening(&self, bias2: f64, var: f64, image: Image, least: f32, most: f32) -> f32 {
        let least = least as f64;
        let most = (most.min(WIDEST2) as f64).max(least);
        if !(var > 0.0) {
            return least as f32;
        }
        let (a, b, d) = self.terms(bias2, var, image);
        let slope = |u: f64| 2.0 * a * u + d - b / (u * u);
        if slope(least) >= 0.0 {
            return least as f32;
        }
        if slope(most) <= 0.0 {
            return most as f32;
        }
        // The root of h(u) = 2 a u³ + d u² − b (the slope times u²).
        let mut u = most;
        for _ in 0..40 {
            let h = 2.0 * a * u * u * u + d * u * u - b;
            let dh = 6.0 * a * u * u + 2.0 * d * u;
            let next = u - h / dh;
            if !(next.is_finite() && next < u) {
                break;
            }
            let done = u - next < 1e-7 * u;
            u = next.max(least);
            if done {
                break;
            }
        }
        u as f32
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_radius_shrinks_as_knaus_and_zwicker_prescribe() {
        assert_eq!(radius2_scale(0, 0.7), 1.0);
        assert!((radius2_scale(1, 0.7) - 1.7 / 2.0).abs() < 1e-6);
        assert!((radius2_scale(2, 0.7) - 1.7 / 2.0 * 2.7 / 3.0).abs() < 1e-6);
        // r²_i ~ i^(α-1): the ratio of passes 1000 and 100 is close to 10^(α-1).
        let ratio = radius2_scale(999, 0.7) / radius2_scale(99, 0.7);
        assert!((ratio - 10f32.powf(-0.3)).abs() < 0.01, "{ratio}");
    }

    /// The widening is the least squared error in a fixed time: wide where the bias is small
    /// against the photons' noise, the `k`-th photon's where it is large, and less wide where
    /// the image's noise is mostly the camera samples' (which widening does not reduce), since
    /// a wider gather takes time from every pixel. With `m` times the photons a pass, it may
    /// narrow to `1 / m`.
    #[test]
    fn the_widening_minimises_the_squared_error() {
        let model = Model::new(0.7, Passes::pilot());
        let n = PASSES as f64;
        let sigmas: Vec<f64> = (0..PASSES).map(|i| radius2_scale(i, 0.7) as f64).collect();
        assert!((model.sigma - sigmas.iter().sum::<f64>() / n).abs() < 1e-9);
        assert!((model.rho - sigmas.iter().map(|s| 1.0 / s).sum::<f64>() / n).abs() < 1e-9);
        let quiet = Image { slower: 1.0, var: 0.0 };
        let noisy = |var: f64| Image { slower: 1.2, var };
        let more = Model::new(0.7, Passes { n: 20.0, photons: 4.0, gather: 0.05 });
        for model in [model, more] {
            for (b2, v, image) in [
                (1e-4, 1.0, quiet),
                (1e-2, 1.0, quiet),
                (0.05, 1.0, noisy(1.0)),
                (0.0, 1.0, noisy(30.0)),
                (3.0, 1.0, noisy(1.0)),
            ] {
                let least = model.least();
                let u = model.widening(b2, v, image, least, WIDEST2) as f64;
                let best = (0..=30000)
                    .map(|j| least as f64 + (WIDEST2 - least) as f64 * j as f64 / 30000.0)
                    .map(|w| model.mse(w, b2, v, image))
                    .fold(f64::INFINITY, f64::min);
                assert!(model.mse(u, b2, v, image) <= best * 1.00001, "b² {b2} {image:?}: u {u}");
            }
        }
        let widest =
            |model: &Model, b2: f64, v: f64, image: Image| model.widening(b2, v, image, 1.0, WIDEST2);
        // Flat light and nothing else to pay for: the widest; none of the photons' noise: none.
        assert_eq!(widest(&model, 0.0, 1.0, quiet), WIDEST2);
        assert_eq!(widest(&model, -0.1, 1.0, quiet), WIDEST2);
        assert_eq!(model.widening(0.0, 1.0, quiet, 1.0, 2.5), 2.5);
        assert_eq!(widest(&model, 0.1, 0.0, quiet), 1.0);
        // Large bias: the k-th nearest photon's radius, or with more photons a pass, a narrower one.
        assert_eq!(widest(&model, 100.0, 1.0, quiet), 1.0);
        assert_eq!(more.widening(1e6, 1.0, quiet, 0.25, 1.0), 0.25);
        let u = more.widening(0.3, 1.0, quiet, 0.25, 1.0);
        assert!(u > 0.25 && u < 1.0, "{u}");
        // Camera noise over the image holds the widening back.
        assert!(widest(&model, 0.0, 1.0, noisy(300.0)) < widest(&model, 0.0, 1.0, noisy(3.0)));
        assert_eq!(widest(&model, 0.0, 1.0, noisy(1e4)), 1.0);
    }

    /// A pixel not measured keeps a pass's own `k`-th nearest photon (`1 / m` with `m` times
    /// the photons a pass); the error predicted counts its squared bias, which falls as `1 / m`,
    /// and a measured pixel never narrows below the pilot's radius.
    #[test]
    fn pixels_not_measured_keep_a_pass_s_own_k_th_photon() {
        let (w, h) = (32, 16);
        let spreads: Vec<Spread> = (0..w * h)
            .map(|i| {
                let (fixed2, measured) = if i % w >= w / 2 { (10.0, false) } else { (0.0, true) };
                Spread {
                    bias2: 100.0,
                    var: 1.0,
                    camera: 0.0,
                    room: WIDEST2,
                    measured,
                    fixed2,
                    fixed_var: 0.0,
                }
            })
            .collect();
        let passes = |photons: f64| Model::new(0.7, Passes { n: 16.0, photons, gather: 0.05 });
        let widened = widenings(&spreads, w, &passes(4.0));
        assert_eq!(widened.u[8 * w + 2], 1.0, "measured, large bias: the pilot's radius");
        assert_eq!(widened.u[8 * w + w - 2], 0.25, "not measured: a pass's own k-th nearest photon");
        let one = widenings(&spreads, w, &passes(1.0));
        assert!(one.u.iter().all(|&u| u == 1.0), "{:?}", one.u);
        // The squared bias of the pixels not measured: 1/m of it at m times the photons.
        let flat: Vec<Spread> = spreads.iter().map(|s| Spread { fixed2: 0.0, ..*s }).collect();
        let bias = |photons: f64| {
            widenings(&spreads, w, &passes(photons)).mse - widenings(&flat, w, &passes(photons)).mse
        };
        assert!((bias(1.0) / bias(4.0) - 4.0).abs() < 1e-6, "{} {}", bias(1.0), bias(4.0));
    }

    /// Pixels pool their window: a flat region widens, a biased one does not, unmeasured
    /// pixels keep their radius, and the result does not depend on anything but the spreads.
    #[test]
    fn windows_pool_their_pixels() {
        let (w, h) = (64, 32);
        let mut spreads = vec![Spread::default(); w * h];
        for y in 0..h {
            for x in 0..w {
                let biased = x >= w / 2;
                // Noisy per-pixel estimates whose mean is 0 (left) or large (right).
                let noise = if (x + y) % 2 == 0 { 0.05 } else { -0.05 };
                let bias2 = if biased { 1.0 + noise } else { noise };
                let room = if x == 6 && y == 6 { 2.0 } else { WIDEST2 };
                spreads[y * w + x] = Spread {
                    bias2,
                    var: 1.0,
                    camera: 0.0,
                    room,
                    measured: !(x == 3 && y == 3),
                    fixed2: 0.0,
                    fixed_var: 0.0,
                };
            }
        }
        let u = widenings(&spreads, w, &Model::new(0.7, Passes::pilot())).u;
        // Widened nearly fully (what it costs the other pixels' passes holds it back a little).
        assert!(u[5 * w + 5] > 0.9 * WIDEST2, "flat region: {}", u[5 * w + 5]);
        assert_eq!(u[5 * w + w - 5], 1.0, "biased region");
        assert_eq!(u[3 * w + 3], 1.0, "unmeasured pixel");
        assert_eq!(u[6 * w + 6], 2.0, "a wall within the widest disc");
        // Along a row: wide while the window holds flat pixels only, none once it is past the
        // border into the biased half.
        let row: Vec<f32> = (0..w).map(|x| u[16 * w + x]).collect();
        assert!(row[..w / 2 - WINDOW].iter().all(|&u| u > 0.9 * WIDEST2), "{row:?}");
        assert!(row[w / 2..].iter().all(|&u| u == 1.0), "{row:?}");
    }
}
