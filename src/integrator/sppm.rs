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
use crate::accel::{Accel, Hit};
use crate::config::ProgressiveConfig;
use crate::film::Film;
use crate::frame::camera::{for_each_pixel, CameraBatch, SampleMean};
use crate::frame::direct::direct_light;
use crate::frame::specular::{walk, Landing, Start};
use crate::frame::SurfaceHit;
use crate::frame::{Counters, Frame, Part, Progress};
use crate::geometry::{offset_ray_origin, Ray};
use crate::material::face_forward;
use crate::photon::kdtree::Neighbor;
use crate::photon::map::{GatherParams, PhotonMap, PhotonMaps, GUESS_MARGIN};
use crate::stats::Stats;
use glam::{Vec2, Vec3};
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
                    let (l, _) = camera_samples(frame, cfg, pass, x, y, &mut scratch.batch, rng, c);
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

/// The mean emission and direct light of pixel `(x, y)`'s camera samples in `pass`, and the
/// variance of that mean from the samples' own spread (summed over the channels; 0 with fewer
/// than two finite samples).
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
) -> (Vec3, f64) {
    frame.camera_rays(&pass.samples, x, y, batch, c);
    let mut mean = SampleMean::default();
    let (mut sum, mut sq, mut n) = (Vec3::ZERO, Vec3::ZERO, 0u32);
    for (ray, hit) in batch.rays.iter().zip(&batch.hits) {
        let l = trace_camera(frame, cfg, *ray, *hit, rng, c);
        mean.add(l, c);
        if l.is_finite() {
            sum += l;
            sq += l * l;
            n += 1;
        }
    }
    let mean = mean.mean();
    if n < 2 {
        return (mean, 0.0);
    }
    let n = n as f64;
    let var: f64 = (0..3).map(|i| (sq[i] as f64 - (sum[i] as f64).powi(2) / n) / (n - 1.0)).sum();
    (mean, var.max(0.0) / n)
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
    let landing = walk(frame, start, Vec3::ONE, cfg.max_depth, rng, c, count, |seen, beta| {
        l += beta * seen.emitted(frame.lights)
    });
    if let Some(v) = &landing {
        l += v.beta * direct_light(frame, &v.hit, v.wo, &v.m, cfg.light_samples, rng, c);
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
) -> Option<Landing> {
    let ray = frame.visible_point_ray(&pass.samples, pass.index, x, y);
    c.rays.camera += 1;
    let hit = c.timed(Part::Rays, || frame.accel.intersect(&ray));
    let count = |c: &mut Counters| c.rays.specular += 1;
    walk(frame, Start::Traced(ray, hit), Vec3::ONE, cfg.max_depth, rng, c, count, |_, _| {})
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
    /// light, [`super::bandwidth`]).
    pub(super) narrow: f32,
}

/// How much wider than the first radius the surface is probed for walls and edges: a later
/// disc, about a visible point a little off the first, must fit inside.
pub(super) const CLEAR: f32 = 1.5;

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
        Some(FirstPoint::probed(frame, &v.hit, n, r2, 1.0, rng, c))
    }

    /// The first point at `hit` (unit normal `n` on the viewer's side) with the squared first
    /// radius `r2` widened `widening` times (the caustic maps keep `r2`), its surface probed
    /// `CLEAR` times as wide.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn probed<A: Accel>(
        frame: &Frame<'_, A>,
        hit: &SurfaceHit,
        n: Vec3,
        r2: f32,
        widening: f32,
        rng: &mut Pcg32,
        c: &mut Counters,
    ) -> FirstPoint {
        let r2 = r2 * widening;
        let wide = CLEAR * CLEAR * r2;
        let clear2 = if Footprint::clear(frame, hit, n, wide, rng, c) { wide } else { 0.0 };
        FirstPoint { p: hit.p, n, r2, clear2, narrow: 1.0 / widening }
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
            Footprint::probe(frame, &v.hit, ns, r2, rng, c)
        }
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

/// Directions in which a visible point probes its surface, evenly spaced around it.
pub(super) const PROBES: usize = 8;

/// The least part of its own disc a footprint is taken to fill (see [`Footprint::probe`]).
const LEAST_SHARE: f32 = 1.0 / 16.0;

