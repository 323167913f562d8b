//! The photon stages of a pass, shared by two-pass and progressive photon mapping: the scene
//! analysis that decides which maps are needed, the indirect and caustic photon passes, the
//! balancing of the maps (each stage recorded in the stats with why it ran or why not), and the
//! gather parameters both read the maps with.

use super::passes;
use crate::accel::Accel;
use crate::config::{CausticPass, ColorMode, Gathers, PhotonPasses};
use crate::frame::{Frame, Progress};
use crate::light::LightSet;
use crate::photon::guide::{
    effective_efficiency, EmissionGuide, EmitterPilot, VisibleRegion, GUIDE_BELOW, GUIDE_GAIN,
};
use crate::photon::irradiance::{self, SitePoint};
use crate::photon::map::{GatherParams, MapColor, PhotonMap, PhotonMaps};
use crate::photon::portal::{Outside, PortalSet};
use crate::photon::trace::{self, Pass, PassSpec, Portals, Target};
use crate::sampling::derive_seed;
use crate::scene::Scene;
use crate::stats::Stats;
use glam::Vec3;
use rayon::prelude::*;
use std::cell::OnceCell;

/// What the scene needs, decided before any work.
#[derive(Clone, Debug)]
pub struct Analysis {
    /// Some triangle is a mirror or glass.
    pub has_specular: bool,
    /// Some triangle is diffuse or glossy (stores photons, gathers light).
    pub has_diffuse: bool,
    pub light_power: Vec3,
    /// Where caustic photons are aimed and the share of emission that reaches there, worked
    /// out at the first caustic pass (with its seed) and kept for the passes after it.
    aim: OnceCell<Aim>,
    /// What the camera sees and where photons are sent, worked out at the first photon pass.
    guide: OnceCell<Guide>,
    /// The portals of the photon pass and their incoming flux, worked out at the first pass.
    portals: OnceCell<PortalSet>,
}

/// The region the camera sees (for the maps' efficiency) and, when a pilot found that few
/// photons reach it, the emission guided there.
#[derive(Clone, Debug, Default)]
struct Guide {
    region: VisibleRegion,
    emission: Option<EmissionGuide>,
}

/// The specular targets of aimed caustic photons, and the share of emission aimed at them (0:
/// none found, or nothing to aim at).
#[derive(Clone, Debug)]
struct Aim {
    targets: Vec<Target>,
    acceptance: f64,
}

impl Analysis {
    pub fn of(scene: &Scene, lights: &LightSet) -> Self {
        let mut used = vec![false; scene.materials.len()];
        for &m in &scene.tri_material {
            used[m as usize] = true;
        }
        let any = |f: fn(&crate::material::Material) -> bool| {
            scene.materials.iter().zip(&used).any(|(m, &u)| u && f(m))
        };
        // A glTF metallic-roughness texture can make any texel plastic or matte (never a mirror
        // where the material is not one: `MetalRough`).
        let textured_diffuse = scene.maps.iter().zip(&used).any(|(maps, &u)| u && maps.metal_rough.is_some());
        Analysis {
            has_specular: any(|m| m.is_specular()),
            has_diffuse: any(|m| m.is_diffuse_like()) || textured_diffuse,
            light_power: lights.total_power(),
            aim: OnceCell::new(),
            guide: OnceCell::new(),
            portals: OnceCell::new(),
        }
    }

    /// Whether any light has power.
    pub fn has_light(&self) -> bool {
        self.light_power.max_element() > 0.0
    }
}

/// Emission samples from which the share of aimed caustic photons is estimated: more, 16 times
/// over, while none is aimed at a target (a 1 cm marble 2 m from a point light takes one in
/// about 600 000; 65 536 tries found none and its caustic vanished).
const ACCEPTANCE_TRIES: [u64; 3] = [1 << 16, 1 << 20, 1 << 24];

