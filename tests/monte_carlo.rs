//! Properties of the lecture's Monte Carlo examples (`photonmap::tools::montecarlo`).

use photonmap::tools::montecarlo::{
    estimate_pi, integrate_x2, loglog_slope, rms_error_vs_n, Pdf, X2_INTEGRAL,
};
use rand::SeedableRng;
use rand_pcg::Pcg64;
use std::f64::consts::PI;

fn variance(xs: &[f64]) -> f64 {
    let m = xs.iter().sum::<f64>() / xs.len() as f64;
    xs.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (xs.len() - 1) as f64
}

#[test]
fn quadratic_pdf_is_exact_for_any_n_and_seed() {
    for seed in [0u64, 1, 7, 42, 0xdead_beef] {
        let mut rng = Pcg64::seed_from_u64(seed);
        for n in [1usize, 2, 10, 100, 1_000, 10_000] {
            let est = integrate_x2(n, Pdf::Quadratic, &mut rng);
            let rel = (est - X2_INTEGRAL).abs() / X2_INTEGRAL;
            assert!(rel < 1e-12, "seed {seed}, n {n}: {est} (relative error {rel:e})");
        }
    }
}

#[test]
fn variance_ordering_uniform_linear_quadratic() {
    const REPS: usize = 200;
    const N: usize = 100;
    let mut rng = Pcg64::seed_from_u64(2024);
    let vars: Vec<f64> = Pdf::ALL
        .iter()
        .map(|&pdf| {
            let ests: Vec<f64> = (0..REPS).map(|_| integrate_x2(N, pdf, &mut rng)).collect();
            variance(&ests)
        })
        .collect();
    let (uni, lin, quad) = (vars[0], vars[1], vars[2]);
    // Theory: Var[F_N] = (1/5 - 1/9)/N = 8.9e-4, (1/8 - 1/9)/N = 1.4e-4, 0.
    assert!(uni > lin && lin > quad, "variances uniform {uni:e}, 2x {lin:e}, 3x² {quad:e}");
    assert!(uni > 2.0 * lin, "uniform {uni:e} should clearly exceed 2x {lin:e} (expected ratio 6.4)");
    assert!(quad < 1e-28, "3x² variance {quad:e} should be rounding noise only");
    // And they match theory: the sample variance of 200 runs is within ~10 % (1σ) of Var/N.
    for (pdf, v) in [(Pdf::Uniform, uni), (Pdf::Linear, lin)] {
        let expect = pdf.x2_variance() / N as f64;
        assert!((v / expect - 1.0).abs() < 0.3, "{pdf:?}: {v:e} vs theory {expect:e}");
    }
}

#[test]
fn pi_rms_error_follows_inverse_sqrt_n() {
    let ns = [100usize, 1_000, 10_000, 100_000];
    let mut rng = Pcg64::seed_from_u64(11);
    let rms = rms_error_vs_n(&ns, 64, PI, &mut rng, estimate_pi);
    let slope = loglog_slope(&rms);
    assert!((-0.6..=-0.4).contains(&slope), "slope {slope}, points {rms:?}");
}

#[test]
fn pi_with_a_million_points() {
    // With the lecture's square of side 4, p = π/16 and the estimator's standard deviation at
    // N = 10⁶ is 16·sqrt(p(1−p)/N) ≈ 0.0064, so the 0.01 bound is only ≈ 1.6σ: about one seed in
    // eight misses it by chance (seeds 1, 3 and 6 do). It is checked for one fixed seed; the loop
    // below is the seed-independent check, at 4σ.
    let est = estimate_pi(1_000_000, &mut Pcg64::seed_from_u64(0));
    assert!((est - PI).abs() < 0.01, "estimate {est}");
    for seed in 1..=8u64 {
        let est = estimate_pi(1_000_000, &mut Pcg64::seed_from_u64(seed));
        assert!((est - PI).abs() < 4.0 * 0.0064, "seed {seed}: estimate {est}");
    }
}
