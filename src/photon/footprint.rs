//! The footprint of a gather disc: the part of it that the surface at its centre fills, as
//! far as probes cast onto the surface found it (the probing itself, which needs the scene's
//! rays, is the integrators': `integrator::probe`). Photons count only over a footprint, and an
//! estimate divides by its area: the geometry here keeps the two in agreement.

use super::kernel::kernel_integral;
use crate::config::Kernel;
use glam::{Vec2, Vec3};

/// Directions in which a surface point probes its surface, evenly spaced around it (eight:
/// [`Footprint::contains`] finds a point's wedge by halving the turn three times).
pub const PROBES: usize = 8;

/// How much wider than a gather's radius a surface is probed for walls and edges where later
/// discs nearby may be served by what it found (a progressive pixel's first point, a block of
/// irradiance sites): a later disc, about a point a little off the first, must fit inside.
pub const CLEAR: f32 = 1.5;

/// The least cosine between two points' normals for one's clear disc to serve the other
/// (26°).
const SAME_SURFACE_COS: f32 = 0.9;

/// The least part of its own disc a footprint is taken to fill (see `integrator::probe`).
pub const LEAST_SHARE: f32 = 1.0 / 16.0;

/// The part of a gather disc that the visible point's own surface fills, as far as rays cast
/// down onto the surface can tell: the disc cut back by the walls standing on the surface and
/// by the edges where it ends.
///
/// Where a wall stands on the surface within the gather radius (a room's corners and edges, a
/// block on the floor, a thin wall standing on it), or the surface ends (a block's top, a
/// slab's edge), the disc reaches past it: its part beyond holds no photons of this surface, so
/// photons over `π r²` made every edge too dark (by a missing strip about 0.15 r wide with the
/// flattened disc), and it may hold photons of the surface on a thin wall's far side (light
/// leaked under the wall).
///
/// In each of `PROBES` evenly spaced directions, turned by a random angle, a ray from a point
/// `r / √8` above the visible point (the flattened disc's half thickness) is aimed at the
/// surface where the disc's rim should be, and goes on to as deep below it. It meets a wall (a
/// surface at more than 60° to this one) at or before the rim: the footprint ends at the
/// wall's foot (pulled back by `r / 1000`, so that the wall's own photons, over its foot, stay
/// out). It meets a surface (within 60°) there: the surface reaches the rim in that direction.
/// It meets nothing, or a wall beyond the rim: the surface ends before the rim, and the aim is
/// halved (then moved a quarter back out if that finds it), two more rays at most. The
/// footprint is the disc within the polygon of the probes' end points; photons count only
/// over it and the estimate divides by its area (`share` of the disc's). Every end point lies
/// on the surface, so on a surface bounded by straight walls and convex edges the polygon
/// stays on it, whatever the number of probes, and the photons counted and the area agree
/// exactly; what it does not see are walls and edges between two probes that miss them.
#[derive(Clone, Copy)]
pub struct Footprint {
    /// Tangent frame: the polygon's coordinates are along these.
    pub(crate) t: [Vec3; 2],
    /// `(cos, sin)` of the angle of the first probe.
    pub(crate) turn: Vec2,
    /// The probes' end points, counter-clockwise, in the tangent frame.
    pub(crate) ends: [Vec2; PROBES],
    /// Whether some probe ended inside the rim (otherwise the footprint is the whole disc).
    pub(crate) cut: bool,
    /// The squared radius of the disc the footprint is cut from: the one asked for, or a
    /// sixteenth or a 256th of it where little of the larger disc lies on the surface and the
    /// smaller footprint is the larger.
    pub r2: f32,
    /// The footprint's area over the area `π r²` of the disc asked for, in `[0, 1]`.
    pub share: f32,
}

impl Footprint {
    /// The whole disc of squared radius `r2`.
    pub fn whole(r2: f32) -> Self {
        Footprint {
            t: [Vec3::X, Vec3::Y],
            turn: Vec2::X,
            ends: [Vec2::ZERO; PROBES],
            cut: false,
            r2,
            share: 1.0,
        }
    }