/// Photons of the first pilot of guided emission: an eighth of the pass's budget within these bounds;
/// the pilot grows 4 times over, up to the last, while it sees fewer than [`PILOT_SEEN`], unless
/// a pilot of the middle size or more has stored no photon anywhere (see [`barren`]). (A
/// pilot grown to 2^22 photons whenever guiding runs, to meet more of the rare paths, did
/// worse on the sunroom: RMSE 0.0043 against 0.0030 at 20 s, the mean of four seeds.)
const PILOT_PHOTONS: [u64; 3] = [1 << 16, 1 << 20, 1 << 23];
const PILOT_SEEN: u64 = 300;

/// Which maps an integrator reads, and how they are traced.
#[derive(Clone, Copy, Debug)]
pub struct MapStages<'a> {
    pub passes: &'a PhotonPasses,
    /// Why the image does not need the indirect map, if it does not (a `--component` choice).
    pub indirect_unused: Option<&'static str>,
    /// Why the image does not need the caustic map, if it does not.
    pub caustic_unused: Option<&'static str>,
    /// Trace one path for every this-many indirect photon paths, whose hits are the sites of
    /// precomputed irradiance (`None`: no sites).
    pub site_stride: Option<usize>,
    /// Trace the sites of precomputed caustic irradiance ([`CAUSTIC_SITE_SHARE`]).
    pub caustic_sites: bool,
}

/// The caustic sites' paths are this fraction of the caustic map's (tries), so the sites are
/// about half as dense as the caustic photons: a few per gather disc of the map's 60 photons.
pub const CAUSTIC_SITE_SHARE: u64 = 2;

/// Where a pass's irradiance is to be precomputed: photon positions of each map.
#[derive(Debug, Default)]
pub struct Sites {
    pub indirect: Vec<SitePoint>,
    pub caustic: Vec<SitePoint>,
}

