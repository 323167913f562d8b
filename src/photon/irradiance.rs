//! Precomputed irradiance (Christensen, "Faster Photon Map Global Illumination", JGT 4(3),
//! 1999): the irradiance estimate is computed once at a subset of the photon positions, and a
//! diffuse surface then reads the nearest precomputed value with a matching normal instead of
//! gathering `k` photons itself. It turns each indirect lookup (and each final-gather hit) from
//! a k-nearest search plus `k` BRDF evaluations into a search for one point.
//!
//! Each site stores its direct, indirect and caustic irradiance separately. At camera hits
//! only the indirect part is used (direct light comes from shadow rays there and the caustic
//! map is read directly, so caustics stay sharp); final-gather rays use all three, so a gather
//! ray costs one lookup and no shadow ray (Christensen's global map holds direct light for the
//! same reason; here it is computed at each site with shadow rays, since the first photon hits
//! are not stored).
//!
//! The values are estimated on demand, a block of neighbouring sites at a time, when a lookup
//! first reads one of the block's sites: a view sees part of the scene, and the sites it never
//! reads are never estimated (on the default renders 19 % of the doorway's sites are
//! estimated, 78 % of the Cornell box's: `--stats`, `irradiance_cache`). A block's values depend only on its sites and the maps,
//! so they are the same whichever thread estimates them and whenever.

use super::footprint::{Clear, Footprint, Footprints};
use super::kdtree::{KdPoint, KdTree, Neighbor};
use super::map::{GatherParams, Hits, PhotonMap};
use super::pack;
use glam::Vec3;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::OnceLock;

/// A site in the search tree: 28 bytes.
#[derive(Clone, Copy, Debug)]
#[repr(C)]
struct Site {
    pos: [f32; 3],
    /// The unit normal on the side its photon arrived from.
    normal: [f32; 3],
    /// Its place in Morton order (and so its block).
    order: u32,
}

impl Site {
    #[inline(always)]
    fn normal(&self) -> Vec3 {
        Vec3::from_array(self.normal)
    }
}

/// A site's irradiance, packed over its block's scale: 16 bytes.
#[derive(Clone, Copy, Debug, Default)]
struct Values {
    direct: u32,
    indirect: u32,
    caustic: u32,
    /// Indirect irradiance on the other side (the side of `-normal`).
    indirect_back: u32,
}

/// The values of a block of [`SITE_BLOCK`] sites (consecutive in Morton order).
#[derive(Debug)]
struct Block {
    /// The values pack irradiance divided by this power of two (see [`pack::rgb9e5_scale`]),
    /// so that any light power fits RGB9E5's range.
    scale: f32,
    values: Box<[Values]>,
}

/// Irradiance at a surface point, by the kind of light path that brought it.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Irradiance {
    pub direct: Vec3,
    pub indirect: Vec3,
    pub caustic: Vec3,
}

impl KdPoint for Site {
    #[inline(always)]
    fn position(&self) -> Vec3 {
        Vec3::from_array(self.pos)
    }
}

/// Lookups consider this many nearest sites for one with a matching normal.
const CANDIDATES: usize = 8;
/// Smallest cosine between a site's normal and the surface's.
const NORMAL_COS: f32 = 0.9;

/// Whether a site at `offset` from a query point, its normal at cosine `cos` to the query's
/// (unit normal `ns`), lies on the query's surface as far as a lookup can tell: its normal
/// within 25° ([`NORMAL_COS`]), and it within 21° of the query's tangent plane (its height off
/// the plane at most `1/√8` of its distance, the slope of the flattened disc of the gathers over
/// the whole disc). A site whose normal agrees but which lies off the plane is on another
/// surface facing the same way: a ceiling 2.4 cm above a closed lamp found the sites on the
/// inside of the lamp's top, facing down as the ceiling does, and glowed with the lamp's inside
/// light (`scripts/closed-lamp.sh`); so did a floor below a closed box.
#[inline]
fn on_surface(cos: f32, offset: Vec3, ns: Vec3) -> bool {
    let h = offset.dot(ns);
    cos >= NORMAL_COS && 8.0 * h * h <= offset.length_squared()
}

/// Irradiance at photon positions, for fast diffuse lookups: the sites, indexed, and their
/// values as far as they have been estimated (read through [`Sites`]).
#[derive(Debug, Default)]
pub struct PrecomputedIrradiance {
    tree: KdTree<Site>,
    /// Largest distance at which a site is used.
    max_radius: f32,
    /// The sites' places in the tree, in Morton order ([`SITE_BLOCK`] to a block).
    in_tree: Vec<u32>,
    /// Their error bounds, in Morton order, when kept (for the direct light at a site).
    errors: Vec<Vec3>,
    blocks: Vec<OnceLock<Block>>,
    /// Sites estimated so far, and the thread time it took (nanoseconds).
    estimated: AtomicU64,
    estimate_ns: AtomicU64,
}

/// Direct irradiance at a site: `direct(i, site)`, `i` the site's place in Morton order.
pub type SiteDirect<'a> = dyn Fn(usize, &SitePoint) -> Vec3 + Sync + 'a;

/// The footprint of a site's indirect gather: `probe(i, site, back, r2)`, on the side of the
/// site's normal (or with `back` the other) within the squared radius `r2` (`i` the site's
/// place in Morton order).
pub type SiteProbe<'a> = dyn Fn(usize, &SitePoint, bool, f32) -> Footprint + Sync + 'a;

