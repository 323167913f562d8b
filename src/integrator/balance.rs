//! How many photons and camera samples a pass of pass-indexed progressive photon mapping
//! takes, and each pixel's radius with them: the pilot's plan (`plan`).
//!
//! A pass pays a fixed price for its photon term (tracing the photons, building their tree,
//! one visible point per pixel, its gather and the probes of its footprint) and a price per
//! camera sample (emission and direct light: camera, mirror and shadow rays). Its image's
//! variance is likewise the camera samples' `C / s` (`C` the variance of one sample, `s`
//! samples) plus the photon term's `V`, which more samples do not reduce. A time `T` allows
//! `T / (F + s S)` passes (`F` the fixed price, `S` the price of one sample over the image),
//! so the image's variance after it is
//!
//! ```text
//! (C / s + V) (F + s S) / T,   least at   s = √(C F / (V S))
//! ```
//!
//! where the camera samples' noise is large (an area light seen over a scanned mesh) more of
//! them per pass pay; where the photons' is (a sun through a window), fewer. With 4 samples a
//! pass everywhere, the fixed price was 10 to 25 samples' worth on the hard scenes, and 8 or 16
//! samples a pass brought the error of a 20 s render down 12–14 % on the scanned bunny and the
//! far-away box (`photonmap render S.toml --integrator pppm --time 20 --spp 16`).
//!
//! The photons of a pass, `m` times the pilot's (`m` in `PHOTONS`), change three things: a
//! disc of the same radius holds `m` times the photons (`V / m`), so the pass's other work
//! (samples, visible points, probes) is spread over more of them; the radii that stay a pass's
//! own `k`-th nearest photon's (the caustics everywhere, and every map where the pilot could not
//! measure the light about a pixel: near walls and edges) shrink `m` times in area, and their
//! bias with them; and fewer, longer passes fit in the time, so the radii shrink less over the
//! render. The caustics' variance does not fall with them: their discs hold `k` photons
//! whatever `m` (counted, it kept the caustics scene at 1; uncounted, it took 4 and its error
//! rose 10 %).
//! For each `m` the plan balances the samples against the photons' noise and widens the radii
//! for the bias against the noise ([`super::bandwidth`]), and keeps the `m` whose image the
//! model predicts best in a reference time (64 of the pilot's passes). The bias that only more
//! photons reduce comes from the pilot's own bias probe at the first radius,
//! `2 (L_r − L_{r/√2})` over the photons within it, less its variance, pooled over a window
//! about each pixel as the widening's is.
//!
//! The pilot measures `C` and `V` at every pixel (`C` from each camera ray followed twice,
//! `sppm::camera_noise`: only what is random after the camera ray counts, the lights'
//! sampling and glass's choices, since where in the pixel the rays start follows one
//! low-discrepancy sequence over all the passes and its error falls far faster than `1 / N` —
//! counting it, a sun's patch with sharp edges drew 19 samples a pass and the error rose; `V`
//! from the photons within its first radius, `Σ (β Φ)² / (π r²)²`, scaled by the mean over the
//! passes of `r²_1 / r²_i` and the widening, [`super::bandwidth`]), and the prices as counts of what
//! a pass does (rays of each kind, photons stored, pixels gathered), weighed in the time of one
//! camera or shadow ray by constants measured on the hard scenes. Counts, not clocks: the
//! choice, like everything else in a pass, depends on the render's seed only, so that passes
//! rendered apart still agree.

use super::bandwidth::{widenings, Model, Passes, Spread};

/// What a pass does, counted by the pilot.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(super) struct PassWork {
    /// Photon rays traced (every segment of every photon path).
    pub photon_rays: u64,
    /// Photons stored in the pass's maps.
    pub stored: u64,
    /// Pixels with a visible point (each gathers once a pass).
    pub points: u64,
    /// The photons the indirect gathers hold at the `k`-th nearest photon (`k` a point).
    pub gathered: u64,
    /// Probe rays a pass casts for its footprints (where the pilot's own disc was not whole).
    pub probe_rays: u64,
    /// Camera, mirror and shadow rays of one camera sample at every pixel.
    pub sample_rays: f64,
}

