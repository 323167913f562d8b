//! Openings found where nobody declared one: the window a sun shines through into the room the
//! camera is in, made a portal ([`crate::light::Portal`]) as if the scene had declared it.
//!
//! A declared `[[portal]]` is what makes a sunlit room easy (see [`crate::photon::portal`]):
//! the sun's photons go through the window instead of over the whole scene's disc, and the
//! light off the ground outside comes in as the portal's own photons instead of as the few that
//! happen to bounce in. Scenes made elsewhere do not declare one. So where the scene declares
//! none and has a distant light, the openings are looked for before the photon pass:
//!
//! 1. **What the camera sees.** A grid of camera rays (48 × 48) lands on the surfaces the
//!    camera sees; mirrors and glass are skipped.
//! 2. **Rays that leave.** From each landing, a ray toward each distant light and four
//!    cosine-distributed rays. Those that meet nothing have left the scene; if more than a
//!    fifth do, the camera is not in an enclosure (an outdoor view) and nothing is looked for.
//! 3. **The wall around each.** Around each ray that left, rays turned a little off it (8
//!    directions, at 0.03 to 0.5 radians) find the surfaces that bound the opening. Of those
//!    that face back toward the ray's start (a wall's face, not the sides of the opening) and
//!    whose plane the ray crosses near where they were met, the plane it crosses first is the
//!    wall's inside face: the ray crossed it inside the opening.
//! 4. **Openings.** Crossings of the same wall plane are grouped, those close together (within
//!    the typical distance from a crossing to the wall around it) joined into one opening.
//! 5. **A rectangle in the open.** Along each direction of the hull of an opening's crossings
//!    and of the world's axes, the rectangle holding them is checked to lie in the open (at
//!    9 × 9 points, short rays across the plane either way meet nothing; else it is shrunk
//!    about its centre, 10 % at a time, five times at most), then each side is pushed out, a
//!    twentieth of its size at a time, while its new edge stays in the open: the crossings
//!    seldom fill an opening (rays crossing near its edges tend to meet its sides). The
//!    largest is kept: a window cut along the scene's axes is found whole, an arched or round
//!    one as the rectangle its sides allow.
//! 6. **Through the wall.** The rectangle moves out through the wall's thickness, a fiftieth
//!    of its size at a time, while the way is clear and the wall still stands around it, to
//!    the wall's outside face. There the opening's sides (a window's sill and jambs, sunlit)
//!    are inside the portal, and the sun's photons that land on them bounce in as they would
//!    without one; left on the inside face, a portal cut those photons and brought their light
//!    in again as its own photons, whose power varies with the few directions that see the
//!    sunlit sill: on the sunroom (a 15 cm wall) that made the images noisier than no portal.
//!
//! The search looks through glass: a window's pane is part of its opening.
//!
//! The portal only changes where photons go: every light path is counted once whatever the
//! portal is ([`crate::photon::portal`]), so a portal that misses part of an opening costs
//! noise, not bias. The search depends on the scene and its first camera only (a fixed seed),
//! so parts of a render made on other machines find the same portals.

use crate::accel::{Accel, Hit};
use crate::frame::SurfaceHit;
use crate::geometry::{offset_ray_origin, Ray};
use crate::light::{LightDesc, Portal};

use crate::material::{face_forward, Material};
use crate::sampling::{sample_cosine_hemisphere, Frame as Basis};
use crate::scene::{Camera, Scene};
use glam::{Vec2, Vec3};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg32;

/// Camera rays per side of the pilot grid.
const GRID: u32 = 48;
/// Cosine-distributed rays from each landing, beside one toward each distant light.
const RANDOM_RAYS: usize = 4;
/// Above this share of rays leaving the scene the camera is not in an enclosure.
const MAX_OPEN: f32 = 0.2;
/// Rays that leave needed to look for an opening, and crossings needed to make one.
const MIN_CROSSINGS: usize = 8;
/// Angles (radians) at which the rays around a ray that left are turned off it, in order.
const RIM_ANGLES: [f32; 5] = [0.03, 0.06, 0.12, 0.25, 0.5];
/// Directions around it.
const RIM_DIRECTIONS: usize = 8;
/// Test points per side of a portal.
const CHECKS: usize = 9;

/// The portals found and what the search says about them.
#[derive(Debug, Default)]
pub struct Found {
    pub portals: Vec<Portal>,
    pub reason: String,
    pub rays: u64,
}

