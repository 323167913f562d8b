//! Surface materials, as the scene file describes them, and their BSDFs.
//!
//! RGB triples are linear Rec.709 values, one independent channel each (`glam::Vec3` as a
//! colour). Conventions follow `scenes/SCENES.md`: diffuse surfaces are two-sided, emission
//! comes from the front face only.
//!
//! BSDF conventions (pbrt-v4 vocabulary): every direction is a unit world-space vector; `n` is the
//! flat geometric normal of the hit triangle (front side = where `n` points); `wo` points away
//! from the surface toward the viewer / previous path vertex, `wi` toward the light / next
//! vertex. Two-sided materials (diffuse, glossy, emissive albedo, mirror) first flip `n` to the
//! side of `wo`; glass uses `n` as given to tell entering (IOR 1 → `ior`) from leaving. For delta
//! lobes `f` is returned pbrt-style as `R / |cos(n, wi)|` with `pdf` the discrete lobe
//! probability, so the path throughput update is always `beta *= f |cos| / pdf`.
//!
//! Russian roulette for photons follows Jensen, "Realistic Image Synthesis Using Photon
//! Mapping" (2001), section 5.2: see [`Material::photon_probabilities`] and
//! [`Normals::scatter_photon`]. Shading normals: [`Normals`].

mod diffuse;
mod glass;
mod glossy;
mod mirror;
mod principled;
mod shading;
#[cfg(test)]
mod testutil;

pub use diffuse::DiffuseBsdf;
pub use glass::{fresnel_dielectric, refract, GlassBsdf};
pub use glossy::GlossyBsdf;
pub use mirror::MirrorBsdf;
pub use principled::{Parts, PrincipledBsdf, MIN_ALPHA};
pub use shading::{Normals, Scattered};

use glam::Vec3;

/// The Phong exponent above which a glossy lobe is sharp: camera paths trace it
/// ([`crate::frame::specular::through_lobe`]) instead of estimating its light from photons.
/// A density estimate weighs its `k` photons by the lobe, and light arriving evenly puts about
/// `1.39 / ns` of them inside the lobe's half-maximum cone (half-angle `√(2 ln 2 / ns)`): above
/// `ns = k`, the two-pass gathers' default of 100, less than about one photon.
pub const SHARP_NS: f32 = 100.0;

/// The GGX width below which a principled material's lobe is sharp: the one whose Phong
/// exponent by the Beckmann–Phong correspondence, `2 / α² − 2`, is [`SHARP_NS`] (`√(2 / 102)`;
/// glTF roughness 0.374).
pub const SHARP_ALPHA: f32 = 0.140_028;

/// What a surface does with light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Material {
    /// Lambertian, BRDF `kd / pi`, two-sided.
    Diffuse { kd: Vec3 },
    /// `kd / pi` plus an energy-conserving normalised Phong lobe `ks (n + 2) / (2 pi) cos^n`.
    Glossy { kd: Vec3, ks: Vec3, ns: f32 },
    /// glTF's metallic-roughness material: a GGX lobe with Schlick's Fresnel over a Lambertian
    /// base ([`PrincipledBsdf`]; `alpha` = roughness², at least [`MIN_ALPHA`]); made by
    /// [`Material::principled`].
    Principled { base: Vec3, metallic: f32, alpha: f32, parts: Parts },
    /// Perfect specular reflection with reflectance `ks`.
    Mirror { ks: Vec3 },
    /// Smooth dielectric with index `ior` inside, 1 outside; exact Fresnel, no absorption.
    Glass { ior: f32 },
    /// Lambertian with albedo `kd` plus emitted radiance `ke` (W m^-2 sr^-1) from the front face.
    Emissive { kd: Vec3, ke: Vec3 },
}

