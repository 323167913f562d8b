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
    pub stages: Vec<Stage>,
    pub photons: BTreeMap<String, MapStats>,
    pub rays: RayCounts,
    pub rays_per_second: f64,
    pub photons_traced_per_second: f64,
    pub gather_queries: u64,
    pub gather_queries_per_second: f64,
    pub nonfinite_samples: u64,
    pub wall_seconds: f64,
    /// Peak resident memory of the process (Linux `VmHWM`), 0 where unknown.
    pub peak_memory_bytes: u64,
}

/// The process's peak resident set size from `/proc/self/status` (Linux), if available.
pub fn peak_memory_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

impl Stats {
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

    /// Seconds spent in the stage `name` (0 if it did not run).
    pub fn seconds(&self, name: &str) -> f64 {
        self.stages.iter().filter(|s| s.name == name).map(|s| s.seconds).sum()
    }
}
