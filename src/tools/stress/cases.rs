//! The cases of the stress suite and the reasoning behind each expected value and bound.
//!
//! (One file of about 450 lines on purpose: each case is a short function whose comment derives
//! its bound, and reading them side by side is how the suite is reviewed.)

use super::scenes::{self, Walls, PLANE_ALBEDO};
use super::{agreement, row, Case, Probe, Row, StressError, StressOptions};
use crate::accel::AccelKind;
use crate::config::{Component, Kernel, RenderSettings};
use crate::film::Film;
use crate::geometry::Vec3;
use crate::photon::map::{GatherParams, MapColor, PhotonHit, PhotonMap};
use crate::scene::Scene;
use std::f32::consts::PI;

pub(super) fn all() -> Vec<Case> {
    vec![
        Case {
            name: "furnace",
            about: "white furnace at scales 1e-4, 1, 1e4 and moved by 1e5",
            run: furnace,
        },
        Case {
            name: "glass-furnace",
            about: "glass sphere in a uniform emitter at the default depth",
            run: glass_furnace,
        },
        Case { name: "grazing", about: "plane lit at 1 and 0.1 degrees, and from below", run: grazing },
        Case { name: "coplanar", about: "overlapping coplanar quads", run: coplanar },
        Case { name: "touching", about: "boxes sharing a face", run: touching },
        Case {
            name: "camera-inside",
            about: "camera inside a closed box lit from outside, walls thick and of no thickness",
            run: camera_inside,
        },
        Case {
            name: "light-inside",
            about: "light inside a closed box seen from outside, walls thick and of no thickness",
            run: light_inside,
        },
        Case { name: "back-facing", about: "area light seen from behind", run: back_facing },
        Case { name: "power", about: "light power 1e-12 and 1e12", run: power },
        Case { name: "duplicates", about: "a million photons on one point", run: duplicates },
        Case { name: "zero-photons", about: "no photon stored", run: zero_photons },
        Case { name: "one-triangle", about: "a scene of one triangle", run: one_triangle },
        Case { name: "slivers", about: "a million sliver triangles", run: slivers },
    ]
}

/// Image side of the renders.
const SIZE: u32 = 32;

fn name(k: AccelKind) -> String {
    format!("{k:?}").to_lowercase()
}

fn settings(spp: u32, photons: u64, seed: u64) -> RenderSettings {
    RenderSettings { spp: Some(spp), photons: Some(photons), seed: Some(seed), ..Default::default() }
}

/// Largest `|channel - expected| / expected` over the film.
fn max_rel_dev(film: &Film, expected: f32) -> f64 {
    film.pixels
        .iter()
        .flat_map(|p| p.to_array())
        .map(|c| ((c - expected).abs() / expected) as f64)
        .fold(0.0, f64::max)
}

/// Largest channel value of the film.
fn max_value(film: &Film) -> f32 {
    film.pixels.iter().map(|p| p.max_element()).fold(0.0, f32::max)
}

/// Rows of a scene whose every pixel has the same known radiance `expected`, rendered on every
/// backend, plus its agreement row. `tolerance` is relative (absolute for `expected == 0`).
fn uniform(
    case: &str,
    scene: &Scene,
    settings: &RenderSettings,
    expected: f32,
    tolerance: f64,
    opts: &StressOptions,
) -> Vec<Row> {
    let mut rows = Vec::new();
    for &accel in &opts.accels {
        let (check, want) = if expected == 0.0 {
            ("every pixel 0".to_string(), "0".to_string())
        } else {
            ("every pixel analytic".to_string(), format!("{expected:.4e} ±{tolerance:.0e} rel"))
        };
        rows.push(row(case, &name(accel), &check, want, |p| {
            let film = p.render(scene, settings, SIZE, accel)?.film;
            Ok(if expected == 0.0 {
                let m = max_value(&film);
                (format!("max {m:.2e}"), m as f64 <= tolerance)
            } else {
                let d = max_rel_dev(&film, expected);
                (format!("max rel dev {d:.1e}"), d <= tolerance)
            })
        }));
    }
    rows.extend(agreement(case, scene, opts));
    rows
}

