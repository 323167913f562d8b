//! Photon maps and the radiance estimate (Jensen 2001, ch. 7).
//!
//! A map is a [`KdTree`] of compact [`Photon`] records (20 bytes: position, octahedral incoming
//! direction, power) plus the number of photons *emitted* for it, since density estimates
//! divide by emitted paths, not by stored photons (Mitsuba 0.6, pbrt-v2). In the lecture's
//! per-channel mode there are three maps, one per colour channel, and a photon's power lives in
//! its map's channel only; in RGB mode one map holds RGB photons (power in shared-exponent
//! RGB9E5).
//!
//! The estimate gathers the `k` nearest photons within a maximum radius with a metric
//! flattened along the surface normal (a disc rather than a sphere, to limit leaks at corners),
//! rejects photons arriving from behind the surface, and weights them with a box, cone or
//! Gaussian kernel, each normalised to integrate to one over the disc.

use super::footprint::{Footprint, Footprints};
use super::kdtree::{flattened_metric, KdPoint, KdTree, Neighbor};
use super::kernel::kernel_weight;
use super::pack;
use crate::config::Kernel;
use crate::material::{face_forward, Material, Normals};
use glam::Vec3;
use rayon::prelude::*;
use std::f32::consts::PI;

/// A stored photon: where it landed, where it came from, and its power.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct Photon {
    pos: [f32; 3],
    /// Unit direction back toward where the photon came from, octahedral 2 × 16 bits.
    dir: u32,
    /// RGB9E5 power (RGB maps) or the `f32` bits of the channel's power (per-channel maps).
    power: u32,
}

impl KdPoint for Photon {
    #[inline(always)]
    fn position(&self) -> Vec3 {
        Vec3::from_array(self.pos)
    }
}

/// A photon as the tracer produces it, before packing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PhotonHit {
    pub pos: Vec3,
    /// Unit surface normal on the side the photon arrived from (not stored in the map; used to
    /// place precomputed irradiance).
    pub n: Vec3,
    /// Bound on the rounding error of `pos` (not stored either).
    pub err: Vec3,
    /// Unit direction back toward where the photon came from.
    pub wi: Vec3,
    pub power: Vec3,
}

/// A pass's photons for one map, as its chunks traced them: in order, each chunk a vector of
/// its own, so that nothing copies them into one (a million photons are 52 MB, and that copy
/// was serial): the map packs them and the sites are picked from them in parallel.
#[derive(Clone, Debug, Default)]
pub struct Hits {
    /// The chunks, none empty.
    chunks: Vec<Vec<PhotonHit>>,
    /// The index of each chunk's first photon in the whole sequence.
    starts: Vec<usize>,
    len: usize,
}

impl Hits {
    /// The photons of `chunks`, in order.
    pub fn from_chunks(chunks: impl IntoIterator<Item = Vec<PhotonHit>>) -> Self {
        let chunks: Vec<Vec<PhotonHit>> = chunks.into_iter().filter(|c| !c.is_empty()).collect();
        let mut starts = Vec::with_capacity(chunks.len());
        let mut len = 0;
        for c in &chunks {
            starts.push(len);
            len += c.len();
        }
        Hits { chunks, starts, len }
    }

    pub fn len(&self) -> usize {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The photons in order.
    pub fn iter(&self) -> impl Iterator<Item = &PhotonHit> {
        self.chunks.iter().flatten()
    }

    /// The photons, in parallel (in no particular order).
    pub fn par_iter(&self) -> impl ParallelIterator<Item = &PhotonHit> {
        self.chunks.par_iter().flat_map_iter(|c| c.iter())
    }

    /// `f` of every `stride`-th photon from the first, in order, worked out in parallel.
    pub fn every<U: Send>(&self, stride: usize, f: impl Fn(&PhotonHit) -> U + Sync) -> Vec<U> {
        let stride = stride.max(1);
        self.chunks
            .par_iter()
            .zip(&self.starts)
            .flat_map_iter(|(c, &start)| {
                c.iter().skip((stride - start % stride) % stride).step_by(stride).map(&f)
            })
            .collect()
    }

    /// `f(photon)` in order into a vector of the same length, worked out in parallel, chunk by
    /// chunk (`fill` is the value the vector starts with).
    fn map<U: Copy + Send + Sync>(&self, fill: U, f: impl Fn(&PhotonHit) -> U + Sync) -> Vec<U> {
        let mut out = vec![fill; self.len];
        let mut rest = &mut out[..];
        let mut pieces = Vec::with_capacity(self.chunks.len());
        for c in &self.chunks {
            let (piece, tail) = std::mem::take(&mut rest).split_at_mut(c.len());
            pieces.push(piece);
            rest = tail;
        }
        pieces.into_par_iter().zip(&self.chunks).for_each(|(piece, c)| {
            for (o, h) in piece.iter_mut().zip(c) {
                *o = f(h);
            }
        });
        out
    }
}

impl From<Vec<PhotonHit>> for Hits {
    fn from(hits: Vec<PhotonHit>) -> Self {
        Hits::from_chunks([hits])
    }
}

/// What the power of a map's photons means.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MapColor {
    /// Photons carry RGB power.
    Rgb,
    /// Photons carry only this channel's power.
    Channel(usize),
}

