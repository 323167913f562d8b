//! Embree against the BVH (and both against brute force where affordable) on the shipped scenes,
//! on the Cornell box at extreme scales and offsets, on a large procedural mesh, and on slivers
//! and degenerate triangles. `tests/agree_bvh.rs` covers the BVH against brute force alone.
//!
//! Every comparison must be free of hit/miss, primitive and occlusion disagreements: the only
//! differences allowed are edge/coplanar ties as classified by [`photonmap::tools::agree::classify`].
//! Ties are bounded per case (see [`Limits`]), and so is the relative distance error on camera
//! rays. Without the `embree` feature the same cases run the BVH against brute force.
//!
//! With the `embree` feature on, failing to build Embree fails the tests; nothing is skipped.

use photonmap::accel::{Accel, AccelKind, AccelOptions, AnyAccel};
use photonmap::geometry::{Ray, TriangleMesh, Vec3};
use photonmap::scene::Scene;
use photonmap::tools::agree::{
    agree_scene, classify_ray, compare, generate_rays, AgreeReport, CameraLike, RayKind, Verdict,
};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;
use std::path::{Path, PathBuf};

fn manifest_dir() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// What a comparison may show beyond exact agreement.
#[derive(Clone, Copy, Debug)]
struct Limits {
    /// Largest fraction of the rays counted as edge/coplanar ties.
    tie_fraction: f64,
    /// Largest relative distance difference on camera rays hitting the same triangle.
    camera_rel_dt: f64,
}

/// For ordinary scenes. A tie needs a hit within `TIE_ULPS` (64) ULPs of the coordinates' magnitude
/// (or barycentric 1e-5) of an edge *and* the two watertight-style tests rounding to different
/// sides of it. For rays spread over a scene with triangle edges of length ~L that band covers
/// about 64·2⁻²³·|x|/L ≈ 1e-5 of the surface per edge crossing, so 1% is a generous ceiling that
/// still catches any systematic edge error (a backend missing a whole class of edges would
/// exceed it). Camera rays are straight from a fixed eye: both backends compute `t` from the
/// same inputs to a few ULPs, so 1e-5 relative is already 80 ULPs.
const ORDINARY: Limits = Limits { tie_fraction: 0.01, camera_rel_dt: 1e-5 };

/// For rays that all hit needles of the fan, 1e-6 rad wide. At the hit the needle is at most
/// 0.45e-6 wide, below the tie band (64 ULPs of coordinates ~0.6 is 4.6e-6), so *every* hit is
/// near an edge by definition; two tests differ where their edge functions (rounding ~1e-7
/// relative, ~3e-8 absolute here) round to different sides of a shared edge, about
/// 3e-8 / 2.5e-7 ≈ 10% of rays at most. 5% leaves room over the measured ~1.2% while still
/// catching a backend that misses or mislabels needles wholesale.
const NEEDLES: Limits = Limits { tie_fraction: 0.05, camera_rel_dt: 1e-5 };

/// The first ray on which `a` and `b` really disagree (closest hit not a tie, or occlusion),
/// for the failure message.
fn first_disagreement(a: &dyn Accel, b: &dyn Accel, rays: &[(RayKind, Ray)], mesh: &TriangleMesh) -> String {
    for (kind, ray) in rays {
        let (ha, hb) = (a.intersect(ray), b.intersect(ray));
        let verdict = classify_ray(mesh, Some(ray), ha, hb);
        let (oa, ob) = (a.occluded(ray), b.occluded(ray));
        if matches!(verdict, Verdict::HitMiss | Verdict::Primitive) || oa != ob {
            return format!(
                "first disagreement ({kind:?}): {ray:?}\n  {}: {ha:?} occluded={oa}\n  {}: {hb:?} occluded={ob}",
                a.name(),
                b.name()
            );
        }
    }
    "no disagreeing ray found on re-run".into()
}