/// The part of a gather disc that the visible point's own surface fills, as far as rays cast
/// down onto the surface can tell: the disc cut back by the walls standing on the surface and
/// by the edges where it ends.
///
/// Where a wall stands on the surface within the gather radius (a room's corners and edges, a
/// block on the floor, a thin wall standing on it), or the surface ends (a block's top, a
/// slab's edge), the disc reaches past it: its part beyond holds no photons of this surface, so
/// photons over `π r²` made every edge too dark (by a missing strip about 0.15 r wide with the
/// flattened disc), and it may hold photons of the surface on a thin wall's far side (light
/// leaked under the wall).
///
/// In each of `PROBES` evenly spaced directions, turned by a random angle, a ray from a point
/// `r / √8` above the visible point (the flattened disc's half thickness) is aimed at the
/// surface where the disc's rim should be, and goes on to as deep below it. It meets a wall (a
/// surface at more than 60° to this one) at or before the rim: the footprint ends at the
/// wall's foot (pulled back by `r / 1000`, so that the wall's own photons, over its foot, stay
/// out). It meets a surface (within 60°) there: the surface reaches the rim in that direction.
/// It meets nothing, or a wall beyond the rim: the surface ends before the rim, and the aim is
/// halved (then moved a quarter back out if that finds it), two more rays at most. The
/// footprint is the disc within the polygon of the probes' end points; photons count only
/// over it and the estimate divides by its area (`share` of the disc's). Every end point lies
/// on the surface, so on a surface bounded by straight walls and convex edges the polygon
/// stays on it, whatever the number of probes, and the photons counted and the area agree
/// exactly; what it does not see are walls and edges between two probes that miss them.
#[derive(Clone, Copy)]
pub(super) struct Footprint {
    /// Tangent frame: the polygon's coordinates are along these.
    t: [Vec3; 2],
    /// The angle of the first probe.
    theta0: f32,
    /// The probes' end points, counter-clockwise, in the tangent frame.
    ends: [Vec2; PROBES],
    /// Whether some probe ended inside the rim (otherwise the footprint is the whole disc).
    cut: bool,
    /// The squared radius of the disc the footprint is cut from: the one asked for, or a
    /// sixteenth or a 256th of it where little of the larger disc lies on the surface and the
    /// smaller footprint is the larger.
    pub r2: f32,
    /// The footprint's area over the area `π r²` of the disc asked for, in `[0, 1]`.
    pub share: f32,
}

/// What a probe found along one direction.
enum Reach {
    /// The surface reaches this far (as aimed).
    Surface,
    /// A wall stands on the surface at this distance.
    Wall(f32),
    /// The surface ends before the aim.
    Edge,
}

impl Footprint {
    /// The whole disc of squared radius `r2`.
    pub fn whole(r2: f32) -> Self {
        Footprint {
            t: [Vec3::X, Vec3::Y],
            theta0: 0.0,
            ends: [Vec2::ZERO; PROBES],
            cut: false,
            r2,
            share: 1.0,
        }
    }

    /// Probes the surface of `hit` (unit normal `ns` on the viewer's side) within the squared
    /// radius `r2`. Where less than a quarter of the disc lies on the surface (a strip narrower
    /// than the disc, such as the side of a thin slab), the footprint is also cut from a disc
    /// of a quarter of the radius, and again if need be, and the largest kept: an estimate over
    /// a small footprint is noisy, but skipping it would leave such surfaces dark. Eight probes
    /// keep two in the open quarter of a right-angled corner, so that a footprint there is
    /// never less than an eighth of the disc (with six, one probe in it made the footprint
    /// vanish: nothing counted there, or, cut from ever smaller discs, a few photons weighted
    /// by thousands).
    pub fn probe<A: Accel>(
        frame: &Frame<'_, A>,
        hit: &SurfaceHit,
        ns: Vec3,
        r2: f32,
        rng: &mut Pcg32,
        c: &mut Counters,
    ) -> Self {
        let mut fp = Footprint::cut_from(frame, hit, ns, r2, rng, c);
        let mut shrink = 1.0;
        while fp.share < 0.25 && shrink < 256.0 {
            shrink *= 16.0;
            let small = Footprint::cut_from(frame, hit, ns, r2 / shrink, rng, c);
            // The largest footprint, for the most photons: near a corner the smaller disc is cut
            // the same way (and would only be noisier), in a narrow strip it is cut far less.
            if small.share / shrink > fp.share {
                fp = Footprint { share: small.share / shrink, ..small };
            }
        }
        // A footprint filling almost none of its own disc (a visible point on the very edge
        // where two surfaces meet, whose lifted probe origin lands past the other surface) would
        // weigh its few photons by thousands: a pixel of the Cornell box's top edge came out 9,000
        // times too bright in one pass at k = 60. Its area is taken as no less than
        // `LEAST_SHARE` of the disc: a bounded weight, and a little light lost on such points.
        let least = LEAST_SHARE * fp.r2 / r2;
        if fp.share < least {
            fp.share = least;
        }
        fp
    }