/// How to gather: photon count, radius bound, kernel, and the flattening of the search region.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GatherParams {
    pub k: usize,
    pub max_radius: f32,
    pub kernel: Kernel,
    /// Squash factor along the normal (`>= 1`; 1 = sphere).
    pub flatten: f32,
}

/// The squared radius a query near the last one first searches within, over the last one's:
/// a radius 1.22 times as wide, enough for most Morton-order neighbours (a query that finds
/// fewer than `k` photons within it searches again at the full radius).
pub const GUESS_MARGIN: f32 = 1.5;

/// One photon map.
#[derive(Debug, Default)]
pub struct PhotonMap {
    tree: KdTree<Photon>,
    color: Option<MapColor>,
    /// RGB maps pack `power / scale`, a power of two chosen from the largest power channel
    /// ([`pack::rgb9e5_scale`]), so that any light power fits RGB9E5's range (2⁻²⁴ to 2¹⁶
    /// unscaled); 1 for per-channel maps, which store `f32` powers.
    scale: f32,
    /// Photon paths emitted to build this map (the estimate's denominator is already folded
    /// into each photon's power; kept for reports).
    pub emitted: u64,
}

impl PhotonMap {
    /// Packs `hits` and builds the kd-tree (in parallel).
    pub fn build(hits: impl Into<Hits>, color: MapColor, emitted: u64) -> Self {
        Self::build_from(&hits.into(), color, emitted)
    }

    /// [`PhotonMap::build`] from photons the caller keeps.
    pub fn build_from(hits: &Hits, color: MapColor, emitted: u64) -> Self {
        let scale = match color {
            MapColor::Rgb => {
                pack::rgb9e5_scale(hits.par_iter().map(|h| h.power.max_element()).reduce(|| 0.0, f32::max))
            }
            MapColor::Channel(_) => 1.0,
        };
        // In parallel (a million photons take some 20 ms to pack on one thread), into a fresh
        // exact-size buffer.
        let empty = Photon { pos: [0.0; 3], dir: 0, power: 0 };
        let photons = hits.map(empty, |h| Photon {
            pos: h.pos.to_array(),
            dir: pack::encode_dir_oct(h.wi),
            power: match color {
                MapColor::Rgb => pack::rgb9e5_encode(h.power / scale),
                MapColor::Channel(c) => h.power[c].to_bits(),
            },
        });
        PhotonMap { tree: KdTree::build(photons), color: Some(color), emitted, scale }
    }

    pub fn len(&self) -> usize {
        self.tree.len()
    }

    pub fn is_empty(&self) -> bool {
        self.tree.is_empty()
    }

    /// Memory of the photons and the tree.
    pub fn bytes(&self) -> usize {
        self.tree.bytes()
    }

    /// A photon's power.
    #[inline]
    fn power(&self, p: &Photon) -> Vec3 {
        self.packed_power(p) * self.scale
    }

    /// A photon's power over the map's `scale` (a power of two, so the gathers sum these and
    /// scale the sum once, with the same result).
    #[inline]
    fn packed_power(&self, p: &Photon) -> Vec3 {
        match self.color {
            Some(MapColor::Rgb) => pack::rgb9e5_decode(p.power),
            Some(MapColor::Channel(c)) => {
                let mut v = Vec3::ZERO;
                v[c] = f32::from_bits(p.power);
                v
            }
            None => Vec3::ZERO,
        }
    }