/// Prints one summary line and checks the report against `limits`.
fn check_report(case: &str, r: &AgreeReport, limits: Limits, culprit: impl FnOnce() -> String) {
    let camera = r.per_kind.get(&RayKind::Camera).copied().unwrap_or_default();
    let tie_fraction = r.edge_ties as f64 / r.rays.max(1) as f64;
    eprintln!(
        "agree {case:<26} {:>14} rays {:>6} hit/miss {} prim {} occl {} ties {:>4} ({:.4}%) max_rel_dt {:.2e} camera {:.2e}",
        r.backends.join("-"),
        r.rays,
        r.hit_miss_disagreements,
        r.primitive_disagreements,
        r.occlusion_disagreements,
        r.edge_ties,
        100.0 * tie_fraction,
        r.max_rel_dt,
        camera.max_rel_dt,
    );
    if !r.clean() {
        panic!("{case}: real disagreements\n{r}\n{}", culprit());
    }
    assert!(
        tie_fraction <= limits.tie_fraction,
        "{case}: {} edge ties of {} rays exceed {:.3}%\n{r}",
        r.edge_ties,
        r.rays,
        100.0 * limits.tie_fraction
    );
    assert!(
        camera.max_rel_dt <= limits.camera_rel_dt,
        "{case}: camera max_rel_dt {:.3e} > {:.1e}\n{r}",
        camera.max_rel_dt,
        limits.camera_rel_dt
    );
    assert!(r.max_rel_dt.is_finite(), "{case}\n{r}");
}

/// Builds `kind` over `mesh`. With the `embree` feature a failed Embree build panics: the test
/// fails rather than silently comparing fewer backends.
fn build(kind: AccelKind, mesh: &TriangleMesh) -> AnyAccel {
    match AnyAccel::build(kind, mesh, None, AccelOptions::default()) {
        Ok(a) => a,
        Err(e) => panic!("building {kind:?} over {} triangles failed: {e}", mesh.len()),
    }
}

fn as_dyn(a: &AnyAccel) -> &dyn Accel {
    photonmap::dispatch!(a, x => x as &dyn Accel)
}

/// The backends compared on a mesh: Embree and the BVH when built with Embree, else the BVH
/// alone; brute force joins as the reference when `with_naive`.
fn backends(mesh: &TriangleMesh, with_naive: bool) -> Vec<AnyAccel> {
    let mut out = Vec::new();
    if cfg!(feature = "embree") {
        out.push(build(AccelKind::Embree, mesh));
    }
    out.push(build(AccelKind::Bvh, mesh));
    if with_naive {
        out.push(build(AccelKind::Naive, mesh));
    }
    out
}

/// Compares every pair of backends over `n` generated rays and checks each report.
fn check_mesh(
    case: &str,
    mesh: &TriangleMesh,
    camera: Option<CameraLike>,
    n: usize,
    with_naive: bool,
    limits: Limits,
) -> Vec<AgreeReport> {
    let rays = generate_rays(mesh, camera, n, 0xa9ee ^ mesh.len() as u64);
    check_rays(case, mesh, &rays, with_naive, limits)
}

/// Compares every pair of backends over `rays` and checks each report.
fn check_rays(
    case: &str,
    mesh: &TriangleMesh,
    rays: &[(RayKind, Ray)],
    with_naive: bool,
    limits: Limits,
) -> Vec<AgreeReport> {
    let accels = backends(mesh, with_naive);
    assert!(accels.len() >= 2, "{case}: need two backends (brute force off without Embree?)");
    let mut reports = Vec::new();
    for i in 0..accels.len() {
        for j in i + 1..accels.len() {
            let (a, b) = (as_dyn(&accels[i]), as_dyn(&accels[j]));
            let r = compare(a, b, rays, mesh);
            check_report(case, &r, limits, || first_disagreement(a, b, rays, mesh));
            reports.push(r);
        }
    }
    reports
}

/// The scene files under `scenes/*/*.toml`, sorted.
fn scene_files() -> Vec<PathBuf> {
    let mut out = Vec::new();
    for dir in std::fs::read_dir(manifest_dir().join("scenes")).expect("scenes/") {
        let dir = dir.expect("scenes/ entry").path();
        if !dir.is_dir() {
            continue;
        }
        for f in std::fs::read_dir(&dir).expect("scene directory") {
            let f = f.expect("scene directory entry").path();
            if f.extension().is_some_and(|e| e == "toml") {
                out.push(f);
            }
        }
    }
    out.sort();
    out
}