/// Which quantity a path carries; matters only for refraction (pbrt-v4 `TransportMode`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum TransportMode {
    /// Camera paths carry radiance: refraction scales it by `1 / eta^2` (radiance is compressed
    /// into a smaller solid angle when entering a denser medium).
    #[default]
    Radiance,
    /// Photons carry power (flux), which refraction does not rescale.
    Importance,
}

/// Which lobe produced a [`BsdfSample`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LobeKind {
    Diffuse,
    Glossy,
    SpecularReflection,
    SpecularTransmission,
}

/// A sampled incident direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfSample {
    /// Unit direction toward the light / next vertex.
    pub wi: Vec3,
    /// BSDF value; for delta lobes `R / |cos(n, wi)|` (times `1/eta^2` for radiance refraction).
    pub f: Vec3,
    /// Solid-angle density of `wi` for non-delta lobes; the discrete lobe probability for delta.
    pub pdf: f32,
    /// Whether `wi` came from a delta (perfectly specular) lobe.
    pub delta: bool,
    /// The lobe that was sampled.
    pub kind: LobeKind,
}

impl BsdfSample {
    /// The throughput factor `f |cos(n, wi)| / pdf` (`n` either orientation).
    #[inline]
    pub fn weight(&self, n: Vec3) -> Vec3 {
        self.f * (n.dot(self.wi).abs() / self.pdf)
    }
}

/// Result of [`Normals::scatter_photon`]: the continued photon.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PhotonScatter {
    pub wi: Vec3,
    /// The photon's new power (already divided by the survival probability).
    pub power: Vec3,
    pub kind: LobeKind,
}

/// `n` flipped, if needed, to the side `w` is on (two-sided shading).
#[inline]
pub fn face_forward(n: Vec3, w: Vec3) -> Vec3 {
    if n.dot(w) < 0.0 {
        -n
    } else {
        n
    }
}

/// Mirror reflection of `wo` about `n`: `-wo + 2 (wo . n) n` (works from either side).
#[inline]
pub fn reflect(wo: Vec3, n: Vec3) -> Vec3 {
    -wo + 2.0 * wo.dot(n) * n
}

#[inline]
fn channel_or_max(c: Vec3, channel: Option<usize>) -> f32 {
    match channel {
        Some(ch) => c[ch],
        None => c.max_element(),
    }
}

impl Material {
    /// glTF's metallic-roughness material of base colour `base`, metallic value `metallic` and
    /// roughness `roughness` (each clamped to `[0, 1]`; `α = roughness²`, at least
    /// [`MIN_ALPHA`]).
    pub fn principled(base: Vec3, metallic: f32, roughness: f32) -> Material {
        let unit = |x: f32| if x.is_finite() { x.clamp(0.0, 1.0) } else { 0.0 };
        let r = unit(roughness);
        Material::Principled {
            base: base.clamp(Vec3::ZERO, Vec3::ONE),
            metallic: unit(metallic),
            alpha: (r * r).max(MIN_ALPHA),
            parts: Parts::Both,
        }
    }

    /// The material with its base colour multiplied by `c` (a vertex colour): the albedo of
    /// diffuse, glossy and emissive materials, the base colour of a principled one; mirrors
    /// and glass are left as they are.
    pub fn tinted(&self, c: Vec3) -> Material {
        match *self {
            Material::Diffuse { kd } => Material::Diffuse { kd: kd * c },
            Material::Emissive { kd, ke } => Material::Emissive { kd: kd * c, ke },
            Material::Glossy { kd, ks, ns } => Material::Glossy { kd: kd * c, ks, ns },
            Material::Principled { base, metallic, alpha, parts } => {
                Material::Principled { base: (base * c).min(Vec3::ONE), metallic, alpha, parts }
            }
            Material::Mirror { .. } | Material::Glass { .. } => *self,
        }
    }

    /// Radiance emitted from the front face, zero for non-emitters.
    pub fn emission(&self) -> Vec3 {
        match *self {
            Material::Emissive { ke, .. } => ke,
            _ => Vec3::ZERO,
        }
    }

