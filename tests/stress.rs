//! The stress suite (`photonmap::tools::stress`, also `photonmap stress`): every case on
//! every backend, in its quick form (fewer samples and photons; the same scenes, bounds and
//! agreement checks), and every row must pass. Also: Embree gives the same hits on the same
//! rays in two runs (the thread-count determinism of the renders is in `tests/accuracy.rs`,
//! `tests/path_tracer.rs` and `tests/progressive.rs`).

use photonmap::tools::stress::{self, StressOptions};

/// Runs the case called `name` and fails with the table of its rows if any fails.
fn check(name: &str) {
    let opts = StressOptions { quick: true, ..Default::default() };
    let case = stress::cases().into_iter().find(|c| c.name == name).expect("no such case");
    let rows = case.run(&opts);
    let table: Vec<String> = rows.iter().map(stress::table_row).collect();
    eprintln!("{}\n{}", stress::table_header(), table.join("\n"));
    assert!(!rows.is_empty(), "{name}: no rows");
    let failed: Vec<&String> = rows.iter().zip(&table).filter(|(r, _)| !r.pass).map(|(_, t)| t).collect();
    assert!(
        failed.is_empty(),
        "{name}: failed rows:\n{}",
        failed.iter().map(|s| s.as_str()).collect::<Vec<_>>().join("\n")
    );
}

#[test]
fn furnace_at_every_scale() {
    check("furnace");
}

#[test]
fn glass_at_the_default_depth() {
    check("glass-furnace");
}

#[test]
fn grazing_light() {
    check("grazing");
}

#[test]
fn coplanar_quads() {
    check("coplanar");
}

#[test]
fn touching_boxes() {
    check("touching");
}

#[test]
fn camera_inside_geometry() {
    check("camera-inside");
}

#[test]
fn light_inside_a_closed_object() {
    check("light-inside");
}

#[test]
fn back_facing_area_light() {
    check("back-facing");
}

#[test]
fn tiny_and_huge_light_power() {
    check("power");
}

#[test]
fn a_million_photons_on_one_point() {
    check("duplicates");
}

#[test]
fn zero_photons_stored() {
    check("zero-photons");
}

#[test]
fn one_triangle() {
    check("one-triangle");
}

#[test]
fn a_million_slivers() {
    check("slivers");
}

/// Every case is covered by a test above.
#[test]
fn every_case_is_tested() {
    let tested = [
        "furnace",
        "glass-furnace",
        "grazing",
        "coplanar",
        "touching",
        "camera-inside",
        "light-inside",
        "back-facing",
        "power",
        "duplicates",
        "zero-photons",
        "one-triangle",
        "slivers",
    ];
    let names: Vec<&str> = stress::cases().iter().map(|c| c.name).collect();
    assert_eq!(names, tested);
}

