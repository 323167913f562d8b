//! Chi-square goodness-of-fit tests of the direction samplers against their own pdfs, after
//! pbrt-v3/v4 (`src/tests/bsdfs.cpp`, `Chi2Test`) and Mitsuba's `ChiSquare`: the sphere is binned
//! in `theta x phi`, a million samples are histogrammed, expected counts come from adaptively
//! integrating the pdf over each bin (`pdf sin(theta) dtheta dphi`), bins with expected counts
//! below 5 are pooled, failed samples ("no sample") form one more bin, and the statistic's
//! p-value (regularised upper incomplete gamma function, implemented here) must not fall below
//! `0.01 / NUM_TESTS` (Bonferroni). Negative checks make sure a mismatched pdf is rejected.

use glam::Vec3;
use photonmap::material::Material;
use photonmap::sampling::{
    cosine_hemisphere_pdf, sample_cosine_hemisphere, sample_uniform_cone, sample_uniform_sphere,
    uniform_cone_pdf, uniform_hemisphere_pdf, uniform_sphere_pdf,
};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;
use std::f64::consts::PI;

const SAMPLES: usize = 1_000_000;
const MIN_EXPECTED: f64 = 5.0;
/// Number of positive (must-pass) tests in this file, for the Bonferroni correction.
const NUM_TESTS: f64 = 16.0;
const SIGNIFICANCE: f64 = 0.01;

/// ln Gamma(x) for x > 0 (Lanczos, g = 7, n = 9).
fn ln_gamma(x: f64) -> f64 {
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        return (PI / (PI * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let t = x + 7.5;
    let s = C[1..].iter().enumerate().fold(C[0], |s, (i, c)| s + c / (x + 1.0 + i as f64));
    0.5 * (2.0 * PI).ln() + (x + 0.5) * t.ln() - t + s.ln()
}

/// Regularised upper incomplete gamma function Q(a, x) = Gamma(a, x) / Gamma(a) (Numerical
/// Recipes: series for x < a + 1, Lentz's continued fraction otherwise).
fn gamma_q(a: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 1.0;
    }
    let ln_pre = -x + a * x.ln() - ln_gamma(a);
    if x < a + 1.0 {
        let (mut term, mut sum, mut ap) = (1.0 / a, 1.0 / a, a);
        for _ in 0..10_000 {
            ap += 1.0;
            term *= x / ap;
            sum += term;
            if term.abs() < sum.abs() * 1e-15 {
                break;
            }
        }
        1.0 - sum * ln_pre.exp()
    } else {
        let tiny = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / tiny;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..10_000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            d = if d.abs() < tiny { tiny } else { d };
            c = b + an / c;
            c = if c.abs() < tiny { tiny } else { c };
            d = 1.0 / d;
            let delta = d * c;
            h *= delta;
            if (delta - 1.0).abs() < 1e-15 {
                break;
            }
        }
        ln_pre.exp() * h
    }
}

fn adaptive_simpson(f: &dyn Fn(f64) -> f64, a: f64, b: f64, eps: f64, depth: u32) -> f64 {
    /// `fs` holds `f` at `a`, the midpoint and `b`; `whole` is Simpson's rule over `[a, b]`.
    fn rec(f: &dyn Fn(f64) -> f64, (a, b): (f64, f64), fs: [f64; 3], whole: f64, eps: f64, d: u32) -> f64 {
        let [fa, fm, fb] = fs;
        let m = 0.5 * (a + b);
        let (flm, frm) = (f(0.5 * (a + m)), f(0.5 * (m + b)));
        let left = (m - a) / 6.0 * (fa + 4.0 * flm + fm);
        let right = (b - m) / 6.0 * (fm + 4.0 * frm + fb);
        let delta = left + right - whole;
        if d == 0 || delta.abs() <= 15.0 * eps {
            return left + right + delta / 15.0;
        }
        rec(f, (a, m), [fa, flm, fm], left, eps / 2.0, d - 1)
            + rec(f, (m, b), [fm, frm, fb], right, eps / 2.0, d - 1)
    }
    let (fa, fm, fb) = (f(a), f(0.5 * (a + b)), f(b));
    rec(f, (a, b), [fa, fm, fb], (b - a) / 6.0 * (fa + 4.0 * fm + fb), eps, depth)
}

fn direction(theta: f64, phi: f64) -> Vec3 {
    Vec3::new((theta.sin() * phi.cos()) as f32, (theta.sin() * phi.sin()) as f32, theta.cos() as f32)
}

/// A `theta_res x 2 theta_res` binning of the sphere around `+z`.
struct Grid {
    theta_res: usize,
}

