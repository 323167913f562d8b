//! Watertight ray-triangle intersection (Woop, Benthin, Wald, "Watertight Ray/Triangle
//! Intersection", JCGT 2(1), 2013).
//!
//! The ray is sheared so that it runs along +z from the origin; the triangle's 2D edge functions
//! are then evaluated in that frame. Neighbouring triangles evaluate their shared edge with the
//! same operands, so a ray through an edge or vertex is never missed by both (no leaks), and
//! edge functions that round to zero are recomputed in double precision.

use glam::{Vec3, Vec4};

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
    /// The origin's components, each splatted over four lanes, for [`Self::intersect4`].
    org4: [Vec4; 3],
}

/// Four triangles in structure-of-arrays layout for [`WatertightRay::intersect4`]:
/// `v[corner][axis]` holds that coordinate of that corner of the four triangles, one per lane.
/// Fewer than four triangles are padded by repeating the last one, which can never win a
/// closest-hit test against itself (hits must be strictly closer).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Tri4 {
    pub v: [[Vec4; 3]; 3],
}

impl Tri4 {
    /// Packs one to four triangles (padding with the last one).
    pub fn new(tris: &[[Vec3; 3]]) -> Self {
        assert!((1..=4).contains(&tris.len()), "a Tri4 holds one to four triangles");
        let lane = |i: usize| tris[i.min(tris.len() - 1)];
        let mut v = [[Vec4::ZERO; 3]; 3];
        for (corner, axes) in v.iter_mut().enumerate() {
            for (axis, a) in axes.iter_mut().enumerate() {
                *a = Vec4::from_array(std::array::from_fn(|i| lane(i)[corner][axis]));
            }
        }
        Tri4 { v }
    }

    /// The triangle in lane `i`.
    pub fn get(&self, i: usize) -> [Vec3; 3] {
        self.v.map(|c| Vec3::new(c[0][i], c[1][i], c[2][i]))
    }
}

/// The result of [`WatertightRay::intersect4`]: a bit per lane that hits within the interval,
/// and per-lane values to finish a lane's hit with [`Hit4::get`].
#[derive(Clone, Copy, Debug)]
pub struct Hit4 {
    pub mask: u32,
    t: Vec4,
    inv: Vec4,
    v: Vec4,
    w: Vec4,
}

impl Hit4 {
    /// The hit distance in lane `i` (meaningful if bit `i` of `mask` is set).
    #[inline(always)]
    pub fn t(&self, i: usize) -> f32 {
        self.t[i]
    }

    /// The hit in lane `i`, bit for bit what [`WatertightRay::intersect`] returns for that triangle.
    #[inline(always)]
    pub fn get(&self, i: usize) -> TriHit {
        let inv = self.inv[i];
        TriHit { t: self.t[i], u: self.v[i] * inv, v: self.w[i] * inv }
    }

    /// The closest hit lane (the first of equally close ones), as [`WatertightRay::intersect`]
    /// on the lanes in order with a shrinking interval would pick it.
    #[inline(always)]
    pub fn closest(&self) -> Option<usize> {
        self.closest_in(self.mask)
    }

