//! The lecture's Monte Carlo examples as small, pure, RNG-agnostic functions.
//!
//! Source: `photon-mapping-lecture.md`, slides "A Simple Example", "Monte Carlo Approach",
//! "Monte Carlo Methods", "Monte Carlo Integration (in 1D)" and "Importance Sampling".
//!
//! * [`estimate_pi`]: throw `N` uniform points into a square of side 4 that contains the unit
//!   circle and count the ones inside: `π ≈ 16 · N_blue / N_total`.
//! * [`integrate_x2`]: the estimator `F_N = (1/N) Σ f(X_i) / p(X_i)` for `∫₀¹ x² dx = 1/3` with
//!   the three densities of the lecture's table (`p(x) = 1`, `2x`, `3x²`), each sampled by
//!   inverting its CDF. With `p(x) = 3x² = f(x) / ∫f` every sample contributes exactly `1/3`, so
//!   the estimate has zero variance ("gives the exact solution with a single sample").
//! * [`rms_error_vs_n`] and [`loglog_slope`]: the "error decreases like `1/√N`" claim, measured as
//!   the root-mean-square error over independent repetitions and the least-squares slope of
//!   `ln(rms)` against `ln(N)` (≈ −0.5).
//!
//! Every function takes the random number generator as an argument, so results are reproducible
//! from a seed and independent of any global state.

use rand::Rng;

/// Estimates π as in the lecture's "Monte Carlo Approach" slide.
///
/// The unit circle (radius 1, centred at the origin) lies inside the square `[-2, 2]²` of side 4.
/// `n` points are drawn uniformly in that square; those with `x² + y² ≤ 1` are the "blue" ones.
/// Since `A_circle / A_box = π / 16`, the estimate is `16 · N_blue / N_total`.
///
/// The square is twice as wide as it needs to be (side 2 would also contain the circle), so only
/// about 20 % of the points land inside and the standard deviation is `≈ 6.36 / √n` rather than
/// the `≈ 1.64 / √n` of the tight square; it is the lecture's construction all the same.
///
/// # Panics
///
/// If `n == 0`.
pub fn estimate_pi(n: usize, rng: &mut impl Rng) -> f64 {
    assert!(n > 0, "estimate_pi needs at least one sample");
    let blue = (0..n)
        .filter(|_| {
            let x = rng.gen_range(-2.0..2.0f64);
            let y = rng.gen_range(-2.0..2.0f64);
            x * x + y * y <= 1.0
        })
        .count();
    16.0 * blue as f64 / n as f64
}

/// A probability density on `[0, 1]` for [`integrate_x2`], as in the lecture's importance
/// sampling table.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Pdf {
    /// `p(x) = 1`; sampled as `x = u`.
    Uniform,
    /// `p(x) = 2x`; CDF `x²`, sampled as `x = √u`.
    Linear,
    /// `p(x) = 3x²`; CDF `x³`, sampled as `x = ∛u`. Proportional to the integrand, so the
    /// estimator has zero variance.
    Quadratic,
}

impl Pdf {
    /// All three densities, in the order of the lecture's table.
    pub const ALL: [Pdf; 3] = [Pdf::Uniform, Pdf::Linear, Pdf::Quadratic];

    /// The density `p(x)` at `x ∈ [0, 1]`.
    pub fn density(self, x: f64) -> f64 {
        match self {
            Pdf::Uniform => 1.0,
            Pdf::Linear => 2.0 * x,
            Pdf::Quadratic => 3.0 * x * x,
        }
    }

    /// Maps a uniform `u ∈ (0, 1]` to a sample distributed by this density (inverse CDF).
    pub fn sample(self, u: f64) -> f64 {
        match self {
            Pdf::Uniform => u,
            Pdf::Linear => u.sqrt(),
            Pdf::Quadratic => u.cbrt(),
        }
    }

    /// Variance of one term `f(X)/p(X)` of the `∫₀¹ x² dx` estimator under this density:
    /// `1/5 − 1/9 = 4/45` (uniform), `1/8 − 1/9 = 1/72` (`2x`), `0` (`3x²`). The estimate
    /// [`integrate_x2`] with `n` samples has variance `x2_variance() / n`.
    pub fn x2_variance(self) -> f64 {
        match self {
            Pdf::Uniform => 4.0 / 45.0,
            Pdf::Linear => 1.0 / 72.0,
            Pdf::Quadratic => 0.0,
        }
    }

