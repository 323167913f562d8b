//! Stochastic progressive photon mapping (Hachisuka & Jensen 2009), on the same kd-tree photon
//! maps and photon stages ([`super::maps`]) as the two-pass method.
//!
//! Every pass traces fresh photon maps (the indirect map and, when the scene has mirrors or
//! glass, the aimed caustic map: together every photon path but the first hit, which direct
//! light covers) and `spp` camera samples per pixel. Emission and direct light (shadow rays)
//! along each sample are averaged over all passes. The first diffuse or glossy hit of one more
//! ray per pixel and pass, from a sequence of its own that covers the pixel evenly over passes
//! ([`Stream::VisiblePoint`](crate::frame::camera::Stream)), is the pixel's *visible point* of
//! the pass: the photons within the pixel's radius `R`
//! around it (a disc flattened along the surface, as in the gathers) give `M` photons and a
//! flux `Φ = Σ β f(wo, wi) power`, and the pixel's statistics are updated as in the paper:
//!
//! ```text
//! N' = N + α M,   R'² = R² N' / (N + M),   τ' = (τ + Φ) R'² / R²
//! ```
//!
//! After `n` passes the pixel is `Ld / n + τ / (n π R²)` (each photon's power is already its
//! pass's flux over the photons emitted in that pass). `R` starts at the distance to the
//! `k`-th nearest photon of the first visible point (`--gather-photons`, in the map where photons
//! are densest, so caustics start small), bounded by `--gather-radius`; it then shrinks so that
//! bias and variance both go to zero as passes are added.

use super::maps::{Analysis, GatherPair, MapStages};
use super::passes::{camera_stage, Pass, PassRenderer};
use crate::accel::{Accel, Hit};
use crate::config::ProgressiveConfig;
use crate::film::Film;
use crate::frame::camera::{for_each_pixel, CameraBatch, SampleMean};
use crate::frame::direct::direct_light;
use crate::frame::specular::{walk, Landing, Start};
use crate::frame::{Counters, Frame, Progress};
use crate::geometry::Ray;
use crate::material::face_forward;
use crate::photon::kdtree::Neighbor;
use crate::photon::map::PhotonMaps;
use crate::stats::Stats;
use glam::Vec3;
use rand_pcg::Pcg32;

/// A pixel's progressive statistics (the emission and direct light, averaged over passes like
/// any integrator's image, are not here).
#[derive(Clone, Copy, Debug, Default)]
struct PixelState {
    /// Squared gather radius (0 until the first visible point).
    r2: f32,
    /// Accumulated photon count `N`.
    n: f32,
    /// Accumulated flux `τ`, scaled to the current radius.
    tau: Vec3,
}

/// Progressive photon mapping over a render's passes.
pub struct Progressive<'f, 'a, A: Accel> {
    frame: &'f Frame<'a, A>,
    cfg: &'f ProgressiveConfig,
    analysis: Analysis,
    gathers: GatherPair,
    states: Vec<PixelState>,
}

impl<'f, 'a, A: Accel> Progressive<'f, 'a, A> {
    pub fn new(frame: &'f Frame<'a, A>, cfg: &'f ProgressiveConfig) -> Self {
        let pixels = frame.camera.width as usize * frame.camera.height as usize;
        Progressive {
            frame,
            cfg,
            analysis: Analysis::of(frame.scene, frame.lights),
            gathers: GatherPair::new(&cfg.gathers, frame.scene),
            states: vec![PixelState::default(); pixels],
        }
    }
}

