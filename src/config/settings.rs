//! The settings a scene's `[render]` table and the command line may give, declared once: the
//! `settings!` list below makes the struct, its merge and the table of flags.

use super::{CausticPass, ColorMode, Component, IndirectMode, IntegratorKind, Kernel};
use crate::accel::AccelKind;
use crate::choice::Choice;
use serde::{Deserialize, Serialize};

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

            /// Whether the setting `name` (a key of [`RenderSettings::FIELDS`]) is set.
            pub fn is_set(&self, name: &str) -> bool {
                match name {
                    $(stringify!($field) => self.$field.is_some(),)+
                    _ => false,
                }
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
    /// Longest photon path; Russian roulette ends almost all of them far sooner [default: 1000].
    max_bounces: u32,
    /// Longest camera path through mirrors and glass; with the path tracer, of any kind
    /// [default: 1000].
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
    /// Precompute irradiance at photon positions (and caustic irradiance where caustic paths
    /// land) and read it at diffuse surfaces instead of gathering photons there (Christensen
    /// 1999) [default: true].
    irradiance_cache: bool,
    /// Render only one term of the sum: emitted, direct, caustic or indirect [default: all].
    component: Component,
    /// Photon mapping, stochastic (sppm) or pass-indexed (pppm) progressive photon mapping, or
    /// the path tracer (next-event estimation and MIS) as a cross-check; the path tracer ignores the photon settings and uses --max-depth
    /// for every bounce [default: photon].
    integrator: IntegratorKind,
    /// Render this many passes and average them (progressive photon mapping shrinks its radii
    /// between passes) [default: 1; sppm: 64 unless --time is given].
    passes: u32,
    /// Time budget in seconds from the start of the command: no pass starts that would end
    /// after it, and the image so far is written.
    time: f64,
    /// Stop once the image's estimated relative RMSE (from the spread of its passes, and the
    /// probed bias of pppm's photon estimate) is below this, e.g. 0.01 for 1 %; with --passes
    /// or --time, whichever comes first. Not with sppm, whose passes are not independent.
    target_error: f64,
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
    /// Guide photon emission toward what the camera sees when a pilot finds that few photons
    /// get there (a sun through a small window, a light behind a door); false: emit as usual
    /// [default: true].
    photon_guide: bool,
    /// Send half of each distant light's photons through the scene's `[[portal]]` openings
    /// and the rest over the disc outside them (unbiased either way); false: ignore the
    /// portals [default: true].
    portals: bool,
}
