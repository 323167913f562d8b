//! Watertight ray-triangle intersection (Woop, Benthin, Wald, "Watertight Ray/Triangle
//! Intersection", JCGT 2(1), 2013).
//!
//! The ray is sheared so that it runs along +z from the origin; the triangle's 2D edge functions
//! are then evaluated in that frame. Neighbouring triangles evaluate their shared edge with the
//! same operands, so a ray through an edge or vertex is never missed by both (no leaks), and
//! edge functions that round to zero are recomputed in double precision.

use glam::Vec3;

/// A ray prepared for repeated triangle tests: the shear and permutation are computed once.
#[derive(Clone, Copy, Debug)]
pub struct WatertightRay {
    org: Vec3,
    kx: usize,
    ky: usize,
    kz: usize,
    sx: f32,
    sy: f32,
    sz: f32,
}

/// A triangle hit: distance and Embree-convention barycentrics (`u` weights v1, `v` weights v2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriHit {
    pub t: f32,
    pub u: f32,
    pub v: f32,
}

impl WatertightRay {
    /// Prepares `org + t dir`. `dir` must be non-zero and finite.
    #[inline]
    pub fn new(org: Vec3, dir: Vec3) -> Self {
        let a = dir.abs();
        let kz = if a.x >= a.y && a.x >= a.z {
            0
        } else if a.y >= a.z {
            1
        } else {
            2
        };
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        if dir[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        let sz = 1.0 / dir[kz];
        WatertightRay { org, kx, ky, kz, sx: dir[kx] * sz, sy: dir[ky] * sz, sz }
    }

    /// Intersects the triangle `(v0, v1, v2)` (both faces) within `(t_min, t_max)`.
    #[inline]
    pub fn intersect(&self, v0: Vec3, v1: Vec3, v2: Vec3, t_min: f32, t_max: f32) -> Option<TriHit> {
        let (kx, ky, kz) = (self.kx, self.ky, self.kz);
        let a = v0 - self.org;
        let b = v1 - self.org;
        let c = v2 - self.org;
        let ax = a[kx] - self.sx * a[kz];
        let ay = a[ky] - self.sy * a[kz];
        let bx = b[kx] - self.sx * b[kz];
        let by = b[ky] - self.sy * b[kz];
        let cx = c[kx] - self.sx * c[kz];
        let cy = c[ky] - self.sy * c[kz];
        let mut u = cx * by - cy * bx;
        let mut v = ax * cy - ay * cx;
        let mut w = bx * ay - by * ax;
        if u == 0.0 || v == 0.0 || w == 0.0 {
            let (ax, ay, bx, by, cx, cy) = (ax as f64, ay as f64, bx as f64, by as f64, cx as f64, cy as f64);
            u = (cx * by - cy * bx) as f32;
            v = (ax * cy - ay * cx) as f32;
            w = (bx * ay - by * ax) as f32;
        }
        if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return None;
        }
        let det = u + v + w;
        if det == 0.0 || !det.is_finite() {
            return None;
        }
        let az = self.sz * a[kz];
        let bz = self.sz * b[kz];
        let cz = self.sz * c[kz];
        let t_scaled = u * az + v * bz + w * cz;
        let inv = 1.0 / det;
        let t = t_scaled * inv;
        if !(t > t_min && t < t_max) {
            return None;
        }
        Some(TriHit { t, u: v * inv, v: w * inv })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hits_centre_with_barycentrics() {
        let r = WatertightRay::new(Vec3::new(0.25, 0.25, -1.0), Vec3::Z);
        let h = r.intersect(Vec3::ZERO, Vec3::X, Vec3::Y, 0.0, f32::INFINITY).unwrap();
        assert!((h.t - 1.0).abs() < 1e-6);
        assert!((h.u - 0.25).abs() < 1e-6 && (h.v - 0.25).abs() < 1e-6);
        // Both faces, and the interval is respected.
        let back = WatertightRay::new(Vec3::new(0.25, 0.25, 1.0), -Vec3::Z);
        assert!(back.intersect(Vec3::ZERO, Vec3::X, Vec3::Y, 0.0, 2.0).is_some());
        assert!(back.intersect(Vec3::ZERO, Vec3::X, Vec3::Y, 0.0, 0.5).is_none());
        assert!(back.intersect(Vec3::ZERO, Vec3::X, Vec3::Y, 1.5, 2.0).is_none());
    }

    #[test]
    fn shared_edges_never_leak() {
        // A quad split along its diagonal; rays aimed exactly at points of the open diagonal
        // must hit at least one of the two triangles. (The diagonal's end points are corners of
        // the quad's outer boundary, where a ray may legitimately pass outside.)
        let (p0, p1, p2, p3) = (Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y);
        for i in 1..1000 {
            let s = i as f32 / 1000.0;
            let target = p0 + s * (p2 - p0);
            for org in
                [Vec3::new(0.3, -0.2, -1.0), Vec3::new(-2.0, 3.0, 1.7), Vec3::new(0.1, 0.1, 0.1 + 1e-3)]
            {
                let r = WatertightRay::new(org, target - org);
                let hit = r.intersect(p0, p1, p2, 0.0, 2.0).is_some()
                    || r.intersect(p0, p2, p3, 0.0, 2.0).is_some();
                assert!(hit, "leak at s = {s} from {org}");
            }
        }
    }

    #[test]
    fn degenerate_triangles_never_hit() {
        let r = WatertightRay::new(Vec3::new(0.5, 0.0, -1.0), Vec3::Z);
        assert!(r.intersect(Vec3::ZERO, Vec3::X, Vec3::X * 2.0, 0.0, f32::INFINITY).is_none());
        assert!(r.intersect(Vec3::ZERO, Vec3::ZERO, Vec3::ZERO, 0.0, f32::INFINITY).is_none());
    }
}
