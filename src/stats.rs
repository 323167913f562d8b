//! What a render did, for `--stats`: every stage with whether it ran (and why, or why not) and
//! its time, photons per map, rays per kind, and non-finite samples.

use serde::Serialize;
use std::collections::BTreeMap;
use std::time::Instant;

/// One stage of the pipeline.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Stage {
    pub name: String,
    pub ran: bool,
    pub reason: String,
    pub seconds: f64,
}

/// Photons of one map.
#[derive(Clone, Debug, Default, Serialize, PartialEq)]
pub struct MapStats {
    pub emitted: u64,
    pub stored: u64,
    /// Photons stored where the camera looks ([`crate::photon::guide::VisibleRegion`]).
    pub seen: u64,
    /// `seen / emitted`: the share of the photons emitted that the image can use.
    pub efficiency: f64,
    pub bytes: u64,
}

/// Rays cast, by kind.
#[derive(Clone, Copy, Debug, Default, Serialize, PartialEq, Eq)]
pub struct RayCounts {
    pub camera: u64,
    pub shadow: u64,
    pub photon: u64,
    pub gather: u64,
    pub specular: u64,
    /// Continuation rays of the path tracer (`--integrator path`).
    pub path: u64,
}

impl std::ops::AddAssign for RayCounts {
    fn add_assign(&mut self, o: RayCounts) {
        self.camera += o.camera;
        self.shadow += o.shadow;
        self.photon += o.photon;
        self.gather += o.gather;
        self.specular += o.specular;
        self.path += o.path;
    }
}

impl RayCounts {
    pub fn total(&self) -> u64 {
        self.camera + self.shadow + self.photon + self.gather + self.specular + self.path
    }
}

/// Whether the stage `name` casts rays: the photon stages (guide, maps, sites, portals), the
/// openings' search, pass-indexed progressive photon mapping's pilot and the camera stage; not
/// loading, building trees or the accelerator, or the irradiance stage.
pub fn casts_rays(name: &str) -> bool {
    name == "camera" || name == "pilot" || name.starts_with("photons.") || name.starts_with("portals.")
}

/// The report written by `--stats`.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Stats {
    pub scene: String,
    pub accel: String,
    pub threads: usize,
    pub width: u32,
    pub height: u32,
    /// Passes rendered (progressive modes; 1 otherwise).
    pub passes: u32,
    /// Whether a stop request (Ctrl-C) ended the render early.
    pub cancelled: bool,
    /// The image's error estimated from the spread of its passes (and the probed bias of the
    /// photon estimate): `None` with one pass, or with sppm, whose passes are not independent.
    pub error_estimate: Option<crate::film::sums::ErrorEstimate>,
    pub stages: Vec<Stage>,
    /// Each photon map's record, and the precomputed irradiance's sites' ([`SITE_RECORDS`]).
    pub photons: BTreeMap<String, MapStats>,
    pub rays: RayCounts,
    /// [`Stats::traced_rays`] over the time of the stages that cast them ([`casts_rays`]), the
    /// estimate of the precomputed irradiance left out.
    pub rays_per_second: f64,
    pub photons_traced_per_second: f64,
    pub gather_queries: u64,
    pub gather_queries_per_second: f64,
    pub nonfinite_samples: u64,
    pub wall_seconds: f64,
    /// Peak resident memory of the process (Linux `VmHWM`), 0 where unknown.
    pub peak_memory_bytes: u64,
    /// The accelerator alone on rays like the render's, same threads, measured after the
    /// render (only when asked for: `--stats`, `photonmap bench`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub raw_rays: Option<RawRays>,
    /// What the render left out that the image would otherwise show (printed by the command
    /// too), once each.
    pub warnings: Vec<String>,
    /// The raw rates weighted by the render's mix of rays (rays/s), 0 when not measured.
    pub raw_rays_per_second: f64,
    /// `rays_per_second / raw_rays_per_second`: the share of the time of the stages that cast
    /// rays ([`casts_rays`]) that is ray casting (1 would mean nothing else costs anything; the
    /// precomputed irradiance's estimation is left out of that time wherever it runs, and its
    /// probe rays out of the count); 0 when not measured.
    pub rays_to_raw_ratio: f64,
    /// The rays `rays_per_second` counts: those of the stages [`casts_rays`] names, but for the
    /// precomputed irradiance's probes (their time is the estimate's, left out).
    #[serde(skip)]
    pub traced_rays: RayCounts,
    /// Where the camera stage's time went.
    pub camera_time: CameraTime,
    /// How much pass-indexed progressive photon mapping widened its first radii (its pilot's
    /// choice; `None` with other integrators).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub widening: Option<Widening>,
    /// The photons and camera samples pass-indexed progressive photon mapping's pilot chose for
    /// each pass (`None` where it chose neither: other integrators, `--spp` and `--photons`
    /// given, short renders).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pass_plan: Option<PassPlan>,
}