/// The white furnace: radiance exactly 2 everywhere, at any scale and position.
///
/// Bounds: the mean of the image within 1 % of 2 (the issue's); and every pixel of two
/// independent renders (seeds 1 and 2) within 6 σ of 2, where σ is the per-pixel noise at that
/// setting measured from the same two renders (`rms(a - b) / √2`). A pixel that rounding
/// darkens or brightens (self-intersection, a light leak at the far-from-origin corners) stands
/// far outside that, while Gaussian noise passes 6 σ on all 6144 values (2 images × 1024
/// pixels × 3 channels) with probability above 1 − 10⁻⁴.
fn furnace(opts: &StressOptions) -> Vec<Row> {
    let (spp, photons) = if opts.quick { (8, 20_000) } else { (16, 100_000) };
    let variants = [
        ("x1e-4", 1e-4, Vec3::ZERO),
        ("x1", 1.0, Vec3::ZERO),
        ("x1e4", 1e4, Vec3::ZERO),
        ("+1e5", 1.0, Vec3::splat(1e5)),
    ];
    let mut rows = Vec::new();
    for (label, scale, offset) in variants {
        let case = format!("furnace {label}");
        let scene = scenes::furnace(scale, offset);
        for &accel in &opts.accels {
            rows.push(row(
                &case,
                &name(accel),
                "mean 2 ±1%, pixels within 6σ",
                "2 ±1%, 6σ".into(),
                |p| {
                    let a = p.render(&scene, &settings(spp, photons, 1), SIZE, accel)?.film;
                    let b = p.render(&scene, &settings(spp, photons, 2), SIZE, accel)?.film;
                    let values = |f: &Film| f.pixels.iter().flat_map(|p| p.to_array()).collect::<Vec<f32>>();
                    let (va, vb) = (values(&a), values(&b));
                    let n = va.len() as f64;
                    let sigma =
                        (va.iter().zip(&vb).map(|(x, y)| ((x - y) as f64).powi(2)).sum::<f64>() / n / 2.0)
                            .sqrt();
                    let dev = va.iter().chain(&vb).map(|x| (*x as f64 - 2.0).abs()).fold(0.0, f64::max);
                    let mean = 0.5 * (a.mean() + b.mean());
                    let ok = (mean / 2.0 - 1.0).abs() < 0.01 && sigma > 0.0 && dev <= 6.0 * sigma;
                    Ok((format!("mean {mean:.4}, max {:.1}σ (σ {sigma:.3})", dev / sigma), ok))
                },
            ));
        }
        rows.extend(agreement(&case, &scene, opts));
    }
    rows
}

/// A glass sphere (IOR 1.5, 24 rings) in a uniform emitter: every pixel's exact value is 1.
/// Light trapped by total internal reflection is lost where the camera path is cut short; at
/// the old default depth of 16 bounces this render's mean was 0.9865, at the default 1000 it
/// is within 0.15 % of 1 (`examples/glass_depth.rs` shows the trend). Bound: the mean within
/// 0.3 % of 1; noise is far below that (the walls emit exactly 1 and the glass only
/// redirects, so a sample is 1 unless cut).
fn glass_furnace(opts: &StressOptions) -> Vec<Row> {
    let spp = if opts.quick { 8 } else { 32 };
    let scene = scenes::glass_in_furnace(1.5, 24);
    let mut rows = Vec::new();
    for &accel in &opts.accels {
        rows.push(row("glass furnace", &name(accel), "mean 1 ±0.3%", "1 ±0.3%".into(), |p| {
            let mean = p.render(&scene, &settings(spp, 1000, 1), SIZE, accel)?.film.mean();
            Ok((format!("mean {mean:.4}"), (mean - 1.0).abs() < 0.003))
        }));
    }
    rows
}