    /// Whether the probes find the surface of `hit` filling the whole disc of squared radius
    /// `r2` (no wall standing on it and no edge within it).
    pub fn clear<A: Accel>(
        frame: &Frame<'_, A>,
        hit: &SurfaceHit,
        ns: Vec3,
        r2: f32,
        rng: &mut Pcg32,
        c: &mut Counters,
    ) -> bool {
        !Footprint::cut_from(frame, hit, ns, r2, rng, c).cut
    }

    /// The footprint within the disc of squared radius `r2`.
    fn cut_from<A: Accel>(
        frame: &Frame<'_, A>,
        hit: &SurfaceHit,
        ns: Vec3,
        r2: f32,
        rng: &mut Pcg32,
        c: &mut Counters,
    ) -> Self {
        let r = r2.sqrt();
        let step = std::f32::consts::TAU / PROBES as f32;
        // The polygon of probes that reach the rim circumscribes the disc.
        let far = r / (0.5 * step).cos();
        let lift = r * std::f32::consts::FRAC_1_SQRT_2 * 0.5;
        let (t1, t2) = ns.any_orthonormal_pair();
        let theta0 = rng.gen::<f32>() * step;
        let origin = offset_ray_origin(hit.p, hit.err, ns) + lift * ns;
        let mut probe = |t: Vec3, aim: f32| {
            c.rays.gather += 1;
            // At parameter 1 the ray reaches the surface's plane at `aim`, at 2 as far below.
            let ray = Ray::segment(origin, aim * t - lift * ns, 0.0, 2.0);
            match frame.trace(&ray, c) {
                None => Reach::Edge,
                Some(h) => {
                    let along = (h.p - hit.p).dot(t);
                    if h.n.dot(ns).abs() >= 0.5 {
                        Reach::Surface
                    } else if along <= aim {
                        Reach::Wall(along)
                    } else {
                        Reach::Edge
                    }
                }
            }
        };
        let mut ends = [Vec2::ZERO; PROBES];
        let mut cut = false;
        for (j, end) in ends.iter_mut().enumerate() {
            let (sin, cos) = (theta0 + step * j as f32).sin_cos();
            let t = cos * t1 + sin * t2;
            let reach = match probe(t, far) {
                Reach::Surface => far,
                Reach::Wall(d) => (d - 1e-3 * r).max(0.0),
                Reach::Edge => match probe(t, 0.5 * far) {
                    Reach::Surface => match probe(t, 0.75 * far) {
                        Reach::Surface => 0.75 * far,
                        Reach::Wall(d) => (d - 1e-3 * r).max(0.5 * far),
                        Reach::Edge => 0.5 * far,
                    },
                    Reach::Wall(d) => (d - 1e-3 * r).max(0.0),
                    Reach::Edge => match probe(t, 0.25 * far) {
                        Reach::Surface => 0.25 * far,
                        Reach::Wall(d) => (d - 1e-3 * r).max(0.0),
                        Reach::Edge => 0.0,
                    },
                },
            };
            cut |= reach < far;
            *end = Vec2::new(cos, sin) * reach;
        }
        if !cut {
            return Footprint::whole(r2);
        }
        let area: f32 = (0..PROBES).map(|j| wedge_area(ends[j], ends[(j + 1) % PROBES], r)).sum();
        let share = (area / (std::f32::consts::PI * r2)).clamp(0.0, 1.0);
        Footprint { t: [t1, t2], theta0, ends, cut, r2, share }
    }

    /// The footprint over the same surface within the disc of half the area (squared radius
    /// `r2 / 2`), its `share` likewise of half the disc this one's `share` is of (the requested
    /// one, before any shrinking in [`Footprint::probe`]), so that flux over `share` estimates
    /// the same radiance over `π r² / 2` as over `π r²`, less the bias of the larger disc.
    pub fn half(&self) -> Footprint {
        self.within(0.5)
    }

