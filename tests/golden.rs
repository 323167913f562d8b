//! Golden images: every integrator and the main photon-mapping modes on the four shipped scenes,
//! rendered at 32x32 with a fixed seed and pass count on the pure-Rust BVH, must hash to the
//! values in `tests/data/golden.txt`. Any change to the rendering code that is meant to leave
//! images alone (a refactor, a speed-up) must keep every hash; a change that is meant to alter
//! images re-records them, says so in its commit, and measures what moved.
//!
//! The BVH is used because its results depend only on this crate's code (Embree picks its
//! instruction set at run time, and its last bits may differ between machines).
//!
//! To re-record after an intended change: `PHOTONMAP_RECORD_GOLDEN=1 cargo test --test all golden::`.

use crate::common::{render_checked, scene};
use photonmap::accel::AccelKind;
use photonmap::config::{ColorMode, Component, IndirectMode, IntegratorKind, RenderSettings};
use std::fmt::Write;
use std::path::Path;

const SCENES: [&str; 4] = ["cornell", "caustics", "pointlight", "furnace"];

/// The render modes covered: name and settings (over the scene's own).
fn variants() -> Vec<(&'static str, RenderSettings)> {
    let base = RenderSettings {
        accel: Some(AccelKind::Bvh),
        photons: Some(20_000),
        caustic_photons: Some(6_000),
        spp: Some(2),
        seed: Some(7),
        ..Default::default()
    };
    vec![
        ("photon", base.clone()),
        ("photon-passes", RenderSettings { passes: Some(2), ..base.clone() }),
        ("photon-per-channel", RenderSettings { color: Some(ColorMode::PerChannel), ..base.clone() }),
        ("photon-no-cache", RenderSettings { irradiance_cache: Some(false), ..base.clone() }),
        (
            "photon-final-gather",
            RenderSettings {
                indirect: Some(IndirectMode::FinalGather),
                final_gather_rays: Some(4),
                spp: Some(1),
                ..base.clone()
            },
        ),
        ("photon-caustic", RenderSettings { component: Some(Component::Caustic), ..base.clone() }),
        (
            "sppm",
            RenderSettings {
                integrator: Some(IntegratorKind::Sppm),
                passes: Some(3),
                photons: Some(5_000),
                caustic_photons: Some(2_000),
                ..base.clone()
            },
        ),
        (
            "pppm",
            RenderSettings {
                integrator: Some(IntegratorKind::Pppm),
                passes: Some(3),
                photons: Some(5_000),
                caustic_photons: Some(2_000),
                ..base.clone()
            },
        ),
        ("path", RenderSettings { integrator: Some(IntegratorKind::Path), spp: Some(4), ..base }),
    ]
}

/// FNV-1a over the bits of every pixel channel.
fn hash(pixels: &[glam::Vec3]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for p in pixels {
        for c in p.to_array() {
            for b in c.to_bits().to_le_bytes() {
                h = (h ^ b as u64).wrapping_mul(0x0100_0000_01b3);
            }
        }
    }
    h
}

fn golden_path() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/golden.txt")
}

#[test]
fn images_match_the_recorded_hashes() {
    let mut lines = String::new();
    for name in SCENES {
        let s = scene(name);
        for (variant, settings) in variants() {
            let out = render_checked(&s, &settings, 32);
            writeln!(lines, "{name} {variant} {:016x}", hash(&out.film.pixels)).unwrap();
        }
    }
    if std::env::var_os("PHOTONMAP_RECORD_GOLDEN").is_some() {
        std::fs::write(golden_path(), &lines).unwrap();
        eprintln!("recorded {}", golden_path().display());
        return;
    }
    let expected = std::fs::read_to_string(golden_path()).unwrap();
    let mut wrong = Vec::new();
    for (got, want) in lines.lines().zip(expected.lines()) {
        if got != want {
            wrong.push(format!("got {got}, recorded {want}"));
        }
    }
    assert_eq!(lines.lines().count(), expected.lines().count(), "the recorded list has other cases");
    assert!(wrong.is_empty(), "{} images changed:\n{}", wrong.len(), wrong.join("\n"));
}