/// A photon ray's time in camera rays': it scatters and stores where a camera ray only shades
/// (about 160 ns against 95 ns on this machine, on the hard scenes, from `--stats`).
const PHOTON_RAY: f64 = 1.75;
/// A stored photon's part of building the tree (about 110 ns).
const STORED: f64 = 1.2;
/// A probe ray (about 165 ns: it is cast and its hit classified).
const PROBE_RAY: f64 = 1.75;
/// A pixel's visible point, its gather and its bias probe, besides the probes (about 0.7 µs).
const POINT: f64 = 7.5;
/// A pass's indirect gathers, per photon of their `k`, over the passes' shrinking discs (which
/// hold 0.41 `k` on average over 64 passes): about 9 ns. Measured on the white furnace with
/// `--integrator pppm --passes 8 --stats` at `--gather-photons` 30 and 120: the camera stage
/// took 0.66 s longer for 8 × 65,536 × 90 more photons of `k` (14 ns each at the 8 passes' mean
/// disc, 0.65 `k`).
const GATHERED: f64 = 0.09;

/// The most camera samples a pass takes (two-pass photon mapping's default).
pub(super) const MOST: u32 = 64;

/// The fewest: pppm's default. Where the pixels hold no random noise (a sun's patch through a
/// window, a black sky) the balance alone would take one, but the positions in the pixel need
/// samples too, however fast their sequence converges: at one a pass the sun-through-a-window
/// room's 20 s error rose from 0.00072 (4) to 0.00080.
pub(super) const LEAST: u32 = 4;

/// The photons a pass may trace, over the pilot's (`--photons` and `--caustic-photons`).
pub(super) const PHOTONS: [u32; 4] = [1, 2, 4, 8];

impl PassWork {
    /// The fixed price of a pass tracing `photons` times the pilot's photons (its gathers at
    /// the `k`-th nearest photon) and the price of one camera sample over the image, in camera
    /// rays.
    pub(super) fn prices(&self, photons: f64) -> (f64, f64) {
        let fixed = photons * (PHOTON_RAY * self.photon_rays as f64 + STORED * self.stored as f64)
            + PROBE_RAY * self.probe_rays as f64
            + POINT * self.points as f64;
        (fixed, self.sample_rays.max(1.0))
    }

    /// The price of a pass's indirect gathers at the `k`-th nearest photon, in camera rays.
    fn gathers(&self) -> f64 {
        GATHERED * self.gathered as f64
    }
}

/// The camera samples a pass takes, in `LEAST..=MOST`, for the least variance in a given time:
/// `camera` the image's mean variance of one camera sample, `photons` the image's mean
/// variance of one pass's photon term (both summed over the channels), `fixed` and
/// `per_sample` a pass's prices ([`PassWork::prices`]).
pub(super) fn samples(camera: f64, photons: f64, fixed: f64, per_sample: f64) -> u32 {
    let cost = |s: u32| (camera / s as f64 + photons) * (fixed + s as f64 * per_sample);
    if !(camera > 0.0 && camera.is_finite() && photons.is_finite() && photons >= 0.0) {
        // No random noise in the camera samples to spread over more of them (or nothing
        // measured): the fewest.
        return LEAST;
    }
    (LEAST..=MOST).min_by(|&a, &b| cost(a).total_cmp(&cost(b))).unwrap_or(LEAST)
}

/// What the pilot may choose: the camera samples (no `--spp` given), the photons (no
/// `--photons` or `--caustic-photons` given).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Choose {
    pub samples: bool,
    pub photons: bool,
}

/// What every pass does, as the pilot chose it.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Plan {
    /// Camera samples a pixel.
    pub spp: u32,
    /// Photons traced over the pilot's.
    pub photons: u32,
    /// Each pixel's squared first radius over the pilot's `k`-th nearest photon's.
    pub widening: Vec<f32>,
    /// The camera samples' share of a pass's variance.
    pub camera_share: f64,
    /// The price of a pass's photon term in camera samples over the image.
    pub fixed_in_samples: f64,
}