/// Regression (found by the `power` and `furnace x1e-4` cases): RGB9E5 covers about 2⁻²⁴ to
/// 2¹⁶, and photon powers outside it were flushed to 0 (light power 10⁻¹², or a scene scaled by
/// 10⁻⁴, lost its indirect light) or saturated (10¹²). Maps and the irradiance cache now pack
/// powers over a power-of-two scale, so the estimates scale with the light.
#[test]
fn photon_and_cache_powers_of_any_magnitude_scale_linearly() {
    use photonmap::config::Kernel;
    use photonmap::geometry::Vec3;
    use photonmap::photon::irradiance::{
        pick_sites, LookupScratch, PrecomputedIrradiance, SitePoint, SiteSource,
    };
    use photonmap::photon::map::{GatherParams, Hits, MapColor, PhotonHit, PhotonMap};
    let estimate = |k: f32| {
        let n = 100;
        let hits: Vec<PhotonHit> = (0..n * n)
            .map(|i| PhotonHit {
                pos: Vec3::new((i % n) as f32 / n as f32, 0.0, (i / n) as f32 / n as f32),
                n: Vec3::Y,
                err: Vec3::ZERO,
                wi: Vec3::Y,
                power: Vec3::new(1.0, 0.5, 0.25) * (k * 1e-4),
            })
            .collect();
        let sites = pick_sites(&[Hits::from(hits.clone())], 4);
        let map = PhotonMap::build(hits, MapColor::Rgb, (n * n) as u64);
        let params = GatherParams { k: 50, max_radius: 0.2, kernel: Kernel::Box, flatten: 8.0 };
        let cache = PrecomputedIrradiance::new(sites, params.max_radius, true);
        let direct = |_: usize, _: &SitePoint| Vec3::splat(k);
        let source = SiteSource {
            indirect: std::slice::from_ref(&map),
            caustic: &[],
            gather: &params,
            caustic_gather: &params,
            direct: Some(&direct),
            probe: None,
        };
        let cache = cache.sites(source);
        let x = Vec3::new(0.5, 0.0, 0.5);
        let mut scratch = Vec::new();
        let e = map.irradiance(x, Vec3::Y, &params, &mut scratch);
        let site = cache.lookup(x, Vec3::Y, &mut LookupScratch::default()).expect("a site");
        (e, site.indirect, site.direct)
    };
    let (e1, c1, d1) = estimate(1.0);
    assert!(e1.x > 0.5 && c1.x > 0.5, "{e1} {c1}");
    for k in [1e-12f32, 1e12] {
        let (e, c, d) = estimate(k);
        for (got, base) in [(e, e1), (c, c1), (d, d1)] {
            let dev = (got - base * k).abs().max_element() / (k * base.max_element());
            assert!(dev <= 2f32.powi(-8), "power x{k:e}: {got} vs {} ({dev:e})", base * k);
        }
    }
}

/// Regression (found by the `furnace +1e5` case): shadow rays stopped a fixed fraction (10⁻⁴)
/// short of the sampled point on an area light, but 10⁵ from the origin that point is rounded
/// by more than that, so rays hit the emitter itself and the furnace lost 11 % of its direct
/// light (0.445 instead of 0.5). They now stop short by the point's error bound too. Checked
/// on the furnace left at 10⁵ (the renderer itself would move it to the origin first): inside
/// the closed cube nothing should block a shadow ray. A few still are: where the sampled point
/// lies at an edge, its rounding can put it outside the neighbouring wall (measured: 30 of
/// 16557, against 4416 with the fixed margin alone).
#[test]
fn shadow_rays_do_not_hit_the_light_they_aim_at_far_from_the_origin() {
    use photonmap::accel::{bvh::Bvh, Accel};
    use photonmap::frame::direct::SHADOW_MARGIN;
    use photonmap::geometry::{offset_ray_origin, Ray, Vec3};
    use photonmap::light::area_lights;
    use rand::{Rng, SeedableRng};
    let scene = stress::scenes::furnace(1.0, Vec3::splat(1e5));
    let bvh = Bvh::build(&scene.mesh);
    let lights = area_lights(&scene.mesh, &scene.tri_material, &scene.materials);
    let mut rng = rand_pcg::Pcg64::seed_from_u64(3);
    let (mut tried, mut blocked, mut blocked_before) = (0, 0, 0);
    for _ in 0..20_000 {
        let prim = rng.gen_range(0..scene.mesh.len() as u32);
        let (r1, r2) = (rng.gen::<f32>().sqrt(), rng.gen::<f32>());
        let (p, err) = scene.mesh.point_and_error(prim, r1 * (1.0 - r2), r1 * r2);
        let n = scene.mesh.normal(prim).unwrap();
        let Some(ls) = lights.sample_li(p, [rng.gen(), rng.gen()]) else { continue };
        if ls.wi.dot(n) <= 0.0 {
            continue;
        }
        tried += 1;
        let origin = offset_ray_origin(p, err, n);
        let t_max = (ls.dist - ls.end_error).max(0.0) * (1.0 - SHADOW_MARGIN);
        blocked += usize::from(bvh.occluded(&Ray::segment(origin, ls.wi, 0.0, t_max)));
        let t_before = ls.dist * (1.0 - SHADOW_MARGIN);
        blocked_before += usize::from(bvh.occluded(&Ray::segment(origin, ls.wi, 0.0, t_before)));
    }
    eprintln!("{blocked} of {tried} shadow rays blocked ({blocked_before} with the fixed margin alone)");
    assert!(tried > 10_000, "{tried}");
    assert!(blocked * 200 <= tried, "{blocked} of {tried} shadow rays blocked inside the furnace");
}

