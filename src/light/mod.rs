//! Light sources: the explicit lights of the scene file ([`LightDesc`]: point, spot, distant,
//! environment)
//! and the area lights made of emissive triangles (from the mesh, not from this list).
//!
//! Sources: pbrt-v4 chapter 12 (light interface, `SampleLi`/`PDF_Li`, `SampleLe`, `Phi`) and
//! Jensen 2001, section 5.1 (photon emission with equal photon powers). Radiometry follows
//! `scenes/SCENES.md`: intensity in W/sr, radiance in W m^-2 sr^-1, irradiance in W/m^2, per
//! RGB channel.
//!
//! Photon power of an [`EmissionSample`] is `le |cos| / (pdf_pos pdf_dir)` (the cosine only for
//! area lights), see [`EmissionSample::photon_power`]; divide by the number of photons shot.

mod area;
mod bounds;
mod distant;
mod environment;
mod point;
pub mod portal;
mod set;
mod spot;

pub use area::{AreaLights, EmissionMap, EmissionTextures, EmitterTriangle, MAX_SUBDIVISION};
pub use distant::DistantLight;
pub use environment::{EnvironmentLight, EnvironmentMap};
pub use point::PointLight;
pub use portal::Portal;
pub use set::{Emission, Emitter, LightSet};
pub use spot::SpotLight;

use crate::geometry::{Aabb, TriangleMesh};
use crate::material::Material;
use crate::sampling::Distribution1D;
use glam::Vec3;

/// A light given explicitly in the scene file.
#[derive(Clone, Debug, PartialEq)]
pub enum LightDesc {
    /// Isotropic point light; `intensity` in W/sr per channel.
    Point { position: Vec3, intensity: Vec3 },
    /// Point light restricted to a cone around `direction` (unit): full intensity within
    /// `cone_deg - falloff_deg` of the axis, smoothly falling to zero at `cone_deg`.
    Spot { position: Vec3, direction: Vec3, intensity: Vec3, cone_deg: f32, falloff_deg: f32 },
    /// Sun-like light from infinitely far; `direction` (unit) is the way the light travels,
    /// `irradiance` in W/m^2 on a surface perpendicular to it.
    Distant { direction: Vec3, irradiance: Vec3 },
    /// Radiance from every direction at infinity: `radiance` times the equirectangular `map`
    /// (if any), the sky turned by `to_world` (a rotation).
    Environment { radiance: Vec3, map: Option<EnvironmentMap>, to_world: glam::Mat3 },
}

/// A direction toward a light from a receiving point, for next-event estimation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSample {
    /// Unit direction from the receiver toward the light.
    pub wi: Vec3,
    /// Distance to the sampled light point (for the shadow ray); infinite for distant lights.
    pub dist: f32,
    /// How much shorter than `dist` a shadow ray must stop so that it cannot reach the emitter
    /// itself: the sampled point's rounding-error bound, measured along `wi` (0 for point,
    /// spot and distant lights, which are not on a surface).
    pub end_error: f32,
    /// Incident radiance; for delta lights the incident "delta" term (`I / d^2` or `E`).
    pub li: Vec3,
    /// Solid-angle density; 1 for delta lights.
    pub pdf: f32,
    /// Whether the light is a delta light (no MIS possible).
    pub delta: bool,
}

/// A photon leaving a light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EmissionSample {
    /// Where the photon starts (already offset off an emitting surface).
    pub ray_origin: Vec3,
    /// Unit direction of travel.
    pub dir: Vec3,
    /// Front normal of the emitting surface (area lights only).
    pub normal: Option<Vec3>,
    /// Density of the origin: per area for area and distant lights, 1 for point and spot lights.
    pub pdf_pos: f32,
    /// Density of the direction: per solid angle, 1 for distant lights.
    pub pdf_dir: f32,
    /// Radiance (area), intensity toward `dir` (point, spot) or irradiance (distant).
    pub le: Vec3,
}

impl EmissionSample {
    /// The flux this single sample represents, `le |cos| / (pdf_pos pdf_dir)`.
    pub fn photon_power(&self) -> Vec3 {
        let cos = self.normal.map_or(1.0, |n| n.dot(self.dir).abs());
        self.le * (cos / (self.pdf_pos * self.pdf_dir))
    }
}

/// Rec.709 luminance of a linear RGB triple.
#[inline]
pub fn luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.2126, 0.7152, 0.0722))
}

/// Any light of the scene.
#[derive(Clone, Debug)]
pub enum Light {
    Point(PointLight),
    Spot(SpotLight),
    Distant(DistantLight),
    Environment(EnvironmentLight),
    /// All emissive triangles of the mesh.
    Area(AreaLights),
}

/// All emissive triangles of `mesh` (material of triangle `i` is `materials[tri_material[i]]`).
pub fn area_lights(mesh: &TriangleMesh, tri_material: &[u32], materials: &[Material]) -> AreaLights {
    AreaLights::from_mesh(mesh, tri_material, materials)
}