/// What the values of a [`PrecomputedIrradiance`]'s sites are estimated from: the maps its
/// sites were picked from (or, for caustic sites, whose light they read), the gathers, the
/// direct irradiance at a site (`direct(i, site)`, `i` the site's place in Morton order; none:
/// zero) and the footprints the indirect gathers count photons over (none: the whole disc).
#[derive(Clone, Copy)]
pub struct SiteSource<'m> {
    pub indirect: &'m [PhotonMap],
    pub caustic: &'m [PhotonMap],
    pub gather: &'m GatherParams,
    pub caustic_gather: &'m GatherParams,
    pub direct: Option<&'m SiteDirect<'m>>,
    pub probe: Option<&'m SiteProbe<'m>>,
}

/// The sites of a [`PrecomputedIrradiance`] with what their values are estimated from: its
/// lookups. A lookup first finds a site (`find_*`: where the time goes on the camera's side),
/// then reads its value, estimating the site's block if no lookup has before.
#[derive(Clone, Copy)]
pub struct Sites<'c> {
    cache: &'c PrecomputedIrradiance,
    source: SiteSource<'c>,
}

/// A site found by a lookup of [`Sites`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SiteRef(u32);

/// A thread's scratch space for the lookups of [`Sites`] ([`Sites::find`],
/// [`Sites::find_indirect`], [`Sites::find_caustic`]). It remembers the last site found, which
/// starts the next search (a camera pixel's samples, looked up one after the other, mostly land
/// by the same site), and every site around the last place searched (a neighbourhood), which
/// answers most of the next queries without a search: the answers do not depend on either,
/// only the time.
#[derive(Debug, Default)]
pub struct LookupScratch {
    rejected: Vec<Neighbor>,
    last: Option<u32>,
    /// Where the coming queries lie ([`LookupScratch::expect`]).
    region: Option<(Vec3, f32)>,
    near: Neighbourhood,
}

/// Sites a neighbourhood holds at most.
const NEIGHBOURHOOD_SITES: usize = 64;

impl LookupScratch {
    /// Tells the lookups that the next ones lie within `radius` of `centre` (a camera pixel's
    /// first hits), until told otherwise: the first of them that the sites held do not answer
    /// gathers the sites of that whole region (and a margin), and the others scan them.
    pub fn expect(&mut self, centre: Vec3, radius: f32) {
        self.region = Some((centre, radius));
    }
}

/// Every site within `radius` of `centre`, so that a query at `x` whose answer lies nearer to
/// `x` than `radius - |x - centre|` can be answered from these alone, exactly: no site outside
/// is that near (the triangle inequality). A pixel's samples land within a pixel's footprint of
/// each other: one search gathers the neighbourhood, and the other samples scan a few sites
/// already in cache instead of walking the tree from its root.
#[derive(Debug, Default)]
struct Neighbourhood {
    centre: Vec3,
    /// Every site nearer than this to `centre` is held (0: empty).
    radius: f32,
    /// Rounding allowance on distances: computed distances may fall short of true ones by
    /// about the rounding of the coordinates (positions far from the origin) and of the
    /// arithmetic.
    slack: f32,
    sites: Vec<NearSite>,
    /// Whether `sites` are the nearest [`NEIGHBOURHOOD_SITES`] to `centre`, more lying
    /// within the radius asked for.
    capped: bool,
    /// Scratch for the search that gathers them, and for their order.
    found: Vec<Neighbor>,
    keys: Vec<u64>,
}

#[derive(Clone, Copy, Debug)]
struct NearSite {
    pos: Vec3,
    normal: Vec3,
    /// Distance from the neighbourhood's centre (the sites are held in its order).
    from_centre: f32,
    index: u32,
}

/// What a [`Neighbourhood`] says about a query.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Known {
    /// The answer, exactly (`None`: no site qualifies).
    Answer(Option<u32>),
    /// The query reaches past the sites held.
    Unknown,
}

impl Neighbourhood {
    /// The nearest site `accept`ed (by its decoded normal and its offset from `x`) among the
    /// `k` nearest to `x` within `max_radius` — what [`KdTree::nearest_among`] returns — if the
    /// sites held decide it.
    #[inline]
    fn answer(&self, x: Vec3, k: usize, max_radius: f32, accept: impl Fn(Vec3, Vec3) -> bool) -> Known {
        if self.radius <= 0.0 {
            return Known::Unknown;
        }
        let e = (x - self.centre).length();
        let reach = self.radius - e - self.slack;
        if reach <= 0.0 {
            return Known::Unknown;
        }
        // Every site with `d2 < known` is held; the search takes `d2 <= max_radius²`.
        let known = reach * reach;
        let within = max_radius * max_radius;
        let limit = known.min(f32::from_bits(within.to_bits() + 1));
        let mut best = (limit, None);
        // Squared distances of the rejected sites found nearer than the best at the time.
        let mut rejected = [0.0f32; NEIGHBOURHOOD_SITES];
        let mut n_rejected = 0;
        for s in &self.sites {
            // Sites come by distance from the centre: none after this one can be nearer.
            let lower = s.from_centre - e - self.slack;
            if lower > 0.0 && lower * lower >= best.0 {
                break;
            }
            let d2 = (s.pos - x).length_squared();
            if d2 < best.0 {
                if accept(s.normal, s.pos - x) {
                    best = (d2, Some(s.index));
                } else {
                    rejected[n_rejected] = d2;
                    n_rejected += 1;
                }
            }
        }
        let nearer = rejected[..n_rejected].iter().filter(|&&d2| d2 < best.0).count();
        match best.1 {
            Some(index) => Known::Answer((nearer < k).then_some(index)),
            // No accepted site within the search's reach, which lies inside what is held:
            // none at all.
            None if nearer >= k || within < known => Known::Answer(None),
            None => Known::Unknown,
        }
    }

