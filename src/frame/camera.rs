//! The camera pass's frame: each pixel's primary rays, and the loop over pixels that every
//! integrator's camera pass runs.
//!
//! A pixel's sample positions are a stretch of a Halton sequence rotated per pixel (the
//! rotation depends on the render's seed and the pixel only), each pass continuing where the
//! last stopped, so the samples of all passes together stay stratified. Through a thin lens,
//! each sample's point on the lens is the same Halton point's next two dimensions (bases 5 and
//! 7) with a rotation of their own. Rows are rendered in
//! parallel and every pixel has its own generator seeded from (pass seed, pixel), so the image
//! does not depend on the thread count.

use super::{Counters, Frame, Part, Progress};
use crate::accel::{Accel, Hit};
use crate::film::Film;
use crate::geometry::Ray;
use crate::sampling::{derive_seed, halton2, halton2_lens};
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

/// The independent sample sequences of a pixel, each a Halton sequence with its own per-pixel
/// rotation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stream {
    /// The camera samples: `spp` a pass, continued from pass to pass.
    Camera,
    /// Progressive photon mapping's visible points: one a pass, so that the visible points of
    /// all passes together cover the pixel evenly whatever `spp` is. (Taking the pass's first
    /// camera sample instead, Halton index `pass * spp`, kept every visible point in a strip a
    /// quarter of the pixel wide at 4 spp: the radical inverse of `4k` is that of `k` over 4.)
    VisiblePoint,
}

impl PixelSamples {
    /// Where in pixel number `pixel` sample `index` of `stream` lies, in `[0, 1)²`.
    #[inline]
    pub fn position(&self, stream: Stream, pixel: u64, index: u64) -> [f32; 2] {
        halton2(index, self.rotation(stream, pixel))
    }

    /// Where on the lens (in `[0, 1)²`, for [`crate::scene::Camera::lens_ray`]) sample
    /// `index` of `stream` in pixel number `pixel` lies: the lens dimensions of the same
    /// Halton point as [`PixelSamples::position`]'s.
    #[inline]
    pub fn lens_position(&self, stream: Stream, pixel: u64, index: u64) -> [f32; 2] {
        halton2_lens(index, self.lens_rotation(stream, pixel))
    }

    /// The per-pixel rotation of `stream`'s sequence (fixed over passes).
    #[inline]
    fn rotation(&self, stream: Stream, pixel: u64) -> [f32; 2] {
        let salt = match stream {
            Stream::Camera => 0x5A3D1E,
            Stream::VisiblePoint => 0x715B1E,
        };
        self.rotation_of(salt, pixel)
    }

    /// The per-pixel rotation of `stream`'s lens dimensions, independent of the film's.
    #[inline]
    fn lens_rotation(&self, stream: Stream, pixel: u64) -> [f32; 2] {
        let salt = match stream {
            Stream::Camera => 0x1E45CA,
            Stream::VisiblePoint => 0x1E45B1,
        };
        self.rotation_of(salt, pixel)
    }

    #[inline]
    fn rotation_of(&self, salt: u64, pixel: u64) -> [f32; 2] {
        let mut rotation = Pcg32::seed_from_u64(derive_seed(self.seed, salt, pixel));
        [rotation.gen(), rotation.gen()]
    }
}

/// A pixel's primary rays and their hits, traced as one coherent batch; kept per thread.
#[derive(Default)]
pub struct CameraBatch {
    pub rays: Vec<Ray>,
    pub hits: Vec<Option<Hit>>,
}

impl CameraBatch {
    /// A ball holding every first hit of the batch (centre and radius), `None` without hits.
    pub fn hit_bounds(&self) -> Option<(Vec3, f32)> {
        let points = || self.rays.iter().zip(&self.hits).filter_map(|(r, h)| h.map(|h| r.at(h.t)));
        let (sum, n) = points().fold((Vec3::ZERO, 0u32), |(s, n), p| (s + p, n + 1));
        if n == 0 {
            return None;
        }
        let centre = sum / n as f32;
        // One square root: it is monotonic and correctly rounded, so this is the largest length.
        let radius = points().map(|p| (p - centre).length_squared()).fold(0.0, f32::max).sqrt();
        Some((centre, radius))
    }
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
        let offset = samples.rotation(Stream::Camera, pixel);
        batch.rays.clear();
        if self.camera.lens.is_pinhole() {
            for s in 0..samples.spp as u64 {
                let [jx, jy] = halton2(samples.first + s, offset);
                batch.rays.push(self.camera.ray(px as f32 + jx, py as f32 + jy));
            }
        } else {
            let lens = samples.lens_rotation(Stream::Camera, pixel);
            for s in 0..samples.spp as u64 {
                let i = samples.first + s;
                let [jx, jy] = halton2(i, offset);
                let ray = self.camera.lens_ray(px as f32 + jx, py as f32 + jy, halton2_lens(i, lens));
                batch.rays.push(ray);
            }
        }
        batch.hits.clear();
        batch.hits.resize(batch.rays.len(), None);
        c.timed(Part::Rays, || self.accel.intersect_batch(&batch.rays, &mut batch.hits));
        c.rays.camera += batch.rays.len() as u64;
    }
}

