//! The frame of a render: what the photon pass and every integrator stand on. The scene, its
//! accelerator and its lights ([`Frame`]); the surface point a ray reaches ([`SurfaceHit`]);
//! the camera's samples ([`camera`]); the walk through mirrors and glass ([`specular`]); direct
//! light by shadow rays ([`direct`]); per-thread counters ([`Counters`]) and progress reports
//! ([`Progress`]).

pub mod camera;
pub mod direct;
pub mod hit;
pub mod specular;

pub use hit::SurfaceHit;

use crate::accel::{Accel, Hit};
use crate::geometry::Ray;
use crate::light::LightSet;
use crate::scene::{Camera, Scene};
use crate::stats::RayCounts;

/// What every stage of a render reads, shared by all threads.
pub struct Frame<'a, A: Accel> {
    pub scene: &'a Scene,
    pub accel: &'a A,
    pub lights: &'a LightSet,
    /// The camera of the image being rendered, at the render's resolution.
    pub camera: Camera,
    /// Every view the photon stages serve: all the images a batch renders from the same photon
    /// maps (the guide's pilot looks through them, and a portal's inside is the side of the
    /// first one's eye); for one image, its camera alone. Never empty.
    pub views: &'a [Camera],
}

impl<'a, A: Accel> Frame<'a, A> {
    /// Closest surface along `ray`, with a usable normal (degenerate triangles are skipped as
    /// misses, which they are for every backend).
    #[inline]
    pub fn trace(&self, ray: &Ray, c: &mut Counters) -> Option<SurfaceHit> {
        self.surface(c.timed(Part::Rays, || self.accel.intersect(ray))?)
    }

    /// The surface point of a backend's hit (`None` on a degenerate triangle).
    #[inline]
    pub fn surface(&self, hit: Hit) -> Option<SurfaceHit> {
        SurfaceHit::new(self.scene, hit)
    }
}

/// Per-thread counters, summed at the end (no atomics in hot loops).
#[derive(Clone, Copy, Debug, Default)]
pub struct Counters {
    pub rays: RayCounts,
    /// Photon-map (and precomputed-irradiance) lookups.
    pub queries: u64,
    /// Camera samples whose radiance was NaN or infinite (dropped).
    pub nonfinite: u64,
    /// Where the per-pixel loops' time goes.
    pub clock: Clock,
}

impl std::ops::AddAssign for Counters {
    fn add_assign(&mut self, o: Counters) {
        self.rays += o.rays;
        self.queries += o.queries;
        self.nonfinite += o.nonfinite;
        self.clock += o.clock;
    }
}

/// The parts of the per-pixel work that [`Counters::timed`] tells apart.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Part {
    /// Calls into the ray caster.
    Rays,
    /// Photon-map gathers and precomputed-irradiance lookups.
    Gathers,
}

/// One call in this many is timed by [`Counters::timed`] (a power of two); its time, times
/// this, estimates the time of all the calls. An unbiased estimate at a cost of about
/// 2 ns a call where timing each call would cost some 25 ns.
const CLOCK_STRIDE: u32 = 16;

/// Thread time (nanoseconds, summed over threads) inside the per-pixel loops
/// ([`camera::for_each_pixel`]), all of it measured, and the parts of it spent casting rays
/// and gathering, estimated from a random sample of the calls.
#[derive(Clone, Copy, Debug, Default)]
pub struct Clock {
    /// xorshift32 state choosing the calls timed (0: not yet seeded).
    state: u32,
    pub pixels_ns: u64,
    pub rays_ns: u64,
    pub gathers_ns: u64,
    /// Of `pixels_ns`, the time estimating precomputed irradiance as lookups first read it
    /// (measured, not sampled: set by the integrator after its camera pass).
    pub estimate_ns: u64,
    /// The rays that estimate cast (its probes), counted with the camera stage's.
    pub estimate_rays: u64,
}

impl std::ops::AddAssign for Clock {
    fn add_assign(&mut self, o: Clock) {
        self.pixels_ns += o.pixels_ns;
        self.rays_ns += o.rays_ns;
        self.gathers_ns += o.gathers_ns;
        self.estimate_ns += o.estimate_ns;
        self.estimate_rays += o.estimate_rays;
    }
}

impl Counters {
    /// Runs `f`, a call of kind `part`, timing it one time in `CLOCK_STRIDE` (16, chosen at
    /// random, so no periodic pattern of calls can bias the estimate).
    #[inline(always)]
    pub fn timed<T>(&mut self, part: Part, f: impl FnOnce() -> T) -> T {
        let mut x = if self.clock.state == 0 { 0x9E37_79B9 } else { self.clock.state };
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        self.clock.state = x;
        if x & (CLOCK_STRIDE - 1) != 0 {
            return f();
        }
        let start = std::time::Instant::now();
        let out = f();
        let elapsed = start.elapsed().as_nanos() as u64;
        let ns = elapsed.saturating_sub(clock_overhead_ns()) * CLOCK_STRIDE as u64;
        match part {
            Part::Rays => self.clock.rays_ns += ns,
            Part::Gathers => self.clock.gathers_ns += ns,
        }
        out
    }
}

/// What the clock adds to a timed interval (the tail of one reading and the head of the next),
/// in nanoseconds: the median of empty intervals, measured once a process. On this project's
/// machines it is some 24 ns, a fifth of a gather or a shadow ray: left in, it overstated their
/// shares of the camera stage by as much.
fn clock_overhead_ns() -> u64 {
    static OVERHEAD: std::sync::OnceLock<u64> = std::sync::OnceLock::new();
    *OVERHEAD.get_or_init(|| {
        let mut empty: Vec<u64> = (0..1001)
            .map(|_| {
                let start = std::time::Instant::now();
                start.elapsed().as_nanos() as u64
            })
            .collect();
        empty.sort_unstable();
        empty[empty.len() / 2]
    })
}

/// Reports progress of long stages (a no-op implementation is fine).
pub trait Progress: Sync {
    /// A stage of `total` units begins.
    fn start(&self, _stage: &str, _total: u64) {}
    /// `n` more units are done.
    fn advance(&self, _n: u64) {}
    /// What the stage has done so far, in words (`12 passes, 1.2M photons`), shown by its bar.
    fn message(&self, _text: &str) {}
    /// The stage is over.
    fn finish(&self) {}
}

/// Progress that reports nothing.
pub struct Quiet;
impl Progress for Quiet {}

#[cfg(test)]
mod tests {
    use super::*;

    /// Timing calls that do nothing adds up to almost nothing: the clock's own cost (some 24 ns
    /// an interval) is not counted as the calls'. The least of five trials, so that a trial the
    /// machine interrupts does not decide.
    #[test]
    fn timing_leaves_out_the_clocks_own_cost() {
        let calls = 64_000;
        let per_call = (0..5)
            .map(|_| {
                let mut c = Counters::default();
                for _ in 0..calls {
                    c.timed(Part::Gathers, || std::hint::black_box(()));
                }
                c.clock.gathers_ns as f64 / calls as f64
            })
            .fold(f64::INFINITY, f64::min);
        assert!(
            per_call < 8.0,
            "{per_call} ns counted for an empty call, overhead {} ns",
            clock_overhead_ns()
        );
    }
}
