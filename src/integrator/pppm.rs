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
//! of `n` passes converges with both going to zero. `r_1` is the pass's own distance from the
//! visible point to its `k`-th nearest photon (`--gather-photons`, bounded by
//! `--gather-radius`): nothing is carried from pass to pass, so a pass's image depends only on
//! (seed, pass index) and passes rendered anywhere can be averaged.
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
    camera_samples, first_radius2, fluxes_within, pass_maps, visible_point, Footprint, Scratch,
};
use crate::accel::Accel;
use crate::config::ProgressiveConfig;
use crate::film::sums::Bias;
use crate::film::Film;
use crate::frame::camera::for_each_pixel;
use crate::frame::{Counters, Frame, Progress};
use crate::material::face_forward;
use crate::stats::Stats;
use glam::Vec3;

/// Pass-indexed progressive photon mapping over a render's passes.
pub struct PassIndexed<'f, 'a, A: Accel> {
    frame: &'f Frame<'a, A>,
    cfg: &'f ProgressiveConfig,
    analysis: &'f Analysis,
    gathers: GatherPair,
}

impl<'f, 'a, A: Accel> PassIndexed<'f, 'a, A> {
    pub fn new(frame: &'f Frame<'a, A>, cfg: &'f ProgressiveConfig, analysis: &'f Analysis) -> Self {
        PassIndexed { frame, cfg, analysis, gathers: GatherPair::new(&cfg.gathers, frame.scene) }
    }
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
        let maps = pass_maps(self.frame, self.cfg, self.analysis, pass, stats, progress);
        let (frame, cfg, gathers) = (self.frame, self.cfg, &self.gathers);
        let scale = radius2_scale(pass.index, cfg.alpha);
        let camera = &frame.camera;
        // Each pixel's bias probe.
        let mut probes = vec![Vec3::ZERO; camera.width as usize * camera.height as usize];
        let why = "visible points at the pass's radius, direct light";
        let (film, c) = camera_stage(stats, progress, camera.height, why, || {
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
                    let Some(r2) = first_radius2(&maps, gathers, v.hit.p, ns, &mut scratch.neighbors, c)
                    else {
                        return l;
                    };
                    let r2 = r2 * scale;
                    let footprint = Footprint::probe(frame, &v.hit, ns, r2, rng, c);
                    let half = footprint.half();
                    let (phi, phi_half, _) =
                        fluxes_within(&maps, gathers, &v, ns, &footprint, Some(&half), c);
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
        (PassImage { film, bias_probe: Some(bias_probe) }, c)
    }

    fn bias(&self) -> Bias {
        Bias::Probed
    }
}

#[cfg(test)]
mod tests {
    use super::radius2_scale;

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
