//! The sums of a render's passes, kept exactly so that passes rendered anywhere and added in any
//! order give the same image bit for bit, and the error estimate read from them.
//!
//! Each pass's value `x` (an `f32` per pixel and channel) enters as the integer nearest to
//! `x · 2⁶⁰` (an `i128`): integer addition is associative, so the sum of a set of passes does
//! not depend on how they were grouped or ordered, and the image, `sum / passes`, is the same
//! however a render was split. The resolution, 2⁻⁶⁰ ≈ 8.7e-19, is far below an `f32`'s for any
//! radiance above 1e-12; a sum saturates at ±2⁶⁷ ≈ 1.5e20.
//!
//! Per pixel it keeps, over the passes: the sum of each channel, the same over the first half
//! of the render's passes, and for the photon estimate's bias the sum of each channel's bias
//! probe `d` and of its squares ([`Bias`]). [`PassSums::estimate`] turns them into the
//! estimated error of the image: the variance of the mean (two batch means: the first half of
//! the passes against the second) and the square of the estimated bias, less the variance of
//! that estimate.

use super::Film;
use glam::Vec3;
use serde::Serialize;

/// `2^60`: the fixed-point scale of every sum.
pub const SCALE: f64 = (1u64 << 60) as f64;

/// `x` in fixed point (saturating; NaN counts as 0).
#[inline]
pub fn fixed(x: f64) -> i128 {
    (x * SCALE).round() as i128
}

/// A fixed-point value back as a float.
#[inline]
pub fn float(v: i128) -> f64 {
    v as f64 / SCALE
}

/// What a render knows of the bias of its passes' photon estimate.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Bias {
    /// None: the estimator is unbiased (the path tracer).
    Zero,
    /// Each pass gives a probe of its bias per pixel (pass-indexed progressive photon mapping:
    /// twice the difference between the estimate over the gather disc and over the disc of
    /// half its area, the bias of a disc being proportional to its area for smooth light).
    Probed,
    /// Not estimated (two-pass photon mapping's fixed gathers, whose passes all share one bias;
    /// stochastic progressive photon mapping, whose passes are not independent).
    Unknown,
}

impl Bias {
    pub fn name(self) -> &'static str {
        match self {
            Bias::Zero => "zero",
            Bias::Probed => "probed",
            Bias::Unknown => "unknown",
        }
    }

    pub fn from_name(name: &str) -> Option<Self> {
        [Bias::Zero, Bias::Probed, Bias::Unknown].into_iter().find(|b| b.name() == name)
    }
}

/// The exact sums of a set of passes of a `width × height` image.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PassSums {
    pub width: usize,
    pub height: usize,
    /// Passes summed.
    pub passes: u32,
    /// Of them, those in the first batch (`FIRST` sums): the passes before the render's half
    /// way ([`PassSums::half`]).
    pub first_passes: u32,
    pub bias: Bias,
    /// Per pixel: the sums of R, G, B over every pass; over the first batch's; of the bias
    /// probe's R, G, B; and of its squares, `dR² + dG² + dB²` ([`WORDS`] values a pixel).
    pub values: Vec<[i128; WORDS]>,
}

/// Sums a pixel keeps.
pub const WORDS: usize = 10;
/// Their names, in order (the channels of a partial film).
pub const WORD_NAMES: [&str; WORDS] =
    ["sum.R", "sum.G", "sum.B", "first.R", "first.G", "first.B", "bias.R", "bias.G", "bias.B", "biassq"];
const FIRST: usize = 3;
const PROBE: usize = 6;
const PROBE_SQUARES: usize = 9;

impl PassSums {
    /// No passes yet.
    pub fn new(width: usize, height: usize, bias: Bias) -> Self {
        PassSums { width, height, passes: 0, first_passes: 0, bias, values: vec![[0; WORDS]; width * height] }
    }

    /// The passes of a render of `total` passes that make its first batch: those before
    /// `total / 2` (the error estimate compares the two halves).
    pub fn half(total: u32) -> u32 {
        total / 2
    }

    /// Adds one pass: its image and, if the render probes its bias, the probe; `first`: the
    /// pass belongs to the first batch.
    ///
    /// # Panics
    /// If the sizes differ.
    pub fn add_pass(&mut self, film: &Film, probe: Option<&Film>, first: bool) {
        assert_eq!((film.width, film.height), (self.width, self.height), "pass size");
        for (i, v) in self.values.iter_mut().enumerate() {
            let x = film.pixels[i].as_dvec3();
            let d = probe.map_or(Vec3::ZERO, |p| p.pixels[i]).as_dvec3();
            for c in 0..3 {
                let q = fixed(x[c]);
                v[c] = v[c].saturating_add(q);
                if first {
                    v[FIRST + c] = v[FIRST + c].saturating_add(q);
                }
                v[PROBE + c] = v[PROBE + c].saturating_add(fixed(d[c]));
            }
            v[PROBE_SQUARES] = v[PROBE_SQUARES].saturating_add(fixed(d.length_squared()));
        }
        self.passes += 1;
        self.first_passes += first as u32;
    }

