//! Light trapped in glass, measured: a faceted glass sphere (IOR 2.5 unless given, 24 rings)
//! inside an enclosure that emits radiance 1 and reflects nothing
//! ([`scenes::glass_in_furnace`]): every pixel's exact value is 1; a camera path cut short
//! inside the glass brings back nothing. Prints the image mean and darkest pixel of the photon
//! mapper for several `--max-depth` values.
//!
//! ```text
//! cargo run --release --example glass_depth [-- SPP [IOR]]
//! ```

use photonmap::config::RenderSettings;
use photonmap::frame::Quiet;
use photonmap::integrator::render_scene;
use photonmap::tools::stress::scenes;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let spp: u32 = args.next().map(|s| s.parse()).transpose()?.unwrap_or(16);
    let ior: f32 = args.next().map(|s| s.parse()).transpose()?.unwrap_or(2.5);
    let scene = scenes::glass_in_furnace(ior, 24);
    println!("glass sphere (IOR {ior}) in a uniform emitter, 24x24, {spp} spp: exact value 1 everywhere");
    println!("max-depth   mean      darkest pixel   seconds");
    for depth in [16, 64, 256, 1000] {
        let start = std::time::Instant::now();
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
        let secs = start.elapsed().as_secs_f64();
        println!("{depth:>9}   {:.5}   {darkest:.4}          {secs:.2}", film.mean());
    }
    Ok(())
}
