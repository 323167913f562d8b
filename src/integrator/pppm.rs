//! Pass-indexed ("probabilistic") progressive photon mapping (Knaus & Zwicker, "Progressive
//! Photon Mapping: A Probabilistic Approach", ACM TOG 30(3), 2011).
//!
//! Every pass is an independent photon-mapping render: fresh maps (the same photon stages as
//! the stochastic kind), `spp` camera samples for emission and direct light, and one visible
//! point per pixel whose photons within a radius `r_i` give the photon term `Φ / (π r_i²)`.
//! The radius of pass `i` (counted from 1) depends on `i` only:
//!
//! ```text
//! r²_i = r²_1 · Π_{j=1}^{i-1} (j + α) / (j + 1)   (~ i^(α-1))
//! ```
//!
//! so the variance of a pass grows as `i^(1-α)` while its bias shrinks as `r²_i`; the average
//! of `n` passes converges with both going to zero. `r_1` is the pixel's distance to its `k`-th
//! nearest photon (`--gather-photons`, bounded by `--gather-radius`) in a *pilot*: a pass of its
//! own seed, made once per render (where a pass's visible point strays off the pilot's surface,
//! the pass's own `k`-th nearest photon gives it). Nothing is carried from pass to pass, so a
//! pass's image depends only on (seed, pass index) and passes rendered anywhere can be
//! averaged; and a pass's photons are found by one fixed-radius query, not a k-nearest search
//! (the pilot made pppm 17 % faster a pass on the white furnace).
//!
//! Each pass also probes the bias of its photon term for the error estimate
//! ([`Bias::Probed`]): in the same gather it sums the photons within the disc of half the area,
//! `r²_i / 2`. For light that varies smoothly over the disc the bias of a disc estimate grows
//! as its area (the Taylor expansion's second-order term; the first cancels over a symmetric
//! disc: Hachisuka, Jarosz and Jensen 2010), so the two estimates differ by half the larger
//! disc's bias and `2 (L_r − L_{r/√2})` is an estimate of that bias, zero in expectation where
//! the photon density is uniform.

use super::balance::{self, PassWork};
use super::bandwidth::{mean_inverse_scale, radius2_scale, summary, widenings, Spread};
use super::maps::{Analysis, GatherPair};
use super::passes::{camera_stage, Pass, PassImage, PassRenderer};
use super::sppm::{
    camera_noise, camera_samples, first_radius2, fluxes_within, for_each_flux, pass_maps, visible_point,
    FirstPoint, Nearest, Scratch,
};
use crate::accel::Accel;
use crate::config::ProgressiveConfig;
use crate::film::sums::Bias;
use crate::film::Film;
use crate::frame::camera::{for_each_pixel, PixelSamples};
use crate::frame::specular::Landing;
use crate::frame::{Counters, Frame, Progress, Quiet, SurfaceHit};
use crate::material::face_forward;
use crate::photon::footprint::Footprint;
use crate::photon::map::PhotonMaps;
use crate::sampling::derive_seed;
use crate::stats::{PassSamples, Stats};
use glam::Vec3;

/// Pass-indexed progressive photon mapping over a render's passes.
pub struct PassIndexed<'f, 'a, A: Accel> {
    frame: &'f Frame<'a, A>,
    cfg: &'f ProgressiveConfig,
    analysis: &'f Analysis,
    gathers: GatherPair,
    /// Each pixel's first radius, once the first pass has made it.
    pilot: Option<Vec<FirstPoint>>,
    /// Whether the pilot widens the first radii where the light is flat (a long render's).
    widen: bool,
    /// The camera samples of each pass, once the pilot has chosen them ([`balance`]; `None`:
    /// the render's own).
    spp: Option<u32>,
}

impl<'f, 'a, A: Accel> PassIndexed<'f, 'a, A> {
    /// `widen`: whether the pilot widens the first radii where the light is flat
    /// ([`super::bandwidth::pays`]).
    pub fn new(
        frame: &'f Frame<'a, A>,
        cfg: &'f ProgressiveConfig,
        analysis: &'f Analysis,
        widen: bool,
    ) -> Self {
        let gathers = GatherPair::with_footprint(&cfg.gathers, frame.scene);
        PassIndexed { frame, cfg, analysis, gathers, pilot: None, widen, spp: None }
    }

