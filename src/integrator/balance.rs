//! How many camera samples a pass of pass-indexed progressive photon mapping takes.
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
//! rendered apart still agree. The bias is left out: fewer passes shrink the radius less (the
//! bias falls as `n^(α-1)`, 1.2 times higher at a quarter of the passes), which the widening's
//! model weighs where the light is flat.

/// What a pass does, counted by the pilot.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(super) struct PassWork {
    /// Photon rays traced (every segment of every photon path).
    pub photon_rays: u64,
    /// Photons stored in the pass's maps.
    pub stored: u64,
    /// Pixels with a visible point (each gathers once a pass).
    pub points: u64,
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

/// The most camera samples a pass takes (two-pass photon mapping's default).
pub(super) const MOST: u32 = 64;

/// The fewest: pppm's default. Where the pixels hold no random noise (a sun's patch through a
/// window, a black sky) the balance alone would take one, but the positions in the pixel need
/// samples too, however fast their sequence converges: at one a pass the sun-through-a-window
/// room's 20 s error rose from 0.00072 (4) to 0.00080.
pub(super) const LEAST: u32 = 4;

impl PassWork {
    /// The fixed price of a pass and the price of one camera sample over the image, in camera
    /// rays.
    pub(super) fn prices(&self) -> (f64, f64) {
        let fixed = PHOTON_RAY * self.photon_rays as f64
            + STORED * self.stored as f64
            + PROBE_RAY * self.probe_rays as f64
            + POINT * self.points as f64;
        (fixed, self.sample_rays.max(1.0))
    }
}

/// The camera samples a pass takes, in `LEAST..=MOST`, for the least variance in a given time:
/// `camera` the image's mean variance of one camera sample, `photons` the image's mean
/// variance of one pass's photon term (both summed over the channels).
pub(super) fn samples(camera: f64, photons: f64, work: &PassWork) -> u32 {
    let (fixed, per_sample) = work.prices();
    let cost = |s: u32| (camera / s as f64 + photons) * (fixed + s as f64 * per_sample);
    if !(camera > 0.0 && camera.is_finite() && photons.is_finite() && photons >= 0.0) {
        // No random noise in the camera samples to spread over more of them (or nothing
        // measured): the fewest.
        return LEAST;
    }
    (LEAST..=MOST).min_by(|&a, &b| cost(a).total_cmp(&cost(b))).unwrap_or(LEAST)
}

#[cfg(test)]
mod tests {
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
        let (f, s) = w.prices();
        assert!((f / s - 17.5).abs() < 0.01, "{}", f / s);
        for (c, v) in [(1.0, 1.0), (10.0, 1.0), (0.1, 1.0), (3.0, 0.2), (1000.0, 0.01)] {
            let best = (c * f / (v * s)).sqrt().clamp(LEAST as f64, MOST as f64);
            let got = samples(c, v, &w) as f64;
            assert!((got - best).abs() <= 1.0, "C {c} V {v}: {got} against {best}");
        }
        assert_eq!(samples(0.1, 1.0, &w), LEAST);
        assert_eq!(samples(1000.0, 0.01, &w), MOST);
        // No photon noise: as many as allowed; no camera noise: the fewest.
        assert_eq!(samples(1.0, 0.0, &w), MOST);
        assert_eq!(samples(0.0, 1.0, &w), LEAST);
        assert_eq!(samples(f64::NAN, 1.0, &w), LEAST);
        // A pass whose photons cost nothing takes the fewest: passes are then free to add.
        assert_eq!(samples(1.0, 1.0, &work(0, 100_000.0)), LEAST);
    }

    /// The prices weigh each kind of work by its constant.
    #[test]
    fn prices_count_every_kind_of_work() {
        let w = PassWork { photon_rays: 100, stored: 10, points: 4, probe_rays: 8, sample_rays: 0.0 };
        let (fixed, sample) = w.prices();
        let want = 100.0 * PHOTON_RAY + 10.0 * STORED + 8.0 * PROBE_RAY + 4.0 * POINT;
        assert!((fixed - want).abs() < 1e-9);
        assert_eq!(sample, 1.0);
    }
}
