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

/// `gamma(n) = n u / (1 - n u)` with `u = 2^-24`: the relative error bound of `n` rounded float
/// operations (Higham; pbrt's `gamma`).
#[inline]
pub const fn gamma(n: i32) -> f32 {
    let u = f32::EPSILON * 0.5;
    n as f32 * u / (1.0 - n as f32 * u)
}

/// Rounding-error bound of a point interpolated from triangle corners `v` with barycentrics
/// `b`: pbrt-v4's `gamma(7) (|b0 v0| + |b1 v1| + |b2 v2|)`. Any barycentrics give a point in
/// the triangle's plane, so the bound holds whichever intersector (Embree or the BVH) computed
/// them; their own error only moves the point within the plane.
#[inline]
pub fn barycentric_error(v: [Vec3; 3], b: [f32; 3]) -> Vec3 {
    gamma(7) * ((b[0] * v[0]).abs() + (b[1] * v[1]).abs() + (b[2] * v[2]).abs())
}

/// How far [`offset_ray_origin`] moves `p` along `n`, before its final rounding (which adds at
/// most one float per coordinate).
#[inline]
pub fn offset_distance(p: Vec3, err: Vec3, n: Vec3) -> f32 {
    // (1e-30: a point exactly at the world origin still moves, by a normal float.)
    n.abs().dot(err).max(gamma(7) * p.abs().max_element()).max(1e-30)
}

/// Moves `p`, a point on a surface with unit normal `n` and absolute error bound `err`, off the
/// surface to the side `n` points to (pbrt-v4 `OffsetRayOrigin`, Pharr, Jakob & Humphreys,
/// *Physically Based Rendering*, 4th ed., 6.8.6): by `|n| . err` along `n`, then each moved
/// coordinate rounded one more float away, so the new origin is certainly on that side of the
/// true surface. The offset scales with the coordinates' magnitude, so it works the same at any
/// world scale and any distance from the origin. Flip `n` to leave on the other side.
///
/// The move is at least `gamma(7) max|p|`: where the error bound vanishes (a point exactly on
/// the plane x = 0) an intersector's own rounding, proportional to the coordinates, could
/// still report the surface it leaves; Embree has no conservative `t` bound to reject it.
#[inline]
pub fn offset_ray_origin(p: Vec3, err: Vec3, n: Vec3) -> Vec3 {
    let offset = offset_distance(p, err, n) * n;
    let po = p + offset;
    Vec3::new(away(po.x, offset.x), away(po.y, offset.y), away(po.z, offset.z))
}

/// `v` moved one float up where `dir > 0` ([`next_float_up`]), down where `dir < 0`
/// ([`next_float_down`]), and left where `dir` is zero or NaN: the same floats, chosen by
/// selects instead of branches (the sign of a normal's coordinate, which picks the way, is
/// anyone's guess from one hit to the next).
#[inline(always)]
fn away(v: f32, dir: f32) -> f32 {
    let down = dir < 0.0;
    // Down is up from the negation, negated back.
    let w = if down { -v } else { v };
    let b = w.to_bits();
    // -0 goes up as +0 does.
    let b = if b == 0x8000_0000 { 0 } else { b };
    let stepped = if b >> 31 == 0 { b.wrapping_add(1) } else { b.wrapping_sub(1) };
    let kept = w.is_nan() || w == f32::INFINITY;
    let up = f32::from_bits(if kept { w.to_bits() } else { stepped });
    let moved = if down { -up } else { up };
    if down || dir > 0.0 {
        moved
    } else {
        v
    }
}

/// The smallest float greater than `v` (infinity and NaN unchanged; -0 goes to the smallest
/// positive subnormal).
#[inline]
pub fn next_float_up(v: f32) -> f32 {
    if v.is_infinite() && v > 0.0 || v.is_nan() {
        return v;
    }
    let v = if v == -0.0 { 0.0 } else { v };
    let bits = v.to_bits();
    f32::from_bits(if v >= 0.0 { bits + 1 } else { bits - 1 })
}

/// The largest float smaller than `v`.
#[inline]
pub fn next_float_down(v: f32) -> f32 {
    -next_float_up(-v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offset_clears_the_error_bound_at_every_scale_and_position() {
        for scale in [1e-4f32, 1e-2, 1.0, 1e3, 1e5] {
            for shift in [0.0f32, 1e5] {
                let v = [Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 0.0, 1.0)]
                    .map(|c| c * scale + Vec3::splat(shift));
                for b in [[0.2f32, 0.3, 0.5], [1.0, 0.0, 0.0], [0.001, 0.001, 0.998]] {
                    let p = b[0] * v[0] + b[1] * v[1] + b[2] * v[2];
                    let err = barycentric_error(v, b);
                    for n in [Vec3::Y, -Vec3::Y] {
                        let q = offset_ray_origin(p, err, n);
                        // The plane is y = shift: the new origin is strictly on the n side.
                        assert!((q.y - shift) * n.y > 0.0, "scale {scale} shift {shift}: {p} -> {q}");
                        // And close: within a few error bounds.
                        assert!(
                            (q - p).length()
                                <= 4.0 * err.length() + 4.0 * f32::EPSILON * p.abs().max_element()
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn moving_away_is_next_float_up_or_down() {
        let mut specials = vec![0.0f32, -0.0, f32::INFINITY, f32::NEG_INFINITY, f32::NAN, f32::MAX, f32::MIN];
        specials.extend([
            f32::MIN_POSITIVE,
            -f32::MIN_POSITIVE,
            f32::from_bits(1),
            -f32::from_bits(1),
            1.0,
            -1.0,
        ]);
        let mut x = 0x2545_F491u32;
        let mut values = specials.clone();
        for _ in 0..100_000 {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            values.push(f32::from_bits(x));
        }
        for &v in &values {
            for dir in [1.0f32, -1.0, 0.0, -0.0, 1e-30, -1e-30, f32::NAN] {
                let want = if dir > 0.0 {
                    next_float_up(v)
                } else if dir < 0.0 {
                    next_float_down(v)
                } else {
                    v
                };
                let got = away(v, dir);
                assert!(
                    got.to_bits() == want.to_bits() || got.is_nan() && want.is_nan(),
                    "{v:e} {dir}: {got:e} {want:e}"
                );
            }
        }
    }

    #[test]
    fn next_float() {
        assert!(next_float_up(1.0) > 1.0 && next_float_down(1.0) < 1.0);
        assert!(next_float_up(-0.0) > 0.0 && next_float_down(0.0) < 0.0);
        assert_eq!(next_float_up(f32::INFINITY), f32::INFINITY);
        assert!(next_float_up(-1.0) > -1.0);
        // The cases Embree's closed ray interval relies on (`accel::embree`): either zero goes
        // to the smallest subnormal, an infinite end to the largest finite float, NaN stays NaN.
        assert_eq!(next_float_up(0.0).to_bits(), 1);
        assert_eq!(next_float_up(-0.0).to_bits(), 1);
        assert_eq!(next_float_down(f32::INFINITY), f32::MAX);
        assert_eq!(next_float_up(f32::NEG_INFINITY), f32::MIN);
        assert!(next_float_up(f32::NAN).is_nan() && next_float_down(f32::NAN).is_nan());
    }

    #[test]
    fn ray_at() {
        let r = Ray::new(Vec3::ONE, Vec3::X);
        assert_eq!(r.at(2.0), Vec3::new(3.0, 1.0, 1.0));
        assert_eq!(r.t_max, f32::INFINITY);
    }
}