impl Grid {
    fn bins(&self) -> usize {
        2 * self.theta_res * self.theta_res
    }

    fn bin(&self, w: Vec3) -> usize {
        let w = w.as_dvec3().normalize();
        let theta = w.z.clamp(-1.0, 1.0).acos();
        let mut phi = w.y.atan2(w.x);
        if phi < 0.0 {
            phi += 2.0 * PI;
        }
        let t = ((theta / PI * self.theta_res as f64) as usize).min(self.theta_res - 1);
        let p = ((phi / (2.0 * PI) * (2 * self.theta_res) as f64) as usize).min(2 * self.theta_res - 1);
        t * 2 * self.theta_res + p
    }

    fn histogram(&self, seed: u64, mut sample: impl FnMut(&mut Pcg64) -> Option<Vec3>) -> Vec<f64> {
        let mut rng = Pcg64::seed_from_u64(seed);
        let mut h = vec![0.0; self.bins()];
        for _ in 0..SAMPLES {
            if let Some(w) = sample(&mut rng) {
                h[self.bin(w)] += 1.0;
            }
        }
        h
    }

    fn expected(&self, pdf: &dyn Fn(Vec3) -> f32) -> Vec<f64> {
        let (dt, dp) = (PI / self.theta_res as f64, PI / self.theta_res as f64);
        let mut e = Vec::with_capacity(self.bins());
        for t in 0..self.theta_res {
            for p in 0..2 * self.theta_res {
                let (p0, p1) = (p as f64 * dp, (p + 1) as f64 * dp);
                let inner = |theta: f64| {
                    let g = |phi: f64| pdf(direction(theta, phi)) as f64;
                    theta.sin() * adaptive_simpson(&g, p0, p1, 1e-7, 10)
                };
                e.push(
                    SAMPLES as f64 * adaptive_simpson(&inner, t as f64 * dt, (t + 1) as f64 * dt, 1e-7, 12),
                );
            }
        }
        e
    }
}

/// pbrt-v4's `Chi2Test` pooling; the failed samples are one more bin. Returns the p-value.
fn chi2_p_value(observed: &[f64], expected: &[f64]) -> f64 {
    let mut obs = observed.to_vec();
    let mut exp = expected.to_vec();
    obs.push(SAMPLES as f64 - observed.iter().sum::<f64>());
    exp.push((SAMPLES as f64 - expected.iter().sum::<f64>()).max(0.0));
    let mut order: Vec<usize> = (0..obs.len()).collect();
    order.sort_by(|&a, &b| exp[a].total_cmp(&exp[b]));
    let (mut pooled_obs, mut pooled_exp, mut chi2, mut dof) = (0.0, 0.0, 0.0, 0i64);
    for i in order {
        if exp[i] <= 1e-9 * SAMPLES as f64 {
            if obs[i] > SAMPLES as f64 * 1e-5 {
                return 0.0; // samples where the pdf says there can be none
            }
            // Round-off scale: merge into the pool.
            pooled_obs += obs[i];
            pooled_exp += exp[i];
        } else if exp[i] < MIN_EXPECTED || (pooled_exp > 0.0 && pooled_exp < MIN_EXPECTED) {
            pooled_obs += obs[i];
            pooled_exp += exp[i];
        } else {
            chi2 += (obs[i] - exp[i]).powi(2) / exp[i];
            dof += 1;
        }
    }
    if pooled_exp > 0.0 {
        chi2 += (pooled_obs - pooled_exp).powi(2) / pooled_exp;
        dof += 1;
    }
    dof -= 1;
    if dof <= 0 {
        return 1.0;
    }
    gamma_q(dof as f64 / 2.0, chi2 / 2.0)
}

fn check(name: &str, observed: &[f64], expected: &[f64]) {
    let p = chi2_p_value(observed, expected);
    eprintln!("{name}: p = {p:.4}");
    assert!(p.is_finite() && p >= SIGNIFICANCE / NUM_TESTS, "{name}: rejected, p = {p:e}");
}

fn reject(name: &str, observed: &[f64], expected: &[f64]) {
    let p = chi2_p_value(observed, expected);
    eprintln!("{name} (must be rejected): p = {p:e}");
    assert!(p < SIGNIFICANCE / NUM_TESTS, "{name}: a wrong pdf was accepted, p = {p:e}");
}

fn u2(rng: &mut Pcg64) -> [f32; 2] {
    [rng.gen(), rng.gen()]
}

fn wo_at(theta_deg: f32) -> Vec3 {
    let t = theta_deg.to_radians();
    Vec3::new(t.sin() * 0.8, t.sin() * 0.6, t.cos()).normalize()
}

