//! RNG-agnostic sample warps: every function maps uniform numbers in `[0, 1)` to a point or a
//! direction and has a matching density, so callers may feed stratified, low-discrepancy or plain
//! pseudo-random numbers alike.
//!
//! Sources: pbrt-v4 (Pharr, Jakob, Humphreys), chapters A.5 "Sampling multidimensional functions"
//! and 13.4 "Multiple importance sampling"; Duff et al., "Building an Orthonormal Basis,
//! Revisited" (JCGT 2017); Shirley & Chiu, "A Low Distortion Map Between Disk and Square" (1997);
//! Heitz, "A Low-Distortion Map Between Triangle and Square" (2019); Veach's power heuristic.
//!
//! Directions from the hemisphere/cone warps are in a local frame with `+z` as the axis; use
//! [`Frame`] to bring them to world space.

use glam::{Vec2, Vec3};
use std::f32::consts::{FRAC_1_PI, FRAC_PI_2, FRAC_PI_4, PI};

/// The largest `f32` below one; uniforms are clamped to it so that `u = 1` never escapes a range.
pub const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

/// Two unit vectors `(s, t)` such that `(s, t, n)` is a right-handed orthonormal basis, for unit
/// `n` (Duff et al. 2017, branchless).
#[inline]
pub fn coordinate_system(n: Vec3) -> (Vec3, Vec3) {
    let sign = 1.0f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x), Vec3::new(b, sign + n.y * n.y * a, -n.y))
}

/// An orthonormal frame; `n` is the local `+z` axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    pub s: Vec3,
    pub t: Vec3,
    pub n: Vec3,
}

impl Frame {
    /// The frame whose `z` axis is the unit vector `n`.
    #[inline]
    pub fn from_z(n: Vec3) -> Self {
        let (s, t) = coordinate_system(n);
        Frame { s, t, n }
    }

    /// World → local coordinates.
    #[inline]
    pub fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.s), v.dot(self.t), v.dot(self.n))
    }

    /// Local → world coordinates.
    #[inline]
    pub fn from_local(&self, v: Vec3) -> Vec3 {
        v.x * self.s + v.y * self.t + v.z * self.n
    }
}

/// The unit vector with polar angle given by `(sin_theta, cos_theta)` and azimuth `phi`.
#[inline]
pub fn spherical_direction(sin_theta: f32, cos_theta: f32, phi: f32) -> Vec3 {
    let sin_theta = sin_theta.clamp(-1.0, 1.0);
    Vec3::new(sin_theta * phi.cos(), sin_theta * phi.sin(), cos_theta.clamp(-1.0, 1.0))
}

/// Uniform direction on the unit sphere; density [`uniform_sphere_pdf`].
#[inline]
pub fn sample_uniform_sphere(u: [f32; 2]) -> Vec3 {
    let z = 1.0 - 2.0 * u[0];
    let r = (1.0 - z * z).max(0.0).sqrt();
    spherical_direction(r, z, 2.0 * PI * u[1])
}

/// `1 / (4 pi)`.
#[inline]
pub fn uniform_sphere_pdf() -> f32 {
    0.25 * FRAC_1_PI
}

/// Uniform direction on the `z >= 0` hemisphere; density [`uniform_hemisphere_pdf`].
#[inline]
pub fn sample_uniform_hemisphere(u: [f32; 2]) -> Vec3 {
    let z = u[0];
    let r = (1.0 - z * z).max(0.0).sqrt();
    spherical_direction(r, z, 2.0 * PI * u[1])
}

/// `1 / (2 pi)`.
#[inline]
pub fn uniform_hemisphere_pdf() -> f32 {
    0.5 * FRAC_1_PI
}

/// Uniform point on the unit disk by the concentric map (Shirley & Chiu 1997); density `1 / pi`.
#[inline]
pub fn sample_uniform_disk_concentric(u: [f32; 2]) -> Vec2 {
    let o = Vec2::new(2.0 * u[0] - 1.0, 2.0 * u[1] - 1.0);
    if o == Vec2::ZERO {
        return Vec2::ZERO;
    }
    let (r, theta) = if o.x.abs() > o.y.abs() {
        (o.x, FRAC_PI_4 * (o.y / o.x))
    } else {
        (o.y, FRAC_PI_2 - FRAC_PI_4 * (o.x / o.y))
    };
    r * Vec2::new(theta.cos(), theta.sin())
}

