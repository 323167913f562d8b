//! The sums of a render's passes, kept exactly so that passes rendered anywhere and added in any
//! order give the same image bit for bit, and the error estimate read from them.
//!
//! Each pass's value `x` (an `f32` per pixel and channel) enters as the integer nearest to
//! `x · 2⁶⁰` (an `i128`): integer addition is associative, so the sum of a set of passes does
//! not depend on how they were grouped or ordered, and the image (`sum / passes`, less pppm's
//! bias correction: [`PassSums::mean`]) is the same however a render was split. The
//! resolution, 2⁻⁶⁰ ≈ 8.7e-19, is far below an `f32`'s for any radiance above 1e-12; a sum
//! saturates at ±2⁶⁷ ≈ 1.5e20.
//!
//! Per pixel it keeps, over the passes: the sum of each channel, the same over the first half
//! of the render's passes, and for the photon estimate's bias the sum of each channel's bias
//! probe `d` and of its squares ([`Bias`]). [`PassSums::estimate`] turns them into the
//! estimated error of the image: the variance of the mean (two batch means: the first half of
//! the passes against the second, scaled by how much faster than independent passes the
//! image converges, read from the quarters: see [`PassSums::convergence`]) and the square of
//! the estimated bias, less the variance of that estimate.

use super::windows::Windows;
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
    /// Of them, those in the first quarter and in the third ([`PassSums::quarter`]: the first
    /// half of each batch).
    pub quarter_passes: [u32; 2],
    pub bias: Bias,
    /// Per pixel: the sums of R, G, B over every pass; over the first batch's; of the bias
    /// probe's R, G, B; of its squares, `dR² + dG² + dB²`; and of `R + G + B` over the first
    /// quarter and over the third ([`WORDS`] values a pixel).
    pub values: Vec<[i128; WORDS]>,
}

/// Sums a pixel keeps.
pub const WORDS: usize = 12;
/// Their names, in order (the channels of a partial film).
pub const WORD_NAMES: [&str; WORDS] = [
    "sum.R", "sum.G", "sum.B", "first.R", "first.G", "first.B", "bias.R", "bias.G", "bias.B", "biassq",
    "quarter1", "quarter3",
];
const FIRST: usize = 3;
const PROBE: usize = 6;
const PROBE_SQUARES: usize = 9;
const QUARTERS: [usize; 2] = [10, 11];

/// How many pixels each way the bias probe is averaged over before the image takes half of it
/// off ([`PassSums::correction`]): 33 × 33 pixels. At 256², over 17, 33 and 65 pixels, the means
/// were the same (the atrium's, the column's and the point-lit box's within 0.01 %); the white
/// furnace's RMSE rose 2.6 %, 0.5 % and 0.3 % (its probe is noise alone), the column's fell
/// 1.1 %, 0.5 % and 0.7 %.
const PROBE_WINDOW: usize = 16;

/// A pixel's mean bias probe over `n` passes (per channel) and the variance of that mean
/// (summed over the channels, from the spread of the passes' probes; 0 for one pass).
fn probe_spread(v: &[i128; WORDS], n: f64) -> ([f64; 3], f64) {
    let sum_sq: f64 = (0..3).map(|c| float(v[PROBE + c]).powi(2)).sum();
    let variance =
        if n > 1.0 { ((float(v[PROBE_SQUARES]) - sum_sq / n) / (n - 1.0)).max(0.0) / n } else { 0.0 };
    (std::array::from_fn(|c| float(v[PROBE + c]) / n), variance)
}

/// `R + G + B` of three fixed-point sums (what the quarters keep).
#[inline]
fn total(rgb: &[i128]) -> i128 {
    rgb.iter().fold(0i128, |t, &c| t.saturating_add(c))
}

/// Which quarter of a render's passes a pass is in: 0 and 1 halve the first batch, 2 and 3
/// the second ([`PassSums::quarter`]); `None` while the batches are not known yet (a render
/// whose length is not: [`PassSums::set_batches`] names them at the end).
pub type Quarter = Option<u8>;

