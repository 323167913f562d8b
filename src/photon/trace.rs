//! The photon pass (Jensen 2001, ch. 5; the lecture's slides on emission, storage, absorption
//! and bouncing).
//!
//! * The budget is split among emitters in proportion to their power, and a photon carries the
//!   flux of its emission sample ([`crate::light::Emission::power`]) over the photons expected
//!   from its emitter: every light samples in proportion to what it emits, so every photon of a
//!   map carries the same power (a textured light's nearly: its texture varies within the
//!   pieces it is sampled by), and brighter lights emit more photons, not stronger ones.
//!   Counts are rounded stochastically so the split stays unbiased.
//! * Emissive triangles are emitters of their own, each covered by a stratified grid (one photon
//!   per cell, at a random position inside it) with cosine-distributed directions.
//! * At each diffuse or glossy hit a copy of the photon is stored and the original goes on; the
//!   first hit straight from the light is never stored (direct light comes from shadow rays).
//! * Russian roulette on the surface's reflectances decides absorption, a diffuse bounce or a
//!   specular bounce; survivors keep their power (equal-power photons).
//! * The caustic map holds light → specular+ → diffuse paths. Caustic photons are aimed: an
//!   emission sample is kept only if its ray meets the bounding sphere of a specular object
//!   (a projection map made of spheres); rejected tries still count as emitted, so every photon
//!   keeps the power `flux / tries` and the estimate stays exact. Without aiming
//!   ([`PassSpec::aim`] false) caustic photons leave the lights as usual and only the
//!   light → specular+ → diffuse paths are stored: the same estimate, with fewer photons stored
//!   per photon traced.
//! * The indirect map holds photons with at least one diffuse bounce behind them.
//!
//! * Guided emission ([`super::guide`]): when a pilot of photons found that few reach what the
//!   camera sees, the budget is split by a mix of seen flux and power, and each emitter's
//!   position (distant lights) or direction (the others) follows the learnt density; each
//!   photon's power is divided by its sample's density, so the estimates keep their value.
//!
//! * Portals ([`super::portal`]): paths crossing a portal inward after a diffuse bounce are
//!   cut there, and each portal is an emitter of its own (after the lights) whose photons carry
//!   the light that came in that way.
//!
//! Work is split into fixed chunks, each with its own generator seeded from (seed, pass, chunk),
//! so the maps are identical for any number of threads.

use super::guide::{EmissionGuide, EmitterPilot, Grid2, Guided, VisibleRegion, DEFENSIVE};
use super::map::{Hits, PhotonHit};
use super::portal::{Outside, PortalSet};
use crate::accel::Accel;
use crate::config::ColorMode;
use crate::frame::{Progress, SurfaceHit};
use crate::geometry::Ray;
use crate::light::{Emitter, Light, LightSet};
use crate::material::{face_forward, LobeKind};
use crate::sampling::derive_seed;
use crate::scene::Scene;
use glam::Vec3;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg32;
use rayon::prelude::*;

/// Photons per work chunk (and per generator).
const CHUNK: u64 = 4096;

/// Which map a pass fills.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pass {
    /// Light → specular+ → diffuse paths, photons aimed at specular objects.
    Caustic,
    /// Paths with at least one diffuse bounce.
    Indirect,
}

/// What a pass produced: photons per map (one map in RGB mode, three per channel), how many
/// paths were emitted for each, and the rays traced.
#[derive(Debug, Default)]
pub struct PassOutput {
    pub maps: Vec<Hits>,
    pub emitted: Vec<u64>,
    pub rays: u64,
    pub paths: u64,
}

/// A bounding sphere of a group of specular triangles, target of caustic photons.
#[derive(Clone, Copy, Debug)]
pub struct Target {
    pub center: Vec3,
    pub radius: f32,
}

impl Target {
    /// Whether the ray `o + t d` (`t > 0`) meets the sphere.
    #[inline]
    fn hit_by(&self, o: Vec3, d: Vec3) -> bool {
        let oc = self.center - o;
        let r2 = self.radius * self.radius;
        let dd = d.length_squared();
        let tca = oc.dot(d);
        let d2 = oc.length_squared() - tca * tca / dd;
        // Inside the sphere, or ahead of the ray and close enough to its axis.
        oc.length_squared() <= r2 || (tca > 0.0 && d2 <= r2)
    }
}

