//! Render settings: the `[render]` table of a scene file, overridden by command-line flags, then
//! resolved into a complete, validated [`RenderConfig`] whose [`Integrator`] carries the settings
//! of the chosen integrator only.
//!
//! [`RenderSettings`] is declared once, by the list in `settings.rs`: the struct, its merge
//! ([`RenderSettings::overridden_by`]) and the table the command line builds its flags from
//! ([`RenderSettings::FIELDS`], [`RenderSettings::set`]) all come from that list.

mod resolve;
mod settings;

pub use resolve::ConfigError;
pub use settings::{Field, RenderSettings, SettingValue};

use crate::accel::AccelKind;
use serde::Serialize;

crate::choice! {
    /// How indirect diffuse light is computed at camera hits.
    pub enum IndirectMode {
        /// The indirect map's radiance estimate read directly at the hit.
        Estimate = "estimate",
        /// Jensen's final gathering: hemisphere rays, each reading the maps where it lands.
        FinalGather = "final-gather",
    }
}

crate::choice! {
    /// What a photon carries.
    pub enum ColorMode {
        /// The lecture's three maps: each photon carries one colour channel.
        PerChannel = "per-channel",
        /// One map of photons carrying RGB power.
        Rgb = "rgb",
    }
}

crate::choice! {
    /// Density-estimation kernel of the radiance estimate.
    pub enum Kernel {
        Box = "box",
        Cone = "cone",
        Gaussian = "gaussian",
    }
}

crate::choice! {
    /// Which part of the light a render shows (the lecture's sum, term by term).
    #[derive(Default)]
    pub enum Component {
        /// Everything: the image.
        #[default]
        All = "all",
        /// Emitters seen directly or through mirrors and glass.
        Emitted = "emitted",
        /// Direct light from shadow rays.
        Direct = "direct",
        /// The caustic map's estimate.
        Caustic = "caustic",
        /// The indirect map's estimate (or the final gather).
        Indirect = "indirect",
    }
}

impl Component {
    /// Whether a render of `self` includes the term `c`.
    #[inline]
    pub fn shows(self, c: Component) -> bool {
        self == Component::All || self == c
    }
}

crate::choice! {
    /// Which estimator renders the image (the `integrator` setting; [`Integrator`] holds the
    /// resolved settings of each).
    #[derive(Default)]
    pub enum IntegratorKind {
        /// Jensen's two-pass photon mapping (the renderer proper).
        #[default]
        Photon = "photon",
        /// An independent unidirectional path tracer with next-event estimation and MIS, sharing
        /// only the scene, materials, lights and accelerator: a cross-check of the photon mapper.
        Path = "path",
        /// Stochastic progressive photon mapping (Hachisuka & Jensen 2009): passes of photons
        /// with a per-pixel radius that shrinks, so the error goes to zero as passes are added.
        Sppm = "sppm",
        /// Probabilistic progressive photon mapping (Knaus & Zwicker 2011): independent passes
        /// whose gather radius depends only on the pass index, averaged.
        Pppm = "pppm",
    }
}

crate::choice! {
    /// Whether the caustic photon pass runs.
    #[derive(Default)]
    pub enum CausticPass {
        /// When the scene analysis says caustics are possible (mirrors or glass, something
        /// diffuse to receive them, a light with power) and the render shows them.
        #[default]
        Auto = "auto",
        /// Always, even when the analysis would skip it (to measure what skipping saves).
        On = "on",
        /// Never: the image has no caustics from the caustic map.
        Off = "off",
    }
}

/// How the photon maps of a pass are traced (two-pass and progressive photon mapping).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct PhotonPasses {
    /// Photons emitted for the indirect map (all channels together).
    pub photons: u64,
    /// Photons emitted toward specular objects for the caustic map.
    pub caustic_photons: u64,
    /// Longest photon path (bounces after emission).
    pub max_bounces: u32,
    pub color: ColorMode,
    /// Aim caustic photons at the bounding spheres of the specular objects (a projection map);
    /// `false`: emit them from the lights as usual and keep only light → specular+ → diffuse
    /// paths.
    pub caustic_aim: bool,
    /// Whether the caustic pass runs: as the scene analysis decides, always, or never.
    pub caustic_pass: CausticPass,
    /// Whether indirect photons may be guided toward what the camera sees (`photon::guide`).
    pub guide: bool,
}

/// The k-nearest-photon gathers.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Gathers {
    pub gather_photons: u32,
    /// `None`: chosen from the scene size.
    pub gather_radius: Option<f32>,
    pub caustic_gather_photons: u32,
    pub caustic_gather_radius: Option<f32>,
    pub kernel: Kernel,
}