    /// Reflected radiance toward `wo` at `x` (normals `normals`, material `m`) from this
    /// map's photons: `sum_p w_p f(wo, wi_p) power_p / (norm * pi r^2)`. The BSDF is taken
    /// about the shading normal; the disc and the side test follow the geometric one, as the
    /// photons were stored. `scratch` is reused between calls.
    pub fn radiance(
        &self,
        x: Vec3,
        normals: Normals,
        wo: Vec3,
        m: &Material,
        params: &GatherParams,
        scratch: &mut Vec<Neighbor>,
    ) -> Vec3 {
        self.radiance_over(x, normals, wo, m, params, scratch, &mut whole_disc)
    }

    /// Irradiance at `x` on the side of `ns` (unit): `sum_p w_p power_p / (pi r^2)`, for
    /// Lambertian surfaces and precomputed irradiance (Christensen 1999).
    pub fn irradiance(&self, x: Vec3, ns: Vec3, params: &GatherParams, scratch: &mut Vec<Neighbor>) -> Vec3 {
        self.irradiance_sides(x, ns, params, scratch)[0]
    }

    /// Irradiance at `x` on the side of `ns` (unit) and on the other side, from one gather:
    /// the flattened disc does not tell the sides apart, and each side's estimate sums the
    /// photons of the disc that arrived on it (a wall lit from one side gets 0 on the other).
    pub fn irradiance_sides(
        &self,
        x: Vec3,
        ns: Vec3,
        params: &GatherParams,
        scratch: &mut Vec<Neighbor>,
    ) -> [Vec3; 2] {
        self.irradiance_sides_near(x, ns, params, &mut 0.0, scratch)
    }

    /// [`PhotonMap::irradiance_sides`] for queries in sequence, each near the one before
    /// (sites in Morton order): the search first tries within the squared radius `guess` (0:
    /// none), which then receives [`GUESS_MARGIN`] times this query's. The same photons are
    /// found (ties at the `k`-th distance aside), so the same estimate but for the rounding of
    /// a sum taken in another order.
    pub fn irradiance_sides_near(
        &self,
        x: Vec3,
        ns: Vec3,
        params: &GatherParams,
        guess: &mut f32,
        scratch: &mut Vec<Neighbor>,
    ) -> [Vec3; 2] {
        self.sides_over(x, ns, params, guess, scratch, true, &mut whole_disc)
    }

    /// [`PhotonMap::radiance`] over footprints: the photons count only over
    /// `probe(false, r2)`, the footprint of the gather's disc (squared radius `r2`, that of the
    /// k-nearest search) on the surface at `x`, and the estimate divides by its weight
    /// ([`Footprint::kernel_share`]) instead of the whole disc's. Two-pass photon mapping's
    /// indirect estimates: over the whole disc, every point near an edge or a wall, and every
    /// point of a surface curving away within the disc, came out dark.
    #[allow(clippy::too_many_arguments)]
    pub fn radiance_over(
        &self,
        x: Vec3,
        normals: Normals,
        wo: Vec3,
        m: &Material,
        params: &GatherParams,
        scratch: &mut Vec<Neighbor>,
        probe: &mut dyn FnMut(bool, f32) -> Footprint,
    ) -> Vec3 {
        let ns = face_forward(normals.geometric, wo);
        if let Some(kd) = m.lambertian() {
            let [e, _] = self.sides_over(x, ns, params, &mut 0.0, scratch, false, probe);
            return e * kd * std::f32::consts::FRAC_1_PI;
        }
        let Some(r2) = self.gather(x, ns, params, scratch) else { return Vec3::ZERO };
        let mut footprint: Option<Over> = None;
        let mut sum = Vec3::ZERO;
        for nb in estimated(scratch, params) {
            let p = self.tree.get(nb.index);
            let wi = pack::decode_dir_oct(p.dir);
            if wi.dot(ns) <= 0.0 {
                continue;
            }
            let over = footprint.get_or_insert_with(|| Over::new(probe(false, r2), r2));
            if let Some(w) = over.weight(nb, p.position() - x, params.kernel) {
                sum += w * normals.gather_eval(m, wo, wi) * self.packed_power(p);
            }
        }
        footprint.map_or(Vec3::ZERO, |over| sum * self.scale / over.area(params.kernel))
    }