#[test]
fn incomplete_gamma_matches_known_values() {
    assert!((gamma_q(1.0, 2.0) - (-2.0f64).exp()).abs() < 1e-12);
    assert!((gamma_q(5.0, 18.307 / 2.0) - 0.05).abs() < 1e-4, "chi2(10) 95% quantile");
    assert!((gamma_q(50.0, 124.342 / 2.0) - 0.05).abs() < 1e-4, "chi2(100) 95% quantile");
    assert!((gamma_q(0.5, 0.5 * 3.841_459) - 0.05).abs() < 1e-5, "chi2(1) 95% quantile");
    assert!((gamma_q(2.0, 13.2767 / 2.0) - 0.01).abs() < 1e-4, "chi2(4) 99% quantile");
    assert!((ln_gamma(10.0) - 362_880f64.ln()).abs() < 1e-10);
}

#[test]
fn warps_fit_their_pdfs() {
    let g = Grid { theta_res: 10 };
    let cos = g.histogram(1, |r| Some(sample_cosine_hemisphere(u2(r))));
    check("cosine hemisphere", &cos, &g.expected(&|w| cosine_hemisphere_pdf(w.z)));
    let sph = g.histogram(2, |r| Some(sample_uniform_sphere(u2(r))));
    check("uniform sphere", &sph, &g.expected(&|_| uniform_sphere_pdf()));
    for (k, deg) in [25.0f32, 70.0].into_iter().enumerate() {
        let cos_max = deg.to_radians().cos();
        let h = g.histogram(3 + k as u64, |r| Some(sample_uniform_cone(u2(r), cos_max)));
        let pdf = move |w: Vec3| if w.z >= cos_max { uniform_cone_pdf(cos_max) } else { 0.0 };
        check(&format!("uniform cone {deg}"), &h, &g.expected(&pdf));
    }
}

#[test]
fn diffuse_material_fits_its_pdf() {
    let g = Grid { theta_res: 10 };
    let m = Material::Diffuse { kd: Vec3::new(0.725, 0.71, 0.68) };
    for (k, wo) in [wo_at(0.0), wo_at(60.0), -wo_at(30.0)].into_iter().enumerate() {
        let h = g.histogram(10 + k as u64, |r| m.sample(Vec3::Z, wo, r.gen(), u2(r)).map(|s| s.wi));
        check(&format!("diffuse wo {wo}"), &h, &g.expected(&|wi| m.pdf(Vec3::Z, wo, wi)));
    }
}

#[test]
fn glossy_material_fits_its_pdf() {
    for (i, ns) in [1.0f32, 10.0, 100.0].into_iter().enumerate() {
        // Finer bins for the narrow lobe, so the test can see its shape.
        let g = Grid { theta_res: if ns >= 100.0 { 30 } else { 10 } };
        let m = Material::Glossy { kd: Vec3::splat(0.3), ks: Vec3::new(0.6, 0.5, 0.4), ns };
        for (j, theta) in [0.0f32, 45.0, 80.0].into_iter().enumerate() {
            let wo = wo_at(theta);
            let seed = 100 + 10 * i as u64 + j as u64;
            let h = g.histogram(seed, |r| m.sample(Vec3::Z, wo, r.gen(), u2(r)).map(|s| s.wi));
            check(&format!("glossy ns {ns} wo {theta}"), &h, &g.expected(&|wi| m.pdf(Vec3::Z, wo, wi)));
        }
    }
}

#[test]
fn mismatched_pdfs_are_rejected() {
    let g = Grid { theta_res: 10 };
    // Cosine-distributed samples are not uniform over the hemisphere.
    let cos = g.histogram(1, |r| Some(sample_cosine_hemisphere(u2(r))));
    reject(
        "cosine vs uniform",
        &cos,
        &g.expected(&|w| if w.z >= 0.0 { uniform_hemisphere_pdf() } else { 0.0 }),
    );
    // A slightly wrong Phong exponent.
    let wo = wo_at(30.0);
    let m = Material::Glossy { kd: Vec3::splat(0.3), ks: Vec3::splat(0.6), ns: 10.0 };
    let wrong = Material::Glossy { kd: Vec3::splat(0.3), ks: Vec3::splat(0.6), ns: 12.0 };
    let h = g.histogram(7, |r| m.sample(Vec3::Z, wo, r.gen(), u2(r)).map(|s| s.wi));
    reject("glossy ns 10 vs 12", &h, &g.expected(&|wi| wrong.pdf(Vec3::Z, wo, wi)));
    // A pdf with the right shape but a missing normalisation factor.
    reject("cosine pdf * 1.02", &cos, &g.expected(&|w| 1.02 * cosine_hemisphere_pdf(w.z)));
}
