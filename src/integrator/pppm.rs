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
//! the photon density is uniform. The image takes off half of it, averaged over a window
//! ([`crate::film::sums::PassSums::mean`]): the half-area disc's bias at the whole disc's noise.

use super::balance::{self, Choose, PassWork};
use super::bandwidth::{radius2_scale, summary, widenings, Model, Passes, Spread};
use super::maps::{Analysis, GatherPair};
use super::passes::{camera_stage, Pass, PassImage, PassRenderer};
use super::sppm::{
    camera_noise, camera_samples, first_radius2, fluxes_within, for_each_flux, pass_maps, visible_point,
    FirstPoint, Nearest, Scratch,
};
use crate::accel::Accel;
use crate::config::{PhotonPasses, ProgressiveConfig};
use crate::film::sums::Bias;
use crate::film::Film;
use crate::frame::camera::{for_each_pixel, PixelSamples};
use crate::frame::specular::Landing;
use crate::frame::{Counters, Frame, Progress, Quiet, SurfaceHit};
use crate::material::face_forward;
use crate::photon::footprint::Footprint;
use crate::photon::map::PhotonMaps;
use crate::sampling::derive_seed;
use crate::stats::{PassPlan, Stats};
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
    /// The photons of each pass over the render's own, once the pilot has chosen them.
    photons: u32,
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
        PassIndexed { frame, cfg, analysis, gathers, pilot: None, widen, spp: None, photons: 1 }
    }

    /// The pilot: a pass of its own seed (the photon maps every pass traces, and pass 0's visible
    /// points) whose `k`-th nearest photon gives each pixel its first radius `r_1`, widened where
    /// the light about the pixel is flat ([`bandwidth`]), and, where `--spp` or `--photons` was
    /// not given, the camera samples and the photons of each pass ([`balance`]). It depends on
    /// the render's seed only, so every pass, on whatever machine, scales the same radius and
    /// takes the same samples and photons; a pass's
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
        let ((points, summary, plan), c) = stats.run("pilot", "", |_| {
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
                            // Every point's photon noise, measured or not (what more photons
                            // or samples a pass weigh against), and the bias that only more
                            // photons a pass reduce, over the disc within the `k`-th photon:
                            // that one lies on the edge, always in the disc and never in its
                            // half, and counted would make even light look biased by `2 / k`
                            // (the other `k − 1` lie anywhere within it).
                            let all = !spread.measured;
                            let footprint = Footprint::whole(r2 * (1.0 - 1e-4));
                            let (var, fixed_var, fixed2) =
                                first_disc(&maps, gathers, &v, ns, &footprint, nearest, all, c);
                            let (var, fixed_var) = if all { (var, 0.0) } else { (spread.var, fixed_var) };
                            found.spread = Spread { camera, var, fixed2, fixed_var, ..spread };
                        }
                    }
                    Vec3::ZERO
                },
            );
            let spreads: Vec<Spread> = found.iter().map(|f| f.spread).collect();
            // Each point's surface probed about its widened radius (a seed of its own: the
            // pixels' first seed drew their visible points), and the rays a pass will cast to
            // probe its footprints: as many as the pilot's where its disc was not whole.
            let probed = |widening: &[f32], photons: u32, c: &mut Counters| {
                let mut states: Vec<(FirstPoint, u64)> = vec![(FirstPoint::default(), 0); found.len()];
                let seed = derive_seed(pass.seed, 0x911070, 1);
                let (_, probing) =
                    for_each_pixel(width, &mut states, seed, &Quiet, |x, y, state, rng, _: &mut (), c| {
                        let i = y as usize * width + x as usize;
                        if let Some((hit, ns, r2)) = &found[i].point {
                            let before = c.rays.gather;
                            state.0 =
                                FirstPoint::probed(frame, hit, *ns, *r2, widening[i], photons as f32, rng, c);
                            state.1 = c.rays.gather - before;
                        }
                        Vec3::ZERO
                    });
                *c += probing;
                let rays = states.iter().filter(|s| !s.0.whole()).map(|s| s.1).sum::<u64>();
                (states.into_iter().map(|s| s.0).collect::<Vec<_>>(), rays)
            };
            if !widen {
                let (points, _) = probed(&vec![1.0; spreads.len()], 1, &mut c);
                return ((points, None, None), c);
            }
            // The widenings of passes like the pilot's, for the probes' count; then the plan,
            // and the probes again where it changed them.
            let first = widenings(&spreads, width, &Model::new(cfg.alpha, Passes::pilot())).u;
            let (mut points, probe_rays) = probed(&first, 1, &mut c);
            let points_seen = found.iter().filter(|f| f.point.is_some()).count() as u64;
            let work = PassWork {
                photon_rays,
                stored: maps.indirect.iter().chain(&maps.caustic).map(|m| m.len() as u64).sum(),
                points: points_seen,
                gathered: points_seen * gathers.indirect.k as u64,
                probe_rays,
                sample_rays: found.iter().map(|f| f.sample_rays).sum::<u64>() as f64 / spp as f64,
            };
            let choose = Choose { samples: cfg.auto_samples, photons: cfg.auto_photons };
            let plan = balance::plan(&spreads, width, cfg.alpha, &work, spp, choose);
            if plan.widening != first || plan.photons != 1 {
                (points, _) = probed(&plan.widening, plan.photons, &mut c);
            }
            let summary = summary(&plan.widening, &spreads, plan.photons as f64);
            ((points, Some(summary), Some((plan, choose))), c)
        });
        let chosen =
            plan.as_ref().filter(|(_, choose)| choose.samples || choose.photons).map(|(plan, _)| PassPlan {
                spp: plan.spp,
                photons: cfg.maps.photons * plan.photons as u64,
                caustic_photons: cfg.maps.caustic_photons * plan.photons as u64,
                camera_share: plan.camera_share,
                fixed_in_samples: plan.fixed_in_samples,
            });
        if let Some(stage) = stats.stages.last_mut() {
            let how = match summary {
                Some(w) => format!(
                    "widened {:.2}x on average where the light is flat ({:.0} % of the {} pixels measured fully)",
                    w.mean,
                    100.0 * w.widest,
                    w.pixels
                ),
                None => "not widened (a short render: fewer than 16 passes, or under 10 s)".to_string(),
            };
            let planned = match chosen {
                Some(p) => format!(
                    "; passes of {} photons ({} caustic) and {} camera samples (their noise {:.0} % of a pass's, the photon term's work {:.1} samples' worth)",
                    p.photons,
                    p.caustic_photons,
                    p.spp,
                    100.0 * p.camera_share,
                    p.fixed_in_samples
                ),
                None => String::new(),
            };
            stage.reason = format!(
                "each pixel's first radius, from a pass of its own seed: the k-th nearest photon's, {how}{planned}"
            );
        }
        stats.widening = summary;
        stats.pass_plan = chosen;
        let (spp, photons) = match plan {
            Some((plan, choose)) => (choose.samples.then_some(plan.spp), plan.photons),
            None => (None, 1),
        };
        Pilot { points, spp, photons, counters: c }
    }
}

