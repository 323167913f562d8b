//! Smooth dielectric (pbrt-v4 `DielectricBxDF`, smooth case): exact unpolarised Fresnel
//! reflectance (pbrt-v4 `FrDielectric`; Walter et al., "Microfacet Models for Refraction through
//! Rough Surfaces", EGSR 2007, eq. 22 in its equivalent form), reflection or refraction chosen
//! with probability `F` resp. `1 - F`, no absorption.
//!
//! `n` is the outward geometric normal: IOR 1 on its side, `ior` behind it. Delta convention:
//! reflection `f = F / |cos|`, `pdf = F`; refraction `f = (1 - F) / |cos| * s`, `pdf = 1 - F`,
//! with `s = 1 / eta'^2` for [`TransportMode::Radiance`] (`eta'` = IOR of the `wi` side over the
//! IOR of the `wo` side: radiance changes by `(eta_o / eta_i)^2` crossing the interface) and
//! `s = 1` for [`TransportMode::Importance`] (photons carry power, which only Fresnel changes).

use super::{reflect, BsdfSample, LobeKind, TransportMode};
use glam::Vec3;

/// Unpolarised Fresnel reflectance of a dielectric interface. `cos_i` is the cosine between the
/// incident direction (pointing away from the surface) and the normal; `eta = eta_t / eta_i` is
/// the relative IOR of the far side of the normal. Negative `cos_i` means the direction is on
/// the far side: `eta` is inverted. Returns 1 under total internal reflection.
pub fn fresnel_dielectric(cos_i: f32, eta: f32) -> f32 {
    let mut cos_i = cos_i.clamp(-1.0, 1.0);
    let mut eta = eta;
    if cos_i < 0.0 {
        eta = 1.0 / eta;
        cos_i = -cos_i;
    }
    let sin2_i = 1.0 - cos_i * cos_i;
    let sin2_t = sin2_i / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).max(0.0).sqrt();
    let r_parl = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    0.5 * (r_parl * r_parl + r_perp * r_perp)
}

/// Refraction of `wi` (pointing away from the surface) through an interface with normal `n` and
/// relative IOR `eta` (far side over near side of `n`), from either side. Returns the transmitted
/// direction and the relative IOR `eta'` actually crossed, or `None` under total internal
/// reflection (pbrt-v4 `Refract`).
pub fn refract(wi: Vec3, n: Vec3, eta: f32) -> Option<(Vec3, f32)> {
    let (mut n, mut eta, mut cos_i) = (n, eta, n.dot(wi));
    if cos_i < 0.0 {
        eta = 1.0 / eta;
        cos_i = -cos_i;
        n = -n;
    }
    let sin2_i = (1.0 - cos_i * cos_i).max(0.0);
    let sin2_t = sin2_i / (eta * eta);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some(((-wi / eta + (cos_i / eta - cos_t) * n).normalize(), eta))
}

/// A smooth dielectric with index `ior` behind the normal, 1 in front.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GlassBsdf {
    pub ior: f32,
}

impl GlassBsdf {
    /// Reflects if `u_lobe < F`, else refracts (TIR always reflects).
    pub fn sample(&self, n: Vec3, wo: Vec3, u_lobe: f32, mode: TransportMode) -> Option<BsdfSample> {
        let cos_o = n.dot(wo);
        if cos_o == 0.0 || !cos_o.is_finite() {
            return None;
        }
        let f_r = fresnel_dielectric(cos_o, self.ior);
        if u_lobe < f_r {
            let wi = reflect(wo, n).normalize();
            let f = Vec3::splat(f_r / cos_o.abs());
            return Some(BsdfSample { wi, f, pdf: f_r, delta: true, kind: LobeKind::SpecularReflection });
        }
        let (wi, etap) = refract(wo, n, self.ior)?;
        let t = 1.0 - f_r;
        let scale = match mode {
            TransportMode::Radiance => 1.0 / (etap * etap),
            TransportMode::Importance => 1.0,
        };
        let f = Vec3::splat(t * scale / wi.dot(n).abs());
        Some(BsdfSample { wi, f, pdf: t, delta: true, kind: LobeKind::SpecularTransmission })
    }
}

