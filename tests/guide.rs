//! Guided photon emission (`photon::guide`): in a room lit by the sun through a window, the
//! photons are sent where the camera looks, many more of them are seen, and the image keeps
//! its value (each photon's power is divided by the density of its sample); the same with the
//! window declared a portal (`[[portal]]`), and with the window found as one where none is
//! declared.

use crate::common;
use photonmap::accel::bvh::Bvh;
use photonmap::config::{IntegratorKind, RenderSettings};
use photonmap::geometry::Vec3;
use photonmap::integrator::openings;
use photonmap::light::{LightDesc, Portal};
use photonmap::material::Material;
use photonmap::scene::Scene;
use photonmap::tools::stress::scenes::{camera, diffuse, Builder};

use crate::common::render_checked;

/// A room `[-1, 1] × [0, 2] × [-1, 1]` with a window `[-w, w] × [1 - w, 1 + w]` in its +z wall,
/// on a ground of half-width 10, lit by a sun travelling in through the window; the camera
/// stands inside, looking at the floor and the back wall.
fn sunroom(w: f32) -> Scene {
    sunroom_seen_from(w, Vec3::new(0.0, 1.0, 0.9), Vec3::new(0.0, 0.4, -0.6), false)
}

/// [`sunroom`] seen from `eye`, looking at `target`; `glazed`: a pane of glass 1 cm thick
/// fills the window.
fn sunroom_seen_from(w: f32, eye: Vec3, target: Vec3, glazed: bool) -> Scene {
    let mut b = Builder::default();
    if glazed {
        let glass = b.material("glass", Material::Glass { ior: 1.5 });
        let v = Vec3::new;
        for (z, n) in [(0.995f32, Vec3::NEG_Z), (1.005, Vec3::Z)] {
            b.quad([v(-w, 1.0 - w, z), v(w, 1.0 - w, z), v(w, 1.0 + w, z), v(-w, 1.0 + w, z)], n, glass);
        }
    }
    let wall = b.material("wall", diffuse(0.7));
    let ground = b.material("ground", diffuse(0.3));
    let v = Vec3::new;
    let quad = |b: &mut Builder, x0: f32, x1: f32, y0: f32, y1: f32, z: f32| {
        b.quad([v(x0, y0, z), v(x1, y0, z), v(x1, y1, z), v(x0, y1, z)], Vec3::NEG_Z, wall);
    };
    // The +z wall around the window.
    quad(&mut b, -1.0, 1.0, 0.0, 1.0 - w, 1.0);
    quad(&mut b, -1.0, 1.0, 1.0 + w, 2.0, 1.0);
    quad(&mut b, -1.0, -w, 1.0 - w, 1.0 + w, 1.0);
    quad(&mut b, w, 1.0, 1.0 - w, 1.0 + w, 1.0);
    // The other walls, floor and ceiling.
    quad(&mut b, -1.0, 1.0, 0.0, 2.0, -1.0);
    for (x, n) in [(-1.0f32, Vec3::X), (1.0, Vec3::NEG_X)] {
        b.quad([v(x, 0.0, -1.0), v(x, 0.0, 1.0), v(x, 2.0, 1.0), v(x, 2.0, -1.0)], n, wall);
    }
    for (y, n) in [(0.001f32, Vec3::Y), (2.0, Vec3::NEG_Y)] {
        b.quad([v(-1.0, y, -1.0), v(1.0, y, -1.0), v(1.0, y, 1.0), v(-1.0, y, 1.0)], n, wall);
    }
    b.quad(
        [v(-10.0, 0.0, -10.0), v(10.0, 0.0, -10.0), v(10.0, 0.0, 10.0), v(-10.0, 0.0, 10.0)],
        Vec3::Y,
        ground,
    );
    b.light(LightDesc::Distant { direction: Vec3::new(0.0, -0.6, -1.0), irradiance: Vec3::splat(5.0) });
    b.build("sunroom", camera(eye, target, Vec3::Y, 80.0))
}

/// Guided or not, without portals (none declared, none looked for).
fn settings(guide: bool, passes: u32) -> RenderSettings {
    RenderSettings {
        integrator: Some(IntegratorKind::Sppm),
        photon_guide: Some(guide),
        portals: Some(false),
        passes: Some(passes),
        photons: Some(50_000),
        spp: Some(2),
        seed: Some(5),
        ..Default::default()
    }
}

/// The mean of the path tracer's image at 16×16, 2048 spp.
fn path_mean(scene: &Scene) -> f64 {
    let path = RenderSettings {
        integrator: Some(IntegratorKind::Path),
        spp: Some(2048),
        seed: Some(1),
        ..Default::default()
    };
    render_checked(scene, &path, 16).film.mean()
}

/// Seen photons over emitted photons of the render's indirect map.
fn efficiency(out: &photonmap::integrator::RenderOutput) -> f64 {
    out.stats.photons["indirect"].efficiency
}

