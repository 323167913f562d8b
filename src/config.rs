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
            robust
        )
    }
}