/// Bounding spheres of the connected groups of specular triangles (triangles sharing a vertex
/// are connected). Many small groups are merged per material so the list stays short.
pub fn specular_targets(scene: &Scene) -> Vec<Target> {
    let mesh = &scene.mesh;
    let mut parent: Vec<u32> = (0..mesh.positions.len() as u32).collect();
    fn find(parent: &mut [u32], mut i: u32) -> u32 {
        while parent[i as usize] != i {
            parent[i as usize] = parent[parent[i as usize] as usize];
            i = parent[i as usize];
        }
        i
    }
    let specular: Vec<u32> = (0..mesh.len() as u32).filter(|&t| scene.material(t).is_specular()).collect();
    for &t in &specular {
        let [a, b, c] = mesh.indices[t as usize];
        let (ra, rb, rc) = (find(&mut parent, a), find(&mut parent, b), find(&mut parent, c));
        parent[rb as usize] = ra;
        parent[rc as usize] = ra;
    }
    let mut groups: std::collections::BTreeMap<u32, crate::geometry::Aabb> = Default::default();
    for &t in &specular {
        let root = find(&mut parent, mesh.indices[t as usize][0]);
        let b = groups.entry(root).or_default();
        for p in mesh.triangle(t) {
            *b = b.grow(p);
        }
    }
    const MAX_TARGETS: usize = 256;
    if groups.len() > MAX_TARGETS {
        // One sphere per specular material instead.
        let mut per_material: std::collections::BTreeMap<u32, crate::geometry::Aabb> = Default::default();
        for &t in &specular {
            let b = per_material.entry(scene.tri_material[t as usize]).or_default();
            for p in mesh.triangle(t) {
                *b = b.grow(p);
            }
        }
        groups = per_material;
    }
    groups
        .values()
        .map(|b| {
            let (center, radius) = b.bounding_sphere();
            // A little slack so rays grazing the silhouette are kept.
            Target { center, radius: radius * 1.001 + 1e-6 * center.abs().max_element() }
        })
        .collect()
}

/// One emitter's share of a pass: how many photons (or tries), for which map and channel, and
/// the factor that turns an emission sample's flux into a photon's power (one over the
/// photons expected from the emitter).
#[derive(Clone, Copy, Debug)]
struct EmitterShare {
    emitter: usize,
    map: usize,
    channel: Option<usize>,
    count: u64,
    scale: f32,
}

impl EmitterShare {
    /// The power of a photon whose emission sample stands for the flux `flux`.
    #[inline]
    fn photon_power(&self, flux: Vec3) -> Vec3 {
        match self.channel {
            Some(c) => {
                let mut p = Vec3::ZERO;
                p[c] = flux[c] * self.scale;
                p
            }
            None => flux * self.scale,
        }
    }
}

/// Splits `n` photons among emitters by power, per map, or with `seen` (each emitter's share of
/// the photons a pilot saw) by `DEFENSIVE` of power and the rest by `seen`. Returns the shares
/// and the photons allotted to each map.
fn allocate(
    emitters: &[Emitter],
    n: u64,
    color: ColorMode,
    seen: Option<&[f64]>,
    rng: &mut Pcg32,
) -> (Vec<EmitterShare>, Vec<u64>) {
    let mut shares = Vec::new();
    let channels: Vec<Option<usize>> = match color {
        ColorMode::PerChannel => vec![Some(0), Some(1), Some(2)],
        ColorMode::Rgb => vec![None],
    };
    let mut emitted = vec![0u64; channels.len()];
    for (map, &channel) in channels.iter().enumerate() {
        let n_map = n / channels.len() as u64 + u64::from((map as u64) < n % channels.len() as u64);
        let weight = |e: &Emitter| match channel {
            Some(c) => e.power[c],
            None => e.power.x + e.power.y + e.power.z,
        };
        let total: f64 = emitters.iter().map(|e| weight(e) as f64).sum();
        if !(total > 0.0) || n_map == 0 {
            continue;
        }
        // The seen shares of the emitters that emit in this map.
        let seen_total: f64 = seen
            .map_or(0.0, |s| emitters.iter().zip(s).filter(|(e, _)| weight(e) > 0.0).map(|(_, &s)| s).sum());
        for (i, e) in emitters.iter().enumerate() {
            let w = weight(e) as f64;
            if !(w > 0.0) {
                continue;
            }
            // The expected photons of this emitter, and one over them.
            let (expected, scale) = match seen {
                Some(s) if seen_total > 0.0 => {
                    let d = DEFENSIVE as f64;
                    let expected = n_map as f64 * ((1.0 - d) * s[i] / seen_total + d * w / total);
                    (expected, 1.0 / expected)
                }
                _ => (n_map as f64 * w / total, (total / n_map as f64) / w),
            };
            let count = expected.floor() as u64 + u64::from(rng.gen::<f64>() < expected.fract());
            if count == 0 {
                continue;
            }
            let scale = scale as f32;
            emitted[map] += count;
            shares.push(EmitterShare { emitter: i, map, channel, count, scale });
        }
    }
    (shares, emitted)
}