    /// The pilot: a pass of its own seed (the photon maps every pass traces, and pass 0's visible
    /// points) whose `k`-th nearest photon gives each pixel its first radius `r_1`, widened where
    /// the light about the pixel is flat ([`bandwidth`]), and, where `--spp` was not given, the
    /// camera samples of each pass ([`balance`]). It depends on the render's seed only, so every
    /// pass, on whatever machine, scales the same radius and takes the same samples; a pass's
    /// own photons then only need the fixed-radius query, and nothing in its estimate depends on
    /// where they happen to lie (Knaus and Zwicker's radius is independent of the pass's photons
    /// too).
    fn pilot(&self, render_seed: u64, spp: u32, stats: &mut Stats, progress: &dyn Progress) -> Pilot {
        let PassIndexed { frame, cfg, analysis, gathers, .. } = self;
        let widen = self.widen;
        let samples = PixelSamples { spp, first: 0, seed: render_seed };
        let pass = Pass { index: 0, seed: derive_seed(render_seed, 0x911070, 0), samples };
        let photon_rays = stats.rays.photon;
        let maps = pass_maps(frame, cfg, analysis, &pass, stats, progress);
        let photon_rays = stats.rays.photon - photon_rays;
        let camera = &frame.camera;
        let width = camera.width as usize;
        let mut found = vec![Found::default(); width * camera.height as usize];
        let ((points, summary, chosen), c) = stats.run("pilot", "", |_| {
            let (_, mut c) = for_each_pixel(
                width,
                &mut found,
                pass.seed,
                &Quiet,
                |x, y, found, rng, scratch: &mut Scratch, c| {
                    // The variance of a pass's mean of its camera samples, and the rays of
                    // one pass's samples (each was followed twice).
                    let camera = if widen {
                        let (rays, traced) = (c.rays.camera, traced_rays(c));
                        let noise = camera_noise(frame, cfg, &pass, x, y, &mut scratch.batch, rng, c);
                        found.sample_rays = c.rays.camera - rays + (traced_rays(c) - traced) / 2;
                        noise / spp as f64
                    } else {
                        0.0
                    };
                    found.spread.camera = camera;
                    let Some(v) = visible_point(frame, cfg, &pass, x, y, rng, c) else { return Vec3::ZERO };
                    let ns = face_forward(v.hit.n, v.wo);
                    let nearest = &mut scratch.nearest;
                    if let Some(r2) = first_radius2(&maps, gathers, (x, y), v.hit.p, ns, nearest, c) {
                        found.point = Some((v.hit, ns, r2));
                        if widen {
                            let spread = Spread::measure(frame, &maps, gathers, &v, ns, r2, rng, c);
                            found.spread = Spread { camera, ..spread };
                            found.photon_var = photon_variance(&maps, gathers, &v, ns, r2, nearest, c);
                        }
                    }
                    Vec3::ZERO
                },
            );
            let spreads: Vec<Spread> = found.iter().map(|f| f.spread).collect();
            // Each point's surface probed about its widened radius (a seed of its own: the
            // pixels' first seed drew their visible points), and the rays a pass will cast to
            // probe its footprints: as many as the pilot's where its disc was not whole.
            let probed = |widening: &[f32], c: &mut Counters| {
                let mut states: Vec<(FirstPoint, u64)> = vec![(FirstPoint::default(), 0); found.len()];
                let seed = derive_seed(pass.seed, 0x911070, 1);
                let (_, probing) =
                    for_each_pixel(width, &mut states, seed, &Quiet, |x, y, state, rng, _: &mut (), c| {
                        let i = y as usize * width + x as usize;
                        if let Some((hit, ns, r2)) = &found[i].point {
                            let before = c.rays.gather;
                            state.0 = FirstPoint::probed(frame, hit, *ns, *r2, widening[i], rng, c);
                            state.1 = c.rays.gather - before;
                        }
                        Vec3::ZERO
                    });
                *c += probing;
                let rays = states.iter().filter(|s| !s.0.whole()).map(|s| s.1).sum::<u64>();
                (states.into_iter().map(|s| s.0).collect::<Vec<_>>(), rays)
            };
            let mut widening =
                if widen { widenings(&spreads, width, cfg.alpha) } else { vec![1.0; spreads.len()] };
            let (mut points, mut probe_rays) = probed(&widening, &mut c);
            let mut chosen = None;
            if widen && cfg.auto_samples {
                let mut work = PassWork {
                    photon_rays,
                    stored: maps.indirect.iter().chain(&maps.caustic).map(|m| m.len() as u64).sum(),
                    points: found.iter().filter(|f| f.point.is_some()).count() as u64,
                    probe_rays,
                    sample_rays: found.iter().map(|f| f.sample_rays).sum::<u64>() as f64 / spp as f64,
                };
                let first = choose_samples(&found, &points, spp, cfg.alpha, &work);
                if first.spp != spp {
                    // The widening weighs the camera samples' noise: again, for the samples
                    // chosen (more samples, less of it, so wider gathers pay).
                    let scale = spp as f64 / first.spp as f64;
                    let spreads: Vec<Spread> =
                        spreads.iter().map(|s| Spread { camera: s.camera * scale, ..*s }).collect();
                    widening = widenings(&spreads, width, cfg.alpha);
                    (points, probe_rays) = probed(&widening, &mut c);
                    work.probe_rays = probe_rays;
                }
                chosen = Some(choose_samples(&found, &points, spp, cfg.alpha, &work));
            }
            ((points, widen.then(|| summary(&widening, &spreads)), chosen), c)
        });
        if let Some(stage) = stats.stages.last_mut() {
            let how = match summary {
                Some(w) => format!(
                    "widened {:.2}x on average where the light is flat ({:.0} % of the {} pixels measured fully, 2x)",
                    w.mean,
                    100.0 * w.widest,
                    w.pixels
                ),
                None => "not widened (a short render: fewer than 16 passes, or under 10 s)".to_string(),
            };
            let samples = match chosen {
                Some(p) => format!(
                    "; {} camera samples a pass (their noise {:.0} % of a pass's, the photon term's work {:.1} samples' worth)",
                    p.spp,
                    100.0 * p.camera_share,
                    p.fixed_in_samples
                ),
                None => String::new(),
            };
            stage.reason = format!(
                "each pixel's first radius, from a pass of its own seed: the k-th nearest photon's, {how}{samples}"
            );
        }
        stats.widening = summary;
        stats.pass_samples = chosen;
        Pilot { points, spp: chosen.map(|p| p.spp), counters: c }
    }
}