impl<A: Accel> PassRenderer for Progressive<'_, '_, A> {
    fn render_pass(&mut self, pass: &Pass, stats: &mut Stats, progress: &dyn Progress) -> (Film, Counters) {
        let maps = pass_maps(self.frame, self.cfg, &self.analysis, pass.seed, stats, progress);
        let (frame, cfg, gathers) = (self.frame, self.cfg, &self.gathers);
        let why = "visible points, direct light and progressive radius updates";
        let width = frame.camera.width as usize;
        camera_stage(stats, progress, frame.camera.height, why, || {
            for_each_pixel(
                width,
                &mut self.states,
                pass.seed,
                progress,
                |x, y, st, rng, scratch: &mut Scratch, c| {
                    let l = camera_samples(frame, cfg, pass, x, y, &mut scratch.batch, rng, c);
                    if let Some(v) = visible_point(frame, cfg, pass, x, y, rng, c) {
                        gather(&maps, gathers, st, &v, cfg.alpha, &mut scratch.neighbors, c);
                    }
                    l
                },
            )
        })
    }

    /// After `passes` passes the pixel is `Ld / n + τ / (n π R²)`.
    fn finish(&self, mean: Film, passes: u32) -> Film {
        let mut film = mean;
        let n = passes.max(1) as f32;
        for (px, st) in film.pixels.iter_mut().zip(&self.states) {
            if st.r2 > 0.0 {
                *px += st.tau / (n * std::f32::consts::PI * st.r2);
            }
        }
        film
    }
}

/// Per-thread scratch buffers reused across pixels.
#[derive(Default)]
pub(super) struct Scratch {
    pub(super) batch: CameraBatch,
    pub(super) neighbors: Vec<Neighbor>,
}

/// The photon maps of a progressive pass (both kinds gather at visible points, so nothing is
/// precomputed).
pub(super) fn pass_maps<A: Accel>(
    frame: &Frame<'_, A>,
    cfg: &ProgressiveConfig,
    analysis: &Analysis,
    seed: u64,
    stats: &mut Stats,
    progress: &dyn Progress,
) -> PhotonMaps {
    let stages =
        MapStages { passes: &cfg.maps, indirect_unused: None, caustic_unused: None, site_stride: None };
    let (maps, _) = stages.trace(frame, analysis, seed, stats, progress);
    stats.skip("irradiance", "progressive photon mapping gathers at visible points");
    maps
}

/// The mean emission and direct light of pixel `(x, y)`'s camera samples in `pass`.
#[allow(clippy::too_many_arguments)]
pub(super) fn camera_samples<A: Accel>(
    frame: &Frame<'_, A>,
    cfg: &ProgressiveConfig,
    pass: &Pass,
    x: u32,
    y: u32,
    batch: &mut CameraBatch,
    rng: &mut Pcg32,
    c: &mut Counters,
) -> Vec3 {
    frame.camera_rays(&pass.samples, x, y, batch, c);
    let mut mean = SampleMean::default();
    for (ray, hit) in batch.rays.iter().zip(&batch.hits) {
        mean.add(trace_camera(frame, cfg, *ray, *hit, rng, c), c);
    }
    mean.mean()
}

/// Follows a camera sample through mirrors and glass: the emission seen and the direct light
/// at the first diffuse or glossy surface.
fn trace_camera<A: Accel>(
    frame: &Frame<'_, A>,
    cfg: &ProgressiveConfig,
    ray: Ray,
    first: Option<Hit>,
    rng: &mut Pcg32,
    c: &mut Counters,
) -> Vec3 {
    let mut l = Vec3::ZERO;
    let count = |c: &mut Counters| c.rays.specular += 1;
    let start = Start::Traced(ray, first);
    let landing = walk(frame, start, Vec3::ONE, cfg.max_depth, rng, c, count, |hit, wo, m, beta| {
        l += beta * m.emitted(hit.n, wo)
    });
    if let Some(v) = &landing {
        l += v.beta * direct_light(frame, &v.hit, v.wo, v.m, cfg.light_samples, rng, c);
    }
    l
}

