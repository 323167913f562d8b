//! Render settings: the `[render]` table of a scene file, overridden by command-line flags, then
//! resolved into a complete, validated [`RenderConfig`].

use crate::accel::AccelKind;
use serde::{Deserialize, Serialize};

/// How indirect diffuse light is computed at camera hits.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum IndirectMode {
    /// The indirect map's radiance estimate read directly at the hit.
    Estimate,
    /// Jensen's final gathering: hemisphere rays, each reading the maps where it lands.
    FinalGather,
}

/// What a photon carries.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum ColorMode {
    /// The lecture's three maps: each photon carries one colour channel.
    PerChannel,
    /// One map of photons carrying RGB power.
    Rgb,
}

/// Density-estimation kernel of the radiance estimate.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Kernel {
    Box,
    Cone,
    Gaussian,
}

/// Which part of the light a render shows (the lecture's sum, term by term).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, Serialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Component {
    /// Everything: the image.
    #[default]
    All,
    /// Emitters seen directly or through mirrors and glass.
    Emitted,
    /// Direct light from shadow rays.
    Direct,
    /// The caustic map's estimate.
    Caustic,
    /// The indirect map's estimate (or the final gather).
    Indirect,
}

impl Component {
    /// Whether a render of `self` includes the term `c`.
    #[inline]
    pub fn shows(self, c: Component) -> bool {
        self == Component::All || self == c
    }
}

/// Which estimator renders the image.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, Serialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Integrator {
    /// Jensen's two-pass photon mapping (the renderer proper).
    #[default]
    Photon,
    /// An independent unidirectional path tracer with next-event estimation and MIS, sharing
    /// only the scene, materials, lights and accelerator: a cross-check of the photon mapper.
    Path,
    /// Stochastic progressive photon mapping (Hachisuka & Jensen 2009): passes of photons with
    /// a per-pixel radius that shrinks, so the error goes to zero as passes are added.
    Sppm,
}

/// Whether the caustic photon pass runs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize, Serialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum CausticPass {
    /// When the scene analysis says caustics are possible (mirrors or glass, something diffuse
    /// to receive them, a light with power) and the render shows them.
    #[default]
    Auto,
    /// Always, even when the analysis would skip it (to measure what skipping saves).
    On,
    /// Never: the image has no caustics from the caustic map.
    Off,
}

/// Optional settings as written in `[render]` (or given on the command line). `None` means
/// "use the default".
#[derive(Clone, Debug, Default, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RenderSettings {
    pub accel: Option<AccelKind>,
    pub photons: Option<u64>,
    pub caustic_photons: Option<u64>,
    pub spp: Option<u32>,
    pub seed: Option<u64>,
    pub max_bounces: Option<u32>,
    pub max_depth: Option<u32>,
    pub gather_photons: Option<u32>,
    pub gather_radius: Option<f32>,
    pub caustic_gather_photons: Option<u32>,
    pub caustic_gather_radius: Option<f32>,
    pub indirect: Option<IndirectMode>,
    pub final_gather_rays: Option<u32>,
    pub color: Option<ColorMode>,
    pub kernel: Option<Kernel>,
    pub light_samples: Option<u32>,
    pub robust: Option<bool>,
    pub irradiance_cache: Option<bool>,
    pub component: Option<Component>,
    pub integrator: Option<Integrator>,
    pub passes: Option<u32>,
    pub time: Option<f64>,
    pub alpha: Option<f32>,
    pub caustic_aim: Option<bool>,
    pub caustic_pass: Option<CausticPass>,
}

impl RenderSettings {
    /// `self` with every field that `over` sets replaced.
    pub fn overridden_by(&self, over: &RenderSettings) -> RenderSettings {
        macro_rules! pick {
            ($($f:ident),*) => { RenderSettings { $($f: over.$f.or(self.$f)),* } };
        }
        pick!(
            accel,
            photons,
            caustic_photons,
            spp,
            seed,
            max_bounces,
            max_depth,
            gather_photons,
            gather_radius,
            caustic_gather_photons,
            caustic_gather_radius,
            indirect,
            final_gather_rays,
            color,
            kernel,
            light_samples,
            robust,
            irradiance_cache,
            component,
            integrator,
            passes,
            time,
            alpha,
            caustic_aim,
            caustic_pass
        )
    }
}

