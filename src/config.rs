//! Render settings: the `[render]` table of a scene file, overridden by command-line flags, then
//! resolved into a complete, validated [`RenderConfig`] whose [`Integrator`] carries the settings
//! of the chosen integrator only.
//!
//! [`RenderSettings`] is declared once, by the `settings!` list below: the struct, its merge
//! ([`RenderSettings::overridden_by`]) and the table the command line builds its flags from
//! ([`RenderSettings::FIELDS`], [`RenderSettings::set`]) all come from that list.

use crate::accel::AccelKind;
use crate::choice::Choice;
use serde::{Deserialize, Serialize};

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

/// The type of a setting, as the command line sees it.
pub trait SettingValue: Sized {
    /// The names a flag accepts (enums); empty for numbers and booleans.
    const CHOICES: &'static [&'static str];
    /// What the flag's value is called in `--help`.
    const VALUE_NAME: &'static str;
    /// Parses the text of a flag.
    fn parse_setting(text: &str) -> Result<Self, String>;
}

macro_rules! number_setting {
    ($($t:ty => $value:literal),*) => {$(
        impl SettingValue for $t {
            const CHOICES: &'static [&'static str] = &[];
            const VALUE_NAME: &'static str = $value;
            fn parse_setting(text: &str) -> Result<Self, String> {
                text.parse().map_err(|e| format!("{e}"))
            }
        }
    )*};
}
number_setting!(u32 => "N", u64 => "N", f32 => "X", f64 => "SECONDS", bool => "BOOL");

impl<T: Choice> SettingValue for T {
    const CHOICES: &'static [&'static str] = T::NAMES;
    const VALUE_NAME: &'static str = "NAME";
    fn parse_setting(text: &str) -> Result<Self, String> {
        T::from_name(text).ok_or_else(|| format!("expected one of {}", T::NAMES.join(", ")))
    }
}

/// One setting, as the command line offers it: `--name-with-dashes VALUE`.
#[derive(Clone, Copy, Debug)]
pub struct Field {
    /// The key in `[render]` (`snake_case`).
    pub name: &'static str,
    /// Its documentation (the doc comment of the field).
    pub help: &'static str,
    /// The accepted names, for enums.
    pub choices: &'static [&'static str],
    pub value_name: &'static str,
    /// Whether `text` is a valid value.
    pub check: fn(&str) -> Result<(), String>,
}