    /// Gathers the sites within `radius` of `centre` from `tree` (the nearest
    /// [`NEIGHBOURHOOD_SITES`] if there are more, the radius shrunk to the farthest of them).
    /// Nothing is searched when the sites held already answer for the same centre: those
    /// within a radius as large, or the nearest [`NEIGHBOURHOOD_SITES`] (a pixel's queries
    /// that reach past them are searched for one by one).
    fn gather(&mut self, tree: &KdTree<Site>, centre: Vec3, radius: f32) {
        if self.radius > 0.0 && centre == self.centre && (self.capped || radius <= self.radius) {
            return;
        }
        tree.knn(centre, NEIGHBOURHOOD_SITES, radius, &mut self.found);
        self.centre = centre;
        self.capped = self.found.len() == NEIGHBOURHOOD_SITES;
        self.radius = if self.capped {
            // Every site strictly nearer than the farthest one kept is held.
            self.found[0].dist2.sqrt()
        } else {
            radius
        };
        let scale = centre.abs().max_element() + self.radius;
        self.slack = self.radius * 1e-5 + 8.0 * f32::EPSILON * scale;
        self.sites.clear();
        // By distance, as integers: a non-negative float's bits order as its value does (and
        // ties go by index).
        self.keys.clear();
        self.keys.extend(self.found.iter().map(|n| u64::from(n.dist2.to_bits()) << 32 | u64::from(n.index)));
        self.keys.sort_unstable();
        self.sites.extend(self.keys.iter().map(|&key| {
            let index = key as u32;
            let s = tree.get(index);
            let from_centre = f32::from_bits((key >> 32) as u32).sqrt();
            NearSite { pos: s.position(), normal: s.normal(), from_centre, index }
        }));
    }
}

/// A place where irradiance is precomputed: a photon's position, its error bound and the
/// normal on the side it arrived from.
#[derive(Clone, Copy, Debug)]
pub struct SitePoint {
    pub pos: Vec3,
    pub err: Vec3,
    pub n: Vec3,
}

/// Every `stride`-th photon of each map, as sites.
pub fn pick_sites(maps: &[Hits], stride: usize) -> Vec<SitePoint> {
    maps.iter()
        .flat_map(|hits| hits.every(stride, |h| SitePoint { pos: h.pos, err: h.err, n: h.n }))
        .collect()
}

/// Sites a block holds: estimated together, one after the other, each search starting from
/// the last one's radius (the guess chain restarts at every block, so a block's values do not
/// depend on which blocks were estimated before it, nor by which thread).
pub const SITE_BLOCK: usize = 32;

impl PrecomputedIrradiance {
    /// Indexes `sites`, whose values will be estimated on demand (read them through
    /// [`PrecomputedIrradiance::sites`]); a site is read within `max_radius`. `keep_errors`:
    /// keep the sites' error bounds, which a [`SiteSource`] with direct light or probes needs
    /// (their rays leave from the sites).
    pub fn new(sites: Vec<SitePoint>, max_radius: f32, keep_errors: bool) -> Self {
        // Photons come in the order they were traced, scattered over the scene; estimating in
        // Morton order makes consecutive queries walk the same part of the tree, and puts
        // nearby sites in one block.
        let mut sites = sites;
        morton_sort(&mut sites);
        let errors = if keep_errors { sites.iter().map(|s| s.err).collect() } else { Vec::new() };
        let tree_sites = sites
            .par_iter()
            .enumerate()
            .map(|(i, p)| Site { pos: p.pos.to_array(), normal: p.n.to_array(), order: i as u32 })
            .collect();
        let tree = KdTree::build(tree_sites);
        let mut in_tree = vec![0u32; sites.len()];
        for (i, s) in tree.items().iter().enumerate() {
            in_tree[s.order as usize] = i as u32;
        }
        let blocks = (0..sites.len().div_ceil(SITE_BLOCK)).map(|_| OnceLock::new()).collect();
        PrecomputedIrradiance {
            tree,
            max_radius,
            in_tree,
            errors,
            blocks,
            estimated: AtomicU64::new(0),
            estimate_ns: AtomicU64::new(0),
        }
    }

    /// The lookups, with what the values are estimated from (the maps the sites were made for).
    pub fn sites<'c>(&'c self, source: SiteSource<'c>) -> Sites<'c> {
        assert!(
            (source.direct.is_none() && source.probe.is_none()) || self.errors.len() == self.in_tree.len(),
            "direct light or probes at sites indexed without their error bounds"
        );
        Sites { cache: self, source }
    }

    /// Sites whose values have been estimated so far, and the thread time it took (seconds).
    pub fn estimated(&self) -> (u64, f64) {
        (self.estimated.load(Ordering::Relaxed), self.estimate_ns.load(Ordering::Relaxed) as f64 * 1e-9)
    }

