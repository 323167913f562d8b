use super::*;
use crate::accel::naive::Naive;

fn quad_mesh() -> TriangleMesh {
    TriangleMesh {
        positions: vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y, Vec3::X * 2.0],
        // Two real triangles and a degenerate one.
        indices: vec![[0, 1, 2], [0, 2, 3], [0, 1, 4]],
    }
}

#[test]
fn empty_mesh_misses_everything() {
    let bvh = Bvh::build(&TriangleMesh::default());
    assert_eq!(bvh.node_count(), 0);
    assert!(bvh.intersect(&Ray::new(Vec3::ZERO, Vec3::X)).is_none());
    assert!(!bvh.occluded(&Ray::new(Vec3::ZERO, Vec3::X)));
}

#[test]
fn skips_degenerate_and_matches_naive() {
    let m = quad_mesh();
    let bvh = Bvh::build(&m);
    assert_eq!(bvh.triangle_count(), 2);
    let naive = Naive::new(&m);
    let r = Ray::new(Vec3::new(0.25, 0.5, -1.0), Vec3::Z);
    assert_eq!(bvh.intersect(&r), naive.intersect(&r));
    assert_eq!(bvh.intersect(&r).unwrap().prim, 1);
    // Along the degenerate triangle's line, in its plane: nothing to hit, no NaN.
    assert!(bvh.intersect(&Ray::new(Vec3::new(-1.0, 0.0, 0.0), Vec3::X)).is_none());
}

#[test]
fn zero_direction_components_on_box_planes() {
    // Rays with exact zero components whose origins lie on the bounding planes.
    let m = quad_mesh();
    let bvh = Bvh::build(&m);
    for (o, d) in [
        (Vec3::new(0.0, 0.5, -1.0), Vec3::Z),
        (Vec3::new(1.0, 0.25, -1.0), Vec3::new(-0.0, 0.0, 1.0)),
        (Vec3::new(0.5, 1.0, 1.0), Vec3::new(0.0, -0.0, -2.0)),
    ] {
        let r = Ray::new(o, d);
        let want = Naive::new(&m).intersect(&r);
        assert!(want.is_some(), "{o} {d}");
        assert_eq!(bvh.intersect(&r), want, "{o} {d}");
        assert!(bvh.occluded(&r));
    }
}
