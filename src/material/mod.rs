//! Surface materials, as the scene file describes them.
//!
//! RGB triples are linear Rec.709 values, one independent channel each (`glam::Vec3` as a
//! colour). Conventions follow `scenes/SCENES.md`: diffuse surfaces are two-sided, emission
//! comes from the front face only.

use glam::Vec3;

/// What a surface does with light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Material {
    /// Lambertian, BRDF `kd / pi`, two-sided.
    Diffuse { kd: Vec3 },
    /// `kd / pi` plus an energy-conserving normalised Phong lobe `ks (n + 2) / (2 pi) cos^n`.
    Glossy { kd: Vec3, ks: Vec3, ns: f32 },
    /// Perfect specular reflection with reflectance `ks`.
    Mirror { ks: Vec3 },
    /// Smooth dielectric with index `ior` inside, 1 outside; exact Fresnel, no absorption.
    Glass { ior: f32 },
    /// Lambertian with albedo `kd` plus emitted radiance `ke` (W m^-2 sr^-1) from the front face.
    Emissive { kd: Vec3, ke: Vec3 },
}

impl Material {
    /// Radiance emitted from the front face, zero for non-emitters.
    pub fn emission(&self) -> Vec3 {
        match *self {
            Material::Emissive { ke, .. } => ke,
            _ => Vec3::ZERO,
        }
    }

    /// Whether the surface has a perfectly specular (delta) component.
    pub fn is_specular(&self) -> bool {
        matches!(self, Material::Mirror { .. } | Material::Glass { .. })
    }

    /// Whether the surface has a non-delta (diffuse or glossy) component, i.e. stores photons and
    /// gathers light.
    pub fn is_diffuse_like(&self) -> bool {
        match *self {
            Material::Diffuse { .. } | Material::Emissive { .. } => true,
            Material::Glossy { .. } => true,
            Material::Mirror { .. } | Material::Glass { .. } => false,
        }
    }
}