    /// The footprint over the same surface within the disc of `fraction` (in `(0, 1]`) of the
    /// area, its `share` of that disc (as [`Footprint::half`]).
    pub fn within(&self, fraction: f32) -> Footprint {
        let r2 = fraction * self.r2;
        if !self.cut {
            return Footprint { r2, ..*self };
        }
        let area = |r: f32| -> f32 {
            (0..PROBES).map(|j| wedge_area(self.ends[j], self.ends[(j + 1) % PROBES], r)).sum()
        };
        let outer = area(self.r2.sqrt());
        let ratio = if outer > 0.0 { area(r2.sqrt()) / outer } else { 0.0 };
        Footprint { r2, share: (self.share / fraction * ratio).clamp(0.0, 1.0), ..*self }
    }

    /// How far from the visible point the surface was found whole: the nearest of the probes'
    /// end points where a wall or an edge cut the disc, else the disc's radius.
    pub fn reach(&self) -> f32 {
        if !self.cut {
            return self.r2.sqrt();
        }
        self.ends.iter().map(|e| e.length()).fold(f32::INFINITY, f32::min)
    }

    /// Whether a photon at `offset` from the visible point lies over the footprint (its
    /// distance is the caller's test).
    #[inline]
    pub fn contains(&self, offset: Vec3) -> bool {
        if !self.cut {
            return true;
        }
        let q = Vec2::new(offset.dot(self.t[0]), offset.dot(self.t[1]));
        let step = std::f32::consts::TAU / PROBES as f32;
        let angle = (q.y.atan2(q.x) - self.theta0).rem_euclid(std::f32::consts::TAU);
        let j = ((angle / step) as usize).min(PROBES - 1);
        let (a, b) = (self.ends[j], self.ends[(j + 1) % PROBES]);
        (b - a).perp_dot(q - a) > 0.0
    }
}

