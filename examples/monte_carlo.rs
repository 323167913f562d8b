//! The lecture's Monte Carlo examples ("Monte Carlo Approach", "Importance Sampling",
//! "Monte Carlo Methods"), reproducibly seeded.
//!
//! ```text
//! cargo run --release --example monte_carlo [-- --seed N]
//! ```
//!
//! Prints (a) π estimates `16 · N_blue / N_total` for N = 100, 10⁴, 10⁶; (b) the lecture's table
//! for `∫₀¹ x² dx` at N = 100 with `p(x) = 1, 2x, 3x²`; (c) the RMS error of the π estimator
//! against N and the fitted log-log slope (≈ −0.5, the `1/√N` law).

use photonmap::tools::montecarlo::{
    estimate_pi, integrate_x2, loglog_slope, rms_error_vs_n, Pdf, X2_INTEGRAL,
};
use rand::SeedableRng;
use rand_pcg::Pcg64;
use std::f64::consts::PI;

const DEFAULT_SEED: u64 = 1;
const RMS_REPS: usize = 100;

fn parse_seed() -> Result<u64, String> {
    let mut args = std::env::args().skip(1);
    let mut seed = DEFAULT_SEED;
    while let Some(arg) = args.next() {
        let value = if arg == "--seed" {
            args.next().ok_or("--seed needs a value")?
        } else if let Some(v) = arg.strip_prefix("--seed=") {
            v.to_owned()
        } else {
            return Err(format!("unknown argument `{arg}`"));
        };
        seed = value.parse().map_err(|e| format!("bad seed `{value}`: {e}"))?;
    }
    Ok(seed)
}

fn main() {
    let seed = parse_seed().unwrap_or_else(|e| {
        eprintln!("error: {e}\nusage: monte_carlo [--seed N]");
        std::process::exit(2);
    });
    println!("Monte Carlo examples from the photon-mapping lecture (seed {seed})\n");

    // (a) Monte Carlo Approach: unit circle inside a square of side 4, π ≈ 16 N_blue / N_total.
    println!("(a) pi ~= 16 * N_blue / N_total  (unit circle in a square of side 4)");
    println!("    {:>9}  {:>10}  {:>10}  {:>12}", "N", "estimate", "error", "sigma(N)");
    let mut rng = Pcg64::seed_from_u64(seed);
    let p_in = PI / 16.0;
    for n in [100usize, 10_000, 1_000_000] {
        let est = estimate_pi(n, &mut rng);
        let sigma = 16.0 * (p_in * (1.0 - p_in) / n as f64).sqrt();
        println!("    {n:>9}  {est:>10.6}  {:>+10.6}  {sigma:>12.6}", est - PI);
    }
    println!("    (sigma(N) = 16 sqrt(p(1-p)/N), p = pi/16: the estimator's standard deviation)\n");

    // (b) Importance Sampling: ∫₀¹ x² dx with N = 100 samples.
    println!("(b) int_0^1 x^2 dx = 1/3 with N = 100, F_N = (1/N) sum f(X_i)/p(X_i)");
    println!(
        "    {:>6}  {:>10}  {:>14}  {:>14}  {:>18}",
        "p(x)", "estimate", "relative error", "expected (1sd)", "lecture's values"
    );
    let lecture = ["0.33671, 1.01%", "0.33368, 0.105%", "0.33333, 0.000%"];
    let mut rng = Pcg64::seed_from_u64(seed.wrapping_add(1));
    for (pdf, lect) in Pdf::ALL.into_iter().zip(lecture) {
        let est = integrate_x2(100, pdf, &mut rng);
        let rel = (est - X2_INTEGRAL).abs() / X2_INTEGRAL;
        let rel_sd = (pdf.x2_variance() / 100.0).sqrt() / X2_INTEGRAL;
        println!(
            "    {:>6}  {est:>10.5}  {:>13.3}%  {:>13.3}%  {lect:>18}",
            pdf.label(),
            rel * 100.0,
            rel_sd * 100.0
        );
    }
    println!("    (expected = relative standard deviation sqrt(Var[f/p]/N)/(1/3); 3x^2 = f/int f:");
    println!("     every sample contributes exactly 1/3, zero variance)\n");

    // (c) Monte Carlo Methods: error decreases like 1/sqrt(N).
    println!("(c) RMS error of the pi estimator over {RMS_REPS} independent runs");
    println!("    {:>9}  {:>12}  {:>14}", "N", "RMS error", "RMS * sqrt(N)");
    let ns = [100usize, 1_000, 10_000, 100_000, 1_000_000];
    let mut rng = Pcg64::seed_from_u64(seed.wrapping_add(2));
    let rms = rms_error_vs_n(&ns, RMS_REPS, PI, &mut rng, estimate_pi);
    for &(n, e) in &rms {
        println!("    {n:>9}  {e:>12.6}  {:>14.4}", e * (n as f64).sqrt());
    }
    println!(
        "    fitted log-log slope: {:.3}  (1/sqrt(N) law: -0.5; RMS * sqrt(N) -> 16 sqrt(p(1-p)) = {:.4})",
        loglog_slope(&rms),
        16.0 * (p_in * (1.0 - p_in)).sqrt()
    );
}