impl PassSums {
    /// No passes yet.
    pub fn new(width: usize, height: usize, bias: Bias) -> Self {
        PassSums {
            width,
            height,
            passes: 0,
            first_passes: 0,
            quarter_passes: [0; 2],
            bias,
            values: vec![[0; WORDS]; width * height],
        }
    }

    /// The passes of a render of `total` passes that make its first batch: those before
    /// `total / 2` (the error estimate compares the two halves).
    pub fn half(total: u32) -> u32 {
        total / 2
    }

    /// The quarter of a render of `total` passes that pass `index` is in: each batch halved
    /// ([`PassSums::half`] of each).
    pub fn quarter(index: u32, total: u32) -> u8 {
        let half = Self::half(total);
        if index < half {
            (index >= half / 2) as u8
        } else {
            2 + (index >= half + Self::half(total - half)) as u8
        }
    }

    /// How many of passes `range` of a `total`-pass render are in the first batch, the first
    /// quarter and the third.
    pub fn batch_counts(range: std::ops::Range<u32>, total: u32) -> (u32, [u32; 2]) {
        let count = |q: &[u8]| range.clone().filter(|&i| q.contains(&Self::quarter(i, total))).count() as u32;
        (count(&[0, 1]), [count(&[0]), count(&[2])])
    }

    /// Adds one pass: its image and, if the render probes its bias, the probe, in `quarter`.
    ///
    /// # Panics
    /// If the sizes differ.
    pub fn add_pass(&mut self, film: &Film, probe: Option<&Film>, quarter: Quarter) {
        let first = matches!(quarter, Some(0 | 1));
        let quarter_word = match quarter {
            Some(0) => Some(0),
            Some(2) => Some(1),
            _ => None,
        };
        assert_eq!((film.width, film.height), (self.width, self.height), "pass size");
        for (i, v) in self.values.iter_mut().enumerate() {
            let x = film.pixels[i].as_dvec3();
            let d = probe.map_or(Vec3::ZERO, |p| p.pixels[i]).as_dvec3();
            let q = [fixed(x[0]), fixed(x[1]), fixed(x[2])];
            for c in 0..3 {
                v[c] = v[c].saturating_add(q[c]);
                if first {
                    v[FIRST + c] = v[FIRST + c].saturating_add(q[c]);
                }
                v[PROBE + c] = v[PROBE + c].saturating_add(fixed(d[c]));
            }
            v[PROBE_SQUARES] = v[PROBE_SQUARES].saturating_add(fixed(d.length_squared()));
            if let Some(k) = quarter_word {
                v[QUARTERS[k]] = v[QUARTERS[k]].saturating_add(total(&q));
            }
        }
        self.passes += 1;
        self.first_passes += first as u32;
        if let Some(k) = quarter_word {
            self.quarter_passes[k] += 1;
        }
    }

    /// The sums of every pass so far, as the first batch will want them (the three colour
    /// sums of each pixel): a render whose length is not known in advance keeps these at
    /// chosen passes and names the batches at the end ([`PassSums::set_batches`]).
    pub fn snapshot(&self) -> Vec<[i128; 3]> {
        self.values.iter().map(|v| [v[0], v[1], v[2]]).collect()
    }

    /// What a quarter wants of the passes so far: `R + G + B` of each pixel.
    pub fn total_snapshot(&self) -> Vec<i128> {
        self.values.iter().map(|v| total(&v[..3])).collect()
    }