/// `agree_scene` on a loaded scene: Embree vs BVH (BVH vs brute force without Embree), and each
/// against brute force when the scene is within `NAIVE_BUDGET`.
fn check_scene(case: &str, scene: &Scene, n: usize, limits: Limits) {
    let result = agree_scene(scene, n, 0x5ce7e ^ scene.mesh.len() as u64, AccelOptions::default());
    let agreement = result.unwrap_or_else(|e| panic!("{case}: building the backends failed: {e}"));
    // On a failure, re-run the pair to name the ray.
    let culprit = |names: &[String]| {
        let names = names.to_vec();
        move || {
            let mesh = &scene.mesh;
            let eye = scene.camera.eye;
            let cam = CameraLike { eye, target: eye + scene.camera.forward };
            let rays = generate_rays(mesh, Some(cam), n, 0x5ce7e ^ mesh.len() as u64);
            let kind = |s: &str| match s {
                "embree" => AccelKind::Embree,
                "bvh" => AccelKind::Bvh,
                _ => AccelKind::Naive,
            };
            let (a, b) = (build(kind(&names[0]), mesh), build(kind(&names[1]), mesh));
            first_disagreement(as_dyn(&a), as_dyn(&b), &rays, mesh)
        }
    };
    check_report(case, &agreement.main, limits, culprit(&agreement.main.backends));
    for r in &agreement.against_naive {
        check_report(case, r, limits, culprit(&r.backends));
    }
    let with_naive = scene.mesh.len() as u64 * n as u64 <= photonmap::tools::agree::NAIVE_BUDGET;
    if cfg!(feature = "embree") && with_naive {
        assert_eq!(agreement.against_naive.len(), 2, "{case}: brute force should have joined");
    }
}

#[test]
fn embree_is_built_when_enabled() {
    let tri = TriangleMesh { positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y], indices: vec![[0, 1, 2]] };
    let r = AnyAccel::build(AccelKind::Embree, &tri, None, AccelOptions::default());
    if cfg!(feature = "embree") {
        let a = r.unwrap_or_else(|e| panic!("the `embree` feature is on but Embree cannot be built: {e}"));
        assert_eq!(a.name(), "embree");
        let hit = as_dyn(&a).intersect(&Ray::new(Vec3::new(0.25, 0.25, 1.0), -Vec3::Z));
        assert!(hit.is_some_and(|h| h.prim == 0 && (h.t - 1.0).abs() < 1e-6), "{hit:?}");
    } else {
        assert!(r.is_err(), "no Embree without the feature");
    }
}

#[test]
fn shipped_scenes_agree() {
    let files = scene_files();
    assert!(files.len() >= 4, "expected the shipped scenes, found {files:?}");
    for f in &files {
        let scene = Scene::load(f).unwrap_or_else(|e| panic!("{}: {e}", f.display()));
        let name = f.file_stem().unwrap().to_string_lossy();
        check_scene(&name, &scene, 30_000, ORDINARY);
    }
}

/// The Cornell box scene with its mesh scaled by `scale` then translated by `translate`, the
/// camera moved with it, loaded from a TOML file written to a temporary directory that
/// references `scenes/cornell/cornell.obj` by absolute path.
fn cornell_transformed(scale: f32, translate: [f32; 3]) -> Scene {
    let dir = manifest_dir().join("scenes/cornell");
    let text = std::fs::read_to_string(dir.join("cornell.toml")).expect("cornell.toml");
    let mut doc: toml::Table = text.parse().expect("cornell.toml parses");
    let t = Vec3::from(translate);
    let camera = doc["camera"].as_table_mut().expect("[camera]");
    for key in ["eye", "target"] {
        let p: Vec<f32> =
            camera[key].as_array().unwrap().iter().map(|v| v.as_float().unwrap() as f32).collect();
        let q = Vec3::from_slice(&p) * scale + t;
        camera[key] =
            toml::Value::Array(q.to_array().iter().map(|&x| toml::Value::Float(x as f64)).collect());
    }
    let meshes = doc["mesh"].as_array_mut().expect("[[mesh]]");
    for m in meshes {
        let m = m.as_table_mut().unwrap();
        let obj = dir.join(m["obj"].as_str().unwrap());
        m.insert("obj".into(), toml::Value::String(obj.to_str().unwrap().into()));
        m.insert("scale".into(), toml::Value::Float(scale as f64));
        m.insert(
            "translate".into(),
            toml::Value::Array(translate.iter().map(|&x| toml::Value::Float(x as f64)).collect()),
        );
    }
    let tmp = tempfile::tempdir().expect("tempdir");
    let path = tmp.path().join("cornell_transformed.toml");
    std::fs::write(&path, toml::to_string(&doc).unwrap()).unwrap();
    Scene::load(&path).unwrap_or_else(|e| panic!("scaled Cornell ({scale}, {translate:?}): {e}"))
}

/// Loads the transformed Cornell box, checks the transform was applied, and compares.
fn check_cornell(case: &str, scale: f32, translate: [f32; 3]) {
    let base = Scene::load(manifest_dir().join("scenes/cornell/cornell.toml")).unwrap();
    let scene = cornell_transformed(scale, translate);
    assert_eq!(scene.mesh.len(), base.mesh.len());
    for (p, q) in base.mesh.positions.iter().zip(&scene.mesh.positions) {
        let expect = *p * scale + Vec3::from(translate);
        assert!((*q - expect).length() <= 1e-6 * expect.length().max(1e-3), "{case}: {q} != {expect}");
    }
    check_scene(case, &scene, 30_000, ORDINARY);
}