    /// Estimates block `b`: indirect (both sides) and caustic irradiance from the maps, direct
    /// from `direct`.
    fn estimate(&self, b: usize, source: &SiteSource<'_>) -> Block {
        let start = std::time::Instant::now();
        let first = b * SITE_BLOCK;
        let in_block = &self.in_tree[first..(first + SITE_BLOCK).min(self.in_tree.len())];
        let mut scratch: Vec<Neighbor> = Vec::new();
        // Consecutive sites are near each other: each map's search starts from the last one's
        // radius.
        let mut guesses = vec![0.0f32; source.indirect.len()];
        // On each side, the last disc the block's probes found whole.
        let mut clear: [Option<Clear>; 2] = [None, None];
        let raw: Vec<(Irradiance, Vec3)> = in_block
            .iter()
            .enumerate()
            .map(|(j, &t)| {
                let site = self.tree.get(t);
                let (pos, n) = (site.position(), site.normal());
                let [mut indirect, mut back] = [Vec3::ZERO; 2];
                let point = || SitePoint { pos, err: self.errors[first + j], n };
                let maps = source.indirect.len();
                let clear = &mut clear;
                let mut footprints = source.probe.map(|probe| {
                    // The block's next sites within a disc found whole on the same side
                    // need no probes of their own.
                    let at = move |back: bool, r2: f32| {
                        let side = if back { -n } else { n };
                        Clear::or_probe(&mut clear[usize::from(back)], pos, side, r2, |wide| {
                            probe(first + j, &point(), back, wide)
                        })
                    };
                    Footprints::new(at, maps)
                });
                for (m, guess) in source.indirect.iter().zip(&mut guesses) {
                    let [f, b] = match &mut footprints {
                        Some(fps) => {
                            let mut at = |back, r2| fps.get(back, r2);
                            m.irradiance_sides_over(pos, n, source.gather, guess, &mut scratch, &mut at)
                        }
                        None => m.irradiance_sides_near(pos, n, source.gather, guess, &mut scratch),
                    };
                    (indirect, back) = (indirect + f, back + b);
                }
                let caustic = source
                    .caustic
                    .iter()
                    .map(|m| m.irradiance(pos, n, source.caustic_gather, &mut scratch))
                    .sum();
                let direct = source.direct.map_or(Vec3::ZERO, |d| d(first + j, &point()));
                (Irradiance { direct, indirect, caustic }, back)
            })
            .collect();
        let largest = raw
            .iter()
            .map(|(e, back)| e.direct.max(e.indirect).max(e.caustic).max(*back).max_element())
            .fold(0.0, f32::max);
        let scale = pack::rgb9e5_scale(largest);
        let values = raw
            .iter()
            .map(|(e, back)| Values {
                direct: pack::rgb9e5_encode(e.direct / scale),
                indirect: pack::rgb9e5_encode(e.indirect / scale),
                caustic: pack::rgb9e5_encode(e.caustic / scale),
                indirect_back: pack::rgb9e5_encode(*back / scale),
            })
            .collect();
        self.estimated.fetch_add(in_block.len() as u64, Ordering::Relaxed);
        self.estimate_ns.fetch_add(start.elapsed().as_nanos() as u64, Ordering::Relaxed);
        Block { scale, values }
    }

    pub fn len(&self) -> usize {
        self.tree.len()
    }

    pub fn is_empty(&self) -> bool {
        self.tree.is_empty()
    }

    /// Memory held: the index, the Morton order, the error bounds kept and the values
    /// estimated so far.
    pub fn bytes(&self) -> usize {
        let estimated = self.estimated.load(Ordering::Relaxed) as usize;
        self.tree.bytes()
            + self.in_tree.len() * std::mem::size_of::<u32>()
            + self.errors.len() * std::mem::size_of::<Vec3>()
            + self.blocks.len() * std::mem::size_of::<OnceLock<Block>>()
            + estimated * std::mem::size_of::<Values>()
    }

    /// The site [`Sites::find_indirect`] finds.
    #[inline]
    fn indirect_site(&self, x: Vec3, ns: Vec3, scratch: &mut LookupScratch) -> Option<u32> {
        self.site(x, |n: Vec3, offset: Vec3| on_surface(n.dot(ns).abs(), offset, ns), scratch)
    }

    /// The nearest site that `accept` takes (by its decoded normal and its offset from `x`) among the [`CANDIDATES`] nearest
    /// to `x` within the largest radius, from the neighbourhood held in `scratch` when it
    /// decides, else by a search (which then gathers the neighbourhood of the region
    /// expected).
    #[inline]
    fn site(&self, x: Vec3, accept: impl Fn(Vec3, Vec3) -> bool, scratch: &mut LookupScratch) -> Option<u32> {
        let parallel = accept;
        let index = match scratch.near.answer(x, CANDIDATES, self.max_radius, &parallel) {
            Known::Answer(index) => index,
            Known::Unknown => {
                let accept = |s: &Site| parallel(s.normal(), s.position() - x);
                let (hint, rejected) = (scratch.last, &mut scratch.rejected);
                let best = self.tree.nearest_among(x, CANDIDATES, self.max_radius, accept, hint, rejected);
                // The sites of the region the query lies in, wide enough that the others in it
                // find their answers inside (if they are about as near as this one's).
                if let Some((centre, radius)) = scratch.region.filter(|&(c, r)| (x - c).length() <= r) {
                    let found = best.map_or(self.max_radius, |b| b.dist2.sqrt());
                    // At most some 50 sites (a region spanning a silhouette would hold many more).
                    scratch.near.gather(&self.tree, centre, (radius + 2.0 * found).min(8.0 * found));
                }
                best.map(|b| b.index)
            }
        };
        scratch.last = index;
        index
    }
}