/// Cosine-distributed direction on the `z >= 0` hemisphere (Malley's method: a concentric disk
/// point lifted to the hemisphere); density [`cosine_hemisphere_pdf`].
#[inline]
pub fn sample_cosine_hemisphere(u: [f32; 2]) -> Vec3 {
    let d = sample_uniform_disk_concentric(u);
    let z = (1.0 - d.x * d.x - d.y * d.y).max(0.0).sqrt();
    Vec3::new(d.x, d.y, z)
}

/// `cos_theta / pi` (zero below the horizon).
#[inline]
pub fn cosine_hemisphere_pdf(cos_theta: f32) -> f32 {
    cos_theta.max(0.0) * FRAC_1_PI
}

/// Uniform direction in the cone of directions within angle `acos(cos_theta_max)` of `+z`;
/// density [`uniform_cone_pdf`].
#[inline]
pub fn sample_uniform_cone(u: [f32; 2], cos_theta_max: f32) -> Vec3 {
    let cos_theta = (1.0 - u[0]) + u[0] * cos_theta_max;
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    spherical_direction(sin_theta, cos_theta, 2.0 * PI * u[1])
}

/// `1 / (2 pi (1 - cos_theta_max))`, the density inside the cone.
#[inline]
pub fn uniform_cone_pdf(cos_theta_max: f32) -> f32 {
    1.0 / (2.0 * PI * (1.0 - cos_theta_max))
}

/// Uniformly distributed barycentrics `[b0, b1, b2]` on a triangle (Heitz 2019, as in pbrt-v4);
/// the point `b0 p0 + b1 p1 + b2 p2` has area density `1 / area`.
#[inline]
pub fn sample_uniform_triangle(u: [f32; 2]) -> [f32; 3] {
    let (b0, b1) = if u[0] < u[1] {
        let b0 = u[0] / 2.0;
        (b0, u[1] - b0)
    } else {
        let b1 = u[1] / 2.0;
        (u[0] - b1, b1)
    };
    [b0, b1, 1.0 - b0 - b1]
}

/// Veach's power heuristic (beta = 2) for `nf` samples from density `f_pdf` combined with `ng`
/// samples from `g_pdf`: the weight of the `f` sample.
#[inline]
pub fn power_heuristic(nf: f32, f_pdf: f32, ng: f32, g_pdf: f32) -> f32 {
    let f = nf * f_pdf;
    let g = ng * g_pdf;
    if f.is_infinite() {
        return 1.0;
    }
    let (f2, g2) = (f * f, g * g);
    if f2 + g2 > 0.0 {
        f2 / (f2 + g2)
    } else {
        0.0
    }
}

/// A piecewise-constant discrete distribution over `n` non-negative weights (pbrt-v4's
/// `PiecewiseConstant1D`, used here in its discrete form): picks index `i` with probability
/// `w_i / sum(w)`. Negative and non-finite weights count as zero; zero-weight entries are never
/// picked.
#[derive(Clone, Debug, Default)]
pub struct Distribution1D {
    func: Vec<f32>,
    cdf: Vec<f32>,
    /// `func[i] / total`, rounded once from `f64` (kept: a light sample reads it twice).
    pmf: Vec<f32>,
    total: f64,
}

impl Distribution1D {
    /// Builds the CDF (prefix sums in `f64`, so equal weights stay exactly equal).
    pub fn new(weights: &[f32]) -> Self {
        let func: Vec<f32> =
            weights.iter().map(|&w| if w.is_finite() && w > 0.0 { w } else { 0.0 }).collect();
        let mut prefix = Vec::with_capacity(func.len() + 1);
        let mut sum = 0.0f64;
        prefix.push(0.0);
        for &w in &func {
            sum += w as f64;
            prefix.push(sum);
        }
        let cdf = prefix.iter().map(|&c| if sum > 0.0 { (c / sum) as f32 } else { 0.0 }).collect();
        let pmf = func.iter().map(|&w| if sum > 0.0 { (w as f64 / sum) as f32 } else { 0.0 }).collect();
        Distribution1D { func, cdf, pmf, total: sum }
    }

    /// Number of entries.
    pub fn len(&self) -> usize {
        self.func.len()
    }

    /// Whether there are no entries.
    pub fn is_empty(&self) -> bool {
        self.func.is_empty()
    }

    /// Sum of the (clamped) weights.
    pub fn total(&self) -> f32 {
        self.total as f32
    }

    /// Probability of picking index `i` (zero out of range).
    pub fn pmf(&self, i: usize) -> f32 {
        self.pmf.get(i).copied().unwrap_or(0.0)
    }