    /// [`PhotonMap::irradiance_sides_near`] over footprints: each side's photons count only over
    /// `probe(back, r2)`, the footprint of the gather's disc on that side of the surface at `x`
    /// (probed only where photons arrived on that side), as in [`PhotonMap::radiance_over`].
    pub fn irradiance_sides_over(
        &self,
        x: Vec3,
        ns: Vec3,
        params: &GatherParams,
        guess: &mut f32,
        scratch: &mut Vec<Neighbor>,
        probe: &mut dyn FnMut(bool, f32) -> Footprint,
    ) -> [Vec3; 2] {
        self.sides_over(x, ns, params, guess, scratch, true, probe)
    }

    /// Irradiance on the side of `ns` (and with `both`, on the other) over the footprints
    /// `probe` gives, from one k-nearest search begun at `guess` ([`PhotonMap::gather_guessed`]).
    #[allow(clippy::too_many_arguments)]
    fn sides_over(
        &self,
        x: Vec3,
        ns: Vec3,
        params: &GatherParams,
        guess: &mut f32,
        scratch: &mut Vec<Neighbor>,
        both: bool,
        probe: &mut dyn FnMut(bool, f32) -> Footprint,
    ) -> [Vec3; 2] {
        let found = self.gather_guessed(x, ns, params, *guess, scratch);
        *guess = found.map_or(0.0, |r2| r2 * GUESS_MARGIN);
        let Some(r2) = found else { return [Vec3::ZERO; 2] };
        let mut footprints: [Option<Over>; 2] = [None, None];
        let mut sums = [Vec3::ZERO; 2];
        for nb in estimated(scratch, params) {
            let p = self.tree.get(nb.index);
            let side = pack::decode_dir_oct_unnormalized(p.dir).dot(ns);
            let s = match side {
                _ if side > 0.0 => 0,
                _ if side < 0.0 && both => 1,
                _ => continue,
            };
            let over = footprints[s].get_or_insert_with(|| Over::new(probe(s == 1, r2), r2));
            if let Some(w) = over.weight(nb, p.position() - x, params.kernel) {
                sums[s] += w * self.packed_power(p);
            }
        }
        let estimate = |s: usize| {
            footprints[s].map_or(Vec3::ZERO, |over| sums[s] * self.scale / over.area(params.kernel))
        };
        [estimate(0), estimate(1)]
    }

    /// Gathers the photons near `x` into `scratch` (a disc flattened along `ns`) and returns the
    /// squared radius of the estimate's disc, or `None` when nothing was found. Photons arriving
    /// from behind the surface (`wi . ns <= 0`) are left for the caller to reject.
    #[inline]
    fn gather(&self, x: Vec3, ns: Vec3, params: &GatherParams, scratch: &mut Vec<Neighbor>) -> Option<f32> {
        self.gather_guessed(x, ns, params, 0.0, scratch)
    }

    /// [`PhotonMap::gather`], the search tried first within the squared radius `guess` (0: not).
    #[inline]
    fn gather_guessed(
        &self,
        x: Vec3,
        ns: Vec3,
        params: &GatherParams,
        guess: f32,
        scratch: &mut Vec<Neighbor>,
    ) -> Option<f32> {
        if self.tree.is_empty() {
            scratch.clear();
            return None;
        }
        let metric = flattened_metric(ns, params.flatten);
        self.tree.knn_with_guess(x, params.k, params.max_radius, guess, metric, scratch);
        if scratch.is_empty() {
            return None;
        }
        // With k photons found the disc reaches the farthest; with fewer, the whole search disc
        // was empty beyond them, so its area is the search area.
        let r2 =
            if scratch.len() == params.k { scratch[0].dist2 } else { params.max_radius * params.max_radius };
        (r2 > 0.0).then_some(r2)
    }

    /// Calls `f(wi, power)` for every photon within `radius` of `x` in the region flattened
    /// along `ns` (unit) by `flatten`, arriving from the side of `ns`; returns how many there
    /// were. The fixed-radius query of progressive photon mapping.
    #[inline]
    pub fn for_each_within(
        &self,
        x: Vec3,
        ns: Vec3,
        radius: f32,
        flatten: f32,
        mut f: impl FnMut(Vec3, Vec3),
    ) -> u32 {
        let mut count = 0;
        self.tree.for_each_within_with(x, radius, flattened_metric(ns, flatten), |i, _| {
            let p = self.tree.get(i);
            let wi = pack::decode_dir_oct(p.dir);
            if wi.dot(ns) > 0.0 {
                count += 1;
                f(wi, self.power(p));
            }
        });
        count
    }

