//! Light trapped in glass, measured: a faceted glass sphere (IOR 2.5, 24 rings) inside an
//! enclosure that emits radiance 1 and reflects nothing. Lossless glass in a uniform emitter
//! must look like the emitter, so every pixel's exact value is 1; a camera path cut short
//! inside the glass brings back nothing. Prints the image mean and darkest pixel of the photon
//! mapper for several `--max-depth` values.
//!
//! ```text
//! cargo run --release --example glass_depth [-- SPP]
//! ```

use photonmap::config::RenderSettings;
use photonmap::frame::Quiet;
use photonmap::geometry::Vec3;
use photonmap::integrator::render_scene;
use photonmap::material::Material;
use photonmap::scene::Scene;
use photonmap::tools::stress::scenes::{camera, Builder, Facing};

/// A UV sphere of `rings` × `2 rings` quads, outward facing (pole triangles only).
fn sphere(b: &mut Builder, center: Vec3, radius: f32, rings: u32, material: u32) {
    let at = |i: u32, j: u32| {
        let theta = std::f32::consts::PI * i as f32 / rings as f32;
        let phi = std::f32::consts::PI * j as f32 / rings as f32;
        center + radius * Vec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin())
    };
    for i in 0..rings {
        for j in 0..2 * rings {
            let (p, q, r, s) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            if i > 0 {
                b.triangle(p, r, q, material);
            }
            if i + 1 < rings {
                b.triangle(p, s, r, material);
            }
        }
    }
}

fn glass_in_furnace() -> Scene {
    let mut b = Builder::default();
    let wall = b.material("wall", Material::Emissive { kd: Vec3::ZERO, ke: Vec3::ONE });
    let glass = b.material("glass", Material::Glass { ior: 2.5 });
    b.cuboid(-Vec3::splat(3.0), Vec3::splat(3.0), Facing::Inward, wall);
    sphere(&mut b, Vec3::ZERO, 1.0, 24, glass);
    b.build("glass-in-furnace", camera(Vec3::new(0.0, 0.0, -2.6), Vec3::ZERO, Vec3::Y, 50.0))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let spp: u32 = std::env::args().nth(1).map(|s| s.parse()).transpose()?.unwrap_or(16);
    let scene = glass_in_furnace();
    println!("glass sphere (IOR 2.5) in a uniform emitter, 24x24, {spp} spp: exact value 1 everywhere");
    println!("max-depth   mean      darkest pixel");
    for depth in [16, 64, 256, 1000] {
        let settings = RenderSettings {
            max_depth: Some(depth),
            photons: Some(1000),
            caustic_photons: Some(1000),
            spp: Some(spp),
            seed: Some(3),
            ..Default::default()
        };
        let cfg = scene.render.overridden_by(&settings).resolve(24, 24)?;
        let film = render_scene(&scene, &cfg, &Quiet)?.film;
        let darkest = film.pixels.iter().map(|p| p.min_element()).fold(f32::INFINITY, f32::min);
        println!("{depth:>9}   {:.5}   {darkest:.4}", film.mean());
    }
    Ok(())
}
