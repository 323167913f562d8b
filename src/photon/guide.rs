//! Photons where the camera looks: the region of the scene the camera sees, and emission
//! guided toward it.
//!
//! A photon is only ever read near a surface the camera sees (through mirrors and glass): a
//! photon stored anywhere else is work thrown away. In a room lit by the sun through a small
//! window almost every photon lands outside; with a light behind a door, most land in the
//! wrong room. Two pieces address it:
//!
//! * [`VisibleRegion`]: the cells of grids around the points a coarse pilot of camera rays
//!   lands on (128 rays across the long side of the image, through each of up to 8 of the
//!   views a batch renders, each followed through mirrors and glass; through a thin lens,
//!   from points spread over the aperture), grown by one cell on every side, each point at the
//!   cell size of what its ray sees (a point far away, seen through a window, marks a coarser
//!   cell; a point out of focus, one as wide as the lens blurs it). Photons stored inside count as *seen*; their
//!   share of the photons emitted is the map's efficiency in `--stats`.
//! * [`EmissionGuide`]: learnt from a pilot of photons traced as usual, it tells each emitter
//!   which of its emission samples lead to seen photons (after Hachisuka and Jensen 2011,
//!   "Robust adaptive photon tracing using photon path visibility", whose target is the same
//!   set of paths; here the paths are found by importance sampling the emission instead of by
//!   a Markov chain, so photons stay independent and a pass depends only on its seed). Each
//!   emitter's two guided sample dimensions (the position on a distant light's disc, the
//!   direction of every other light) get a piecewise-constant density on a grid of cells: a
//!   mixture of the counts of seen photons at the grid's resolution and at coarser ones
//!   ([`LEVELS`]), and a uniform share ([`DEFENSIVE`]) so that no sample has zero density. The
//!   fine level finds a small window; the coarse ones keep a fair share for the many paths
//!   that each reach the camera's view rarely (sunlight off the ground outside, in through the
//!   window), which the pilot sees too sparsely to place finely, and which, sampled only at
//!   the uniform share, would come as a few photons of great power. The photon budget is split among
//!   emitters by the same mixture of seen flux and power. Each photon's power is divided by
//!   the density of its sample, so every estimate keeps its expected value: guiding changes
//!   the noise, not the answer.
//!
//! Guiding runs only where it pays: when the pilot's photons store at least [`GUIDE_BELOW`]
//! seen photons each already, or a guided pilot does not do [`GUIDE_GAIN`] times better, the
//! emission stays as it is.

use crate::accel::Accel;
use crate::frame::specular::{walk, Start};
use crate::frame::{Counters, Frame};
use crate::sampling::{derive_seed, halton2_lens};
use glam::Vec3;
use rand::SeedableRng;
use rand_pcg::Pcg32;
use rustc_hash::FxHashSet;

/// Camera rays across the long side of the image in the pilot that finds the seen region.
const PILOT_SIDE: u32 = 128;

/// Views of a batch the pilot looks through: a turntable's 60 frames are well covered by 8.
pub const PILOT_VIEWS: usize = 8;

/// At most `n` of `items`, evenly spaced from the first to the last.
pub fn spread<T>(items: &[T], n: usize) -> impl Iterator<Item = &T> {
    let len = items.len();
    let take = len.min(n);
    (0..take).map(move |i| if take <= 1 { &items[0] } else { &items[i * (len - 1) / (take - 1)] })
}

/// Share of each guided density (and of the photon split) kept uniform (by power).
pub const DEFENSIVE: f32 = 0.15;

/// Guiding runs when the pilot's photons store fewer seen photons than this per photon emitted,
/// and only if a guided pilot stores at least [`GUIDE_GAIN`] times as many (where photons
/// scatter far from where they were aimed, as in a white furnace, aiming them changes little).
pub const GUIDE_BELOW: f64 = 0.5;
pub const GUIDE_GAIN: f64 = 1.5;

/// Cells a side of a distant light's guided disc, and of every other emitter's directions.
const DISC_CELLS: usize = 512;
const DIRECTION_CELLS: usize = 32;