/// Two-pass photon mapping.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct PhotonConfig {
    pub maps: PhotonPasses,
    pub gathers: Gathers,
    pub indirect: IndirectMode,
    pub final_gather_rays: u32,
    /// Precompute irradiance at photon positions for diffuse lookups (Christensen 1999).
    pub irradiance_cache: bool,
    pub light_samples: u32,
    /// Longest camera path through mirrors and glass.
    pub max_depth: u32,
    /// Which term of the sum is shown.
    pub component: Component,
}

/// Progressive photon mapping, stochastic or pass-indexed.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ProgressiveConfig {
    /// The maps traced at every pass.
    pub maps: PhotonPasses,
    /// The first radius of each pixel (the k-th nearest photon, bounded by the radius).
    pub gathers: Gathers,
    /// The fraction of new photons kept at each radius update (Hachisuka & Jensen's alpha, in
    /// (0, 1)).
    pub alpha: f32,
    pub light_samples: u32,
    pub max_depth: u32,
    /// Whether pass-indexed progressive photon mapping chooses its camera samples per pass
    /// (no `--spp` given; `src/integrator/balance.rs`), in renders long enough for its pilot
    /// to measure them.
    pub auto_samples: bool,
    /// Whether it chooses the photons a pass traces, a multiple of `maps`' (neither
    /// `--photons` nor `--caustic-photons` given).
    pub auto_photons: bool,
}

/// The path tracer.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct PathConfig {
    /// Longest path of any kind (bounces after the camera ray).
    pub max_depth: u32,
}

/// The integrator that renders the image, with its own settings.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Integrator {
    Photon(PhotonConfig),
    Progressive(ProgressiveConfig),
    /// Pass-indexed progressive photon mapping: the same settings as the stochastic kind.
    PassIndexed(ProgressiveConfig),
    Path(PathConfig),
}

impl Integrator {
    pub fn kind(&self) -> IntegratorKind {
        match self {
            Integrator::Photon(_) => IntegratorKind::Photon,
            Integrator::Progressive(_) => IntegratorKind::Sppm,
            Integrator::PassIndexed(_) => IntegratorKind::Pppm,
            Integrator::Path(_) => IntegratorKind::Path,
        }
    }

    /// How the photon maps are traced, for the integrators that trace them.
    pub fn photon_passes(&self) -> Option<&PhotonPasses> {
        match self {
            Integrator::Photon(c) => Some(&c.maps),
            Integrator::Progressive(c) | Integrator::PassIndexed(c) => Some(&c.maps),
            Integrator::Path(_) => None,
        }
    }
}

/// A complete, validated set of render settings.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RenderConfig {
    pub accel: AccelKind,
    /// Embree's robust (watertight) mode.
    pub robust: bool,
    /// Distant lights emit through the scene's portals.
    pub portals: bool,
    pub width: u32,
    pub height: u32,
    /// Camera samples per pixel per pass.
    pub spp: u32,
    pub seed: u64,
    /// Passes to render and average (progressive photon mapping refines its radii between
    /// them); `None`: one pass, or as many as `time` allows.
    pub passes: Option<u32>,
    /// Time budget in seconds: no pass starts that would end after it (the first always runs).
    pub time: Option<f64>,
    /// Stop once the estimated relative RMSE of the image is below this (after at least
    /// [`TARGET_ERROR_MIN_PASSES`](crate::integrator::passes::TARGET_ERROR_MIN_PASSES) passes).
    pub target_error: Option<f64>,
    pub integrator: Integrator,
}

impl RenderConfig {
    /// Whether more than one pass may run.
    pub fn is_progressive(&self) -> bool {
        self.time.is_some() || self.target_error.is_some() || self.passes.is_some_and(|p| p > 1)
    }
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

/// Default longest camera path (`max_depth`) and photon path (`max_bounces`). Diffuse paths end
/// by Russian roulette long before; the cap only stops light trapped in glass by total internal
/// reflection, and a low one darkens it (`examples/glass_depth.rs`: a faceted glass sphere of
/// IOR 2.5 in a uniform emitter, exact 1, averages 0.973 at depth 16, 0.992 at 256, 0.995 at
/// 1000, at the same render time).
pub const DEFAULT_DEPTH: u32 = 1000;

/// Bytes one stored photon costs, tree included; used to refuse absurd budgets up front.
pub const BYTES_PER_PHOTON: u64 = 20;
/// Photon budgets above this are refused (10^9 photons would need about 20 GB).
pub const MAX_PHOTONS: u64 = 500_000_000;
/// Largest image side accepted (a 16k × 16k float RGB film is 3 GiB).
pub const MAX_IMAGE_SIDE: u32 = 16384;
