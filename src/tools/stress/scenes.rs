//! The stress suite's scenes, built in memory (no files): a small builder for quads, boxes and
//! materials, and one constructor per scene of the suite.

use crate::config::RenderSettings;
use crate::geometry::{TriangleMesh, Vec3};
use crate::light::LightDesc;
use crate::material::Material;
use crate::scene::{Camera, Scene, SceneCamera};
use std::path::PathBuf;

/// Which way the faces of a box look.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Facing {
    Outward,
    Inward,
}

/// Collects triangles, their materials and the lights of a scene.
#[derive(Default)]
pub struct Builder {
    mesh: TriangleMesh,
    tri_material: Vec<u32>,
    materials: Vec<Material>,
    names: Vec<String>,
    lights: Vec<LightDesc>,
}

impl Builder {
    /// Adds a material and returns its index.
    pub fn material(&mut self, name: &str, m: Material) -> u32 {
        self.materials.push(m);
        self.names.push(name.to_owned());
        self.materials.len() as u32 - 1
    }

    fn vertex(&mut self, p: Vec3) -> u32 {
        self.mesh.positions.push(p);
        self.mesh.positions.len() as u32 - 1
    }

    /// One triangle, wound as given.
    pub fn triangle(&mut self, a: Vec3, b: Vec3, c: Vec3, material: u32) {
        let i = [self.vertex(a), self.vertex(b), self.vertex(c)];
        self.mesh.indices.push(i);
        self.tri_material.push(material);
    }

    /// The planar quad `a b c d` (in order around it) as two triangles whose front faces look
    /// along `normal`.
    pub fn quad(&mut self, corners: [Vec3; 4], normal: Vec3, material: u32) {
        let [a, b, c, d] = corners;
        let [a, b, c, d] = if (b - a).cross(c - a).dot(normal) >= 0.0 { [a, b, c, d] } else { [a, d, c, b] };
        let i = [self.vertex(a), self.vertex(b), self.vertex(c), self.vertex(d)];
        self.mesh.indices.extend([[i[0], i[1], i[2]], [i[0], i[2], i[3]]]);
        self.tri_material.extend([material, material]);
    }

    /// The axis-aligned box `[min, max]`: six quads, front faces outward or inward.
    pub fn cuboid(&mut self, min: Vec3, max: Vec3, facing: Facing, material: u32) {
        for axis in 0..3 {
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            for (side, sign) in [(min[axis], -1.0), (max[axis], 1.0)] {
                let corner = |a: f32, b: f32| {
                    let mut p = Vec3::ZERO;
                    p[axis] = side;
                    p[u] = a;
                    p[v] = b;
                    p
                };
                let mut n = Vec3::ZERO;
                n[axis] = if facing == Facing::Outward { sign } else { -sign };
                let corners = [
                    corner(min[u], min[v]),
                    corner(max[u], min[v]),
                    corner(max[u], max[v]),
                    corner(min[u], max[v]),
                ];
                self.quad(corners, n, material);
            }
        }
    }

    pub fn light(&mut self, l: LightDesc) {
        self.lights.push(l);
    }

    /// The scene seen by `camera` (width and height are set by the render settings).
    pub fn build(self, name: &str, camera: Camera) -> Scene {
        Scene {
            path: PathBuf::from(format!("stress/{name}")),
            camera,
            cameras: vec![SceneCamera::still("camera", camera)],
            mesh: self.mesh,
            attributes: Default::default(),
            tri_material: self.tri_material,
            materials: self.materials,
            maps: vec![Default::default(); self.names.len()],
            textured: false,
            textures: Default::default(),
            warnings: Vec::new(),
            material_names: self.names,
            lights: self.lights,
            portals: Vec::new(),
            render: RenderSettings::default(),
        }
    }
}

/// A look-at camera; the views here are fixed and never degenerate.
pub fn camera(eye: Vec3, target: Vec3, up: Vec3, vfov_deg: f32) -> Camera {
    Camera::look_at(eye, target, up, vfov_deg, 32, 32).expect("the stress scenes' cameras are valid")
}

