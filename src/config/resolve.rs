//! From settings to a [`RenderConfig`]: defaults filled, every value checked, and the settings
//! of the chosen integrator gathered into its own config.

use super::{
    ColorMode, Component, Gathers, IndirectMode, Integrator, IntegratorKind, Kernel, PathConfig,
    PhotonConfig, PhotonPasses, ProgressiveConfig, RenderConfig, RenderSettings, BYTES_PER_PHOTON,
    DEFAULT_DEPTH, MAX_IMAGE_SIDE, MAX_PHOTONS, SPPM_CAUSTIC_PHOTONS, SPPM_GATHER_PHOTONS, SPPM_PASSES,
    SPPM_PHOTONS, SPPM_SPP,
};
use crate::accel::AccelKind;

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
        let sppm = matches!(kind, IntegratorKind::Sppm | IntegratorKind::Pppm);
        let maps = PhotonPasses {
            photons: self.photons.unwrap_or(if sppm { SPPM_PHOTONS } else { 1_000_000 }),
            caustic_photons: self.caustic_photons.unwrap_or(if sppm {
                SPPM_CAUSTIC_PHOTONS
            } else {
                300_000
            }),
            max_bounces: self.max_bounces.unwrap_or(DEFAULT_DEPTH),
            color: self.color.unwrap_or(ColorMode::Rgb),
            caustic_aim: self.caustic_aim.unwrap_or(true),
            caustic_pass: self.caustic_pass.unwrap_or_default(),
            guide: self.photon_guide.unwrap_or(true),
        };
        let gathers = Gathers {
            gather_photons: self.gather_photons.unwrap_or(if sppm { SPPM_GATHER_PHOTONS } else { 100 }),
            gather_radius: self.gather_radius,
            caustic_gather_photons: self.caustic_gather_photons.unwrap_or(60),
            caustic_gather_radius: self.caustic_gather_radius,
            kernel: self.kernel.unwrap_or(Kernel::Cone),
        };
        let max_depth = self.max_depth.unwrap_or(DEFAULT_DEPTH);
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
            IntegratorKind::Sppm | IntegratorKind::Pppm => {
                if component != Component::All {
                    return Err(bad("component", "progressive photon mapping renders the whole sum only"));
                }
                let alpha = self.alpha.unwrap_or(0.7);
                let auto_samples = self.spp.is_none();
                let auto_photons = self.photons.is_none() && self.caustic_photons.is_none();
                let c = ProgressiveConfig {
                    maps,
                    gathers,
                    alpha,
                    light_samples,
                    max_depth,
                    auto_samples,
                    auto_photons,
                };
                match kind {
                    IntegratorKind::Sppm => Integrator::Progressive(c),
                    _ => Integrator::PassIndexed(c),
                }
            }
            IntegratorKind::Path => Integrator::Path(PathConfig { max_depth }),
        };
        let c = RenderConfig {
            accel: self.accel.unwrap_or_else(AccelKind::default_kind),
            robust: self.robust.unwrap_or(true),
            portals: self.portals.unwrap_or(true),
            width,
            height,
            spp: self.spp.unwrap_or(if sppm { SPPM_SPP } else { 64 }),
            seed: self.seed.unwrap_or(1),
            passes: self.passes.or(if sppm && self.time.is_none() && self.target_error.is_none() {
                Some(SPPM_PASSES)
            } else {
                None
            }),
            time: self.time,
            target_error: self.target_error,
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
        if let Some(e) = self.target_error {
            if !(e.is_finite() && e > 0.0) {
                return Err(bad(
                    "target_error",
                    format!("{e} must be a finite relative error above 0 (0.01: 1 %)"),
                ));
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
    // An estimate through the k-th photon counts the k - 1 inside (`photon::map`): k = 1
    // would count none.
    for (field, k) in
        [("gather_photons", g.gather_photons), ("caustic_gather_photons", g.caustic_gather_photons)]
    {
        if !(2..=10_000).contains(&k) {
            return Err(bad(field, format!("{k} is not in 2..=10000")));
        }
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