    /// Radiance emitted toward `w` (unit, pointing away from the surface) from a surface with
    /// geometric normal `n`: `ke` on the front side, zero behind.
    pub fn emitted(&self, n: Vec3, w: Vec3) -> Vec3 {
        if n.dot(w) > 0.0 {
            self.emission()
        } else {
            Vec3::ZERO
        }
    }

    /// Whether the surface has a perfectly specular (delta) component.
    pub fn is_specular(&self) -> bool {
        matches!(self, Material::Mirror { .. } | Material::Glass { .. })
    }

    /// The albedo `kd` of a purely Lambertian surface (diffuse, or an emitter's reflection),
    /// whose BRDF is the constant `kd / pi`; `None` for any other kind.
    #[inline]
    pub fn lambertian(&self) -> Option<Vec3> {
        match *self {
            Material::Diffuse { kd } | Material::Emissive { kd, .. } => Some(kd),
            _ => None,
        }
    }

    /// A glossy or principled material's two parts apart, where its lobe is sharp (Phong `ns`
    /// above [`SHARP_NS`], GGX `α` below [`SHARP_ALPHA`]): the Lambertian part (`Diffuse`) and
    /// the lobe alone (which [`Material::sample`] then always picks); `None` for any other
    /// kind, one without a lobe or a wider one.
    #[inline]
    pub fn sharp_lobe(&self) -> Option<(Material, Material)> {
        match *self {
            Material::Glossy { kd, ks, ns } if ks.max_element() > 0.0 && ns > SHARP_NS => {
                Some((Material::Diffuse { kd }, Material::Glossy { kd: Vec3::ZERO, ks, ns }))
            }
            Material::Principled { base, metallic, alpha, parts: Parts::Both } if alpha < SHARP_ALPHA => {
                let kd = PrincipledBsdf { base, metallic, alpha, parts: Parts::Both }.kd();
                Some((
                    Material::Diffuse { kd },
                    Material::Principled { base, metallic, alpha, parts: Parts::LobeOnly },
                ))
            }
            _ => None,
        }
    }

    /// The probability that [`Material::sample`] from `wo` picks a glossy or principled
    /// material's Lambertian part (one for any other kind; `n` on the side of `wo` or not).
    #[inline]
    pub fn diffuse_share(&self, n: Vec3, wo: Vec3) -> f32 {
        match *self {
            Material::Glossy { kd, ks, ns } => 1.0 - GlossyBsdf { kd, ks, ns }.specular_probability(),
            Material::Principled { base, metallic, alpha, parts } => {
                1.0 - PrincipledBsdf { base, metallic, alpha, parts }.lobe_probability(n.dot(wo).abs())
            }
            _ => 1.0,
        }
    }

    /// Whether the surface has a non-delta (diffuse or glossy) component, i.e. stores photons and
    /// gathers light.
    pub fn is_diffuse_like(&self) -> bool {
        match *self {
            Material::Diffuse { .. } | Material::Emissive { .. } => true,
            Material::Glossy { .. } | Material::Principled { .. } => true,
            Material::Mirror { .. } | Material::Glass { .. } => false,
        }
    }

    /// Directional-hemispherical reflectance at normal incidence, per channel: `kd`, `kd + ks`,
    /// `ks`, one for glass (reflection plus transmission, no absorption); for a principled
    /// material its diffuse albedo plus `F0` (the lobe's masking left out: a bound).
    pub fn albedo(&self) -> Vec3 {
        match *self {
            Material::Diffuse { kd } | Material::Emissive { kd, .. } => kd,
            Material::Glossy { kd, ks, .. } => kd + ks,
            Material::Principled { base, metallic, alpha, parts } => {
                let b = PrincipledBsdf { base, metallic, alpha, parts };
                b.kd() + b.f0()
            }
            Material::Mirror { ks } => ks,
            Material::Glass { .. } => Vec3::ONE,
        }
    }