/// The grazing plane: a distant light of irradiance 1 at elevation `e` gives radiance
/// `sin(e) ρ / π` on the whole plane, exactly: direct light from a delta light has no noise and
/// no photon is stored (every photon leaves after its first hit). The bound, 10⁻⁴ relative, is
/// far above float rounding (10⁻⁶) and far below what one self-shadowed sample costs
/// (1 / spp). From below, the top must stay black.
fn grazing(opts: &StressOptions) -> Vec<Row> {
    let spp = if opts.quick { 4 } else { 16 };
    let mut rows = Vec::new();
    for elevation in [1.0f32, 0.1] {
        let expected = elevation.to_radians().sin() * PLANE_ALBEDO / PI;
        let scene = scenes::grazing_plane(elevation);
        rows.extend(uniform(
            &format!("grazing {elevation}°"),
            &scene,
            &settings(spp, 10_000, 1),
            expected,
            1e-4,
            opts,
        ));
    }
    let below = scenes::grazing_plane(-1.0);
    let mut r = uniform("grazing -1° (below)", &below, &settings(spp, 10_000, 1), 0.0, 0.0, opts);
    r.retain(|row| !row.accel.contains('='));
    rows.extend(r);
    rows
}

/// Radiance of the surfaces lit by [`scenes::TOP_LIGHT_ELEVATION_DEG`].
fn top_lit() -> f32 {
    scenes::TOP_LIGHT_ELEVATION_DEG.to_radians().sin() * PLANE_ALBEDO / PI
}

/// Coplanar quads: whichever quad a ray hits, the radiance is the same; a shadow ray hitting
/// the other quad (acne) costs 1 / spp.
fn coplanar(opts: &StressOptions) -> Vec<Row> {
    let spp = if opts.quick { 4 } else { 16 };
    uniform("coplanar quads", &scenes::coplanar_quads(), &settings(spp, 10_000, 1), top_lit(), 1e-4, opts)
}

/// Touching boxes: the two tops are lit alike; a crack at the seam would show the dark
/// side faces or the background.
fn touching(opts: &StressOptions) -> Vec<Row> {
    let spp = if opts.quick { 4 } else { 16 };
    uniform("touching boxes", &scenes::touching_boxes(), &settings(spp, 10_000, 1), top_lit(), 1e-4, opts)
}

/// Stored photons of the render's indirect map(s).
fn stored(out: &crate::integrator::RenderOutput) -> u64 {
    out.stats.photons.iter().filter(|(k, _)| k.starts_with("indirect")).map(|(_, m)| m.stored).sum()
}

/// Rows of a closed box that must look black: every pixel exactly 0, with photons stored (so
/// the gathers had something to leak).
///
/// Each box is rendered with walls [`scenes::WALL`] thick and, a twentieth the size, with walls
/// of no thickness, both under a gather radius wider than the walls (and than the whole thin
/// box). The thin box with the light inside stands over a floor, out of the reach of the
/// floor's gathers but not of its irradiance lookups: before lookups kept to the query's own
/// plane, the floor took the sites on the box's inside bottom for its own (facing up, as the
/// floor does) and read up to 1.7 there (and a closed lamp lit the ceiling above it:
/// `scripts/closed-lamp.sh`). Gathers still reach the photons of a surface facing the same way
/// within their region (`r / √2` off the plane): the same box 0.08 over the floor gave it
/// 1e-4 (docs/robustness.md).
fn black_box(case: &str, scene: &Scene, opts: &StressOptions) -> Vec<Row> {
    let (spp, photons) = if opts.quick { (4, 20_000) } else { (16, 50_000) };
    let s = RenderSettings { gather_radius: Some(scenes::WALL_GATHER_RADIUS), ..settings(spp, photons, 1) };
    let mut rows = Vec::new();
    for &accel in &opts.accels {
        rows.push(row(case, &name(accel), "every pixel 0, photons stored", "0".into(), |p| {
            let out = p.render(scene, &s, SIZE, accel)?;
            let (m, n) = (max_value(&out.film), stored(&out));
            Ok((format!("max {m:.2e}, {n} photons stored"), m == 0.0 && n > 0))
        }));
    }
    rows.extend(agreement(case, scene, opts));
    rows
}