    /// Names the batches of a render whose passes were added with no quarter: the first `m`
    /// passes (`first`, their [`PassSums::snapshot`]) are the first batch; the first `q1` of
    /// them (`quarter1`, a [`PassSums::total_snapshot`]) its first quarter; and the passes
    /// from `m` to `q3` (`quarter3`, the total snapshot after `q3` passes) the third quarter.
    pub fn set_batches(
        &mut self,
        first: (&[[i128; 3]], u32),
        quarter1: Option<(&[i128], u32)>,
        quarter3: Option<(&[i128], u32)>,
    ) {
        let (m, snapshot) = (first.1, first.0);
        for (i, (v, s)) in self.values.iter_mut().zip(snapshot).enumerate() {
            v[FIRST..FIRST + 3].copy_from_slice(s);
            let first_total = total(s);
            v[QUARTERS[0]] = quarter1.map_or(0, |(q, _)| q[i]);
            v[QUARTERS[1]] = quarter3.map_or(0, |(q, _)| q[i].saturating_sub(first_total));
        }
        self.first_passes = m;
        self.quarter_passes = [quarter1.map_or(0, |q| q.1), quarter3.map_or(0, |q| q.1.saturating_sub(m))];
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
        self.quarter_passes[0] += other.quarter_passes[0];
        self.quarter_passes[1] += other.quarter_passes[1];
    }

    /// The image: the mean of the passes (black before the first), less, where the passes
    /// probe their bias, half their mean probe averaged over a window (`correction`, below).
    pub fn mean(&self) -> Film {
        let n = self.passes.max(1) as f64;
        let correction = self.correction();
        let pixels = self
            .values
            .iter()
            .enumerate()
            .map(|(i, v)| {
                let mean =
                    Vec3::new((float(v[0]) / n) as f32, (float(v[1]) / n) as f32, (float(v[2]) / n) as f32);
                correction.as_ref().map_or(mean, |c| mean - c[i].value)
            })
            .collect();
        Film { width: self.width, height: self.height, pixels }
    }

    /// Where the passes probe their bias ([`Bias::Probed`]), what the image takes off each
    /// pixel, and that correction's variance: half the mean probe over the pixels of a window
    /// about it (`PROBE_WINDOW` each way, cut by the image's border).
    ///
    /// Half a probe, `L_r − L_{r/√2}`, turns the estimate over the disc of radius `r` into the
    /// estimate over the disc of half its area. Its bias is the bias the passes themselves
    /// would reach once their radii had shrunk to `r/√2` (at α = 0.7 about ten times as many
    /// passes): where the bias grows as `r^p`, `2^(−p/2)` of it (0.71 at an edge, `p = 1`;
    /// a half for smooth light, `p = 2`), never turned over, as taking off the whole probe
    /// (exact for `p = 2` only) turns it where the bias grows faster than the area (on our
    /// atrium the whole probe read twice the image's bias and turned +0.34 % into −0.38 %;
    /// half read −0.02 %: docs/accuracy.md). The smaller disc's estimate is the noisier, by
    /// the photons it leaves out; averaged over the window, its difference from the larger
    /// disc's keeps only its low frequencies, where the bias lies, and adds almost no noise. The
    /// correction vanishes with the radius, so the passes converge where they did.
    ///
    /// Where the bias does not shrink with the disc (discs as wide as a surface's own detail:
    /// a fluted column's flutes under discs of 80 000 photons a pass grow darker from `r` to
    /// `r/√2`), the correction moves the image as far along that road as the passes would,
    /// no farther.
    fn correction(&self) -> Option<Vec<Correction>> {
        if self.bias != Bias::Probed || self.passes == 0 {
            return None;
        }
        let (w, h, n) = (self.width, self.height, self.passes as f64);
        // Each pixel's mean probe (R, G, B) and its variance (summed over the channels: the
        // spread of the passes' probes), summed over windows.
        let windows = Windows::new(w, h, |x, y| {
            let (probe, variance) = probe_spread(&self.values[y * w + x], n);
            [probe[0], probe[1], probe[2], variance]
        });
        let mut out = Vec::with_capacity(w * h);
        for y in 0..h {
            for x in 0..w {
                let (sums, count) = windows.around(x, y, PROBE_WINDOW);
                let count = count as f64;
                let mean = |k: usize| sums[k] / count;
                out.push(Correction {
                    value: Vec3::new(mean(0) as f32, mean(1) as f32, mean(2) as f32) * 0.5,
                    // Half of a mean of `count` pixels' probes, taken as independent.
                    variance: 0.25 * mean(3) / count,
                });
            }
        }
        Some(out)
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
        let factor = m * (n - m) / (n * n) * self.convergence();
        let bias = self.bias;
        let correction = self.correction();
        Some(self.values.iter().enumerate().map(move |(i, v)| {
            let taken = correction.as_ref().map_or(Correction::default(), |c| c[i]);
            let mean = Vec3::new(float(v[0]) as f32, float(v[1]) as f32, float(v[2]) as f32) / n as f32
                - taken.value;
            let variance: f64 = (0..3)
                .map(|c| {
                    let first = float(v[FIRST + c]);
                    let d = first / m - (float(v[c]) - first) / (n - m);
                    d * d * factor
                })
                .sum::<f64>()
                + taken.variance;
            let bias2 = match bias {
                // The bias before the image's correction ([`Self::correction`]), the whole
                // probe's: what the correction leaves is not known (a half of it for a bias
                // growing as the area, more or less for others), and an estimate that errs
                // high stops a `--target-error` render late rather than early. Counted as half
                // the probe, the estimate over the true error fell on every scene measured, by
                // up to 0.15 (the fluted column's to 0.63; docs/accuracy.md).
                Bias::Probed => {
                    let (probe, variance) = probe_spread(v, n);
                    probe.iter().map(|p| p * p).sum::<f64>() - variance
                }
                Bias::Zero | Bias::Unknown => 0.0,
            };
            PixelError { mean, variance, bias2 }
        }))
    }