impl MapStages<'_> {
    /// Traces and balances the maps of `pass` (empty maps dropped), and picks the photon
    /// positions for precomputed irradiance. What the analysis works out once (the aim, the
    /// guide, the portals) it works out from the render's seed, whichever pass comes first,
    /// so that a pass's maps depend on the seed and the pass index only (`--pass-range`).
    pub fn trace<A: Accel>(
        &self,
        frame: &Frame<'_, A>,
        analysis: &Analysis,
        pass: &passes::Pass,
        stats: &mut Stats,
        progress: &dyn Progress,
    ) -> (PhotonMaps, Sites) {
        let seeds = Seeds { pass: pass.seed, render: pass.samples.seed };
        let (indirect, sites) = self.indirect(frame, analysis, seeds, stats, progress);
        let (caustic, caustic_sites) = self.caustic(frame, analysis, seeds, stats, progress);
        (PhotonMaps { indirect, caustic }, Sites { indirect: sites, caustic: caustic_sites })
    }

    fn indirect<A: Accel>(
        &self,
        frame: &Frame<'_, A>,
        analysis: &Analysis,
        seeds: Seeds,
        stats: &mut Stats,
        progress: &dyn Progress,
    ) -> (Vec<PhotonMap>, Vec<SitePoint>) {
        let seed = seeds.pass;
        let p = self.passes;
        let why_not = if !analysis.has_light() {
            Some("no light has power")
        } else if !analysis.has_diffuse {
            Some("nothing diffuse or glossy: no surface stores photons")
        } else if p.photons == 0 {
            Some("photon budget is 0")
        } else {
            self.indirect_unused
        };
        if let Some(why) = why_not {
            stats.skip("photons.indirect", why);
            return (Vec::new(), Vec::new());
        }
        let outside = crate::integrator::path::Outside { frame, max_depth: p.max_bounces };
        let set = analysis.portals.get_or_init(|| self.portal_set(frame, &outside, seeds.render, stats));
        let portals = (!set.is_empty()).then_some(Portals { set, outside: &outside });
        let guide = analysis.guide.get_or_init(|| self.guide(frame, portals, seeds.render, stats));
        progress.start("indirect photons", p.photons);
        let why = if guide.emission.is_some() {
            "diffuse surfaces and lit scene; emission guided toward what the camera sees"
        } else {
            "diffuse surfaces and lit scene"
        };
        // The map's paths, and the sites' (below), traced the same way.
        let spec = |n, seed| PassSpec {
            pass: Pass::Indirect,
            n,
            color: p.color,
            max_bounces: p.max_bounces,
            targets: &[],
            aim: false,
            guide: guide.emission.as_ref(),
            portals,
            seed,
        };
        let out = stats.run("photons.indirect", why, |_| {
            trace::trace_pass(frame.scene, frame.accel, frame.lights, &spec(p.photons, seed), progress)
        });
        progress.finish();
        stats.rays.photon += out.rays;
        // The seen photons counted while the maps are built, which fills the cores the builds'
        // serial steps leave idle.
        let (maps, seen) = stats.run("kdtree.indirect", "balance the indirect map", |_| {
            rayon::join(|| build_maps(&out, p.color), || count_seen(&out, &guide.region))
        });
        drop(out);
        record_maps(stats, "indirect", &maps, &seen);
        let maps = drop_empty(stats, "indirect", maps);
        let sites = match self.site_stride {
            Some(stride) if !maps.is_empty() => {
                // The sites of precomputed irradiance: where indirect photons land, from paths
                // of their own, traced the same way: one for every `stride` of the map's paths,
                // and as many sites whatever the colour mode (per-channel paths, a third each
                // map's, are a third as many).
                // Sites at the map's own photons were biased: a site's estimate counted its own
                // photon (+3 / (k - 1) with the cone), and where photons happened to be sparse
                // the site read low over a larger cell (about -2 %); both cancelled only in
                // part, and with the gathers' shortfall at edges. A point independent of the
                // map gets the estimate any point gets.
                let channels = if p.color == ColorMode::PerChannel { 3 } else { 1 };
                let n = p.photons.div_ceil((stride * channels) as u64);
                progress.start("irradiance sites", n);
                let why = format!(
                    "{n} indirect paths traced for where they land: sites independent of the map's photons"
                );
                let sites = stats.run("photons.indirect_sites", why, |stats| {
                    let spec = spec(n, seed ^ 0x517E);
                    let out = trace::trace_pass(frame.scene, frame.accel, frame.lights, &spec, progress);
                    stats.rays.photon += out.rays;
                    irradiance::pick_sites(&out.maps, 1)
                });
                progress.finish();
                sites
            }
            _ => Vec::new(),
        };
        (maps, sites)
    }

    /// The scene's portals (none with `--portals false`) with their incoming flux estimated
    /// with `outside` (stage `photons.portals`).
    fn portal_set<A: Accel>(
        &self,
        frame: &Frame<'_, A>,
        outside: &dyn Outside,
        seed: u64,
        stats: &mut Stats,
    ) -> PortalSet {
        let portals = frame.lights.portals();
        if portals.is_empty() {
            return PortalSet::default();
        }
        let eye = frame.views.first().unwrap_or(&frame.camera).eye;
        let (set, reason) = stats.run("photons.portals", "", |stats| {
            let (set, rays) = PortalSet::new(portals, eye, outside, derive_seed(seed, 0x9077, 0));
            stats.rays.photon += rays;
            let flux: f32 = set.powers().iter().map(|&p| crate::light::luminance(p)).sum();
            let reason = format!(
                "{} portals: paths cut where they cross one inward after a diffuse bounce; {flux:.3e} W estimated to come in that way, brought by the portals' photons",
                set.len()
            );
            (set, reason)
        });
        if let Some(stage) = stats.stages.last_mut() {
            stage.reason = reason;
        }
        set
    }

    /// The region the camera sees and, unless `--photon-guide false` or the photons reach it
    /// well enough already, the guided emission learnt from a pilot (a stage of its own).
    fn guide<A: Accel>(
        &self,
        frame: &Frame<'_, A>,
        portals: Option<Portals<'_>>,
        seed: u64,
        stats: &mut Stats,
    ) -> Guide {
        let p = self.passes;
        let region = VisibleRegion::of(frame, seed);
        let why_not = if !p.guide {
            Some("off (--photon-guide false)".to_string())
        } else if region.is_empty() {
            Some("the camera sees no surface".to_string())
        } else {
            None
        };
        if let Some(why) = why_not {
            stats.skip("photons.guide", why);
            return Guide { region, emission: None };
        }
        let kinds = trace::guided_kinds(frame.lights, portals);
        let (emission, reason) = stats.run("photons.guide", "", |stats| {
            let mut pilot = Vec::new();
            let mut n = 0u64;
            let run_pilot = |stats: &mut Stats, photons: u64, guide: Option<&EmissionGuide>, n: u64| {
                let (run, rays) = trace::pilot(
                    frame.scene,
                    frame.accel,
                    frame.lights,
                    photons,
                    p.max_bounces,
                    &region,
                    guide,
                    portals,
                    derive_seed(seed, 0x9170, n),
                );
                stats.rays.photon += rays;
                run
            };
            // Uniform pilots, growing while too few of their photons are seen to learn from.
            let first = (p.photons / 8).clamp(PILOT_PHOTONS[0], PILOT_PHOTONS[1]);
            let mut size = first;
            loop {
                let run = run_pilot(stats, size - n, None, n);
                n = size;
                merge_pilot(&mut pilot, run);
                let (_, seen) = efficiency(&pilot);
                if seen >= PILOT_SEEN
                    || effective_efficiency(&pilot) >= GUIDE_BELOW
                    || size >= PILOT_PHOTONS[2]
                    || barren(&pilot, size)
                {
                    break;
                }
                size = (size * 4).min(PILOT_PHOTONS[2]);
            }
            let share = effective_efficiency(&pilot);
            let found = format!(
                "pilot of {n} photons: {share:.3e} effective photons stored where the camera looks per photon (cells of {:.3e})",
                region.cell()
            );
            if share >= GUIDE_BELOW {
                return (None, format!("{found}; no guiding needed"));
            }
            // A second pilot of `first` photons sent where the first found seen photons, which
            // sharpens the guide where the first saw only a few.
            let Some(coarse) = EmissionGuide::learn(&pilot, &kinds) else {
                let none = if stored_none(&pilot) { " (none stored anywhere)" } else { "" };
                return (None, format!("{found}; nothing to guide toward{none}"));
            };
            let run = run_pilot(stats, first, Some(&coarse), n);
            let share2 = effective_efficiency(&run);
            let tried = format!("{found}; a guided pilot of {first}: {share2:.3e}");
            if share2 < GUIDE_GAIN * share {
                return (None, format!("{tried}, too little gain to guide"));
            }
            merge_pilot(&mut pilot, run);
            match EmissionGuide::learn(&pilot, &kinds) {
                Some(g) => (Some(g), format!("{tried}; emission guided there")),
                None => (Some(coarse), format!("{tried}; emission guided there")),
            }
        });
        if let Some(stage) = stats.stages.last_mut() {
            stage.reason = reason;
        }
        Guide { region, emission }
    }

    /// Why the caustic pass does not run, if it does not: the scene analysis, overridden by
    /// `--caustic-pass on|off`.
    fn caustic_skip_reason(&self, analysis: &Analysis) -> Option<&'static str> {
        let p = self.passes;
        if p.caustic_photons == 0 {
            Some("caustic photon budget is 0")
        } else if p.caustic_pass == CausticPass::On {
            None
        } else if p.caustic_pass == CausticPass::Off {
            Some("off (--caustic-pass off)")
        } else if !analysis.has_specular {
            Some("no specular (mirror or glass) material")
        } else if !analysis.has_diffuse {
            Some("nothing diffuse or glossy to receive caustics")
        } else if !analysis.has_light() {
            Some("no light has power")
        } else {
            self.caustic_unused
        }
    }

    /// The caustic map: photons aimed at the specular objects (or, with `--caustic-aim false`
    /// or nothing to aim at, emitted as usual) that reach a diffuse surface through mirrors and
    /// glass only.
    fn caustic<A: Accel>(
        &self,
        frame: &Frame<'_, A>,
        analysis: &Analysis,
        seeds: Seeds,
        stats: &mut Stats,
        progress: &dyn Progress,
    ) -> (Vec<PhotonMap>, Vec<SitePoint>) {
        let seed = seeds.pass;
        let p = self.passes;
        if let Some(why) = self.caustic_skip_reason(analysis) {
            stats.skip("photons.caustic", why);
            return (Vec::new(), Vec::new());
        }
        let forced = if p.caustic_pass == CausticPass::On { " (--caustic-pass on)" } else { "" };
        let no_aim = Aim { targets: Vec::new(), acceptance: 0.0 };
        let Aim { targets, acceptance } = if !p.caustic_aim {
            &no_aim
        } else {
            analysis.aim.get_or_init(|| {
                let targets = trace::specular_targets(frame.scene);
                let acceptance = if targets.is_empty() {
                    0.0
                } else {
                    ACCEPTANCE_TRIES
                        .iter()
                        .map(|&n| trace::target_acceptance(frame.lights, &targets, n, seeds.render))
                        .find(|&a| a > 0.0)
                        .unwrap_or(0.0)
                };
                Aim { targets, acceptance }
            })
        };
        let acceptance = *acceptance;
        let aim = acceptance > 0.0;
        let (tries, reason) = if aim {
            // Tries such that about `caustic_photons` photons are aimed at the targets.
            let tries = ((p.caustic_photons as f64 / acceptance).ceil() as u64)
                .min(p.caustic_photons.saturating_mul(1000));
            let share = 100.0 * acceptance;
            let share = if share >= 0.01 { format!("{share:.2}%") } else { format!("{share:.1e}%") };
            let reason =
                format!("{} specular targets, {share} of emission aimed at them{forced}", targets.len());
            (tries, reason)
        } else if p.caustic_aim && p.caustic_pass != CausticPass::On {
            let tries = ACCEPTANCE_TRIES[ACCEPTANCE_TRIES.len() - 1];
            stats.skip(
                "photons.caustic",
                format!("no emitted photon in {tries} tries is aimed at a specular object"),
            );
            stats.warn(format!(
                "no caustics: none of {tries} photons emitted toward the {} mirror and glass objects would reach them",
                targets.len()
            ));
            return (Vec::new(), Vec::new());
        } else {
            let why = if p.caustic_aim { "nothing to aim at" } else { "aiming off (--caustic-aim false)" };
            let reason = format!("{why}: photons emitted from the lights, specular paths kept{forced}");
            (p.caustic_photons, reason)
        };
        progress.start("caustic photons", tries);
        let out = stats.run("photons.caustic", reason, |_| {
            let spec = PassSpec {
                pass: Pass::Caustic,
                n: tries,
                color: p.color,
                max_bounces: p.max_bounces,
                targets,
                aim,
                guide: None,
                portals: None,
                seed: seed ^ 0x5EED,
            };
            trace::trace_pass(frame.scene, frame.accel, frame.lights, &spec, progress)
        });
        progress.finish();
        stats.rays.photon += out.rays;
        // (Learnt here only when no indirect pass runs: the region alone is read.)
        let region = &analysis.guide.get_or_init(|| self.guide(frame, None, seeds.render, stats)).region;
        let (maps, seen) = stats.run("kdtree.caustic", "balance the caustic map", |_| {
            rayon::join(|| build_maps(&out, p.color), || count_seen(&out, region))
        });
        drop(out);
        record_maps(stats, "caustic", &maps, &seen);
        let maps = drop_empty(stats, "caustic", maps);
        if !self.caustic_sites || maps.is_empty() {
            return (maps, Vec::new());
        }
        // The sites of precomputed caustic irradiance: where caustic photons land, from paths
        // of their own. Sites at the map's own photons would be biased: an estimate at a
        // photon counts it (+3 / (k - 1) with the cone), and leaving it out is exact only for
        // photons scattered independently, which stratified emission makes them not (a lens
        // images the light's stratified grid onto the caustic: -6.6 % on the caustics scene's
        // caustic term). A point independent of the map gets the estimate any point gets.
        let n = tries.div_ceil(CAUSTIC_SITE_SHARE);
        progress.start("caustic sites", n);
        let why =
            format!("{n} caustic paths traced for where they land: sites independent of the map's photons");
        let sites = stats.run("photons.caustic_sites", why, |stats| {
            let spec = PassSpec {
                pass: Pass::Caustic,
                n,
                color: ColorMode::Rgb,
                max_bounces: p.max_bounces,
                targets,
                aim,
                guide: None,
                portals: None,
                seed: seed ^ 0x5173,
            };
            let out = trace::trace_pass(frame.scene, frame.accel, frame.lights, &spec, progress);
            stats.rays.photon += out.rays;
            irradiance::pick_sites(&out.maps, 1)
        });
        progress.finish();
        (maps, sites)
    }
}