/// The pixel's visible point of `pass`: the first diffuse or glossy surface along the pass's
/// visible-point ray ([`Frame::visible_point_ray`]), through mirrors and glass.
pub(super) fn visible_point<'s, A: Accel>(
    frame: &Frame<'s, A>,
    cfg: &ProgressiveConfig,
    pass: &Pass,
    x: u32,
    y: u32,
    rng: &mut Pcg32,
    c: &mut Counters,
) -> Option<Landing<'s>> {
    let ray = frame.visible_point_ray(&pass.samples, pass.index, x, y);
    c.rays.camera += 1;
    let hit = frame.accel.intersect(&ray);
    let count = |c: &mut Counters| c.rays.specular += 1;
    walk(frame, Start::Traced(ray, hit), Vec3::ONE, cfg.max_depth, rng, c, count, |_, _, _, _| {})
}

/// The photons of this pass around the visible point: the progressive update of `st`.
fn gather(
    maps: &PhotonMaps,
    gathers: &GatherPair,
    st: &mut PixelState,
    v: &Landing<'_>,
    alpha: f32,
    nb: &mut Vec<Neighbor>,
    c: &mut Counters,
) {
    if maps.indirect.is_empty() && maps.caustic.is_empty() {
        return;
    }
    let ns = face_forward(v.hit.n, v.wo);
    if st.r2 == 0.0 {
        match first_radius2(maps, gathers, v.hit.p, ns, nb, c) {
            Some(r2) => st.r2 = r2,
            None => return,
        }
    }
    let (phi, m) = flux_within(maps, gathers, v, ns, st.r2, c);
    if m == 0 {
        return;
    }
    if !phi.is_finite() {
        c.nonfinite += 1;
        return;
    }
    let (n, m) = (st.n, m as f32);
    let n_new = n + alpha * m;
    let ratio = n_new / (n + m);
    st.tau = (st.tau + phi) * ratio;
    st.r2 *= ratio;
    st.n = n_new;
}

/// The squared distance from `x` to the `k`-th nearest photon in the map where photons are
/// densest (so caustics start small), bounded by the gather radius; `None` where no photon is
/// near enough.
pub(super) fn first_radius2(
    maps: &PhotonMaps,
    gathers: &GatherPair,
    x: Vec3,
    ns: Vec3,
    nb: &mut Vec<Neighbor>,
    c: &mut Counters,
) -> Option<f32> {
    let kinds = [(&maps.indirect, &gathers.indirect), (&maps.caustic, &gathers.caustic)];
    let mut r2 = f32::INFINITY;
    for (kind, params) in kinds {
        for map in kind.iter() {
            r2 = r2.min(map.knn_radius2(x, ns, params, nb));
        }
    }
    c.queries += (maps.indirect.len() + maps.caustic.len()) as u64;
    (r2.is_finite() && r2 > 0.0).then_some(r2)
}

/// The flux `β Σ f(wo, wi) power` of the photons of every map strictly inside the squared
/// radius `r2` of the visible point `v` (a disc flattened along `ns`), and how many there were.
/// Strictly: when `r2` is the distance to the `k`-th nearest photon of this pass's maps (the
/// first radius), that photon is on the disc's edge and the `k - 1` inside are what its area
/// measures; counting it too made the first pass `k / (k - 1)` too bright (+3.4 % at k = 30).
pub(super) fn flux_within(
    maps: &PhotonMaps,
    gathers: &GatherPair,
    v: &Landing<'_>,
    ns: Vec3,
    r2: f32,
    c: &mut Counters,
) -> (Vec3, u32) {
    let mut phi = Vec3::ZERO;
    let mut m = 0u32;
    for map in maps.indirect.iter().chain(&maps.caustic) {
        m += map.for_each_inside(v.hit.p, ns, r2, gathers.indirect.flatten, |_, wi, power| {
            phi += v.m.eval(v.hit.n, v.wo, wi) * power;
            true
        });
    }
    c.queries += (maps.indirect.len() + maps.caustic.len()) as u64;
    (v.beta * phi, m)
}