/// The levels of the mixture: cells merged a side (1: the grid's own) and share of the density.
/// With [`DEFENSIVE`] the shares add up to 1.
pub const LEVELS: [(usize, f32); 3] = [(1, 0.45), (8, 0.25), (64, 0.15)];

/// Pilot photons an emitter needs before its samples are guided (fewer: uniform).
const MIN_PILOT: u64 = 1024;

/// Levels of cell size in the seen region: level `l` has cells `2^l` times the finest.
const REGION_LEVELS: usize = 16;

/// Cells of space near what the camera sees, at the scale of what each pilot ray sees: a point
/// far away (the ground seen through a window) covers a cell of a coarser level.
#[derive(Clone, Debug, Default)]
pub struct VisibleRegion {
    cell: f32,
    origin: Vec3,
    /// The cells of each level that is in use, finest first.
    levels: Vec<(usize, FxHashSet<[i32; 3]>)>,
}

impl VisibleRegion {
    /// The region seen by a pilot of camera rays through `frame`'s views (see the module doc;
    /// at most [`PILOT_VIEWS`] of them, evenly spaced over the list, each with a pilot of its
    /// own). The finest cell is twice the median footprint of a pilot ray where it lands; each
    /// landing marks the cells, grown by one, of the level whose cell is at least twice its
    /// footprint.
    pub fn of<A: Accel>(frame: &Frame<'_, A>, seed: u64) -> Self {
        let mut rng = Pcg32::seed_from_u64(derive_seed(seed, 0x5EE_4E61, 0));
        let mut c = Counters::default();
        let mut landings = Vec::new();
        for cam in spread(frame.views, PILOT_VIEWS) {
            let (w, h) = (cam.width as f32, cam.height as f32);
            let scale = PILOT_SIDE as f32 / w.max(h);
            let (sw, sh) = (((w * scale).round() as u32).max(1), ((h * scale).round() as u32).max(1));
            let (dx, dy) = (w / sw as f32, h / sh as f32);
            for j in 0..sh {
                for i in 0..sw {
                    let (x, y) = ((i as f32 + 0.5) * dx, (j as f32 + 0.5) * dy);
                    let pinhole = cam.ray(x, y);
                    // The angle between this ray and its neighbour one pilot cell away.
                    let spread = (cam.ray(x + dx, y + dy).dir - pinhole.dir).length()
                        * std::f32::consts::FRAC_1_SQRT_2;
                    // Through a thin lens, from a point of the lens that a Halton sequence
                    // spreads over the aperture (a pinhole ignores it).
                    let ray = cam.lens_ray(x, y, halton2_lens((j * sw + i) as u64, [0.0; 2]));
                    let start = Start::Ray(ray);
                    let landing = walk(frame, start, Vec3::ONE, 64, &mut rng, &mut c, |_| {}, |_, _| {});
                    if let Some(l) = landing {
                        // The pixel's footprint, widened by the lens's blur there.
                        let mut footprint = (l.hit.p - cam.eye).length() * spread;
                        if !cam.lens.is_pinhole() {
                            footprint += cam.defocus_diameter(l.hit.p);
                        }
                        if footprint.is_finite() {
                            landings.push((l.hit.p, footprint));
                        }
                    }
                }
            }
        }
        if landings.is_empty() {
            return VisibleRegion::default();
        }
        let mut footprints: Vec<f32> = landings.iter().map(|l| l.1).collect();
        footprints.sort_by(f32::total_cmp);
        let extent = frame.scene.bounds().bounding_sphere().1;
        let median = footprints[footprints.len() / 2];
        let cell = (2.0 * median).max(1e-5 * extent);
        if !(cell.is_finite() && cell > 0.0) {
            return VisibleRegion::default();
        }
        let mut region = VisibleRegion { cell, origin: landings[0].0, levels: Vec::new() };
        let mut sets = vec![FxHashSet::default(); REGION_LEVELS];
        for (p, footprint) in landings {
            let level = ((2.0 * footprint / cell).log2().ceil().max(0.0) as usize).min(REGION_LEVELS - 1);
            let [x, y, z] = region.key(p, level);
            for k in -1..=1 {
                for j in -1..=1 {
                    for i in -1..=1 {
                        sets[level].insert([x + i, y + j, z + k]);
                    }
                }
            }
        }
        region.levels = sets.into_iter().enumerate().filter(|(_, s)| !s.is_empty()).collect();
        region
    }

