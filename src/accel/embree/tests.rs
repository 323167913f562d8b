//! Tests of the Embree wrapper against the brute-force [`Naive`] ground truth. They need the
//! Embree library: a build with the `embree` feature and no Embree fails in `build.rs` (and a
//! missing shared library fails at load time), so these tests never skip silently.

use super::device::Device;
use super::*;
use crate::accel::naive::Naive;
use crate::geometry::Vec3;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

fn quad() -> TriangleMesh {
    TriangleMesh {
        positions: vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y],
        indices: vec![[0, 1, 2], [0, 2, 3]],
    }
}

/// The closed unit cube [0, 1]^3, 12 triangles, normals pointing out.
fn cube() -> TriangleMesh {
    let positions =
        (0..8).map(|i| Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, (i >> 2) as f32)).collect();
    let faces = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
    let indices = faces.iter().flat_map(|&[a, b, c, d]| [[a, b, c], [a, c, d]]).collect();
    TriangleMesh { positions, indices }
}

/// Robust on (the default) and off.
fn options() -> [AccelOptions; 2] {
    [AccelOptions::default(), AccelOptions { robust: false }]
}

/// Rays from around the mesh towards points of (slightly more than) its bounds; a third are
/// segments `(t_min, t_max)` that may end before or start after the surface.
fn random_rays(mesh: &TriangleMesh, n: usize, seed: u64) -> Vec<Ray> {
    let mut rng = Pcg64::seed_from_u64(seed);
    let b = mesh.bounds();
    let (lo, hi) = (b.min - Vec3::splat(0.2), b.max + Vec3::splat(0.2));
    let point = |rng: &mut Pcg64, lo: Vec3, hi: Vec3| {
        Vec3::new(rng.gen_range(lo.x..=hi.x), rng.gen_range(lo.y..=hi.y), rng.gen_range(lo.z..=hi.z))
    };
    (0..n)
        .map(|i| {
            let origin = point(&mut rng, b.min - Vec3::splat(2.0), b.max + Vec3::splat(2.0));
            let dir = point(&mut rng, lo, hi) - origin;
            if i % 3 == 0 {
                Ray::segment(origin, dir, rng.gen_range(0.0..0.9), rng.gen_range(0.9..2.0))
            } else {
                Ray::new(origin, dir)
            }
        })
        .collect()
}

fn rel(a: f32, b: f32) -> f32 {
    (a - b).abs() / a.abs().max(b.abs()).max(1e-6)
}

/// A hit within 1e-3 (barycentric) of an edge, or within 1e-4 (relative) of an interval end:
/// there two correct intersectors may legitimately disagree.
fn borderline(ray: &Ray, h: &Option<Hit>) -> bool {
    h.is_some_and(|h| {
        h.u.min(h.v).min(1.0 - h.u - h.v) < 1e-3 || rel(h.t, ray.t_min) < 1e-4 || rel(h.t, ray.t_max) < 1e-4
    })
}

/// Compares Embree with Naive on `rays`; returns (hits, excused disagreements).
fn compare(mesh: &TriangleMesh, options: AccelOptions, rays: &[Ray]) -> (usize, usize) {
    let naive = Naive::new(mesh);
    let embree = EmbreeAccel::build(mesh, options).expect("Embree build");
    let (mut hits, mut excused) = (0, 0);
    for ray in rays {
        let (want, got) = (naive.intersect(ray), embree.intersect(ray));
        let excuse = borderline(ray, &want) || borderline(ray, &got);
        let same = match (want, got) {
            (None, None) => true,
            (Some(w), Some(g)) => w.prim == g.prim && rel(w.t, g.t) < 1e-4,
            _ => false,
        };
        hits += want.is_some() as usize;
        if !same || naive.occluded(ray) != embree.occluded(ray) {
            assert!(excuse, "{options:?}: {ray:?}: naive {want:?}, embree {got:?}");
            excused += 1;
        }
        if let (Some(w), Some(g)) = (want, got) {
            // Whatever the triangle, the hit distance agrees (the surface is the same).
            assert!(rel(w.t, g.t) < 1e-4 || excuse, "{ray:?}: t {} vs {}", w.t, g.t);
            if w.prim == g.prim {
                assert!((w.u - g.u).abs() < 1e-3 && (w.v - g.v).abs() < 1e-3, "{ray:?}: {w:?} vs {g:?}");
            }
        }
    }
    (hits, excused)
}

