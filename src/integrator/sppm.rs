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
//! pass's flux over the photons emitted in that pass); since `τ' / R'² = (τ + Φ) / R²`, that is
//! the mean over passes of each pass's own estimate `Φ / (π R²)` at the radius the passes
//! before it left, which does not depend on the pass's photons (but for the first pass, whose
//! disc is drawn through its own `k`-th photon and so leaves that photon out).
//!
//! Only the photons over the disc's footprint (`Footprint`) count, the part of the disc that
//! the visible point's surface fills (found by a few probe rays: walls standing on the surface
//! and edges where it ends cut it back), and `Φ` is scaled by the disc's area over the
//! footprint's. The whole disc made every edge and corner too dark and let light in under
//! thin walls: a bias proportional to `R`, which shrinks only as `n^((α - 1) / 2)`.
//!
//! `R` starts at the distance to the `k`-th nearest photon of the first visible point
//! (`--gather-photons`, in the map where photons are densest, so caustics start small), bounded
//! by `--gather-radius`; it then shrinks so that bias and variance both go to zero as passes are
//! added.

use super::maps::{Analysis, GatherPair, MapStages};
use super::passes::{camera_stage, Pass, PassImage, PassRenderer};
use super::probe;
use crate::accel::{Accel, Hit};
use crate::config::ProgressiveConfig;
use crate::film::Film;
use crate::frame::camera::{for_each_pixel, CameraBatch, SampleMean};
use crate::frame::direct::direct_light;
use crate::frame::specular::{through_lobe, walk, Landing, Start, GLOSSY_DEPTH};
use crate::frame::SurfaceHit;
use crate::frame::{Counters, Frame, Part, Progress};
use crate::geometry::Ray;
use crate::material::face_forward;
use crate::photon::footprint::{Footprint, CLEAR};
use crate::photon::kdtree::Neighbor;
use crate::photon::map::{GatherParams, PhotonMap, PhotonMaps, GUESS_MARGIN};
use crate::stats::Stats;
use glam::Vec3;
use rand::Rng;
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
    /// Where the first radius was found.
    first: FirstPoint,
}

/// Progressive photon mapping over a render's passes.
pub struct Progressive<'f, 'a, A: Accel> {
    frame: &'f Frame<'a, A>,
    cfg: &'f ProgressiveConfig,
    analysis: &'f Analysis,
    gathers: GatherPair,
    states: Vec<PixelState>,
}

impl<'f, 'a, A: Accel> Progressive<'f, 'a, A> {
    pub fn new(frame: &'f Frame<'a, A>, cfg: &'f ProgressiveConfig, analysis: &'f Analysis) -> Self {
        let pixels = frame.camera.width as usize * frame.camera.height as usize;
        Progressive {
            frame,
            cfg,
            analysis,
            gathers: GatherPair::with_footprint(&cfg.gathers, frame.scene),
            states: vec![PixelState::default(); pixels],
        }
    }
}

impl<A: Accel> PassRenderer for Progressive<'_, '_, A> {
    fn render_pass(
        &mut self,
        pass: &Pass,
        stats: &mut Stats,
        progress: &dyn Progress,
    ) -> (PassImage, Counters) {
        let maps = pass_maps(self.frame, self.cfg, self.analysis, pass, stats, progress);
        let (frame, cfg, gathers) = (self.frame, self.cfg, &self.gathers);
        let why = "visible points, direct light and progressive radius updates";
        let width = frame.camera.width as usize;
        let (film, c) = camera_stage(stats, progress, frame.camera.height, why, || {
            for_each_pixel(
                width,
                &mut self.states,
                pass.seed,
                progress,
                |x, y, st, rng, scratch: &mut Scratch, c| {
                    let l = camera_samples(frame, cfg, pass, x, y, &mut scratch.batch, rng, c);
                    if let Some(v) = visible_point(frame, cfg, pass, x, y, rng, c) {
                        let nearest = &mut scratch.nearest;
                        gather(frame, &maps, gathers, (x, y), st, &v, cfg.alpha, nearest, rng, c);
                    }
                    l
                },
            )
        });
        (film.into(), c)
    }