    /// Non-delta BSDF value `f(wo, wi)`; zero for mirror and glass and whenever `wi` is not on
    /// the side of `wo`.
    pub fn eval(&self, n: Vec3, wo: Vec3, wi: Vec3) -> Vec3 {
        match *self {
            Material::Diffuse { kd } | Material::Emissive { kd, .. } => {
                DiffuseBsdf { kd }.eval(face_forward(n, wo), wo, wi)
            }
            Material::Glossy { kd, ks, ns } => GlossyBsdf { kd, ks, ns }.eval(face_forward(n, wo), wo, wi),
            Material::Principled { base, metallic, alpha, parts } => {
                PrincipledBsdf { base, metallic, alpha, parts }.eval(face_forward(n, wo), wo, wi)
            }
            Material::Mirror { .. } | Material::Glass { .. } => Vec3::ZERO,
        }
    }

    /// Solid-angle density with which [`Material::sample`] returns `wi` (zero for delta lobes).
    pub fn pdf(&self, n: Vec3, wo: Vec3, wi: Vec3) -> f32 {
        match *self {
            Material::Diffuse { kd } | Material::Emissive { kd, .. } => {
                DiffuseBsdf { kd }.pdf(face_forward(n, wo), wo, wi)
            }
            Material::Glossy { kd, ks, ns } => GlossyBsdf { kd, ks, ns }.pdf(face_forward(n, wo), wo, wi),
            Material::Principled { base, metallic, alpha, parts } => {
                PrincipledBsdf { base, metallic, alpha, parts }.pdf(face_forward(n, wo), wo, wi)
            }
            Material::Mirror { .. } | Material::Glass { .. } => 0.0,
        }
    }

    /// Samples `wi` for a camera path (radiance transport). `u_lobe` picks a lobe, `u` the
    /// direction. `None` means "no sample" (e.g. a lobe direction below the surface).
    pub fn sample(&self, n: Vec3, wo: Vec3, u_lobe: f32, u: [f32; 2]) -> Option<BsdfSample> {
        self.sample_mode(n, wo, u_lobe, u, TransportMode::Radiance)
    }

    /// [`Material::sample`] with an explicit transport mode (use `Importance` for photons).
    pub fn sample_mode(
        &self,
        n: Vec3,
        wo: Vec3,
        u_lobe: f32,
        u: [f32; 2],
        mode: TransportMode,
    ) -> Option<BsdfSample> {
        match *self {
            Material::Diffuse { kd } | Material::Emissive { kd, .. } => {
                DiffuseBsdf { kd }.sample(face_forward(n, wo), wo, u)
            }
            Material::Glossy { kd, ks, ns } => {
                GlossyBsdf { kd, ks, ns }.sample(face_forward(n, wo), wo, u_lobe, u)
            }
            Material::Principled { base, metallic, alpha, parts } => {
                PrincipledBsdf { base, metallic, alpha, parts }.sample(face_forward(n, wo), wo, u_lobe, u)
            }
            Material::Mirror { ks } => MirrorBsdf { ks }.sample(face_forward(n, wo), wo),
            Material::Glass { ior } => GlassBsdf { ior }.sample(n, wo, u_lobe, mode),
        }
    }