/// What one pass does.
#[derive(Clone, Copy, Debug)]
pub struct PassSpec<'a> {
    pub pass: Pass,
    /// Photons (indirect pass) or emission tries (caustic pass).
    pub n: u64,
    pub color: ColorMode,
    pub max_bounces: u32,
    /// Bounding spheres caustic photons are aimed at.
    pub targets: &'a [Target],
    /// Whether a caustic pass keeps only emission samples aimed at `targets`.
    pub aim: bool,
    /// Where the photons of an indirect pass are sent ([`super::guide`]); `None`: as emitted.
    pub guide: Option<&'a EmissionGuide>,
    /// The portals that cut paths and emit photons of their own (indirect passes only).
    pub portals: Option<Portals<'a>>,
    pub seed: u64,
}

/// The scene's portals and the radiance their photons carry in.
#[derive(Clone, Copy)]
pub struct Portals<'a> {
    pub set: &'a PortalSet,
    pub outside: &'a dyn Outside,
}

impl std::fmt::Debug for Portals<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Portals").field("set", self.set).finish()
    }
}

/// The emitters of a pass: the lights', then (indirect passes with portals) one per portal,
/// numbered after the lights (`light` = number of lights + the portal's index).
pub fn sources(lights: &LightSet, portals: Option<Portals<'_>>) -> Vec<Emitter> {
    let mut out = lights.emitters().to_vec();
    if let Some(p) = portals {
        let base = lights.lights().len();
        out.extend(p.set.powers().iter().enumerate().map(|(i, &power)| Emitter {
            light: base + i,
            triangle: None,
            power,
        }));
    }
    out
}

/// A photon of emitter `e` of [`sources`]: its start, direction and flux, whether it carries
/// light that was already bounced (a portal's photon, stored at its first hit), and the rays
/// traced to make it.
#[inline]
fn emit(
    lights: &LightSet,
    portals: Option<Portals<'_>>,
    e: &Emitter,
    u_pos: [f32; 2],
    u_dir: [f32; 2],
    rng: &mut Pcg32,
) -> (Option<crate::light::Emission>, bool, u64) {
    match (e.light.checked_sub(lights.lights().len()), portals) {
        (Some(i), Some(p)) => {
            let ((origin, dir, power), rays) = p.set.emit(i, u_pos, u_dir, p.outside, rng);
            let em = (power.max_element() > 0.0).then_some(crate::light::Emission { origin, dir, power });
            (em, true, rays)
        }
        (Some(_), None) => (None, false, 0),
        (None, _) => (lights.sample_emission(e, u_pos, u_dir), false, 0),
    }
}

/// The photon chunks of `shares`: (share, first photon, end).
fn chunks(shares: &[EmitterShare]) -> Vec<(usize, u64, u64)> {
    let mut chunks = Vec::new();
    for (j, share) in shares.iter().enumerate() {
        let mut start = 0;
        while start < share.count {
            let end = (start + CHUNK).min(share.count);
            chunks.push((j, start, end));
            start = end;
        }
    }
    chunks
}