    /// Its passes carry each pixel's photon statistics to the next.
    fn independent_passes(&self) -> bool {
        false
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
    pub(super) nearest: Nearest,
}

/// The `k` nearest photons of each map (the indirect maps, then the caustic ones) around the
/// last visible point, as [`first_radius2`] found them, and where the next pixel's searches
/// start. A pass-indexed pass gathers within a disc no wider than the first radius, so these
/// are all the photons its gather needs ([`PhotonMap::for_each_found_inside`]).
#[derive(Default)]
pub(super) struct Nearest {
    found: Vec<Vec<Neighbor>>,
    /// Per map, the squared radius the next pixel's search tries first (0: none).
    guesses: Vec<f32>,
    /// The pixel whose searches left `guesses`. Only the next pixel of its row uses them, so
    /// that what a pixel's search does depends on its row alone, not on the jobs that threads
    /// took (the photons found are the same whatever the guess; their order is not).
    after: Option<(u32, u32)>,
}

/// The photon maps of a progressive pass (both kinds gather at visible points, so nothing is
/// precomputed).
pub(super) fn pass_maps<A: Accel>(
    frame: &Frame<'_, A>,
    cfg: &ProgressiveConfig,
    analysis: &Analysis,
    pass: &Pass,
    stats: &mut Stats,
    progress: &dyn Progress,
) -> PhotonMaps {
    let stages = MapStages {
        passes: &cfg.maps,
        indirect_unused: None,
        caustic_unused: None,
        site_stride: None,
        caustic_sites: false,
    };
    let (maps, _) = stages.trace(frame, analysis, pass, stats, progress);
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

/// The variance of one of pixel `(x, y)`'s camera samples in `pass` from what is random after
/// its camera ray (the lights' sampling, glass's choice of reflection or refraction), summed
/// over the channels: each camera ray is followed twice, and half the squared difference of
/// the two is that variance's estimate. The part from where in the pixel the ray starts is
/// left out: the samples' positions follow one low-discrepancy sequence over all passes, so
/// that part falls far faster than as one over the samples (a sun's patch on the floor, sharp
/// at its edges, made the samples' plain spread 3 to 5 times the random part).
#[allow(clippy::too_many_arguments)]
pub(super) fn camera_noise<A: Accel>(
    frame: &Frame<'_, A>,
    cfg: &ProgressiveConfig,
    pass: &Pass,
    x: u32,
    y: u32,
    batch: &mut CameraBatch,
    rng: &mut Pcg32,
    c: &mut Counters,
) -> f64 {
    frame.camera_rays(&pass.samples, x, y, batch, c);
    let (mut sum, mut n) = (0.0f64, 0u32);
    for (ray, hit) in batch.rays.iter().zip(&batch.hits) {
        let a = trace_camera(frame, cfg, *ray, *hit, rng, c);
        let b = trace_camera(frame, cfg, *ray, *hit, rng, c);
        let d = a - b;
        let v = 0.5 * d.dot(d) as f64;
        if v.is_finite() {
            sum += v;
            n += 1;
        }
    }
    if n == 0 {
        0.0
    } else {
        sum / n as f64
    }
}

/// Follows a camera sample through mirrors and glass: the emission seen and the direct light
/// at the first diffuse or glossy surface, and past a sharp glossy lobe there (up to
/// [`GLOSSY_DEPTH`] of them, as the visible point goes: [`visible_point`]) the direct light of
/// the surface the lobe sees and the emitters it sees past mirrors and glass.
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
    let mut landing = walk(frame, start, Vec3::ONE, cfg.max_depth, rng, c, count, |seen, beta| {
        l += beta * seen.emitted(frame.lights)
    });
    for depth in 0..=GLOSSY_DEPTH {
        let Some(v) = &landing else { break };
        l += v.beta * direct_light(frame, &v.hit, v.wo, &v.m, cfg.light_samples, rng, c);
        let Some((_, lobe)) = v.m.sharp_lobe().filter(|_| depth < GLOSSY_DEPTH) else { break };
        let (emitted, next) = through_lobe(frame, v, &lobe, 1.0, cfg.max_depth, rng, c, count);
        l += emitted;
        landing = next;
    }
    l
}

/// The pixel's visible point of `pass`: the first diffuse or glossy surface along the pass's
/// visible-point ray ([`Frame::visible_point_ray`]), through mirrors and glass. On a sharp
/// glossy lobe ([`Material::sharp_lobe`], whose light the photons estimate as a few specks)
/// it is, by the probability the BSDF picks each part, the Lambertian part's point there or a
/// point past the lobe, its throughput over that probability (up to [`GLOSSY_DEPTH`] lobes;
/// [`trace_camera`] takes the direct light past them).
pub(super) fn visible_point<'s, A: Accel>(
    frame: &Frame<'s, A>,
    cfg: &ProgressiveConfig,
    pass: &Pass,
    x: u32,
    y: u32,
    rng: &mut Pcg32,
    c: &mut Counters,
) -> Option<Landing> {
    let ray = frame.visible_point_ray(&pass.samples, pass.index, x, y);
    c.rays.camera += 1;
    let hit = c.timed(Part::Rays, || frame.accel.intersect(&ray));
    let count = |c: &mut Counters| c.rays.specular += 1;
    let mut v = walk(frame, Start::Traced(ray, hit), Vec3::ONE, cfg.max_depth, rng, c, count, |_, _| {})?;
    for _ in 0..GLOSSY_DEPTH {
        let Some((diffuse, lobe)) = v.m.sharp_lobe() else { break };
        let q = v.m.diffuse_share(v.hit.normals().about(v.wo), v.wo);
        if rng.gen::<f32>() < q {
            return Some(Landing { m: diffuse, beta: v.beta / q, ..v });
        }
        v = through_lobe(frame, &v, &lobe, 1.0 / (1.0 - q), cfg.max_depth, rng, c, count).1?;
    }
    Some(v)
}

