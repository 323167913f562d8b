//! Bias of the photon mappers (sppm, pppm, and two-pass photon mapping's gathers), one cause at
//! a time, on scenes whose
//! answer is known exactly: furnace-like closed boxes whose walls have albedo 0.5 and emit 1
//! (radiance exactly 2 everywhere, in corners and on thin walls too), and a box that emits
//! nothing beside one that does (exactly 0 in it: whatever shows there leaked in).
//!
//! In a furnace of albedo 0.5 emission and direct light are 1.5 of the 2: the photon term is
//! 0.5, a quarter of the image, so a bias of x in the photon estimate moves the mean by x / 4.

use photonmap::config::{IntegratorKind, RenderSettings};
use photonmap::film::Film;
use photonmap::frame::Quiet;
use photonmap::geometry::Vec3;
use photonmap::integrator::render_scene;
use photonmap::material::Material;
use photonmap::scene::Scene;
use photonmap::tools::stress::scenes::{camera, Builder, Facing};

/// The furnace's material: albedo 0.5, emitted radiance 1.
fn furnace_material(b: &mut Builder) -> u32 {
    b.material("furnace", Material::Emissive { kd: Vec3::splat(0.5), ke: Vec3::ONE })
}

/// The furnace cube `[-1, 1]³` seen from its centre toward `target` with a `fov_deg` view.
fn furnace_view(target: Vec3, fov_deg: f32) -> Scene {
    let mut b = Builder::default();
    let m = furnace_material(&mut b);
    b.cuboid(-Vec3::ONE, Vec3::ONE, Facing::Inward, m);
    b.build("furnace-view", camera(Vec3::ZERO, target, Vec3::Y, fov_deg))
}

fn progressive(kind: IntegratorKind, passes: u32, photons: u64, seed: u64) -> RenderSettings {
    RenderSettings {
        integrator: Some(kind),
        passes: Some(passes),
        photons: Some(photons),
        seed: Some(seed),
        ..Default::default()
    }
}

fn render(scene: &Scene, settings: &RenderSettings, size: u32) -> Film {
    let cfg = scene.render.overridden_by(settings).resolve(size, size).unwrap();
    let out = render_scene(scene, &cfg, &Quiet).unwrap();
    assert_eq!(out.stats.nonfinite_samples, 0, "non-finite samples");
    out.film
}

/// The mean of `seeds` renders (seeds 1, 2, ...).
fn mean_of(scene: &Scene, settings: &RenderSettings, size: u32, seeds: u64) -> f64 {
    let total: f64 = (1..=seeds)
        .map(|seed| render(scene, &RenderSettings { seed: Some(seed), ..settings.clone() }, size).mean())
        .sum();
    total / seeds as f64
}

/// The first radius of both progressive kinds is the distance from the visible point to its
/// k-th nearest photon of the first pass, and that pass's photons are then counted inside it:
/// the k-th, on the disc's edge, must be left out, or the first pass is `k / (k - 1)` too
/// bright. Here k = 5 (+25 % of the photon term before the fix, measured +0.10 on the mean of
/// 2 with the k-th counted whenever the square root of its distance squared back to it or
/// above, about 4 times in 5), on a wall seen far from any edge, in one pass.
/// After the fix: 2.000 ± 0.01.
#[test]
fn first_pass_leaves_out_the_kth_photon() {
    let scene = furnace_view(Vec3::new(0.0, 0.0, 1.0), 40.0);
    for kind in [IntegratorKind::Sppm, IntegratorKind::Pppm] {
        let settings = RenderSettings { gather_photons: Some(5), ..progressive(kind, 1, 100_000, 1) };
        let mean = mean_of(&scene, &settings, 48, 2);
        eprintln!("{kind:?}: one pass, k = 5: mean {mean:.4} (exact 2)");
        assert!((mean - 2.0).abs() < 0.03, "{kind:?}: mean {mean}, exact 2");
    }
}