/// What the pilot gives every pass: each pixel's first point, the camera samples of a pass
/// (`None`: the render's own), the photons of a pass over the render's own, and the pilot's
/// counters.
struct Pilot {
    points: Vec<FirstPoint>,
    spp: Option<u32>,
    photons: u32,
    counters: Counters,
}

/// The mirror and shadow rays counted so far.
fn traced_rays(c: &Counters) -> u64 {
    c.rays.specular + c.rays.shadow
}

/// What the photons within the first radius say of a pass's photon term at the visible point
/// `v` (unit normal `ns` on the viewer's side), from the photons `nearest` holds, over the
/// `footprint` of the first radius's disc: its variance, `Σ (β Φ)² / A²`, that of its part
/// whose radius is not widened (the caustic maps; with `all`, the indirect ones too), and an
/// unbiased estimate of that part's squared bias, `b̂² − var(b̂)` for the
/// passes' own bias probe `b̂ = 2 (L_A − L_{A/2})` over the footprint and its half (each
/// photon weighs `2 (1 / A − 1 / A_h)` within the half, `2 / A` outside it). Both summed over
/// the channels.
#[allow(clippy::too_many_arguments)]
fn first_disc(
    maps: &PhotonMaps,
    gathers: &GatherPair,
    v: &Landing,
    ns: Vec3,
    footprint: &Footprint,
    nearest: &Nearest,
    all: bool,
    c: &mut Counters,
) -> (f64, f64, f64) {
    let half = footprint.half();
    let (mut sq, mut fixed, mut inner) = (Vec3::ZERO, (Vec3::ZERO, Vec3::ZERO), (Vec3::ZERO, Vec3::ZERO));
    for_each_flux(
        maps,
        gathers,
        v,
        ns,
        [footprint, footprint],
        Some(nearest),
        None,
        c,
        |flux, d2, caustic| {
            let q = flux * flux;
            sq += q;
            if all || caustic {
                fixed.0 += flux;
                fixed.1 += q;
                if d2 < half.r2 {
                    inner.0 += flux;
                    inner.1 += q;
                }
            }
        },
    );
    let pi = std::f32::consts::PI;
    let (area, area_half) = (pi * footprint.r2 * footprint.share, pi * half.r2 * half.share);
    let beta2 = v.beta * v.beta;
    let var = (beta2 * sq / (area * area)).element_sum() as f64;
    let fixed_var = (beta2 * fixed.1 / (area * area)).element_sum() as f64;
    let bias = 2.0 * v.beta * (fixed.0 / area - inner.0 / area_half);
    let (w_in, w_out) = (2.0 * (1.0 / area - 1.0 / area_half), 2.0 / area);
    let var_bias = beta2 * (w_in * w_in * inner.1 + w_out * w_out * (fixed.1 - inner.1));
    let fixed2 = (bias * bias - var_bias).element_sum() as f64;
    let finite = |x: f64| if x.is_finite() { x } else { 0.0 };
    (finite(var), finite(fixed_var), finite(fixed2))
}

