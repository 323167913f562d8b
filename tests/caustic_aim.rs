//! Aimed caustic photons for small specular objects: the share of emission that reaches them
//! is estimated from more tries until one does, so a marble far from a point light still
//! casts its caustic; when even the last estimate finds none, the render says so.

use crate::common::render_checked;
use photonmap::config::RenderSettings;
use photonmap::geometry::Vec3;
use photonmap::light::LightDesc;
use photonmap::material::Material;
use photonmap::scene::Scene;
use photonmap::tools::stress::scenes::{camera, Builder};

/// An octahedron of "radius" `r` around `c`: the smallest closed glass object.
fn octahedron(b: &mut Builder, c: Vec3, r: f32, material: u32) {
    let [x, y, z] = [Vec3::X * r, Vec3::Y * r, Vec3::Z * r];
    for (sx, sz) in [(1.0, 1.0), (-1.0, 1.0), (-1.0, -1.0), (1.0, -1.0)] {
        let (a, d) = (c + x * sx, c + z * sz);
        // Counter-clockwise seen from outside: (a, d) turn one way around +y and the other around -y.
        if sx * sz > 0.0 {
            b.triangle(a, c + y, d, material);
            b.triangle(a, d, c - y, material);
        } else {
            b.triangle(d, c + y, a, material);
            b.triangle(d, a, c - y, material);
        }
    }
}

/// A floor lit by a point light 2 m above it, and a glass marble of radius `r` on the floor.
fn marble(r: f32) -> Scene {
    let mut b = Builder::default();
    let floor = b.material("floor", Material::Diffuse { kd: Vec3::splat(0.5) });
    let glass = b.material("glass", Material::Glass { ior: 1.5 });
    b.quad(
        [
            Vec3::new(-1.0, 0.0, -1.0),
            Vec3::new(-1.0, 0.0, 1.0),
            Vec3::new(1.0, 0.0, 1.0),
            Vec3::new(1.0, 0.0, -1.0),
        ],
        Vec3::Y,
        floor,
    );
    octahedron(&mut b, Vec3::new(0.0, r, 0.0), r, glass);
    b.light(LightDesc::Point { position: Vec3::new(0.0, 2.0, 0.0), intensity: Vec3::splat(10.0) });
    b.build("marble", camera(Vec3::new(0.0, 1.0, -2.0), Vec3::ZERO, Vec3::Y, 40.0))
}

fn settings() -> RenderSettings {
    RenderSettings { photons: Some(2_000), caustic_photons: Some(2_000), spp: Some(1), ..Default::default() }
}

#[test]
fn a_small_marble_far_from_its_light_gets_caustic_photons() {
    // About one emitted photon in a million heads for a 2.3 mm marble 2 m away (its bounding
    // sphere, radius 2.3 mm × √3): 65 536 tries alone would almost always find none.
    let out = render_checked(&marble(0.0023), &settings(), 8);
    let stage = out.stats.stages.iter().find(|s| s.name == "photons.caustic").unwrap();
    assert!(stage.ran, "caustic pass skipped: {}", stage.reason);
    assert!(out.stats.photons["caustic"].emitted > 0);
    assert!(out.stats.warnings.is_empty(), "{:?}", out.stats.warnings);
}

#[test]
fn a_caustic_that_cannot_be_aimed_at_is_reported() {
    // A 0.1 mm marble: about one photon in 500 million, beyond the largest estimate.
    let out = render_checked(&marble(0.0001), &settings(), 8);
    let stage = out.stats.stages.iter().find(|s| s.name == "photons.caustic").unwrap();
    assert!(!stage.ran);
    assert_eq!(out.stats.warnings.len(), 1, "{:?}", out.stats.warnings);
    assert!(out.stats.warnings[0].contains("no caustics"), "{}", out.stats.warnings[0]);
}
