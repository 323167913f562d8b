//! Distant (directional) light (pbrt-v4 `DistantLight`): parallel light travelling along
//! `direction` with irradiance `E` (W/m^2) on a perpendicular surface.
//!
//! Its flux into the scene is `E pi R^2` for the disk of radius `R` perpendicular to the
//! direction that covers the scene's bounding sphere (centre `c`, radius `R`); photons start
//! uniformly on that disk, moved back outside the sphere. With portals (`[[portal]]`, see
//! [`super::portal`]) half the photons start on lines through them and the rest on the disk
//! outside them; the flux does not change. Call [`DistantLight::preprocess`] with the scene bounds and portals before
//! asking for power or photons.

use super::portal::{Portal, Projected};
use super::{EmissionSample, LightSample};
use crate::geometry::Aabb;
use crate::sampling::{sample_uniform_disk_concentric, Frame};
use glam::Vec3;
use std::f32::consts::PI;

/// Share of a distant light's photons sent through its portals (the rest cover the disk
/// outside them).
pub const PORTAL_SHARE: f32 = 0.5;

/// A distant light; `direction` is the (unit) way the light travels.
#[derive(Clone, Debug, PartialEq)]
pub struct DistantLight {
    pub direction: Vec3,
    pub irradiance: Vec3,
    /// Scene bounding sphere, set by [`DistantLight::preprocess`].
    pub scene_center: Vec3,
    pub scene_radius: f32,
    /// The portals projected along `direction` about `scene_center` (empty: the whole disk).
    portals: Projected,
}

impl DistantLight {
    /// A light with an empty scene sphere (no power until [`DistantLight::preprocess`]).
    pub fn new(direction: Vec3, irradiance: Vec3) -> Self {
        DistantLight {
            direction: direction.normalize_or(Vec3::NEG_Y),
            irradiance,
            scene_center: Vec3::ZERO,
            scene_radius: 0.0,
            portals: Projected::default(),
        }
    }

    /// Records the scene's bounding sphere and the portals photons are sent through.
    pub fn preprocess(&mut self, scene_bounds: Aabb, portals: &[Portal]) {
        if scene_bounds.is_empty() {
            (self.scene_center, self.scene_radius) = (Vec3::ZERO, 0.0);
        } else {
            (self.scene_center, self.scene_radius) = scene_bounds.bounding_sphere();
        }
        self.portals = Projected::new(portals, &Frame::from_z(self.direction), self.scene_center);
    }

    /// Whether half the photons start on lines through portals.
    pub fn has_portals(&self) -> bool {
        !self.portals.is_empty()
    }

    /// `E pi R^2` (portals change where photons start, not the flux).
    pub fn power(&self) -> Vec3 {
        self.irradiance * PI * self.scene_radius * self.scene_radius
    }

