//! Pinhole camera with the look-at convention of `scenes/SCENES.md` (Mitsuba's `perspective`
//! with `fov_axis = "y"`).

use crate::geometry::Ray;
use glam::Vec3;

/// A pinhole camera producing primary rays for film positions in pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    pub eye: Vec3,
    /// Unit forward, right and up vectors: `f = normalize(target - eye)`,
    /// `r = normalize(f x up)`, `u = r x f`.
    pub forward: Vec3,
    pub right: Vec3,
    pub up: Vec3,
    /// `tan(vfov / 2)`.
    pub tan_half_fov: f32,
    pub width: u32,
    pub height: u32,
}

impl Camera {
    /// Builds the camera; `None` if the frame is degenerate (eye = target, up parallel to the
    /// view direction) or the field of view is not in (0, 180) degrees.
    pub fn look_at(
        eye: Vec3,
        target: Vec3,
        up: Vec3,
        vfov_deg: f32,
        width: u32,
        height: u32,
    ) -> Option<Self> {
        let forward = (target - eye).try_normalize()?;
        let right = forward.cross(up).try_normalize()?;
        let up = right.cross(forward);
        if !(vfov_deg > 0.0 && vfov_deg < 180.0) || width == 0 || height == 0 {
            return None;
        }
        let tan_half_fov = (0.5 * vfov_deg.to_radians()).tan();
        Some(Camera { eye, forward, right, up, tan_half_fov, width, height })
    }

    /// The primary ray through film position `(x, y)` in pixels (`x` left to right in
    /// `[0, width)`, `y` top to bottom in `[0, height)`); the direction is normalised.
    #[inline]
    pub fn ray(&self, x: f32, y: f32) -> Ray {
        let (w, h) = (self.width as f32, self.height as f32);
        let sx = (2.0 * x / w - 1.0) * self.tan_half_fov * (w / h);
        let sy = (1.0 - 2.0 * y / h) * self.tan_half_fov;
        let dir = (self.forward + sx * self.right + sy * self.up).normalize();
        Ray::new(self.eye, dir)
    }

    /// The same camera at another resolution (the field of view is kept).
    pub fn with_resolution(mut self, width: u32, height: u32) -> Self {
        self.width = width;
        self.height = height;
        self
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cornell() -> Camera {
        let vfov = 2.0 * (12.5f32 / 35.0).atan().to_degrees();
        Camera::look_at(Vec3::new(0.278, 0.273, -0.8), Vec3::new(0.278, 0.273, 0.0), Vec3::Y, vfov, 256, 256)
            .unwrap()
    }

    #[test]
    fn centre_and_corners_follow_the_convention() {
        let c = cornell();
        let centre = c.ray(128.0, 128.0);
        assert!((centre.dir - Vec3::Z).length() < 1e-6);
        // Looking along +Z with +Y up, the right vector is -X: the red wall (x ~ 0.556) is on
        // the left of the image.
        assert!((c.right - Vec3::new(-1.0, 0.0, 0.0)).length() < 1e-6);
        let top_left = c.ray(0.0, 0.0).dir;
        assert!(top_left.x > 0.0 && top_left.y > 0.0);
        // The vertical half angle is vfov / 2.
        let top = c.ray(128.0, 0.0).dir;
        assert!((top.y / top.z - 12.5 / 35.0).abs() < 1e-5);
    }

    #[test]
    fn degenerate_frames_are_refused() {
        assert!(Camera::look_at(Vec3::ZERO, Vec3::ZERO, Vec3::Y, 40.0, 8, 8).is_none());
        assert!(Camera::look_at(Vec3::ZERO, Vec3::Y, Vec3::Y, 40.0, 8, 8).is_none());
        assert!(Camera::look_at(Vec3::ZERO, Vec3::Z, Vec3::Y, 180.0, 8, 8).is_none());
        assert!(Camera::look_at(Vec3::ZERO, Vec3::Z, Vec3::Y, 40.0, 0, 8).is_none());
    }
}
