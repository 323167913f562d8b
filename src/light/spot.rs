//! Spot light (pbrt-v4 `SpotLight`): a point light whose intensity is `I * falloff(cos theta)`,
//! `theta` the angle from the axis. Full intensity within `cone_deg - falloff_deg` of the axis,
//! zero beyond `cone_deg`, and in between pbrt-v4's `SmoothStep` in `cos theta`:
//! `falloff = smoothstep(cos(cone), cos(cone - falloff), cos theta)`.
//!
//! Because the smoothstep ramp is point-symmetric, its integral over `cos theta` is half the ramp
//! width, so the flux is exactly `I 2 pi [(1 - cos_start) + (cos_start - cos_end) / 2]`
//! (pbrt-v4 `SpotLight::Phi`). Photons are emitted with density proportional to the intensity
//! profile (plateau: uniform in `cos theta`; ramp: the smoothstep CDF `2t^3 - t^4` inverted by
//! bisection), so every photon carries the same power, equal to that flux.

use super::{EmissionSample, LightSample};
use crate::sampling::{spherical_direction, Frame};
use glam::Vec3;
use std::f32::consts::PI;

/// A spot light; see the module docs for the falloff.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpotLight {
    pub position: Vec3,
    /// Local frame with the (unit) axis as `z`.
    pub frame: Frame,
    pub intensity: Vec3,
    /// `cos(cone_deg)`: intensity is zero below it.
    pub cos_falloff_end: f32,
    /// `cos(cone_deg - falloff_deg)`: full intensity above it.
    pub cos_falloff_start: f32,
}