/// The photons of this pass around the visible point: the progressive update of `st`. The
/// flux and count are those of the disc's [`Footprint`], scaled to the whole disc (over the
/// footprint's share of it), so that `τ / (π R²)` stays the estimate and `M` a density.
#[allow(clippy::too_many_arguments)]
fn gather<A: Accel>(
    frame: &Frame<'_, A>,
    maps: &PhotonMaps,
    gathers: &GatherPair,
    pixel: (u32, u32),
    st: &mut PixelState,
    v: &Landing,
    alpha: f32,
    nearest: &mut Nearest,
    rng: &mut Pcg32,
    c: &mut Counters,
) {
    if maps.indirect.is_empty() && maps.caustic.is_empty() {
        return;
    }
    let ns = face_forward(v.hit.n, v.wo);
    if st.r2 == 0.0 {
        match FirstPoint::find(frame, maps, gathers, pixel, v, nearest, rng, c) {
            Some(first) => (st.r2, st.first) = (first.r2, first),
            None => return,
        }
    }
    let footprint = st.first.footprint(frame, v, ns, st.r2, rng, c);
    let (phi, m) = flux_within(maps, gathers, v, ns, &footprint, c);
    if m == 0 {
        return;
    }
    if !phi.is_finite() {
        c.nonfinite += 1;
        return;
    }
    let (n, m) = (st.n, m as f32 / footprint.share);
    let n_new = n + alpha * m;
    let ratio = n_new / (n + m);
    st.tau = (st.tau + phi) * ratio;
    st.r2 *= ratio;
    st.n = n_new;
}

/// Where a pixel's first radius was found: the visible point (the pilot's in pass-indexed
/// passes, the first pass's in stochastic ones), the surface's normal there, the radius, and
/// how wide about it the surface was found whole. Later visible points of the pixel on the same
/// surface take its radius, and their discs within the whole one need no probe rays.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct FirstPoint {
    p: Vec3,
    /// The surface's unit normal on the viewer's side.
    n: Vec3,
    /// The first radius, squared (0: no photon near the point, or nothing seen).
    pub(super) r2: f32,
    /// The squared radius about `p` within which the probes found the surface whole
    /// (`CLEAR² r2`; 0 where they found a wall or an edge).
    clear2: f32,
    /// The caustic maps' squared radius over `r2` (below 1 where `r2` was widened for smooth
    /// light, [`super::bandwidth`], or the passes trace more photons than the pilot,
    /// [`super::balance`]).
    pub(super) narrow: f32,
}

/// The least cosine between a visible point's normal and its pixel's first point's for the
/// first point to serve it (26°).
const SAME_SURFACE_COS: f32 = 0.9;