/// The explicit lights followed by the area lights (if any), preprocessed for `mesh.bounds()`
/// (distant lights emit through `portals`, when there are any; emissive materials with a
/// texture in `emission` emit it).
pub fn build_lights(
    descs: &[LightDesc],
    mesh: &TriangleMesh,
    tri_material: &[u32],
    materials: &[Material],
    portals: &[Portal],
    emission: Option<EmissionTextures<'_>>,
) -> Vec<Light> {
    let mut lights: Vec<Light> = descs.iter().map(Light::from_desc).collect();
    let area = AreaLights::from_mesh_textured(mesh, tri_material, materials, emission);
    if !area.is_empty() {
        lights.push(Light::Area(area));
    }
    let bounds = mesh.bounds();
    lights.iter_mut().for_each(|l| l.preprocess(bounds, portals));
    lights
}

/// A distribution picking lights by the luminance of their power (call after `preprocess`).
pub fn power_distribution(lights: &[Light]) -> Distribution1D {
    Distribution1D::new(&lights.iter().map(|l| luminance(l.power())).collect::<Vec<_>>())
}

impl Light {
    /// The light described by `desc` (a distant light still needs [`Light::preprocess`]).
    pub fn from_desc(desc: &LightDesc) -> Light {
        match desc.clone() {
            LightDesc::Point { position, intensity } => Light::Point(PointLight { position, intensity }),
            LightDesc::Spot { position, direction, intensity, cone_deg, falloff_deg } => {
                Light::Spot(SpotLight::new(position, direction, intensity, cone_deg, falloff_deg))
            }
            LightDesc::Distant { direction, irradiance } => {
                Light::Distant(DistantLight::new(direction, irradiance))
            }
            LightDesc::Environment { radiance, map, to_world } => {
                Light::Environment(EnvironmentLight::new(radiance, map.map(|m| m.0), to_world))
            }
        }
    }

    /// Lets a light adapt to the scene (distant lights record the bounding sphere and the
    /// portals).
    pub fn preprocess(&mut self, scene_bounds: Aabb, portals: &[Portal]) {
        match self {
            Light::Distant(d) => d.preprocess(scene_bounds, portals),
            Light::Environment(e) => e.preprocess(scene_bounds),
            _ => {}
        }
    }

    /// Whether the light is a delta light (cannot be hit by rays, no MIS).
    pub fn is_delta(&self) -> bool {
        !matches!(self, Light::Area(_) | Light::Environment(_))
    }

    /// Total emitted flux per channel (W).
    pub fn power(&self) -> Vec3 {
        match self {
            Light::Point(l) => l.power(),
            Light::Spot(l) => l.power(),
            Light::Distant(l) => l.power(),
            Light::Environment(l) => l.power(),
            Light::Area(l) => l.power(),
        }
    }

    /// Samples incident light at `p` (`u` is only used by area lights).
    #[inline]
    pub fn sample_li(&self, p: Vec3, u: [f32; 2]) -> Option<LightSample> {
        match self {
            Light::Point(l) => l.sample_li(p),
            Light::Spot(l) => l.sample_li(p),
            Light::Distant(l) => l.sample_li(p),
            Light::Environment(l) => l.sample_li(u),
            Light::Area(l) => l.sample_li(p, u),
        }
    }

    /// Solid-angle density of [`Light::sample_li`] from `p` for a ray along `wi` that hit mesh
    /// triangle `prim` at `hit_point`; zero for delta lights.
    pub fn pdf_li(&self, p: Vec3, wi: Vec3, prim: u32, hit_point: Vec3) -> f32 {
        match self {
            Light::Area(l) => l.pdf_li(p, wi, prim, hit_point),
            _ => 0.0,
        }
    }

    /// A photon: `u1` chooses the position (area, distant, environment), `u2` the direction
    /// (point, spot, area, environment). Photons of one light all carry the same power (equal luminance for untextured area lights).
    pub fn sample_emission(&self, u1: [f32; 2], u2: [f32; 2]) -> Option<EmissionSample> {
        match self {
            Light::Point(l) => l.sample_emission(u2),
            Light::Spot(l) => l.sample_emission(u2),
            Light::Distant(l) => l.sample_emission(u1),
            Light::Environment(l) => l.sample_emission(u1, u2),
            Light::Area(l) => l.sample_emission(u1, u2),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builds_lights_from_descriptions_and_mesh() {
        let mesh = TriangleMesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(0.0, 0.0, 2.0)],
            indices: vec![[0, 1, 2], [0, 1, 3]],
        };
        let mats =
            [Material::Emissive { kd: Vec3::ZERO, ke: Vec3::ONE }, Material::Diffuse { kd: Vec3::ONE }];
        let descs = [
            LightDesc::Point { position: Vec3::Y, intensity: Vec3::ONE },
            LightDesc::Distant { direction: Vec3::NEG_Z, irradiance: Vec3::ONE },
        ];
        let lights = build_lights(&descs, &mesh, &[0, 1], &mats, &[], None);
        assert_eq!(lights.len(), 3);
        assert!(lights[0].is_delta() && lights[1].is_delta() && !lights[2].is_delta());
        assert!(lights[1].power().x > 0.0, "distant light preprocessed");
        assert!((lights[2].power().x - std::f32::consts::PI * 0.5).abs() < 1e-5);
        let d = power_distribution(&lights);
        assert!((d.pmf(0) - 4.0 * std::f32::consts::PI / d.total()).abs() < 1e-5);
        assert!(lights[2].sample_li(Vec3::new(0.1, 0.1, 1.0), [0.5, 0.5]).is_some());
        assert_eq!(lights[0].pdf_li(Vec3::ZERO, Vec3::Y, 0, Vec3::Y), 0.0);
    }
}
