//! Distant (directional) light (pbrt-v4 `DistantLight`): parallel light travelling along
//! `direction` with irradiance `E` (W/m^2) on a perpendicular surface.
//!
//! Its flux into the scene is `E pi R^2` for the disk of radius `R` perpendicular to the
//! direction that covers the scene's bounding sphere (centre `c`, radius `R`); photons start
//! uniformly on that disk, moved back outside the sphere. Call [`DistantLight::preprocess`] with
//! the scene bounds before asking for power or photons.

use super::{EmissionSample, LightSample};
use crate::geometry::Aabb;
use crate::sampling::{sample_uniform_disk_concentric, Frame};
use glam::Vec3;
use std::f32::consts::PI;

/// A distant light; `direction` is the (unit) way the light travels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DistantLight {
    pub direction: Vec3,
    pub irradiance: Vec3,
    /// Scene bounding sphere, set by [`DistantLight::preprocess`].
    pub scene_center: Vec3,
    pub scene_radius: f32,
}

impl DistantLight {
    /// A light with an empty scene sphere (no power until [`DistantLight::preprocess`]).
    pub fn new(direction: Vec3, irradiance: Vec3) -> Self {
        DistantLight {
            direction: direction.normalize_or(Vec3::NEG_Y),
            irradiance,
            scene_center: Vec3::ZERO,
            scene_radius: 0.0,
        }
    }

    /// Records the scene's bounding sphere.
    pub fn preprocess(&mut self, scene_bounds: Aabb) {
        if scene_bounds.is_empty() {
            (self.scene_center, self.scene_radius) = (Vec3::ZERO, 0.0);
        } else {
            (self.scene_center, self.scene_radius) = scene_bounds.bounding_sphere();
        }
    }

    /// `E pi R^2`.
    pub fn power(&self) -> Vec3 {
        self.irradiance * PI * self.scene_radius * self.scene_radius
    }

    /// Toward the light from anywhere: `wi = -direction`, infinite distance, `li = E`, delta.
    pub fn sample_li(&self, _p: Vec3) -> Option<LightSample> {
        Some(LightSample {
            wi: -self.direction,
            dist: f32::INFINITY,
            end_error: 0.0,
            li: self.irradiance,
            pdf: 1.0,
            delta: true,
        })
    }

    /// A photon from a uniform point (`u_pos`) of the disk covering the bounding sphere,
    /// starting just outside the sphere and travelling along `direction`.
    pub fn sample_emission(&self, u_pos: [f32; 2]) -> Option<EmissionSample> {
        let r = self.scene_radius;
        if r <= 0.0 || !r.is_finite() {
            return None;
        }
        let frame = Frame::from_z(self.direction);
        let d = sample_uniform_disk_concentric(u_pos) * r;
        let back = r * 1.001 + 1e-4;
        let ray_origin = self.scene_center + frame.from_local(Vec3::new(d.x, d.y, -back));
        Some(EmissionSample {
            ray_origin,
            dir: self.direction,
            normal: None,
            pdf_pos: 1.0 / (PI * r * r),
            pdf_dir: 1.0,
            le: self.irradiance,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::sample_uniform_sphere;

    #[test]
    fn disk_covers_the_bounding_sphere() {
        let bounds = Aabb::from_points([Vec3::new(-0.2, 0.0, 0.1), Vec3::new(0.556, 0.5488, 0.5592)]);
        let mut l = DistantLight::new(Vec3::new(0.3, -1.0, 0.2).normalize(), Vec3::new(2.0, 1.5, 1.0));
        l.preprocess(bounds);
        let (c, r) = bounds.bounding_sphere();
        assert!((l.power() - l.irradiance * PI * r * r).abs().max_element() < 1e-5);
        let frame = Frame::from_z(l.direction);
        let (mut max_lateral, n) = (0.0f32, 64);
        for i in 0..n * n {
            let u = [((i % n) as f32 + 0.5) / n as f32, ((i / n) as f32 + 0.5) / n as f32];
            let e = l.sample_emission(u).unwrap();
            assert!((e.ray_origin - c).length() > r, "starts outside the sphere");
            assert!((e.ray_origin - c).dot(e.dir) < 0.0, "and travels toward it");
            assert!((e.photon_power() - l.power()).abs().max_element() < 1e-3);
            let lateral = frame.to_local(e.ray_origin - c);
            max_lateral = max_lateral.max(lateral.truncate().length());
            // Every photon line passes within R of the centre: it can reach the scene.
            assert!(lateral.truncate().length() <= r * (1.0 + 1e-5));
        }
        assert!(max_lateral > 0.97 * r, "the disk is filled out to the sphere's silhouette");
        // Every point of the sphere lies on some photon line: its lateral offset is inside the disk.
        for i in 0..1000 {
            let q = c + r * sample_uniform_sphere([(i as f32 + 0.5) / 1000.0, (i as f32 * 0.618).fract()]);
            assert!(frame.to_local(q - c).truncate().length() <= r * (1.0 + 1e-5));
        }
        let s = l.sample_li(Vec3::ZERO).unwrap();
        assert!(s.delta && s.dist.is_infinite() && s.wi == -l.direction && s.li == l.irradiance);
    }

    #[test]
    fn empty_scene_emits_nothing() {
        let mut l = DistantLight::new(Vec3::NEG_Y, Vec3::ONE);
        l.preprocess(Aabb::EMPTY);
        assert_eq!(l.power(), Vec3::ZERO);
        assert!(l.sample_emission([0.5, 0.5]).is_none());
    }
}