/// Which of an emitter's sample dimensions guiding reshapes.
fn guided_dims(lights: &LightSet, e: &Emitter) -> Guided {
    match lights.lights().get(e.light) {
        Some(Light::Distant(_)) => Guided::Position,
        _ => Guided::Direction,
    }
}

/// A pilot of `n` photons of an indirect pass, split among emitters by power and emitted as
/// usual or, with `guide`, as its grids say: for each emitter, the photons emitted and stored
/// and, per path, its guided sample and the photons it stored inside `region` over the
/// sample's density. Also returns the rays traced.
#[allow(clippy::too_many_arguments)]
pub fn pilot<A: Accel>(
    scene: &Scene,
    accel: &A,
    lights: &LightSet,
    n: u64,
    max_bounces: u32,
    region: &VisibleRegion,
    guide: Option<&EmissionGuide>,
    portals: Option<Portals<'_>>,
    seed: u64,
) -> (Vec<EmitterPilot>, u64) {
    let emitters = &sources(lights, portals)[..];
    let mut alloc_rng = Pcg32::seed_from_u64(derive_seed(seed, 0x9170, u64::MAX));
    let (shares, _) = allocate(emitters, n, ColorMode::Rgb, None, &mut alloc_rng);
    let chunks = chunks(&shares);
    // Per chunk: the emitter, its pilot, and the rays traced.
    let results: Vec<(usize, EmitterPilot, u64)> = chunks
        .par_iter()
        .enumerate()
        .map(|(ci, &(j, start, end))| {
            let share = &shares[j];
            let e = &emitters[share.emitter];
            let dims = guided_dims(lights, e);
            let mut rng = Pcg32::seed_from_u64(derive_seed(seed, 0x9170, ci as u64));
            let strata = Strata::new(share.count);
            let grid = guide.and_then(|g| g.grids[share.emitter].as_ref());
            let (mut samples, mut rays, mut stored) = (Vec::new(), 0u64, Vec::new());
            let (mut total, mut seen_total, mut flux, mut flux2) = (0u64, 0u64, 0.0f64, 0.0f64);
            for i in start..end {
                let (u_pos, u_dir, density) = emission_samples(&strata, i, grid, &mut rng);
                let (em, bounced, r) = emit(lights, portals, e, u_pos, u_dir, &mut rng);
                rays += r;
                let Some(em) = em else { continue };
                stored.clear();
                let power = share.photon_power(em.power) / density;
                let start = Start { origin: em.origin, dir: em.dir, power, bounced };
                rays += trace_photon(
                    scene,
                    accel,
                    Pass::Indirect,
                    start,
                    None,
                    max_bounces,
                    portals.map(|p| p.set),
                    &mut rng,
                    &mut stored,
                );
                total += stored.len() as u64;
                let seen = stored.iter().filter(|h| region.contains(h.pos)).count();
                seen_total += seen as u64;
                // The flux of the photons seen (photons of unequal power, from a distant light's
                // portals and the disc outside them, weigh what they carry): over the samples
                // of one pilot, an estimate of the seen flux of the emitter.
                let carried = crate::light::luminance(power);
                let weight = seen as f32 * carried;
                // Per photon of a pilot of n, for the effective number of seen photons.
                let p = carried as f64 * n as f64;
                flux += seen as f64 * p;
                flux2 += seen as f64 * p * p;
                samples.push((if dims == Guided::Position { u_pos } else { u_dir }, weight));
            }
            (
                share.emitter,
                EmitterPilot { emitted: 0, stored: total, seen: seen_total, flux, flux2, samples },
                rays,
            )
        })
        .collect();
    let mut out = vec![EmitterPilot::default(); emitters.len()];
    for share in &shares {
        out[share.emitter].emitted += share.count;
    }
    let mut rays = 0;
    for (e, chunk, r) in results {
        out[e].samples.extend(chunk.samples);
        out[e].stored += chunk.stored;
        out[e].seen += chunk.seen;
        out[e].flux += chunk.flux;
        out[e].flux2 += chunk.flux2;
        rays += r;
    }
    (out, rays)
}

/// The guided dimensions of every emitter, in the order of [`LightSet::emitters`].
pub fn guided_kinds(lights: &LightSet, portals: Option<Portals<'_>>) -> Vec<Guided> {
    sources(lights, portals).iter().map(|e| guided_dims(lights, e)).collect()
}

