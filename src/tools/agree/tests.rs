use super::*;
use crate::accel::naive::Naive;

fn tri(scale: f32) -> TriangleMesh {
    TriangleMesh {
        positions: vec![Vec3::ZERO, Vec3::X * scale, Vec3::Y * scale, Vec3::X * 2.0 * scale],
        indices: vec![[0, 1, 2], [0, 1, 3]],
    }
}

fn hit(prim: u32, t: f32, u: f32, v: f32) -> Hit {
    Hit { t, prim, u, v }
}

#[test]
fn near_edge_interior_edges_vertices_and_degenerate() {
    for s in [1e-3, 1.0, 1e4] {
        let m = tri(s);
        assert!(!near_edge(&m, &hit(0, 1.0, 0.3, 0.3)), "centre at scale {s}");
        assert!(!near_edge(&m, &hit(0, 1.0, 0.01, 0.5)), "1% from an edge at scale {s}");
        assert!(near_edge(&m, &hit(0, 1.0, 0.5, 0.5)), "hypotenuse at scale {s}");
        assert!(near_edge(&m, &hit(0, 1.0, 0.0, 0.4)), "edge u = 0 at scale {s}");
        assert!(near_edge(&m, &hit(0, 1.0, 3e-6, 0.4)), "within 1e-5 at scale {s}");
        assert!(near_edge(&m, &hit(0, 1.0, 1.0, 0.0)), "vertex at scale {s}");
        assert!(near_edge(&m, &hit(1, 1.0, 0.3, 0.3)), "degenerate at scale {s}");
    }
    // Far from the origin, a few ULPs of the coordinates is more than 1e-5 of a small triangle.
    let mut m = tri(1.0);
    m.positions.iter_mut().for_each(|p| *p += Vec3::splat(1e4));
    assert!(near_edge(&m, &hit(0, 1.0, 1e-4, 0.4)));
    assert!(!near_edge(&m, &hit(0, 1.0, 0.2, 0.4)));
}

#[test]
fn classify_verdicts() {
    let m = tri(1.0);
    let inner = hit(0, 2.0, 0.3, 0.3);
    assert_eq!(classify(&m, None, None), Verdict::Agree { rel_dt: None });
    assert_eq!(classify(&m, Some(inner), None), Verdict::HitMiss);
    assert_eq!(classify(&m, None, Some(hit(0, 2.0, 0.5, 0.5))), Verdict::EdgeTie);
    assert_eq!(classify(&m, Some(inner), Some(hit(0, 2.0, 0.3, 0.3))), Verdict::Agree { rel_dt: Some(0.0) });
    let other = TriangleMesh {
        positions: [m.positions.clone(), vec![Vec3::Z, Vec3::new(1.0, 0.0, 1.0), Vec3::new(0.0, 1.0, 1.0)]]
            .concat(),
        indices: vec![[0, 1, 2], [0, 1, 3], [4, 5, 6]],
    };
    assert_eq!(classify(&other, Some(inner), Some(hit(2, 3.0, 0.3, 0.3))), Verdict::Primitive);
    // Same distance, different triangles (coplanar overlap): a tie.
    assert_eq!(classify(&other, Some(inner), Some(hit(2, 2.0, 0.3, 0.3))), Verdict::EdgeTie);
}

#[test]
fn rays_are_deterministic_finite_and_mixed() {
    let m = tri(1.0);
    let a = generate_rays(&m, None, 1003, 7);
    assert_eq!(a, generate_rays(&m, None, 1003, 7));
    assert_ne!(a, generate_rays(&m, None, 1003, 8));
    assert_eq!(a.len(), 1003);
    for kind in RayKind::ALL {
        assert!(a.iter().filter(|(k, _)| *k == kind).count() >= 200);
    }
    for (kind, r) in &a {
        assert!(r.origin.is_finite() && r.dir.is_finite() && r.dir != Vec3::ZERO, "{kind:?}");
        if *kind == RayKind::Shadow {
            assert!(r.t_max < 1.0);
        }
    }
    let naive = Naive::new(&m);
    let report = compare(&naive, &naive, &a, &m);
    assert!(report.clean() && report.edge_ties == 0, "{report}");
    let json = serde_json::to_value(&report).unwrap();
    for key in ["rays", "hit_miss_disagreements", "edge_ties", "primitive_disagreements"] {
        assert!(json.get(key).is_some(), "{key}");
    }
    assert!(json["per_kind"]["camera"]["rays"].as_u64().unwrap() > 0);
    // Empty meshes still get rays (random ones).
    assert_eq!(generate_rays(&TriangleMesh::default(), None, 10, 1).len(), 10);
}

/// Brute force that loses every hit on triangle 0: a backend that is wrong on purpose.
struct LosesTriangle0(Naive);

impl Accel for LosesTriangle0 {
    fn name(&self) -> &'static str {
        "loses-triangle-0"
    }

    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        self.0.intersect(ray).filter(|h| h.prim != 0)
    }

    fn occluded(&self, ray: &Ray) -> bool {
        self.intersect(ray).is_some()
    }
}

#[test]
fn a_wrong_backend_disagrees_and_one_compared_with_itself_never_does() {
    // A tetrahedron: every kind of ray hits its faces, triangle 0 among them.
    let m = TriangleMesh {
        positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z],
        indices: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
    };
    let rays = generate_rays(&m, None, 1000, 3);
    let (naive, wrong) = (Naive::new(&m), LosesTriangle0(Naive::new(&m)));
    let r = compare(&wrong, &naive, &rays, &m);
    assert!(!r.clean(), "{r}");
    assert!(r.hit_miss_disagreements > 20 && r.occlusion_disagreements > 20, "{r}");
    // The same wrong backend against itself finds nothing: such a check cannot fail.
    assert!(compare(&wrong, &wrong, &rays, &m).clean());
}

#[test]
fn within_budget_spreads_the_subset_over_every_kind() {
    let rays = generate_rays(&tri(1.0), None, 1000, 5);
    assert_eq!(within_budget(&rays, 2, 2000), rays);
    assert_eq!(within_budget(&rays, 0, 0), rays);
    let sub = within_budget(&rays, 2, 200);
    assert_eq!(sub.len(), 100);
    for kind in RayKind::ALL {
        assert_eq!(sub.iter().filter(|(k, _)| *k == kind).count(), 20, "{kind:?}");
    }
    assert!(within_budget(&rays, 2, 1).is_empty());
}

/// However large the scene, the main comparison is of two different backends and casts
/// rays, or it is not run and not clean. Without Embree it is the BVH against brute force,
/// on a subset of the rays when brute force's budget is short.
#[test]
fn scene_agreement_never_compares_a_backend_with_itself() {
    let m = tri(1.0);
    let options = crate::accel::AccelOptions::default();
    for budget in [NAIVE_BUDGET, 2 * 100] {
        let r = agree_mesh(&m, None, None, 1000, 9, options, budget).unwrap();
        assert_ne!(r.main.backends[0], r.main.backends[1], "{r}");
        assert_eq!(r.generated_rays, 1000);
        assert!(r.ran() && r.clean(), "{r}");
        if cfg!(not(feature = "embree")) {
            assert_eq!(r.main.backends, ["bvh", "naive"]);
            let expected = if budget == NAIVE_BUDGET { 1000 } else { 100 };
            assert_eq!(r.main.rays, expected, "{r}");
        }
    }
    if cfg!(not(feature = "embree")) {
        let r = agree_mesh(&m, None, None, 1000, 9, options, 1).unwrap();
        assert!(!r.ran() && !r.clean(), "{r}");
        assert!(r.to_string().contains("not run"), "{r}");
    }
}