    /// [`Hit4::closest`] among the lanes of `mask` (a subset of [`Hit4::mask`]).
    #[inline(always)]
    pub fn closest_in(&self, mask: u32) -> Option<usize> {
        let mut best: Option<(usize, f32)> = None;
        let mut m = mask;
        while m != 0 {
            let i = m.trailing_zeros() as usize;
            m &= m - 1;
            let t = self.t[i];
            if best.is_none_or(|(_, bt)| t < bt) {
                best = Some((i, t));
            }
        }
        best.map(|(i, _)| i)
    }
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
        let org4 = [Vec4::splat(org.x), Vec4::splat(org.y), Vec4::splat(org.z)];
        WatertightRay { org, kx, ky, kz, sx: dir[kx] * sz, sy: dir[ky] * sz, sz, org4 }
    }

    /// [`Self::intersect`] on four triangles at once, lane by lane with the same operations in
    /// the same order (no fused multiply-adds), so every lane's result is bit for bit that of
    /// `intersect` on the lane's triangle (a test below checks it).
    #[inline(always)]
    pub fn intersect4(&self, tri: &Tri4, t_min: f32, t_max: f32) -> Hit4 {
        let (kx, ky, kz) = (self.kx, self.ky, self.kz);
        let o = &self.org4;
        let [p0, p1, p2] = &tri.v;
        let (a_x, a_y, a_z) = (p0[kx] - o[kx], p0[ky] - o[ky], p0[kz] - o[kz]);
        let (b_x, b_y, b_z) = (p1[kx] - o[kx], p1[ky] - o[ky], p1[kz] - o[kz]);
        let (c_x, c_y, c_z) = (p2[kx] - o[kx], p2[ky] - o[ky], p2[kz] - o[kz]);
        let (sx, sy) = (Vec4::splat(self.sx), Vec4::splat(self.sy));
        let ax = a_x - sx * a_z;
        let ay = a_y - sy * a_z;
        let bx = b_x - sx * b_z;
        let by = b_y - sy * b_z;
        let cx = c_x - sx * c_z;
        let cy = c_y - sy * c_z;
        let mut u = cx * by - cy * bx;
        let mut v = ax * cy - ay * cx;
        let mut w = bx * ay - by * ax;
        let zero = Vec4::ZERO;
        let any_zero = u.cmpeq(zero) | v.cmpeq(zero) | w.cmpeq(zero);
        if any_zero.any() {
            // Rare: recompute the lanes with a zero edge function in double precision.
            let bits = any_zero.bitmask();
            let (mut ua, mut va, mut wa) = (u.to_array(), v.to_array(), w.to_array());
            for i in 0..4 {
                if bits & (1 << i) != 0 {
                    let (ax, ay, bx, by, cx, cy) =
                        (ax[i] as f64, ay[i] as f64, bx[i] as f64, by[i] as f64, cx[i] as f64, cy[i] as f64);
                    ua[i] = (cx * by - cy * bx) as f32;
                    va[i] = (ax * cy - ay * cx) as f32;
                    wa[i] = (bx * ay - by * ax) as f32;
                }
            }
            (u, v, w) = (Vec4::from_array(ua), Vec4::from_array(va), Vec4::from_array(wa));
        }
        let neg = u.cmplt(zero) | v.cmplt(zero) | w.cmplt(zero);
        let pos = u.cmpgt(zero) | v.cmpgt(zero) | w.cmpgt(zero);
        let det = u + v + w;
        // `|det| < inf` is false for infinities and NaN: `det.is_finite()` per lane.
        let reject = (neg & pos) | det.cmpeq(zero) | !det.abs().cmplt(Vec4::INFINITY);
        let sz = Vec4::splat(self.sz);
        let az = sz * a_z;
        let bz = sz * b_z;
        let cz = sz * c_z;
        let t_scaled = u * az + v * bz + w * cz;
        let inv = Vec4::ONE / det;
        let t = t_scaled * inv;
        let inside = t.cmpgt(Vec4::splat(t_min)) & t.cmplt(Vec4::splat(t_max));
        let mask = (inside & !reject).bitmask();
        Hit4 { mask, t, inv, v, w }
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

    /// `intersect4` must agree bit for bit with `intersect`, lane by lane, including rays
    /// through edges and vertices (the double-precision fallback) and degenerate triangles.
    #[test]
    fn intersect4_is_bit_identical() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_pcg::Pcg64::seed_from_u64(7);
        let mut p =
            || Vec3::new(rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0));
        let mut lanes_hit = 0;
        for k in 0..20_000 {
            let mut tris: Vec<[Vec3; 3]> = (0..4).map(|_| [p(), p(), p()]).collect();
            if k % 7 == 0 {
                tris[1] = [tris[0][0], tris[0][2], p()]; // a shared edge
                tris[3] = [tris[2][0], tris[2][0], tris[2][1]]; // degenerate
            }
            if k % 11 == 0 {
                // Axis-aligned triangles with coordinates exactly on small grids.
                tris[2] = [Vec3::ZERO, Vec3::X, Vec3::Y];
            }
            let org = p() * 3.0;
            // Aim at a vertex, an edge midpoint or a random point of one of the triangles.
            let tri = tris[k % 4];
            let target = match k % 3 {
                0 => tri[0],
                1 => 0.5 * (tri[1] + tri[2]),
                _ => tri[0] + 0.3 * (tri[1] - tri[0]) + 0.2 * (tri[2] - tri[0]),
            };
            let mut dir = target - org;
            if k % 13 == 0 {
                dir.x = 0.0;
            }
            if dir == Vec3::ZERO {
                continue;
            }
            let r = WatertightRay::new(org, dir);
            let (t_min, t_max) = if k % 5 == 0 { (0.2, 0.9) } else { (0.0, f32::INFINITY) };
            let h4 = r.intersect4(&Tri4::new(&tris), t_min, t_max);
            for (i, t) in tris.iter().enumerate() {
                let one = r.intersect(t[0], t[1], t[2], t_min, t_max);
                let lane = (h4.mask & (1 << i) != 0).then(|| h4.get(i));
                let bits = |h: Option<TriHit>| h.map(|h| (h.t.to_bits(), h.u.to_bits(), h.v.to_bits()));
                assert_eq!(bits(lane), bits(one), "case {k} lane {i}");
                lanes_hit += usize::from(one.is_some());
            }
        }
        assert!(lanes_hit > 5_000, "the test rays should mostly hit ({lanes_hit})");
    }

    #[test]
    fn degenerate_triangles_never_hit() {
        let r = WatertightRay::new(Vec3::new(0.5, 0.0, -1.0), Vec3::Z);
        assert!(r.intersect(Vec3::ZERO, Vec3::X, Vec3::X * 2.0, 0.0, f32::INFINITY).is_none());
        assert!(r.intersect(Vec3::ZERO, Vec3::ZERO, Vec3::ZERO, 0.0, f32::INFINITY).is_none());
    }
}