impl Sites<'_> {
    /// Whether there are no sites.
    pub fn is_empty(&self) -> bool {
        self.cache.is_empty()
    }

    /// The nearest site to `x` whose normal agrees with the unit normal `ns` (within 25
    /// degrees) among the nearest eight; `None` if none is near enough.
    #[inline]
    pub fn find(&self, x: Vec3, ns: Vec3, scratch: &mut LookupScratch) -> Option<SiteRef> {
        let tree = &self.cache.tree;
        let matches = |s: &Site| on_surface(s.normal().dot(ns), s.position() - x, ns);
        let (hint, rejected) = (scratch.last, &mut scratch.rejected);
        let best = tree.nearest_among(x, CANDIDATES, self.cache.max_radius, matches, hint, rejected);
        scratch.last = best.map(|b| b.index);
        best.map(|b| SiteRef(b.index))
    }

    /// The site for the indirect irradiance at `x` on the side of unit normal `ns`: the nearest
    /// lying either way (its normal along `ns` or against it: each site holds both sides'
    /// indirect irradiance) among the nearest eight (`CANDIDATES`); `None` if none is near
    /// enough. Where only one side of a surface gets photons, its other side is still found
    /// (the outside of a room, dark: without it each such camera hit fell back to a full
    /// gather to find zero). Queries that the sites held in `scratch` decide
    /// ([`LookupScratch::expect`]) are answered from them: the same answer, without a search.
    #[inline]
    pub fn find_indirect(&self, x: Vec3, ns: Vec3, scratch: &mut LookupScratch) -> Option<SiteRef> {
        self.cache.indirect_site(x, ns, scratch).map(SiteRef)
    }

    /// The site for the caustic irradiance at `x` on the side of unit normal `ns`: the
    /// nearest whose normal agrees (within 25 degrees) among the nearest eight, or `None` (no
    /// site near enough, or none facing the same way: the far side of a lit wall, a corner),
    /// where the caller gathers: where the sites are sparse the map's photons are too, and
    /// such gathers are few and cheap. Found as the indirect sites are
    /// ([`LookupScratch::expect`]).
    #[inline]
    pub fn find_caustic(&self, x: Vec3, ns: Vec3, scratch: &mut LookupScratch) -> Option<SiteRef> {
        self.cache.site(x, |n: Vec3, offset: Vec3| on_surface(n.dot(ns), offset, ns), scratch).map(SiteRef)
    }

    /// Site `s`'s values, unpacked by `unpack` with its block's scale (the block estimated
    /// first if it has not been).
    #[inline]
    fn values<T>(&self, s: SiteRef, unpack: impl FnOnce(&Values, f32) -> T) -> T {
        let order = self.cache.tree.get(s.0).order as usize;
        let b = order / SITE_BLOCK;
        let block = self.cache.blocks[b].get_or_init(|| self.cache.estimate(b, &self.source));
        unpack(&block.values[order % SITE_BLOCK], block.scale)
    }

    /// The irradiance at site `s`, by kind of path.
    pub fn irradiance(&self, s: SiteRef) -> Irradiance {
        self.values(s, |v, scale| Irradiance {
            direct: pack::rgb9e5_decode(v.direct) * scale,
            indirect: pack::rgb9e5_decode(v.indirect) * scale,
            caustic: pack::rgb9e5_decode(v.caustic) * scale,
        })
    }

    /// The indirect irradiance at site `s` on the side of unit normal `ns`.
    #[inline]
    pub fn indirect(&self, s: SiteRef, ns: Vec3) -> Vec3 {
        let front = self.cache.tree.get(s.0).normal().dot(ns) > 0.0;
        self.values(s, |v, scale| {
            pack::rgb9e5_decode(if front { v.indirect } else { v.indirect_back }) * scale
        })
    }

    /// The caustic irradiance at site `s`.
    #[inline]
    pub fn caustic(&self, s: SiteRef) -> Vec3 {
        self.values(s, |v, scale| pack::rgb9e5_decode(v.caustic) * scale)
    }

    /// [`Sites::find`], then the site's irradiance.
    pub fn lookup(&self, x: Vec3, ns: Vec3, scratch: &mut LookupScratch) -> Option<Irradiance> {
        self.find(x, ns, scratch).map(|s| self.irradiance(s))
    }

    /// [`Sites::find_indirect`], then the site's indirect irradiance on the side of `ns`.
    pub fn lookup_indirect(&self, x: Vec3, ns: Vec3, scratch: &mut LookupScratch) -> Option<Vec3> {
        self.find_indirect(x, ns, scratch).map(|s| self.indirect(s, ns))
    }

    /// [`Sites::find_caustic`], then the site's caustic irradiance.
    pub fn lookup_caustic(&self, x: Vec3, ns: Vec3, scratch: &mut LookupScratch) -> Option<Vec3> {
        self.find_caustic(x, ns, scratch).map(|s| self.caustic(s))
    }

    /// Estimates every block not estimated yet, in parallel.
    pub fn estimate_all(&self) {
        let cache = self.cache;
        cache.blocks.par_iter().enumerate().for_each(|(b, block)| {
            block.get_or_init(|| cache.estimate(b, &self.source));
        });
    }
}