/// The rays of the search, which look through glass: a window's pane is part of its opening
/// (the sun's photons and the light off the ground come in through it), so a ray through it
/// has left, and a rectangle across it lies in the open.
struct Caster<'a, A: Accel> {
    scene: &'a Scene,
    accel: &'a A,
}

impl<A: Accel> Caster<'_, A> {
    /// The first hit along `ray` on a surface that is not glass (at most 8 panes passed).
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        let mut r = *ray;
        for _ in 0..8 {
            let h = self.accel.intersect(&r)?;
            if !matches!(self.scene.material(h.prim), Material::Glass { .. }) {
                return Some(h);
            }
            // Just past the pane (a few ulps of the distance and of the coordinates).
            r.t_min = h.t + (h.t + r.origin.abs().max_element()) * 1e-5;
            if !(r.t_min < r.t_max) {
                return None;
            }
        }
        None
    }

    /// Whether something that is not glass lies along `ray`.
    fn occluded(&self, ray: &Ray) -> bool {
        self.intersect(ray).is_some()
    }
}

/// A ray from a seen surface that met nothing.
#[derive(Clone, Copy, Debug)]
struct Escape {
    origin: Vec3,
    dir: Vec3,
}

/// Where a ray that left crossed the wall around its opening.
#[derive(Clone, Copy, Debug)]
struct Crossing {
    /// The wall plane's unit normal, toward the inside (the ray's start).
    normal: Vec3,
    /// Its offset: `normal · x` for points `x` of the plane.
    offset: f32,
    /// Where the ray crossed it.
    at: Vec3,
    /// How far from `at` the nearest surface found around the ray lies in the plane.
    rim: f32,
}

/// Looks for the openings through which the scene's distant lights shine into what `camera`
/// sees (see the module's documentation); none when the scene has no distant light.
pub fn find<A: Accel>(scene: &Scene, accel: &A, camera: &Camera) -> Found {
    let suns: Vec<Vec3> = scene
        .lights
        .iter()
        .filter_map(|l| match l {
            LightDesc::Distant { direction, .. } => direction.try_normalize().map(|d| -d),
            _ => None,
        })
        .collect();
    if suns.is_empty() {
        return Found { reason: "no distant light".into(), ..Found::default() };
    }
    let mut rays = 0u64;
    let caster = Caster { scene, accel };
    let accel = &caster;
    let (escapes, cast) = escapes(scene, accel, camera, &suns, &mut rays);
    let open = escapes.len() as f32 / cast.max(1) as f32;
    if escapes.len() < MIN_CROSSINGS {
        let reason =
            format!("{} of {cast} rays from what the camera sees leave the scene: no opening", escapes.len());
        return Found { reason, rays, ..Found::default() };
    }
    if open > MAX_OPEN {
        let reason = format!(
            "{:.0} % of the rays from what the camera sees leave the scene: not an enclosure",
            100.0 * open
        );
        return Found { reason, rays, ..Found::default() };
    }
    let crossings: Vec<Crossing> =
        escapes.iter().filter_map(|e| crossing(scene, accel, e, &mut rays)).collect();
    let mut portals = Vec::new();
    for group in openings(&crossings) {
        if group.len() < MIN_CROSSINGS {
            continue;
        }
        if let Some(p) = portal(accel, &group, &mut rays) {
            portals.push(p);
        }
    }
    let shapes: Vec<String> = portals
        .iter()
        .map(|p| {
            let c = p.corner + 0.5 * (p.edge_u + p.edge_v);
            format!(
                "{:.3} x {:.3} at ({:.3}, {:.3}, {:.3})",
                p.edge_u.length(),
                p.edge_v.length(),
                c.x,
                c.y,
                c.z
            )
        })
        .collect();
    let reason = format!(
        "{} of {cast} rays from what the camera sees leave the scene; {} openings found{}{}",
        escapes.len(),
        portals.len(),
        if shapes.is_empty() { "" } else { ": " },
        shapes.join(", ")
    );
    Found { portals, reason, rays }
}