/// What the pilot gives every pass: each pixel's first point, the camera samples of a pass
/// (`None`: the render's own), and the pilot's counters.
struct Pilot {
    points: Vec<FirstPoint>,
    spp: Option<u32>,
    counters: Counters,
}

/// The camera samples a pass takes ([`balance`]) for what the pilot found at each pixel, its
/// first points (their widening) and the work of a pass, the pilot's camera samples `spp` a
/// pixel.
fn choose_samples(
    found: &[Found],
    points: &[FirstPoint],
    spp: u32,
    alpha: f32,
    work: &PassWork,
) -> PassSamples {
    // The image's mean variances: of one camera sample, and of one pass's photon term over
    // the passes' radii, widened as chosen.
    let n = found.len().max(1) as f64;
    let rho = mean_inverse_scale(alpha);
    let camera = found.iter().map(|f| f.spread.camera * spp as f64).sum::<f64>() / n;
    let widening = points.iter().map(FirstPoint::widening);
    let photons = found.iter().zip(widening).map(|(f, u)| f.photon_var * rho / u as f64).sum::<f64>() / n;
    let s = balance::samples(camera, photons, work);
    let (fixed, per_sample) = work.prices();
    let per_pass = camera / s as f64 + photons;
    let camera_share = if per_pass > 0.0 { camera / s as f64 / per_pass } else { 0.0 };
    PassSamples { spp: s, camera_share, fixed_in_samples: fixed / per_sample }
}

/// The mirror and shadow rays counted so far.
fn traced_rays(c: &Counters) -> u64 {
    c.rays.specular + c.rays.shadow
}

/// The variance of a pass's photon term at the visible point `v` (unit normal `ns` on the
/// viewer's side) over the whole disc of squared radius `r2`, from the photons `nearest` holds
/// there: `Σ (β Φ)² / (π r²)²`, summed over the channels.
fn photon_variance(
    maps: &PhotonMaps,
    gathers: &GatherPair,
    v: &Landing,
    ns: Vec3,
    r2: f32,
    nearest: &Nearest,
    c: &mut Counters,
) -> f64 {
    let whole = Footprint::whole(r2);
    let mut sq = Vec3::ZERO;
    for_each_flux(maps, gathers, v, ns, [&whole, &whole], Some(nearest), None, c, |flux, _, _| {
        sq += flux * flux
    });
    let area = std::f32::consts::PI * r2;
    let var = (v.beta * v.beta * sq / (area * area)).element_sum() as f64;
    if var.is_finite() {
        var
    } else {
        0.0
    }
}