/// The pilot's choice of the photons and camera samples of every pass
/// (`src/integrator/balance.rs`).
#[derive(Clone, Copy, Debug, Default, Serialize, PartialEq)]
pub struct PassPlan {
    /// Camera samples per pixel in each pass.
    pub spp: u32,
    /// Photons each pass emits for its indirect map.
    pub photons: u64,
    /// Photons each pass aims at specular objects for its caustic map.
    pub caustic_photons: u64,
    /// The camera samples' share of a pass's estimated variance at that many samples.
    pub camera_share: f64,
    /// The price of a pass's photon term in camera samples over the image.
    pub fixed_in_samples: f64,
}

/// What the pilot of pass-indexed progressive photon mapping made of the first radii
/// (`src/integrator/bandwidth.rs`).
#[derive(Clone, Copy, Debug, Default, Serialize, PartialEq)]
pub struct Widening {
    /// The pixels whose visible point the pilot measured.
    pub pixels: u64,
    /// The mean factor their first radius was widened by, in `[1, 2]`.
    pub mean: f64,
    /// The share of them widened fully (2×).
    pub widest: f64,
}

/// The records of [`Stats::photons`] that hold precomputed-irradiance sites, not photons:
/// `stored` sites, `seen` of them estimated (those the camera read), no photon emitted.
pub const SITE_RECORDS: [&str; 2] = [IRRADIANCE_SITES, CAUSTIC_SITES];

/// The record of the indirect precomputed irradiance's sites.
pub const IRRADIANCE_SITES: &str = "irradiance_cache";

/// The record of the caustic sites.
pub const CAUSTIC_SITES: &str = "caustic_cache";

/// The camera stage's thread time (the per-pixel loops, summed over threads) and its shares:
/// ray casting, photon gathers and irradiance lookups, estimating the precomputed irradiance
/// that the lookups read first, and the rest (sampling, shading, light choice). The shares of
/// rays and gathers come from a random one in 16 of the calls timed, the estimates' is
/// measured; they sum to 1.
#[derive(Clone, Copy, Debug, Default, Serialize, PartialEq)]
pub struct CameraTime {
    pub thread_seconds: f64,
    pub rays_share: f64,
    pub gathers_share: f64,
    pub estimate_share: f64,
    pub rest_share: f64,
}

impl CameraTime {
    /// From the nanoseconds measured: all of the per-pixel loops, the parts in ray casting and
    /// gathering (estimated) and in estimating precomputed irradiance (measured), clamped so
    /// that no share is negative: the sampled parts are estimates, the whole is measured.
    pub fn new(pixels_ns: u64, rays_ns: u64, gathers_ns: u64, estimate_ns: u64) -> Self {
        if pixels_ns == 0 {
            return CameraTime::default();
        }
        let whole = pixels_ns as f64;
        let estimate = (estimate_ns as f64 / whole).min(1.0);
        let rays = (rays_ns as f64 / whole).min(1.0 - estimate);
        let gathers = (gathers_ns as f64 / whole).min(1.0 - estimate - rays);
        CameraTime {
            thread_seconds: whole * 1e-9,
            rays_share: rays,
            gathers_share: gathers,
            estimate_share: estimate,
            rest_share: 1.0 - rays - gathers - estimate,
        }
    }
}