    /// Calls `f(offset, wi, power, d2)` (`d2`: its squared distance in that metric; `wi` a
    /// positive multiple of the direction the photon arrived from, not normalised) for every photon strictly inside the squared radius `r2` of
    /// `x` in the region flattened along `ns` (unit) by `flatten`, arriving from the side of
    /// `ns` (`offset` is the photon's position minus `x`); `f` says whether it counted the
    /// photon, and the photons counted are returned. The fixed-radius query of progressive
    /// photon mapping: strict, so that a disc drawn through a photon (the first radius, the
    /// distance to the `k`-th nearest) leaves it out, as [`PhotonMap::radiance`] does.
    #[inline]
    pub fn for_each_inside(
        &self,
        x: Vec3,
        ns: Vec3,
        r2: f32,
        flatten: f32,
        mut f: impl FnMut(Vec3, Vec3, Vec3, f32) -> bool,
    ) -> u32 {
        let mut count = 0;
        self.tree.for_each_below_with(x, r2, flattened_metric(ns, flatten), |i, d2| {
            count += self.offer(i, d2, x, ns, &mut f) as u32;
        });
        count
    }

    /// [`PhotonMap::for_each_inside`] giving up once more than `most` photons lie within the
    /// region (counted or not): `None` then (some photons were offered to `f`, not all).
    pub fn for_each_inside_at_most(
        &self,
        x: Vec3,
        ns: Vec3,
        r2: f32,
        flatten: f32,
        most: u32,
        mut f: impl FnMut(Vec3, Vec3, Vec3, f32) -> bool,
    ) -> Option<u32> {
        let (mut count, mut within) = (0, 0u32);
        self.tree.for_each_below_until(x, r2, flattened_metric(ns, flatten), |i, d2| {
            count += self.offer(i, d2, x, ns, &mut f) as u32;
            within += 1;
            within > most
        });
        (within <= most).then_some(count)
    }

    /// [`PhotonMap::for_each_inside`] over the photons that [`PhotonMap::knn_radius2_guessed`]
    /// found at the same `x` and `ns` with `params` (`found`, in the metric flattened by
    /// `params.flatten`): the same photons (in another order) without searching the tree again
    /// whenever `r2` is at most the search's squared radius, as a pass-indexed pass's disc is;
    /// otherwise it searches.
    #[inline]
    pub fn for_each_found_inside(
        &self,
        x: Vec3,
        ns: Vec3,
        r2: f32,
        params: &GatherParams,
        found: &[Neighbor],
        mut f: impl FnMut(Vec3, Vec3, Vec3, f32) -> bool,
    ) -> u32 {
        // Every photon strictly inside the farthest found is found; with fewer than `k`, every
        // photon within the search radius was.
        let reach = match found.first() {
            Some(far) if found.len() == params.k => far.dist2,
            _ => params.max_radius * params.max_radius,
        };
        if r2 > reach {
            return self.for_each_inside(x, ns, r2, params.flatten, f);
        }
        let mut count = 0;
        for nb in found.iter().filter(|nb| nb.dist2 < r2) {
            count += self.offer(nb.index, nb.dist2, x, ns, &mut f) as u32;
        }
        count
    }

    /// Offers photon `i`, at squared distance `d2` from `x` in the gather's metric, to `f` if
    /// it arrives from the side of `ns`: whether `f` counted it. Its direction goes to `f` as a
    /// positive multiple, not normalised (a Lambertian gather never looks at it).
    #[inline(always)]
    fn offer(
        &self,
        i: u32,
        d2: f32,
        x: Vec3,
        ns: Vec3,
        f: &mut impl FnMut(Vec3, Vec3, Vec3, f32) -> bool,
    ) -> bool {
        let p = self.tree.get(i);
        let wi = pack::decode_dir_oct_unnormalized(p.dir);
        wi.dot(ns) > 0.0 && f(p.position() - x, wi, self.power(p), d2)
    }

