//! Where emissive triangles are: a few boxes around them, so that a BSDF-sampled ray of the
//! direct-light estimate that cannot reach any emitter (and has no sky to escape to) is known to
//! bring no light before it is cast. In a room lit by one small panel almost every such ray is
//! one of these (on the default Cornell box 21 000 of 3.9 million BSDF rays reach the light).
//!
//! The test is conservative: the boxes are padded well beyond the rounding of any ray–triangle
//! test, and a ray that crosses a box is cast as before, so the image is the same bit for bit.

use crate::geometry::{gamma, Aabb, TriangleMesh};
use crate::material::Material;
use glam::Vec3;

/// At most this many boxes: a ray is tested against each (some 3 ns a box), and past a handful
/// a cast ray is the cheaper test.
const MAX_BOXES: usize = 8;

/// The boxes around a scene's emissive triangles (those whose material's `emission()` is not
/// zero: the ones [`crate::frame::direct`] reads emission from), and a ball around each.
#[derive(Clone, Debug, Default)]
pub struct EmitterBounds {
    boxes: Vec<Aabb>,
    /// The box holding them all (empty when nothing emits).
    union: Aabb,
}

impl EmitterBounds {
    /// Boxes around the triangles of `mesh` whose material emits: one per triangle when there
    /// are few, else up to [`MAX_BOXES`] from median splits of their centroids along the
    /// longest axis (triangles near each other share a box).
    pub fn new(mesh: &TriangleMesh, tri_material: &[u32], materials: &[Material]) -> Self {
        let emits = |t: usize| {
            tri_material
                .get(t)
                .and_then(|&m| materials.get(m as usize))
                .is_some_and(|m| m.emission() != Vec3::ZERO)
        };
        let mut tris: Vec<(Vec3, Aabb)> = (0..mesh.indices.len())
            .filter(|&t| emits(t))
            .map(|t| {
                let b = Aabb::from_points(mesh.indices[t].map(|i| mesh.positions[i as usize]));
                (b.center(), b)
            })
            .filter(|(c, _)| c.is_finite())
            .collect();
        let mut boxes = Vec::new();
        split(&mut tris, MAX_BOXES, &mut boxes);
        let boxes: Vec<Aabb> = boxes.into_iter().map(padded).collect();
        let union = boxes.iter().fold(Aabb::EMPTY, |u, b| u.union(*b));
        EmitterBounds { boxes, union }
    }

    /// Whether the emissive triangles surely subtend less than `limit` steradians from `p`: the
    /// bound of the box holding them all is below it, or the sum of the boxes' bounds is (the
    /// boxes may overlap, so either can be the lower). The union's bound, cheaper, is tried
    /// first.
    #[inline]
    pub fn subtend_less(&self, p: Vec3, limit: f32) -> bool {
        if box_solid_angle_bound(&self.union, p) < limit {
            return true;
        }
        let mut sum = 0.0;
        for b in &self.boxes {
            sum += box_solid_angle_bound(b, p);
            if !(sum < limit) {
                return false;
            }
        }
        true
    }

    /// Whether the ray from `origin` along `dir` (over `t ≥ 0`) crosses some box; false when
    /// nothing emits.
    #[inline]
    pub fn crossed_by(&self, origin: Vec3, dir: Vec3) -> bool {
        let inv = Vec3::ONE / dir;
        self.boxes.iter().any(|b| {
            let (t0, t1) = ((b.min - origin) * inv, (b.max - origin) * inv);
            // `min`/`max` skip a NaN (0 × ∞: the origin on a face of the box, the ray along
            // it), leaving that axis unconstrained: conservative.
            let near = t0.min(t1).max_element().max(0.0);
            let far = t0.max(t1).min_element() * (1.0 + 2.0 * gamma(3));
            // `!(near > far)`: a NaN passes.
            !(near > far)
        })
    }
}

/// Appends to `out` the boxes of `tris` (centroid, box) split into at most `budget` groups.
fn split(tris: &mut [(Vec3, Aabb)], budget: usize, out: &mut Vec<Aabb>) {
    if tris.is_empty() {
        return;
    }
    if budget <= 1 || tris.len() == 1 {
        out.push(tris.iter().fold(Aabb::EMPTY, |a, (_, b)| a.union(*b)));
        return;
    }
    let axis = Aabb::from_points(tris.iter().map(|(c, _)| *c)).longest_axis();
    let mid = tris.len() / 2;
    tris.select_nth_unstable_by(mid, |a, b| a.0[axis].total_cmp(&b.0[axis]));
    let (lo, hi) = tris.split_at_mut(mid);
    split(lo, budget / 2, out);
    split(hi, budget - budget / 2, out);
}

