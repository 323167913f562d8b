//! glTF 2.0's metallic-roughness material (the specification's appendix B, "BRDF
//! Implementation"): a GGX microfacet lobe (Walter et al. 2007) with the height-correlated
//! Smith masking-shadowing term (Heitz 2014) and Schlick's Fresnel, over a Lambertian base.
//!
//! With base colour `b`, metallic value `m` and `α = roughness²`:
//!
//! `f = (1 − m) 0.96 b / π + F(wo · h) D(h) V(wo, wi)`, `F(c) = F0 + m (1 − b) (1 − c)⁵`,
//! `F0 = (1 − m) 0.04 + m b`.
//!
//! A metal (`m = 1`) is the specification's exactly: `F` is Schlick's on the base colour,
//! rising to white at grazing angles. A dielectric (`m = 0`) keeps its Fresnel at normal
//! incidence, 4 %, at every angle, and its diffuse part the 96 % that leaves: the
//! specification's `mix(diffuse, specular, F(wo · h))` rises to a mirror at grazing angles
//! and darkens its diffuse part there by a factor that depends on both directions through
//! `h`. Held constant, the diffuse part is Lambertian, so the precomputed irradiance and the
//! maps' Lambertian gathers serve it (the photon maps estimate it as they estimate any
//! diffuse surface), and the material never reflects more than it receives (the
//! specification's form reflects up to 1.37 of the light at 80° on a white base). What is
//! lost is the dielectric's rim reflection at grazing angles.
//!
//! The lobe is sampled from the distribution of visible normals (Heitz 2018), by the
//! spherical-cap construction of Dupuy & Benyoub 2023, with density `G1(wo) D(h) / (4 wo · n)`;
//! reflections that fall below the surface are rejected (`None`), as the glossy lobe's are.
//! The lobe is picked with probability `s / (s + d)`, `s` the mean of `F` at `wo · n` and `d`
//! that of the diffuse albedo; `f` and `pdf` of a sample are the whole mixture's. `n` is
//! already flipped to the side of `wo` by the caller.

use super::{reflect, BsdfSample, LobeKind};
use crate::sampling::{cosine_hemisphere_pdf, sample_cosine_hemisphere, Frame};
use glam::Vec3;
use std::f32::consts::{FRAC_1_PI, PI};

/// A dielectric's Fresnel reflectance (glTF's, for an index of 1.5).
pub const DIELECTRIC_F0: f32 = 0.04;

/// The least `α` drawn: below it, in `f32`, the lobe's peak `1 / (π α²)` is not resolved
/// (`1 − cos²` of a half vector is known to about 1e-7). glTF roughness 0.1 and below are
/// drawn as 0.1; a roughness of 0 on a metal's factors is a mirror (`MetalRoughKind`).
pub const MIN_ALPHA: f32 = 0.01;

/// Which parts of the material a [`PrincipledBsdf`] holds: camera paths trace a sharp lobe
/// alone ([`super::Material::sharp_lobe`]) while the photon maps estimate the diffuse part.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Parts {
    Both,
    LobeOnly,
}

/// The glTF metallic-roughness BSDF (see the module's documentation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PrincipledBsdf {
    /// Base colour, in `[0, 1]`.
    pub base: Vec3,
    /// Metallic value, in `[0, 1]`.
    pub metallic: f32,
    /// GGX width, `roughness²`, at least [`MIN_ALPHA`].
    pub alpha: f32,
    pub parts: Parts,
}

impl PrincipledBsdf {
    /// The diffuse part's albedo: `(1 − m) 0.96 b` (zero for the lobe alone).
    #[inline]
    pub fn kd(&self) -> Vec3 {
        match self.parts {
            Parts::Both => self.base * ((1.0 - self.metallic) * (1.0 - DIELECTRIC_F0)),
            Parts::LobeOnly => Vec3::ZERO,
        }
    }

    /// The lobe's Fresnel reflectance at normal incidence, `F0`.
    #[inline]
    pub fn f0(&self) -> Vec3 {
        Vec3::splat((1.0 - self.metallic) * DIELECTRIC_F0) + self.base * self.metallic
    }