/// Ray rates of the accelerator alone, by kind of ray (rays/s), from [`crate::tools::bench::raw_rays`].
#[derive(Clone, Copy, Debug, Default, Serialize, PartialEq)]
pub struct RawRays {
    /// The scene's camera rays, one batch per pixel as the camera pass traces them.
    pub camera: f64,
    /// Closest hits of rays leaving surface points over the hemisphere (photon, gather and
    /// specular rays are of this kind).
    pub incoherent: f64,
    /// Occlusion of segments between surface points.
    pub shadow: f64,
    /// Rays of each kind cast.
    pub rays_per_kind: u64,
    /// Time of the whole measurement, ray generation included.
    pub seconds: f64,
}

impl RawRays {
    /// The rate of the accelerator alone on the mix of `rays`: camera rays at the camera rate,
    /// shadow rays at the shadow rate, the rest at the incoherent rate (0 without rays).
    pub fn mixed_rate(&self, rays: &RayCounts) -> f64 {
        let incoherent = rays.total() - rays.camera - rays.shadow;
        let time = |n: u64, rate: f64| if n == 0 { 0.0 } else { n as f64 / rate };
        let t = time(rays.camera, self.camera)
            + time(rays.shadow, self.shadow)
            + time(incoherent, self.incoherent);
        if t > 0.0 && t.is_finite() {
            rays.total() as f64 / t
        } else {
            0.0
        }
    }
}

/// The process's peak resident set size from `/proc/self/status` (Linux), if available.
pub fn peak_memory_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

impl Stats {
    /// Records a warning (a repeat of one already recorded is dropped: passes repeat stages).
    pub fn warn(&mut self, message: impl Into<String>) {
        let message = message.into();
        if !self.warnings.contains(&message) {
            self.warnings.push(message);
        }
    }

    /// Records a stage that was skipped, with the reason.
    pub fn skip(&mut self, name: &str, reason: impl Into<String>) {
        self.stages.push(Stage { name: name.into(), ran: false, reason: reason.into(), seconds: 0.0 });
    }

    /// Runs `f` as a stage, recording its time.
    pub fn run<T>(&mut self, name: &str, reason: impl Into<String>, f: impl FnOnce(&mut Self) -> T) -> T {
        let start = Instant::now();
        let out = f(self);
        let seconds = start.elapsed().as_secs_f64();
        self.stages.push(Stage { name: name.into(), ran: true, reason: reason.into(), seconds });
        out
    }

    /// Folds stages that ran once per pass into one entry each, in first-run order, with
    /// their times summed.
    pub fn merge_repeated_stages(&mut self) {
        let mut merged: Vec<Stage> = Vec::new();
        for s in self.stages.drain(..) {
            match merged.iter_mut().find(|m| m.name == s.name && m.ran == s.ran) {
                Some(m) => m.seconds += s.seconds,
                None => merged.push(s),
            }
        }
        self.stages = merged;
    }

    /// Records the raw ray rates and the render's ratio to them.
    pub fn set_raw_rays(&mut self, raw: RawRays) {
        self.raw_rays = Some(raw);
        self.raw_rays_per_second = raw.mixed_rate(&self.traced_rays);
        self.rays_to_raw_ratio = if self.raw_rays_per_second > 0.0 {
            self.rays_per_second / self.raw_rays_per_second
        } else {
            0.0
        };
    }

    /// Seconds spent in the stages that cast rays ([`casts_rays`]).
    pub fn tracing_seconds(&self) -> f64 {
        self.stages.iter().filter(|s| casts_rays(&s.name)).map(|s| s.seconds).sum()
    }

    /// Seconds spent in the stage `name` (0 if it did not run).
    pub fn seconds(&self, name: &str) -> f64 {
        self.stages.iter().filter(|s| s.name == name).map(|s| s.seconds).sum()
    }
}