    /// How much less the variance of the mean image is than independent passes would make it:
    /// 1, or less where the passes are anti-correlated.
    ///
    /// The camera samples continue one low-discrepancy sequence over the passes, so where a
    /// pixel's value depends on where in the pixel a sample falls (an edge, a shadow's
    /// penumbra), the second batch fills the gaps the first left and the mean converges
    /// faster than independent passes would: the two batches' difference then overstates the
    /// mean's error (by 1.4 times on the Cornell box). If a prefix of `s` passes has variance
    /// `∝ s^-γ` (γ = 1 independent, up to 2 for a well-stratified sequence), a batch's two
    /// halves differ by `2^(γ-1)` times more, per pass, than the two batches do, and the
    /// variance of the mean is the batches' estimate over `2^γ - 1`. This reads `ρ = 2^(γ-1)`
    /// over the whole image (the spread of the quarters' `R + G + B` against the batches',
    /// each scaled as for independent passes of its size), bounded to γ in [1, 2], and returns
    /// `1 / (2ρ - 1)`. A batch whose quarters differ in size by more than a factor 2 is not
    /// read; with none read (fewer than 4 passes) it is 1.
    ///
    /// The rate is an image-wide model: measured against the true error (scripts/calibrate.sh,
    /// docs/scale-out.md), it takes the Cornell box's estimate from 1.1–1.4 times the true
    /// error to 0.84–0.95, and leaves the scenes whose noise is the photons' or the lights'
    /// (independent from pass to pass) within a few per cent; where pppm's bias drifts over the
    /// passes (its radii shrink), the quarters differ by that drift too and it reads γ high
    /// (the caustics scene: 0.72–1.03 of the true error, against 1.05–1.24 uncorrected).
    pub fn convergence(&self) -> f64 {
        let (n, m) = (self.passes, self.first_passes);
        if m == 0 || m >= n {
            return 1.0;
        }
        // Each batch's two halves, (passes, passes).
        let first = (self.quarter_passes[0], m.saturating_sub(self.quarter_passes[0]));
        let second = (self.quarter_passes[1], (n - m).saturating_sub(self.quarter_passes[1]));
        // A pair is read when its halves are within a factor 2 of each other: the model is of
        // like halves (a render of unknown length has its quarters where snapshots were).
        let balanced = |(a, b): (u32, u32)| a > 0 && b > 0 && 2 * a.min(b) >= a.max(b);
        let read = [balanced(first), balanced(second)];
        let pairs = read.iter().filter(|&&r| r).count() as f64;
        if pairs == 0.0 {
            return 1.0;
        }
        // (X/a - Y/b)² ab/(a+b): σ² of one pass, for independent passes.
        let spread = |x: i128, a: u32, y: i128, b: u32| {
            let (a, b) = (a as f64, b as f64);
            (float(x) / a - float(y) / b).powi(2) * a * b / (a + b)
        };
        let (mut halves, mut quarters) = (0.0f64, 0.0f64);
        for v in &self.values {
            let all = total(&v[..3]);
            let one = total(&v[FIRST..FIRST + 3]);
            let two = all.saturating_sub(one);
            halves += spread(one, m, two, n - m);
            let (q1, q3) = (v[QUARTERS[0]], v[QUARTERS[1]]);
            if read[0] {
                quarters += spread(q1, first.0, one.saturating_sub(q1), first.1) / pairs;
            }
            if read[1] {
                quarters += spread(q3, second.0, two.saturating_sub(q3), second.1) / pairs;
            }
        }
        if halves <= 0.0 {
            return 1.0;
        }
        let rho = (quarters / halves).clamp(1.0, 2.0);
        1.0 / (2.0 * rho - 1.0)
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

/// What [`PassSums::correction`] takes off a pixel, and its variance (summed over the
/// channels).
#[derive(Clone, Copy, Debug, Default)]
struct Correction {
    value: Vec3,
    variance: f64,
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

    /// A pass in the first batch or the second, the batches not halved into quarters.
    fn batch(first: bool) -> Quarter {
        Some(if first { 0 } else { 3 })
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
        let q = |i: usize| Some(PassSums::quarter(i as u32, 6));
        let mut one = PassSums::new(2, 1, Bias::Zero);
        for (i, p) in passes.iter().enumerate() {
            one.add_pass(p, None, q(i));
        }
        let mut parts = Vec::new();
        for range in [4..6, 0..1, 1..4] {
            let mut s = PassSums::new(2, 1, Bias::Zero);
            range.for_each(|i| s.add_pass(&passes[i], None, q(i)));
            parts.push(s);
        }
        let mut merged = PassSums::new(2, 1, Bias::Zero);
        for p in parts.iter().rev() {
            merged.add(p);
        }
        assert_eq!(merged, one);
        assert_eq!(merged.mean(), one.mean());
        assert_eq!((one.passes, one.first_passes, one.quarter_passes), (6, 3, [1, 1]));
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
                s.add_pass(&Film { width: w, height: 1, pixels }, None, batch(i < first));
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
            c.add_pass(&film(&[2.0]), None, batch(i < 2));
        }
        assert_eq!(c.estimate().unwrap().rmse, 0.0);
        let mut one = PassSums::new(1, 1, Bias::Zero);
        one.add_pass(&film(&[2.0]), None, batch(false));
        assert!(one.estimate().is_none());
    }

    #[test]
    fn half_a_constant_probe_is_taken_off_and_the_whole_is_the_bias_estimated() {
        let mut s = PassSums::new(1, 1, Bias::Probed);
        for i in 0..8 {
            s.add_pass(&film(&[1.0]), Some(&film(&[0.25])), batch(i < 4));
        }
        assert_eq!(s.mean().pixels[0], Vec3::splat(0.875));
        let e = s.estimate().unwrap();
        assert!((e.bias_rmse - 0.25).abs() < 1e-9, "{e:?}");
        assert_eq!(s.convergence(), 1.0, "no quarters, no correction");
        // Without a probe nothing is taken off.
        let mut z = PassSums::new(1, 1, Bias::Unknown);
        z.add_pass(&film(&[1.0]), None, batch(true));
        assert_eq!(z.mean().pixels[0], Vec3::ONE);
    }

    #[test]
    fn the_probe_is_averaged_over_its_window_before_half_is_taken_off() {
        // One pixel's probe in a row of 128, away from the ends: each pixel within
        // `PROBE_WINDOW` of it takes off half of it over its window's pixels, the others
        // nothing; the row loses half the probe in all.
        let (w, at) = (128, 64);
        let window = (2 * PROBE_WINDOW + 1) as f32;
        let mut probe = vec![0.0; w];
        probe[at] = 1.7;
        let mut s = PassSums::new(w, 1, Bias::Probed);
        for i in 0..4 {
            s.add_pass(&film(&vec![1.0; w]), Some(&film(&probe)), batch(i < 2));
        }
        let image = s.mean();
        for (x, p) in image.pixels.iter().enumerate() {
            let expect = if x.abs_diff(at) <= PROBE_WINDOW { 1.0 - 0.85 / window } else { 1.0 };
            assert!((p.x - expect).abs() < 1e-6, "pixel {x}: {p}");
        }
        let lost: f32 = image.pixels.iter().map(|p| 1.0 - p.x).sum();
        assert!((lost - 0.85).abs() < 1e-5, "{lost}");
    }

    #[test]
    fn a_noisy_zero_probe_is_no_bias() {
        // A probe of mean 0 whose spread is its own noise: its square less its variance is
        // about 0 (clamped at 0 below).
        let mut z = PassSums::new(1024, 1, Bias::Probed);
        let mut rng = 12345u64;
        for i in 0..50 {
            let d: Vec<f32> = (0..1024).map(|_| noise(&mut rng) * 0.2).collect();
            z.add_pass(&film(&[1.0; 1024]), Some(&film(&d)), batch(i < 25));
        }
        let e = z.estimate().unwrap();
        // The probe's noise in the mean: 0.2/√12/√50 ≈ 0.0082; what is left after subtracting
        // its variance is far below it (about 0.2 of it over 1024 pixels).
        assert!(e.bias_rmse < 0.004, "{e:?}");
        // Averaged over its window and halved, the noisy probe moves the image by far less than
        // its own noise.
        let worst = z.mean().pixels.iter().map(|p| (p.x - 1.0).abs()).fold(0.0, f32::max);
        assert!(worst < 0.004, "{worst}");
    }

    #[test]
    fn a_snapshot_names_the_first_batch_afterwards() {
        let mut a = PassSums::new(1, 1, Bias::Zero);
        let mut b = PassSums::new(1, 1, Bias::Zero);
        let mut snap = Vec::new();
        for i in 0..6 {
            let f = film(&[i as f32]);
            a.add_pass(&f, None, Some(if i < 4 { 1 } else { 3 }));
            b.add_pass(&f, None, None);
            if i == 3 {
                snap = b.snapshot();
            }
        }
        b.set_batches((&snap, 4), None, None);
        assert_eq!(a, b);
    }

    /// `n` passes of `w` pixels, pixel `p`'s pass `i` drawn by `value(p, i)`, in quarters.
    fn passes(w: usize, n: u32, value: impl Fn(usize, u32) -> f32) -> PassSums {
        let mut s = PassSums::new(w, 1, Bias::Zero);
        for i in 0..n {
            let pixels = (0..w).map(|p| Vec3::splat(value(p, i))).collect();
            s.add_pass(&Film { width: w, height: 1, pixels }, None, Some(PassSums::quarter(i, n)));
        }
        s
    }

    #[test]
    fn the_quarters_correct_the_estimate_where_passes_are_anti_correlated() {
        let (w, n) = (4096usize, 16u32);
        // Independent passes: no correction to speak of.
        let mut rng = 7u64;
        let draws: Vec<f32> = (0..w * n as usize).map(|_| noise(&mut rng)).collect();
        let iid = passes(w, n, |p, i| 1.0 + draws[p * n as usize + i as usize]);
        let k = iid.convergence();
        assert!(k > 0.9, "independent passes corrected by {k}");
        let expected = (1.0f64 / 12.0 / n as f64).sqrt();
        let e = iid.estimate().unwrap().noise_rmse;
        assert!((e / expected - 1.0).abs() < 0.08, "{e} against {expected}");
        // A stratified sequence, as the camera's: pixel p's pass i looks at the point
        // frac(φ_p + radical inverse of i) and sees an edge there (1 left of t_p, else 0).
        // Over 16 passes the points are stratified: the mean's error is far below independent
        // sampling's, and the two batches' difference alone overstates it.
        let radical = |mut i: u32| {
            let (mut x, mut f) = (0.0f64, 0.5f64);
            while i > 0 {
                x += f * (i & 1) as f64;
                i >>= 1;
                f *= 0.5;
            }
            x
        };
        let offsets: Vec<f64> = (0..w).map(|_| noise(&mut rng) as f64 + 0.5).collect();
        let edges: Vec<f64> = (0..w).map(|_| noise(&mut rng) as f64 + 0.5).collect();
        let edge = |p: usize, i: u32| ((offsets[p] + radical(i)).fract() < edges[p]) as u8 as f32;
        let strat = passes(w, n, edge);
        let mean = strat.mean();
        let squares = mean.pixels.iter().zip(&edges).map(|(m, t)| (m.x as f64 - t).powi(2));
        let truth = (squares.sum::<f64>() / w as f64).sqrt();
        let k = strat.convergence();
        let corrected = strat.estimate().unwrap().noise_rmse;
        let uncorrected = corrected / k.sqrt();
        assert!(k < 0.6, "stratified passes corrected by only {k}");
        assert!(uncorrected / truth > 1.5, "the batches alone: {uncorrected} against {truth}");
        assert!((0.67..=1.5).contains(&(corrected / truth)), "corrected {corrected} against {truth}");
    }

    #[test]
    fn quarters_split_each_batch() {
        let quarters: Vec<u8> = (0..10).map(|i| PassSums::quarter(i, 10)).collect();
        assert_eq!(quarters, [0, 0, 1, 1, 1, 2, 2, 3, 3, 3]);
        assert_eq!(PassSums::batch_counts(0..10, 10), (5, [2, 2]));
        assert_eq!(PassSums::batch_counts(3..7, 10), (2, [0, 2]));
        // Parts added up count their quarters as one render does.
        let mut whole = PassSums::new(1, 1, Bias::Zero);
        let mut parts = PassSums::new(1, 1, Bias::Zero);
        for range in [0..3, 3..7, 7..10] {
            let mut part = PassSums::new(1, 1, Bias::Zero);
            for i in range {
                let f = film(&[i as f32]);
                whole.add_pass(&f, None, Some(PassSums::quarter(i, 10)));
                part.add_pass(&f, None, Some(PassSums::quarter(i, 10)));
            }
            parts.add(&part);
        }
        assert_eq!(parts, whole);
        // A render that names its batches at the end gives the same sums.
        let mut open = PassSums::new(1, 1, Bias::Zero);
        let (mut first, mut q1, mut q3) = (Vec::new(), Vec::new(), Vec::new());
        for i in 0..10 {
            open.add_pass(&film(&[i as f32]), None, None);
            match open.passes {
                2 => q1 = open.total_snapshot(),
                5 => first = open.snapshot(),
                7 => q3 = open.total_snapshot(),
                _ => {}
            }
        }
        open.set_batches((&first, 5), Some((&q1, 2)), Some((&q3, 7)));
        assert_eq!(open, whole);
    }
}
