//! Alpha cut-outs through every backend: Embree (intersection filters on a second geometry),
//! the BVH and brute force (the same test after their triangle tests) give the same hits on
//! random rays of every kind against meshes with cut-outs, compared by the agreement machinery
//! (`compare_with_cutouts`: a ray crossing a cut-out within rounding of where its opacity flips
//! is a tie, as one passing at a triangle's edge is). A cut-out that is opaque everywhere
//! changes no answer, and one transparent everywhere is as if its triangles were not there.

use photonmap::accel::{Accel, AccelKind, AccelOptions, AnyAccel, Cutouts, Opacity};
use photonmap::geometry::{Ray, TriangleMesh, Vec3};
use photonmap::tools::agree::{
    classify_ray, compare_with_cutouts, generate_rays, CameraLike, RayKind, Verdict,
};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;
use std::sync::Arc;

/// `layers` parallel fences (planes `z = k d`), each a grid of `n × n` quads, behind each other
/// as seen from `+z`, with some random triangles in between.
fn fences(layers: u32, n: u32, soup: usize) -> TriangleMesh {
    let mut m = TriangleMesh::default();
    for k in 0..layers {
        let z = -0.3 * k as f32;
        let base = m.positions.len() as u32;
        for j in 0..=n {
            for i in 0..=n {
                let (x, y) = (i as f32 / n as f32 - 0.5, j as f32 / n as f32 - 0.5);
                m.positions.push(Vec3::new(2.0 * x, 2.0 * y, z + 0.02 * (x * 7.0).sin()));
            }
        }
        for j in 0..n {
            for i in 0..n {
                let a = base + j * (n + 1) + i;
                let (b, c, d) = (a + 1, a + n + 2, a + n + 1);
                m.indices.extend([[a, b, c], [a, c, d]]);
            }
        }
    }
    let mut rng = Pcg64::seed_from_u64(7);
    for _ in 0..soup {
        let c =
            Vec3::new(rng.gen::<f32>() * 2.0 - 1.0, rng.gen::<f32>() * 2.0 - 1.0, -rng.gen::<f32>() * 1.5);
        let base = m.positions.len() as u32;
        for _ in 0..3 {
            m.positions.push(c + 0.15 * Vec3::new(rng.gen(), rng.gen(), rng.gen()) - 0.075);
        }
        m.indices.push([base, base + 1, base + 2]);
    }
    m
}

/// A closed UV sphere (seen from inside and outside by the generated rays).
fn sphere() -> TriangleMesh {
    TriangleMesh::parametric_sphere(24, 48, |theta, phi| {
        Vec3::new(0.3, -0.2, 0.5)
            + 1.2 * Vec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos())
    })
}

/// Three triangles in four have a cut-out: diagonal stripes in barycentric space, half opaque,
/// shifted from triangle to triangle.
fn striped(mesh: &TriangleMesh) -> Cutouts {
    let marked: Vec<bool> = (0..mesh.len()).map(|p| p % 4 != 0).collect();
    let opaque =
        |prim: u32, u: f32, v: f32| ((7.0 * u + 3.0 * v + 0.37 * prim as f32) * 2.0).rem_euclid(1.0) < 0.5;
    Cutouts::new(&marked, Arc::new(opaque))
}

/// The backends this build has, each over `mesh` with `cutouts`.
fn backends(mesh: &TriangleMesh, cutouts: Option<&Cutouts>) -> Vec<AnyAccel> {
    let mut out = Vec::new();
    for kind in [AccelKind::Embree, AccelKind::Bvh, AccelKind::Naive] {
        match AnyAccel::build(kind, mesh, cutouts, AccelOptions::default()) {
            Ok(a) => out.push(a),
            Err(e) if kind == AccelKind::Embree && !cfg!(feature = "embree") => {
                println!("(no Embree in this build: {e})")
            }
            Err(e) => panic!("building {kind:?} with cut-outs failed: {e}"),
        }
    }
    out
}

fn as_dyn(a: &AnyAccel) -> &dyn Accel {
    photonmap::dispatch!(a, x => x as &dyn Accel)
}

fn rays(mesh: &TriangleMesh, n: usize, seed: u64) -> Vec<(RayKind, Ray)> {
    let camera = CameraLike { eye: Vec3::new(0.4, 0.3, 3.0), target: Vec3::new(0.0, 0.0, -0.5) };
    generate_rays(mesh, Some(camera), n, seed)
}