    /// The sums of every pass so far, as the first batch will want them (the three colour
    /// sums of each pixel): a render whose length is not known in advance keeps these at
    /// chosen passes and names one the first batch at the end ([`PassSums::set_first`]).
    pub fn snapshot(&self) -> Vec<[i128; 3]> {
        self.values.iter().map(|v| [v[0], v[1], v[2]]).collect()
    }

    /// Makes the `passes` passes of `snapshot` (the first passes of these) the first batch.
    pub fn set_first(&mut self, snapshot: &[[i128; 3]], passes: u32) {
        for (v, s) in self.values.iter_mut().zip(snapshot) {
            v[FIRST..FIRST + 3].copy_from_slice(s);
        }
        self.first_passes = passes;
    }

    /// Adds the sums of other passes (of the same image).
    ///
    /// # Panics
    /// If the sizes differ.
    pub fn add(&mut self, other: &PassSums) {
        assert_eq!((other.width, other.height), (self.width, self.height), "sums size");
        for (v, o) in self.values.iter_mut().zip(&other.values) {
            for k in 0..WORDS {
                v[k] = v[k].saturating_add(o[k]);
            }
        }
        self.passes += other.passes;
        self.first_passes += other.first_passes;
    }

    /// The mean image of the passes (black before the first).
    pub fn mean(&self) -> Film {
        let n = self.passes.max(1) as f64;
        let pixels = self
            .values
            .iter()
            .map(|v| Vec3::new((float(v[0]) / n) as f32, (float(v[1]) / n) as f32, (float(v[2]) / n) as f32))
            .collect();
        Film { width: self.width, height: self.height, pixels }
    }

    /// Per pixel, the estimated mean squared error over its three channels: the variance of
    /// the mean of the passes and the squared bias, each estimated (`None` unless both
    /// batches hold a pass).
    ///
    /// The variance comes from two batch means, the first batch's `m` passes against the other
    /// `n - m`: for independent passes `E[(Ā - B̄)²] = σ² (1/m + 1/(n-m))` and the mean's
    /// variance is `σ²/n`, so `(Ā - B̄)² m (n-m) / n²` estimates it. Batches of consecutive
    /// passes (not the passes one by one) because the camera samples continue one
    /// low-discrepancy sequence over the passes: where a pixel's value depends on where in the
    /// pixel a sample falls (an edge), the passes are not independent and their spread (a
    /// batch a pass) says a far larger error than the image has (2.5 times on the Cornell box
    /// at 64×64), while each half of the sequence is itself well spread and the difference of
    /// the halves stays of the order of the image's error.
    fn pixel_errors(&self) -> Option<impl Iterator<Item = PixelError> + '_> {
        let (n, m) = (self.passes as f64, self.first_passes as f64);
        if self.first_passes == 0 || self.first_passes >= self.passes {
            return None;
        }
        let factor = m * (n - m) / (n * n);
        let bias = self.bias;
        Some(self.values.iter().map(move |v| {
            let mean = Vec3::new(float(v[0]) as f32, float(v[1]) as f32, float(v[2]) as f32) / n as f32;
            let variance: f64 = (0..3)
                .map(|c| {
                    let first = float(v[FIRST + c]);
                    let d = first / m - (float(v[c]) - first) / (n - m);
                    d * d * factor
                })
                .sum();
            let bias2 = match bias {
                Bias::Probed => {
                    let sum_sq: f64 = (0..3).map(|c| float(v[PROBE + c]).powi(2)).sum();
                    let probe_variance = ((float(v[PROBE_SQUARES]) - sum_sq / n) / (n - 1.0)).max(0.0) / n;
                    sum_sq / (n * n) - probe_variance
                }
                Bias::Zero | Bias::Unknown => 0.0,
            };
            PixelError { mean, variance, bias2 }
        }))
    }

    /// The estimated error of the mean image (`None` unless both batches hold a pass: one
    /// pass says nothing of its own variance).
    pub fn estimate(&self) -> Option<ErrorEstimate> {
        let pixels = (self.width * self.height).max(1) as f64;
        let (mut variance, mut bias2, mut mean, mut rel) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
        for p in self.pixel_errors()? {
            variance += p.variance;
            bias2 += p.bias2;
            mean += (p.mean.x + p.mean.y + p.mean.z) as f64;
            // The relative MSE of scenes/SCENES.md, channel by channel, with the pixel's
            // error shared evenly among its channels.
            let share = (p.variance + p.bias2) / 3.0;
            rel += (0..3).map(|c| share / ((p.mean[c] as f64).powi(2) + 0.01)).sum::<f64>();
        }
        let samples = 3.0 * pixels;
        let noise = (variance / samples).sqrt();
        // The squared-bias estimate is unbiased but may come out below 0 where the bias is far
        // below the noise: it counts as none.
        let bias = (bias2 / samples).max(0.0).sqrt();
        let rmse = (noise * noise + bias * bias).sqrt();
        let mean = mean / samples;
        Some(ErrorEstimate {
            passes: self.passes,
            rmse,
            relative_rmse: if mean > 0.0 { rmse / mean } else { 0.0 },
            noise_rmse: noise,
            bias_rmse: bias,
            bias: self.bias,
            rel_mse: (rel / samples).max(0.0),
        })
    }

    /// The estimated error per pixel, as a film whose three channels hold each the pixel's
    /// estimated RMSE over its channels (`None` without an estimate). Each pixel's is read
    /// from its own two batches and its own probe: noisy (a few degrees of freedom), right
    /// on average.
    pub fn error_film(&self) -> Option<Film> {
        let pixels = self
            .pixel_errors()?
            .map(|p| Vec3::splat((((p.variance + p.bias2) / 3.0).max(0.0)).sqrt() as f32));
        Some(Film { width: self.width, height: self.height, pixels: pixels.collect() })
    }
}