/// The photons and camera samples of a pass and each pixel's widening, for the least squared
/// error in a fixed time, from the pilot's `spreads` (their `camera` the variance of a pass of
/// `spp` samples), the work of a pilot pass and what may be chosen. For each multiple `m` of
/// the photons in [`PHOTONS`], the samples balance the photons' noise ([`samples`], given the
/// widenings) and the widenings the bias and noise ([`widenings`], given the samples); the
/// multiple whose image the model predicts best wins (see the module's notes).
pub(super) fn plan(
    spreads: &[Spread],
    width: usize,
    alpha: f32,
    work: &PassWork,
    spp: u32,
    choose: Choose,
) -> Plan {
    let pixels = spreads.len().max(1) as f64;
    let (pilot_fixed, per_sample) = work.prices(1.0);
    let reference = pilot_fixed + spp as f64 * per_sample;
    let at = |m: f64, s: u32| {
        let (fixed, _) = work.prices(m);
        let time = fixed + s as f64 * per_sample;
        let model = Model::new(alpha, Passes::new(time / reference, m, work.gathers() / time));
        let scale = spp as f64 / s as f64;
        let spreads: Vec<Spread> =
            spreads.iter().map(|p| Spread { camera: p.camera * scale, ..*p }).collect();
        (model, widenings(&spreads, width, &model))
    };
    // The image's mean variance of one camera sample and of one pass's photon term.
    let camera = spreads.iter().map(|p| p.camera * spp as f64).sum::<f64>() / pixels;
    let photon_term = |model: &Model, u: &[f32]| {
        spreads.iter().zip(u).map(|(p, &u)| model.photon_var(p, u)).sum::<f64>() / pixels
    };
    let multiple = |m: u32| {
        let mf = m as f64;
        let (mut s, (mut model, mut widened)) = (spp, at(mf, spp));
        let (fixed, _) = work.prices(mf);
        if choose.samples {
            let chosen = samples(camera, photon_term(&model, &widened.u), fixed, per_sample);
            if chosen != s {
                s = chosen;
                (model, widened) = at(mf, s);
            }
        }
        let per_pass = camera / s as f64 + photon_term(&model, &widened.u);
        let plan = Plan {
            spp: s,
            photons: m,
            camera_share: if per_pass > 0.0 { camera / s as f64 / per_pass } else { 0.0 },
            fixed_in_samples: fixed / per_sample,
            widening: widened.u,
        };
        (widened.mse, plan)
    };
    let multiples: &[u32] = if choose.photons { &PHOTONS } else { &[1] };
    let mut plans = multiples.iter().map(|&m| multiple(m));
    let first = plans.next().unwrap_or_else(|| multiple(1));
    plans.fold(first, |best, next| if next.0 < best.0 { next } else { best }).1
}

#[cfg(test)]
mod tests {
    use super::super::bandwidth::WIDEST2;
    use super::*;

    /// A pass whose fixed price is `fixed_rays` camera rays (all of it probes).
    fn work(fixed_rays: u64, sample_rays: f64) -> PassWork {
        let probe_rays = (fixed_rays as f64 / PROBE_RAY).round() as u64;
        PassWork { probe_rays, sample_rays, ..Default::default() }
    }

    /// The choice is the least of `(C/s + V)(F + sS)`: `√(C F / (V S))` where that lies
    /// within `LEAST..=MOST`, the bound otherwise.
    #[test]
    fn samples_balance_camera_noise_against_the_fixed_price() {
        let w = work(1_750_000, 100_000.0);
        let (f, s) = w.prices(1.0);
        assert!((f / s - 17.5).abs() < 0.01, "{}", f / s);
        let samples = |c: f64, v: f64| samples(c, v, f, s);
        for (c, v) in [(1.0, 1.0), (10.0, 1.0), (0.1, 1.0), (3.0, 0.2), (1000.0, 0.01)] {
            let best = (c * f / (v * s)).sqrt().clamp(LEAST as f64, MOST as f64);
            let got = samples(c, v) as f64;
            assert!((got - best).abs() <= 1.0, "C {c} V {v}: {got} against {best}");
        }
        assert_eq!(samples(0.1, 1.0), LEAST);
        assert_eq!(samples(1000.0, 0.01), MOST);
        // No photon noise: as many as allowed; no camera noise: the fewest.
        assert_eq!(samples(1.0, 0.0), MOST);
        assert_eq!(samples(0.0, 1.0), LEAST);
        assert_eq!(samples(f64::NAN, 1.0), LEAST);
        // A pass whose photons cost nothing takes the fewest: passes are then free to add.
        let (f, s) = work(0, 100_000.0).prices(1.0);
        assert_eq!(super::samples(1.0, 1.0, f, s), LEAST);
    }