/// The rays from the surfaces `camera` sees toward the `suns` (unit, toward the light) and in
/// random directions that meet nothing, and how many were cast.
fn escapes<A: Accel>(
    scene: &Scene,
    accel: &Caster<'_, A>,
    camera: &Camera,
    suns: &[Vec3],
    rays: &mut u64,
) -> (Vec<Escape>, u64) {
    let mut rng = Pcg32::seed_from_u64(0x0BE7_1175);
    let (w, h) = (camera.width as f32, camera.height as f32);
    let mut out = Vec::new();
    let mut cast = 0u64;
    for j in 0..GRID {
        for i in 0..GRID {
            let (x, y) = ((i as f32 + 0.5) * w / GRID as f32, (j as f32 + 0.5) * h / GRID as f32);
            let ray = camera.ray(x, y);
            *rays += 1;
            let Some(hit) = accel.intersect(&ray).and_then(|h| SurfaceHit::new(scene, h)) else { continue };
            if scene.material(hit.prim).is_specular() {
                continue;
            }
            let n = face_forward(hit.n, -ray.dir);
            let basis = Basis::from_z(n);
            let random =
                (0..RANDOM_RAYS).map(|_| basis.from_local(sample_cosine_hemisphere([rng.gen(), rng.gen()])));
            for d in suns.iter().copied().filter(|s| s.dot(n) > 0.0).chain(random) {
                let d = d.normalize();
                let r = Ray::new(hit.spawn(d), d);
                cast += 1;
                *rays += 1;
                if accel.intersect(&r).is_none() {
                    out.push(Escape { origin: r.origin, dir: d });
                }
            }
        }
    }
    (out, cast)
}

/// Where the ray `e` crossed the inside face of the wall around its opening: rays turned off
/// it by [`RIM_ANGLES`] (the smallest that meets something) in [`RIM_DIRECTIONS`] directions
/// meet the surfaces around the opening; of those that face back toward its start (within 60
/// degrees), whose plane it crosses near where they were met (not a roof or a ground far off),
/// the plane it crosses first. `None` if none qualifies.
fn crossing<A: Accel>(scene: &Scene, accel: &Caster<'_, A>, e: &Escape, rays: &mut u64) -> Option<Crossing> {
    let (from, dir) = (e.origin, e.dir);
    let (t1, t2) = dir.any_orthonormal_pair();
    let mut rims: Vec<(Vec3, Vec3)> = Vec::new();
    for k in 0..RIM_DIRECTIONS {
        let (s, c) = (std::f32::consts::TAU * k as f32 / RIM_DIRECTIONS as f32).sin_cos();
        let side = c * t1 + s * t2;
        for a in RIM_ANGLES {
            let d = (dir + a * side).normalize();
            *rays += 1;
            let Some(h) = accel.intersect(&Ray::new(from, d)) else { continue };
            let Some(n) = scene.mesh.normal(h.prim) else { break };
            let n = if n.dot(d) > 0.0 { -n } else { n };
            rims.push((from + h.t * d, n));
            break;
        }
    }
    let mut best: Option<(f32, Vec3, f32)> = None;
    for &(p, n) in &rims {
        let denom = n.dot(dir);
        if denom > -0.5 {
            continue;
        }
        let offset = n.dot(p);
        let t = (offset - n.dot(from)) / denom;
        // How far off the ray the surface was met, and how far from there the ray crosses its
        // plane.
        let off_ray = (p - from).reject_from_normalized(dir).length();
        let near = (from + t * dir - p).length() <= 3.0 * off_ray;
        if t > 0.0 && t.is_finite() && near && best.is_none_or(|b| t < b.0) {
            best = Some((t, n, offset));
        }
    }
    let (t, normal, offset) = best?;
    let at = from + t * dir;
    // The nearest surface around the crossing, measured in the plane.
    let rim = rims
        .iter()
        .map(|&(p, _)| {
            let q = p - normal * (normal.dot(p) - offset);
            (q - at).length()
        })
        .fold(f32::INFINITY, f32::min);
    (rim.is_finite() && rim > 0.0).then_some(Crossing { normal, offset, at, rim })
}