/// The seeds of a pass's photon stages: the pass's own, and the render's, from which what is
/// worked out once for every pass is worked out.
#[derive(Clone, Copy, Debug)]
struct Seeds {
    pass: u64,
    render: u64,
}

/// The gathers of a photon-mapping render, with radii resolved for the scene.
#[derive(Clone, Copy, Debug)]
pub struct GatherPair {
    pub indirect: GatherParams,
    pub caustic: GatherParams,
}

/// How much the gathers' region is squashed along the normal ([`GatherParams::flatten`]):
/// `|d|² + (f − 1)(n·d)² < r²`, for gathers over the whole disc (two-pass photon mapping's
/// caustic estimates): the flat region (8) is what keeps a corner's other wall out.
const FLATTEN: f32 = 8.0;

/// The flattening of gathers over a footprint (the progressive modes' gathers, two-pass photon
/// mapping's indirect estimates): the footprint cuts the disc at walls and edges, so the region
/// can be thicker, and should be: the normal is the facet's, and where facets tilt from the
/// surface they sample (a scanned mesh, a fluted column) a flat region cuts that surface short
/// across the tilt (at 20°, to 0.74 of its width at 8, 0.95 at 2). The bunny's mean was −0.36 %
/// at 8, −0.19 % at 4, −0.08 % at 2 (60 pppm passes), the Cornell box +0.02 % at each; at 20 s
/// pppm's RMSE at 2 against 8 was 10 % lower on the bunny, 2 % on the glass knot, and the same
/// within noise on six other scenes (docs/accuracy.md). Over the whole disc, 2 made the white
/// furnace's corners 1 % bright (the other wall's photons counted): hence the footprints.
const FOOTPRINT_FLATTEN: f32 = 2.0;