    /// Schlick's Fresnel at cosine `c`: `F0 + m (1 − b) (1 − c)⁵`.
    #[inline]
    fn fresnel(&self, c: f32) -> Vec3 {
        let x = (1.0 - c).clamp(0.0, 1.0);
        let x2 = x * x;
        self.f0() + (Vec3::ONE - self.base) * (self.metallic * x2 * x2 * x)
    }

    /// The GGX distribution of normals at `cos` from `n`.
    #[inline]
    fn d(&self, cos: f32) -> f32 {
        let a2 = self.alpha * self.alpha;
        let c2 = cos * cos;
        let t = (1.0 - c2).max(0.0) + c2 * a2;
        a2 / (PI * t * t)
    }

    /// `√(cos² (1 − α²) + α²)`, the Smith term's root for a direction at `cos` from `n`.
    #[inline]
    fn root(&self, cos: f32) -> f32 {
        let a2 = self.alpha * self.alpha;
        (cos * cos * (1.0 - a2) + a2).sqrt()
    }

    /// The height-correlated masking-shadowing over `4 |wo · n| |wi · n|` (glTF's `V`).
    #[inline]
    fn v(&self, cos_o: f32, cos_i: f32) -> f32 {
        0.5 / (cos_i * self.root(cos_o) + cos_o * self.root(cos_i))
    }

    /// Probability of sampling the lobe from `wo` at `cos_o` from `n`.
    #[inline]
    pub fn lobe_probability(&self, cos_o: f32) -> f32 {
        if self.parts == Parts::LobeOnly {
            return 1.0;
        }
        let s = self.fresnel(cos_o).max(Vec3::ZERO).element_sum();
        let d = self.kd().max(Vec3::ZERO).element_sum();
        if s + d > 0.0 {
            s / (s + d)
        } else {
            0.0
        }
    }

    /// BSDF value; zero unless `wo` and `wi` are both on the side of `n`.
    pub fn eval(&self, n: Vec3, wo: Vec3, wi: Vec3) -> Vec3 {
        let (cos_o, cos_i) = (n.dot(wo), n.dot(wi));
        if cos_o <= 0.0 || cos_i <= 0.0 {
            return Vec3::ZERO;
        }
        let h = (wo + wi).normalize_or_zero();
        if h == Vec3::ZERO {
            return self.kd() * FRAC_1_PI;
        }
        let lobe = self.fresnel(wo.dot(h)) * (self.d(n.dot(h)) * self.v(cos_o, cos_i));
        self.kd() * FRAC_1_PI + lobe
    }

    /// Density of the lobe's samples, `G1(wo) D(h) / (4 wo · n)`.
    #[inline]
    fn lobe_pdf(&self, n: Vec3, wo: Vec3, wi: Vec3) -> f32 {
        let cos_o = n.dot(wo);
        let h = (wo + wi).normalize_or_zero();
        if h == Vec3::ZERO {
            return 0.0;
        }
        let g1 = 2.0 * cos_o / (cos_o + self.root(cos_o));
        g1 * self.d(n.dot(h)) / (4.0 * cos_o)
    }

    /// Mixture density of [`PrincipledBsdf::sample`].
    pub fn pdf(&self, n: Vec3, wo: Vec3, wi: Vec3) -> f32 {
        let (cos_o, cos_i) = (n.dot(wo), n.dot(wi));
        if cos_o <= 0.0 || cos_i <= 0.0 {
            return 0.0;
        }
        let ps = self.lobe_probability(cos_o);
        let lobe = if ps > 0.0 { ps * self.lobe_pdf(n, wo, wi) } else { 0.0 };
        (1.0 - ps) * cosine_hemisphere_pdf(cos_i) + lobe
    }