    fn key(&self, p: Vec3, level: usize) -> [i32; 3] {
        let q = ((p - self.origin) / (self.cell * (1u32 << level) as f32)).floor();
        [q.x as i32, q.y as i32, q.z as i32]
    }

    /// Whether `p` lies in the region.
    #[inline]
    pub fn contains(&self, p: Vec3) -> bool {
        self.levels.iter().any(|(level, cells)| cells.contains(&self.key(p, *level)))
    }

    /// Whether the pilot saw nothing (no surface in view).
    pub fn is_empty(&self) -> bool {
        self.levels.is_empty()
    }

    /// The finest cell side, scene units.
    pub fn cell(&self) -> f32 {
        self.cell
    }
}

/// A piecewise-constant density over `[0, 1)²` on a `side × side` grid, sampled by inverting
/// its CDF (rows, then the cell within the row), so stratified inputs stay stratified.
#[derive(Clone, Debug)]
pub struct Grid2 {
    side: usize,
    /// Probability of each row, and of each cell within its row, as CDFs.
    rows: Vec<f32>,
    cells: Vec<f32>,
    /// Density of each cell (probability × side²).
    density: Vec<f32>,
}

impl Grid2 {
    /// The density proportional to `weights` (row-major, `side²` non-negative values, some
    /// positive).
    pub fn new(side: usize, weights: &[f32]) -> Self {
        let total: f64 = weights.iter().map(|&w| w as f64).sum();
        let cells_n = (side * side) as f32;
        let density = weights.iter().map(|&w| (w as f64 / total) as f32 * cells_n).collect();
        let mut rows = vec![0.0f32; side + 1];
        let mut cells = vec![0.0f32; side * (side + 1)];
        for r in 0..side {
            let row = &weights[r * side..(r + 1) * side];
            let row_total: f64 = row.iter().map(|&w| w as f64).sum();
            rows[r + 1] = rows[r] + (row_total / total) as f32;
            let cdf = &mut cells[r * (side + 1)..(r + 1) * (side + 1)];
            let mut acc = 0.0f64;
            for (c, &w) in row.iter().enumerate() {
                acc += w as f64;
                cdf[c + 1] =
                    if row_total > 0.0 { (acc / row_total) as f32 } else { (c + 1) as f32 / side as f32 };
            }
        }
        rows[side] = 1.0;
        Grid2 { side, rows, cells, density }
    }

    /// Maps a uniform `u` to a sample of the density; returns it with its density.
    #[inline]
    pub fn sample(&self, u: [f32; 2]) -> ([f32; 2], f32) {
        let n = self.side;
        let (r, fr) = invert(&self.rows, u[0]);
        let (c, fc) = invert(&self.cells[r * (n + 1)..(r + 1) * (n + 1)], u[1]);
        let out =
            [(r as f32 + fr) / n as f32, (c as f32 + fc) / n as f32].map(|v| v.min(1.0 - f32::EPSILON / 2.0));
        (out, self.density[r * n + c])
    }

    /// The cell of a sample (the inverse of the grid's layout, for counting).
    fn cell_of(side: usize, u: [f32; 2]) -> usize {
        let i = |v: f32| ((v * side as f32) as usize).min(side - 1);
        i(u[0]) * side + i(u[1])
    }
}

/// The interval `i` of the CDF `cdf` (`cdf[i] <= u < cdf[i + 1]`, a positive interval) and
/// where `u` falls within it.
#[inline]
fn invert(cdf: &[f32], u: f32) -> (usize, f32) {
    let n = cdf.len() - 1;
    let u = u.clamp(0.0, cdf[n] * (1.0 - f32::EPSILON));
    // The first entry above `u`, minus one: `cdf[i] <= u < cdf[i + 1]`, a positive interval.
    let i = cdf.partition_point(|&c| c <= u).saturating_sub(1).min(n - 1);
    let (lo, hi) = (cdf[i], cdf[i + 1]);
    let f = if hi > lo { ((u - lo) / (hi - lo)).clamp(0.0, 1.0 - f32::EPSILON) } else { 0.5 };
    (i, f)
}