#[cfg(test)]
mod tests {
    use super::super::testutil::dir;
    use super::super::{LobeKind, Material, TransportMode};
    use super::*;

    #[test]
    fn normal_incidence_is_four_percent_from_both_sides() {
        assert!((fresnel_dielectric(1.0, 1.5) - 0.04).abs() < 1e-6);
        assert!((fresnel_dielectric(-1.0, 1.5) - 0.04).abs() < 1e-6);
        assert!((fresnel_dielectric(1.0, 1.0)).abs() < 1e-7, "index-matched: no reflection");
        assert_eq!(fresnel_dielectric(0.0, 1.5), 1.0, "grazing");
    }

    #[test]
    fn total_internal_reflection_beyond_the_critical_angle() {
        let critical = (1.0f32 / 1.5).asin().to_degrees(); // 41.81 deg
        let inside = |deg: f32| -deg.to_radians().cos(); // direction inside the glass
        assert_eq!(fresnel_dielectric(inside(critical + 0.5), 1.5), 1.0);
        assert_eq!(fresnel_dielectric(inside(80.0), 1.5), 1.0);
        assert!(fresnel_dielectric(inside(critical - 0.5), 1.5) < 1.0);
        let n = Vec3::Z;
        let wo = dir(-n, critical + 1.0, 0.0);
        assert!(refract(wo, n, 1.5).is_none());
        let s = Material::Glass { ior: 1.5 }.sample(n, wo, 0.999, [0.0; 2]).unwrap();
        assert_eq!(s.kind, LobeKind::SpecularReflection);
        assert!((s.weight(n).x - 1.0).abs() < 1e-5, "TIR reflects everything");
    }

    #[test]
    fn snell_and_reversibility() {
        let n = Vec3::Z;
        for theta in [0.0f32, 20.0, 60.0, 89.0] {
            let wo = dir(n, theta, 45.0);
            let (wt, etap) = refract(wo, n, 1.5).unwrap();
            assert_eq!(etap, 1.5);
            let sin_t = (1.0 - wt.z * wt.z).sqrt();
            assert!((theta.to_radians().sin() - 1.5 * sin_t).abs() < 1e-5, "Snell");
            let (back, etap2) = refract(wt, n, 1.5).unwrap();
            assert!((back - wo).length() < 1e-4 && (etap2 - 1.0 / 1.5).abs() < 1e-6);
            // Fresnel is the same seen from either side of the same ray pair.
            assert!((fresnel_dielectric(wo.z, 1.5) - fresnel_dielectric(wt.z, 1.5)).abs() < 1e-4);
        }
    }

    #[test]
    fn energy_is_conserved_and_radiance_scales_by_inverse_eta_squared() {
        let n = Vec3::Z;
        let glass = Material::Glass { ior: 1.5 };
        for theta in [0.0, 30.0, 41.0] {
            for side in [n, -n] {
                let wo = dir(side, theta, 10.0);
                let f = fresnel_dielectric(wo.dot(n), 1.5);
                let r = glass.sample_mode(n, wo, 0.0, [0.0; 2], TransportMode::Importance).unwrap();
                let t = glass.sample_mode(n, wo, 0.9999, [0.0; 2], TransportMode::Importance);
                assert_eq!(r.kind, LobeKind::SpecularReflection);
                assert!((r.pdf - f).abs() < 1e-6 && (r.weight(n).x - 1.0).abs() < 1e-5);
                let t = t.unwrap();
                assert_eq!(t.kind, LobeKind::SpecularTransmission);
                // Expected power: F * 1 + (1 - F) * 1 = 1 (photons keep their power).
                assert!((t.pdf - (1.0 - f)).abs() < 1e-6 && (t.weight(n).x - 1.0).abs() < 1e-5);
                let tr = glass.sample(n, wo, 0.9999, [0.0; 2]).unwrap();
                let etap: f32 = if side == n { 1.5 } else { 1.0 / 1.5 };
                assert!((tr.weight(n).x - 1.0 / (etap * etap)).abs() < 1e-5);
                assert_eq!(glass.eval(n, wo, tr.wi), Vec3::ZERO);
                assert_eq!(glass.pdf(n, wo, tr.wi), 0.0);
            }
        }
    }
}