    /// A visible normal for `wo` (local, `z` along the normal), from `u` (Dupuy & Benyoub 2023:
    /// in the frame where the distribution is the unit hemisphere, the visible normals are
    /// `wo` plus a point drawn uniformly on the spherical cap below it).
    fn visible_normal(&self, wo: Vec3, u: [f32; 2]) -> Vec3 {
        let a = self.alpha;
        let w = Vec3::new(a * wo.x, a * wo.y, wo.z).normalize();
        let phi = 2.0 * PI * u[0];
        let z = (1.0 - u[1]) * (1.0 + w.z) - w.z;
        let r = (1.0 - z * z).max(0.0).sqrt();
        let m = Vec3::new(r * phi.cos(), r * phi.sin(), z) + w;
        Vec3::new(a * m.x, a * m.y, m.z.max(0.0)).normalize()
    }

    /// Picks the lobe if `u_lobe` is below [`PrincipledBsdf::lobe_probability`], else the
    /// diffuse part.
    pub fn sample(&self, n: Vec3, wo: Vec3, u_lobe: f32, u: [f32; 2]) -> Option<BsdfSample> {
        let cos_o = n.dot(wo);
        if cos_o <= 0.0 {
            return None;
        }
        let ps = self.lobe_probability(cos_o);
        let frame = Frame::from_z(n);
        let (wi, kind) = if u_lobe < ps {
            let h = frame.from_local(self.visible_normal(frame.to_local(wo), u));
            (reflect(wo, h).normalize(), LobeKind::Glossy)
        } else if ps < 1.0 {
            (frame.from_local(sample_cosine_hemisphere(u)).normalize(), LobeKind::Diffuse)
        } else {
            return None;
        };
        if n.dot(wi) <= 0.0 {
            return None;
        }
        let pdf = self.pdf(n, wo, wi);
        (pdf > 0.0 && pdf.is_finite()).then(|| BsdfSample {
            wi,
            f: self.eval(n, wo, wi),
            pdf,
            delta: false,
            kind,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::super::testutil::*;
    use super::super::Material;
    use super::*;

    fn principled(base: Vec3, metallic: f32, roughness: f32) -> Material {
        Material::principled(base, metallic, roughness)
    }

    /// glTF's reference formulas, written out as the specification gives them (appendix B),
    /// for the metal, where the two agree exactly.
    fn gltf_metal(base: Vec3, roughness: f32, n: Vec3, wo: Vec3, wi: Vec3) -> Vec3 {
        let a = roughness * roughness;
        let h = (wo + wi).normalize();
        let (ndl, ndv, ndh, vdh) = (n.dot(wi), n.dot(wo), n.dot(h), wo.dot(h));
        let d = a * a / (PI * (ndh * ndh * (a * a - 1.0) + 1.0).powi(2));
        let v = 1.0
            / (ndl * (ndv * ndv * (1.0 - a * a) + a * a).sqrt()
                + ndv * (ndl * ndl * (1.0 - a * a) + a * a).sqrt())
            / 2.0;
        let f = base + (Vec3::ONE - base) * (1.0 - vdh).powi(5);
        f * d * v
    }

    #[test]
    fn a_metal_is_gltfs() {
        let base = Vec3::new(1.0, 0.78, 0.34);
        for roughness in [0.2, 0.5, 0.9] {
            let m = principled(base, 1.0, roughness);
            for (to, ti, phi) in
                [(0.0, 10.0, 180.0), (40.0, 35.0, 170.0), (75.0, 70.0, 190.0), (30.0, 60.0, 90.0)]
            {
                let (wo, wi) = (dir(Vec3::Z, to, 0.0), dir(Vec3::Z, ti, phi));
                let (got, want) = (m.eval(Vec3::Z, wo, wi), gltf_metal(base, roughness, Vec3::Z, wo, wi));
                assert!(
                    (got - want).abs().max_element() <= 1e-4 * want.max_element().max(1.0),
                    "{got} vs {want}"
                );
            }
        }
    }

    #[test]
    fn samples_agree_with_eval_and_pdf() {
        for (k, (metallic, roughness)) in
            [(1.0, 0.3), (1.0, 0.8), (0.0, 0.4), (0.4, 0.6), (0.0, 0.15)].into_iter().enumerate()
        {
            let m = principled(Vec3::new(0.8, 0.5, 0.2), metallic, roughness);
            for (j, theta) in [0.0, 45.0, 80.0].into_iter().enumerate() {
                check_sample_matches_eval(&m, Vec3::Z, dir(Vec3::Z, theta, 0.0), (10 * k + j) as u64);
                check_sample_matches_eval(&m, Vec3::Z, dir(-Vec3::Z, theta, 30.0), 99 + k as u64);
            }
        }
    }

    /// The sampled estimate of the albedo agrees with one by uniform directions (which does
    /// not use the sampling), and no material reflects more than it receives.
    #[test]
    fn albedo_by_sampling_agrees_and_never_exceeds_one() {
        let n = Vec3::new(-0.5, 0.5, 0.7).normalize();
        for (metallic, roughness) in [(1.0, 0.4), (1.0, 1.0), (0.0, 0.5), (0.0, 1.0), (0.5, 0.7)] {
            let m = principled(Vec3::ONE, metallic, roughness);
            for theta in [0.0, 30.0, 60.0, 85.0] {
                let wo = dir(n, theta, 100.0);
                let a = furnace(&m, n, wo, 200_000, 11);
                assert!(a.max_element() <= 1.0 + 0.005, "m {metallic} r {roughness} θ {theta}: {a}");
                let b = furnace_uniform(&m, n, wo, 800_000, 12);
                assert!(
                    (a - b).abs().max_element() < 0.02,
                    "m {metallic} r {roughness} θ {theta}: {a} vs {b}"
                );
            }
        }
    }

    /// A smooth metal reflects nearly all of its Fresnel reflectance at every angle, where
    /// the normalised Phong lobe it was drawn with before fell as the cosine (a third of a
    /// ball's light lost toward its rim); a rough one loses some to masking.
    #[test]
    fn a_smooth_metal_reflects_its_fresnel_at_every_angle() {
        let base = Vec3::new(0.9, 0.6, 0.3);
        let m = principled(base, 1.0, 0.2);
        for theta in [0.0, 45.0, 70.0] {
            let a = furnace(&m, Vec3::Z, dir(Vec3::Z, theta, 0.0), 100_000, 3);
            let c = theta.to_radians().cos();
            let f = base + (Vec3::ONE - base) * (1.0 - c).powi(5);
            assert!((a - f).abs().max_element() < 0.02, "θ {theta}: {a} vs {f}");
        }
        // A dielectric: 96 % of the base colour diffusely and 4 % in the lobe, at normal incidence.
        let d = furnace(&principled(Vec3::splat(0.5), 0.0, 0.3), Vec3::Z, Vec3::Z, 200_000, 4);
        assert!((d - Vec3::splat(0.48 + 0.04)).abs().max_element() < 0.005, "{d}");
    }

    #[test]
    fn the_lobe_alone_is_split_off_where_sharp() {
        let m = principled(Vec3::splat(0.5), 0.0, 0.3);
        let (diffuse, lobe) = m.sharp_lobe().unwrap();
        assert_eq!(diffuse, Material::Diffuse { kd: Vec3::splat(0.48) });
        for (j, theta) in [0.0, 45.0, 80.0].into_iter().enumerate() {
            check_sample_matches_eval(&lobe, Vec3::Z, dir(Vec3::Z, theta, 0.0), 40 + j as u64);
        }
        // The two parts add up to the whole.
        let (wo, wi) = (dir(Vec3::Z, 30.0, 0.0), dir(Vec3::Z, 35.0, 175.0));
        let sum = diffuse.eval(Vec3::Z, wo, wi) + lobe.eval(Vec3::Z, wo, wi);
        assert!((sum - m.eval(Vec3::Z, wo, wi)).abs().max_element() < 1e-5);
        assert!(principled(Vec3::splat(0.5), 0.0, 0.4).sharp_lobe().is_none());
        let phong = (2.0 / (super::super::SHARP_NS + 2.0)).sqrt();
        assert!((super::super::SHARP_ALPHA - phong).abs() < 1e-6);
        assert_eq!(
            principled(Vec3::ONE, 1.0, 0.2).sharp_lobe().unwrap().0,
            Material::Diffuse { kd: Vec3::ZERO }
        );
    }
}