    /// Squared distance (in the flattened metric) from `x` to its `k`-th nearest photon, or
    /// `max_radius²` when fewer than `k` lie within `max_radius`; the search is tried first
    /// within the squared radius `guess` (0: not; a nearby query's result times
    /// [`GUESS_MARGIN`]), and the photons it found are left in `found` for
    /// [`PhotonMap::for_each_found_inside`]. The same radius whatever the guess.
    pub fn knn_radius2_guessed(
        &self,
        x: Vec3,
        ns: Vec3,
        params: &GatherParams,
        guess: f32,
        found: &mut Vec<Neighbor>,
    ) -> f32 {
        match self.gather_guessed(x, ns, params, guess, found) {
            Some(r2) => r2,
            None => params.max_radius * params.max_radius,
        }
    }

    /// Stored photons in tree order, unpacked (for tests and tools).
    pub fn photons(&self) -> impl Iterator<Item = PhotonHit> + '_ {
        self.tree.items().iter().map(|p| PhotonHit {
            pos: p.position(),
            n: Vec3::ZERO,
            err: Vec3::ZERO,
            wi: pack::decode_dir_oct(p.dir),
            power: self.power(p),
        })
    }
}

/// The footprint of the whole disc of squared radius `r2`: the estimates without probes.
fn whole_disc(_back: bool, r2: f32) -> Footprint {
    Footprint::whole(r2)
}

/// A gather's footprint as its sum uses it: which photons count and with what kernel weight.
#[derive(Clone, Copy)]
struct Over {
    fp: Footprint,
    /// Whether the footprint's disc is the gather's own (not one shrunk by the probes).
    own: bool,
    inv_r2: f32,
}

impl Over {
    fn new(fp: Footprint, r2: f32) -> Self {
        Over { own: fp.r2 == r2, inv_r2: 1.0 / fp.r2, fp }
    }

    /// The kernel weight of the photon `nb` at `offset` from the gather point, or `None` when
    /// it lies outside the footprint (every photon the search found lies in its own disc).
    #[inline(always)]
    fn weight(&self, nb: &Neighbor, offset: Vec3, kernel: Kernel) -> Option<f32> {
        ((self.own || nb.dist2 < self.fp.r2) && self.fp.contains(offset))
            .then(|| kernel_weight(kernel, nb.dist2 * self.inv_r2))
    }

    /// The area the photons counted are spread over, their kernel's weight over it included.
    #[inline]
    fn area(&self, kernel: Kernel) -> f32 {
        PI * self.fp.r2 * self.fp.kernel_share(kernel)
    }
}

/// The photons an estimate sums, of those [`PhotonMap::gather`] found: all of them when fewer
/// than `k` were within the search radius (the disc is then the search disc), otherwise all
/// but the farthest, whose distance *is* the disc's radius. With `k` photons in a disc drawn
/// through the `k`-th, the `k - 1` inside are what the disc's area measures: summing the `k`-th
/// too makes a box estimate `k / (k - 1)` too bright (+11 % at k = 10, +1.7 % at k = 60) and a
/// Gaussian one about half that; the cone gives it weight 0 anyway.
#[inline]
fn estimated<'s>(found: &'s [Neighbor], params: &GatherParams) -> &'s [Neighbor] {
    // `found` is a max-heap: the farthest is first.
    if found.len() == params.k {
        &found[1..]
    } else {
        found
    }
}

/// `n` photons scattered uniformly at random over the square `[0, side]²` of the floor `y = 0`,
/// arriving straight down with `1 / n` W each (generator seeded `seed`): for tests of the
/// estimates' means.
#[cfg(test)]
pub(crate) fn uniform_floor(n: usize, side: f32, seed: u64) -> Vec<PhotonHit> {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
    (0..n)
        .map(|_| PhotonHit {
            pos: Vec3::new(rng.gen::<f32>() * side, 0.0, rng.gen::<f32>() * side),
            n: Vec3::Y,
            err: Vec3::ZERO,
            wi: Vec3::Y,
            power: Vec3::splat(1.0 / n as f32),
        })
        .collect()
}

/// The maps a render uses. Per-channel mode keeps three maps of each kind, RGB mode one.
#[derive(Debug, Default)]
pub struct PhotonMaps {
    pub caustic: Vec<PhotonMap>,
    pub indirect: Vec<PhotonMap>,
}

