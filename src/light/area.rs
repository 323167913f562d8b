//! Diffuse area lights: the scene's emissive triangles (pbrt-v4 `DiffuseAreaLight` on
//! triangles, with pbrt-v4's area sampling; Jensen 2001, section 5.1.3, for photon emission).
//!
//! Each triangle emits constant radiance `ke` from its front face only (the side the geometric
//! normal `(v1 - v0) x (v2 - v0)` points to), so its flux is `pi ke A`. All emitters form one
//! [`AreaLights`] collection: a triangle is picked by a [`Distribution1D`] over
//! `area * luminance(ke)`, a point uniformly by area on it, and the area density is turned into
//! a solid-angle density `pdf_A d^2 / cos(theta_light)` for direct lighting.

use super::{luminance, EmissionSample, LightSample};
use crate::geometry::{barycentric_error, offset_distance, offset_ray_origin, TriangleMesh};
use crate::material::Material;
use crate::sampling::{
    cosine_hemisphere_pdf, sample_cosine_hemisphere, sample_uniform_triangle, Distribution1D, Frame,
};
use glam::Vec3;
use std::f32::consts::PI;

/// One emitting triangle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EmitterTriangle {
    /// Index of the triangle in the scene mesh.
    pub prim: u32,
    pub vertices: [Vec3; 3],
    /// Unit front-face normal.
    pub normal: Vec3,
    pub area: f32,
    /// Emitted radiance (W m^-2 sr^-1).
    pub ke: Vec3,
}

impl EmitterTriangle {
    /// Flux `pi ke A`.
    pub fn power(&self) -> Vec3 {
        PI * self.ke * self.area
    }

    /// A uniform point and the bound on its rounding error.
    fn point_and_error(&self, u: [f32; 2]) -> (Vec3, Vec3) {
        let b = sample_uniform_triangle(u);
        let [v0, v1, v2] = self.vertices;
        (b[0] * v0 + b[1] * v1 + b[2] * v2, barycentric_error(self.vertices, b))
    }
}

/// All emissive triangles of a scene, sorted by `prim`.
#[derive(Clone, Debug, Default)]
pub struct AreaLights {
    triangles: Vec<EmitterTriangle>,
    distribution: Distribution1D,
}

impl AreaLights {
    /// Collects every triangle whose material (`materials[tri_material[i]]`) emits and whose area
    /// is non-zero. Triangles without a valid material index are skipped.
    pub fn from_mesh(mesh: &TriangleMesh, tri_material: &[u32], materials: &[Material]) -> Self {
        let triangles: Vec<EmitterTriangle> = (0..mesh.len() as u32)
            .filter_map(|prim| {
                let ke = materials.get(*tri_material.get(prim as usize)? as usize)?.emission();
                let normal = mesh.normal(prim)?;
                let area = mesh.area(prim);
                (ke.max_element() > 0.0 && area > 0.0).then(|| EmitterTriangle {
                    prim,
                    vertices: mesh.triangle(prim),
                    normal,
                    area,
                    ke,
                })
            })
            .collect();
        let weights: Vec<f32> = triangles.iter().map(|t| t.area * luminance(t.ke.max(Vec3::ZERO))).collect();
        AreaLights { distribution: Distribution1D::new(&weights), triangles }
    }

    /// The emitters, sorted by mesh triangle index.
    pub fn triangles(&self) -> &[EmitterTriangle] {
        &self.triangles
    }

    pub fn len(&self) -> usize {
        self.triangles.len()
    }

    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    /// Probability that light sampling picks emitter `i` (index into [`AreaLights::triangles`]).
    pub fn triangle_pmf(&self, i: usize) -> f32 {
        self.distribution.pmf(i)
    }

    /// Index into [`AreaLights::triangles`] of mesh triangle `prim`, if it emits.
    pub fn find(&self, prim: u32) -> Option<usize> {
        self.triangles.binary_search_by_key(&prim, |t| t.prim).ok()
    }