    /// The disc of squared radius `r2` cut by the polygon of `ends` (the probes' end points,
    /// counter-clockwise in the tangent frame `t`, the first at angle `theta0`, each
    /// `TAU / PROBES` from the last), some of which fell short of the rim.
    pub fn cut(t: [Vec3; 2], theta0: f32, ends: [Vec2; PROBES], r2: f32) -> Self {
        let r = r2.sqrt();
        let area: f32 = (0..PROBES).map(|j| wedge_area(ends[j], ends[(j + 1) % PROBES], r)).sum();
        let share = (area / (std::f32::consts::PI * r2)).clamp(0.0, 1.0);
        let (sin, cos) = theta0.sin_cos();
        Footprint { t, turn: Vec2::new(cos, sin), ends, cut: true, r2, share }
    }

    /// The footprint's weight under `kernel` over the weight of its whole disc (its own, of
    /// squared radius `r2`): with weights `kernel_weight(d² / r2)` summed over the photons
    /// over it, the estimate divides by `π r2` times this. For the box kernel, the footprint's
    /// area over its disc's; for the others, the kernel's radial integral out to the polygon,
    /// averaged over 64 directions (midpoints of eight in each probe's wedge). At least
    /// [`LEAST_SHARE`], as the probing floors a footprint's area.
    pub fn kernel_share(&self, kernel: Kernel) -> f32 {
        if !self.cut {
            return 1.0;
        }
        let r = self.r2.sqrt();
        let step = std::f32::consts::TAU / PROBES as f32;
        if kernel == Kernel::Box {
            let area: f32 =
                (0..PROBES).map(|j| wedge_area(self.ends[j], self.ends[(j + 1) % PROBES], r)).sum();
            return (area / (std::f32::consts::PI * self.r2)).clamp(LEAST_SHARE, 1.0);
        }
        const SUB: usize = 8;
        // The directions, turned on by step / SUB from half that past the first probe's.
        let by = |angle: f32| {
            let (sin, cos) = angle.sin_cos();
            Vec2::new(cos, sin)
        };
        let (mut u, advance) = (self.turn.rotate(by(0.5 * step / SUB as f32)), by(step / SUB as f32));
        let mut sum = 0.0;
        for j in 0..PROBES {
            let (a, b) = (self.ends[j], self.ends[(j + 1) % PROBES]);
            let edge = b - a;
            for _ in 0..SUB {
                // Where the direction meets the segment `a b`: a + s (b - a) = ρ u.
                let across = u.perp_dot(edge);
                let rho = if across > 0.0 {
                    (a.perp_dot(edge) / across).max(0.0)
                } else if a == Vec2::ZERO {
                    0.0 // both ends at the centre: an empty wedge
                } else {
                    r
                };
                sum += kernel_integral(kernel, (rho / r).min(1.0));
                u = u.rotate(advance);
            }
        }
        (sum / (PROBES * SUB) as f32).clamp(LEAST_SHARE, 1.0)
    }

    /// The footprint over the same surface within the disc of half the area (squared radius
    /// `r2 / 2`), its `share` likewise of half the disc this one's `share` is of (the requested
    /// one, before any shrinking by the probing), so that flux over `share` estimates
    /// the same radiance over `π r² / 2` as over `π r²`, less the bias of the larger disc.
    pub fn half(&self) -> Footprint {
        self.within(0.5)
    }

    /// The footprint over the same surface within the disc of `fraction` (in `(0, 1]`) of the
    /// area, its `share` of that disc (as [`Footprint::half`]).
    pub fn within(&self, fraction: f32) -> Footprint {
        let r2 = fraction * self.r2;
        if !self.cut {
            return Footprint { r2, ..*self };
        }
        let area = |r: f32| -> f32 {
            (0..PROBES).map(|j| wedge_area(self.ends[j], self.ends[(j + 1) % PROBES], r)).sum()
        };
        let outer = area(self.r2.sqrt());
        let ratio = if outer > 0.0 { area(r2.sqrt()) / outer } else { 0.0 };
        Footprint { r2, share: (self.share / fraction * ratio).clamp(0.0, 1.0), ..*self }
    }