    /// Picks an index; returns `(index, pmf, u_remapped)` where `u_remapped` is `u` rescaled to
    /// `[0, 1)` within the chosen entry's CDF interval (reusable as a fresh uniform). `None` when
    /// all weights are zero.
    #[inline]
    pub fn sample(&self, u: f32) -> Option<(usize, f32, f32)> {
        if self.total <= 0.0 {
            return None;
        }
        let u = u.clamp(0.0, ONE_MINUS_EPSILON);
        // First CDF entry > u, minus one: cdf[i] <= u < cdf[i + 1], so weight i is positive.
        let i = self.cdf.partition_point(|&c| c <= u).saturating_sub(1).min(self.func.len() - 1);
        let (lo, hi) = (self.cdf[i], self.cdf[i + 1]);
        let u_remapped = if hi > lo { ((u - lo) / (hi - lo)).clamp(0.0, ONE_MINUS_EPSILON) } else { 0.0 };
        Some((i, self.pmf[i], u_remapped))
    }
}

/// The 2D Halton point `i` (radical inverses in bases 2 and 3), shifted by `offset` modulo 1
/// (a Cranley-Patterson rotation). Every prefix of the sequence is well stratified, so camera
/// samples spread over several passes of a progressive render cover the pixel as evenly as
/// those of one pass.
#[inline]
pub fn halton2(i: u64, offset: [f32; 2]) -> [f32; 2] {
    let wrap = |u: f64, o: f32| {
        let v = (u + o as f64).fract() as f32;
        v.min(ONE_MINUS_EPSILON)
    };
    [wrap(radical_inverse_2(i), offset[0]), wrap(radical_inverse_3(i), offset[1])]
}

/// Dimensions 3 and 4 of the Halton sequence point `i` (radical inverses in bases 5 and 7),
/// shifted by `offset` modulo 1: with [`halton2`] at the same `i`, a 4D Halton point, so a
/// pixel's lens samples are stratified jointly with its film positions.
#[inline]
pub fn halton2_lens(i: u64, offset: [f32; 2]) -> [f32; 2] {
    let wrap = |u: f64, o: f32| {
        let v = (u + o as f64).fract() as f32;
        v.min(ONE_MINUS_EPSILON)
    };
    [wrap(radical_inverse(5, i), offset[0]), wrap(radical_inverse(7, i), offset[1])]
}

/// The base-`base` digits of `i` mirrored about the point.
#[inline]
pub fn radical_inverse(base: u64, mut i: u64) -> f64 {
    let (mut reversed, mut scale) = (0u64, 1.0f64);
    while i > 0 {
        reversed = reversed * base + i % base;
        scale /= base as f64;
        i /= base;
    }
    reversed as f64 * scale
}

/// Van der Corput: the bits of `i` mirrored about the binary point.
#[inline]
pub fn radical_inverse_2(i: u64) -> f64 {
    i.reverse_bits() as f64 * (1.0 / 18_446_744_073_709_551_616.0)
}

/// The base-3 digits of `i` mirrored about the point: [`radical_inverse`] in base 3 bit for
/// bit (the same integer, scaled by the same repeated division), six digits at a time from
/// tables instead of one at a time (a camera sample's position took some 48 instructions of
/// divisions by 3).
#[inline]
pub fn radical_inverse_3(mut i: u64) -> f64 {
    let mut reversed = 0u64;
    let mut digits = 0;
    while i >= BASE3_CHUNK {
        reversed = reversed * BASE3_CHUNK + u64::from(BASE3_FULL[(i % BASE3_CHUNK) as usize]);
        digits += 6;
        i /= BASE3_CHUNK;
    }
    // The last (most significant) digits, leading zeros left out as the digit loop leaves them.
    let (rest, n, shift) = BASE3_PART[i as usize];
    reversed = reversed * u64::from(shift) + u64::from(rest);
    reversed as f64 * BASE3_SCALE[digits + n as usize]
}

/// Six base-3 digits.
const BASE3_CHUNK: u64 = 729;

/// The base-3 digits of `i` mirrored, at least `width` of them (leading zeros counted), as the
/// digit loop of [`radical_inverse`] makes them: the number and how many digits.
const fn mirror3(mut i: u64, width: u32) -> (u64, u32) {
    let (mut r, mut n) = (0, 0);
    while i > 0 || n < width {
        r = r * 3 + i % 3;
        i /= 3;
        n += 1;
    }
    (r, n)
}

/// `v < 729` as six base-3 digits (leading zeros included), mirrored.
const BASE3_FULL: [u16; 729] = {
    let mut table = [0u16; 729];
    let mut v = 0;
    while v < 729 {
        table[v] = mirror3(v as u64, 6).0 as u16;
        v += 1;
    }
    table
};