    /// The density as the lecture writes it: `1`, `2x` or `3x²`.
    pub fn label(self) -> &'static str {
        match self {
            Pdf::Uniform => "1",
            Pdf::Linear => "2x",
            Pdf::Quadratic => "3x²",
        }
    }
}

/// The exact value of `∫₀¹ x² dx`.
pub const X2_INTEGRAL: f64 = 1.0 / 3.0;

/// Estimates `∫₀¹ x² dx` (= 1/3) with `n` samples drawn from `pdf`, using the lecture's
/// importance-sampling estimator `F_N = (1/N) Σ f(X_i) / p(X_i)` with `f(x) = x²`.
///
/// Uniforms are taken in `(0, 1]` (as `1 − u` for `u ∈ [0, 1)`), so `X_i > 0` and `f/p` is never
/// `0/0`. For [`Pdf::Quadratic`] every term is `x² / (3x²) = 1/3` up to rounding, so the result is
/// `1/3` within a few ulps for every `n` and every seed.
///
/// # Panics
///
/// If `n == 0`.
pub fn integrate_x2(n: usize, pdf: Pdf, rng: &mut impl Rng) -> f64 {
    assert!(n > 0, "integrate_x2 needs at least one sample");
    let sum: f64 = (0..n)
        .map(|_| {
            let u = 1.0 - rng.gen::<f64>(); // (0, 1]
            let x = pdf.sample(u);
            x * x / pdf.density(x)
        })
        .sum();
    sum / n as f64
}

/// Root-mean-square error of an estimator for each sample count in `ns`.
///
/// For every `n` in `ns`, `estimator(n, rng)` is run `reps` times (each run drawing fresh numbers
/// from `rng`, so the repetitions are independent) and `sqrt(mean((estimate − exact)²))` is
/// returned alongside `n`. Feed the result to [`loglog_slope`] to check the `1/√N` law.
///
/// # Panics
///
/// If `reps == 0`.
pub fn rms_error_vs_n<R, E>(
    ns: &[usize],
    reps: usize,
    exact: f64,
    rng: &mut R,
    mut estimator: E,
) -> Vec<(usize, f64)>
where
    R: Rng,
    E: FnMut(usize, &mut R) -> f64,
{
    assert!(reps > 0, "rms_error_vs_n needs at least one repetition");
    ns.iter()
        .map(|&n| {
            let sq: f64 = (0..reps)
                .map(|_| {
                    let e = estimator(n, rng) - exact;
                    e * e
                })
                .sum();
            (n, (sq / reps as f64).sqrt())
        })
        .collect()
}

/// Least-squares slope of `ln(error)` against `ln(n)`; about `−0.5` for a Monte Carlo estimator.
///
/// Returns NaN with fewer than two points, if all `n` are equal, or if an error is not positive.
pub fn loglog_slope(points: &[(usize, f64)]) -> f64 {
    if points.len() < 2 {
        return f64::NAN;
    }
    let xy: Vec<(f64, f64)> = points.iter().map(|&(n, e)| ((n as f64).ln(), e.ln())).collect();
    let m = xy.len() as f64;
    let mx = xy.iter().map(|p| p.0).sum::<f64>() / m;
    let my = xy.iter().map(|p| p.1).sum::<f64>() / m;
    let sxy: f64 = xy.iter().map(|&(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = xy.iter().map(|&(x, _)| (x - mx) * (x - mx)).sum();
    if sxx > 0.0 {
        sxy / sxx
    } else {
        f64::NAN
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slope_of_exact_power_law() {
        let pts: Vec<(usize, f64)> = [10, 100, 1000].iter().map(|&n| (n, 3.0 / (n as f64).sqrt())).collect();
        assert!((loglog_slope(&pts) + 0.5).abs() < 1e-12);
    }

    #[test]
    fn sampling_inverts_the_cdf() {
        // CDF(sample(u)) == u: x, x², x³.
        for u in [0.01, 0.25, 0.5, 0.9, 1.0] {
            assert!((Pdf::Uniform.sample(u) - u).abs() < 1e-15);
            assert!((Pdf::Linear.sample(u).powi(2) - u).abs() < 1e-15);
            assert!((Pdf::Quadratic.sample(u).powi(3) - u).abs() < 1e-15);
        }
    }
}