impl FirstPoint {
    /// The first radius at the visible point `v` of `pixel` (see [`first_radius2`], whose
    /// photons are left in `nearest`) and the probes of its surface `CLEAR` times as wide.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn find<A: Accel>(
        frame: &Frame<'_, A>,
        maps: &PhotonMaps,
        gathers: &GatherPair,
        pixel: (u32, u32),
        v: &Landing,
        nearest: &mut Nearest,
        rng: &mut Pcg32,
        c: &mut Counters,
    ) -> Option<FirstPoint> {
        let n = face_forward(v.hit.n, v.wo);
        let r2 = first_radius2(maps, gathers, pixel, v.hit.p, n, nearest, c)?;
        Some(FirstPoint::probed(frame, &v.hit, n, r2, 1.0, 1.0, rng, c))
    }

    /// The first point at `hit` (unit normal `n` on the viewer's side) with the squared first
    /// radius `r2` widened `widening` times, for passes of `photons` times the photons `r2` was
    /// found in (the caustic maps keep their own `k`-th nearest photon's, `r2 / photons`), its
    /// surface probed `CLEAR` times as wide.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn probed<A: Accel>(
        frame: &Frame<'_, A>,
        hit: &SurfaceHit,
        n: Vec3,
        r2: f32,
        widening: f32,
        photons: f32,
        rng: &mut Pcg32,
        c: &mut Counters,
    ) -> FirstPoint {
        let r2 = r2 * widening;
        let wide = CLEAR * CLEAR * r2;
        let clear2 = if probe::clear(frame, hit, n, wide, rng, c) { wide } else { 0.0 };
        FirstPoint { p: hit.p, n, r2, clear2, narrow: (1.0 / (widening * photons)).min(1.0) }
    }

    /// The first radius for a visible point at `p` with normal `n` (on the viewer's side): this
    /// point's where the point lies on the same surface within it (within the radius before
    /// any widening: what the pilot measured holds about its own point), `None` elsewhere (a
    /// pixel across an object's edge whose visible point fell on the other side this pass).
    pub(super) fn radius2_at(&self, p: Vec3, n: Vec3) -> Option<f32> {
        let near = self.r2 * self.narrow;
        let same = self.r2 > 0.0 && (p - self.p).length_squared() < near && n.dot(self.n) > SAME_SURFACE_COS;
        same.then_some(self.r2)
    }

    /// The footprint of the disc of squared radius `r2` about the visible point `v` (normal
    /// `ns`): the whole disc where it lies within the disc this point found whole, on the same
    /// surface; otherwise as the probes find it ([`Footprint::probe`]).
    pub(super) fn footprint<A: Accel>(
        &self,
        frame: &Frame<'_, A>,
        v: &Landing,
        ns: Vec3,
        r2: f32,
        rng: &mut Pcg32,
        c: &mut Counters,
    ) -> Footprint {
        if self.radius2_at(v.hit.p, ns).is_some() && self.clears(v.hit.p, r2) {
            Footprint::whole(r2)
        } else {
            probe::probe(frame, &v.hit, ns, r2, rng, c)
        }
    }

    /// Whether the probes found the surface whole about the point (its later discs within
    /// need none).
    pub(super) fn whole(&self) -> bool {
        self.clear2 > 0.0
    }

    /// Whether the disc of squared radius `r2` about `p` lies within the disc found whole.
    fn clears(&self, p: Vec3, r2: f32) -> bool {
        let reach = (p - self.p).length() + r2.sqrt();
        reach * reach <= self.clear2
    }
}

/// The squared distance from `x` to the `k`-th nearest photon in the map where photons are
/// densest (so caustics start small), bounded by the gather radius; `None` where no photon is
/// near enough. The photons found are left in `nearest`; the search starts from the radius of
/// the row's previous pixel (`pixel` is the one asked for).
#[allow(clippy::too_many_arguments)]
pub(super) fn first_radius2(
    maps: &PhotonMaps,
    gathers: &GatherPair,
    pixel: (u32, u32),
    x: Vec3,
    ns: Vec3,
    nearest: &mut Nearest,
    c: &mut Counters,
) -> Option<f32> {
    let count = maps.indirect.len() + maps.caustic.len();
    nearest.found.resize_with(count, Vec::new);
    nearest.guesses.resize(count, 0.0);
    if nearest.after != Some((pixel.0.wrapping_sub(1), pixel.1)) {
        nearest.guesses.fill(0.0);
    }
    nearest.after = Some(pixel);
    let mut r2 = f32::INFINITY;
    c.timed(Part::Gathers, || {
        for (i, (map, params)) in with_params(maps, gathers).enumerate() {
            let (found, guess) = (&mut nearest.found[i], &mut nearest.guesses[i]);
            let own = map.knn_radius2_guessed(x, ns, params, *guess, found);
            *guess = own * GUESS_MARGIN;
            r2 = r2.min(own);
        }
    });
    c.queries += count as u64;
    (r2.is_finite() && r2 > 0.0).then_some(r2)
}