#[test]
fn agrees_with_naive_on_quad_and_cube() {
    for (name, mesh) in [("quad", quad()), ("cube", cube())] {
        let rays = random_rays(&mesh, 4000, 7);
        for options in options() {
            let (hits, excused) = compare(&mesh, options, &rays);
            assert!(hits > rays.len() / 4, "{name}: only {hits} hits, the test rays are off");
            assert!(excused * 100 < rays.len(), "{name} {options:?}: {excused} borderline disagreements");
        }
    }
}

#[test]
fn single_hit_distance_prim_and_barycentrics() {
    let accel = EmbreeAccel::build(&quad(), AccelOptions::default()).unwrap();
    let h = accel.intersect(&Ray::new(Vec3::new(0.75, 0.25, -2.0), Vec3::Z)).expect("hit");
    assert_eq!(h.prim, 0);
    assert!((h.t - 2.0).abs() < 1e-6, "{h:?}");
    // Point = (1 - u - v) v0 + u v1 + v v2 of triangle 0.
    let p = quad().point(h.prim, h.u, h.v);
    assert!((p - Vec3::new(0.75, 0.25, 0.0)).length() < 1e-5, "{h:?} -> {p}");
    assert!(accel.intersect(&Ray::new(Vec3::new(1.5, 0.5, -1.0), Vec3::Z)).is_none());
    assert_eq!(accel.name(), "embree");
}

#[test]
fn interval_is_open_at_both_ends() {
    let accel = EmbreeAccel::build(&quad(), AccelOptions::default()).unwrap();
    // The hit is at t = 1 up to Embree's arithmetic, which differs between its CPU kernels (on
    // some, 1 - 2^-24): the interval is tested around the t it reports.
    let (o, d) = (Vec3::new(0.5, 0.25, -1.0), Vec3::Z);
    let t = accel.intersect(&Ray::new(o, d)).expect("a hit").t;
    assert!((t - 1.0).abs() < 1e-6, "{t}");
    let up = f32::from_bits(t.to_bits() + 1);
    let down = f32::from_bits(t.to_bits() - 1);
    for (t_min, t_max, expect) in [(0.0, t, false), (0.0, up, true), (t, 2.0, false), (down, 2.0, true)] {
        let ray = Ray::segment(o, d, t_min, t_max);
        assert_eq!(accel.intersect(&ray).is_some(), expect, "({t_min}, {t_max})");
        assert_eq!(accel.occluded(&ray), expect, "({t_min}, {t_max})");
        let mut hits = [None; 3];
        accel.intersect_batch(&[ray; 3], &mut hits);
        assert!(hits.iter().all(|h| h.is_some() == expect));
        let mut blocked = [!expect; 3];
        accel.occluded_batch(&[ray; 3], &mut blocked);
        assert_eq!(blocked, [expect; 3], "({t_min}, {t_max})");
    }
    // Empty and NaN intervals miss.
    assert!(!accel.occluded(&Ray::segment(o, d, 1.5, 0.5)));
    assert!(accel.intersect(&Ray::segment(o, d, f32::NAN, 2.0)).is_none());
}

#[test]
fn batches_equal_single_rays_for_any_length() {
    let mesh = cube();
    let accel = EmbreeAccel::build(&mesh, AccelOptions::default()).unwrap();
    let rays = random_rays(&mesh, 1000, 11);
    for len in [0, 1, 7, 8, 9, 15, 16, 17, 100, 1000] {
        let rays = &rays[..len];
        let mut blocked = vec![false; len];
        accel.occluded_batch(rays, &mut blocked);
        let single: Vec<bool> = rays.iter().map(|r| accel.occluded(r)).collect();
        assert_eq!(blocked, single, "len {len}");
        assert!(len < 100 || (single.contains(&true) && single.contains(&false)));
        let mut hits = vec![None; len];
        accel.intersect_batch(rays, &mut hits);
        for (i, ray) in rays.iter().enumerate() {
            let single = accel.intersect(ray);
            match (single, hits[i]) {
                (Some(s), Some(b)) => assert!(s.prim == b.prim && rel(s.t, b.t) < 1e-6, "{s:?} vs {b:?}"),
                (s, b) => assert_eq!(s, b, "len {len}, ray {i}"),
            }
        }
    }
}