#[test]
fn cornell_scaled_1e_minus_3_agrees() {
    check_cornell("cornell x1e-3", 1e-3, [0.0; 3]);
}

// At 1e4 the watertight test's t has an absolute error of ~eps |vertex - origin| (~5e-4):
// ray origins must leave surfaces by more than that, which the pbrt-style offsets (error bound,
// floored at gamma(7) max|p|) guarantee. A fixed or near-zero-absolute offset failed here.
#[test]
fn cornell_scaled_1e4_agrees() {
    check_cornell("cornell x1e4", 1e4, [0.0; 3]);
}

// At 1e5 coordinates are quantised to 1/128: some random-ray origins round exactly onto a
// wall, where hitting it or not is decided by rounding (`compare` counts such rays as ties).
// The edge-tie band (64 ULPs = 0.78 m) then exceeds the box, so closest-hit differences are all
// ties too.
#[test]
fn cornell_translated_1e5_agrees() {
    check_cornell("cornell +1e5", 1.0, [1e5, 1e5, 1e5]);
}

/// A closed sphere of `rings` × `segments` quads with a bumpy radius (three octaves of
/// sinusoids), about `2 * rings * segments` triangles.
fn noisy_sphere(centre: Vec3, r: f32, rings: u32, segments: u32) -> TriangleMesh {
    let radius = |theta: f32, phi: f32| {
        r * (1.0
            + 0.08 * (5.0 * theta).sin() * (3.0 * phi).cos()
            + 0.03 * (17.0 * theta + 1.0).sin() * (11.0 * phi).sin()
            + 0.01 * (61.0 * theta).cos() * (47.0 * phi + 2.0).sin())
    };
    TriangleMesh::parametric_sphere(rings, segments, |theta, phi| {
        centre + radius(theta, phi) * Vec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos())
    })
}

#[test]
fn large_procedural_mesh_agrees() {
    let m = noisy_sphere(Vec3::new(3.0, -1.0, 2.0), 2.0, 400, 640);
    assert!(m.len() >= 500_000, "{} triangles", m.len());
    // A camera inside the sphere as well as the default one outside.
    let inside = CameraLike { eye: Vec3::new(3.2, -0.9, 2.1), target: Vec3::new(5.0, 0.0, 2.0) };
    if cfg!(feature = "embree") {
        check_mesh("noisy sphere 512k", &m, None, 20_000, false, ORDINARY);
        check_mesh("noisy sphere 512k inside", &m, Some(inside), 5_000, false, ORDINARY);
    } else {
        // Brute force is O(n) per ray: a few hundred rays only.
        check_mesh("noisy sphere 512k", &m, None, 300, true, ORDINARY);
    }
}

