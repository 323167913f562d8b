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
/// zero: the ones [`crate::frame::direct`] reads emission from).
#[derive(Clone, Debug, Default)]
pub struct EmitterBounds {
    boxes: Vec<Aabb>,
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
        EmitterBounds { boxes: boxes.into_iter().map(padded).collect() }
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
}