#[test]
fn empty_mesh_gives_an_empty_scene() {
    let accel = EmbreeAccel::build(&TriangleMesh::default(), AccelOptions::default()).expect("empty scene");
    let ray = Ray::new(Vec3::ZERO, Vec3::X);
    assert!(accel.intersect(&ray).is_none());
    assert!(!accel.occluded(&ray));
    let mut hits = [Some(Hit { t: 1.0, prim: 0, u: 0.0, v: 0.0 }); 9];
    accel.intersect_batch(&[ray; 9], &mut hits);
    assert!(hits.iter().all(Option::is_none));
    let mut blocked = [true; 9];
    accel.occluded_batch(&[ray; 9], &mut blocked);
    assert_eq!(blocked, [false; 9]);
}

#[test]
fn invalid_meshes_are_errors_not_panics() {
    let mut nan = quad();
    nan.positions[2].x = f32::NAN;
    assert!(matches!(EmbreeAccel::build(&nan, AccelOptions::default()), Err(AccelError::Mesh(_))));
    let mut out_of_range = quad();
    out_of_range.indices.push([0, 1, 4]);
    assert!(matches!(EmbreeAccel::build(&out_of_range, AccelOptions::default()), Err(AccelError::Mesh(_))));
}

#[test]
fn embree_errors_are_reported_by_the_device() {
    let device = Device::new(DEVICE_CONFIG).unwrap();
    device.check("fresh device").unwrap();
    // SAFETY: a live device; an unknown geometry type is an error Embree reports, not UB.
    let geom = unsafe { sys::rtcNewGeometry(device.raw(), 12345) };
    assert!(geom.is_null());
    let err = device.check("rtcNewGeometry").unwrap_err();
    assert!(matches!(&err, AccelError::Embree(m) if m.starts_with("rtcNewGeometry")), "{err}");
    device.check("after the error was taken").unwrap();
}

#[test]
fn concurrent_queries_match_and_version_matches_cfg() {
    use rayon::prelude::*;
    let mesh = cube();
    let accel = EmbreeAccel::build(&mesh, AccelOptions::default()).unwrap();
    let rays = random_rays(&mesh, 2000, 3);
    let serial: Vec<_> = rays.iter().map(|r| accel.intersect(r)).collect();
    let parallel: Vec<_> = rays
        .par_iter()
        .map(|r| {
            set_flush_denormals();
            accel.intersect(r)
        })
        .collect();
    assert_eq!(serial, parallel);
    let major = if cfg!(embree4) { "4." } else { "3." };
    assert!(version().starts_with(major), "version {} vs cfg", version());
}

#[test]
fn flush_denormals_sets_ftz() {
    set_flush_denormals();
    let tiny = std::hint::black_box(f32::MIN_POSITIVE);
    let halved = std::hint::black_box(tiny / 2.0);
    if cfg!(target_arch = "x86_64") {
        assert_eq!(halved, 0.0, "FTZ should flush the subnormal result");
    }
    // Tracing still works with FTZ/DAZ on.
    let accel = EmbreeAccel::build(&quad(), AccelOptions::default()).unwrap();
    assert!(accel.occluded(&Ray::new(Vec3::new(0.5, 0.5, 1.0), -Vec3::Z)));
}

#[test]
fn linked_library_matches_the_headers() {
    let device = Device::new(DEVICE_CONFIG).unwrap();
    // SAFETY: a live device and a valid property.
    let linked = unsafe { sys::rtcGetDeviceProperty(device.raw(), sys::RTC_DEVICE_PROPERTY_VERSION) };
    device.check("rtcGetDeviceProperty").unwrap();
    assert_eq!(linked as u32, sys::RTC_VERSION, "headers {} vs linked library {linked}", version());
    let [major, minor, patch] = [sys::RTC_VERSION_MAJOR, sys::RTC_VERSION_MINOR, sys::RTC_VERSION_PATCH];
    assert_eq!(version(), format!("{major}.{minor}.{patch}"));
}