/// What the pilot found at a pixel: its visible point's surface, the normal on the viewer's
/// side and the squared first radius (none where nothing was seen or no photon was near), and
/// the spread of its estimates.
#[derive(Clone, Copy, Debug, Default)]
struct Found {
    point: Option<(SurfaceHit, Vec3, f32)>,
    spread: Spread,
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
            self.photons = pilot.photons;
            pilot_counters = pilot.counters;
        }
        let pilot = self.pilot.as_deref().unwrap_or_default();
        let photons = self.photons as f32;
        // The pilot's camera samples a pass, the pass's own run of each pixel's sequence.
        let pass = &match self.spp {
            Some(spp) => Pass {
                samples: PixelSamples { spp, first: pass.index as u64 * spp as u64, ..pass.samples },
                ..*pass
            },
            None => *pass,
        };
        // The pilot's photons a pass.
        let m = self.photons as u64;
        let maps = PhotonPasses {
            photons: self.cfg.maps.photons * m,
            caustic_photons: self.cfg.maps.caustic_photons * m,
            ..self.cfg.maps
        };
        let cfg = &ProgressiveConfig { maps, ..*self.cfg };
        let maps = pass_maps(self.frame, cfg, self.analysis, pass, stats, progress);
        let (frame, gathers) = (self.frame, &self.gathers);
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
                    // Where the pilot cannot say (the pixel's visible point fell outside the
                    // pilot's radius: a far surface whose pixel is wider than its discs, or
                    // across an edge), the pass's own k-th nearest photon does: as wide as the
                    // pilot's where the pass traces more photons and the pilot kept its radius,
                    // but no wider (the pilot found the light flat about its own point only);
                    // the caustics keep theirs, and where it is not widened, the photons that
                    // search found are the gather's.
                    let grow = if point.r2 > 0.0 { (1.0 / point.narrow).min(photons) } else { 1.0 };
                    let (r2, found, narrow) = match own {
                        Some(r2) => (r2, None, point.narrow),
                        None => match first_radius2(&maps, gathers, (x, y), v.hit.p, ns, nearest, c) {
                            Some(r2) if grow > 1.0 => (r2 * grow, None, 1.0 / grow),
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