/// Diffuse material of albedo `kd` (grey).
pub fn diffuse(kd: f32) -> Material {
    Material::Diffuse { kd: Vec3::splat(kd) }
}

/// The white furnace of `scenes/furnace` (closed cube `[-1, 1]³` facing inward, albedo 0.5,
/// emitting 1: radiance 2 everywhere), scaled by `scale` about the origin and then moved by
/// `offset`; the camera sits at the centre as in the scene file.
pub fn furnace(scale: f32, offset: Vec3) -> Scene {
    let mut b = Builder::default();
    let m = b.material("furnace", Material::Emissive { kd: Vec3::splat(0.5), ke: Vec3::ONE });
    b.cuboid(-Vec3::ONE * scale + offset, Vec3::ONE * scale + offset, Facing::Inward, m);
    let cam = camera(offset, offset + Vec3::new(0.3, 0.2, 1.0) * scale, Vec3::Y, 90.0);
    b.build("furnace", cam)
}

/// A faceted glass sphere (radius 1, `rings` × `2 rings` quads, outward facing) of index `ior`
/// inside a cube `[-3, 3]³` that emits radiance 1 inward and reflects nothing. Lossless glass in
/// a uniform emitter looks like the emitter: every pixel's exact value is 1, and a camera path
/// cut short inside the glass (light trapped by total internal reflection) brings back less.
pub fn glass_in_furnace(ior: f32, rings: u32) -> Scene {
    let mut b = Builder::default();
    let wall = b.material("wall", Material::Emissive { kd: Vec3::ZERO, ke: Vec3::ONE });
    let glass = b.material("glass", Material::Glass { ior });
    b.cuboid(-Vec3::splat(3.0), Vec3::splat(3.0), Facing::Inward, wall);
    let at = |i: u32, j: u32| {
        let theta = std::f32::consts::PI * i as f32 / rings as f32;
        let phi = std::f32::consts::PI * j as f32 / rings as f32;
        Vec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin())
    };
    for i in 0..rings {
        for j in 0..2 * rings {
            let (p, q, r, s) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            if i > 0 {
                b.triangle(p, r, q, glass);
            }
            if i + 1 < rings {
                b.triangle(p, s, r, glass);
            }
        }
    }
    b.build("glass-in-furnace", camera(Vec3::new(0.0, 0.0, -2.6), Vec3::ZERO, Vec3::Y, 50.0))
}

/// A rotation that puts the plane `y = 0` at an angle to every axis, so that points on it are
/// rounded in all three coordinates.
fn tilt(p: Vec3) -> Vec3 {
    let q = glam::Quat::from_rotation_x(0.5) * glam::Quat::from_rotation_z(0.3);
    q * p
}

/// Albedo of the grazing-light plane.
pub const PLANE_ALBEDO: f32 = 0.5;

/// A 2 km square plane (two triangles), tilted, lit by a distant light of irradiance 1 at
/// `elevation_deg` above it (below it when negative); the camera looks straight down at the
/// middle and sees nothing but the plane.
pub fn grazing_plane(elevation_deg: f32) -> Scene {
    let mut b = Builder::default();
    let m = b.material("plane", diffuse(PLANE_ALBEDO));
    let h = 1000.0;
    let corners =
        [Vec3::new(-h, 0.0, -h), Vec3::new(h, 0.0, -h), Vec3::new(h, 0.0, h), Vec3::new(-h, 0.0, h)];
    b.quad(corners.map(tilt), tilt(Vec3::Y), m);
    let e = elevation_deg.to_radians();
    // The way the light travels: toward -x and down onto the plane.
    let direction = tilt(-Vec3::new(e.cos(), e.sin(), 0.0)).normalize();
    b.light(LightDesc::Distant { direction, irradiance: Vec3::ONE });
    let cam = camera(tilt(Vec3::new(0.0, 10.0, 0.0)), tilt(Vec3::ZERO), tilt(Vec3::Z), 60.0);
    b.build("grazing", cam)
}