/// Traces one pass; `progress` advances by the photons of each finished chunk.
pub fn trace_pass<A: Accel>(
    scene: &Scene,
    accel: &A,
    lights: &LightSet,
    spec: &PassSpec<'_>,
    progress: &dyn Progress,
) -> PassOutput {
    let PassSpec { pass, n, color, max_bounces, targets, aim, guide, portals, seed } = *spec;
    let portals = portals.filter(|_| pass == Pass::Indirect);
    let emitters = &sources(lights, portals)[..];
    let mut alloc_rng = Pcg32::seed_from_u64(derive_seed(seed, pass as u64, u64::MAX));
    let (shares, emitted) = allocate(emitters, n, color, guide.map(|g| &g.seen_share[..]), &mut alloc_rng);
    // Fixed chunks over the concatenated shares.
    let chunks = chunks(&shares);
    let n_maps = emitted.len();
    let results: Vec<(Vec<Vec<PhotonHit>>, u64, u64)> = chunks
        .par_iter()
        .enumerate()
        .map(|(ci, &(j, start, end))| {
            let share = &shares[j];
            let mut rng = Pcg32::seed_from_u64(derive_seed(seed, pass as u64, ci as u64));
            let mut out = vec![Vec::new(); n_maps];
            let (mut rays, mut paths) = (0u64, 0u64);
            let e = &emitters[share.emitter];
            let strata = Strata::new(share.count);
            let grid = guide.and_then(|g| g.grids[share.emitter].as_ref());
            for i in start..end {
                let (u_pos, u_dir, density) = emission_samples(&strata, i, grid, &mut rng);
                let (em, bounced, r) = emit(lights, portals, e, u_pos, u_dir, &mut rng);
                rays += r;
                let Some(em) = em else { continue };
                if pass == Pass::Caustic && aim && !targets.iter().any(|t| t.hit_by(em.origin, em.dir)) {
                    continue;
                }
                paths += 1;
                let power = share.photon_power(em.power) / density;
                let start = Start { origin: em.origin, dir: em.dir, power, bounced };
                rays += trace_photon(
                    scene,
                    accel,
                    pass,
                    start,
                    share.channel,
                    max_bounces,
                    portals.map(|p| p.set),
                    &mut rng,
                    &mut out[share.map],
                );
            }
            progress.advance(end - start);
            (out, rays, paths)
        })
        .collect();
    let mut output = PassOutput { maps: Vec::new(), emitted, rays: 0, paths: 0 };
    let mut per_map: Vec<Vec<Vec<PhotonHit>>> = vec![Vec::with_capacity(results.len()); n_maps];
    for (maps, rays, paths) in results {
        for (dst, src) in per_map.iter_mut().zip(maps) {
            dst.push(src);
        }
        output.rays += rays;
        output.paths += paths;
    }
    output.maps = per_map.into_iter().map(Hits::from_chunks).collect();
    output
}

/// The position and direction samples of photon `i` of an emitter, reshaped by its guide grid
/// if it has one, and the density of the reshaped sample (1 without a grid).
#[inline]
fn emission_samples(
    strata: &Strata,
    i: u64,
    grid: Option<&(Guided, Grid2)>,
    rng: &mut Pcg32,
) -> ([f32; 2], [f32; 2], f32) {
    let u_pos = strata.sample(i, rng);
    let u_dir = [rng.gen(), rng.gen()];
    match grid {
        None => (u_pos, u_dir, 1.0),
        Some((Guided::Position, g)) => {
            let (u, d) = g.sample(u_pos);
            (u, u_dir, d)
        }
        Some((Guided::Direction, g)) => {
            let (u, d) = g.sample(u_dir);
            (u_pos, u, d)
        }
    }
}

/// Where a photon starts: from a light, or (`bounced`) from a portal with light that met a
/// diffuse surface outside already (stored from its first hit on).
#[derive(Clone, Copy, Debug)]
struct Start {
    origin: Vec3,
    dir: Vec3,
    power: Vec3,
    bounced: bool,
}