    /// How far from the disc's centre the surface was found whole: the nearest of the probes'
    /// end points where a wall or an edge cut the disc, else the disc's radius.
    pub fn reach(&self) -> f32 {
        if !self.cut {
            return self.r2.sqrt();
        }
        self.ends.iter().map(|e| e.length()).fold(f32::INFINITY, f32::min)
    }

    /// Whether a photon at `offset` from the disc's centre lies over the footprint (its
    /// distance is the caller's test).
    #[inline]
    pub fn contains(&self, offset: Vec3) -> bool {
        if !self.cut {
            return true;
        }
        let q = Vec2::new(offset.dot(self.t[0]), offset.dot(self.t[1]));
        // The probe wedge it lies in: its direction turned back by the first probe's angle.
        let (c, s) = (self.turn.x, self.turn.y);
        let j = octant(Vec2::new(q.x * c + q.y * s, q.y * c - q.x * s));
        let (a, b) = (self.ends[j], self.ends[(j + 1) % PROBES]);
        (b - a).perp_dot(q - a) > 0.0
    }
}

/// A disc about a surface point that its probes found whole (no wall standing on it, no edge
/// within it): a disc within it about a point of the same surface needs no probes.
#[derive(Clone, Copy, Debug)]
pub struct Clear {
    p: Vec3,
    n: Vec3,
    r2: f32,
}

impl Clear {
    /// The footprint of the disc of squared radius `r2` about `p` (normal `n`): whole where
    /// `last` covers it; else probed `CLEAR` times wider (`probe(wide r2)`), cut back to `r2`,
    /// and kept in `last` where the probes found the wider disc whole, so that nearby discs on
    /// the same surface need no probes of their own.
    pub fn or_probe(
        last: &mut Option<Clear>,
        p: Vec3,
        n: Vec3,
        r2: f32,
        probe: impl FnOnce(f32) -> Footprint,
    ) -> Footprint {
        if last.is_some_and(|c| c.covers(p, n, r2)) {
            return Footprint::whole(r2);
        }
        let wide = probe(CLEAR * CLEAR * r2);
        if !wide.cut {
            *last = Some(Clear { p, n, r2: wide.r2 });
            return Footprint::whole(r2);
        }
        if wide.r2 <= r2 {
            wide
        } else {
            wide.within(r2 / wide.r2)
        }
    }

    /// Whether the disc of squared radius `r2` about `p`, normal `n`, lies within this one on
    /// the same surface (normals within 26°).
    pub fn covers(&self, p: Vec3, n: Vec3, r2: f32) -> bool {
        let reach = (p - self.p).length() + r2.sqrt();
        reach * reach <= self.r2 && n.dot(self.n) > SAME_SURFACE_COS
    }
}

/// The footprints of one surface point's gathers, one per photon map (the lecture's three
/// per-channel maps), each at its own radius: probed once, and cut down for the other maps
/// ([`Footprint::within`]). With several maps the first is probed `MARGIN` times wider than
/// asked, so that the others' radii, about the same, mostly fall within it.
pub struct Footprints<F> {
    probe: F,
    margin: f32,
    /// On each side (front, back): the squared radius probed, and what the probes found.
    probed: [Option<(f32, Footprint)>; 2],
}

/// How much wider (in squared radius) a point's first footprint is probed when several maps
/// will ask for theirs.
const MARGIN: f32 = 1.5;

impl<F: FnMut(bool, f32) -> Footprint> Footprints<F> {
    /// The footprints `probe(back, r2)` finds, for the gathers of `maps` maps.
    pub fn new(probe: F, maps: usize) -> Self {
        Footprints { probe, margin: if maps > 1 { MARGIN } else { 1.0 }, probed: [None, None] }
    }