impl<A: Accel> Frame<'_, A> {
    /// The ray of pixel `(px, py)`'s visible point in pass `pass` ([`Stream::VisiblePoint`]).
    pub fn visible_point_ray(&self, samples: &PixelSamples, pass: u32, px: u32, py: u32) -> Ray {
        let pixel = py as u64 * self.camera.width as u64 + px as u64;
        let [jx, jy] = samples.position(Stream::VisiblePoint, pixel, pass as u64);
        if self.camera.lens.is_pinhole() {
            return self.camera.ray(px as f32 + jx, py as f32 + jy);
        }
        let lens = samples.lens_position(Stream::VisiblePoint, pixel, pass as u64);
        self.camera.lens_ray(px as f32 + jx, py as f32 + jy, lens)
    }
}

/// Rows a parallel job of [`for_each_pixel`] takes at most. Rows cost unevenly (glass in half
/// the image; precomputed irradiance estimated by the rows that read it first), and rayon
/// splits a range further only when a thread steals from it: left to itself it gave each of
/// two threads half the rows, and the thread with the cheaper half sat idle for a third of
/// the other's time on the Cornell box at 128x128. Small jobs leave every thread work to steal
/// to the end.
const ROWS_A_JOB: usize = 2;

/// Runs `pixel(x, y, state, rng, scratch, counters)` on every pixel of a `width`-wide image,
/// rows in parallel, and returns the radiance it gives for each as a film. `states` holds one
/// state per pixel (row-major) that the call may update; `scratch` is per job of rows (see
/// `ROWS_A_JOB`).
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
        .with_max_len(ROWS_A_JOB)
        .map_init(
            || {
                crate::accel::init_tracing_thread();
                T::default()
            },
            |scratch, (y, row)| {
                let mut c = Counters::default();
                let start = std::time::Instant::now();
                let radiance = row
                    .iter_mut()
                    .enumerate()
                    .map(|(x, state)| {
                        let index = (y * width + x) as u64;
                        let mut rng = Pcg32::seed_from_u64(derive_seed(seed, 0xCA3E7A, index));
                        pixel(x as u32, y as u32, state, &mut rng, scratch, &mut c)
                    })
                    .collect();
                c.clock.pixels_ns += start.elapsed().as_nanos() as u64;
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

#[cfg(test)]
mod tests {
    use super::*;

    /// How many of `xs` fall in each quarter of `[0, 1)`.
    fn quarters(xs: impl Iterator<Item = f32>) -> [u32; 4] {
        let mut q = [0; 4];
        xs.for_each(|x| q[((x * 4.0) as usize).min(3)] += 1);
        q
    }

    #[test]
    fn visible_points_cover_the_pixel_for_any_spp() {
        for spp in [1, 3, 4, 16] {
            let samples = PixelSamples { spp, first: 0, seed: 7 };
            for pixel in [0, 1, 12345] {
                let p: Vec<[f32; 2]> =
                    (0..64).map(|k| samples.position(Stream::VisiblePoint, pixel, k)).collect();
                for axis in 0..2 {
                    let q = quarters(p.iter().map(|p| p[axis]));
                    assert!(
                        q.iter().all(|&n| (14..=18).contains(&n)),
                        "spp {spp}, pixel {pixel}, axis {axis}: {q:?}"
                    );
                }
            }
        }
        // The defect this replaces: the first camera sample of each pass.
        let samples = PixelSamples { spp: 4, first: 0, seed: 7 };
        let q = quarters((0..64).map(|k| samples.position(Stream::Camera, 0, 4 * k)[0]));
        assert!(q.iter().filter(|&&n| n > 0).count() <= 2, "{q:?}");
    }

    #[test]
    fn lens_samples_are_stratified_and_independent_of_the_film_samples() {
        // A pass continuing another: the 64 lens samples of one pixel over four passes of 16
        // cover the lens as evenly as one pass of 64 would, and are not the film's.
        let samples = PixelSamples { spp: 16, first: 0, seed: 11 };
        for pixel in [0, 7, 99_999] {
            let lens: Vec<[f32; 2]> =
                (0..64).map(|k| samples.lens_position(Stream::Camera, pixel, k)).collect();
            for axis in 0..2 {
                let q = quarters(lens.iter().map(|p| p[axis]));
                assert!(q.iter().all(|&n| (13..=19).contains(&n)), "pixel {pixel}, axis {axis}: {q:?}");
            }
            assert_ne!(lens[0], samples.position(Stream::Camera, pixel, 0));
            assert_ne!(lens[0], samples.lens_position(Stream::VisiblePoint, pixel, 0));
            assert_ne!(lens[0], samples.lens_position(Stream::Camera, pixel + 1, 0));
        }
        // Fixed by the seed, pixel and index alone.
        let again = PixelSamples { spp: 4, first: 40, seed: 11 };
        assert_eq!(again.lens_position(Stream::Camera, 7, 3), samples.lens_position(Stream::Camera, 7, 3));
    }

    #[test]
    fn the_camera_batch_takes_the_camera_stream() {
        // camera_rays draws its rotation inline; it must be the stream's.
        let samples = PixelSamples { spp: 4, first: 8, seed: 3 };
        let mut rotation = Pcg32::seed_from_u64(derive_seed(3, 0x5A3D1E, 5));
        let offset = [rotation.gen(), rotation.gen()];
        for s in 0..4 {
            assert_eq!(halton2(8 + s, offset), samples.position(Stream::Camera, 5, 8 + s));
        }
    }
}