#[test]
fn guided_photons_reach_the_room_and_keep_the_image() {
    let scene = sunroom(0.3);
    let guided = render_checked(&scene, &settings(true, 128), 16);
    let plain = render_checked(&scene, &settings(false, 1), 16);
    let stage = guided.stats.stages.iter().find(|s| s.name == "photons.guide").unwrap();
    assert!(stage.ran && stage.reason.contains("guided"), "{stage:?}");
    // Measured: 0.34 against 0.0010.
    let (eg, ep) = (efficiency(&guided), efficiency(&plain));
    assert!(eg > 30.0 * ep, "efficiency guided {eg} vs plain {ep}");
    // The image keeps its value: the mean agrees with the path tracer's (measured: 0.0635 and
    // 0.0630 over 200 passes at seeds 1 and 2, path tracer 0.0629 at 8192 spp; unguided sppm,
    // its photons sparse in the room, stays 3 % low after 96 passes).
    let (mg, mp) = (guided.film.mean(), path_mean(&scene));
    assert!((mg / mp - 1.0).abs() < 0.02, "mean guided {mg} vs path tracer {mp}");
}

#[test]
fn a_room_seen_whole_is_left_unguided() {
    // In the Cornell box most photons land where the camera looks (0.84 a photon): nothing to
    // gain, and the image is the unguided one.
    let scene = common::scene("cornell");
    let out = render_checked(&scene, &settings(true, 1), 16);
    let stage = out.stats.stages.iter().find(|s| s.name == "photons.guide").unwrap();
    assert!(stage.reason.contains("no guiding needed"), "{stage:?}");
    let plain = render_checked(&scene, &settings(false, 1), 16);
    assert_eq!(out.film.pixels, plain.film.pixels);
    assert!(efficiency(&out) > 0.5, "{}", efficiency(&out));
}

#[test]
fn portal_photons_reach_the_room_and_keep_the_image() {
    // The window as a portal: half the sun's photons go through it, the rest cover the disc
    // outside it (none through it), each stratum's photons carrying its density; the light
    // off the ground comes in as the portal's own photons.
    let mut scene = sunroom(0.3);
    let v = Vec3::new;
    scene.portals = vec![Portal::from_corners([
        v(-0.3, 0.7, 1.0),
        v(0.3, 0.7, 1.0),
        v(0.3, 1.3, 1.0),
        v(-0.3, 1.3, 1.0),
    ])
    .unwrap()];
    let with =
        |portals: bool, passes: u32| RenderSettings { portals: Some(portals), ..settings(false, passes) };
    let portal = render_checked(&scene, &with(true, 128), 16);
    let plain = render_checked(&scene, &with(false, 1), 16);
    let stage = portal.stats.stages.iter().find(|s| s.name == "photons.portals").unwrap();
    assert!(stage.ran && stage.reason.contains("1 portals"), "{stage:?}");
    assert!(!plain.stats.stages.iter().any(|s| s.name == "photons.portals"));
    // The portal stratum alone would make it about 0.5 a photon.
    let (eg, ep) = (efficiency(&portal), efficiency(&plain));
    assert!(eg > 30.0 * ep, "efficiency with the portal {eg} vs without {ep}");
    let (mg, mp) = (portal.film.mean(), path_mean(&scene));
    assert!((mg / mp - 1.0).abs() < 0.02, "mean with the portal {mg} vs path tracer {mp}");
}

#[test]
fn a_portal_anywhere_keeps_the_image() {
    // A portal across the middle of the Cornell box, its inside toward the camera: every path
    // crossing it toward the camera after a diffuse bounce is cut, and the light it carried
    // comes in as the portal's photons instead (a path traced from the portal outward). Light
    // sits on both sides (the ceiling light straddles the plane). The image keeps its value.
    let mut scene = common::scene("cornell");
    let v = Vec3::new;
    let z = 0.28;
    scene.portals = vec![Portal::from_corners([
        v(0.0, 0.0, z),
        v(0.556, 0.0, z),
        v(0.556, 0.5488, z),
        v(0.0, 0.5488, z),
    ])
    .unwrap()];
    let run = |portals: bool| {
        let settings = RenderSettings {
            integrator: Some(IntegratorKind::Sppm),
            portals: Some(portals),
            passes: Some(48),
            photons: Some(50_000),
            spp: Some(2),
            seed: Some(4),
            ..Default::default()
        };
        render_checked(&scene, &settings, 32)
    };
    let (with, without) = (run(true), run(false));
    let stage = with.stats.stages.iter().find(|s| s.name == "photons.portals").unwrap();
    assert!(stage.ran, "{stage:?}");
    let r = common::reference("cornell").downsample(2).mean();
    let (mw, mo) = (with.film.mean(), without.film.mean());
    eprintln!("mean with the portal {mw:.5}, without {mo:.5}, reference {r:.5}");
    assert!((mw / r - 1.0).abs() < 0.01, "with the portal {mw} against {r}");
    assert!((mw / mo - 1.0).abs() < 0.01, "with the portal {mw} against {mo} without");
}