/// `v < 729` as its significant base-3 digits, mirrored, how many there are and `3^` that.
const BASE3_PART: [(u16, u8, u16); 729] = {
    let mut table = [(0u16, 0u8, 1u16); 729];
    let mut v = 0;
    while v < 729 {
        let (r, n) = mirror3(v as u64, 0);
        table[v] = (r as u16, n as u8, 3u16.pow(n));
        v += 1;
    }
    table
};

/// `3^-n` as the digit loop makes it (1 divided by 3, `n` times), for every digit count of a
/// `u64`.
const BASE3_SCALE: [f64; 42] = {
    let mut table = [1.0f64; 42];
    let mut n = 1;
    while n < 42 {
        table[n] = table[n - 1] / 3.0;
        n += 1;
    }
    table
};

/// A well-mixed 64-bit seed from three values (SplitMix64 finaliser): how every generator of a
/// render is seeded from the render's seed, a constant naming its purpose, and the index of its
/// piece of work, so that images do not depend on how work is split among threads.
pub fn derive_seed(a: u64, b: u64, c: u64) -> u64 {
    let mut z = a ^ b.rotate_left(21) ^ c.rotate_left(42) ^ 0x9E37_79B9_7F4A_7C15;
    for _ in 0..2 {
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
    }
    z
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(n: usize) -> impl Iterator<Item = [f32; 2]> {
        (0..n * n).map(move |k| [((k % n) as f32 + 0.5) / n as f32, ((k / n) as f32 + 0.5) / n as f32])
    }

    #[test]
    fn basis_is_orthonormal_for_any_normal() {
        for u in grid(20).chain([[0.0, 0.0], [0.999, 0.5], [0.5, 0.0]]) {
            let n = sample_uniform_sphere(u);
            let f = Frame::from_z(n);
            for (a, b) in [(f.s, f.t), (f.s, f.n), (f.t, f.n)] {
                assert!(a.dot(b).abs() < 1e-5);
            }
            assert!((f.s.cross(f.t) - n).length() < 1e-5, "right-handed");
            let v = Vec3::new(0.3, -0.2, 0.9);
            assert!((f.to_local(f.from_local(v)) - v).length() < 1e-5);
        }
    }

    #[test]
    fn warps_land_in_their_domains_and_estimate_known_integrals() {
        let (mut cos_mean, mut hemi, mut sphere_z, mut disk_r2) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
        let n = 200;
        for u in grid(n) {
            let c = sample_cosine_hemisphere(u);
            assert!((c.length() - 1.0).abs() < 1e-5 && c.z >= 0.0);
            // E[cos] under the cosine density = int cos^2 / pi = 2/3.
            cos_mean += c.z as f64;
            let h = sample_uniform_hemisphere(u);
            hemi += h.z as f64; // E[cos] = 1/2
            let s = sample_uniform_sphere(u);
            sphere_z += (s.z * s.z) as f64; // E[z^2] = 1/3
            let d = sample_uniform_disk_concentric(u);
            assert!(d.length() <= 1.0 + 1e-6);
            disk_r2 += d.length_squared() as f64; // E[r^2] = 1/2
        }
        let m = (n * n) as f64;
        assert!((cos_mean / m - 2.0 / 3.0).abs() < 1e-3);
        assert!((cosine_hemisphere_pdf(0.5) - 0.5 / PI).abs() < 1e-7 && cosine_hemisphere_pdf(-0.1) == 0.0);
        assert!((hemi / m - 0.5).abs() < 1e-3);
        assert!((sphere_z / m - 1.0 / 3.0).abs() < 1e-3);
        assert!((disk_r2 / m - 0.5).abs() < 1e-3);
    }

    #[test]
    fn cone_stays_inside_and_triangle_is_uniform() {
        let cos_max = 0.8f32;
        let mut mean_b = [0.0f64; 3];
        for u in grid(100) {
            let d = sample_uniform_cone(u, cos_max);
            assert!(d.z >= cos_max - 1e-6 && (d.length() - 1.0).abs() < 1e-5);
            let b = sample_uniform_triangle(u);
            assert!(b.iter().all(|&x| (-1e-6..=1.0 + 1e-6).contains(&x)));
            for k in 0..3 {
                mean_b[k] += b[k] as f64 / 1e4;
            }
        }
        assert!((uniform_cone_pdf(cos_max) - 1.0 / (2.0 * PI * 0.2)).abs() < 1e-4);
        // The centroid of a uniform distribution on a triangle is (1/3, 1/3, 1/3).
        assert!(mean_b.iter().all(|&m| (m - 1.0 / 3.0).abs() < 1e-3), "{mean_b:?}");
    }

    #[test]
    fn power_heuristic_limits() {
        assert_eq!(power_heuristic(1.0, 1.0, 1.0, 1.0), 0.5);
        assert_eq!(power_heuristic(1.0, 0.0, 1.0, 0.0), 0.0);
        assert_eq!(power_heuristic(1.0, f32::INFINITY, 1.0, 3.0), 1.0);
        assert!((power_heuristic(1.0, 3.0, 1.0, 1.0) - 0.9).abs() < 1e-6);
    }

    #[test]
    fn distribution_picks_by_weight_and_skips_zeros() {
        let d = Distribution1D::new(&[0.0, 1.0, 0.0, 3.0, 0.0, -2.0, f32::NAN]);
        assert_eq!(d.total(), 4.0);
        assert_eq!(d.pmf(3), 0.75);
        assert_eq!(d.pmf(0), 0.0);
        let mut counts = [0usize; 7];
        for k in 0..4000 {
            let (i, pmf, ur) = d.sample((k as f32 + 0.5) / 4000.0).unwrap();
            assert_eq!(pmf, d.pmf(i));
            assert!((0.0..1.0).contains(&ur));
            counts[i] += 1;
        }
        assert_eq!(counts, [0, 1000, 0, 3000, 0, 0, 0]);
        assert_eq!(d.sample(0.0).unwrap().0, 1);
        assert_eq!(d.sample(1.0).unwrap().0, 3);
        assert!(Distribution1D::new(&[0.0, 0.0]).sample(0.5).is_none());
        assert!(Distribution1D::new(&[]).sample(0.5).is_none());
    }

    /// Every prefix of 2^a 3^b Halton points puts one point in each cell of the 2^a x 3^b grid.
    #[test]
    fn halton_prefixes_are_stratified() {
        for (a, b) in [(2u32, 1u32), (3, 2), (1, 3)] {
            let (nx, ny) = (1u64 << a, 3u64.pow(b));
            let mut seen = vec![false; (nx * ny) as usize];
            for i in 0..nx * ny {
                // In f64 with a nudge: points sit exactly on cell edges (k / 27, say).
                let (x, y) = (radical_inverse_2(i) + 1e-9, radical_inverse_3(i) + 1e-9);
                let cell = ((y * ny as f64) as u64 * nx + (x * nx as f64) as u64) as usize;
                assert!(!seen[cell], "{a} {b}: point {i} shares cell {cell}");
                seen[cell] = true;
            }
        }
        assert_eq!(radical_inverse_2(1), 0.5);
        assert!((radical_inverse_3(5) - (2.0 / 3.0 + 1.0 / 9.0)).abs() < 1e-12);
        let [x, y] = halton2(3, [0.9, 0.9]);
        assert!((0.0..1.0).contains(&x) && (0.0..1.0).contains(&y));
    }

    /// The lens dimensions (bases 5 and 7) are stratified as the film's are, and the generic
    /// radical inverse agrees with the base-3 one.
    #[test]
    fn halton_lens_dimensions_are_stratified() {
        let (nx, ny) = (25u64, 7u64);
        let mut seen = vec![false; (nx * ny) as usize];
        for i in 0..nx * ny {
            let (x, y) = (radical_inverse(5, i) + 1e-9, radical_inverse(7, i) + 1e-9);
            let cell = ((y * ny as f64) as u64 * nx + (x * nx as f64) as u64) as usize;
            assert!(!seen[cell], "point {i} shares cell {cell}");
            seen[cell] = true;
        }
        for i in [0, 1, 5, 12345, u64::MAX] {
            assert_eq!(radical_inverse(3, i), radical_inverse_3(i));
        }
        let [x, y] = halton2_lens(1, [0.0, 0.0]);
        assert!((x - 0.2).abs() < 1e-7 && (y - 1.0 / 7.0).abs() < 1e-7, "{x} {y}");
    }

    /// The tables' base-3 radical inverse is the digit loop's bit for bit: every index to a
    /// million (every sample of passes of 64 up to pass 15 000), around each power of 3 and
    /// spread over the range of 40 digits (where the digit loop's integer fits a `u64`).
    #[test]
    fn radical_inverse_3_is_the_digit_loop() {
        use rand::{Rng, SeedableRng};
        let same =
            |i: u64| assert_eq!(radical_inverse(3, i).to_bits(), radical_inverse_3(i).to_bits(), "{i}");
        (0..1_000_000).for_each(same);
        for k in 1..40u32 {
            let p = 3u64.pow(k);
            (p - 2..=p + 2).for_each(same);
        }
        let mut rng = rand_pcg::Pcg64::seed_from_u64(3);
        (0..100_000).for_each(|_| same(rng.gen_range(0..3u64.pow(40)) >> rng.gen_range(0..64)));
    }
}