/// Spreads the low 10 bits of `v` to every third bit.
#[inline]
fn spread3(v: u32) -> u32 {
    let mut x = v & 0x3ff;
    x = (x | (x << 16)) & 0x0300_00ff;
    x = (x | (x << 8)) & 0x0300_f00f;
    x = (x | (x << 4)) & 0x030c_30c3;
    (x | (x << 2)) & 0x0924_9249
}

/// Sorts `sites` along a Morton (Z-order) curve over their bounding box, 10 bits per axis;
/// stable, so the order is deterministic.
fn morton_sort(sites: &mut [SitePoint]) {
    let (lo, hi) = sites
        .iter()
        .fold((Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)), |(lo, hi), s| (lo.min(s.pos), hi.max(s.pos)));
    let scale = Vec3::splat(1023.0) / (hi - lo).max(Vec3::splat(f32::MIN_POSITIVE));
    let code = |p: Vec3| {
        let q = ((p - lo) * scale).clamp(Vec3::ZERO, Vec3::splat(1023.0)).as_uvec3();
        spread3(q.x) | (spread3(q.y) << 1) | (spread3(q.z) << 2)
    };
    sites.par_sort_by_cached_key(|s| code(s.pos));
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::Kernel;
    use crate::photon::map::MapColor;
    use crate::photon::map::PhotonHit;

    /// What the tests' sites are estimated from: `indirect` and `caustic` maps, one gather.
    fn source<'m>(
        indirect: &'m [PhotonMap],
        caustic: &'m [PhotonMap],
        params: &'m GatherParams,
        direct: Option<&'m SiteDirect<'m>>,
    ) -> SiteSource<'m> {
        SiteSource { indirect, caustic, gather: params, caustic_gather: params, direct, probe: None }
    }

    #[test]
    fn lookup_returns_the_nearest_site_with_a_matching_normal() {
        // Photons on the floor (normal +Y) and on a wall (normal +X) meeting at the origin.
        let mut hits = Vec::new();
        for i in 0..100 {
            for j in 0..100 {
                let (a, b) = (i as f32 / 100.0, j as f32 / 100.0);
                let power = Vec3::splat(1e-4);
                hits.push(PhotonHit {
                    pos: Vec3::new(a, 0.0, b),
                    err: Vec3::ZERO,
                    n: Vec3::Y,
                    wi: Vec3::Y,
                    power,
                });
                hits.push(PhotonHit {
                    pos: Vec3::new(0.0, a, b),
                    err: Vec3::ZERO,
                    n: Vec3::X,
                    wi: Vec3::X,
                    power,
                });
            }
        }
        let sites = pick_sites(&[Hits::from(hits.clone())], 3);
        let map = PhotonMap::build(hits, MapColor::Rgb, 20000);
        let params = GatherParams { k: 50, max_radius: 0.2, kernel: Kernel::Box, flatten: 8.0 };
        let cache = PrecomputedIrradiance::new(sites, params.max_radius, true);
        let direct = |_: usize, _: &SitePoint| Vec3::X;
        let cache = cache.sites(source(std::slice::from_ref(&map), &[], &params, Some(&direct)));
        let mut scratch = LookupScratch::default();
        // 1e-4 W per photon at 1e4 photons per m^2: E = 1 W/m^2 on each plane.
        let e = cache.lookup(Vec3::new(0.5, 0.0, 0.5), Vec3::Y, &mut scratch).expect("a floor site");
        assert!((e.indirect.x - 1.0).abs() < 0.1, "{e:?}");
        assert_eq!(e.caustic, Vec3::ZERO);
        assert_eq!(e.direct, Vec3::X);
        let e = cache.lookup(Vec3::new(0.0, 0.5, 0.5), Vec3::X, &mut scratch).expect("a wall site");
        assert!((e.indirect.x - 1.0).abs() < 0.1, "{e:?}");
        // Seen from below the floor nothing matches.
        assert!(cache.lookup(Vec3::new(0.5, 0.0, 0.5), -Vec3::Y, &mut scratch).is_none());
    }

    /// Values are estimated as they are first read, a block at a time, and are the same
    /// whichever order, thread or block came first: read one by one in a scrambled order, they
    /// are bit for bit those of every block estimated at once in parallel; the first site read
    /// estimates its own block and no other.
    #[test]
    fn values_estimated_on_demand_are_the_same_in_any_order() {
        use rand::seq::SliceRandom;
        use rand::SeedableRng;
        let hits = crate::photon::map::uniform_floor(20_000, 1.0, 7);
        let map = PhotonMap::build(hits.clone(), MapColor::Rgb, 20_000);
        let params = GatherParams { k: 30, max_radius: 0.1, kernel: Kernel::Cone, flatten: 4.0 };
        let make = || PrecomputedIrradiance::new(pick_sites(&[Hits::from(hits.clone())], 4), 0.1, false);
        let (eager, lazy) = (make(), make());
        let from = source(std::slice::from_ref(&map), &[], &params, None);
        let (all, read) = (eager.sites(from), lazy.sites(from));
        all.estimate_all();
        assert_eq!(eager.estimated().0, eager.len() as u64);
        assert_eq!(lazy.estimated().0, 0);
        let mut order: Vec<u32> = (0..lazy.len() as u32).collect();
        order.shuffle(&mut rand_pcg::Pcg32::seed_from_u64(8));
        read.irradiance(SiteRef(order[0]));
        assert_eq!(lazy.estimated().0, SITE_BLOCK as u64);
        for &i in &order {
            let s = SiteRef(i);
            assert_eq!(read.irradiance(s), all.irradiance(s), "site {i}");
            for ns in [Vec3::Y, -Vec3::Y] {
                assert_eq!(
                    read.indirect(s, ns).to_array().map(f32::to_bits),
                    all.indirect(s, ns).to_array().map(f32::to_bits)
                );
            }
        }
        assert!(all.irradiance(SiteRef(order[0])).indirect.x > 0.0);
        assert_eq!(lazy.estimated().0, lazy.len() as u64);
    }

    /// A square of `side` in `y = 0` from the origin, lit on the side of `n` (±Y): 100 × 100
    /// photons on a grid, 1e-4 W each, arriving along `n`.
    fn lit_square(side: f32, n: Vec3) -> Vec<PhotonHit> {
        (0..100)
            .flat_map(|i| {
                (0..100).map(move |j| PhotonHit {
                    pos: Vec3::new(i as f32, 0.0, j as f32) * (side / 100.0),
                    err: Vec3::ZERO,
                    n,
                    wi: n,
                    power: Vec3::splat(1e-4),
                })
            })
            .collect()
    }

    /// Caustic sites: a lit floor reads its nearest site's value, the floor seen from below
    /// or a point farther than the largest radius from every site reads `None` (the caller
    /// gathers); with a neighbourhood held or not, the same answers.
    #[test]
    fn caustic_sites_answer_on_the_lit_side_only() {
        // A lit square of floor, 1e-4 W a photon at 1e4 photons per m^2: E = 1 W/m^2.
        let hits = lit_square(1.0, Vec3::Y);
        // Sites between the photons (independent of them, as the renderer's are).
        let between = |h: &PhotonHit| PhotonHit { pos: h.pos + Vec3::new(0.005, 0.0, 0.005), ..*h };
        let sites = pick_sites(&[Hits::from(hits.iter().map(between).collect::<Vec<_>>())], 1);
        let map = PhotonMap::build(hits, MapColor::Rgb, 10_000);
        let params = GatherParams { k: 30, max_radius: 0.1, kernel: Kernel::Cone, flatten: 8.0 };
        let cache = PrecomputedIrradiance::new(sites, params.max_radius, false);
        assert_eq!(cache.len(), 10_000);
        let cache = cache.sites(source(&[], std::slice::from_ref(&map), &params, None));
        for held in [false, true] {
            let mut scratch = LookupScratch::default();
            let mut at = |x: Vec3, ns: Vec3| {
                if held {
                    scratch.expect(x, 0.01);
                }
                cache.lookup_caustic(x, ns, &mut scratch)
            };
            let e = at(Vec3::new(0.503, 0.0, 0.497), Vec3::Y).expect("a site");
            assert!((e.x - 1.0).abs() < 0.15, "{e}");
            assert_eq!(at(Vec3::new(0.503, 0.0, 0.497), -Vec3::Y), None);
            assert_eq!(at(Vec3::new(1.5, 0.0, 0.5), Vec3::Y), None);
            // Just within the largest radius of the edge's sites: a site answers.
            assert!(at(Vec3::new(1.05, 0.0, 0.5), Vec3::Y).is_some());
        }
    }

    /// A lookup keeps to the query's own surface: a ceiling 2.4 cm above a lit square facing
    /// it the same way (the inside of a closed lamp's top, facing down like the ceiling) finds
    /// none of the square's sites, with a neighbourhood held or not, though they lie within the
    /// largest radius and their normals agree; the square's own points find them.
    #[test]
    fn a_lookup_keeps_to_the_querys_own_surface() {
        let hits = lit_square(0.1, Vec3::NEG_Y);
        let sites = pick_sites(&[Hits::from(hits.clone())], 4);
        let map = PhotonMap::build(hits, MapColor::Rgb, 10_000);
        let params = GatherParams { k: 30, max_radius: 0.1, kernel: Kernel::Cone, flatten: 2.0 };
        let maps = std::slice::from_ref(&map);
        let cache = PrecomputedIrradiance::new(sites, params.max_radius, false);
        let cache = cache.sites(source(maps, maps, &params, None));
        for held in [false, true] {
            let mut scratch = LookupScratch::default();
            for x in
                [Vec3::new(0.05, 0.024, 0.05), Vec3::new(0.12, 0.024, 0.03), Vec3::new(0.05, -0.024, 0.05)]
            {
                if held {
                    scratch.expect(x, 0.01);
                }
                assert_eq!(cache.lookup_indirect(x, Vec3::NEG_Y, &mut scratch), None, "{x}, held {held}");
                assert_eq!(cache.lookup_caustic(x, Vec3::NEG_Y, &mut scratch), None, "{x}, held {held}");
                assert!(cache.lookup(x, Vec3::NEG_Y, &mut scratch).is_none(), "{x}, held {held}");
            }
            let on = Vec3::new(0.05, 0.0, 0.05);
            assert!(cache.lookup_indirect(on, Vec3::NEG_Y, &mut scratch).is_some_and(|e| e.y > 0.0));
            assert!(cache.lookup_caustic(on, Vec3::NEG_Y, &mut scratch).is_some());
        }
    }

    /// On a uniform density (Poisson photons on a plane) the lookups keep the mean of the
    /// gathers they replace, with sites independent of the map's photons (as the renderer
    /// traces them: `integrator::maps`). Sites at the map's own photons were off by the sum of
    /// two opposite effects: each site's estimate counted its own photon at the kernel's
    /// centre (+3 / (k - 1) = +3 % with the cone), and a site where photons happened to be
    /// sparse read low and was read over a larger cell (about -2 %): +1.0 % in all, with the
    /// cone (lookups +0.12 % against gathers +0.09 % now). (`cargo test --release --lib
    /// precomputed_irradiance_keeps -- --nocapture` prints the means.)
    #[test]
    fn precomputed_irradiance_keeps_the_gathers_mean() {
        use rand::{Rng, SeedableRng};
        let (n, side) = (400_000, 10.0f32);
        let hits = crate::photon::map::uniform_floor(n, side, 5);
        let mut rng = rand_pcg::Pcg64::seed_from_u64(6);
        let sites = pick_sites(&[Hits::from(crate::photon::map::uniform_floor(n / 4, side, 7))], 1);
        let map = PhotonMap::build(hits, MapColor::Rgb, n as u64);
        let params = GatherParams { k: 100, max_radius: 1.0, kernel: Kernel::Cone, flatten: 4.0 };
        let cache = PrecomputedIrradiance::new(sites, params.max_radius, false);
        let cache = cache.sites(source(std::slice::from_ref(&map), &[], &params, None));
        let (mut scratch, mut kept) = (Vec::new(), LookupScratch::default());
        let (mut gathered, mut read) = (0.0f64, 0.0f64);
        let queries = 20_000;
        for _ in 0..queries {
            let x = Vec3::new(1.0 + 8.0 * rng.gen::<f32>(), 0.0, 1.0 + 8.0 * rng.gen::<f32>());
            gathered += map.irradiance(x, Vec3::Y, &params, &mut scratch).x as f64;
            read += cache.lookup_indirect(x, Vec3::Y, &mut kept).expect("a site").x as f64;
        }
        let expect = queries as f64 / (side * side) as f64;
        let (g, c) = (gathered / expect - 1.0, read / expect - 1.0);
        eprintln!(
            "mean against the exact irradiance: gathers {:+.2} %, lookups {:+.2} %",
            100.0 * g,
            100.0 * c
        );
        assert!(g.abs() < 0.01, "gathers {g:+.4}");
        assert!((c - g).abs() < 0.005, "lookups {c:+.4} against gathers {g:+.4}");
    }

    /// Lookups answered from a neighbourhood give what a search from scratch gives, on a corner
    /// of three walls (sites of three orientations, some queries on the far side), for pixels
    /// of any size, with photons far from the origin too.
    #[test]
    fn neighbourhoods_answer_as_the_search_does() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_pcg::Pcg32::seed_from_u64(3);
        for offset in [Vec3::ZERO, Vec3::new(3e3, -2e3, 1e3)] {
            let normals = [Vec3::X, Vec3::Y, Vec3::Z];
            let on_wall = |rng: &mut rand_pcg::Pcg32, w: usize| {
                let mut p = Vec3::new(rng.gen(), rng.gen(), rng.gen());
                p[w] = 0.0;
                p + offset
            };
            let hits: Vec<PhotonHit> = (0..30000)
                .map(|i| {
                    let w = i % 3;
                    let n = normals[w];
                    PhotonHit {
                        pos: on_wall(&mut rng, w),
                        err: Vec3::ZERO,
                        n,
                        wi: n,
                        power: Vec3::splat(1e-4),
                    }
                })
                .collect();
            let sites = pick_sites(&[Hits::from(hits)], 4);
            let params = GatherParams { k: 20, max_radius: 0.05, kernel: Kernel::Box, flatten: 8.0 };
            let cache = PrecomputedIrradiance::new(sites, params.max_radius, false);
            let mut kept = LookupScratch::default();
            let (mut answered, mut total) = (0, 0);
            for pixel in [0.002f32, 0.01, 0.05, 0.3] {
                for _ in 0..300 {
                    let w = rng.gen_range(0..3);
                    let centre = on_wall(&mut rng, w);
                    kept.expect(centre, pixel);
                    for _ in 0..16 {
                        let mut x = centre + pixel * (Vec3::new(rng.gen(), rng.gen(), rng.gen()) - 0.5);
                        x[w] = offset[w];
                        let ns = if rng.gen_bool(0.2) { -normals[w] } else { normals[w] };
                        let before = kept.near.radius > 0.0
                            && kept.near.answer(x, CANDIDATES, 0.05, |_, _| true) != Known::Unknown;
                        let got = cache.indirect_site(x, ns, &mut kept);
                        let want = cache.indirect_site(x, ns, &mut LookupScratch::default());
                        // The same site, or (far from the origin, where coordinates are coarse)
                        // one at exactly the same distance: ties are broken arbitrarily.
                        let d2 =
                            |i: Option<u32>| i.map(|i| (cache.tree.get(i).position() - x).length_squared());
                        assert!(got == want || d2(got) == d2(want), "at {x} facing {ns}, pixel {pixel}");
                        answered += before as u32;
                        total += 1;
                    }
                }
            }
            // The neighbourhoods did answer most of them.
            assert!(answered * 2 > total, "{answered} of {total}");
        }
    }
}