#[test]
fn an_undeclared_window_is_found_and_keeps_the_image() {
    // The sunroom with no portal declared: the rays from what the camera sees that leave the
    // scene all went out through the window, whose wall they cross inside it. The portal found
    // lies in the window (in the thin wall's plane, within its edges) and covers most of it.
    let w = 0.3;
    let scene = sunroom(w);
    // Glazed, the same: the search looks through glass (a pane is part of the opening).
    let glazed = sunroom_seen_from(w, Vec3::new(0.0, 1.0, 0.9), Vec3::new(0.0, 0.4, -0.6), true);
    for s in [&scene, &glazed] {
        let found = openings::find(s, &Bvh::build(&s.mesh), &s.camera);
        assert_eq!(found.portals.len(), 1, "{}", found.reason);
        let p = found.portals[0];
        let corners = [p.corner, p.corner + p.edge_u, p.corner + p.edge_v, p.corner + p.edge_u + p.edge_v];
        for c in corners {
            assert!((c.z - 1.0).abs() < 1e-4, "{c} off the wall's plane");
            assert!(c.x.abs() <= w && (c.y - 1.0).abs() <= w, "{c} outside the window");
            assert!(
                c.x.abs() > 0.999 * w && (c.y - 1.0).abs() > 0.999 * w,
                "{c} short of the window's corner"
            );
        }
    }
    // Rendered with it, the photons reach the room as with a declared portal, and the image
    // keeps its value.
    let with = render_checked(&scene, &RenderSettings { portals: Some(true), ..settings(false, 128) }, 16);
    let plain = render_checked(&scene, &settings(false, 1), 16);
    let stage = with.stats.stages.iter().find(|s| s.name == "portals.found").unwrap();
    assert!(stage.reason.contains("1 openings found"), "{stage:?}");
    assert!(!plain.stats.stages.iter().any(|s| s.name == "portals.found"));
    let (ew, ep) = (efficiency(&with), efficiency(&plain));
    assert!(ew > 30.0 * ep, "efficiency with the portal found {ew} vs without {ep}");
    let (mw, mp) = (with.film.mean(), path_mean(&scene));
    assert!((mw / mp - 1.0).abs() < 0.02, "mean with the portal found {mw} vs path tracer {mp}");
}

#[test]
fn no_opening_is_looked_for_outdoors_or_where_nothing_leaves() {
    // Seen from outside, most rays from what the camera sees leave the scene: no enclosure.
    let outdoors = sunroom_seen_from(0.3, Vec3::new(0.0, 1.5, 6.0), Vec3::new(0.0, 1.0, 0.0), false);
    let found = openings::find(&outdoors, &Bvh::build(&outdoors.mesh), &outdoors.camera);
    assert!(found.portals.is_empty() && found.reason.contains("not an enclosure"), "{}", found.reason);
    // A window too small to matter lets no ray out: nothing found, and nothing changed.
    let closed = sunroom(0.0005);
    let found = openings::find(&closed, &Bvh::build(&closed.mesh), &closed.camera);
    assert!(found.portals.is_empty() && found.reason.contains("no opening"), "{}", found.reason);
    // No sun, no search.
    let cornell = common::scene("cornell");
    let found = openings::find(&cornell, &Bvh::build(&cornell.mesh), &cornell.camera);
    assert!(found.portals.is_empty() && found.reason.contains("no distant light"), "{}", found.reason);
}

#[test]
fn a_pilot_that_stores_nothing_stops_growing() {
    // A floor under the sun, seen from above: every photon leaves the scene at its first
    // bounce, so none is stored anywhere. The pilot stops at its middle size (2^20 photons)
    // instead of growing to 2^23 (a second's work on every such render), and guides nothing.
    let mut b = Builder::default();
    let floor = b.material("floor", diffuse(0.5));
    let v = Vec3::new;
    b.quad([v(-1.0, 0.0, -1.0), v(1.0, 0.0, -1.0), v(1.0, 0.0, 1.0), v(-1.0, 0.0, 1.0)], Vec3::Y, floor);
    b.light(LightDesc::Distant { direction: Vec3::new(-0.6, -1.0, 0.0), irradiance: Vec3::splat(3.0) });
    let scene = b.build("floor", camera(v(0.0, 3.0, 0.0), Vec3::ZERO, Vec3::NEG_Z, 30.0));
    let out = render_checked(&scene, &settings(true, 1), 8);
    let stage = out.stats.stages.iter().find(|s| s.name == "photons.guide").unwrap();
    assert!(stage.reason.starts_with("pilot of 1048576 photons"), "{stage:?}");
    assert!(stage.reason.contains("none stored anywhere"), "{stage:?}");
    assert_eq!(out.stats.photons["indirect"].stored, 0);
}