    /// The prices weigh each kind of work by its constant; `m` times the photons multiply
    /// the photons' part only.
    #[test]
    fn prices_count_every_kind_of_work() {
        let w = PassWork {
            photon_rays: 100,
            stored: 10,
            points: 4,
            gathered: 120,
            probe_rays: 8,
            sample_rays: 0.0,
        };
        let photons = 100.0 * PHOTON_RAY + 10.0 * STORED;
        let rest = 8.0 * PROBE_RAY + 4.0 * POINT;
        for m in [1.0, 4.0] {
            let (fixed, sample) = w.prices(m);
            assert!((fixed - (m * photons + rest)).abs() < 1e-9);
            assert_eq!(sample, 1.0);
        }
        assert!((w.gathers() - 120.0 * GATHERED).abs() < 1e-12);
    }

    /// A `w × h` pilot's spreads: every pixel measured, with the squared bias `bias2` at the
    /// first radius (which more passes shrink), photon noise 1, camera noise `camera`, and the
    /// caustics' squared bias `fixed2` and variance `fixed_var` (which a pass's own `k`-th
    /// nearest photon sets).
    fn pilot(bias2: f64, camera: f64, fixed2: f64, fixed_var: f64) -> Vec<Spread> {
        let spread = Spread { bias2, var: 1.0, camera, room: WIDEST2, measured: true, fixed2, fixed_var };
        vec![spread; 32 * 16]
    }

    /// The plan takes more photons a pass where a pass's own `k`-th nearest photon biases the
    /// image (caustics) or where the pass's other work is dear (many camera samples' worth of
    /// rays), and the pilot's where photons are the dear part and more passes shrink a bias, or
    /// where the caustics' noise, which more photons do not reduce, is most of the image's; it
    /// keeps what was asked for.
    #[test]
    fn the_plan_takes_more_photons_where_they_pay() {
        let both = Choose { samples: true, photons: true };
        let plan_of =
            |spreads: &[Spread], work: &PassWork, choose: Choose| plan(spreads, 32, 0.7, work, 4, choose);
        // Photons are nearly all of a pass's price.
        let photon_bound =
            PassWork { photon_rays: 1_000_000, points: 512, sample_rays: 1000.0, ..Default::default() };
        let plan = plan_of(&pilot(1.0, 1e-3, 0.0, 0.0), &photon_bound, both);
        assert_eq!(plan.photons, 1, "{plan:?}");
        // The same with a caustic's bias that a pass's own k-th nearest photon sets.
        let plan = plan_of(&pilot(1.0, 1e-3, 50.0, 0.0), &photon_bound, both);
        assert!(plan.photons > 1, "{plan:?}");
        // Camera samples are the dear part: more photons spread it...
        let sample_bound =
            PassWork { photon_rays: 10_000, points: 512, sample_rays: 100_000.0, ..Default::default() };
        let plan = plan_of(&pilot(0.0, 1e-3, 0.0, 0.0), &sample_bound, both);
        assert!(plan.photons > 1, "{plan:?}");
        // ... unless the caustics' noise, the same at any photons a pass, is the image's.
        let plan = plan_of(&pilot(0.0, 1e-3, 0.0, 100.0), &sample_bound, both);
        assert_eq!(plan.photons, 1, "{plan:?}");
        // Asked for: kept.
        let plan =
            plan_of(&pilot(1.0, 1e-3, 50.0, 0.0), &photon_bound, Choose { samples: false, photons: false });
        assert_eq!((plan.photons, plan.spp), (1, 4));
        // Every pixel measured widens within [1, WIDEST2] whatever the photons.
        let plan = plan_of(&pilot(0.0, 1e-3, 50.0, 0.0), &photon_bound, both);
        assert!(plan.photons > 1 && plan.widening.iter().all(|&u| (1.0..=WIDEST2).contains(&u)), "{plan:?}");
    }
}