/// Irradiance and elevation of the light of the coplanar and touching scenes.
pub const TOP_LIGHT_ELEVATION_DEG: f32 = 60.0;

fn top_light(b: &mut Builder) {
    let e = TOP_LIGHT_ELEVATION_DEG.to_radians();
    let direction = -Vec3::new(0.6 * e.cos(), e.sin(), 0.8 * e.cos());
    b.light(LightDesc::Distant { direction, irradiance: Vec3::ONE });
}

/// Two overlapping coplanar quads at `y = 0.37` (not a round number: rounded in `y`), split
/// along different diagonals, same albedo; the camera looks down at the overlap and the parts
/// covered by one quad only.
pub fn coplanar_quads() -> Scene {
    let mut b = Builder::default();
    let m = b.material("quad", diffuse(PLANE_ALBEDO));
    let y = 0.37;
    let a =
        [Vec3::new(-2.0, y, -2.0), Vec3::new(1.0, y, -2.0), Vec3::new(1.0, y, 2.0), Vec3::new(-2.0, y, 2.0)];
    b.quad(a, Vec3::Y, m);
    let c =
        [Vec3::new(2.0, y, -1.5), Vec3::new(2.0, y, 2.5), Vec3::new(-1.0, y, 2.5), Vec3::new(-1.0, y, -1.5)];
    b.quad(c, Vec3::Y, m);
    top_light(&mut b);
    b.build("coplanar", camera(Vec3::new(0.0, 4.0, 0.0), Vec3::new(0.0, y, 0.0), Vec3::Z, 40.0))
}

/// Two unit cubes sharing the face `x = 1` (touching, coplanar tops), lit from above; the
/// camera looks straight down at the seam and sees the two tops only.
pub fn touching_boxes() -> Scene {
    let mut b = Builder::default();
    let m = b.material("box", diffuse(PLANE_ALBEDO));
    b.cuboid(Vec3::ZERO, Vec3::ONE, Facing::Outward, m);
    b.cuboid(Vec3::X, Vec3::new(2.0, 1.0, 1.0), Facing::Outward, m);
    top_light(&mut b);
    let fov = 2.0 * 0.1f32.atan().to_degrees();
    b.build("touching", camera(Vec3::new(1.0, 5.0, 0.5), Vec3::new(1.0, 0.0, 0.5), Vec3::Z, fov))
}

/// Thickness of the thick walls of the closed boxes, and the gather radius the boxes' renders
/// use: wider than the thick walls, and than the whole thin boxes ([`Walls`]).
pub const WALL: f32 = 0.25;
pub const WALL_GATHER_RADIUS: f32 = 0.2;

/// The walls of a closed box.
#[derive(Clone, Copy, Debug)]
pub enum Walls {
    /// The cavity `[-1, 1]³` inside walls [`WALL`] thick.
    Thick,
    /// A box `[-0.05, 0.05]³` of walls of no thickness, both faces of each diffuse (a lamp's
    /// shade modelled as one surface), the whole scene a twentieth the size: the gather
    /// radius spans the box.
    Thin,
}

impl Walls {
    /// The scene's scale: the thick box's positions are multiplied by it.
    fn scale(self) -> f32 {
        match self {
            Walls::Thick => 1.0,
            Walls::Thin => 0.05,
        }
    }
}

/// A floor facing up: the square `[-half, half]²` at height `y`.
fn floor(b: &mut Builder, half: f32, y: f32, material: u32) {
    let f = half;
    b.quad(
        [Vec3::new(-f, y, -f), Vec3::new(f, y, -f), Vec3::new(f, y, f), Vec3::new(-f, y, f)],
        Vec3::Y,
        material,
    );
}