impl PhotonMaps {
    /// Sum of the radiance estimates of `maps`.
    pub fn radiance(
        maps: &[PhotonMap],
        x: Vec3,
        normals: Normals,
        wo: Vec3,
        m: &Material,
        params: &GatherParams,
        scratch: &mut Vec<Neighbor>,
    ) -> Vec3 {
        maps.iter().map(|map| map.radiance(x, normals, wo, m, params, scratch)).sum()
    }

    /// Sum of the radiance estimates of `maps` over footprints ([`PhotonMap::radiance_over`]).
    #[allow(clippy::too_many_arguments)]
    pub fn radiance_over(
        maps: &[PhotonMap],
        x: Vec3,
        normals: Normals,
        wo: Vec3,
        m: &Material,
        params: &GatherParams,
        scratch: &mut Vec<Neighbor>,
        probe: &mut dyn FnMut(bool, f32) -> Footprint,
    ) -> Vec3 {
        let mut footprints = Footprints::new(probe, maps.len());
        let mut at = |back, r2| footprints.get(back, r2);
        maps.iter().map(|map| map.radiance_over(x, normals, wo, m, params, scratch, &mut at)).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A uniform photon density on a plane gives the exact irradiance and radiance.
    #[test]
    fn uniform_density_estimate_is_exact_on_average() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_pcg::Pcg64::seed_from_u64(7);
        let n = 200_000;
        let side = 10.0f32;
        let power_each = 3.0 / n as f32; // total flux 3 W over 100 m^2: E = 0.03 W/m^2
        let hits: Vec<PhotonHit> = (0..n)
            .map(|_| PhotonHit {
                pos: Vec3::new(rng.gen::<f32>() * side, 0.0, rng.gen::<f32>() * side),
                n: Vec3::Y,
                err: Vec3::ZERO,
                wi: Vec3::new(0.3, 0.9, 0.1).normalize(),
                power: Vec3::splat(power_each),
            })
            .collect();
        let map = PhotonMap::build(hits, MapColor::Rgb, n as u64);
        let m = Material::Diffuse { kd: Vec3::splat(0.5) };
        let mut scratch = Vec::new();
        for kernel in [Kernel::Box, Kernel::Cone, Kernel::Gaussian] {
            let params = GatherParams { k: 200, max_radius: 1.0, kernel, flatten: 4.0 };
            let mut mean = Vec3::ZERO;
            let q = 50;
            for i in 0..q {
                let x = Vec3::new(2.0 + 6.0 * (i as f32 / q as f32), 0.0, 5.0);
                mean +=
                    map.radiance(x, Normals::flat(Vec3::Y), Vec3::Y, &m, &params, &mut scratch) / q as f32;
            }
            let expect = 0.03 * 0.5 / PI; // L = E kd / pi
            assert!((mean.x - expect).abs() / expect < 0.03, "{kernel:?}: {mean} vs {expect}");
            // Seen from below, nothing arrives.
            let below = map.radiance(
                Vec3::new(5.0, 0.0, 5.0),
                Normals::flat(Vec3::Y),
                -Vec3::Y,
                &m,
                &params,
                &mut scratch,
            );
            assert_eq!(below, Vec3::ZERO);
        }
    }

    /// With few photons per estimate the k-nearest estimate is still unbiased, for every
    /// kernel (the k-th photon, which fixes the radius, is not counted).
    #[test]
    fn small_k_estimates_are_unbiased() {
        let (n, side) = (200_000, 10.0f32);
        let hits = uniform_floor(n, side, 11);
        let map = PhotonMap::build(hits, MapColor::Rgb, n as u64);
        let expect = 1.0 / (side * side);
        let mut scratch = Vec::new();
        for k in [5, 10, 60] {
            for kernel in [Kernel::Box, Kernel::Cone, Kernel::Gaussian] {
                let params = GatherParams { k, max_radius: 1.0, kernel, flatten: 4.0 };
                let (mut sum, mut count) = (0.0f64, 0);
                // Query points far enough apart that their estimates are independent.
                for i in 0..60 {
                    for j in 0..60 {
                        let x = Vec3::new(1.0 + 8.0 * i as f32 / 60.0, 0.0, 1.0 + 8.0 * j as f32 / 60.0);
                        sum += map.irradiance(x, Vec3::Y, &params, &mut scratch).x as f64;
                        count += 1;
                    }
                }
                let mean = sum / count as f64;
                let bias = mean / expect as f64 - 1.0;
                assert!(bias.abs() < 0.03, "k {k}, {kernel:?}: mean off by {:+.2}%", 100.0 * bias);
            }
        }
    }

