//! Perfect specular reflection with reflectance `ks` and no Fresnel term (`scenes/SCENES.md`:
//! the mirror reflects exactly `ks`, colourless 1 in the test scenes). pbrt-v4's
//! `ConductorBxDF` in its smooth limit, with the Fresnel factor replaced by `ks`.
//!
//! Delta lobe convention: `f = ks / |cos(n, wi)|`, `pdf = 1`, so `f |cos| / pdf = ks`.

use super::{reflect, BsdfSample, LobeKind};
use glam::Vec3;

/// A perfect mirror.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MirrorBsdf {
    pub ks: Vec3,
}

impl MirrorBsdf {
    /// The reflected direction; `n` is on the side of `wo`. `None` at grazing `wo`.
    pub fn sample(&self, n: Vec3, wo: Vec3) -> Option<BsdfSample> {
        let cos_o = n.dot(wo);
        if cos_o <= 0.0 {
            return None;
        }
        let wi = reflect(wo, n).normalize();
        Some(BsdfSample { wi, f: self.ks / cos_o, pdf: 1.0, delta: true, kind: LobeKind::SpecularReflection })
    }
}

#[cfg(test)]
mod tests {
    use super::super::testutil::dir;
    use super::super::{LobeKind, Material};
    use glam::Vec3;

    #[test]
    fn reflects_about_the_normal_from_both_sides() {
        let m = Material::Mirror { ks: Vec3::ONE };
        for n in [Vec3::Z, -Vec3::Z, Vec3::new(0.3, -0.4, 0.866).normalize()] {
            for theta in [0.0, 45.0, 89.0] {
                let wo = dir(n, theta, 60.0);
                let s = m.sample(n, wo, 0.5, [0.5, 0.5]).unwrap();
                assert!(s.delta && s.kind == LobeKind::SpecularReflection);
                assert!((s.wi.dot(n) - wo.dot(n)).abs() < 1e-5, "equal angles");
                assert!((s.wi + wo).cross(n).length() < 1e-5, "coplanar, mirrored");
                assert!((s.weight(n) - Vec3::ONE).abs().max_element() < 1e-5, "energy conserved");
                // From the back side too (two-sided).
                let s = m.sample(n, -wo, 0.5, [0.5, 0.5]).unwrap();
                assert!(s.wi.dot(n) < 0.0);
            }
        }
    }

    #[test]
    fn delta_lobe_has_no_eval_or_pdf() {
        let m = Material::Mirror { ks: Vec3::splat(0.8) };
        let wo = dir(Vec3::Z, 30.0, 0.0);
        let wi = dir(Vec3::Z, 30.0, 180.0);
        assert_eq!(m.eval(Vec3::Z, wo, wi), Vec3::ZERO);
        assert_eq!(m.pdf(Vec3::Z, wo, wi), 0.0);
        assert!(m.is_specular() && !m.is_diffuse_like());
        let s = m.sample(Vec3::Z, wo, 0.1, [0.0; 2]).unwrap();
        assert!((s.weight(Vec3::Z) - Vec3::splat(0.8)).abs().max_element() < 1e-5);
        assert!((s.wi - wi).length() < 1e-5);
    }
}