/// The crossings grouped by opening: the same wall plane, and chained by neighbours nearer
/// than the median distance from a crossing to the wall around it.
fn openings(crossings: &[Crossing]) -> Vec<Vec<Crossing>> {
    let n = crossings.len();
    let mut parent: Vec<usize> = (0..n).collect();
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    let mut rims: Vec<f32> = crossings.iter().map(|c| c.rim).collect();
    rims.sort_by(f32::total_cmp);
    let link = rims.get(n / 2).copied().unwrap_or(0.0);
    for i in 0..n {
        for j in i + 1..n {
            let (a, b) = (&crossings[i], &crossings[j]);
            let scale = a.at.abs().max_element().max(b.at.abs().max_element()).max(link);
            let same_plane = a.normal.dot(b.normal) > 0.99 && (a.offset - b.offset).abs() <= 1e-3 * scale;
            if same_plane && (a.at - b.at).length() <= link {
                let (ra, rb) = (root(&mut parent, i), root(&mut parent, j));
                parent[ra] = rb;
            }
        }
    }
    let mut groups: std::collections::BTreeMap<usize, Vec<Crossing>> = Default::default();
    for (i, c) in crossings.iter().enumerate() {
        let r = root(&mut parent, i);
        groups.entry(r).or_default().push(*c);
    }
    groups.into_values().collect()
}

/// The portal of one opening: in the crossings' (common) plane, the largest of the rectangles
/// fitted to the crossings ([`fit`]) and to the opening's edges ([`edges`]) along each
/// direction of their hull's edges and of the world's axes, then moved out through the wall
/// ([`through_the_wall`]) onto its outside face and fitted to the edges there; `None` if no
/// rectangle lies in the open.
fn portal<A: Accel>(accel: &Caster<'_, A>, group: &[Crossing], rays: &mut u64) -> Option<Portal> {
    let normal = group.iter().map(|c| c.normal).sum::<Vec3>().try_normalize()?;
    let offset = group.iter().map(|c| c.offset).sum::<f32>() / group.len() as f32;
    let (u, v) = normal.any_orthonormal_pair();
    let on_plane = |p: Vec3| p - normal * (normal.dot(p) - offset);
    let plane = Plane { origin: on_plane(group[0].at), u, v, normal };
    let points: Vec<Vec2> = group
        .iter()
        .map(|c| {
            let d = on_plane(c.at) - plane.origin;
            Vec2::new(d.dot(u), d.dot(v))
        })
        .collect();
    let hull = convex_hull(&points);
    if hull.len() < 3 {
        return None;
    }
    // Openings are mostly cut along the scene's axes, or along their own edges (the hull's).
    // The world's axes first: a hull edge a fraction of a degree off one is not tried again.
    let mut axes: Vec<Vec2> = [Vec3::X, Vec3::Y, Vec3::Z]
        .iter()
        .filter_map(|w| Vec2::new(w.dot(u), w.dot(v)).try_normalize())
        .collect();
    axes.extend((0..hull.len()).filter_map(|i| (hull[(i + 1) % hull.len()] - hull[i]).try_normalize()));
    let mut best: Option<(f32, Rect)> = None;
    let mut tried: Vec<Vec2> = Vec::new();
    for axis in axes {
        // The same rectangle's axes a quarter turn apart, or within a degree of it.
        if tried.iter().any(|t| t.dot(axis).abs().max(t.perp_dot(axis).abs()) > 0.99985) {
            continue;
        }
        tried.push(axis);
        let (lo, hi) =
            hull.iter().fold((Vec2::splat(f32::INFINITY), Vec2::splat(f32::NEG_INFINITY)), |(lo, hi), p| {
                let q = Vec2::new(p.dot(axis), p.dot(axis.perp()));
                (lo.min(q), hi.max(q))
            });
        if let Some(rect) = fit(accel, &plane, axis, lo, hi, rays).map(|r| edges(accel, &plane, r, rays)) {
            let area = (rect.hi - rect.lo).x * (rect.hi - rect.lo).y;
            if best.as_ref().is_none_or(|b| area > b.0) {
                best = Some((area, rect));
            }
        }
    }
    let (_, rect) = best?;
    let out = through_the_wall(accel, &plane, &rect, rays);
    let moved = Plane { origin: plane.origin - normal * out, ..plane };
    // On the outside face exactly, with the opening's edges found to a ten-thousandth of its
    // size: a portal a fraction of a millimetre inside the wall, or a few per cent short of
    // the opening, let through the few heavy photons it is there to stop.
    let face = outside_face(accel, &moved, &rect, rays).unwrap_or(moved);
    let rect = edges(accel, &face, rect, rays);

    let corner = rect.at(&face, 0.0, 0.0);
    Some(Portal {
        corner,
        edge_u: rect.at(&face, 1.0, 0.0) - corner,
        edge_v: rect.at(&face, 0.0, 1.0) - corner,
    })
}