    /// A query with a cap on the photons within its region is the plain query where they are
    /// fewer, and gives up (`None`) where there are more, having offered no more than the cap
    /// and one.
    #[test]
    fn a_capped_query_is_the_plain_one_or_gives_up() {
        let hits = uniform_floor(20_000, 4.0, 3);
        let map = PhotonMap::build(hits, MapColor::Rgb, 20_000);
        let x = Vec3::new(2.0, 0.0, 2.0);
        for r2 in [0.001f32, 0.01, 0.05] {
            let mut plain = 0u32;
            let all = map.for_each_inside(x, Vec3::Y, r2, 2.0, |_, _, _, _| {
                plain += 1;
                true
            });
            assert_eq!(all, plain);
            for most in [all / 2, all, all + 10] {
                let mut offered = 0u32;
                let capped = map.for_each_inside_at_most(x, Vec3::Y, r2, 2.0, most, |_, _, _, _| {
                    offered += 1;
                    true
                });
                if all <= most {
                    assert_eq!(capped, Some(all), "r² {r2}, cap {most}");
                } else {
                    assert_eq!(capped, None, "r² {r2}, cap {most}");
                    assert!(offered <= most + 1, "offered {offered} past the cap {most}");
                }
            }
        }
    }

    /// The photons a k-nearest search found serve any gather within its radius: the same
    /// photons as the fixed-radius query, whatever the guess the search started from; beyond
    /// its radius the query searches.
    #[test]
    fn found_photons_are_the_fixed_radius_query_within_their_radius() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_pcg::Pcg64::seed_from_u64(5);
        let hits: Vec<PhotonHit> = uniform_floor(20_000, 4.0, 3)
            .into_iter()
            .map(|mut h| {
                // Off the plane a little, and some arriving from below.
                h.pos.y = 0.05 * (rng.gen::<f32>() - 0.5);
                h.wi = Vec3::new(rng.gen::<f32>() - 0.5, rng.gen::<f32>() - 0.3, rng.gen::<f32>() - 0.5)
                    .normalize();
                h
            })
            .collect();
        let map = PhotonMap::build(hits, MapColor::Rgb, 20_000);
        let ns = Vec3::Y;
        type Visit<'v> = &'v mut dyn FnMut(Vec3, Vec3, Vec3, f32) -> bool;
        let collect = |f: &mut dyn FnMut(Visit) -> u32| {
            let mut seen = Vec::new();
            let n = f(&mut |offset, _, _, d2| {
                seen.push((offset.x.to_bits(), offset.z.to_bits(), d2.to_bits()));
                true
            });
            seen.sort_unstable();
            assert_eq!(n as usize, seen.len());
            seen
        };
        let (mut found, mut guessed) = (Vec::new(), Vec::new());
        let mut compared = 0;
        for i in 0..200 {
            let x = Vec3::new(0.5 + 3.0 * rng.gen::<f32>(), 0.0, 0.5 + 3.0 * rng.gen::<f32>());
            let k = [5, 30, 100][i % 3];
            let params =
                GatherParams { k, max_radius: [1.0, 0.05][i % 2], kernel: Kernel::Box, flatten: 8.0 };
            let r2 = map.knn_radius2_guessed(x, ns, &params, 0.0, &mut found);
            for guess in [1e-4, 0.01 * r2, 2.0 * r2] {
                assert_eq!(map.knn_radius2_guessed(x, ns, &params, guess, &mut guessed), r2);
            }
            for scale in [1.0, 0.6, 0.05, 2.0] {
                let q = r2 * scale;
                let listed = collect(&mut |f| map.for_each_found_inside(x, ns, q, &params, &found, f));
                let searched = collect(&mut |f| map.for_each_inside(x, ns, q, 8.0, f));
                assert_eq!(listed, searched, "query {i}, k {k}, scale {scale}");
                compared += listed.len();
            }
        }
        assert!(compared > 5000, "{compared}");
    }
}