/// `smoothstep(a, b, x)` with pbrt-v4's convention; a hard step at `a` if `a == b`.
fn smoothstep(a: f32, b: f32, x: f32) -> f32 {
    if a == b {
        return if x < a { 0.0 } else { 1.0 };
    }
    let t = ((x - a) / (b - a)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

impl SpotLight {
    /// `cone_deg` is clamped to `[0, 180]`, `falloff_deg` to `[0, cone_deg]`.
    pub fn new(position: Vec3, direction: Vec3, intensity: Vec3, cone_deg: f32, falloff_deg: f32) -> Self {
        let cone = cone_deg.clamp(0.0, 180.0);
        let start = (cone - falloff_deg.clamp(0.0, cone)).max(0.0);
        SpotLight {
            position,
            frame: Frame::from_z(direction.normalize_or(Vec3::NEG_Y)),
            intensity,
            cos_falloff_end: cone.to_radians().cos(),
            cos_falloff_start: start.to_radians().cos(),
        }
    }

    /// The profile in `[0, 1]` for a direction with `cos theta = cos_theta` from the axis.
    pub fn falloff(&self, cos_theta: f32) -> f32 {
        smoothstep(self.cos_falloff_end, self.cos_falloff_start, cos_theta)
    }

    /// Radiant intensity toward the unit direction `w` (leaving the light).
    pub fn intensity_toward(&self, w: Vec3) -> Vec3 {
        self.intensity * self.falloff(w.dot(self.frame.n))
    }

    /// `(plateau, ramp)`: the profile's integral over `cos theta` on each part.
    fn masses(&self) -> (f32, f32) {
        (1.0 - self.cos_falloff_start, 0.5 * (self.cos_falloff_start - self.cos_falloff_end))
    }

    /// Total flux, `I 2 pi [(1 - cos_start) + (cos_start - cos_end) / 2]`.
    pub fn power(&self) -> Vec3 {
        let (a, b) = self.masses();
        self.intensity * 2.0 * PI * (a + b)
    }

    /// Direction to the light with `li = I falloff / d^2`, delta; `None` outside the cone.
    pub fn sample_li(&self, p: Vec3) -> Option<LightSample> {
        let d = self.position - p;
        let dist = d.length();
        if dist <= 0.0 || !dist.is_finite() {
            return None;
        }
        let wi = d / dist;
        let li = self.intensity_toward(-wi) / (dist * dist);
        (li.max_element() > 0.0).then_some(LightSample {
            wi,
            dist,
            end_error: 0.0,
            li,
            pdf: 1.0,
            delta: true,
        })
    }

    /// A photon direction with density proportional to the profile; `pdf_dir` is that density.
    pub fn sample_emission(&self, u_dir: [f32; 2]) -> Option<EmissionSample> {
        let (a, b) = self.masses();
        if a + b <= 0.0 {
            return None;
        }
        let p_plateau = a / (a + b);
        let cos_theta = if u_dir[0] < p_plateau {
            let v = u_dir[0] / p_plateau;
            1.0 - v * a
        } else {
            let v = ((u_dir[0] - p_plateau) / (1.0 - p_plateau)).clamp(0.0, 1.0);
            // Solve 2 t^3 - t^4 = v (monotone on [0, 1]) by bisection.
            let (mut lo, mut hi) = (0.0f32, 1.0f32);
            for _ in 0..30 {
                let t = 0.5 * (lo + hi);
                if 2.0 * t * t * t - t * t * t * t < v {
                    lo = t;
                } else {
                    hi = t;
                }
            }
            let t = 0.5 * (lo + hi);
            self.cos_falloff_end + t * (self.cos_falloff_start - self.cos_falloff_end)
        };
        let g = self.falloff(cos_theta);
        if g <= 0.0 {
            return None;
        }
        let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
        let dir = self.frame.from_local(spherical_direction(sin_theta, cos_theta, 2.0 * PI * u_dir[1]));
        Some(EmissionSample {
            ray_origin: self.position,
            dir: dir.normalize(),
            normal: None,
            pdf_pos: 1.0,
            pdf_dir: g / (2.0 * PI * (a + b)),
            le: self.intensity * g,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spot() -> SpotLight {
        SpotLight::new(
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(0.2, -1.0, 0.1),
            Vec3::new(3.0, 2.0, 1.0),
            40.0,
            15.0,
        )
    }

    #[test]
    fn falloff_is_full_inside_zero_outside_smooth_between() {
        let s = spot();
        let c = |deg: f32| deg.to_radians().cos();
        assert_eq!(s.falloff(c(0.0)), 1.0);
        assert_eq!(s.falloff(c(24.9)), 1.0);
        assert_eq!(s.falloff(c(40.1)), 0.0);
        let mid = 0.5 * (c(25.0) + c(40.0));
        assert!((s.falloff(mid) - 0.5).abs() < 1e-5);
        assert!(s.falloff(c(30.0)) > s.falloff(c(35.0)));
        let outside = s.position + s.frame.from_local(Vec3::new(1.0, 0.0, 0.2));
        assert!(s.sample_li(outside).is_none());
        let on_axis = s.position + 2.0 * s.frame.n;
        let l = s.sample_li(on_axis).unwrap();
        assert!((l.li - s.intensity / 4.0).abs().max_element() < 1e-6 && l.delta);
    }

    #[test]
    fn power_is_the_integral_of_the_profile() {
        for (cone, fall) in [(40.0, 15.0), (30.0, 0.0), (60.0, 60.0), (180.0, 30.0)] {
            let s = SpotLight::new(Vec3::ZERO, Vec3::Y, Vec3::ONE, cone, fall);
            // Midpoint rule over cos theta in [-1, 1], times 2 pi (independent of `power`).
            let n = 200_000;
            let integral: f64 = (0..n)
                .map(|i| s.falloff(-1.0 + 2.0 * (i as f32 + 0.5) / n as f32) as f64 * 2.0 / n as f64)
                .sum::<f64>()
                * 2.0
                * std::f64::consts::PI;
            assert!((integral as f32 - s.power().x).abs() < 1e-3 * s.power().x, "{cone}/{fall}");
        }
    }

    #[test]
    fn photons_have_equal_power_and_follow_the_profile() {
        let s = spot();
        let power = s.power();
        // Histogram of photon cos theta against the profile's integral over each bin.
        let bins = 16;
        let lo = s.cos_falloff_end;
        let width = (1.0 - lo) / bins as f32;
        let mut hist = vec![0usize; bins];
        let n = 400;
        for i in 0..n * n {
            // Stratified in u[0] (which decides theta), golden-ratio sequence in u[1].
            let u = [(i as f32 + 0.5) / (n * n) as f32, (i as f32 * 0.618_034).fract()];
            let e = s.sample_emission(u).unwrap();
            assert!((e.photon_power() - power).abs().max_element() < 1e-3 * power.max_element());
            assert!((e.le / e.pdf_dir - s.intensity_toward(e.dir) / e.pdf_dir).abs().max_element() < 1e-3);
            let b = (((e.dir.dot(s.frame.n) - lo) / width) as usize).min(bins - 1);
            hist[b] += 1;
        }
        let total_mass = power.x / (2.0 * PI * s.intensity.x);
        for (b, &count) in hist.iter().enumerate() {
            let m = 2000;
            let mass: f32 = (0..m)
                .map(|k| s.falloff(lo + width * (b as f32 + (k as f32 + 0.5) / m as f32)) * width / m as f32)
                .sum();
            let expected = mass / total_mass * (n * n) as f32;
            assert!(
                (count as f32 - expected).abs() <= 0.01 * expected + 20.0,
                "bin {b}: {count} vs {expected}"
            );
        }
    }
}