/// A complete, validated set of render settings.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RenderConfig {
    pub accel: AccelKind,
    pub robust: bool,
    pub width: u32,
    pub height: u32,
    /// Photons emitted for the indirect map (all channels together).
    pub photons: u64,
    /// Photons emitted toward specular objects for the caustic map.
    pub caustic_photons: u64,
    pub spp: u32,
    pub seed: u64,
    /// Longest photon path (bounces after emission).
    pub max_bounces: u32,
    /// Longest camera path through mirrors and glass; with the path tracer, the longest path
    /// of any kind (bounces after the camera ray).
    pub max_depth: u32,
    pub gather_photons: u32,
    /// `None`: chosen from the scene size.
    pub gather_radius: Option<f32>,
    pub caustic_gather_photons: u32,
    pub caustic_gather_radius: Option<f32>,
    pub indirect: IndirectMode,
    pub final_gather_rays: u32,
    pub color: ColorMode,
    pub kernel: Kernel,
    pub light_samples: u32,
    /// Precompute irradiance at photon positions for diffuse lookups (Christensen 1999).
    pub irradiance_cache: bool,
    /// Which term of the sum is shown (photon mapper only).
    pub component: Component,
    /// Photon mapping, the path tracer or progressive photon mapping.
    pub integrator: Integrator,
    /// Passes to render and average (progressive photon mapping refines its radii between
    /// them); `None`: one pass, or as many as `time` allows.
    pub passes: Option<u32>,
    /// Time budget in seconds: no pass starts that would end after it (the first always runs).
    pub time: Option<f64>,
    /// Progressive photon mapping: the fraction of new photons kept at each radius update
    /// (Hachisuka & Jensen's alpha, in (0, 1)).
    pub alpha: f32,
    /// Aim caustic photons at the bounding spheres of the specular objects (a projection map);
    /// `false`: emit them from the lights as usual and keep only light → specular+ → diffuse
    /// paths.
    pub caustic_aim: bool,
    /// Whether the caustic pass runs: as the scene analysis decides, always, or never.
    pub caustic_pass: CausticPass,
}

/// Progressive photon mapping's defaults: photons per pass (indirect and caustic), camera
/// samples per pixel per pass, and passes when no time budget is given.
pub const SPPM_PHOTONS: u64 = 100_000;
pub const SPPM_CAUSTIC_PHOTONS: u64 = 30_000;
pub const SPPM_SPP: u32 = 4;
pub const SPPM_PASSES: u32 = 64;
/// Progressive photon mapping's first radius reaches this many photons (fewer than the
/// two-pass estimate's 100: the radius only shrinks from there, so a small start means less
/// early bias and cheaper range queries).
pub const SPPM_GATHER_PHOTONS: u32 = 30;

/// Bytes one stored photon costs, tree included; used to refuse absurd budgets up front.
pub const BYTES_PER_PHOTON: u64 = 20;
/// Photon budgets above this are refused (10^9 photons would need about 20 GB).
pub const MAX_PHOTONS: u64 = 500_000_000;

/// A setting that cannot be honoured.
#[derive(Debug, thiserror::Error)]
#[error("{field}: {message}")]
pub struct ConfigError {
    pub field: &'static str,
    pub message: String,
}

fn bad(field: &'static str, message: impl Into<String>) -> ConfigError {
    ConfigError { field, message: message.into() }
}

impl RenderSettings {
    /// Fills defaults and validates. `width`/`height` come from the camera unless overridden.
    pub fn resolve(&self, width: u32, height: u32) -> Result<RenderConfig, ConfigError> {
        let integrator = self.integrator.unwrap_or_default();
        // Progressive photon mapping counts photons and camera samples per pass.
        let sppm = integrator == Integrator::Sppm;
        let c = RenderConfig {
            accel: self.accel.unwrap_or_else(AccelKind::default_kind),
            robust: self.robust.unwrap_or(true),
            width,
            height,
            photons: self.photons.unwrap_or(if sppm { SPPM_PHOTONS } else { 1_000_000 }),
            caustic_photons: self.caustic_photons.unwrap_or(if sppm {
                SPPM_CAUSTIC_PHOTONS
            } else {
                300_000
            }),
            spp: self.spp.unwrap_or(if sppm { SPPM_SPP } else { 64 }),
            seed: self.seed.unwrap_or(1),
            max_bounces: self.max_bounces.unwrap_or(64),
            max_depth: self.max_depth.unwrap_or(16),
            gather_photons: self.gather_photons.unwrap_or(if sppm { SPPM_GATHER_PHOTONS } else { 100 }),
            gather_radius: self.gather_radius,
            caustic_gather_photons: self.caustic_gather_photons.unwrap_or(60),
            caustic_gather_radius: self.caustic_gather_radius,
            indirect: self.indirect.unwrap_or(IndirectMode::Estimate),
            final_gather_rays: self.final_gather_rays.unwrap_or(32),
            color: self.color.unwrap_or(ColorMode::Rgb),
            kernel: self.kernel.unwrap_or(Kernel::Cone),
            light_samples: self.light_samples.unwrap_or(1),
            irradiance_cache: self.irradiance_cache.unwrap_or(true),
            component: self.component.unwrap_or_default(),
            integrator,
            passes: self.passes.or(if sppm && self.time.is_none() { Some(SPPM_PASSES) } else { None }),
            time: self.time,
            alpha: self.alpha.unwrap_or(0.7),
            caustic_aim: self.caustic_aim.unwrap_or(true),
            caustic_pass: self.caustic_pass.unwrap_or_default(),
        };
        c.validate()?;
        Ok(c)
    }
}