/// Every map of `maps` (the indirect ones, then the caustic ones) with its gather's parameters.
fn with_params<'m>(
    maps: &'m PhotonMaps,
    gathers: &'m GatherPair,
) -> impl Iterator<Item = (&'m PhotonMap, &'m GatherParams)> {
    let indirect = maps.indirect.iter().map(|m| (m, &gathers.indirect));
    indirect.chain(maps.caustic.iter().map(|m| (m, &gathers.caustic)))
}

/// The flux `β Σ f(wo, wi) power` of the photons of every map over the `footprint` of the
/// visible point `v` (within its disc, flattened along `ns`), scaled to the disc the footprint
/// was asked for (divided by its `share`: `flux / (π r²)` is the estimate over the footprint's
/// area, `r²` the squared radius asked for), and how many photons there were.
///
/// Strictly inside the disc: when its squared radius is the distance to the `k`-th nearest
/// photon of this pass's maps (the first radius), that photon is on the disc's edge and the
/// `k - 1` inside are what its area measures; counting it too made the first pass `k / (k - 1)`
/// too bright (+3.4 % at k = 30).
pub(super) fn flux_within(
    maps: &PhotonMaps,
    gathers: &GatherPair,
    v: &Landing,
    ns: Vec3,
    footprint: &Footprint,
    c: &mut Counters,
) -> (Vec3, u32) {
    let (phi, _, m) = fluxes_within(maps, gathers, v, ns, footprint, None, None, 1.0, c);
    (phi, m)
}

/// [`flux_within`] over `footprint` and, in the same gather, over `inner` (a footprint of the
/// same visible point within a smaller radius, such as [`Footprint::half`]): both fluxes, each
/// scaled to its own disc, and the photons over `footprint`. With `nearest` (what
/// [`first_radius2`] found at this visible point) the photons are taken from there instead of
/// searched for again. The caustic maps are gathered over the disc of `narrow` (in `(0, 1]`)
/// times the area (and `inner`'s likewise), their flux scaled up to the wider disc's: a radius
/// widened for smooth light ([`super::bandwidth`]) leaves the caustics as sharp as they were.
#[allow(clippy::too_many_arguments)]
pub(super) fn fluxes_within(
    maps: &PhotonMaps,
    gathers: &GatherPair,
    v: &Landing,
    ns: Vec3,
    footprint: &Footprint,
    inner: Option<&Footprint>,
    nearest: Option<&Nearest>,
    narrow: f32,
    c: &mut Counters,
) -> (Vec3, Vec3, u32) {
    let (mut phi, mut phi_inner) = (Vec3::ZERO, Vec3::ZERO);
    let inner_r2 = inner.map_or(0.0, |f| f.r2);
    // The caustic maps' own discs, where narrower.
    let apart = narrow < 1.0 && !maps.caustic.is_empty();
    let caustic = if apart { footprint.within(narrow) } else { *footprint };
    let caustic_inner = inner.filter(|_| apart).map(|_| caustic.half());
    let caustic_inner_r2 = caustic_inner.map_or(0.0, |f| f.r2);
    let (mut phi_c, mut phi_c_inner) = (Vec3::ZERO, Vec3::ZERO);
    let visit = |flux, d2, is_caustic| {
        if apart && is_caustic {
            phi_c += flux;
            if d2 < caustic_inner_r2 {
                phi_c_inner += flux;
            }
        } else {
            phi += flux;
            if d2 < inner_r2 {
                phi_inner += flux;
            }
        }
    };
    let m = for_each_flux(maps, gathers, v, ns, [footprint, &caustic], nearest, None, c, visit).unwrap_or(0);
    if m == 0 {
        // Also where the footprint is empty (share 0: the visible point hemmed in by walls).
        return (Vec3::ZERO, Vec3::ZERO, 0);
    }
    // Flux over a footprint of `share` of a disc of `narrow` times the area, as over the whole
    // of the wider disc.
    let scaled = |flux: Vec3, share: f32| {
        if share > 0.0 {
            flux / (share * narrow)
        } else {
            Vec3::ZERO
        }
    };
    let inner = match inner {
        Some(f) if f.share > 0.0 && apart => {
            let c_share = caustic_inner.map_or(0.0, |f| f.share);
            v.beta * (phi_inner / f.share + scaled(phi_c_inner, c_share))
        }
        Some(f) if f.share > 0.0 => v.beta * phi_inner / f.share,
        _ => Vec3::ZERO,
    };
    if apart {
        return (v.beta * (phi / footprint.share + scaled(phi_c, caustic.share)), inner, m);
    }
    (v.beta * phi / footprint.share, inner, m)
}