struct PixelError {
    mean: Vec3,
    /// The variance of the mean, summed over the channels.
    variance: f64,
    /// The estimated squared bias, summed over the channels (may be below 0).
    bias2: f64,
}

/// How far an image is estimated to be from the converged one, from its passes alone.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ErrorEstimate {
    /// Passes it was estimated from.
    pub passes: u32,
    /// Estimated RMSE over all pixels and channels (as `photonmap compare` measures it against
    /// a reference): `√(noise² + bias²)`.
    pub rmse: f64,
    /// `rmse` over the image's mean.
    pub relative_rmse: f64,
    /// The noise part: the standard deviation of the mean of the passes, from their spread.
    pub noise_rmse: f64,
    /// The bias part (0 when not estimated: see `bias`).
    pub bias_rmse: f64,
    /// What is known of the bias.
    pub bias: Bias,
    /// Estimated relative MSE (the metric of `scenes/SCENES.md`).
    pub rel_mse: f64,
}

impl ErrorEstimate {
    /// `estimated RMSE 0.0123 (1.2 % of the mean; noise 0.0110, bias 0.0055)`.
    pub fn describe(&self) -> String {
        let bias = match self.bias {
            Bias::Zero => "unbiased".to_string(),
            Bias::Probed => format!("bias {:.3e}", self.bias_rmse),
            Bias::Unknown => "bias not estimated".to_string(),
        };
        format!(
            "estimated RMSE {:.3e} ({:.2} % of the mean; noise {:.3e}, {bias}; {} passes)",
            self.rmse,
            100.0 * self.relative_rmse,
            self.noise_rmse,
            self.passes
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn film(values: &[f32]) -> Film {
        Film { width: values.len(), height: 1, pixels: values.iter().map(|&v| Vec3::splat(v)).collect() }
    }

    /// Uniform numbers in [-0.5, 0.5) from a fixed generator.
    fn noise(state: &mut u64) -> f32 {
        *state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (*state >> 40) as f32 / (1u64 << 24) as f32 - 0.5
    }

    #[test]
    fn sums_are_exact_in_any_grouping() {
        // Values whose f32 sums depend on the order.
        let passes: Vec<Film> =
            [1e8f32, 1.0, -1e8, 3.1e-7, 0.1, 7.77e4].iter().map(|&v| film(&[v, v * 0.5])).collect();
        let half = PassSums::half(6);
        let mut one = PassSums::new(2, 1, Bias::Zero);
        for (i, p) in passes.iter().enumerate() {
            one.add_pass(p, None, (i as u32) < half);
        }
        let mut parts = Vec::new();
        for range in [4..6, 0..1, 1..4] {
            let mut s = PassSums::new(2, 1, Bias::Zero);
            range.for_each(|i| s.add_pass(&passes[i], None, (i as u32) < half));
            parts.push(s);
        }
        let mut merged = PassSums::new(2, 1, Bias::Zero);
        for p in parts.iter().rev() {
            merged.add(p);
        }
        assert_eq!(merged, one);
        assert_eq!(merged.mean(), one.mean());
        assert_eq!((one.passes, one.first_passes), (6, 3));
        let expected = (1.0f64 + 3.1e-7f32 as f64 + 0.1f32 as f64 + 7.77e4) / 6.0;
        // No cancellation: the sum is exact (an f32 sum in this order loses the 1).
        assert!((float(one.values[0][0]) / 6.0 - expected).abs() < 1e-12 * expected);
    }

    #[test]
    fn the_noise_estimate_is_the_variance_of_the_mean_of_independent_passes() {
        // 4096 pixels, 10 passes of uniform noise of width 2 about 3: the mean's variance is
        // (4/12)/10 per channel; two batch means estimate it with 3 degrees of freedom a pixel,
        // within a few per cent over the image. Unequal batches too (3 and 7 passes).
        for first in [5u32, 3] {
            let (w, n) = (4096, 10u32);
            let mut s = PassSums::new(w, 1, Bias::Zero);
            let mut rng = 99u64 + first as u64;
            for i in 0..n {
                let pixels = (0..w)
                    .map(|_| {
                        Vec3::new(
                            3.0 + 2.0 * noise(&mut rng),
                            3.0 + 2.0 * noise(&mut rng),
                            3.0 + 2.0 * noise(&mut rng),
                        )
                    })
                    .collect();
                s.add_pass(&Film { width: w, height: 1, pixels }, None, i < first);
            }
            let e = s.estimate().unwrap();
            let expected = (4.0f64 / 12.0 / n as f64).sqrt();
            assert!(
                (e.noise_rmse / expected - 1.0).abs() < 0.05,
                "{first}: {} against {expected}",
                e.noise_rmse
            );
            assert_eq!(e.bias_rmse, 0.0);
            assert!((e.relative_rmse - e.rmse / 3.0).abs() < 0.01 * e.rmse);
            let err = s.error_film().unwrap();
            let mean_sq: f64 = err.pixels.iter().map(|p| (p.x as f64).powi(2)).sum::<f64>() / w as f64;
            assert!((mean_sq.sqrt() / expected - 1.0).abs() < 0.05);
        }
        // A constant image has no noise; one batch alone says nothing.
        let mut c = PassSums::new(1, 1, Bias::Zero);
        for i in 0..4 {
            c.add_pass(&film(&[2.0]), None, i < 2);
        }
        assert_eq!(c.estimate().unwrap().rmse, 0.0);
        let mut one = PassSums::new(1, 1, Bias::Zero);
        one.add_pass(&film(&[2.0]), None, false);
        assert!(one.estimate().is_none());
    }

    #[test]
    fn a_constant_probe_is_the_bias_and_a_noisy_zero_probe_is_none() {
        let mut s = PassSums::new(1, 1, Bias::Probed);
        for i in 0..8 {
            s.add_pass(&film(&[1.0]), Some(&film(&[0.25])), i < 4);
        }
        let e = s.estimate().unwrap();
        assert!((e.bias_rmse - 0.25).abs() < 1e-9, "{e:?}");
        // A probe of mean 0 whose spread is its own noise: its square less its variance is
        // about 0 (clamped at 0 below).
        let mut z = PassSums::new(1024, 1, Bias::Probed);
        let mut rng = 12345u64;
        for i in 0..50 {
            let d: Vec<f32> = (0..1024).map(|_| noise(&mut rng) * 0.2).collect();
            z.add_pass(&film(&[1.0; 1024]), Some(&film(&d)), i < 25);
        }
        let e = z.estimate().unwrap();
        // The probe's noise in the mean: 0.2/√12/√50 ≈ 0.0082; what is left after subtracting
        // its variance is far below it (about 0.2 of it over 1024 pixels).
        assert!(e.bias_rmse < 0.004, "{e:?}");
    }

    #[test]
    fn a_snapshot_names_the_first_batch_afterwards() {
        let mut a = PassSums::new(1, 1, Bias::Zero);
        let mut b = PassSums::new(1, 1, Bias::Zero);
        let mut snap = Vec::new();
        for i in 0..6 {
            let f = film(&[i as f32]);
            a.add_pass(&f, None, i < 4);
            b.add_pass(&f, None, false);
            if i == 3 {
                snap = b.snapshot();
            }
        }
        b.set_first(&snap, 4);
        assert_eq!(a, b);
    }
}