/// The camera inside a closed box lit from outside sees black: photons on the outer walls
/// arrive from the other side and are rejected, shadow rays cannot pass the walls.
fn camera_inside(opts: &StressOptions) -> Vec<Row> {
    let mut rows = black_box("camera inside box", &scenes::camera_inside_box(Walls::Thick), opts);
    rows.extend(black_box("camera inside thin box", &scenes::camera_inside_box(Walls::Thin), opts));
    rows
}

/// A light inside a closed box lights nothing outside it.
fn light_inside(opts: &StressOptions) -> Vec<Row> {
    let mut rows = black_box("light inside box", &scenes::light_inside_box(Walls::Thick), opts);
    rows.extend(black_box("light inside thin box", &scenes::light_inside_box(Walls::Thin), opts));
    rows
}

/// An area light emits from its front face only: from behind, it and the floor on its back
/// side are black; from the front, the middle of the image sees its radiance exactly.
fn back_facing(opts: &StressOptions) -> Vec<Row> {
    let spp = if opts.quick { 4 } else { 16 };
    let (back, front) = (scenes::back_facing_light(false), scenes::back_facing_light(true));
    let mut rows = Vec::new();
    for &accel in &opts.accels {
        let want = format!("back 0, front {}", scenes::AREA_LE);
        rows.push(row("back-facing light", &name(accel), "black from behind, Le in front", want, |p| {
            let b = p.render(&back, &settings(spp, 10_000, 1), SIZE, accel)?.film;
            let f = p.render(&front, &settings(spp, 10_000, 1), SIZE, accel)?.film;
            let m = max_value(&b);
            let c = SIZE as usize / 2;
            let centre = [f.get(c - 1, c - 1), f.get(c, c - 1), f.get(c - 1, c), f.get(c, c)];
            let dev = centre
                .iter()
                .flat_map(|p| p.to_array())
                .map(|x| (x - scenes::AREA_LE).abs() / scenes::AREA_LE)
                .fold(0.0, f32::max);
            Ok((format!("back max {m:.2e}, front dev {dev:.1e}"), m == 0.0 && dev <= 1e-5))
        }));
    }
    rows.extend(agreement("back-facing light", &back, opts));
    rows
}

/// Light power scales the image linearly. Same seed, same random decisions (Russian roulette
/// depends on albedo, not power), so `L(k) = k L(1)` pixel by pixel up to the rounding of the
/// stored powers, which differs at each scale: RGB9E5 rounds each channel of a photon's power
/// to within 2⁻⁹ of its largest channel, and the precomputed irradiance rounds the sums once more the
/// same way. So every channel of a pixel is within 2⁻⁸ of its largest channel times `k` (the
/// bound; sums of many photons average the rounding down).
fn power(opts: &StressOptions) -> Vec<Row> {
    let (spp, photons) = if opts.quick { (4, 20_000) } else { (8, 50_000) };
    let s = settings(spp, photons, 1);
    let base = scenes::lit_box(1.0);
    let mut rows = Vec::new();
    for &accel in &opts.accels {
        for k in [1e-12f32, 1e12] {
            let scaled = scenes::lit_box(k);
            let check = format!("image = {k:.0e} x image at power 1");
            rows.push(row(
                &format!("power {k:.0e}"),
                &name(accel),
                &check,
                "k L(1) ±2^-8 max".into(),
                |p| {
                    let a = p.render(&base, &s, SIZE, accel)?.film;
                    let b = p.render(&scaled, &s, SIZE, accel)?.film;
                    let k = k as f64;
                    let mut dev = 0.0f64;
                    for (x, y) in a.pixels.iter().zip(&b.pixels) {
                        let scale = k * x.max_element() as f64;
                        for c in 0..3 {
                            let d = (y[c] as f64 - k * x[c] as f64).abs();
                            dev = dev.max(if scale > 0.0 {
                                d / scale
                            } else if d > 0.0 {
                                f64::INFINITY
                            } else {
                                0.0
                            });
                        }
                    }
                    let lit = a.pixels.iter().any(|x| x.max_element() > 0.0);
                    Ok((format!("max dev {dev:.1e}"), lit && dev <= 2f64.powi(-8)))
                },
            ));
        }
    }
    rows.extend(agreement("power", &base, opts));
    rows
}

