//! Shared checks for the per-material unit tests.

use super::Material;
use crate::sampling::{sample_uniform_sphere, Frame};
use glam::Vec3;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

/// A deterministic RNG for tests.
pub fn rng(seed: u64) -> Pcg64 {
    Pcg64::seed_from_u64(seed)
}

/// Unit direction at polar angle `theta_deg` from `n`, azimuth `phi_deg`.
pub fn dir(n: Vec3, theta_deg: f32, phi_deg: f32) -> Vec3 {
    let (t, p) = (theta_deg.to_radians(), phi_deg.to_radians());
    Frame::from_z(n).from_local(Vec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos()))
}

/// Monte Carlo estimate of the directional albedo `int f |cos| dwi` by BSDF sampling (the white
/// furnace: a BRDF under unit incident radiance from everywhere reflects this much).
pub fn furnace(m: &Material, n: Vec3, wo: Vec3, samples: usize, seed: u64) -> Vec3 {
    let mut r = rng(seed);
    let mut sum = Vec3::ZERO;
    for _ in 0..samples {
        if let Some(s) = m.sample(n, wo, r.gen(), [r.gen(), r.gen()]) {
            sum += s.weight(n);
        }
    }
    sum / samples as f32
}

/// The same integral by uniform sphere sampling of `eval` (independent of `sample`).
pub fn furnace_uniform(m: &Material, n: Vec3, wo: Vec3, samples: usize, seed: u64) -> Vec3 {
    let mut r = rng(seed);
    let mut sum = Vec3::ZERO;
    for _ in 0..samples {
        let wi = sample_uniform_sphere([r.gen(), r.gen()]);
        sum += m.eval(n, wo, wi) * n.dot(wi).abs() * 4.0 * std::f32::consts::PI;
    }
    sum / samples as f32
}

/// For non-delta samples: `f` and `pdf` returned by `sample` equal `eval` and `pdf`, and the
/// direction is on the side of `wo`. Also checks reciprocity `f(wo, wi) = f(wi, wo)`.
pub fn check_sample_matches_eval(m: &Material, n: Vec3, wo: Vec3, seed: u64) {
    let mut r = rng(seed);
    let mut got = 0;
    for _ in 0..2000 {
        let Some(s) = m.sample(n, wo, r.gen(), [r.gen(), r.gen()]) else { continue };
        got += 1;
        assert!(!s.delta);
        assert!(n.dot(s.wi) * n.dot(wo) > 0.0, "wi on the wrong side");
        assert!((s.wi.length() - 1.0).abs() < 1e-4);
        let f = m.eval(n, wo, s.wi);
        let pdf = m.pdf(n, wo, s.wi);
        assert!((f - s.f).abs().max_element() <= 1e-4 * f.max_element().max(1.0), "{f} vs {}", s.f);
        assert!((pdf - s.pdf).abs() <= 1e-4 * pdf.max(1.0), "{pdf} vs {}", s.pdf);
        assert!(s.pdf > 0.0);
        let back = m.eval(n, s.wi, wo);
        assert!((back - f).abs().max_element() <= 1e-3 * f.max_element().max(1e-3), "reciprocity");
    }
    assert!(got > 1000, "too few samples: {got}");
}
