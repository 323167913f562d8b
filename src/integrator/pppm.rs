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

use super::maps::{Analysis, GatherPair};
use super::passes::{camera_stage, Pass, PassImage, PassRenderer};
use super::sppm::{
    camera_samples, first_radius2, fluxes_within, pass_maps, visible_point, Footprint, Nearest, Scratch,
};
use crate::accel::Accel;
use crate::config::ProgressiveConfig;
use crate::film::sums::Bias;
use crate::film::Film;
use crate::frame::camera::{for_each_pixel, PixelSamples};
use crate::frame::{Counters, Frame, Progress, Quiet};
use crate::material::face_forward;
use crate::sampling::derive_seed;
use crate::stats::Stats;
use glam::Vec3;

/// Pass-indexed progressive photon mapping over a render's passes.
pub struct PassIndexed<'f, 'a, A: Accel> {
    frame: &'f Frame<'a, A>,
    cfg: &'f ProgressiveConfig,
    analysis: &'f Analysis,
    gathers: GatherPair,
    /// Each pixel's first radius, once the first pass has made it.
    pilot: Option<Vec<PilotPoint>>,
}

impl<'f, 'a, A: Accel> PassIndexed<'f, 'a, A> {
    pub fn new(frame: &'f Frame<'a, A>, cfg: &'f ProgressiveConfig, analysis: &'f Analysis) -> Self {
        let gathers = GatherPair::new(&cfg.gathers, frame.scene);
        PassIndexed { frame, cfg, analysis, gathers, pilot: None }
    }
}

/// A pixel's visible point in the pilot and its first radius there (0: no photon near it).
#[derive(Clone, Copy, Default)]
struct PilotPoint {
    p: Vec3,
    /// The surface's unit normal on the viewer's side.
    n: Vec3,
    r2: f32,
    /// The squared radius about `p` within which the pilot's probes found the surface whole
    /// (`CLEAR² r2`; 0 where they found a wall or an edge).
    clear2: f32,
}

impl PilotPoint {
    /// The first radius for a visible point at `p` with normal `n` (on the viewer's side): the
    /// pilot's where the point lies on the same surface within it, `None` elsewhere (a pixel
    /// across an object's edge whose visible point fell on the other side this pass).
    fn radius2_at(&self, p: Vec3, n: Vec3) -> Option<f32> {
        let same = self.r2 > 0.0 && (p - self.p).length_squared() < self.r2 && n.dot(self.n) > PILOT_COS;
        same.then_some(self.r2)
    }

    /// Whether the disc of squared radius `r2` about `p` (a visible point this pilot point
    /// serves) lies within the disc the pilot found whole: then the disc needs no probes.
    fn clears(&self, p: Vec3, r2: f32) -> bool {
        let reach = (p - self.p).length() + r2.sqrt();
        reach * reach <= self.clear2
    }
}

/// How much wider than the first radius the pilot probes the surface for walls and edges: a
/// pass's disc, about a visible point a little off the pilot's, must fit inside.
const CLEAR: f32 = 1.5;

/// The least cosine between a visible point's normal and its pixel's pilot point's for the
/// pilot's radius to serve it (26°).
const PILOT_COS: f32 = 0.9;

/// The pilot: a pass of its own seed (the photon maps every pass traces, and pass 0's visible
/// points) whose `k`-th nearest photon gives each pixel its first radius `r_1`. It depends on
/// the render's seed only, so every pass, on whatever machine, scales the same radius; a
/// pass's own photons then only need the fixed-radius query, and nothing in its estimate
/// depends on where they happen to lie (Knaus and Zwicker's radius is independent of the
/// pass's photons too).
fn pilot<A: Accel>(
    integrator: &PassIndexed<'_, '_, A>,
    render_seed: u64,
    spp: u32,
    stats: &mut Stats,
    progress: &dyn Progress,
) -> (Vec<PilotPoint>, Counters) {
    let PassIndexed { frame, cfg, analysis, gathers, .. } = integrator;
    let samples = PixelSamples { spp, first: 0, seed: render_seed };
    let pass = Pass { index: 0, seed: derive_seed(render_seed, 0x911070, 0), samples };
    let maps = pass_maps(frame, cfg, analysis, &pass, stats, progress);
    let camera = &frame.camera;
    let mut points = vec![PilotPoint::default(); camera.width as usize * camera.height as usize];
    let why = "each pixel's first radius, from a pass of its own seed";
    let (_, c) = stats.run("pilot", why, |_| {
        for_each_pixel(
            camera.width as usize,
            &mut points,
            pass.seed,
            &Quiet,
            |x, y, point, rng, nearest: &mut Nearest, c| {
                let Some(v) = visible_point(frame, cfg, &pass, x, y, rng, c) else { return Vec3::ZERO };
                let n = face_forward(v.hit.n, v.wo);
                if let Some(r2) = first_radius2(&maps, gathers, (x, y), v.hit.p, n, nearest, c) {
                    let wide = CLEAR * CLEAR * r2;
                    let clear2 = if Footprint::clear(frame, &v.hit, n, wide, rng, c) { wide } else { 0.0 };
                    *point = PilotPoint { p: v.hit.p, n, r2, clear2 };
                }
                Vec3::ZERO
            },
        )
    });
    (points, c)
}