/// Regression (found by the `furnace +1e5` case): 10⁵ from the origin the conservative ray
/// offsets are 4 cm and left strips along the furnace's edges dark (mean 1.978 instead of 2).
/// A scene far from the origin is now rendered moved onto it, and looks as it does there.
#[test]
fn furnace_far_from_the_origin_renders_as_at_the_origin() {
    use photonmap::config::RenderSettings;
    use photonmap::frame::Quiet;
    use photonmap::geometry::Vec3;
    use photonmap::integrator::render_scene;
    let settings = RenderSettings { spp: Some(8), photons: Some(20_000), ..Default::default() };
    let mean = |offset: f32| {
        let scene = stress::scenes::furnace(1.0, Vec3::splat(offset));
        let cfg = scene.render.overridden_by(&settings).resolve(16, 16).unwrap();
        render_scene(&scene, &cfg, &Quiet).unwrap().film.mean()
    };
    let (near, far) = (mean(0.0), mean(1e5));
    assert!((far - near).abs() < 0.002, "at the origin {near}, 1e5 away {far}");
}

/// Embree answers the same rays the same way in two runs (two builds of the same mesh, single
/// rays and packets), so renders with Embree repeat bit for bit.
#[cfg(feature = "embree")]
#[test]
fn embree_gives_the_same_hits_on_the_same_rays_every_run() {
    use photonmap::accel::embree::EmbreeAccel;
    use photonmap::accel::{Accel, AccelKind, AccelOptions};
    use photonmap::config::RenderSettings;
    use photonmap::frame::Quiet;
    use photonmap::geometry::Ray;
    use photonmap::integrator::render_scene;
    use photonmap::tools::agree::generate_rays;
    let scene = stress::scenes::furnace(1.0, photonmap::geometry::Vec3::splat(1e5));
    let mesh = photonmap::geometry::TriangleMesh::parametric_sphere(64, 128, |t, p| {
        photonmap::geometry::Vec3::new(t.sin() * p.cos(), t.cos(), t.sin() * p.sin())
            * (1.0 + 0.1 * (7.0 * p).sin())
    });
    let rays: Vec<Ray> = generate_rays(&mesh, None, 20_000, 5).into_iter().map(|(_, r)| r).collect();
    let cast = || {
        let a = EmbreeAccel::build(&mesh, AccelOptions::default()).unwrap();
        let single: Vec<_> = rays.iter().map(|r| (a.intersect(r), a.occluded(r))).collect();
        let mut batch = vec![None; rays.len()];
        a.intersect_batch(&rays, &mut batch);
        (single, batch)
    };
    let (s1, b1) = cast();
    let (s2, b2) = cast();
    assert!(s1.iter().any(|(h, _)| h.is_some()));
    assert_eq!(s1, s2, "single rays differ between runs");
    assert_eq!(b1, b2, "packets differ between runs");
    let settings = RenderSettings {
        spp: Some(4),
        photons: Some(5000),
        accel: Some(AccelKind::Embree),
        ..Default::default()
    };
    let cfg = scene.render.overridden_by(&settings).resolve(16, 16).unwrap();
    let render = || render_scene(&scene, &cfg, &Quiet).unwrap().film;
    assert_eq!(render(), render(), "two Embree renders differ");
}