/// A million photons at one point: the kd-tree holds only duplicates. Seen from distance `d`
/// in the surface's plane, the `k` nearest are all at `d`, so the box-kernel irradiance is
/// exactly `(k - 1) Φ / (π d²)` (the estimate counts the photons of the disc through the `k`-th
/// but that one, `photon::map`); beyond the search radius nothing is found; at distance 0 the disc
/// is empty of area and the estimate must stay finite (it is 0); the range query finds them
/// all.
fn duplicates(_opts: &StressOptions) -> Vec<Row> {
    let n: usize = 1_000_000;
    vec![row(
        "1M photons on 1 point",
        "kd-tree",
        "knn, estimate, range query",
        "(k-1) Φ/(π d²), all found".into(),
        |_| {
            let p0 = Vec3::new(0.3, 0.7, -0.2);
            let phi = 2f32.powi(-20); // exact in RGB9E5
            let hit =
                PhotonHit { pos: p0, n: Vec3::Y, err: Vec3::ZERO, wi: Vec3::Y, power: Vec3::splat(phi) };
            let map = PhotonMap::build(vec![hit; n], MapColor::Rgb, n as u64);
            let mut scratch = Vec::new();
            let k = 100;
            let mut worst = 0.0f64;
            let mut finite = true;
            for d in [0.01f32, 0.1, 0.5] {
                let params = GatherParams { k, max_radius: 1.0, kernel: Kernel::Box, flatten: 4.0 };
                let e = map.irradiance(p0 + Vec3::X * d, Vec3::Y, &params, &mut scratch);
                let expect = (k - 1) as f32 * phi / (PI * d * d);
                worst = worst.max(((e.x - expect).abs() / expect) as f64);
                for kernel in [Kernel::Cone, Kernel::Gaussian] {
                    let params = GatherParams { kernel, ..params };
                    finite &= map.irradiance(p0 + Vec3::X * d, Vec3::Y, &params, &mut scratch).is_finite();
                }
            }
            let params = GatherParams { k, max_radius: 1.0, kernel: Kernel::Box, flatten: 4.0 };
            let at = map.irradiance(p0, Vec3::Y, &params, &mut scratch);
            let far = map.irradiance(p0 + Vec3::X * 2.0, Vec3::Y, &params, &mut scratch);
            let found = map.for_each_within(p0 + Vec3::X * 0.1, Vec3::Y, 0.2, 4.0, |_, _| {});
            let ok = worst <= 1e-5 && finite && at.is_finite() && far == Vec3::ZERO && found as usize == n;
            Ok((format!("rel err {worst:.1e}, at point {:.1e}, {found} found", at.x), ok))
        },
    )]
}