impl GatherPair {
    /// `gathers` with the default radii of `scene`: a tenth of its bounding sphere's radius for
    /// indirect light, a quarter of that for caustics; for two-pass photon mapping, whose
    /// indirect estimates count photons over a footprint and caustic ones over the whole disc.
    pub fn new(gathers: &Gathers, scene: &Scene) -> Self {
        GatherPair::flattened(gathers, scene, [FOOTPRINT_FLATTEN, FLATTEN])
    }

    /// [`GatherPair::new`] for gathers over a footprint (the progressive modes).
    pub fn with_footprint(gathers: &Gathers, scene: &Scene) -> Self {
        GatherPair::flattened(gathers, scene, [FOOTPRINT_FLATTEN; 2])
    }

    /// The gathers, the indirect ones flattened by `flatten[0]`, the caustic ones by `flatten[1]`.
    fn flattened(gathers: &Gathers, scene: &Scene, flatten: [f32; 2]) -> Self {
        let auto_radius = 0.1 * scene.bounds().bounding_sphere().1;
        let params = |k: u32, radius: Option<f32>, default: f32, flatten: f32| GatherParams {
            k: k as usize,
            max_radius: radius.unwrap_or(default),
            kernel: gathers.kernel,
            flatten,
        };
        GatherPair {
            indirect: params(gathers.gather_photons, gathers.gather_radius, auto_radius, flatten[0]),
            caustic: params(
                gathers.caustic_gather_photons,
                gathers.caustic_gather_radius,
                0.25 * auto_radius,
                flatten[1],
            ),
        }
    }
}