fn check_agreement(name: &str, mesh: &TriangleMesh, n: usize) {
    let cutouts = striped(mesh);
    let accels = backends(mesh, Some(&cutouts));
    let rays = rays(mesh, n, 0xa1fa ^ mesh.len() as u64);
    for (i, a) in accels.iter().enumerate() {
        for b in &accels[i + 1..] {
            let r = compare_with_cutouts(as_dyn(a), as_dyn(b), &rays, mesh, Some(&cutouts));
            println!("{name}:\n{r}");
            assert!(r.clean(), "{name}: {} vs {}\n{r}", a.name(), b.name());
            assert!(r.edge_ties as f64 <= 2e-3 * r.rays as f64, "{name}\n{r}");
            // As tests/agree_scenes.rs: camera rays agree on distances to 1e-5 (shadow segments
            // between surface points, near-parallel to them, less).
            let camera = r.per_kind[&RayKind::Camera].max_rel_dt;
            assert!(camera <= 1e-5, "{name}: camera max_rel_dt {camera:e}\n{r}");
            assert!(r.max_rel_dt.is_finite(), "{name}\n{r}");
        }
    }
    // The cut-outs matter: without them a good share of the closest hits differ.
    let plain = AnyAccel::build(AccelKind::Bvh, mesh, None, AccelOptions::default()).unwrap();
    let plain = as_dyn(&plain);
    let bvh = as_dyn(accels.iter().find(|a| a.name() == "bvh").unwrap());
    let changed = rays.iter().filter(|(_, r)| plain.intersect(r) != bvh.intersect(r)).count();
    let occl = rays.iter().filter(|(_, r)| plain.occluded(r) != bvh.occluded(r)).count();
    println!("{name}: cut-outs change {changed} closest hits and {occl} occlusion answers of {}", rays.len());
    assert!(changed as f64 > 0.1 * rays.len() as f64, "{name}: {changed} of {}", rays.len());
    assert!(occl > 0, "{name}");
}

#[test]
fn backends_agree_through_cutout_fences() {
    check_agreement("fences", &fences(6, 12, 200), 20_000);
}

#[test]
fn backends_agree_on_a_cutout_sphere() {
    check_agreement("sphere", &sphere(), 20_000);
}

/// Every backend's closest hits and occlusion answers with `cutouts` against the same backend
/// over `reference` without any; `map` takes a reference triangle to the cut-out mesh's.
fn same_answers(mesh: &TriangleMesh, cutouts: &Cutouts, reference: &TriangleMesh, map: &dyn Fn(u32) -> u32) {
    let rays = rays(mesh, 10_000, 0xc0de);
    for (a, b) in backends(mesh, Some(cutouts)).iter().zip(backends(reference, None)) {
        let (a, b) = (as_dyn(a), as_dyn(&b));
        let mut ties = 0;
        for (kind, ray) in &rays {
            let ha = a.intersect(ray);
            let hb = b.intersect(ray).map(|h| photonmap::accel::Hit { prim: map(h.prim), ..h });
            if ha != hb || a.occluded(ray) != b.occluded(ray) {
                // Embree's hierarchy differs between the two meshes: only the order in which it
                // meets two triangles at one point (a tie) may tell them apart.
                let tie = a.name() == "embree" && classify_ray(mesh, Some(ray), ha, hb) == Verdict::EdgeTie;
                assert!(tie, "{} on a {kind:?} ray {ray:?}: {ha:?} vs {hb:?}", a.name());
                ties += 1;
            }
        }
        assert!(ties as f64 <= 1e-3 * rays.len() as f64, "{}: {ties} ties", a.name());
    }
}

#[test]
fn an_opaque_cutout_changes_nothing() {
    let mesh = fences(4, 10, 100);
    let marked: Vec<bool> = (0..mesh.len()).map(|p| p % 3 != 1).collect();
    let always: Arc<Opacity> = Arc::new(|_, _, _| true);
    same_answers(&mesh, &Cutouts::new(&marked, always), &mesh, &|p| p);
}

#[test]
fn a_transparent_cutout_removes_its_triangles() {
    let mesh = fences(4, 10, 100);
    let marked: Vec<bool> = (0..mesh.len()).map(|p| p % 3 == 1).collect();
    let never: Arc<Opacity> = Arc::new(|_, _, _| false);
    let kept: Vec<u32> = (0..mesh.len() as u32).filter(|&p| !marked[p as usize]).collect();
    let reference = TriangleMesh {
        positions: mesh.positions.clone(),
        indices: kept.iter().map(|&p| mesh.indices[p as usize]).collect(),
    };
    same_answers(&mesh, &Cutouts::new(&marked, never), &reference, &|p| kept[p as usize]);
}

/// A panic in the opacity test must not unwind into Embree's C code: the filter catches it
/// and keeps the hit (the point counts as opaque).
#[cfg(feature = "embree")]
#[test]
fn a_panicking_opacity_test_counts_as_opaque_in_embree() {
    let mesh = fences(2, 4, 0);
    let marked = vec![true; mesh.len()];
    let panics: Arc<Opacity> = Arc::new(|_, _, _| panic!("opacity test panics (on purpose)"));
    let cut = AnyAccel::build(
        AccelKind::Embree,
        &mesh,
        Some(&Cutouts::new(&marked, panics)),
        AccelOptions::default(),
    )
    .unwrap();
    let plain = AnyAccel::build(AccelKind::Embree, &mesh, None, AccelOptions::default()).unwrap();
    let (cut, plain) = (as_dyn(&cut), as_dyn(&plain));
    let ray = Ray::new(Vec3::new(0.1, 0.1, 2.0), Vec3::new(0.0, 0.0, -1.0));
    assert_eq!(cut.intersect(&ray).map(|h| h.t), plain.intersect(&ray).map(|h| h.t));
    assert!(cut.occluded(&ray));
}