/// Follows one photon, storing copies at diffuse hits as `pass` requires; with `cut`, a photon
/// past a diffuse bounce stops where it crosses a portal inward. Returns rays cast.
#[allow(clippy::too_many_arguments)]
fn trace_photon<A: Accel>(
    scene: &Scene,
    accel: &A,
    pass: Pass,
    start: Start,
    channel: Option<usize>,
    max_bounces: u32,
    cut: Option<&PortalSet>,
    rng: &mut Pcg32,
    out: &mut Vec<PhotonHit>,
) -> u64 {
    let mut ray = Ray::new(start.origin, start.dir);
    let mut power = start.power;
    let mut specular_only = !start.bounced;
    let mut rays = 0;
    for bounce in 0..=max_bounces {
        rays += 1;
        let hit = accel.intersect(&ray);
        if !specular_only && bounce > 0 {
            if let Some(c) = cut {
                if c.cuts(ray.origin, ray.dir, hit.map_or(f32::INFINITY, |h| h.t)) {
                    break;
                }
            }
        }
        let Some(hit) = hit else { break };
        let Some(at) = SurfaceHit::new(scene, hit) else { break };
        let (p, err, n) = (at.p, at.err, at.n);
        let m = &scene.material_at(hit.prim, at.uv, at.colour);
        let wo = -ray.dir.normalize();
        if m.is_diffuse_like() {
            match pass {
                Pass::Caustic => {
                    if bounce > 0 && specular_only {
                        out.push(PhotonHit { pos: p, err, n: face_forward(n, wo), wi: wo, power });
                    }
                    break;
                }
                Pass::Indirect => {
                    if !specular_only {
                        out.push(PhotonHit { pos: p, err, n: face_forward(n, wo), wi: wo, power });
                    }
                }
            }
        }
        if bounce == max_bounces {
            break;
        }
        let Some(s) =
            at.normals().scatter_photon(m, wo, power, channel, rng.gen(), rng.gen(), [rng.gen(), rng.gen()])
        else {
            break;
        };
        if matches!(s.kind, LobeKind::Diffuse | LobeKind::Glossy) {
            specular_only = false;
        }
        power = s.power;
        ray = Ray::new(at.spawn(s.wi), s.wi);
    }
    rays
}

/// The position samples of `n` photons on an emitter: jittered cells of an `m × m` grid
/// (`m² <= n`), the remainder uniformly random.
#[derive(Clone, Copy, Debug)]
struct Strata {
    side: u64,
}

impl Strata {
    fn new(n: u64) -> Self {
        Strata { side: (n as f64).sqrt() as u64 }
    }

    /// Position sample `i`.
    #[inline]
    fn sample(&self, i: u64, rng: &mut Pcg32) -> [f32; 2] {
        let m = self.side;
        if i < m * m {
            let (cx, cy) = (i % m, i / m);
            [(cx as f32 + rng.gen::<f32>()) / m as f32, (cy as f32 + rng.gen::<f32>()) / m as f32]
        } else {
            [rng.gen(), rng.gen()]
        }
        .map(|u: f32| u.min(1.0 - f32::EPSILON / 2.0))
    }
}

/// Fraction of emission samples that meet a specular target, estimated from `tries` samples
/// split among emitters by power (the same split as the pass). Used to turn a caustic photon
/// budget into a number of tries.
pub fn target_acceptance(lights: &LightSet, targets: &[Target], tries: u64, seed: u64) -> f64 {
    if targets.is_empty() {
        return 0.0;
    }
    let emitters = lights.emitters();
    let mut rng = Pcg32::seed_from_u64(derive_seed(seed, 7, 7));
    let (shares, _) = allocate(emitters, tries, ColorMode::Rgb, None, &mut rng);
    let (mut accepted, mut total) = (0u64, 0u64);
    for share in &shares {
        let strata = Strata::new(share.count);
        for i in 0..share.count {
            total += 1;
            let u_pos = strata.sample(i, &mut rng);
            if let Some(em) = lights.sample_emission(&emitters[share.emitter], u_pos, [rng.gen(), rng.gen()])
            {
                accepted += u64::from(targets.iter().any(|t| t.hit_by(em.origin, em.dir)));
            }
        }
    }
    if total == 0 {
        0.0
    } else {
        accepted as f64 / total as f64
    }
}
