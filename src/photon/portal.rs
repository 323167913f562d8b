//! Portals in the photon pass: the cut they make in light paths, and the photons they emit.
//!
//! A portal (`[[portal]]`, [`crate::light::Portal`]) is an opening between an outside and the
//! inside the camera is in. Light comes in through it in two ways: straight from a light
//! (sunlight through a window), and off surfaces outside (sunlight off the ground, in through
//! the window). The first reaches the inside as before, and a distant light sends half its
//! photons straight through its portals (`DistantLight::sample_emission`). The second is what
//! makes a sunlit room hard: a photon must land on the ground just outside and then happen to
//! bounce into the window, and each that does carries the weight of all those that did not.
//!
//! With portals, the photon pass cuts every light path where it crosses a portal inward after
//! a diffuse or glossy bounce: such a photon is dropped there. The light it stood for comes in
//! instead as photons the portal emits: each starts at a uniform point of the portal, goes
//! inward with a cosine-distributed direction, and carries `pi A L / n`, where `L` is an
//! estimate of the radiance coming in along its line after at least one diffuse bounce outside
//! (a path traced outward from the portal: [`Outside`]). Every light path is counted once —
//! either it never crosses a portal inward after a diffuse bounce, or its part after the last
//! such crossing is a portal photon's path and its part before it is in that photon's `L` — so
//! the estimate keeps its value whatever the portals are. Photons straight from a light and
//! those that only met mirrors and glass are never cut: a path traced from the portal cannot
//! find a point or distant light through a mirror.
//!
//! The inside of a portal is the side the camera's eye is on.

use crate::light::{luminance, Portal};
use crate::sampling::{derive_seed, sample_cosine_hemisphere, Frame};
use glam::Vec3;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg32;
use std::f32::consts::PI;

/// Radiance coming in from outside, for the photons portals emit.
pub trait Outside: Sync {
    /// An unbiased estimate of the radiance arriving at `p` from the direction `out` (unit),
    /// counting only light that met a diffuse or glossy surface on its way (emission seen
    /// directly or through mirrors and glass is left out), and the rays it traced.
    fn incoming(&self, p: Vec3, out: Vec3, rng: &mut Pcg32) -> (Vec3, u64);
}

/// A portal with the side it lets light in to.
#[derive(Clone, Copy, Debug)]
struct Side {
    portal: Portal,
    /// Unit normal pointing inside.
    inward: Vec3,
    area: f32,
}

/// Samples of the incoming flux per portal that set each portal's share of the photons.
const POWER_SAMPLES: u64 = 4096;

/// The scene's portals as the photon pass uses them, with each portal's estimated incoming
/// flux (which only splits the budget: every photon carries its own estimate).
#[derive(Clone, Debug, Default)]
pub struct PortalSet {
    sides: Vec<Side>,
    powers: Vec<Vec3>,
}

impl PortalSet {
    /// `portals` with their inside toward `eye`, their incoming flux estimated with `outside`
    /// (seeded by `seed`); also returns the rays traced. Portals of no area are dropped.
    pub fn new(portals: &[Portal], eye: Vec3, outside: &dyn Outside, seed: u64) -> (PortalSet, u64) {
        let mut set = PortalSet::default();
        let mut rays = 0;
        for (i, p) in portals.iter().enumerate() {
            let n = p.edge_u.cross(p.edge_v);
            let area = n.length();
            if !(area > 0.0 && area.is_finite()) {
                continue;
            }
            let n = n / area;
            let inward = if n.dot(eye - p.corner) < 0.0 { -n } else { n };
            let side = Side { portal: *p, inward, area };
            let mut rng = Pcg32::seed_from_u64(derive_seed(seed, 0x9077, i as u64));
            let mut sum = Vec3::ZERO;
            for _ in 0..POWER_SAMPLES {
                let (flux, r) = side.emit([rng.gen(), rng.gen()], [rng.gen(), rng.gen()], outside, &mut rng);
                sum += flux.2;
                rays += r;
            }
            set.sides.push(side);
            set.powers.push(sum / POWER_SAMPLES as f32);
        }
        (set, rays)
    }

    pub fn is_empty(&self) -> bool {
        self.sides.is_empty()
    }

    pub fn len(&self) -> usize {
        self.sides.len()
    }

    /// The estimated flux coming in through each portal after a bounce outside.
    pub fn powers(&self) -> &[Vec3] {
        &self.powers
    }