/// A closed box `[-1, 1]³` parted at `x = 0` by a wall of zero thickness (one quad, emitting
/// from its `+x` face only, two-sided diffuse): the `+x` half is a furnace (2 everywhere), the
/// `-x` half has walls of albedo 0.5 that emit nothing and no light can reach it (exactly 0).
/// The camera stands in the dark half, looking at the wall's foot on the floor. With `glossy`
/// the parting wall is a two-sided glossy quad instead (the lit half is then no furnace, the
/// dark half still exactly 0).
fn parted_box(glossy: bool) -> Scene {
    let mut b = Builder::default();
    let lit = furnace_material(&mut b);
    let dark = b.material("dark", Material::Diffuse { kd: Vec3::splat(0.5) });
    let wall = if glossy {
        b.material("glossy", Material::Glossy { kd: Vec3::splat(0.3), ks: Vec3::splat(0.5), ns: 20.0 })
    } else {
        lit
    };
    for (material, x0, x1) in [(lit, 0.0, 1.0), (dark, -1.0, 0.0)] {
        let p = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
        // Floor, ceiling, front, back and the outer end of this half, facing inward.
        b.quad([p(x0, -1.0, -1.0), p(x1, -1.0, -1.0), p(x1, -1.0, 1.0), p(x0, -1.0, 1.0)], Vec3::Y, material);
        b.quad([p(x0, 1.0, -1.0), p(x1, 1.0, -1.0), p(x1, 1.0, 1.0), p(x0, 1.0, 1.0)], -Vec3::Y, material);
        b.quad([p(x0, -1.0, -1.0), p(x1, -1.0, -1.0), p(x1, 1.0, -1.0), p(x0, 1.0, -1.0)], Vec3::Z, material);
        b.quad([p(x0, -1.0, 1.0), p(x1, -1.0, 1.0), p(x1, 1.0, 1.0), p(x0, 1.0, 1.0)], -Vec3::Z, material);
        let (end, inward) = if x0 == 0.0 { (1.0, -Vec3::X) } else { (-1.0, Vec3::X) };
        b.quad(
            [p(end, -1.0, -1.0), p(end, 1.0, -1.0), p(end, 1.0, 1.0), p(end, -1.0, 1.0)],
            inward,
            material,
        );
    }
    let p = |y: f32, z: f32| Vec3::new(0.0, y, z);
    b.quad([p(-1.0, -1.0), p(1.0, -1.0), p(1.0, 1.0), p(-1.0, 1.0)], Vec3::X, wall);
    let cam = camera(Vec3::new(-0.6, 0.0, 0.0), Vec3::new(0.0, -0.8, 0.3), Vec3::Y, 60.0);
    b.build("parted-box", cam)
}

/// A furnace with a thin sheet in it: two quads of the furnace's material back to back, a
/// tenth of a millimetre apart (so it has no side faces to see), half a metre across, seen
/// from above at an angle with its four edges in view: 2 everywhere.
fn furnace_with_sheet() -> Scene {
    let mut b = Builder::default();
    let m = furnace_material(&mut b);
    b.cuboid(-Vec3::ONE, Vec3::ONE, Facing::Inward, m);
    let (h, s) = (0.5e-4, 0.5);
    for (y, n) in [(h, Vec3::Y), (-h, -Vec3::Y)] {
        let p = |x: f32, z: f32| Vec3::new(x, y, z);
        b.quad([p(-s, -s), p(s, -s), p(s, s), p(-s, s)], n, m);
    }
    b.build("sheet", camera(Vec3::new(0.0, 0.6, -0.9), Vec3::ZERO, Vec3::Y, 70.0))
}

/// Gathers near the edges and corners of a room: a disc (flattened along the surface) that
/// reaches past the wall standing on the floor has no floor photons beyond it, and takes only
/// some of the wall's, so every edge was too dark. The furnace seen into a corner (three
/// edges across the view), 16 passes of 5k photons (photons sparse: the first radius near the
/// largest, 0.17, a twelfth of the box), 4 seeds: before the footprint probes sppm's mean was
/// -1.06 % and pppm's -1.22 % (at 100k photons a pass and 64 passes, -0.24 % and -0.28 %);
/// after, -0.04 % and -0.02 %.
#[test]
fn edges_and_corners_are_not_dark() {
    let scene = furnace_view(Vec3::new(1.0, -1.0, 1.0), 40.0);
    for kind in [IntegratorKind::Sppm, IntegratorKind::Pppm] {
        let mean = mean_of(&scene, &progressive(kind, 16, 5_000, 1), 32, 4);
        eprintln!("{kind:?}: corner view: mean {mean:.4} ({:+.3} %)", 100.0 * (mean / 2.0 - 1.0));
        assert!((mean / 2.0 - 1.0).abs() < 0.003, "{kind:?}: mean {mean}, exact 2");
    }
}