impl RenderConfig {
    fn validate(&self) -> Result<(), ConfigError> {
        let side = crate::scene::MAX_IMAGE_SIDE;
        if self.width == 0 || self.height == 0 {
            return Err(bad(
                "width/height",
                format!("{}x{}: both must be at least 1", self.width, self.height),
            ));
        }
        if self.width > side || self.height > side {
            // A float RGB film is 12 bytes a pixel, before any per-pixel render state.
            let gb = self.width as f64 * self.height as f64 * 12.0 / 1e9;
            return Err(bad(
                "width/height",
                format!(
                    "{}x{} would need about {gb:.1} GB for the film alone; at most {side} per side",
                    self.width, self.height
                ),
            ));
        }
        for (field, n) in [("photons", self.photons), ("caustic_photons", self.caustic_photons)] {
            if n > MAX_PHOTONS {
                let gb = (n as f64 * BYTES_PER_PHOTON as f64) / 1e9;
                return Err(bad(
                    field,
                    format!(
                        "{n} photons would need about {gb:.0} GB for the map alone; at most {MAX_PHOTONS}"
                    ),
                ));
            }
        }
        let pixels = self.width as u64 * self.height as u64;
        if self.spp == 0 || self.spp > 1 << 20 {
            return Err(bad("spp", format!("{} is not in 1..=1048576", self.spp)));
        }
        if pixels * self.spp as u64 > 1 << 40 {
            return Err(bad("spp", "width x height x spp exceeds 2^40 camera samples"));
        }
        if self.gather_photons == 0 || self.gather_photons > 10_000 {
            return Err(bad("gather_photons", format!("{} is not in 1..=10000", self.gather_photons)));
        }
        if self.caustic_gather_photons == 0 || self.caustic_gather_photons > 10_000 {
            return Err(bad(
                "caustic_gather_photons",
                format!("{} is not in 1..=10000", self.caustic_gather_photons),
            ));
        }
        for (field, r) in
            [("gather_radius", self.gather_radius), ("caustic_gather_radius", self.caustic_gather_radius)]
        {
            if let Some(r) = r {
                if !(r.is_finite() && r > 0.0) {
                    return Err(bad(field, format!("{r} must be finite and positive")));
                }
            }
        }
        if self.final_gather_rays == 0 || self.final_gather_rays > 4096 {
            return Err(bad("final_gather_rays", format!("{} is not in 1..=4096", self.final_gather_rays)));
        }
        if self.light_samples == 0 || self.light_samples > 1024 {
            return Err(bad("light_samples", format!("{} is not in 1..=1024", self.light_samples)));
        }
        if let Some(p) = self.passes {
            if p == 0 || p > 1 << 24 {
                return Err(bad("passes", format!("{p} is not in 1..=16777216")));
            }
        }
        if let Some(t) = self.time {
            if !(t.is_finite() && t > 0.0) {
                return Err(bad("time", format!("{t} must be a finite number of seconds above 0")));
            }
        }
        if !(self.alpha > 0.0 && self.alpha < 1.0) {
            return Err(bad("alpha", format!("{} is not in (0, 1)", self.alpha)));
        }
        if self.integrator == Integrator::Sppm && self.component != Component::All {
            return Err(bad("component", "progressive photon mapping renders the whole sum only"));
        }
        if self.max_bounces > 10_000 || self.max_depth > 10_000 {
            return Err(bad("max_bounces/max_depth", "at most 10000"));
        }
        Ok(())
    }
}