/// The area of the disc of radius `r` about the origin within the triangle (origin, `a`, `b`),
/// `b` counter-clockwise from `a` by less than a half turn: the triangle's part of the segment
/// `a b` inside the disc, and circular sectors where it runs outside.
fn wedge_area(a: Vec2, b: Vec2, r: f32) -> f32 {
    let sector = |u: Vec2, v: Vec2| 0.5 * r * r * u.perp_dot(v).atan2(u.dot(v));
    let d = b - a;
    let (qa, qb, qc) = (d.dot(d), a.dot(d), a.dot(a) - r * r);
    let disc = qb * qb - qa * qc;
    if qa <= 0.0 || disc <= 0.0 {
        return if qa <= 0.0 { 0.0 } else { sector(a, b) };
    }
    let s = disc.sqrt();
    let t0 = ((-qb - s) / qa).clamp(0.0, 1.0);
    let t1 = ((-qb + s) / qa).clamp(0.0, 1.0);
    if t0 >= t1 {
        return sector(a, b);
    }
    let (p0, p1) = (a + t0 * d, a + t1 * d);
    // Outside the disc before `t0` and after `t1` (tested, not computed: the angle between a
    // point and itself, as `-0.0` and a rounded `0.0`, would be atan2(0, -0) = π).
    let before = if t0 > 0.0 { sector(a, p0) } else { 0.0 };
    let after = if t1 < 1.0 { sector(p1, b) } else { 0.0 };
    before + 0.5 * p0.perp_dot(p1) + after
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

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

    /// A visible point on the very edge where a wall meets the ceiling, a hair above the
    /// ceiling's plane (as rounding put one on the Cornell box's top edge), lifts its probes'
    /// origin past the ceiling: every probe meets the ceiling's back at once and the footprint
    /// fills next to nothing of its disc. Its photons must not be weighed by thousands (that
    /// pixel came out 9,000 times too bright in one pass at k = 60).
    #[test]
    fn a_footprint_on_an_edge_weighs_its_photons_boundedly() {
        use crate::accel::bvh::Bvh;
        use crate::geometry::TriangleMesh;
        use crate::light::LightSet;
        use crate::material::Material;
        use crate::scene::{Camera, Scene, SceneCamera};
        // A wall x = 1 and a ceiling y = 1 meeting along an edge (two-sided diffuse).
        let positions = vec![
            Vec3::new(1.0, -1.0, -1.0),
            Vec3::new(1.0, 1.0, -1.0),
            Vec3::new(1.0, 1.0, 1.0),
            Vec3::new(1.0, -1.0, 1.0),
            Vec3::new(-1.0, 1.0, -1.0),
            Vec3::new(-1.0, 1.0, 1.0),
        ];
        let indices = vec![[0, 1, 2], [0, 2, 3], [4, 1, 2], [4, 2, 5]];
        let cam = Camera::look_at(Vec3::ZERO, Vec3::X, Vec3::Y, 60.0, 8, 8).unwrap();
        let scene = Scene {
            path: "edge".into(),
            camera: cam,
            cameras: vec![SceneCamera::still("camera", cam)],
            mesh: TriangleMesh { positions, indices },
            attributes: Default::default(),
            tri_material: vec![0; 4],
            materials: vec![Material::Diffuse { kd: Vec3::splat(0.5) }],
            maps: vec![Default::default()],
            textured: false,
            textures: Default::default(),
            warnings: Vec::new(),
            material_names: vec!["white".into()],
            lights: Vec::new(),
            portals: Vec::new(),
            render: Default::default(),
        };
        let accel = Bvh::build(&scene.mesh);
        let lights = LightSet::new(&scene.lights, &scene.mesh, &scene.tri_material, &scene.materials);
        let frame = Frame {
            scene: &scene,
            accel: &accel,
            lights: &lights,
            camera: cam,
            views: std::slice::from_ref(&cam),
        };
        // The wall x = 1 (facing -x), its point on the edge with the ceiling y = 1.
        let ray = Ray::new(Vec3::new(0.0, 1.0 - 1e-3, 0.0), Vec3::X);
        let mut c = Counters::default();
        let mut hit = frame.trace(&ray, &mut c).expect("the wall");
        hit.p = Vec3::new(1.0, 1.0 + 2e-6, 0.0);
        let ns = -Vec3::X;
        let r2 = 0.01;
        let mut rng = Pcg32::seed_from_u64(5);
        for _ in 0..20 {
            let fp = Footprint::probe(&frame, &hit, ns, r2, &mut rng, &mut c);
            let own = fp.share * r2 / fp.r2;
            assert!(own >= LEAST_SHARE, "the footprint fills {own} of its disc");
        }
    }

    /// The footprint's area (`share`) is the share of the disc where `contains` says yes, for
    /// polygons of every kind (probes that reach the rim, stop at a wall, or find nothing), so
    /// that photons counted and area divided by agree: the estimate's unbiasedness rests on it.
    #[test]
    fn footprint_area_matches_what_it_contains() {
        let mut rng = Pcg32::seed_from_u64(3);
        let r = 0.7f32;
        let step = std::f32::consts::TAU / PROBES as f32;
        let far = r / (0.5 * step).cos();
        for case in 0..50 {
            let theta0 = rng.gen::<f32>() * step;
            let mut ends = [Vec2::ZERO; PROBES];
            for (j, end) in ends.iter_mut().enumerate() {
                let reach = match rng.gen_range(0..4) {
                    0 => far,
                    1 => 0.0,
                    _ => rng.gen::<f32>() * far,
                };
                let (sin, cos) = (theta0 + step * j as f32).sin_cos();
                *end = Vec2::new(cos, sin) * reach;
            }
            let area: f32 = (0..PROBES).map(|j| wedge_area(ends[j], ends[(j + 1) % PROBES], r)).sum();
            let share = area / (std::f32::consts::PI * r * r);
            let fp = Footprint { t: [Vec3::X, Vec3::Z], theta0, ends, cut: true, r2: r * r, share };
            let n = 40_000;
            let mut inside = 0;
            for i in 0..n {
                // Stratified in radius and angle over the disc.
                let u = (i as f32 + 0.5) / n as f32;
                let (rho, phi) = (r * u.sqrt(), rng.gen::<f32>() * std::f32::consts::TAU);
                if fp.contains(Vec3::new(rho * phi.cos(), 0.3, rho * phi.sin())) {
                    inside += 1;
                }
            }
            let measured = inside as f32 / n as f32;
            assert!((measured - share).abs() < 0.01, "case {case}: share {share}, contains {measured}");
        }
        // Every probe at the rim or beyond: the whole disc.
        let full: f32 = (0..PROBES)
            .map(|j| {
                let (a, b) = (j as f32 * step, (j + 1) as f32 * step);
                wedge_area(Vec2::new(a.cos(), a.sin()) * far, Vec2::new(b.cos(), b.sin()) * far, r)
            })
            .sum();
        assert!((full / (std::f32::consts::PI * r * r) - 1.0).abs() < 1e-4, "{full}");
    }
}