    /// The footprint on the front (or with `back` the back) within the squared radius `r2`
    /// (or a smaller one, where the probing shrank the disc: its own `r2`).
    pub fn get(&mut self, back: bool, r2: f32) -> Footprint {
        let side = usize::from(back);
        let fp = match self.probed[side] {
            Some((asked, fp)) if r2 <= asked => fp,
            _ => {
                let asked = r2 * self.margin;
                let fp = (self.probe)(back, asked);
                self.probed[side] = Some((asked, fp));
                fp
            }
        };
        if fp.r2 <= r2 {
            fp
        } else {
            fp.within(r2 / fp.r2)
        }
    }
}

/// The eighth of a turn `[j π/4, (j + 1) π/4)` holding the direction of `p` (on a boundary,
/// either side's: the two wedges' tests agree along the probe between them).
#[inline]
fn octant(p: Vec2) -> usize {
    let (mut x, mut y, mut j) = (p.x, p.y, 0);
    if y < 0.0 {
        (x, y, j) = (-x, -y, 4);
    }
    if x <= 0.0 {
        (x, y) = (y, -x);
        j += 2;
    }
    if y >= x {
        j += 1;
    }
    j
}

/// The area of the disc of radius `r` about the origin within the triangle (origin, `a`, `b`),
/// `b` counter-clockwise from `a` by less than a half turn: the triangle's part of the segment
/// `a b` inside the disc, and circular sectors where it runs outside.
fn wedge_area(a: Vec2, b: Vec2, r: f32) -> f32 {
    let sector = |u: Vec2, v: Vec2| 0.5 * r * r * u.perp_dot(v).atan2(u.dot(v));
    let d = b - a;
    let (qa, qb, qc) = (d.dot(d), a.dot(d), a.dot(a) - r * r);
    let disc = qb * qb - qa * qc;
    if qa <= 0.0 || disc <= 0.0 {
        return if qa <= 0.0 { 0.0 } else { sector(a, b) };
    }
    let s = disc.sqrt();
    let t0 = ((-qb - s) / qa).clamp(0.0, 1.0);
    let t1 = ((-qb + s) / qa).clamp(0.0, 1.0);
    if t0 >= t1 {
        return sector(a, b);
    }
    let (p0, p1) = (a + t0 * d, a + t1 * d);
    // Outside the disc before `t0` and after `t1` (tested, not computed: the angle between a
    // point and itself, as `-0.0` and a rounded `0.0`, would be atan2(0, -0) = π).
    let before = if t0 > 0.0 { sector(a, p0) } else { 0.0 };
    let after = if t1 < 1.0 { sector(p1, b) } else { 0.0 };
    before + 0.5 * p0.perp_dot(p1) + after
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_pcg::Pcg32;

    /// The first probe's angle and the probes' end points of a random footprint of radius
    /// `r`: each probe reaches the rim (and beyond, to the polygon circumscribing the disc),
    /// stops at once, or stops anywhere between.
    fn random_probes(rng: &mut Pcg32, r: f32) -> (f32, [Vec2; PROBES]) {
        let step = std::f32::consts::TAU / PROBES as f32;
        let far = r / (0.5 * step).cos();
        let theta0 = rng.gen::<f32>() * step;
        let mut ends = [Vec2::ZERO; PROBES];
        for (j, end) in ends.iter_mut().enumerate() {
            let reach = match rng.gen_range(0..4) {
                0 => far,
                1 => 0.0,
                _ => rng.gen::<f32>() * far,
            };
            let (sin, cos) = (theta0 + step * j as f32).sin_cos();
            *end = Vec2::new(cos, sin) * reach;
        }
        (theta0, ends)
    }

    /// The footprint's area (`share`) is the share of the disc where `contains` says yes, for
    /// polygons of every kind (probes that reach the rim, stop at a wall, or find nothing), so
    /// that photons counted and area divided by agree: the estimate's unbiasedness rests on it.
    #[test]
    fn footprint_area_matches_what_it_contains() {
        let mut rng = Pcg32::seed_from_u64(3);
        let r = 0.7f32;
        let step = std::f32::consts::TAU / PROBES as f32;
        let far = r / (0.5 * step).cos();
        for case in 0..50 {
            let (theta0, ends) = random_probes(&mut rng, r);
            let area: f32 = (0..PROBES).map(|j| wedge_area(ends[j], ends[(j + 1) % PROBES], r)).sum();
            let share = area / (std::f32::consts::PI * r * r);
            let fp = Footprint::cut([Vec3::X, Vec3::Z], theta0, ends, r * r);
            assert!((fp.share - share).abs() < 1e-6);
            let n = 40_000;
            let mut inside = 0;
            for i in 0..n {
                // Stratified in radius and angle over the disc.
                let u = (i as f32 + 0.5) / n as f32;
                let (rho, phi) = (r * u.sqrt(), rng.gen::<f32>() * std::f32::consts::TAU);
                if fp.contains(Vec3::new(rho * phi.cos(), 0.3, rho * phi.sin())) {
                    inside += 1;
                }
            }
            let measured = inside as f32 / n as f32;
            assert!((measured - share).abs() < 0.01, "case {case}: share {share}, contains {measured}");
        }
        // Every probe at the rim or beyond: the whole disc.
        let full: f32 = (0..PROBES)
            .map(|j| {
                let (a, b) = (j as f32 * step, (j + 1) as f32 * step);
                wedge_area(Vec2::new(a.cos(), a.sin()) * far, Vec2::new(b.cos(), b.sin()) * far, r)
            })
            .sum();
        assert!((full / (std::f32::consts::PI * r * r) - 1.0).abs() < 1e-4, "{full}");
    }

    /// The wedge a direction falls in is the one its angle gives.
    #[test]
    fn octants_are_eighths_of_the_turn() {
        for k in 0..720 {
            let angle = (k as f32 + 0.25) * std::f32::consts::TAU / 720.0;
            let expect = (angle / (std::f32::consts::TAU / 8.0)) as usize;
            assert_eq!(octant(Vec2::new(angle.cos(), angle.sin()) * 3.0), expect, "{angle}");
        }
    }

    /// Under every kernel, the footprint's weighted share is the kernel's weight over what it
    /// contains (measured by sampling the disc), for the same kinds of polygons.
    #[test]
    fn kernel_share_is_the_weight_of_what_it_contains() {
        use super::super::kernel::kernel_weight;
        let mut rng = Pcg32::seed_from_u64(11);
        let r = 0.4f32;
        for kernel in [Kernel::Box, Kernel::Cone, Kernel::Gaussian] {
            for case in 0..30 {
                let (theta0, ends) = random_probes(&mut rng, r);
                let fp = Footprint::cut([Vec3::X, Vec3::Z], theta0, ends, r * r);
                let n = 40_000;
                let mut weight = 0.0f64;
                for i in 0..n {
                    let u = (i as f32 + 0.5) / n as f32;
                    let (rho, phi) = (r * u.sqrt(), rng.gen::<f32>() * std::f32::consts::TAU);
                    if fp.contains(Vec3::new(rho * phi.cos(), -0.1, rho * phi.sin())) {
                        weight += kernel_weight(kernel, u) as f64;
                    }
                }
                let measured = (weight / n as f64) as f32;
                let share = fp.kernel_share(kernel);
                let expect = measured.max(LEAST_SHARE);
                assert!((expect - share).abs() < 0.012, "{kernel:?} case {case}: {share} against {measured}");
                if kernel == Kernel::Box {
                    assert!((share - fp.share.max(LEAST_SHARE)).abs() < 1e-6);
                }
            }
            assert_eq!(Footprint::whole(0.3).kernel_share(kernel), 1.0);
        }
    }
}