/// An upper bound on the solid angle box `b` subtends from `p`: the area of the faces that
/// face `p` over the squared distance to the box's nearest point (each face's points are no
/// nearer, and its solid angle is at most its area over that distance squared), at most 4π;
/// 4π from inside, 0 for an empty box.
#[inline]
fn box_solid_angle_bound(b: &Aabb, p: Vec3) -> f32 {
    let whole = 4.0 * std::f32::consts::PI;
    if b.is_empty() {
        return 0.0;
    }
    if !p.is_finite() {
        return whole;
    }
    let below = (b.min - p).max(Vec3::ZERO);
    let above = (p - b.max).max(Vec3::ZERO);
    let gap = below + above;
    let d2 = gap.length_squared();
    let e = b.extent();
    let faces = [e.y * e.z, e.x * e.z, e.x * e.y];
    let area: f32 = (0..3).filter(|&a| gap[a] > 0.0).map(|a| faces[a]).sum();
    // Inside (d2 = 0): everything.
    if d2 > 0.0 && area / d2 < whole {
        area / d2
    } else {
        whole
    }
}

/// `b` grown on every side by far more than the rounding of a ray–triangle test or of a ray's
/// origin offset: a millionth of its size and of its distance from the origin, in every axis.
fn padded(b: Aabb) -> Aabb {
    let scale = b.extent().max_element() + b.min.abs().max(b.max.abs()).max_element();
    let pad = Vec3::splat(scale * 1e-5 + f32::MIN_POSITIVE);
    Aabb { min: b.min - pad, max: b.max + pad }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    fn lamp(tris: &[[Vec3; 3]]) -> (TriangleMesh, Vec<u32>) {
        let positions: Vec<Vec3> = tris.iter().flatten().copied().collect();
        let indices = (0..tris.len() as u32).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect();
        (TriangleMesh { positions, indices }, vec![0; tris.len()])
    }

    fn emissive() -> Vec<Material> {
        vec![Material::Emissive { kd: Vec3::ZERO, ke: Vec3::ONE }]
    }

    /// A ray that hits a triangle always crosses its box, from near or far, at any angle,
    /// grazing included (the exact crossing computed in f64).
    #[test]
    fn every_ray_that_hits_an_emitter_crosses_its_box() {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(3);
        for scale in [1e-3f32, 1.0, 1e3] {
            let offset = Vec3::new(1e4, -2e4, 3e4) * (scale / 1e3);
            let tri = [Vec3::ZERO, Vec3::X, Vec3::Z].map(|v| v * scale + offset);
            let (mesh, tm) = lamp(&[tri]);
            let bounds = EmitterBounds::new(&mesh, &tm, &emissive());
            for _ in 0..20_000 {
                let (a, b): (f32, f32) = (rng.gen(), rng.gen());
                let (a, b) = if a + b > 1.0 { (1.0 - a, 1.0 - b) } else { (a, b) };
                let target = tri[0] + (tri[1] - tri[0]) * a + (tri[2] - tri[0]) * b;
                let from =
                    Vec3::new(rng.gen_range(-3.0..3.0), rng.gen_range(-1.0..1.0), rng.gen_range(-3.0..3.0));
                let origin = target + from * scale * 2.0;
                let dir = (target - origin).normalize();
                assert!(bounds.crossed_by(origin, dir), "{origin:?} -> {target:?}");
            }
            // From inside the plane of the triangle, along it.
            assert!(bounds.crossed_by(offset - Vec3::X * scale, Vec3::X));
        }
    }

    /// Rays pointing away from the emitters, or passing beside them, are told apart; no
    /// emitter, no crossing.
    #[test]
    fn rays_away_from_every_emitter_do_not_cross() {
        let tris: Vec<[Vec3; 3]> = (0..40)
            .map(|i| {
                let o = Vec3::new(i as f32 * 3.0, 10.0, 0.0);
                [o, o + Vec3::X, o + Vec3::Z]
            })
            .collect();
        let (mesh, tm) = lamp(&tris);
        let bounds = EmitterBounds::new(&mesh, &tm, &emissive());
        assert!(bounds.boxes.len() <= MAX_BOXES);
        assert!(bounds.crossed_by(Vec3::new(0.5, 0.0, 0.5), Vec3::Y));
        assert!(bounds.crossed_by(Vec3::new(60.5, 0.0, 0.5), Vec3::Y));
        assert!(!bounds.crossed_by(Vec3::new(0.5, 0.0, 0.5), -Vec3::Y));
        assert!(!bounds.crossed_by(Vec3::new(0.5, 0.0, 5.0), Vec3::Y));
        assert!(!bounds.crossed_by(Vec3::new(0.0, 0.0, 0.0), Vec3::X));
        let none = EmitterBounds::new(&mesh, &tm, &[Material::Diffuse { kd: Vec3::ONE }]);
        assert!(none.boxes.is_empty());
        assert!(!none.crossed_by(Vec3::ZERO, Vec3::Y));
    }

    /// The solid angle of triangle `t` seen from `p` (Van Oosterom and Strackee 1983), in f64.
    fn triangle_solid_angle(t: [Vec3; 3], p: Vec3) -> f64 {
        let [a, b, c] = t.map(|v| (v - p).as_dvec3());
        let (la, lb, lc) = (a.length(), b.length(), c.length());
        let det = a.dot(b.cross(c)).abs();
        let den = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
        2.0 * det.atan2(den).abs()
    }

    /// The bound is never below the true solid angle of the emitters, from points near and far,
    /// around a triangle, a quad (two triangles, as the Cornell box's light) and twenty
    /// triangles (boxes merged), at several scales: a point the bound calls small really sees a
    /// small light. (Twenty triangles may overlap as seen from a point, so there the largest of
    /// them, which their union is no smaller than, is what is checked.)
    #[test]
    fn the_solid_angle_bound_is_never_below_the_truth() {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(5);
        let v = |rng: &mut rand_pcg::Pcg64| Vec3::new(rng.gen(), rng.gen(), rng.gen());
        for scale in [1e-2f32, 1.0, 1e3] {
            for n in [1usize, 2, 20] {
                let tris: Vec<[Vec3; 3]> = if n == 2 {
                    // Axis-aligned, as a ceiling light.
                    let (o, a, b) =
                        (v(&mut rng), Vec3::X * rng.gen_range(0.1..0.3), Vec3::Z * rng.gen_range(0.1..0.3));
                    vec![[o, o + a, o + a + b], [o, o + a + b, o + b]]
                } else {
                    (0..n)
                        .map(|_| {
                            let c = v(&mut rng) * 0.5;
                            [0, 1, 2].map(|_| c + 0.2 * v(&mut rng))
                        })
                        .collect()
                };
                let tris: Vec<[Vec3; 3]> = tris.iter().map(|t| t.map(|p| p * scale)).collect();
                let (mesh, tm) = lamp(&tris);
                let bounds = EmitterBounds::new(&mesh, &tm, &emissive());
                // Points all around, and points far out along the normal of the first triangle,
                // where the bound is tight (every point of it at about the same distance, the
                // cosines near one).
                let t0 = tris[0];
                let (centre, normal) =
                    ((t0[0] + t0[1] + t0[2]) / 3.0, (t0[1] - t0[0]).cross(t0[2] - t0[0]).normalize());
                let size = (t0[1] - t0[0]).length().max((t0[2] - t0[0]).length());
                for i in 0..2000 {
                    let p = if i % 2 == 0 {
                        (v(&mut rng) * 5.0 - Vec3::splat(2.0)) * scale
                    } else {
                        centre + normal * size * rng.gen_range(20.0..60.0)
                    };
                    let each = tris.iter().map(|&t| triangle_solid_angle(t, p));
                    let truth = if n == 20 { each.fold(0.0, f64::max) } else { each.sum() } as f32;
                    assert!(!bounds.subtend_less(p, truth), "{truth} sr at {p}, said less");
                    if i % 2 == 1 && n == 2 {
                        assert!(bounds.subtend_less(p, truth * 1.05), "{truth} sr at {p}: bound loose");
                    }
                }
            }
        }
    }

    /// A Cornell-box light (a 13 x 10.5 cm quad, two triangles, facing down from 0.55 m) is small
    /// from the floor and the walls and not from next to it; nothing emitting is small from
    /// everywhere.
    #[test]
    fn a_ceiling_light_is_small_from_the_floor_not_from_beside_it() {
        let quad =
            [Vec3::new(0.343, 0.548, 0.227), Vec3::new(0.343, 0.548, 0.332), Vec3::new(0.213, 0.548, 0.332)];
        let other = [quad[0], quad[2], Vec3::new(0.213, 0.548, 0.227)];
        let (mesh, tm) = lamp(&[quad, other]);
        let bounds = EmitterBounds::new(&mesh, &tm, &emissive());
        assert!(bounds.subtend_less(Vec3::new(0.28, 0.0, 0.28), 0.05));
        assert!(bounds.subtend_less(Vec3::new(0.0, 0.27, 0.28), 0.5));
        assert!(!bounds.subtend_less(Vec3::new(0.28, 0.45, 0.28), 0.5));
        assert!(!bounds.subtend_less(Vec3::new(0.28, 0.548, 0.28), 12.0));
        assert!(!bounds.subtend_less(Vec3::new(f32::NAN, 0.0, 0.0), 12.0));
        let none = EmitterBounds::new(&mesh, &tm, &[Material::Diffuse { kd: Vec3::ONE }]);
        assert!(none.subtend_less(Vec3::ZERO, 1e-6));
    }
}