    /// Total flux `pi sum(ke A)`.
    pub fn power(&self) -> Vec3 {
        self.triangles.iter().map(EmitterTriangle::power).sum()
    }

    /// Samples a point on an emitter as seen from `p`: `li = ke`, `pdf` in solid angle, `dist`
    /// to the sampled point. `None` if `p` is behind (or in the plane of) that emitter's front.
    ///
    /// `end_error` is the distance along `wi` from the sampled point to the plane where pbrt-v4's
    /// `OffsetRayOrigin` would move it toward `p` (its error bound along the normal, over the
    /// cosine at the light): far from the origin the rounding of the point is larger than any
    /// fixed fraction of `dist`, and a shadow ray stopping only a fraction short would hit the
    /// emitter itself (the furnace moved by 1e5 lost 11 % of its direct light that way).
    pub fn sample_li(&self, p: Vec3, u: [f32; 2]) -> Option<LightSample> {
        let (i, pmf, u0) = self.distribution.sample(u[0])?;
        let tri = &self.triangles[i];
        let (q, err) = tri.point_and_error([u0, u[1]]);
        let d = q - p;
        let dist2 = d.length_squared();
        let dist = dist2.sqrt();
        if dist <= 0.0 || !dist.is_finite() {
            return None;
        }
        let wi = d / dist;
        let cos_light = -tri.normal.dot(wi);
        if cos_light <= 0.0 {
            return None;
        }
        let pdf = pmf / tri.area * dist2 / cos_light;
        // Twice the offset: room for its final rounding by a float per coordinate.
        let end_error = 2.0 * offset_distance(q, err, tri.normal) / cos_light;
        (pdf.is_finite() && pdf > 0.0).then_some(LightSample {
            wi,
            dist,
            end_error,
            li: tri.ke,
            pdf,
            delta: false,
        })
    }

    /// Solid-angle density with which [`AreaLights::sample_li`] from `p` produces direction `wi`
    /// hitting mesh triangle `prim` at `hit_point` (for MIS when a BSDF-sampled ray hits an
    /// emitter). Zero for non-emitters and for hits on the back face.
    pub fn pdf_li(&self, p: Vec3, wi: Vec3, prim: u32, hit_point: Vec3) -> f32 {
        let Some(i) = self.find(prim) else { return 0.0 };
        let tri = &self.triangles[i];
        let cos_light = -tri.normal.dot(wi);
        if cos_light <= 0.0 {
            return 0.0;
        }
        self.distribution.pmf(i) / tri.area * (hit_point - p).length_squared() / cos_light
    }

    /// A photon from the whole collection: emitter by `area * luminance(ke)` (`u_pos[0]`,
    /// remapped), uniform point, cosine-distributed direction on the front side.
    pub fn sample_emission(&self, u_pos: [f32; 2], u_dir: [f32; 2]) -> Option<EmissionSample> {
        let (i, pmf, u0) = self.distribution.sample(u_pos[0])?;
        let mut e = self.sample_emission_on_triangle(i, [u0, u_pos[1]], u_dir)?;
        e.pdf_pos *= pmf;
        Some(e)
    }