/// A wavy `n` × `n` grid whose quads are fans around a point 1e-6 of the diagonal from one
/// corner (two ordinary triangles and two needles with edge ratio ~1e6 per quad), plus
/// zero-area triangles (repeated vertices, exactly collinear corners, a single point), thin
/// slivers (height 1e-6 of their length) standing across the surface, and a fan of 2000 needles
/// of 1e-6 rad each (ratio 1e6) filling a narrow wedge. Returns the mesh and the wedge's apex
/// and a point on its bisector, for aiming camera rays.
fn slivers_and_degenerates(n: u32, seed: u64) -> (TriangleMesh, Vec3, Vec3) {
    let mut rng = Pcg64::seed_from_u64(seed);
    let h = |x: f32, y: f32| 0.15 * (3.0 * x).sin() * (2.0 * y + 0.5).cos();
    let p = |x: f32, y: f32| Vec3::new(x, y, h(x, y));
    let mut m = TriangleMesh::default();
    let d = 1.0 / n as f32;
    let grid = |i: u32, j: u32| i * (n + 1) + j;
    for i in 0..=n {
        for j in 0..=n {
            m.positions.push(p(i as f32 * d, j as f32 * d));
        }
    }
    for i in 0..n {
        for j in 0..n {
            let (p00, p10, p11, p01) = (grid(i, j), grid(i + 1, j), grid(i + 1, j + 1), grid(i, j + 1));
            let (a, c) = (m.positions[p00 as usize], m.positions[p11 as usize]);
            let mid = m.positions.len() as u32;
            m.positions.push(a.lerp(c, 1.0 - 1e-6));
            // Two ordinary triangles from p00 and two needles at p11.
            m.indices.extend([[p00, p10, mid], [mid, p10, p11], [p00, mid, p01], [mid, p11, p01]]);
            // Zero area: repeated corners, a single point.
            m.indices.push([p00, p00, p10]);
            m.indices.push([p11, p01, p11]);
            m.indices.push([mid, mid, mid]);
            if (i + j) % 3 == 0 {
                // Exactly collinear corners (constant y and z), just above the surface.
                let z = h(i as f32 * d, j as f32 * d) + 0.01;
                let (x, y) = (i as f32 * d, j as f32 * d);
                let k = m.positions.len() as u32;
                m.positions.extend([
                    Vec3::new(x, y, z),
                    Vec3::new(x + 0.5 * d, y, z),
                    Vec3::new(x + d, y, z),
                ]);
                m.indices.extend([[k, k + 1, k + 2], [k + 2, k, k + 1]]);
            }
            if (i * 7 + j) % 5 == 0 {
                // A vertical sliver: base of length ~d, apex 1e-6 d off the base line.
                let base = p((i as f32 + rng.gen::<f32>()) * d, (j as f32 + rng.gen::<f32>()) * d);
                let dir =
                    Vec3::new(rng.gen::<f32>() - 0.5, rng.gen::<f32>() - 0.5, 0.0).normalize_or(Vec3::X);
                let k = m.positions.len() as u32;
                let b = base + dir * d + Vec3::Z * 0.02;
                let apex = base.lerp(b, 0.5) + Vec3::Z * (1e-6 * d);
                m.positions.extend([base + Vec3::Z * 0.02, b, apex]);
                m.indices.push([k, k + 1, k + 2]);
            }
        }
    }
    // A fan of needles above the grid: apex c, 2000 triangles of 1e-6 rad, radius 0.5.
    let c = Vec3::new(0.1, 0.2, 0.5);
    let k0 = m.positions.len() as u32;
    m.positions.push(c);
    let (steps, dphi) = (2000u32, 1e-6f32);
    for s in 0..=steps {
        let phi = 0.3 + s as f32 * dphi;
        m.positions.push(c + 0.5 * Vec3::new(phi.cos(), phi.sin(), 0.0));
    }
    for s in 0..steps {
        m.indices.push([k0, k0 + 1 + s, k0 + 2 + s]);
    }
    let bisector = 0.3 + 0.5 * steps as f32 * dphi;
    let aim = c + 0.3 * Vec3::new(bisector.cos(), bisector.sin(), 0.0);
    (m, c, aim)
}

// A ray leaving a needle of the fan must not hit the needle's own plane again (it did, with an
// offset that ignored the coordinates' magnitude).
#[test]
fn slivers_and_degenerates_agree() {
    let (m, _, _) = slivers_and_degenerates(24, 11);
    let degenerate = (0..m.len() as u32).filter(|&i| m.normal(i).is_none()).count();
    let needles = (0..m.len() as u32)
        .filter(|&i| {
            let [a, b, c] = m.triangle(i);
            let l = [(b - a).length(), (c - b).length(), (a - c).length()];
            let (lo, hi) =
                (l.iter().copied().fold(f32::MAX, f32::min), l.iter().copied().fold(0.0, f32::max));
            lo > 0.0 && hi / lo > 1e5
        })
        .count();
    eprintln!("slivers: {} triangles, {degenerate} zero-area, {needles} needles", m.len());
    assert!(degenerate > 1000 && needles > 3000);
    check_mesh("slivers", &m, None, 20_000, true, ORDINARY);
}

#[test]
fn needle_fan_agrees() {
    let (m, apex, aim) = slivers_and_degenerates(24, 11);
    // Rays from one eye above the needle fan to random points of its wedge: every one hits a
    // needle (or passes between two along a shared edge).
    let eye = aim + Vec3::new(0.05, -0.03, 0.7);
    let mut rng = Pcg64::seed_from_u64(5);
    let rays: Vec<(RayKind, Ray)> = (0..5_000)
        .map(|_| {
            let phi = 0.3 + rng.gen::<f32>() * 2000.0 * 1e-6;
            let r = 0.05 + 0.4 * rng.gen::<f32>();
            let target = apex + r * Vec3::new(phi.cos(), phi.sin(), 0.0);
            (RayKind::Camera, Ray::new(eye, target - eye))
        })
        .collect();
    check_rays("needle fan", &m, &rays, true, NEEDLES);
}