/// A closed box with `walls`, its cavity `[-k, k]³` (`k` the walls' scale).
fn hollow_box(b: &mut Builder, material: u32, walls: Walls) {
    let k = walls.scale();
    if let Walls::Thick = walls {
        b.cuboid(-Vec3::splat(1.0 + WALL), Vec3::splat(1.0 + WALL), Facing::Outward, material);
    }
    b.cuboid(-Vec3::splat(k), Vec3::splat(k), Facing::Inward, material);
}

/// A closed box with `walls` floating above a floor, lit from outside by a point light; the
/// camera is in its cavity.
pub fn camera_inside_box(walls: Walls) -> Scene {
    let mut b = Builder::default();
    let m = b.material("white", diffuse(0.7));
    hollow_box(&mut b, m, walls);
    let k = walls.scale();
    floor(&mut b, 6.0 * k, -2.0 * k, m);
    b.light(LightDesc::Point {
        position: Vec3::new(0.5, 3.0, 0.3) * k,
        intensity: Vec3::splat(20.0 * k * k),
    });
    let (eye, target) = (Vec3::new(0.2, 0.1, -0.3) * k, Vec3::new(0.5, -0.3, 1.0) * k);
    b.build("camera-inside", camera(eye, target, Vec3::Y, 90.0))
}

/// A point light in the cavity of a closed box with `walls`; the camera is outside, looking at
/// a corner. The thin box stands above a floor (a lamp above a table), which the camera sees
/// around it, 0.16 below the box: further than the indirect gathers' region reaches off the
/// floor (`r / √2`, 0.14 at [`WALL_GATHER_RADIUS`]), so that the floor's gathers cannot reach
/// the photons on the box's inside, but within reach of an irradiance lookup.
pub fn light_inside_box(walls: Walls) -> Scene {
    let mut b = Builder::default();
    let m = b.material("white", diffuse(0.7));
    hollow_box(&mut b, m, walls);
    let k = walls.scale();
    if let Walls::Thin = walls {
        floor(&mut b, 6.0 * k, -k - 0.16, m);
    }
    b.light(LightDesc::Point {
        position: Vec3::new(0.1, 0.2, -0.1) * k,
        intensity: Vec3::splat(5.0 * k * k),
    });
    b.build("light-inside", camera(Vec3::new(3.0, 2.5, -4.0) * k, Vec3::ZERO, Vec3::Y, 40.0))
}

/// Radiance of the back-facing area light.
pub const AREA_LE: f32 = 5.0;

/// An emissive square in `z = 0` facing `+z`, over a floor on its back side (`z < 0`); seen from
/// behind (`front = false`) or from the front.
pub fn back_facing_light(front: bool) -> Scene {
    let mut b = Builder::default();
    let light = b.material("light", Material::Emissive { kd: Vec3::ZERO, ke: Vec3::splat(AREA_LE) });
    let square = [
        Vec3::new(-1.0, -1.0, 0.0),
        Vec3::new(1.0, -1.0, 0.0),
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(-1.0, 1.0, 0.0),
    ];
    b.quad(square, Vec3::Z, light);
    let m = b.material("floor", diffuse(0.7));
    let floor = [
        Vec3::new(-5.0, -1.0, -6.0),
        Vec3::new(5.0, -1.0, -6.0),
        Vec3::new(5.0, -1.0, 0.0),
        Vec3::new(-5.0, -1.0, 0.0),
    ];
    b.quad(floor, Vec3::Y, m);
    let cam = if front {
        camera(Vec3::new(0.0, 0.0, 4.0), Vec3::ZERO, Vec3::Y, 20.0)
    } else {
        camera(Vec3::new(0.0, 0.5, -4.0), Vec3::ZERO, Vec3::Y, 60.0)
    };
    b.build("back-facing", cam)
}