/// Nothing but a plane and a point light: no photon is stored, and the image is the direct
/// light alone, equal to a `--component direct` render, and each pixel (a mean of samples in
/// its footprint) lies within the range of the analytic `I ρ h / (π r³)` over its footprint
/// (sampled at 5 × 5 points, corners included; 10⁻⁴ relative slack for rounding and for the
/// curvature between the points).
fn zero_photons(opts: &StressOptions) -> Vec<Row> {
    let spp = if opts.quick { 4 } else { 16 };
    let scene = scenes::lonely_plane();
    let mut rows = Vec::new();
    for &accel in &opts.accels {
        let want = "0 stored, = direct, in range".to_string();
        rows.push(row("zero photons stored", &name(accel), "direct light only", want, |p| {
            let all = p.render(&scene, &settings(spp, 20_000, 1), SIZE, accel)?;
            let direct_only =
                RenderSettings { component: Some(Component::Direct), ..settings(spp, 20_000, 1) };
            let direct = p.render(&scene, &direct_only, SIZE, accel)?.film;
            let n = stored(&all);
            let diff = all
                .film
                .pixels
                .iter()
                .zip(&direct.pixels)
                .map(|(a, b)| (*a - *b).abs().max_element())
                .fold(0.0, f32::max);
            let cam = scene.camera.with_resolution(SIZE, SIZE);
            let light = Vec3::new(0.0, scenes::LONELY_HEIGHT, 0.0);
            let analytic = |x: f32, y: f32| {
                let ray = cam.ray(x, y);
                let q = ray.origin + ray.dir * (-ray.origin.y / ray.dir.y);
                let r = (q - light).length();
                scenes::LONELY_INTENSITY * PLANE_ALBEDO * scenes::LONELY_HEIGHT / (PI * r * r * r)
            };
            // How far the worst pixel lies outside its footprint's range, relative.
            let mut outside = 0.0f64;
            for y in 0..SIZE {
                for x in 0..SIZE {
                    let (mut lo, mut hi) = (f32::INFINITY, 0.0f32);
                    for i in 0..5 {
                        for j in 0..5 {
                            let l = analytic(x as f32 + i as f32 / 4.0, y as f32 + j as f32 / 4.0);
                            (lo, hi) = (lo.min(l), hi.max(l));
                        }
                    }
                    let v = all.film.get(x as usize, y as usize).max_element();
                    let excess = ((lo - v) / lo).max((v - hi) / hi).max(0.0);
                    outside = outside.max(excess as f64);
                }
            }
            let ok = n == 0 && diff == 0.0 && outside <= 1e-4;
            Ok((format!("{n} stored, |all-direct| {diff:.0e}, out of range {outside:.0e}"), ok))
        }));
    }
    rows.extend(agreement("zero photons stored", &scene, opts));
    rows
}

/// One triangle lit from straight above: the middle of the image lies well inside it and sees
/// exactly `E ρ / π`; no pixel is brighter, none negative.
fn one_triangle(opts: &StressOptions) -> Vec<Row> {
    let spp = if opts.quick { 4 } else { 16 };
    let scene = scenes::one_triangle();
    let expected = scenes::TRIANGLE_IRRADIANCE * scenes::TRIANGLE_ALBEDO / PI;
    let mut rows = Vec::new();
    for &accel in &opts.accels {
        let want = format!("centre {expected:.4}, none above");
        rows.push(row("one triangle", &name(accel), "centre analytic, bounded", want, |p| {
            let film = p.render(&scene, &settings(spp, 10_000, 1), SIZE, accel)?.film;
            let c = SIZE as usize / 2;
            let centre = [film.get(c - 1, c - 1), film.get(c, c - 1), film.get(c - 1, c), film.get(c, c)];
            let dev = centre
                .iter()
                .flat_map(|p| p.to_array())
                .map(|x| (x - expected).abs() / expected)
                .fold(0.0, f32::max);
            let max = max_value(&film);
            let min = film.pixels.iter().map(|p| p.min_element()).fold(f32::INFINITY, f32::min);
            let ok = dev <= 1e-5 && max <= expected * (1.0 + 1e-5) && min >= 0.0;
            Ok((format!("centre dev {dev:.1e}, max {max:.4}, min {min:.1}"), ok))
        }));
    }
    rows.extend(agreement("one triangle", &scene, opts));
    rows
}

/// A million slivers (aspect ratio 500 000) tiling a square lit from above: every pixel sees
/// `E ρ / π` exactly (within 10⁻⁴; a sample slipping through a crack costs 1 / spp), at a tiny
/// resolution and a few photons, in bounded time.
fn slivers(opts: &StressOptions) -> Vec<Row> {
    let spp = if opts.quick { 2 } else { 4 };
    let scene = scenes::slivers(500_000);
    let expected = PLANE_ALBEDO / PI;
    let mut rows = Vec::new();
    for &accel in &opts.accels {
        let want = format!("{expected:.4e} ±1e-4 rel");
        rows.push(row("1M slivers", &name(accel), "every pixel analytic", want, |p: &mut Probe| {
            let film = p.render(&scene, &settings(spp, 1000, 1), 16, accel)?.film;
            let d = max_rel_dev(&film, expected);
            Ok::<_, StressError>((format!("max rel dev {d:.1e}"), d <= 1e-4))
        }));
    }
    rows.extend(agreement("1M slivers", &scene, opts));
    rows
}
