//! Lambertian reflection, `f = kd / pi` (pbrt-v4 `DiffuseBxDF`), sampled by Malley's method
//! (cosine-weighted hemisphere).
//!
//! `n` is already flipped to the side of `wo` by the caller ([`super::Material`] is two-sided).

use super::{BsdfSample, LobeKind};
use crate::sampling::{cosine_hemisphere_pdf, sample_cosine_hemisphere, Frame};
use glam::Vec3;
use std::f32::consts::FRAC_1_PI;

/// A Lambertian BRDF with reflectance `kd`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DiffuseBsdf {
    pub kd: Vec3,
}

impl DiffuseBsdf {
    /// `kd / pi` when `wo` and `wi` are both on the side of `n`, else zero.
    pub fn eval(&self, n: Vec3, wo: Vec3, wi: Vec3) -> Vec3 {
        if n.dot(wo) > 0.0 && n.dot(wi) > 0.0 {
            self.kd * FRAC_1_PI
        } else {
            Vec3::ZERO
        }
    }

    /// `cos(n, wi) / pi` on the side of `wo`, else zero.
    pub fn pdf(&self, n: Vec3, wo: Vec3, wi: Vec3) -> f32 {
        if n.dot(wo) > 0.0 {
            cosine_hemisphere_pdf(n.dot(wi))
        } else {
            0.0
        }
    }

    /// Cosine-weighted direction around `n`.
    pub fn sample(&self, n: Vec3, wo: Vec3, u: [f32; 2]) -> Option<BsdfSample> {
        if n.dot(wo) <= 0.0 || self.kd == Vec3::ZERO {
            return None;
        }
        let local = sample_cosine_hemisphere(u);
        if local.z <= 0.0 {
            return None;
        }
        let wi = Frame::from_z(n).from_local(local).normalize();
        let pdf = cosine_hemisphere_pdf(n.dot(wi));
        (pdf > 0.0).then_some(BsdfSample {
            wi,
            f: self.kd * FRAC_1_PI,
            pdf,
            delta: false,
            kind: LobeKind::Diffuse,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::super::testutil::*;
    use super::super::Material;
    use glam::Vec3;

    const KD: Vec3 = Vec3::new(0.725, 0.71, 0.68);

    #[test]
    fn white_furnace_equals_kd() {
        let m = Material::Diffuse { kd: KD };
        let n = Vec3::new(0.2, 0.9, -0.3).normalize();
        for theta in [0.0, 40.0, 85.0] {
            let wo = dir(n, theta, 30.0);
            // Importance sampling a Lambertian is exact: every sample weighs kd.
            assert!((furnace(&m, n, wo, 10_000, 1) - KD).abs().max_element() < 1e-4);
            let mc = furnace_uniform(&m, n, wo, 400_000, 2);
            assert!((mc - KD).abs().max_element() < 0.01, "{mc}");
        }
    }

    #[test]
    fn sample_matches_eval_and_is_reciprocal() {
        let m = Material::Diffuse { kd: KD };
        for (k, theta) in [0.0, 30.0, 70.0, 89.0].into_iter().enumerate() {
            check_sample_matches_eval(&m, Vec3::Z, dir(Vec3::Z, theta, 10.0), k as u64);
        }
    }

    #[test]
    fn two_sided_from_the_back() {
        let m = Material::Diffuse { kd: KD };
        let n = Vec3::Z;
        let wo = dir(-n, 20.0, 0.0);
        check_sample_matches_eval(&m, n, wo, 9);
        assert!((furnace(&m, n, wo, 1000, 3) - KD).abs().max_element() < 1e-4);
        // Across the surface: no transmission.
        assert_eq!(m.eval(n, wo, Vec3::Z), Vec3::ZERO);
        assert_eq!(m.pdf(n, wo, Vec3::Z), 0.0);
    }
}