/// The plane of the wall's outside face around `rect` (moved out through the wall to near
/// it): rays from points beyond its edges, well outside, back toward the wall meet the face;
/// `None` unless most of them meet it in one plane.
fn outside_face<A: Accel>(
    accel: &Caster<'_, A>,
    plane: &Plane,
    rect: &Rect,
    rays: &mut u64,
) -> Option<Plane> {
    let size = rect.size();
    let mut offsets: Vec<f32> = (0..20)
        .filter_map(|k| {
            let start = rect.beyond(plane, k) - plane.normal * (0.2 * size);
            *rays += 1;
            let h = accel.intersect(&Ray::segment(start, plane.normal, 0.0, 0.4 * size))?;
            Some(plane.normal.dot(start + h.t * plane.normal))
        })
        .collect();
    if offsets.len() < 10 {
        return None;
    }
    offsets.sort_by(f32::total_cmp);
    let median = offsets[offsets.len() / 2];
    let agree = offsets.iter().filter(|&&o| (o - median).abs() <= 1e-3 * size).count();
    if agree < 10 {
        return None;
    }
    let origin = plane.origin + plane.normal * (median - plane.normal.dot(plane.origin));
    Some(Plane { origin, ..*plane })
}

/// `rect` with each side moved to the opening's edge in `plane` (the wall's face): the last
/// position, to a ten-thousandth of the rectangle's size, at which the side's points are in
/// the open, searched out (or in) a twentieth of the size at a time, then by bisection, and
/// moved back by twice that.
fn edges<A: Accel>(accel: &Caster<'_, A>, plane: &Plane, rect: Rect, rays: &mut u64) -> Rect {
    let size = rect.size();
    let mut r = rect;
    for side in 0..4 {
        // The side at `x`: its points in the open?
        let mut open = |r: &Rect, x: f32| {
            let m = r.with_side(side, x);
            (0..CHECKS)
                .all(|k| in_the_open(accel, m.on_side(plane, side, span(k)), plane.normal, 1e-3 * size, rays))
        };
        let (now, outward) = r.side(side);
        let step = 0.05 * size * outward;
        // A bracket: `good` in the open, `bad` not.
        let (mut good, mut bad) = (None, None);
        let mut x = now;
        for _ in 0..20 {
            if open(&r, x) {
                good = Some(x);
                if bad.is_some() {
                    break;
                }
                x += step;
            } else {
                bad = Some(x);
                if good.is_some() {
                    break;
                }
                x -= step;
            }
        }
        let (Some(mut g), Some(mut b)) = (good, bad) else {
            // Open all the way out (or never): leave the side where it was.
            continue;
        };
        while (b - g).abs() > 1e-4 * size {
            let m = 0.5 * (g + b);
            if open(&r, m) {
                g = m;
            } else {
                b = m;
            }
        }
        // Back by twice the search's precision: the points tested along the side cannot
        // see the wall's edge closer than that.
        r = r.with_side(side, g - 2e-4 * size * outward);
    }
    r
}

/// A plane with a unit normal toward the inside and an orthonormal basis in it.
struct Plane {
    origin: Vec3,
    u: Vec3,
    v: Vec3,
    normal: Vec3,
}

/// A rectangle of a [`Plane`]: `[lo, hi]` along the unit `axis` and its perpendicular (plane
/// coordinates).
#[derive(Clone, Copy, Debug)]
struct Rect {
    axis: Vec2,
    lo: Vec2,
    hi: Vec2,
}

impl Rect {
    /// The point at `(s, t)` of the rectangle (`[0, 1]²`).
    fn at(&self, plane: &Plane, s: f32, t: f32) -> Vec3 {
        let q = self.lo + (self.hi - self.lo) * Vec2::new(s, t);
        let q = self.axis * q.x + self.axis.perp() * q.y;
        plane.origin + plane.u * q.x + plane.v * q.y
    }

    fn size(&self) -> f32 {
        (self.hi - self.lo).max_element()
    }

    /// Where side `side` (0, 1: low and high `x`; 2, 3: low and high `y`) lies, and the sign
    /// that moves it outward.
    fn side(&self, side: usize) -> (f32, f32) {
        match side {
            0 => (self.lo.x, -1.0),
            1 => (self.hi.x, 1.0),
            2 => (self.lo.y, -1.0),
            _ => (self.hi.y, 1.0),
        }
    }

