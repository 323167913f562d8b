//! Rays and robust origin offsets.

use glam::Vec3;

/// A ray `origin + t * dir` for `t` in `[t_min, t_max]`. `dir` need not be normalised; hit
/// distances are in units of `dir`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    pub origin: Vec3,
    pub dir: Vec3,
    pub t_min: f32,
    pub t_max: f32,
}

impl Ray {
    /// A ray over `[0, inf)`.
    pub fn new(origin: Vec3, dir: Vec3) -> Self {
        Ray { origin, dir, t_min: 0.0, t_max: f32::INFINITY }
    }

    /// A ray over `[t_min, t_max]`.
    pub fn segment(origin: Vec3, dir: Vec3, t_min: f32, t_max: f32) -> Self {
        Ray { origin, dir, t_min, t_max }
    }

    /// The point at parameter `t`.
    #[inline]
    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + t * self.dir
    }
}

const ORIGIN: f32 = 1.0 / 32.0;
const FLOAT_SCALE: f32 = 1.0 / 65536.0;
const INT_SCALE: f32 = 256.0;

/// Moves `p`, a point computed on a surface with geometric normal `n`, off that surface to the
/// side `n` points to (Wächter & Binder 2019). Flip `n` to leave on the other side.
///
/// Each coordinate is moved by `INT_SCALE * n` ULPs, so the offset grows with the magnitude of
/// the coordinate; near zero, where ULPs become tiny, a small absolute offset is used instead.
#[inline]
pub fn offset_ray_origin(p: Vec3, n: Vec3) -> Vec3 {
    #[inline]
    fn one(p: f32, n: f32) -> f32 {
        if p.abs() < ORIGIN {
            return p + FLOAT_SCALE * n;
        }
        let of_i = (INT_SCALE * n) as i32;
        let bits = p.to_bits() as i32;
        let moved = if p < 0.0 { bits - of_i } else { bits + of_i };
        f32::from_bits(moved as u32)
    }
    Vec3::new(one(p.x, n.x), one(p.y, n.y), one(p.z, n.z))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offset_moves_to_the_normal_side_at_every_scale() {
        for scale in [1e-4f32, 1e-2, 1.0, 1e3, 1e5] {
            for n in [Vec3::X, -Vec3::Y, Vec3::new(0.6, 0.0, 0.8), Vec3::new(-0.3, 0.9, -0.3).normalize()] {
                let p = Vec3::new(0.3, -0.7, 0.5) * scale;
                let q = offset_ray_origin(p, n);
                assert!((q - p).dot(n) > 0.0, "scale {scale} n {n}: {p} -> {q}");
                // The move is tiny relative to the coordinates.
                assert!((q - p).length() <= 1e-3 * scale.max(1.0), "scale {scale}: {p} -> {q}");
            }
        }
    }

    #[test]
    fn ray_at() {
        let r = Ray::new(Vec3::ONE, Vec3::X);
        assert_eq!(r.at(2.0), Vec3::new(3.0, 1.0, 1.0));
        assert_eq!(r.t_max, f32::INFINITY);
    }
}