/// Light leaking under a thin wall: a floor point of the dark half near the wall's foot had
/// the lit half's floor photons, on the wall's other side, within its gather disc (same plane,
/// same side: neither the back-side test nor a stored normal can tell them apart). 16 passes of
/// 20k photons: before the footprint probes the dark half's mean was 0.012 (it is exactly 0);
/// after, 0 to five decimals. The wall's own dark face is the back-side test's (the wall has
/// zero thickness: the lit face's photons lie exactly on it and are turned away by their
/// direction), and was already 0, diffuse or glossy.
#[test]
fn no_light_leaks_under_a_thin_wall() {
    for glossy in [false, true] {
        let scene = parted_box(glossy);
        for kind in [IntegratorKind::Sppm, IntegratorKind::Pppm] {
            let mean = mean_of(&scene, &progressive(kind, 16, 20_000, 1), 32, 1);
            eprintln!("{kind:?}, glossy wall {glossy}: dark half: mean {mean:.5} (exact 0)");
            assert!(mean < 2e-4, "{kind:?}, glossy wall {glossy}: mean {mean} in the dark half, exact 0");
        }
    }
}

/// Gathers at the edges of a surface that ends (a table top, a block's top): the disc reaches
/// past the edge into empty space, where there are no photons. A sheet in the furnace seen
/// with its four edges in view, 16 passes of 5k photons (a first radius near the largest,
/// 0.17), 4 seeds: before the footprint probes, sppm's mean was -1.17 % (and with probes that
/// found walls but not the surface's end, about half of that); after, +0.23 % and +0.21 % on
/// these seeds and -0.08 % on 8 others (the spread from seed to seed here is about 0.15 %,
/// hence the bound of 0.4 %).
#[test]
fn the_edges_of_a_sheet_are_not_dark() {
    let scene = furnace_with_sheet();
    for kind in [IntegratorKind::Sppm, IntegratorKind::Pppm] {
        let mean = mean_of(&scene, &progressive(kind, 16, 5_000, 1), 32, 4);
        eprintln!("{kind:?}: sheet: mean {mean:.4} ({:+.3} %)", 100.0 * (mean / 2.0 - 1.0));
        assert!((mean / 2.0 - 1.0).abs() < 0.004, "{kind:?}: mean {mean}, exact 2");
    }
}

/// Pass-indexed passes widen their first radius where the light is flat (the pilot's choice,
/// `src/integrator/bandwidth.rs`): in the white furnace, flat everywhere, most pixels widen,
/// and the mean stays exact (corners and edges in view, where the widening must stop short of
/// the walls). 16 passes of 20k photons, 48², 2 seeds; at 8 passes it does not widen.
#[test]
fn pppm_widens_where_the_light_is_flat_without_bias() {
    let scene = furnace_view(Vec3::new(1.0, -1.0, 1.0), 60.0);
    let settings = progressive(IntegratorKind::Pppm, 16, 20_000, 1);
    let cfg = scene.render.overridden_by(&settings).resolve(48, 48).unwrap();
    let out = render_scene(&scene, &cfg, &Quiet).unwrap();
    let widening = out.stats.widening.expect("pppm reports its widening");
    eprintln!("{widening:?}");
    assert!(widening.pixels > 1000, "{widening:?}");
    assert!(widening.mean > 1.3, "{widening:?}");
    // A short render (under 16 passes) does not pay for the measuring.
    let short =
        scene.render.overridden_by(&progressive(IntegratorKind::Pppm, 8, 20_000, 1)).resolve(48, 48).unwrap();
    assert_eq!(render_scene(&scene, &short, &Quiet).unwrap().stats.widening, None);
    let mean = mean_of(&scene, &settings, 48, 2);
    eprintln!("pppm, widened: mean {mean:.4} ({:+.3} %)", 100.0 * (mean / 2.0 - 1.0));
    assert!((mean / 2.0 - 1.0).abs() < 0.003, "mean {mean}, exact 2");
}