/// What the pilot found at a pixel: its visible point's surface, the normal on the viewer's
/// side and the squared first radius (none where nothing was seen or no photon was near), and
/// the spread of its estimates.
#[derive(Clone, Copy, Debug, Default)]
struct Found {
    point: Option<(SurfaceHit, Vec3, f32)>,
    spread: Spread,
    /// The variance of the photon term at the first radius ([`photon_variance`]).
    photon_var: f64,
    /// The camera, mirror and shadow rays of the pilot's camera samples.
    sample_rays: u64,
}

impl<A: Accel> PassRenderer for PassIndexed<'_, '_, A> {
    fn render_pass(
        &mut self,
        pass: &Pass,
        stats: &mut Stats,
        progress: &dyn Progress,
    ) -> (PassImage, Counters) {
        let mut pilot_counters = Counters::default();
        if self.pilot.is_none() {
            let (seed, spp) = (pass.samples.seed, pass.samples.spp);
            let pilot = self.pilot(seed, spp, stats, progress);
            self.pilot = Some(pilot.points);
            self.spp = pilot.spp;
            pilot_counters = pilot.counters;
        }
        let pilot = self.pilot.as_deref().unwrap_or_default();
        // The pilot's camera samples a pass, the pass's own run of each pixel's sequence.
        let pass = &match self.spp {
            Some(spp) => Pass {
                samples: PixelSamples { spp, first: pass.index as u64 * spp as u64, ..pass.samples },
                ..*pass
            },
            None => *pass,
        };
        let maps = pass_maps(self.frame, self.cfg, self.analysis, pass, stats, progress);
        let (frame, cfg, gathers) = (self.frame, self.cfg, &self.gathers);
        let scale = radius2_scale(pass.index, cfg.alpha);
        let camera = &frame.camera;
        // Each pixel's bias probe.
        let mut probes = vec![Vec3::ZERO; camera.width as usize * camera.height as usize];
        let why = "visible points at the pass's radius, direct light";
        let (film, mut c) = camera_stage(stats, progress, camera.height, why, || {
            let width = camera.width as usize;
            for_each_pixel(
                width,
                &mut probes,
                pass.seed,
                progress,
                |x, y, probe, rng, scratch: &mut Scratch, c| {
                    let mut l = camera_samples(frame, cfg, pass, x, y, &mut scratch.batch, rng, c);
                    let Some(v) = visible_point(frame, cfg, pass, x, y, rng, c) else { return l };
                    if maps.indirect.is_empty() && maps.caustic.is_empty() {
                        return l;
                    }
                    let ns = face_forward(v.hit.n, v.wo);
                    let nearest = &mut scratch.nearest;
                    let point = &pilot[y as usize * width + x as usize];
                    let own = point.radius2_at(v.hit.p, ns);
                    // Where the pilot cannot say, the pass's own k-th nearest photon does, and
                    // the photons that search found are the gather's.
                    let (r2, found, narrow) = match own {
                        Some(r2) => (r2, None, point.narrow),
                        None => match first_radius2(&maps, gathers, (x, y), v.hit.p, ns, nearest, c) {
                            Some(r2) => (r2, Some(&*nearest), 1.0),
                            None => return l,
                        },
                    };
                    let r2 = r2 * scale;
                    let footprint = point.footprint(frame, &v, ns, r2, rng, c);
                    let half = footprint.half();
                    let (phi, phi_half, _) =
                        fluxes_within(&maps, gathers, &v, ns, &footprint, Some(&half), found, narrow, c);
                    let area = std::f32::consts::PI * r2;
                    let photons = phi / area;
                    if photons.is_finite() {
                        l += photons;
                        let d = 2.0 * (photons - phi_half / (0.5 * area));
                        if d.is_finite() {
                            *probe = d;
                        }
                    } else {
                        c.nonfinite += 1;
                    }
                    l
                },
            )
        });
        let bias_probe = Film { width: film.width, height: film.height, pixels: probes };
        c += pilot_counters;
        (PassImage { film, bias_probe: Some(bias_probe) }, c)
    }

    fn bias(&self) -> Bias {
        Bias::Probed
    }
}
