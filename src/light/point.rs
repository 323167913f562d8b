//! Isotropic point light (pbrt-v4 `PointLight`): radiant intensity `I` (W/sr) in every direction,
//! flux `4 pi I`, irradiance `I cos(theta) / d^2`. A delta light: it cannot be hit by rays.

use super::{EmissionSample, LightSample};
use crate::sampling::{sample_uniform_sphere, uniform_sphere_pdf};
use glam::Vec3;
use std::f32::consts::PI;

/// A point light at `position` with intensity `intensity` (W/sr per channel).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointLight {
    pub position: Vec3,
    pub intensity: Vec3,
}

impl PointLight {
    /// Total flux `4 pi I`.
    pub fn power(&self) -> Vec3 {
        4.0 * PI * self.intensity
    }

    /// The (only) direction to the light from `p`, with `li = I / d^2`, `pdf = 1`, `delta`.
    pub fn sample_li(&self, p: Vec3) -> Option<LightSample> {
        let d = self.position - p;
        let dist = d.length();
        if dist <= 0.0 || !dist.is_finite() {
            return None;
        }
        Some(LightSample {
            wi: d / dist,
            dist,
            end_error: 0.0,
            li: self.intensity / (dist * dist),
            pdf: 1.0,
            delta: true,
        })
    }

    /// A photon leaving the light in a uniformly distributed direction (`u_dir`).
    pub fn sample_emission(&self, u_dir: [f32; 2]) -> Option<EmissionSample> {
        Some(EmissionSample {
            ray_origin: self.position,
            dir: sample_uniform_sphere(u_dir),
            normal: None,
            pdf_pos: 1.0,
            pdf_dir: uniform_sphere_pdf(),
            le: self.intensity,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn irradiance_is_intensity_cos_over_distance_squared() {
        let l = PointLight {
            position: Vec3::new(0.278, 0.5, 0.2796),
            intensity: Vec3::new(0.23205, 0.1638, 0.0546),
        };
        let p = Vec3::new(0.1, 0.0, 0.4);
        let n = Vec3::Y;
        let s = l.sample_li(p).unwrap();
        let d = l.position - p;
        let expected = l.intensity * n.dot(d.normalize()) / d.length_squared();
        assert!((s.li * n.dot(s.wi) / s.pdf - expected).abs().max_element() < 1e-6);
        assert!(s.delta && (s.dist - d.length()).abs() < 1e-6);
        assert!(l.sample_li(l.position).is_none());
    }

    #[test]
    fn photons_carry_the_total_power() {
        let l = PointLight { position: Vec3::ZERO, intensity: Vec3::new(1.0, 2.0, 3.0) };
        let e = l.sample_emission([0.3, 0.9]).unwrap();
        assert!((e.photon_power() - l.power()).abs().max_element() < 1e-4);
        assert!((e.dir.length() - 1.0).abs() < 1e-5);
    }
}