/// Which two sample dimensions of an emitter are guided.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Guided {
    /// The position on the emitter (a distant light's disc).
    Position,
    /// The emission direction (point, spot and area lights).
    Direction,
}

impl Guided {
    fn side(self) -> usize {
        match self {
            Guided::Position => DISC_CELLS,
            Guided::Direction => DIRECTION_CELLS,
        }
    }
}

/// What the pilot learnt about one emitter: photons emitted and stored, and for each guided
/// sample the flux its path stored inside the region (the seen photons times the power each
/// carries, which includes one over the sample's density: the samples of one pilot, guided or
/// not, add up to an estimate of the emitter's seen flux).
#[derive(Clone, Debug, Default)]
pub struct EmitterPilot {
    pub emitted: u64,
    pub stored: u64,
    /// Of the photons stored, those inside the region.
    pub seen: u64,
    /// Sums over the seen photons of their power `p` and of `p²`, each photon's power scaled by
    /// its pilot's photons (so that pilots of any size compare): see [`effective_efficiency`].
    pub flux: f64,
    pub flux2: f64,
    pub samples: Vec<([f32; 2], f32)>,
}

/// Seen photons per photon emitted, counted as photons of equal power would be: `(Σ p)² / (n
/// Σ p²)` over the seen photons of `n` emitted. With equal powers it is the share of photons
/// seen; photons of unequal power (guided emission, portals) count for less, as their noise
/// does. Guiding is judged by it.
pub fn effective_efficiency(pilot: &[EmitterPilot]) -> f64 {
    let (emitted, flux, flux2) =
        pilot.iter().fold((0u64, 0.0, 0.0), |(n, f, f2), e| (n + e.emitted, f + e.flux, f2 + e.flux2));
    if emitted == 0 || !(flux2 > 0.0) {
        return 0.0;
    }
    flux * flux / (emitted as f64 * flux2)
}

/// Per emitter: its share of the photon budget and, when guided, the density of its guided
/// sample dimensions.
#[derive(Clone, Debug)]
pub struct EmissionGuide {
    /// Seen flux per emitter over all seen flux (sums to 1).
    pub seen_share: Vec<f64>,
    pub grids: Vec<Option<(Guided, Grid2)>>,
}

impl EmissionGuide {
    /// The guide learnt from `pilot` (one entry per emitter, `kinds[e]` its guided
    /// dimensions); `None` when no pilot photon was seen.
    pub fn learn(pilot: &[EmitterPilot], kinds: &[Guided]) -> Option<Self> {
        let seen: Vec<f64> =
            pilot.iter().map(|p| p.samples.iter().map(|s| s.1 as f64).sum::<f64>()).collect();
        let total: f64 = seen.iter().sum();
        if !(total > 0.0) {
            return None;
        }
        let grids = pilot
            .iter()
            .zip(kinds)
            .zip(&seen)
            .map(|((p, &kind), &s)| {
                if p.emitted < MIN_PILOT || !(s > 0.0) {
                    return None;
                }
                let side = kind.side();
                let mut counts = vec![0.0f32; side * side];
                for &(u, w) in &p.samples {
                    counts[Grid2::cell_of(side, u)] += w;
                }
                let mut weights = vec![DEFENSIVE / (side * side) as f32; side * side];
                for (merge, share) in LEVELS {
                    let merge = merge.min(side);
                    let level = if merge == 1 { fill(&counts, side) } else { coarsen(&counts, side, merge) };
                    let sum: f32 = level.iter().sum();
                    for (w, l) in weights.iter_mut().zip(&level) {
                        *w += share * l / sum;
                    }
                }
                Some((kind, Grid2::new(side, &weights)))
            })
            .collect();
        Some(EmissionGuide { seen_share: seen.iter().map(|s| s / total).collect(), grids })
    }
}

/// `counts` summed over blocks of `merge × merge` cells and spread evenly over each block.
fn coarsen(counts: &[f32], side: usize, merge: usize) -> Vec<f32> {
    let blocks = side.div_ceil(merge);
    let mut sums = vec![0.0f32; blocks * blocks];
    let block = |r: usize, c: usize| (r / merge) * blocks + c / merge;
    for r in 0..side {
        for c in 0..side {
            sums[block(r, c)] += counts[r * side + c];
        }
    }
    let mut out = vec![0.0f32; counts.len()];
    for r in 0..side {
        for c in 0..side {
            let rows = merge.min(side - (r / merge) * merge);
            let cols = merge.min(side - (c / merge) * merge);
            out[r * side + c] = sums[block(r, c)] / (rows * cols) as f32;
        }
    }
    out
}

