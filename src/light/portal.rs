//! Portals: openings (windows, doorways) through which a distant light's photons are sent.
//!
//! A room lit by the sun through a window takes only the sun's photons whose lines pass
//! through the window; emitted over the disc covering the whole scene, nearly all land outside.
//! A `[[portal]]` parallelogram declares the opening: a distant light then sends half its
//! photons along lines through its portals (each point of a portal's projection onto the plane
//! perpendicular to the light equally likely) and the other half over the rest of its disc,
//! each photon's power divided by its stratum's density (`DistantLight::sample_emission`). The
//! light that comes in off surfaces outside is the portals' own photons' work
//! ([`crate::photon::portal`]).

use crate::sampling::Frame;
use glam::{Vec2, Vec3};

/// A parallelogram `corner + s edge_u + t edge_v`, `s, t` in `[0, 1]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Portal {
    pub corner: Vec3,
    pub edge_u: Vec3,
    pub edge_v: Vec3,
}

impl Portal {
    /// The parallelogram of four corners given in order around it, or why not: the fourth
    /// corner must close the parallelogram of the first three (within 1e-4 of its size), and
    /// its area must not be zero.
    pub fn from_corners(c: [Vec3; 4]) -> Result<Portal, String> {
        let (edge_u, edge_v) = (c[1] - c[0], c[3] - c[0]);
        let size = edge_u.length().max(edge_v.length());
        if !(size > 0.0) || !(edge_u.cross(edge_v).length() > 1e-6 * size * size) {
            return Err("the corners span no area".into());
        }
        let gap = (c[0] + edge_u + edge_v - c[2]).length();
        if !(gap <= 1e-4 * size) {
            return Err(format!(
                "the corners are not a parallelogram in order (the third is {gap:.3e} from where the others put it)"
            ));
        }
        Ok(Portal { corner: c[0], edge_u, edge_v })
    }

    /// The portal moved by `d` (the scene recentred).
    pub fn translated(self, d: Vec3) -> Portal {
        Portal { corner: self.corner + d, ..self }
    }
}

/// Portals seen along one direction: each projected onto the plane perpendicular to it, in the
/// plane's coordinates about `center`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Projected {
    /// Corner and edges of each projected parallelogram.
    shapes: Vec<[Vec2; 3]>,
    /// Running sum of the projected areas (the last is the total).
    cumulative: Vec<f32>,
}

impl Projected {
    /// `portals` seen along `dir` (unit), the plane's origin at `center`; portals seen edge-on
    /// are dropped.
    pub fn new(portals: &[Portal], frame: &Frame, center: Vec3) -> Projected {
        let mut out = Projected::default();
        let mut sum = 0.0;
        for p in portals {
            let flat = |v: Vec3| frame.to_local(v).truncate();
            let (o, u, v) = (flat(p.corner - center), flat(p.edge_u), flat(p.edge_v));
            let area = u.perp_dot(v).abs();
            if area > 0.0 && area.is_finite() {
                sum += area;
                out.shapes.push([o, u, v]);
                out.cumulative.push(sum);
            }
        }
        out
    }

    pub fn is_empty(&self) -> bool {
        self.shapes.is_empty()
    }

    /// Total projected area.
    pub fn area(&self) -> f32 {
        self.cumulative.last().copied().unwrap_or(0.0)
    }

    /// A point of the projections, every point equally likely (per unit of projected area,
    /// overlaps counted once for each portal): `u[0]` picks the portal and then, rescaled, the
    /// position along its first edge; `u[1]` along its second.
    pub fn sample(&self, u: [f32; 2]) -> Vec2 {
        let total = self.area();
        let x = u[0] * total;
        let i = self.cumulative.partition_point(|&c| c <= x).min(self.shapes.len() - 1);
        let lo = if i == 0 { 0.0 } else { self.cumulative[i - 1] };
        let s = ((x - lo) / (self.cumulative[i] - lo)).clamp(0.0, 1.0);
        let [o, a, b] = self.shapes[i];
        o + s * a + u[1] * b
    }

    /// How many projections cover `q` (plane coordinates).
    pub fn coverage(&self, q: Vec2) -> usize {
        self.shapes
            .iter()
            .filter(|[o, a, b]| {
                let det = a.perp_dot(*b);
                let d = q - *o;
                let s = d.perp_dot(*b) / det;
                let t = a.perp_dot(d) / det;
                (0.0..=1.0).contains(&s) && (0.0..=1.0).contains(&t)
            })
            .count()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn window() -> Portal {
        Portal::from_corners([
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(0.5, 1.0, 0.0),
            Vec3::new(0.5, 1.6, 0.0),
            Vec3::new(0.0, 1.6, 0.0),
        ])
        .unwrap()
    }

    #[test]
    fn corners_must_make_a_parallelogram() {
        let c = [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y];
        assert!(Portal::from_corners(c).is_ok());
        let skew = [Vec3::ZERO, Vec3::X, Vec3::new(1.2, 1.0, 0.0), Vec3::Y];
        assert!(Portal::from_corners(skew).unwrap_err().contains("parallelogram"));
        let flat = [Vec3::ZERO, Vec3::X, Vec3::new(2.0, 0.0, 0.0), Vec3::X];
        assert!(Portal::from_corners(flat).unwrap_err().contains("no area"));
        assert!(Portal::from_corners([Vec3::NAN; 4]).is_err());
    }

    #[test]
    fn projected_area_is_the_area_times_the_cosine() {
        let dir = Vec3::new(0.3, -0.5, -0.8).normalize();
        let frame = Frame::from_z(dir);
        let w = window();
        let p = Projected::new(&[w], &frame, Vec3::new(0.2, 0.4, -0.1));
        let expected = 0.5 * 0.6 * dir.z.abs();
        assert!((p.area() - expected).abs() < 1e-5, "{} against {expected}", p.area());
        // Seen edge-on: dropped.
        let edge = Projected::new(&[w], &Frame::from_z(Vec3::X), Vec3::ZERO);
        assert!(edge.is_empty() && edge.area() == 0.0);
    }

    #[test]
    fn samples_cover_each_portal_by_its_area() {
        let frame = Frame::from_z(Vec3::new(0.2, -0.3, -1.0).normalize());
        let big = Portal { corner: Vec3::new(3.0, 0.0, 0.0), edge_u: Vec3::X * 2.0, edge_v: Vec3::Y * 1.5 };
        let p = Projected::new(&[window(), big], &frame, Vec3::ZERO);
        let small = Projected::new(&[window()], &frame, Vec3::ZERO);
        let n = 200;
        let mut in_small = 0;
        for i in 0..n * n {
            let u = [((i % n) as f32 + 0.5) / n as f32, ((i / n) as f32 + 0.5) / n as f32];
            let q = p.sample(u);
            assert_eq!(p.coverage(q), 1, "every sample is inside exactly one portal");
            in_small += small.coverage(q);
        }
        let share = in_small as f32 / (n * n) as f32;
        let expected = small.area() / p.area();
        assert!((share - expected).abs() < 0.01, "{share} against {expected}");
        assert_eq!(p.coverage(Vec2::new(100.0, 100.0)), 0);
    }
}