    /// The rectangle with side `side` moved to `x`.
    fn with_side(mut self, side: usize, x: f32) -> Rect {
        match side {
            0 => self.lo.x = x,
            1 => self.hi.x = x,
            2 => self.lo.y = x,
            _ => self.hi.y = x,
        }
        self
    }

    /// The point at fraction `t` along side `side`.
    fn on_side(&self, plane: &Plane, side: usize, t: f32) -> Vec3 {
        match side {
            0 => self.at(plane, 0.0, t),
            1 => self.at(plane, 1.0, t),
            2 => self.at(plane, t, 0.0),
            _ => self.at(plane, t, 1.0),
        }
    }

    /// Point `k` (of 20: five a side) a tenth of the rectangle's size beyond its edges.
    fn beyond(&self, plane: &Plane, k: usize) -> Vec3 {
        let margin = 0.1 * self.size() / (self.hi - self.lo).max(Vec2::splat(f32::MIN_POSITIVE));
        let t = 0.1 + 0.2 * (k % 5) as f32;
        match k / 5 {
            0 => self.at(plane, -margin.x, t),
            1 => self.at(plane, 1.0 + margin.x, t),
            2 => self.at(plane, t, -margin.y),
            _ => self.at(plane, t, 1.0 + margin.y),
        }
    }
}

/// Test point `k` of [`CHECKS`] along a side (or a row), just inside its ends.
fn span(k: usize) -> f32 {
    0.005 + 0.99 * k as f32 / (CHECKS - 1) as f32
}

/// The rectangle `[lo, hi]` along `axis`, checked to lie in the open (9 × 9 points, shrunk
/// about its centre 10 % at a time until they are, at most five times), then each side pushed
/// out, a twentieth of its size at a time, while its new edge stays in the open: the crossings
/// seldom fill an opening (rays crossing near its edges tend to meet its sides). `None` if it
/// never lies in the open.
fn fit<A: Accel>(
    accel: &Caster<'_, A>,
    plane: &Plane,
    axis: Vec2,
    lo: Vec2,
    hi: Vec2,
    rays: &mut u64,
) -> Option<Rect> {
    let size = (hi - lo).max_element();
    if !(size > 0.0) {
        return None;
    }
    let mut open = |p: Vec3| in_the_open(accel, p, plane.normal, 1e-3 * size, rays);
    let (centre, half) = (0.5 * (lo + hi), 0.5 * (hi - lo));
    let mut shrink = 1.0;
    let mut rect = loop {
        let r = Rect { axis, lo: centre - half * shrink, hi: centre + half * shrink };
        if (0..CHECKS * CHECKS).all(|k| open(r.at(plane, span(k % CHECKS), span(k / CHECKS)))) {
            break r;
        }
        shrink -= 0.1;
        if shrink < 0.45 {
            return None;
        }
    };
    let step = 0.05 * size;
    for side in 0..4 {
        for _ in 0..20 {
            let (x, outward) = rect.side(side);
            let r = rect.with_side(side, x + outward * step);
            if !(0..CHECKS).all(|k| open(r.on_side(plane, side, span(k)))) {
                break;
            }
            rect = r;
        }
    }
    Some(rect)
}

/// How far the rectangle moves out (against the plane's normal) through the wall it is cut
/// in, to its outside face: a fiftieth of its size at a time, while the way is clear (5 × 5
/// rays) and the wall still stands around it (at least 15 of 20 points a tenth of its size
/// beyond its edges are hidden from its centre: they lie inside the wall). On a wall of no
/// thickness, nowhere.
fn through_the_wall<A: Accel>(accel: &Caster<'_, A>, plane: &Plane, rect: &Rect, rays: &mut u64) -> f32 {
    let shift = |q: Vec3, by: f32| q - plane.normal * by;
    let step = 0.02 * rect.size();
    let grid = |k: usize| 0.1 + 0.2 * k as f32;
    let mut out = 0.0f32;
    for _ in 0..200 {
        let next = out + step;
        let clear = (0..25).all(|k| {
            *rays += 1;
            let p = shift(rect.at(plane, grid(k % 5), grid(k / 5)), out);
            !accel.occluded(&Ray::segment(p, -plane.normal, 0.0, step))
        });
        if !clear {
            break;
        }
        let centre = shift(rect.at(plane, 0.5, 0.5), next);
        let walled = (0..20)
            .filter(|&k| {
                let d = shift(rect.beyond(plane, k), next) - centre;
                *rays += 1;
                accel.occluded(&Ray::segment(centre, d.normalize(), 0.0, d.length()))
            })
            .count();
        if walled < 15 {
            break;
        }
        out = next;
    }
    out
}