macro_rules! settings {
    ($($(#[doc = $doc:literal])+ $field:ident: $t:ty,)+) => {
        /// Optional settings as written in `[render]` (or given on the command line). `None`
        /// means "use the default".
        #[derive(Clone, Debug, Default, Deserialize, Serialize, PartialEq)]
        #[serde(deny_unknown_fields)]
        pub struct RenderSettings {
            $($(#[doc = $doc])+ pub $field: Option<$t>,)+
        }

        impl RenderSettings {
            /// Every setting, in the order of the struct.
            pub const FIELDS: &'static [Field] = &[$(Field {
                name: stringify!($field),
                help: concat!($($doc),+),
                choices: <$t as SettingValue>::CHOICES,
                value_name: <$t as SettingValue>::VALUE_NAME,
                check: |text| <$t as SettingValue>::parse_setting(text).map(|_| ()),
            },)+];

            /// `self` with every field that `over` sets replaced.
            pub fn overridden_by(&self, over: &RenderSettings) -> RenderSettings {
                RenderSettings { $($field: over.$field.or(self.$field),)+ }
            }

            /// Sets the setting `name` (a key of [`RenderSettings::FIELDS`]) from its text.
            pub fn set(&mut self, name: &str, text: &str) -> Result<(), String> {
                match name {
                    $(stringify!($field) => self.$field = Some(<$t as SettingValue>::parse_setting(text)?),)+
                    _ => return Err(format!("no setting called {name}")),
                }
                Ok(())
            }
        }
    };
}

settings! {
    /// Ray-casting backend [default: embree when built with it, else bvh].
    accel: AccelKind,
    /// Use Embree's robust (watertight) mode [default: true].
    robust: bool,
    /// Photons emitted for the indirect map [default: 1000000; sppm: 100000 a pass].
    photons: u64,
    /// Photons aimed at specular objects for the caustic map [default: 300000; sppm: 30000 a
    /// pass].
    caustic_photons: u64,
    /// Camera samples per pixel per pass [default: 64; sppm: 4].
    spp: u32,
    /// Random seed; the same seed gives the same image for any thread count [default: 1].
    seed: u64,
    /// Longest photon path [default: 64].
    max_bounces: u32,
    /// Longest camera path through mirrors and glass; with the path tracer, of any kind
    /// [default: 16].
    max_depth: u32,
    /// Photons per indirect radiance estimate (sppm: for the first radius) [default: 100; sppm:
    /// 30].
    gather_photons: u32,
    /// Largest indirect gather radius, scene units [default: a tenth of the scene radius].
    gather_radius: f32,
    /// Photons per caustic radiance estimate [default: 60].
    caustic_gather_photons: u32,
    /// Largest caustic gather radius [default: a quarter of the indirect one].
    caustic_gather_radius: f32,
    /// Indirect light from the map's estimate or by final gathering [default: estimate].
    indirect: IndirectMode,
    /// Rays per final gather [default: 32].
    final_gather_rays: u32,
    /// Photons carry one colour channel (three maps, the lecture's way) or RGB [default: rgb].
    color: ColorMode,
    /// Density-estimation kernel [default: cone].
    kernel: Kernel,
    /// Shadow-ray samples per shading point [default: 1].
    light_samples: u32,
    /// Precompute irradiance at photon positions and read it at diffuse surfaces instead of
    /// gathering photons there (Christensen 1999) [default: true].
    irradiance_cache: bool,
    /// Render only one term of the sum: emitted, direct, caustic or indirect [default: all].
    component: Component,
    /// Photon mapping, progressive photon mapping, or the path tracer (next-event estimation and
    /// MIS) as a cross-check; the path tracer ignores the photon settings and uses --max-depth
    /// for every bounce [default: photon].
    integrator: IntegratorKind,
    /// Render this many passes and average them (progressive photon mapping shrinks its radii
    /// between passes) [default: 1; sppm: 64 unless --time is given].
    passes: u32,
    /// Time budget in seconds from the start of the command: no pass starts that would end
    /// after it, and the image so far is written.
    time: f64,
    /// Progressive photon mapping's alpha, the fraction of new photons kept when the radius
    /// shrinks, in (0, 1) [default: 0.7].
    alpha: f32,
    /// Aim caustic photons at the mirrors and glass (bounding-sphere projection map); false:
    /// emit them from the lights as usual and keep the light-specular-diffuse paths
    /// [default: true].
    caustic_aim: bool,
    /// Run the caustic photon pass when the scene analysis says it is needed (auto), always (on)
    /// or never (off) [default: auto].
    caustic_pass: CausticPass,
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

/// Stochastic progressive photon mapping.
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
    Path(PathConfig),
}

impl Integrator {
    pub fn kind(&self) -> IntegratorKind {
        match self {
            Integrator::Photon(_) => IntegratorKind::Photon,
            Integrator::Progressive(_) => IntegratorKind::Sppm,
            Integrator::Path(_) => IntegratorKind::Path,
        }
    }

    /// How the photon maps are traced, for the integrators that trace them.
    pub fn photon_passes(&self) -> Option<&PhotonPasses> {
        match self {
            Integrator::Photon(c) => Some(&c.maps),
            Integrator::Progressive(c) => Some(&c.maps),
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
    pub integrator: Integrator,
}

impl RenderConfig {
    /// Whether more than one pass may run.
    pub fn is_progressive(&self) -> bool {
        self.time.is_some() || self.passes.is_some_and(|p| p > 1)
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

/// Bytes one stored photon costs, tree included; used to refuse absurd budgets up front.
pub const BYTES_PER_PHOTON: u64 = 20;
/// Photon budgets above this are refused (10^9 photons would need about 20 GB).
pub const MAX_PHOTONS: u64 = 500_000_000;
/// Largest image side accepted (a 16k × 16k float RGB film is 3 GiB).
pub const MAX_IMAGE_SIDE: u32 = 16384;

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
        let kind = self.integrator.unwrap_or_default();
        // Progressive photon mapping counts photons and camera samples per pass.
        let sppm = kind == IntegratorKind::Sppm;
        let maps = PhotonPasses {
            photons: self.photons.unwrap_or(if sppm { SPPM_PHOTONS } else { 1_000_000 }),
            caustic_photons: self.caustic_photons.unwrap_or(if sppm {
                SPPM_CAUSTIC_PHOTONS
            } else {
                300_000
            }),
            max_bounces: self.max_bounces.unwrap_or(64),
            color: self.color.unwrap_or(ColorMode::Rgb),
            caustic_aim: self.caustic_aim.unwrap_or(true),
            caustic_pass: self.caustic_pass.unwrap_or_default(),
        };
        let gathers = Gathers {
            gather_photons: self.gather_photons.unwrap_or(if sppm { SPPM_GATHER_PHOTONS } else { 100 }),
            gather_radius: self.gather_radius,
            caustic_gather_photons: self.caustic_gather_photons.unwrap_or(60),
            caustic_gather_radius: self.caustic_gather_radius,
            kernel: self.kernel.unwrap_or(Kernel::Cone),
        };
        let max_depth = self.max_depth.unwrap_or(16);
        let light_samples = self.light_samples.unwrap_or(1);
        let component = self.component.unwrap_or_default();
        let integrator = match kind {
            IntegratorKind::Photon => Integrator::Photon(PhotonConfig {
                maps,
                gathers,
                indirect: self.indirect.unwrap_or(IndirectMode::Estimate),
                final_gather_rays: self.final_gather_rays.unwrap_or(32),
                irradiance_cache: self.irradiance_cache.unwrap_or(true),
                light_samples,
                max_depth,
                component,
            }),
            IntegratorKind::Sppm => {
                if component != Component::All {
                    return Err(bad("component", "progressive photon mapping renders the whole sum only"));
                }
                let alpha = self.alpha.unwrap_or(0.7);
                Integrator::Progressive(ProgressiveConfig { maps, gathers, alpha, light_samples, max_depth })
            }
            IntegratorKind::Path => Integrator::Path(PathConfig { max_depth }),
        };
        let c = RenderConfig {
            accel: self.accel.unwrap_or_else(AccelKind::default_kind),
            robust: self.robust.unwrap_or(true),
            width,
            height,
            spp: self.spp.unwrap_or(if sppm { SPPM_SPP } else { 64 }),
            seed: self.seed.unwrap_or(1),
            passes: self.passes.or(if sppm && self.time.is_none() { Some(SPPM_PASSES) } else { None }),
            time: self.time,
            integrator,
        };
        c.validate()?;
        // Settings the chosen integrator does not read are still checked, so that a mistake
        // in a scene file shows whatever integrator renders it.
        let sppm_alpha = self.alpha.unwrap_or(0.7);
        if !(sppm_alpha > 0.0 && sppm_alpha < 1.0) {
            return Err(bad("alpha", format!("{sppm_alpha} is not in (0, 1)")));
        }
        validate_maps(&maps)?;
        validate_gathers(&gathers)?;
        validate_camera_paths(light_samples, max_depth, self.final_gather_rays.unwrap_or(32))?;
        Ok(c)
    }
}

impl RenderConfig {
    fn validate(&self) -> Result<(), ConfigError> {
        let side = MAX_IMAGE_SIDE;
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
        let pixels = self.width as u64 * self.height as u64;
        if self.spp == 0 || self.spp > 1 << 20 {
            return Err(bad("spp", format!("{} is not in 1..=1048576", self.spp)));
        }
        if pixels * self.spp as u64 > 1 << 40 {
            return Err(bad("spp", "width x height x spp exceeds 2^40 camera samples"));
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
        Ok(())
    }
}

fn validate_maps(m: &PhotonPasses) -> Result<(), ConfigError> {
    for (field, n) in [("photons", m.photons), ("caustic_photons", m.caustic_photons)] {
        if n > MAX_PHOTONS {
            let gb = (n as f64 * BYTES_PER_PHOTON as f64) / 1e9;
            return Err(bad(
                field,
                format!("{n} photons would need about {gb:.0} GB for the map alone; at most {MAX_PHOTONS}"),
            ));
        }
    }
    if m.max_bounces > 10_000 {
        return Err(bad("max_bounces/max_depth", "at most 10000"));
    }
    Ok(())
}

fn validate_gathers(g: &Gathers) -> Result<(), ConfigError> {
    if g.gather_photons == 0 || g.gather_photons > 10_000 {
        return Err(bad("gather_photons", format!("{} is not in 1..=10000", g.gather_photons)));
    }
    if g.caustic_gather_photons == 0 || g.caustic_gather_photons > 10_000 {
        return Err(bad(
            "caustic_gather_photons",
            format!("{} is not in 1..=10000", g.caustic_gather_photons),
        ));
    }
    for (field, r) in [("gather_radius", g.gather_radius), ("caustic_gather_radius", g.caustic_gather_radius)]
    {
        if let Some(r) = r {
            if !(r.is_finite() && r > 0.0) {
                return Err(bad(field, format!("{r} must be finite and positive")));
            }
        }
    }
    Ok(())
}

fn validate_camera_paths(
    light_samples: u32,
    max_depth: u32,
    final_gather_rays: u32,
) -> Result<(), ConfigError> {
    if final_gather_rays == 0 || final_gather_rays > 4096 {
        return Err(bad("final_gather_rays", format!("{final_gather_rays} is not in 1..=4096")));
    }
    if light_samples == 0 || light_samples > 1024 {
        return Err(bad("light_samples", format!("{light_samples} is not in 1..=1024")));
    }
    if max_depth > 10_000 {
        return Err(bad("max_bounces/max_depth", "at most 10000"));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_field_is_listed_once_and_parses_its_own_values() {
        let names: std::collections::BTreeSet<_> = RenderSettings::FIELDS.iter().map(|f| f.name).collect();
        assert_eq!(names.len(), RenderSettings::FIELDS.len());
        let mut s = RenderSettings::default();
        s.set("photons", "123").unwrap();
        s.set("kernel", "gaussian").unwrap();
        s.set("caustic_aim", "false").unwrap();
        assert_eq!((s.photons, s.kernel, s.caustic_aim), (Some(123), Some(Kernel::Gaussian), Some(false)));
        assert!(s.set("photons", "many").is_err());
        assert!(s.set("kernel", "tent").unwrap_err().contains("box, cone, gaussian"));
        assert!(s.set("nonsense", "1").is_err());
        let kernel = RenderSettings::FIELDS.iter().find(|f| f.name == "kernel").unwrap();
        assert_eq!(kernel.choices, &["box", "cone", "gaussian"]);
        assert!((kernel.check)("cone").is_ok() && (kernel.check)("tent").is_err());
    }

    #[test]
    fn overrides_replace_only_what_they_set() {
        let base = RenderSettings { photons: Some(5), spp: Some(2), ..Default::default() };
        let over = RenderSettings { spp: Some(9), seed: Some(3), ..Default::default() };
        let merged = base.overridden_by(&over);
        assert_eq!((merged.photons, merged.spp, merged.seed), (Some(5), Some(9), Some(3)));
    }

    #[test]
    fn each_integrator_gets_its_own_settings() {
        let sppm = RenderSettings { integrator: Some(IntegratorKind::Sppm), ..Default::default() };
        let c = sppm.resolve(8, 8).unwrap();
        let Integrator::Progressive(p) = c.integrator else { panic!("{:?}", c.integrator) };
        assert_eq!(
            (p.maps.photons, p.gathers.gather_photons, c.spp),
            (SPPM_PHOTONS, SPPM_GATHER_PHOTONS, SPPM_SPP)
        );
        assert_eq!(c.passes, Some(SPPM_PASSES));
        let c = RenderSettings::default().resolve(8, 8).unwrap();
        assert!(matches!(c.integrator, Integrator::Photon(p) if p.maps.photons == 1_000_000));
        assert_eq!(c.passes, None);
        // A setting the integrator does not read is still checked.
        let path = RenderSettings {
            integrator: Some(IntegratorKind::Path),
            gather_photons: Some(0),
            ..Default::default()
        };
        assert_eq!(path.resolve(8, 8).unwrap_err().field, "gather_photons");
        let bad_component = RenderSettings { component: Some(Component::Direct), ..sppm };
        assert_eq!(bad_component.resolve(8, 8).unwrap_err().field, "component");
    }
}
