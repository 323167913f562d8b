//! The scene's lights as the renderer sees them: one distribution to pick a light for a shadow
//! ray (by power), and a flat list of photon emitters where every emissive triangle is an
//! emitter of its own (so the photon pass can stratify over each).

use super::bounds::EmitterBounds;
use super::LightDesc;
use super::{build_lights, power_distribution, EmissionTextures, Light, LightSample, Portal};
use crate::geometry::TriangleMesh;
use crate::material::Material;
use crate::sampling::Distribution1D;
use glam::Vec3;

/// A photon source: a light, or one triangle of the area lights.
#[derive(Clone, Copy, Debug)]
pub struct Emitter {
    pub light: usize,
    /// Index into the area light's triangles.
    pub triangle: Option<usize>,
    /// Flux per channel (W) the photon budget is split by: the emitted flux, or for a distant
    /// light with portals its flux through them over the share of photons sent that way.
    pub power: Vec3,
}

/// Where a photon starts, where it goes, and the flux the sample stands for.
#[derive(Clone, Copy, Debug)]
pub struct Emission {
    pub origin: Vec3,
    pub dir: Vec3,
    /// `le |cos| / (pdf_pos pdf_dir)` ([`EmissionSample::photon_power`](super::EmissionSample::photon_power)):
    /// the emitter's whole flux when it is sampled in proportion to what it emits, as every
    /// light here is; divided by the photons shot, it is the photon's power.
    pub power: Vec3,
}

/// All lights of a scene, ready for sampling.
pub struct LightSet {
    lights: Vec<Light>,
    select: Distribution1D,
    emitters: Vec<Emitter>,
    area: Option<usize>,
    environment: Option<usize>,
    /// The portals distant lights emit through (and the photon pass cuts at).
    portals: Vec<Portal>,
    /// Where the emissive triangles are.
    emitter_bounds: EmitterBounds,
}

impl LightSet {
    /// The lights of `descs` and the emissive triangles of `mesh` (see [`build_lights`]).
    pub fn new(
        descs: &[LightDesc],
        mesh: &TriangleMesh,
        tri_material: &[u32],
        materials: &[Material],
    ) -> Self {
        Self::with_portals(descs, mesh, tri_material, materials, &[])
    }

    /// As [`LightSet::new`], the distant lights emitting through `portals` (none: as usual).
    pub fn with_portals(
        descs: &[LightDesc],
        mesh: &TriangleMesh,
        tri_material: &[u32],
        materials: &[Material],
        portals: &[Portal],
    ) -> Self {
        Self::with_emission(descs, mesh, tri_material, materials, portals, None)
    }

    /// As [`LightSet::with_portals`], the emissive materials with a texture in `emission`
    /// emitting it.
    pub fn with_emission(
        descs: &[LightDesc],
        mesh: &TriangleMesh,
        tri_material: &[u32],
        materials: &[Material],
        portals: &[Portal],
        emission: Option<EmissionTextures<'_>>,
    ) -> Self {
        let lights = build_lights(descs, mesh, tri_material, materials, portals, emission);
        let select = power_distribution(&lights);
        let mut emitters = Vec::new();
        let mut area = None;
        let mut environment = None;
        for (i, l) in lights.iter().enumerate() {
            if matches!(l, Light::Environment(_)) {
                environment = Some(i);
            }
            match l {
                Light::Area(a) => {
                    area = Some(i);
                    emitters.extend(a.triangles().iter().enumerate().map(|(t, tri)| Emitter {
                        light: i,
                        triangle: Some(t),
                        power: tri.power(),
                    }));
                }
                Light::Distant(d) => {
                    emitters.push(Emitter { light: i, triangle: None, power: d.budget_power() })
                }
                _ => emitters.push(Emitter { light: i, triangle: None, power: l.power() }),
            }
        }
        emitters.retain(|e| e.power.max_element() > 0.0 && e.power.is_finite());
        let emitter_bounds = EmitterBounds::new(mesh, tri_material, materials);
        LightSet { lights, select, emitters, area, environment, portals: portals.to_vec(), emitter_bounds }
    }

    /// Whether there is nothing to sample.
    pub fn is_empty(&self) -> bool {
        self.select.total() <= 0.0
    }