    /// The flux the photon budget is split by: the power, or with portals the flux through
    /// them over the share of photons sent that way (what photons toward the inside carry;
    /// the disc's other photons light only the outside).
    pub fn budget_power(&self) -> Vec3 {
        if self.has_portals() && self.scene_radius > 0.0 {
            self.irradiance * (self.portals.area() / PORTAL_SHARE)
        } else {
            self.power()
        }
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
    ///
    /// With portals the disk is split in two strata. `u_pos[0] < PORTAL_SHARE` picks a point
    /// of the portals' projections (density `PORTAL_SHARE / A_portals`): light straight in.
    /// The rest pick a uniform point of the disk, `None` inside a portal's projection (density
    /// `(1 - PORTAL_SHARE) / (pi R^2)`): light on the outside, whose bounces in through the
    /// portals the portals' own photons bring ([`crate::photon::portal`]). Every line keeps
    /// one stratum and its density, so the light's flux is all there.
    pub fn sample_emission(&self, u_pos: [f32; 2]) -> Option<EmissionSample> {
        let r = self.scene_radius;
        if r <= 0.0 || !r.is_finite() {
            return None;
        }
        let frame = Frame::from_z(self.direction);
        let disk = PI * r * r;
        let (d, pdf_pos) = if !self.has_portals() {
            (sample_uniform_disk_concentric(u_pos) * r, 1.0 / disk)
        } else if u_pos[0] < PORTAL_SHARE {
            let q = self.portals.sample([u_pos[0] / PORTAL_SHARE, u_pos[1]]);
            (q, PORTAL_SHARE / self.portals.area())
        } else {
            let u = [((u_pos[0] - PORTAL_SHARE) / (1.0 - PORTAL_SHARE)).min(1.0), u_pos[1]];
            let q = sample_uniform_disk_concentric(u) * r;
            if self.portals.coverage(q) > 0 {
                return None;
            }
            (q, (1.0 - PORTAL_SHARE) / disk)
        };
        let back = r * 1.001 + 1e-4;
        let ray_origin = self.scene_center + frame.from_local(Vec3::new(d.x, d.y, -back));
        Some(EmissionSample {
            ray_origin,
            dir: self.direction,
            normal: None,
            pdf_pos,
            pdf_dir: 1.0,
            le: self.irradiance,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::light::portal::Projected;
    use crate::sampling::sample_uniform_sphere;

    #[test]
    fn disk_covers_the_bounding_sphere() {
        let bounds = Aabb::from_points([Vec3::new(-0.2, 0.0, 0.1), Vec3::new(0.556, 0.5488, 0.5592)]);
        let mut l = DistantLight::new(Vec3::new(0.3, -1.0, 0.2).normalize(), Vec3::new(2.0, 1.5, 1.0));
        l.preprocess(bounds, &[]);
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
    fn portal_strata_keep_every_line_and_its_flux() {
        // A window in a wall, seen by a low sun. Over stratified samples, the power of the
        // photons whose line crosses a region of the disk's plane estimates E times its area:
        // the portal's projection, a square next to it, one far off, and the whole disk.
        let bounds = Aabb::from_points([Vec3::new(-4.0, 0.0, -3.0), Vec3::new(4.0, 3.0, 3.0)]);
        let dir = Vec3::new(-0.26, -0.64, -0.72).normalize();
        let window = Portal {
            corner: Vec3::new(0.05, 1.15, 1.65),
            edge_u: Vec3::new(0.5, 0.0, 0.0),
            edge_v: Vec3::new(0.0, 0.6, 0.0),
        };
        let mut l = DistantLight::new(dir, Vec3::splat(2.0));
        l.preprocess(bounds, &[window]);
        assert!(l.has_portals());
        let mut open = DistantLight::new(dir, Vec3::splat(2.0));
        open.preprocess(bounds, &[]);
        assert_eq!(l.power(), open.power(), "the flux does not change");
        let frame = Frame::from_z(dir);
        let lateral = |p: Vec3| frame.to_local(p - l.scene_center).truncate();
        let w = Projected::new(&[window], &frame, l.scene_center);
        let near = lateral(window.corner + 0.5 * (window.edge_u + window.edge_v));
        let square = |c: glam::Vec2, half: f32| move |q: glam::Vec2| (q - c).abs().max_element() <= half;
        let beside = square(near + glam::Vec2::new(0.9, 0.0), 0.3);
        let far = square(glam::Vec2::new(-0.6 * l.scene_radius, 0.0), 1.0);
        let (mut sums, n) = ([0.0f64; 4], 1024);
        for i in 0..n * n {
            let u = [((i % n) as f32 + 0.5) / n as f32, ((i / n) as f32 + 0.5) / n as f32];
            let Some(e) = l.sample_emission(u) else { continue };
            let q = lateral(e.ray_origin);
            let p = e.photon_power().x as f64 / (n * n) as f64;
            sums[0] += p * (w.coverage(q) > 0) as u8 as f64;
            sums[1] += p * beside(q) as u8 as f64;
            sums[2] += p * far(q) as u8 as f64;
            sums[3] += p;
        }
        let expected = [2.0 * w.area() as f64, 2.0 * 0.36, 2.0 * 4.0, open.power().x as f64];
        for (k, (s, e)) in sums.iter().zip(expected).enumerate() {
            assert!((s / e - 1.0).abs() < 0.03, "region {k}: {s} against {e}");
        }
    }

    #[test]
    fn empty_scene_emits_nothing() {
        let mut l = DistantLight::new(Vec3::NEG_Y, Vec3::ONE);
        l.preprocess(Aabb::EMPTY, &[]);
        assert_eq!(l.power(), Vec3::ZERO);
        assert!(l.sample_emission([0.5, 0.5]).is_none());
    }
}