/// A closed box lit from inside by a coloured point light of intensity `scale · (1, 0.5, 0.25)`
/// W/sr, seen from inside.
pub fn lit_box(scale: f32) -> Scene {
    let mut b = Builder::default();
    let m = b.material("white", diffuse(0.6));
    b.cuboid(-Vec3::ONE, Vec3::ONE, Facing::Inward, m);
    let intensity = Vec3::new(1.0, 0.5, 0.25) * scale;
    b.light(LightDesc::Point { position: Vec3::new(0.2, 0.5, 0.1), intensity });
    b.build("power", camera(Vec3::new(0.0, -0.2, -0.8), Vec3::new(0.0, 0.0, 1.0), Vec3::Y, 80.0))
}

/// Height of the point light over the plane of [`lonely_plane`], its intensity and the albedo.
pub const LONELY_HEIGHT: f32 = 1.0;
pub const LONELY_INTENSITY: f32 = 1.0;

/// A plane `y = 0` and a point light above it: every photon leaves the scene after its first
/// (never stored) hit, so no photon is stored.
pub fn lonely_plane() -> Scene {
    let mut b = Builder::default();
    let m = b.material("plane", diffuse(PLANE_ALBEDO));
    let f = 10.0;
    b.quad(
        [Vec3::new(-f, 0.0, -f), Vec3::new(f, 0.0, -f), Vec3::new(f, 0.0, f), Vec3::new(-f, 0.0, f)],
        Vec3::Y,
        m,
    );
    let position = Vec3::new(0.0, LONELY_HEIGHT, 0.0);
    b.light(LightDesc::Point { position, intensity: Vec3::splat(LONELY_INTENSITY) });
    b.build("zero-photons", camera(Vec3::new(0.0, 3.0, 0.0), Vec3::ZERO, Vec3::Z, 60.0))
}

/// Albedo of the single triangle and the irradiance on it.
pub const TRIANGLE_ALBEDO: f32 = 0.8;
pub const TRIANGLE_IRRADIANCE: f32 = 2.0;

/// One diffuse triangle in `y = 0` lit straight from above, seen from above.
pub fn one_triangle() -> Scene {
    let mut b = Builder::default();
    let m = b.material("triangle", diffuse(TRIANGLE_ALBEDO));
    b.triangle(Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 0.0, -1.0), Vec3::new(0.0, 0.0, 1.2), m);
    b.light(LightDesc::Distant { direction: -Vec3::Y, irradiance: Vec3::splat(TRIANGLE_IRRADIANCE) });
    b.build("one-triangle", camera(Vec3::new(0.0, 3.0, 0.0), Vec3::ZERO, Vec3::Z, 60.0))
}

/// The unit square `[0, 1]²` in `y = 0` tiled by `2 columns` slivers: `columns` strips of width
/// `1 / columns`, each cut along its diagonal (aspect ratio `columns`, shared vertices, so the
/// tiling is watertight); lit straight from above with irradiance 1, seen from above (the
/// camera sees only the square).
pub fn slivers(columns: u32) -> Scene {
    let mut b = Builder::default();
    let m = b.material("slivers", diffuse(PLANE_ALBEDO));
    let n = columns as usize;
    let mut mesh =
        TriangleMesh { positions: Vec::with_capacity(2 * (n + 1)), indices: Vec::with_capacity(2 * n) };
    for i in 0..=columns {
        let x = i as f32 / columns as f32;
        mesh.positions.extend([Vec3::new(x, 0.0, 0.0), Vec3::new(x, 0.0, 1.0)]);
    }
    for i in 0..columns {
        let (b0, t0, b1, t1) = (2 * i, 2 * i + 1, 2 * i + 2, 2 * i + 3);
        mesh.indices.extend([[b0, t1, b1], [b0, t0, t1]]);
    }
    b.tri_material = vec![m; mesh.len()];
    b.mesh = mesh;
    b.light(LightDesc::Distant { direction: -Vec3::Y, irradiance: Vec3::ONE });
    let fov = 2.0 * 0.2f32.atan().to_degrees();
    b.build("slivers", camera(Vec3::new(0.5, 2.0, 0.5), Vec3::new(0.5, 0.0, 0.5), Vec3::Z, fov))
}