/// Packs and balances the maps of one pass.
fn build_maps(out: &trace::PassOutput, color: ColorMode) -> Vec<PhotonMap> {
    out.maps
        .iter()
        .zip(out.emitted.iter().copied())
        .enumerate()
        .map(|(i, (hits, emitted))| {
            let c = match color {
                ColorMode::Rgb => MapColor::Rgb,
                ColorMode::PerChannel => MapColor::Channel(i),
            };
            PhotonMap::build_from(hits, c, emitted)
        })
        .collect()
}

/// `maps` without its empty maps (an empty map is never queried); when none is left, the
/// lookups of `kind` are recorded as skipped.
fn drop_empty(stats: &mut Stats, kind: &str, mut maps: Vec<PhotonMap>) -> Vec<PhotonMap> {
    maps.retain(|m| !m.is_empty());
    if maps.is_empty() {
        stats.skip(&format!("lookups.{kind}"), format!("the {kind} map is empty: no photon was stored"));
    }
    maps
}

/// Photons of each map of `out` stored inside `region` (in parallel: every pass's photons are
/// looked up).
fn count_seen(out: &trace::PassOutput, region: &VisibleRegion) -> Vec<u64> {
    out.maps.iter().map(|m| m.par_iter().filter(|h| region.contains(h.pos)).count() as u64).collect()
}