/// `r²_i / r²_1` for the pass with 0-based index `pass`: `Π_{j=1}^{pass} (j + α) / (j + 1)`.
pub fn radius2_scale(pass: u32, alpha: f32) -> f32 {
    let alpha = alpha as f64;
    (1..=pass as u64).map(|j| (j as f64 + alpha) / (j as f64 + 1.0)).product::<f64>() as f32
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
            let (points, c) = pilot(self, seed, spp, stats, progress);
            self.pilot = Some(points);
            pilot_counters = c;
        }
        let pilot = self.pilot.as_deref().unwrap_or_default();
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
                    let (r2, found) = match own {
                        Some(r2) => (r2, None),
                        None => match first_radius2(&maps, gathers, (x, y), v.hit.p, ns, nearest, c) {
                            Some(r2) => (r2, Some(&*nearest)),
                            None => return l,
                        },
                    };
                    let r2 = r2 * scale;
                    // Within the pilot's clear disc the surface fills this one: no probes.
                    let footprint = if own.is_some() && point.clears(v.hit.p, r2) {
                        Footprint::whole(r2)
                    } else {
                        Footprint::probe(frame, &v.hit, ns, r2, rng, c)
                    };
                    let half = footprint.half();
                    let (phi, phi_half, _) =
                        fluxes_within(&maps, gathers, &v, ns, &footprint, Some(&half), found, c);
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

#[cfg(test)]
mod tests {
    use super::{radius2_scale, PilotPoint};
    use glam::Vec3;

    /// The pilot's radius serves visible points on its own surface within it, and no other.
    #[test]
    fn the_pilot_radius_serves_its_own_surface_only() {
        let pilot = PilotPoint { p: Vec3::ZERO, n: Vec3::Y, r2: 0.01, clear2: 0.0225 };
        assert_eq!(pilot.radius2_at(Vec3::new(0.05, 0.0, 0.05), Vec3::Y), Some(0.01));
        // Farther than its radius, on a surface turned away, on the back of the surface.
        assert_eq!(pilot.radius2_at(Vec3::new(0.1, 0.0, 0.05), Vec3::Y), None);
        assert_eq!(pilot.radius2_at(Vec3::ZERO, Vec3::new(0.0, 0.8, 0.6)), None);
        assert_eq!(pilot.radius2_at(Vec3::ZERO, -Vec3::Y), None);
        // A pixel without a pilot point (no photon near it, or nothing seen).
        assert_eq!(PilotPoint::default().radius2_at(Vec3::ZERO, Vec3::Y), None);
        // Discs within the one the pilot found whole need no probes; others, and any disc of a
        // pilot point that found a wall, do.
        assert!(pilot.clears(Vec3::new(0.05, 0.0, 0.0), 0.01));
        assert!(!pilot.clears(Vec3::new(0.051, 0.0, 0.0), 0.01));
        assert!(pilot.clears(Vec3::new(0.09, 0.0, 0.0), 0.0025 * 0.99));
        assert!(!PilotPoint { clear2: 0.0, ..pilot }.clears(Vec3::ZERO, 1e-6));
    }

    #[test]
    fn the_radius_shrinks_as_knaus_and_zwicker_prescribe() {
        assert_eq!(radius2_scale(0, 0.7), 1.0);
        assert!((radius2_scale(1, 0.7) - 1.7 / 2.0).abs() < 1e-6);
        assert!((radius2_scale(2, 0.7) - 1.7 / 2.0 * 2.7 / 3.0).abs() < 1e-6);
        // r²_i ~ i^(α-1): the ratio of passes 1000 and 100 is close to 10^(α-1).
        let ratio = radius2_scale(999, 0.7) / radius2_scale(99, 0.7);
        assert!((ratio - 10f32.powf(-0.3)).abs() < 0.01, "{ratio}");
    }
}