    /// A photon from emitter `i` (index into [`AreaLights::triangles`]) alone, for a caller that
    /// stratifies over each emitter itself: `pdf_pos = 1 / area`, so the photon power
    /// `le cos / (pdf_pos pdf_dir)` is the triangle's flux `pi ke A`.
    pub fn sample_emission_on_triangle(
        &self,
        i: usize,
        u_pos: [f32; 2],
        u_dir: [f32; 2],
    ) -> Option<EmissionSample> {
        let tri = self.triangles.get(i)?;
        let (p, err) = tri.point_and_error(u_pos);
        let local = sample_cosine_hemisphere(u_dir);
        if local.z <= 0.0 {
            return None;
        }
        let dir = Frame::from_z(tri.normal).from_local(local).normalize();
        Some(EmissionSample {
            ray_origin: offset_ray_origin(p, err, tri.normal),
            dir,
            normal: Some(tri.normal),
            pdf_pos: 1.0 / tri.area,
            pdf_dir: cosine_hemisphere_pdf(local.z),
            le: tri.ke,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::sample_uniform_hemisphere;
    use rand::{Rng, SeedableRng};
    use rand_pcg::Pcg64;

    const KE: Vec3 = Vec3::new(17.0, 12.0, 4.0);

    /// A unit square at height `h` facing down (-z), light material 1; plus a white floor.
    fn scene(h: f32) -> (TriangleMesh, Vec<u32>, Vec<Material>) {
        let positions = vec![
            Vec3::new(0.0, 0.0, h),
            Vec3::new(0.0, 1.0, h),
            Vec3::new(1.0, 1.0, h),
            Vec3::new(1.0, 0.0, h),
            Vec3::new(-5.0, -5.0, -1.0),
            Vec3::new(5.0, -5.0, -1.0),
            Vec3::new(0.0, 5.0, -1.0),
            Vec3::new(2.0, 2.0, 2.0), // degenerate emitter
        ];
        let mesh = TriangleMesh { positions, indices: vec![[4, 5, 6], [0, 1, 2], [0, 2, 3], [7, 7, 7]] };
        let materials = vec![
            Material::Diffuse { kd: Vec3::splat(0.5) },
            Material::Emissive { kd: Vec3::splat(0.78), ke: KE },
        ];
        (mesh, vec![0, 1, 1, 1], materials)
    }

    /// Form factor from a differential area to a parallel rectangle `a x b` at distance `c`, with
    /// the element's normal through a corner (Howell's catalogue, B-3 form).
    fn corner_form_factor(a: f64, b: f64, c: f64) -> f64 {
        let (x, y) = (a / c, b / c);
        let (sx, sy) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
        (x / sx * (y / sx).atan() + y / sy * (x / sy).atan()) / (2.0 * std::f64::consts::PI)
    }

    fn irradiance_mc(lights: &AreaLights, p: Vec3, n: Vec3, samples: usize, seed: u64) -> Vec3 {
        let mut rng = Pcg64::seed_from_u64(seed);
        let mut sum = Vec3::ZERO;
        for _ in 0..samples {
            if let Some(s) = lights.sample_li(p, [rng.gen(), rng.gen()]) {
                assert!((lights.pdf_li(p, s.wi, lights.triangles()[0].prim, p + s.dist * s.wi) > 0.0));
                sum += s.li * n.dot(s.wi).max(0.0) / s.pdf;
            }
        }
        sum / samples as f32
    }

    #[test]
    fn collects_front_facing_emitters_with_their_power() {
        let (mesh, tm, mats) = scene(0.5);
        let l = AreaLights::from_mesh(&mesh, &tm, &mats);
        assert_eq!(l.len(), 2, "the floor and the degenerate triangle are skipped");
        assert_eq!(l.find(2), Some(1));
        assert_eq!(l.find(0), None);
        assert!((l.power() - PI * KE).abs().max_element() < 1e-4);
        assert!(l.triangles().iter().all(|t| t.normal == Vec3::NEG_Z));
        assert!(AreaLights::from_mesh(&mesh, &[0; 4], &mats).is_empty());
    }

    #[test]
    fn irradiance_matches_the_analytic_form_factor() {
        let h = 0.5;
        let (mesh, tm, mats) = scene(h);
        let l = AreaLights::from_mesh(&mesh, &tm, &mats);
        // Below the centre: four corner rectangles 0.5 x 0.5; below a corner: one 1 x 1.
        let cases = [
            (Vec3::new(0.5, 0.5, 0.0), 4.0 * corner_form_factor(0.5, 0.5, h as f64)),
            (Vec3::new(0.0, 0.0, 0.0), corner_form_factor(1.0, 1.0, h as f64)),
        ];
        for (k, (p, f)) in cases.into_iter().enumerate() {
            let e = irradiance_mc(&l, p, Vec3::Z, 200_000, k as u64);
            let expected = KE * (std::f64::consts::PI * f) as f32;
            let rel = ((e - expected) / expected).abs().max_element();
            assert!(rel < 0.02, "case {k}: {e} vs {expected}");
        }
    }

    #[test]
    fn nothing_reaches_points_behind_the_emitter_and_pdfs_agree() {
        let (mesh, tm, mats) = scene(0.5);
        let l = AreaLights::from_mesh(&mesh, &tm, &mats);
        let above = Vec3::new(0.5, 0.5, 1.0);
        assert!(l.sample_li(above, [0.3, 0.6]).is_none());
        let p = Vec3::new(0.2, 0.7, -0.3);
        let mut rng = Pcg64::seed_from_u64(5);
        for _ in 0..100 {
            let s = l.sample_li(p, [rng.gen(), rng.gen()]).unwrap();
            let hit = p + s.dist * s.wi;
            let prim = if (hit.x - hit.y) > 0.0 { 2 } else { 1 }; // which half of the quad
            let pdf = l.pdf_li(p, s.wi, prim, hit);
            assert!((pdf - s.pdf).abs() < 1e-3 * s.pdf, "{pdf} vs {}", s.pdf);
            assert_eq!(l.pdf_li(p, s.wi, 0, hit), 0.0, "not an emitter");
            assert_eq!(l.pdf_li(above, -s.wi, prim, hit), 0.0, "back face");
        }
    }

    #[test]
    fn power_equals_the_integral_of_emission() {
        let (mesh, tm, mats) = scene(0.5);
        let l = AreaLights::from_mesh(&mesh, &tm, &mats);
        // Independent estimate: uniform points by area, uniform hemisphere directions.
        let mut rng = Pcg64::seed_from_u64(3);
        let (n, total_area) = (200_000, 1.0f32);
        let mut sum = Vec3::ZERO;
        for _ in 0..n {
            let w = sample_uniform_hemisphere([rng.gen(), rng.gen()]);
            sum += KE * w.z * 2.0 * PI * total_area; // le cos / (pdf_dir pdf_pos)
        }
        let mc = sum / n as f32;
        assert!(((mc - l.power()) / l.power()).abs().max_element() < 0.01, "{mc} vs {}", l.power());
        // Photons: equal power, front side, cosine-distributed (E[cos] = 2/3).
        let mut mean_cos = 0.0;
        for _ in 0..n {
            let e = l.sample_emission([rng.gen(), rng.gen()], [rng.gen(), rng.gen()]).unwrap();
            assert!((e.photon_power() - l.power()).abs().max_element() < 1e-3 * l.power().max_element());
            assert!(e.ray_origin.z < 0.5, "offset to the front side");
            mean_cos += e.dir.dot(e.normal.unwrap()) / n as f32;
        }
        assert!((mean_cos - 2.0 / 3.0).abs() < 0.005);
        // Per-triangle emission carries that triangle's flux.
        let e = l.sample_emission_on_triangle(1, [0.2, 0.3], [0.4, 0.5]).unwrap();
        assert!((e.photon_power() - l.triangles()[1].power()).abs().max_element() < 1e-3);
    }

    #[test]
    fn emitters_are_picked_by_area_times_luminance() {
        let (mesh, tm, mut mats) = scene(0.5);
        mats.push(Material::Emissive { kd: Vec3::ZERO, ke: Vec3::new(0.0, 0.0, 10.0) });
        let tm = vec![tm[0], tm[1], 2, tm[3]];
        let l = AreaLights::from_mesh(&mesh, &tm, &mats);
        let (w0, w1) = (luminance(KE), luminance(Vec3::new(0.0, 0.0, 10.0)));
        assert!((l.triangle_pmf(0) - w0 / (w0 + w1)).abs() < 1e-6);
        let e = l.sample_emission([0.999, 0.5], [0.5, 0.5]).unwrap();
        assert!((luminance(e.photon_power()) - PI * 0.5 * (w0 + w1)).abs() < 1e-3, "equal luminance");
    }
}