/// Whether a pilot of `size` photons has stored none anywhere, seen or not, and is as large as
/// [`PILOT_PHOTONS`]`[1]`: every photon left the scene or was absorbed at its first bounce (a
/// floor under the sun or a sky). None in a million means fewer than three a million (at
/// 95 %), so the last pilot, eight times larger, would store a few dozen at most and see fewer,
/// far short of [`PILOT_SEEN`] and of anything to learn a guide from; it took a second on every
/// such render (a lit 8×8 floor: 1.2 s, 1.14 of them the pilot's 2^23 photons; now 0.19 s).
fn barren(pilot: &[EmitterPilot], size: u64) -> bool {
    size >= PILOT_PHOTONS[1] && stored_none(pilot)
}

/// Whether no emitter's pilot photons were stored anywhere.
fn stored_none(pilot: &[EmitterPilot]) -> bool {
    pilot.iter().all(|e| e.stored == 0)
}

/// Photons a pilot emitted, and the seen photons it stored.
fn efficiency(pilot: &[EmitterPilot]) -> (u64, u64) {
    pilot.iter().fold((0, 0), |(a, b), e| (a + e.emitted, b + e.seen))
}

/// Adds the pilot `run` to `pilot`, emitter by emitter.
fn merge_pilot(pilot: &mut Vec<EmitterPilot>, run: Vec<EmitterPilot>) {
    if pilot.is_empty() {
        *pilot = run;
        return;
    }
    for (p, r) in pilot.iter_mut().zip(run) {
        p.emitted += r.emitted;
        p.stored += r.stored;
        p.seen += r.seen;
        p.flux += r.flux;
        p.flux2 += r.flux2;
        p.samples.extend(r.samples);
    }
}

fn record_maps(stats: &mut Stats, kind: &str, maps: &[PhotonMap], seen: &[u64]) {
    let names = ["r", "g", "b"];
    for (i, m) in maps.iter().enumerate() {
        let name = if maps.len() == 1 { kind.to_string() } else { format!("{kind}.{}", names[i]) };
        // Over passes: photons add up; memory is that of the largest map held at once.
        let e = stats.photons.entry(name).or_default();
        e.emitted += m.emitted;
        e.stored += m.len() as u64;
        e.seen += seen.get(i).copied().unwrap_or(0);
        e.efficiency = if e.emitted > 0 { e.seen as f64 / e.emitted as f64 } else { 0.0 };
        e.bytes = e.bytes.max(m.bytes() as u64);
    }
}