/// Calls `visit(flux, d2, caustic)` for every photon of every map over the footprint of the
/// visible point `v` for its kind of map (`footprints`: the indirect maps', the caustic
/// maps'; within their discs, flattened along `ns`): its flux `f(wo, wi) power` (before the
/// visible point's throughput `β` and the footprint's share), its squared (flattened) distance
/// and whether it is a caustic photon. Returns how many photons there were. With `nearest`
/// (what [`first_radius2`] found at this visible point) the photons are taken from there
/// instead of searched for; else, with `most`, the search gives up past that many photons in a
/// map and returns `None`.
#[allow(clippy::too_many_arguments)]
pub(super) fn for_each_flux(
    maps: &PhotonMaps,
    gathers: &GatherPair,
    v: &Landing,
    ns: Vec3,
    footprints: [&Footprint; 2],
    nearest: Option<&Nearest>,
    most: Option<u32>,
    c: &mut Counters,
    mut visit: impl FnMut(Vec3, f32, bool),
) -> Option<u32> {
    let mut m = Some(0u32);
    let normals = v.hit.normals();
    let constant = normals.gather_constant(&v.m, v.wo);
    let indirect = maps.indirect.len();
    c.timed(Part::Gathers, || {
        for (i, (map, params)) in with_params(maps, gathers).enumerate() {
            let is_caustic = i >= indirect;
            let footprint = footprints[usize::from(is_caustic)];
            let each = |offset, wi: Vec3, power, d2| {
                let inside = footprint.contains(offset);
                if inside {
                    let f = constant.unwrap_or_else(|| normals.gather_eval(&v.m, v.wo, wi.normalize()));
                    visit(f * power, d2, is_caustic);
                }
                inside
            };
            let (p, r2) = (v.hit.p, footprint.r2);
            let found = match (nearest, most) {
                (Some(n), _) => Some(map.for_each_found_inside(p, ns, r2, params, &n.found[i], each)),
                (None, Some(most)) => map.for_each_inside_at_most(p, ns, r2, params.flatten, most, each),
                (None, None) => Some(map.for_each_inside(p, ns, r2, params.flatten, each)),
            };
            m = m.zip(found).map(|(a, b)| a + b);
            if m.is_none() {
                break;
            }
        }
    });
    c.queries += (maps.indirect.len() + maps.caustic.len()) as u64;
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A first point's radius serves visible points on its own surface within it, and no
    /// other; discs inside the one found whole need no probes.
    #[test]
    fn a_first_point_serves_its_own_surface_only() {
        let first = FirstPoint { p: Vec3::ZERO, n: Vec3::Y, r2: 0.01, clear2: 0.0225, narrow: 1.0 };
        assert_eq!(first.radius2_at(Vec3::new(0.05, 0.0, 0.05), Vec3::Y), Some(0.01));
        // Farther than its radius, on a surface turned away, on the back of the surface.
        assert_eq!(first.radius2_at(Vec3::new(0.1, 0.0, 0.05), Vec3::Y), None);
        assert_eq!(first.radius2_at(Vec3::ZERO, Vec3::new(0.0, 0.8, 0.6)), None);
        assert_eq!(first.radius2_at(Vec3::ZERO, -Vec3::Y), None);
        // A pixel without a first point (no photon near it, or nothing seen).
        assert_eq!(FirstPoint::default().radius2_at(Vec3::ZERO, Vec3::Y), None);
        // Discs within the one it found whole need no probes; others, and any disc of a
        // point that found a wall, do.
        assert!(first.clears(Vec3::new(0.05, 0.0, 0.0), 0.01));
        assert!(!first.clears(Vec3::new(0.051, 0.0, 0.0), 0.01));
        assert!(first.clears(Vec3::new(0.09, 0.0, 0.0), 0.0025 * 0.99));
        assert!(!FirstPoint { clear2: 0.0, ..first }.clears(Vec3::ZERO, 1e-6));
    }
}