/// Whether short rays across the plane of unit normal `n` at `p`, either way, meet nothing
/// within `reach` (plus the rounding of `p`).
fn in_the_open<A: Accel>(accel: &Caster<'_, A>, p: Vec3, n: Vec3, reach: f32, rays: &mut u64) -> bool {
    [n, -n].iter().all(|&side| {
        let start = offset_ray_origin(p, Vec3::ZERO, -side) - reach * side;
        *rays += 1;
        !accel.occluded(&Ray::segment(start, side, 0.0, 2.0 * reach + (start - p).length()))
    })
}

/// The convex hull of `points`, counter-clockwise (Andrew's monotone chain).
fn convex_hull(points: &[Vec2]) -> Vec<Vec2> {
    let mut p: Vec<Vec2> = points.iter().copied().filter(|q| q.is_finite()).collect();
    p.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    p.dedup();
    if p.len() < 3 {
        return p;
    }
    let cross = |o: Vec2, a: Vec2, b: Vec2| (a - o).perp_dot(b - o);
    let chain = |points: &mut dyn Iterator<Item = Vec2>| {
        let mut out: Vec<Vec2> = Vec::new();
        for q in points {
            while out.len() >= 2 && cross(out[out.len() - 2], out[out.len() - 1], q) <= 0.0 {
                out.pop();
            }
            out.push(q);
        }
        out.pop();
        out
    };
    let mut hull = chain(&mut p.iter().copied());
    hull.extend(chain(&mut p.iter().rev().copied()));
    hull
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::accel::bvh::Bvh;

    /// The portal found in the shipped scene `name`, and the search's reason.
    fn found(name: &str) -> (Vec<Portal>, String) {
        let scene = Scene::load(format!("scenes/sunroom/{name}.toml")).unwrap();
        let f = find(&scene, &Bvh::build(&scene.mesh), &scene.camera);
        (f.portals, f.reason)
    }

    #[test]
    fn the_sunrooms_window_is_found_on_its_outside_face() {
        // The window of scenes/sunroom (x 0.05..0.55, y 1.15..1.75 in a wall 15 cm thick whose
        // outside face is z = 1.65), as sunroom-portal.toml declares it by hand; from inside the
        // house on the 40 m ground and on the 400 m one (fewer rays leave: 1 in 1.7 million sun
        // photons enters).
        for name in ["sunroom", "sunroom-wide"] {
            let (portals, reason) = found(name);
            assert_eq!(portals.len(), 1, "{name}: {reason}");
            let p = portals[0];
            let corners =
                [p.corner, p.corner + p.edge_u, p.corner + p.edge_v, p.corner + p.edge_u + p.edge_v];
            let (lo, hi) = corners
                .iter()
                .fold((Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)), |(lo, hi), &c| (lo.min(c), hi.max(c)));
            let (want_lo, want_hi) = (Vec3::new(0.05, 1.15, 1.65), Vec3::new(0.55, 1.75, 1.65));
            assert!((lo - want_lo).abs().max_element() < 1e-3, "{name}: {lo} for {want_lo}");
            assert!((hi - want_hi).abs().max_element() < 1e-3, "{name}: {hi} for {want_hi}");
            // Never past the opening's edges into the wall.
            assert!(
                lo.cmpge(want_lo - Vec3::splat(1e-6)).all() && hi.cmple(want_hi + Vec3::splat(1e-6)).all(),
                "{name}: {lo} {hi}"
            );
        }
    }

    #[test]
    fn the_hull_keeps_the_corners_and_drops_the_inside() {
        let square = [Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y, Vec2::splat(0.5), Vec2::new(0.5, 0.0)];
        let hull = convex_hull(&square);
        assert_eq!(hull.len(), 4, "{hull:?}");
        for c in [Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y] {
            assert!(hull.contains(&c));
        }
        // Counter-clockwise.
        let area: f32 = (0..4).map(|i| hull[i].perp_dot(hull[(i + 1) % 4])).sum();
        assert!(area > 0.0);
    }
}
