//! The camera pass's frame: each pixel's primary rays, and the loop over pixels that every
//! integrator's camera pass runs.
//!
//! A pixel's sample positions are a stretch of a Halton sequence rotated per pixel (the
//! rotation depends on the render's seed and the pixel only), each pass continuing where the
//! last stopped, so the samples of all passes together stay stratified. Rows are rendered in
//! parallel and every pixel has its own generator seeded from (pass seed, pixel), so the image
//! does not depend on the thread count.

use super::{Counters, Frame, Progress};
use crate::accel::{Accel, Hit};
use crate::film::Film;
use crate::geometry::Ray;
use crate::sampling::{derive_seed, halton2};
use glam::Vec3;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg32;
use rayon::prelude::*;

/// Which camera samples a pass takes.
#[derive(Clone, Copy, Debug)]
pub struct PixelSamples {
    /// Samples per pixel in this pass.
    pub spp: u32,
    /// Index of this pass's first sample in each pixel's sequence.
    pub first: u64,
    /// The render's seed (not the pass's): the per-pixel rotation stays fixed over passes.
    pub seed: u64,
}

/// A pixel's primary rays and their hits, traced as one coherent batch; kept per thread.
#[derive(Default)]
pub struct CameraBatch {
    pub rays: Vec<Ray>,
    pub hits: Vec<Option<Hit>>,
}

impl<A: Accel> Frame<'_, A> {
    /// Fills `batch` with the primary rays of pixel `(px, py)` and their hits (Embree traces
    /// them as packets).
    pub fn camera_rays(
        &self,
        samples: &PixelSamples,
        px: u32,
        py: u32,
        batch: &mut CameraBatch,
        c: &mut Counters,
    ) {
        let pixel = py as u64 * self.camera.width as u64 + px as u64;
        let mut rotation = Pcg32::seed_from_u64(derive_seed(samples.seed, 0x5A3D1E, pixel));
        let offset = [rotation.gen(), rotation.gen()];
        batch.rays.clear();
        for s in 0..samples.spp as u64 {
            let [jx, jy] = halton2(samples.first + s, offset);
            batch.rays.push(self.camera.ray(px as f32 + jx, py as f32 + jy));
        }
        batch.hits.clear();
        batch.hits.resize(batch.rays.len(), None);
        self.accel.intersect_batch(&batch.rays, &mut batch.hits);
        c.rays.camera += batch.rays.len() as u64;
    }
}

/// Runs `pixel(x, y, state, rng, scratch, counters)` on every pixel of a `width`-wide image,
/// rows in parallel, and returns the radiance it gives for each as a film. `states` holds one
/// state per pixel (row-major) that the call may update; `scratch` is per thread.
pub fn for_each_pixel<S, T, F>(
    width: usize,
    states: &mut [S],
    seed: u64,
    progress: &dyn Progress,
    pixel: F,
) -> (Film, Counters)
where
    S: Send,
    T: Default,
    F: Fn(u32, u32, &mut S, &mut Pcg32, &mut T, &mut Counters) -> Vec3 + Sync,
{
    let height = states.len() / width.max(1);
    let rows: Vec<(Vec<Vec3>, Counters)> = states
        .par_chunks_mut(width.max(1))
        .enumerate()
        .map_init(
            || {
                crate::accel::init_tracing_thread();
                T::default()
            },
            |scratch, (y, row)| {
                let mut c = Counters::default();
                let radiance = row
                    .iter_mut()
                    .enumerate()
                    .map(|(x, state)| {
                        let index = (y * width + x) as u64;
                        let mut rng = Pcg32::seed_from_u64(derive_seed(seed, 0xCA3E7A, index));
                        pixel(x as u32, y as u32, state, &mut rng, scratch, &mut c)
                    })
                    .collect();
                progress.advance(1);
                (radiance, c)
            },
        )
        .collect();
    let mut film = Film::new(width, height);
    let mut total = Counters::default();
    for (y, (row, c)) in rows.into_iter().enumerate() {
        film.pixels[y * width..(y + 1) * width].copy_from_slice(&row);
        total += c;
    }
    (film, total)
}

/// The mean of a pixel's finite samples; NaN and infinite ones are dropped and counted.
#[derive(Clone, Copy, Debug, Default)]
pub struct SampleMean {
    sum: Vec3,
    good: u32,
}

impl SampleMean {
    #[inline]
    pub fn add(&mut self, l: Vec3, c: &mut Counters) {
        if l.is_finite() {
            self.sum += l;
            self.good += 1;
        } else {
            c.nonfinite += 1;
        }
    }

    /// The mean (zero when no sample was finite).
    pub fn mean(&self) -> Vec3 {
        if self.good == 0 {
            Vec3::ZERO
        } else {
            self.sum / self.good as f32
        }
    }
}