    /// Whether the segment from `o` along `d` up to `t_max` crosses a portal inward.
    #[inline]
    pub fn cuts(&self, o: Vec3, d: Vec3, t_max: f32) -> bool {
        self.sides.iter().any(|s| {
            let denom = d.dot(s.inward);
            if !(denom > 0.0) {
                return false;
            }
            let t = s.inward.dot(s.portal.corner - o) / denom;
            if !(t > 0.0 && t < t_max) {
                return false;
            }
            let q = o + t * d - s.portal.corner;
            let (u, v) = (s.portal.edge_u, s.portal.edge_v);
            // Coordinates of q in the (u, v) basis of the portal's plane.
            let (uu, uv, vv) = (u.dot(u), u.dot(v), v.dot(v));
            let (qu, qv) = (q.dot(u), q.dot(v));
            let det = uu * vv - uv * uv;
            let a = (qu * vv - qv * uv) / det;
            let b = (qv * uu - qu * uv) / det;
            (0.0..=1.0).contains(&a) && (0.0..=1.0).contains(&b)
        })
    }

    /// A photon of portal `i`: origin, direction and the flux the sample stands for (`pi A L`),
    /// and the rays traced for `L`.
    pub fn emit(
        &self,
        i: usize,
        u_pos: [f32; 2],
        u_dir: [f32; 2],
        outside: &dyn Outside,
        rng: &mut Pcg32,
    ) -> ((Vec3, Vec3, Vec3), u64) {
        self.sides[i].emit(u_pos, u_dir, outside, rng)
    }
}

impl Side {
    fn emit(
        &self,
        u_pos: [f32; 2],
        u_dir: [f32; 2],
        outside: &dyn Outside,
        rng: &mut Pcg32,
    ) -> ((Vec3, Vec3, Vec3), u64) {
        let p = self.portal.corner + u_pos[0] * self.portal.edge_u + u_pos[1] * self.portal.edge_v;
        let dir = Frame::from_z(self.inward).from_local(sample_cosine_hemisphere(u_dir)).normalize();
        let (l, rays) = outside.incoming(p, -dir, rng);
        // Density of (point, direction): 1/A times cos/pi; the flux is L cos over it.
        let flux = if l.is_finite() && luminance(l) >= 0.0 { l * (PI * self.area) } else { Vec3::ZERO };
        ((p, dir, flux), rays)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Radiance 1 from every direction outside.
    struct Uniform;
    impl Outside for Uniform {
        fn incoming(&self, _p: Vec3, _out: Vec3, _rng: &mut Pcg32) -> (Vec3, u64) {
            (Vec3::ONE, 1)
        }
    }

    fn window() -> Portal {
        Portal {
            corner: Vec3::new(0.0, 1.0, 0.0),
            edge_u: Vec3::new(0.5, 0.0, 0.0),
            edge_v: Vec3::new(0.0, 0.6, 0.0),
        }
    }

    #[test]
    fn a_portal_lets_in_pi_a_l_toward_the_eye() {
        let (set, rays) = PortalSet::new(&[window()], Vec3::new(0.2, 1.3, -2.0), &Uniform, 1);
        assert_eq!(rays, POWER_SAMPLES);
        // Uniform radiance 1 through 0.3 m²: pi 0.3 W.
        assert!((set.powers()[0] - Vec3::splat(PI * 0.3)).abs().max_element() < 1e-4);
        let mut rng = Pcg32::seed_from_u64(3);
        for _ in 0..100 {
            let ((p, d, _), _) =
                set.emit(0, [rng.gen(), rng.gen()], [rng.gen(), rng.gen()], &Uniform, &mut rng);
            assert!(d.z < 0.0, "inward is toward the eye");
            assert!(p.z == 0.0 && (0.0..=0.5).contains(&p.x) && (1.0..=1.6).contains(&p.y));
        }
    }

    #[test]
    fn only_inward_crossings_of_the_opening_are_cut() {
        let (set, _) = PortalSet::new(&[window()], Vec3::new(0.2, 1.3, -2.0), &Uniform, 1);
        let inward = Vec3::NEG_Z;
        // Through the opening, toward the eye: cut, unless the segment ends before it.
        assert!(set.cuts(Vec3::new(0.25, 1.3, 1.0), inward, f32::INFINITY));
        assert!(!set.cuts(Vec3::new(0.25, 1.3, 1.0), inward, 0.9));
        // Outward, beside the opening, or starting past it: not cut.
        assert!(!set.cuts(Vec3::new(0.25, 1.3, -1.0), -inward, f32::INFINITY));
        assert!(!set.cuts(Vec3::new(0.7, 1.3, 1.0), inward, f32::INFINITY));
        assert!(!set.cuts(Vec3::new(0.25, 1.3, -0.1), inward, f32::INFINITY));
        // Slanted through it.
        let d = Vec3::new(0.1, 0.05, -1.0).normalize();
        assert!(set.cuts(Vec3::new(0.15, 1.25, 1.0) - d * 0.0, d, f32::INFINITY));
    }
}
