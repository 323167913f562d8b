//! Light sources as the scene file describes them. Emissive triangles (materials with `Ke`) are
//! area lights and come from the mesh, not from this list.

use glam::Vec3;

/// A light given explicitly in the scene file.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightDesc {
    /// Isotropic point light; `intensity` in W/sr per channel.
    Point { position: Vec3, intensity: Vec3 },
    /// Point light restricted to a cone around `direction` (unit): full intensity within
    /// `cone_deg - falloff_deg` of the axis, smoothly falling to zero at `cone_deg`.
    Spot { position: Vec3, direction: Vec3, intensity: Vec3, cone_deg: f32, falloff_deg: f32 },
    /// Sun-like light from infinitely far; `direction` (unit) is the way the light travels,
    /// `irradiance` in W/m^2 on a surface perpendicular to it.
    Distant { direction: Vec3, irradiance: Vec3 },
}