/// Each cell of `counts` at least half the mean of its 3 × 3 neighbourhood (clamped at the
/// borders): a cell the pilot missed amid seen ones keeps a fair density, while the seen
/// cells keep their sharp edges.
fn fill(counts: &[f32], side: usize) -> Vec<f32> {
    let mut out = vec![0.0f32; counts.len()];
    for r in 0..side {
        for c in 0..side {
            let (mut s, mut n) = (0.0, 0.0);
            for rr in r.saturating_sub(1)..(r + 2).min(side) {
                for cc in c.saturating_sub(1)..(c + 2).min(side) {
                    s += counts[rr * side + cc];
                    n += 1.0;
                }
            }
            out[r * side + c] = counts[r * side + c].max(0.5 * s / n);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::Rng;

    #[test]
    fn grid_samples_follow_the_density_and_report_it() {
        let side = 8;
        let mut weights = vec![1.0f32; side * side];
        weights[3 * side + 5] = 50.0;
        weights[7 * side] = 0.0;
        let grid = Grid2::new(side, &weights);
        let total: f32 = weights.iter().sum();
        let mut rng = Pcg32::seed_from_u64(1);
        let n = 200_000;
        let mut hits = vec![0u32; side * side];
        let mut inv_pdf_sum = 0.0f64;
        for _ in 0..n {
            let (u, pdf) = grid.sample([rng.gen(), rng.gen()]);
            let cell = Grid2::cell_of(side, u);
            hits[cell] += 1;
            let expected = weights[cell] / total * (side * side) as f32;
            assert!((pdf - expected).abs() < 1e-4 * expected.max(1.0), "{pdf} vs {expected}");
            inv_pdf_sum += 1.0 / pdf as f64;
        }
        assert_eq!(hits[7 * side], 0, "a zero-weight cell was sampled");
        let share = hits[3 * side + 5] as f32 / n as f32;
        assert!((share - 50.0 / total).abs() < 0.01, "{share}");
        // E[1/pdf] = 1 over the support: the reweighting that keeps estimates unbiased.
        let support = (side * side - 1) as f64 / (side * side) as f64;
        assert!((inv_pdf_sum / n as f64 - support).abs() < 0.01, "{}", inv_pdf_sum / n as f64);
    }

    #[test]
    fn learning_concentrates_on_seen_samples_and_keeps_a_uniform_share() {
        let samples: Vec<([f32; 2], f32)> = (0..4096)
            .map(|i| ([(i % 64) as f32 / 64.0, (i / 64) as f32 / 64.0], f32::from(u8::from(i % 64 < 4))))
            .collect();
        let pilot =
            vec![EmitterPilot { emitted: 4096, stored: 4096, seen: 256, samples, ..Default::default() }];
        let guide = EmissionGuide::learn(&pilot, &[Guided::Direction]).unwrap();
        let (_, grid) = guide.grids[0].as_ref().unwrap();
        let mut rng = Pcg32::seed_from_u64(2);
        let n = 20_000;
        let low = (0..n).filter(|_| grid.sample([rng.gen(), rng.gen()]).0[0] < 0.1).count();
        // Seen samples have u[0] < 4/64: the fine level (filled one cell around), and the middle
        // level's first row of 8 × 8 blocks (u[0] < 1/4) keeps half of its share there.
        assert!(low as f64 / n as f64 > 0.45, "{low}");
        // Far from them: the uniform share and the coarsest level (the whole 32 × 32 grid).
        let (_, pdf) = grid.sample([0.99, 0.5]);
        assert!((pdf - DEFENSIVE - LEVELS[2].1).abs() < 1e-3, "{pdf}");
        assert!(EmissionGuide::learn(
            &[EmitterPilot { emitted: 10, ..Default::default() }],
            &[Guided::Position]
        )
        .is_none());
    }
}