/// The furnace with what an atrium has (`scenes/atrium`): a fluted column floor to ceiling
/// (48 flat sides, 16 shallow flutes: facets tilted up to about 25° from the column's round
/// surface), a beam under the ceiling and a row of thin balusters on the floor, all of the
/// furnace's material (2 everywhere), seen across the column.
fn furnace_with_column() -> Scene {
    let mut b = Builder::default();
    let m = furnace_material(&mut b);
    b.cuboid(-Vec3::ONE, Vec3::ONE, Facing::Inward, m);
    let (centre, radius, sides) = (Vec3::new(0.35, 0.0, 0.55), 0.15f32, 48);
    let at = |k: usize, y: f32| {
        let a = std::f32::consts::TAU * k as f32 / sides as f32;
        let r = radius * (1.0 - 0.03 * (1.0 + (16.0 * a).cos()));
        Vec3::new(centre.x + r * a.cos(), y, centre.z + r * a.sin())
    };
    for k in 0..sides {
        let (a0, a1) = (at(k, -1.0), at(k + 1, -1.0));
        let (b0, b1) = (at(k, 1.0), at(k + 1, 1.0));
        b.triangle(a1, a0, b0, m);
        b.triangle(a1, b0, b1, m);
    }
    b.cuboid(Vec3::new(-1.0, 0.7, 0.75), Vec3::new(1.0, 1.0, 0.9), Facing::Outward, m);
    for k in 0..8 {
        let x = -0.7 + 0.12 * k as f32;
        b.cuboid(Vec3::new(x - 0.025, -1.0, 0.8), Vec3::new(x + 0.025, -0.4, 0.85), Facing::Outward, m);
    }
    b.build("furnace-column", camera(Vec3::new(-0.3, 0.0, -0.6), Vec3::new(0.3, 0.0, 1.0), Vec3::Y, 80.0))
}

/// Two-pass photon mapping's indirect estimates (the precomputed irradiance's sites, and
/// gathers at camera hits without it) count photons over the footprint of their disc, as the
/// progressive modes do: over the whole disc, flattened 8 times along the facet's normal, the
/// column's tilted facets cut its surface short, and the beam's and balusters' edges and
/// corners were dark. The furnace with a column, 40k photons, 4 spp, 48², 4 seeds: before,
/// the mean was -2.0 % with the irradiance cache and -2.3 % without (-0.8 % at the defaults
/// at 256²); after, -0.35 % and -0.16 % with Embree, -0.51 % and -0.30 % with the BVH (the
/// probes meet the column's foot a little differently; the sites probe 1.5 times wider than
/// their disc, which costs a little at the balusters' narrow faces). The sites, where the
/// camera reads precomputed irradiance, are traced apart from the map: at the map's own
/// photons their estimates were about +1 % bright (each counted its own photon), which the
/// edges' shortfall had hidden.
#[test]
fn two_pass_gathers_are_not_dark_at_edges_and_on_columns() {
    let scene = furnace_with_column();
    for cache in [true, false] {
        let settings = RenderSettings {
            photons: Some(40_000),
            spp: Some(4),
            irradiance_cache: Some(cache),
            ..Default::default()
        };
        let mean = mean_of(&scene, &settings, 48, 4);
        eprintln!("two-pass, cache {cache}: column: mean {mean:.4} ({:+.3} %)", 100.0 * (mean / 2.0 - 1.0));
        assert!((mean / 2.0 - 1.0).abs() < 0.008, "cache {cache}: mean {mean}, exact 2");
    }
}

/// The furnace with a column, rendered by pass-indexed progressive photon mapping: the fluted
/// column's facets, tilted every way, bias its gathers little where every facet gets the same
/// light (an atrium's column lit from one side is another matter: docs/accuracy.md).
#[test]
fn pppm_on_a_fluted_column_in_the_furnace() {
    let scene = furnace_with_column();
    for photons in [5_000, 40_000] {
        let settings = RenderSettings { spp: Some(2), ..progressive(IntegratorKind::Pppm, 16, photons, 1) };
        let mean = mean_of(&scene, &settings, 48, 2);
        eprintln!(
            "pppm, {photons} photons a pass: column: mean {mean:.4} ({:+.3} %)",
            100.0 * (mean / 2.0 - 1.0)
        );
        assert!((mean / 2.0 - 1.0).abs() < 0.005, "{photons} photons: mean {mean}, exact 2");
    }
}