    /// Photon Russian-roulette probabilities `(p_diffuse, p_specular)`; absorption has
    /// `1 - p_diffuse - p_specular` (Jensen 2001, 5.2). With `Some(ch)` they come from that
    /// channel's reflectances (one photon map per channel); with `None` (RGB photons) from the
    /// maximum over channels. "Diffuse" means any non-delta bounce (the photon is stored before
    /// it): Diffuse/Emissive `(kd, 0)`; Glossy `(kd + ks, 0)` and principled `(kd + F0, 0)` —
    /// their lobes are non-delta, so they share the diffuse branch and [`Material::sample`]
    /// then picks the lobe itself; Mirror `(0, ks)`; Glass `(0, 1)` (no absorption; Fresnel
    /// picks reflect vs refract).
    pub fn photon_probabilities(&self, channel: Option<usize>) -> (f32, f32) {
        let (d, s) = match *self {
            Material::Diffuse { kd } | Material::Emissive { kd, .. } => (channel_or_max(kd, channel), 0.0),
            Material::Glossy { .. } | Material::Principled { .. } => {
                (channel_or_max(self.albedo(), channel), 0.0)
            }
            Material::Mirror { ks } => (0.0, channel_or_max(ks, channel)),
            Material::Glass { .. } => (0.0, 1.0),
        };
        let d = if d.is_finite() { d.clamp(0.0, 1.0) } else { 0.0 };
        let s = if s.is_finite() { s.clamp(0.0, 1.0 - d) } else { 0.0 };
        (d, s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn photon_probabilities_follow_the_reflectances() {
        let kd = Vec3::new(0.63, 0.065, 0.05);
        let m = Material::Diffuse { kd };
        assert_eq!(m.photon_probabilities(Some(1)), (0.065, 0.0));
        assert_eq!(m.photon_probabilities(None), (0.63, 0.0));
        let g = Material::Glossy { kd: Vec3::splat(0.3), ks: Vec3::new(0.5, 0.2, 0.1), ns: 20.0 };
        assert_eq!(g.photon_probabilities(Some(2)), (0.4, 0.0));
        assert_eq!(Material::Mirror { ks: Vec3::ONE }.photon_probabilities(Some(0)), (0.0, 1.0));
        assert_eq!(Material::Glass { ior: 1.5 }.photon_probabilities(None), (0.0, 1.0));
        let e = Material::Emissive { kd: Vec3::splat(0.5), ke: Vec3::ONE };
        assert_eq!(e.photon_probabilities(Some(0)), (0.5, 0.0));
        assert_eq!(e.albedo(), Vec3::splat(0.5));
    }

    #[test]
    fn photon_power_is_preserved_on_survival_for_lambertian() {
        let m = Material::Diffuse { kd: Vec3::splat(0.5) };
        let n = Vec3::Z;
        let wo = Vec3::new(0.3, 0.0, 0.95).normalize();
        let s = Normals::flat(n).scatter_photon(&m, wo, Vec3::ONE, Some(0), 0.2, 0.5, [0.3, 0.7]).unwrap();
        assert!((s.power - Vec3::ONE).abs().max_element() < 1e-5, "{:?}", s.power);
        assert!(Normals::flat(n).scatter_photon(&m, wo, Vec3::ONE, Some(0), 0.7, 0.5, [0.3, 0.7]).is_none());
        // Glass never absorbs, and photons through it keep their power (importance transport).
        let g = Material::Glass { ior: 1.5 };
        let s = Normals::flat(n).scatter_photon(&g, wo, Vec3::ONE, None, 0.99, 0.99, [0.0; 2]).unwrap();
        assert_eq!(s.kind, LobeKind::SpecularTransmission);
        assert!((s.power - Vec3::ONE).abs().max_element() < 1e-5);
    }

    #[test]
    fn emission_is_front_side_only_and_reflection_two_sided() {
        let e = Material::Emissive { kd: Vec3::splat(0.5), ke: Vec3::ONE };
        assert_eq!(e.emitted(Vec3::Z, Vec3::Z), Vec3::ONE);
        assert_eq!(e.emitted(Vec3::Z, -Vec3::Z), Vec3::ZERO);
        let wo = Vec3::new(0.0, 0.6, -0.8);
        let wi = Vec3::new(0.6, 0.0, -0.8);
        assert!((e.eval(Vec3::Z, wo, wi) - Vec3::splat(0.5 / std::f32::consts::PI)).length() < 1e-6);
        assert_eq!(e.eval(Vec3::Z, wo, -wi), Vec3::ZERO);
    }
}