    /// The portals this set was built with (none with `--portals false`).
    pub fn portals(&self) -> &[Portal] {
        &self.portals
    }

    /// Whether some triangles emit.
    pub fn has_area(&self) -> bool {
        self.area.is_some()
    }

    /// Whether BSDF-sampled rays can find light: emissive triangles, or a sky to escape to.
    pub fn has_hittable(&self) -> bool {
        self.area.is_some() || self.environment.is_some()
    }

    /// Whether a ray from `origin` along `dir` may find light: it can escape to a sky, or it
    /// crosses the bounds of the emissive triangles. A ray for which this is false meets no
    /// emitter and sees no sky (conservative: the converse does not hold).
    #[inline]
    pub fn may_find_light(&self, origin: Vec3, dir: Vec3) -> bool {
        self.environment.is_some() || self.emitter_bounds.crossed_by(origin, dir)
    }

    /// Whether the emissive triangles surely subtend less than `limit` steradians from `p`
    /// (from a bound on their solid angle; a sky is not counted).
    #[inline]
    pub fn emitters_subtend_less(&self, p: Vec3, limit: f32) -> bool {
        self.emitter_bounds.subtend_less(p, limit)
    }

    /// Whether there is a sky (an environment light) for rays to escape to.
    #[inline]
    pub fn has_sky(&self) -> bool {
        self.environment.is_some()
    }

    /// Radiance a ray leaving the scene along `dir` (unit) sees: the sky's, or zero.
    #[inline]
    pub fn escaped(&self, dir: Vec3) -> Vec3 {
        match self.environment.map(|i| &self.lights[i]) {
            Some(Light::Environment(e)) => e.radiance_toward(dir),
            _ => Vec3::ZERO,
        }
    }

    /// Density with which [`LightSet::sample_li`] picks the sky along `dir` (pick included);
    /// zero without a sky.
    #[inline]
    pub fn pdf_li_escaped(&self, dir: Vec3) -> f32 {
        match self.environment.map(|i| (i, &self.lights[i])) {
            Some((i, Light::Environment(e))) => self.select.pmf(i) * e.pdf(dir),
            _ => 0.0,
        }
    }

    pub fn lights(&self) -> &[Light] {
        &self.lights
    }

    /// Emitters with non-zero power.
    pub fn emitters(&self) -> &[Emitter] {
        &self.emitters
    }

    /// Total flux per channel.
    pub fn total_power(&self) -> Vec3 {
        self.emitters.iter().map(|e| e.power).sum()
    }

    /// Incident light at `p`: a light picked by power with `u_sel`, then sampled with `u`; the
    /// pdf includes the pick.
    #[inline]
    pub fn sample_li(&self, p: Vec3, u_sel: f32, u: [f32; 2]) -> Option<LightSample> {
        let (i, pmf, _) = self.select.sample(u_sel)?;
        let mut ls = self.lights[i].sample_li(p, u)?;
        ls.pdf *= pmf;
        (ls.pdf > 0.0 && ls.li.is_finite()).then_some(ls)
    }

    /// Density with which [`LightSet::sample_li`] from `p` picks the point `y` on emissive
    /// triangle `prim` (solid angle, pick included); zero if `prim` does not emit toward `p`.
    pub fn pdf_li_hit(&self, p: Vec3, prim: u32, y: Vec3, _ny: Vec3) -> f32 {
        let Some(a) = self.area else { return 0.0 };
        let wi = (y - p).normalize_or_zero();
        self.select.pmf(a) * self.lights[a].pdf_li(p, wi, prim, y)
    }

    /// A photon leaving emitter `e`: `u_pos` places it (stratified by the caller), `u_dir` aims it.
    #[inline]
    pub fn sample_emission(&self, e: &Emitter, u_pos: [f32; 2], u_dir: [f32; 2]) -> Option<Emission> {
        let s = match (e.triangle, &self.lights[e.light]) {
            (Some(t), Light::Area(a)) => a.sample_emission_on_triangle(t, u_pos, u_dir)?,
            (_, l) => l.sample_emission(u_pos, u_dir)?,
        };
        let power = s.photon_power();
        (s.dir.is_finite() && s.ray_origin.is_finite() && power.is_finite()).then_some(Emission {
            origin: s.ray_origin,
            dir: s.dir,
            power,
        })
    }
}
