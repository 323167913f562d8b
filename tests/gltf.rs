//! glTF 2.0 input: the analytic and differential checks of the real-scenes issue.
//!
//! - The furnace as a glTF cube (emissive 1, base colour 0.5) renders exactly 2.0.
//! - The Cornell box rebuilt as glTF (one primitive per material, the camera on a node, the
//!   light's radiance through `KHR_materials_emissive_strength`) renders as the OBJ one does.
//! - Node transforms: a child's TRS under a parent's matrix places a triangle, a light and a
//!   camera where the composition says; a mirroring one keeps the front face.
//! - A constant PNG base-colour texture (file, buffer view or data URI) renders as its
//!   constant bit for bit, the base colour factor multiplying it.

use crate::common;

use crate::common::render_checked;
use glam::{Mat4, Quat, Vec3};
use photonmap::config::{IntegratorKind, RenderSettings};
use photonmap::film::Film;
use photonmap::light::LightDesc;
use photonmap::material::Material;
use photonmap::scene::Scene;
use serde_json::{json, Value};
use std::path::Path;

/// Builds a glTF: binary data in one buffer (written as `<name>.bin`, or inline as a data URI),
/// accessors over it, and whatever JSON the test adds.
#[derive(Default)]
struct Gltf {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Gltf {
    fn view(&mut self, bytes: &[u8]) -> usize {
        while self.bin.len() % 4 != 0 {
            self.bin.push(0);
        }
        self.views.push(json!({"buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len()}));
        self.bin.extend_from_slice(bytes);
        self.views.len() - 1
    }

    /// An accessor of float vectors (`ty` VEC2/VEC3).
    fn floats(&mut self, data: &[f32], n: usize, ty: &str) -> usize {
        let bytes: Vec<u8> = data.iter().flat_map(|x| x.to_le_bytes()).collect();
        let view = self.view(&bytes);
        self.accessors
            .push(json!({"bufferView": view, "componentType": 5126, "count": data.len() / n, "type": ty}));
        self.accessors.len() - 1
    }

    fn indices(&mut self, data: &[u32]) -> usize {
        let bytes: Vec<u8> = data.iter().flat_map(|&x| (x as u16).to_le_bytes()).collect();
        let view = self.view(&bytes);
        self.accessors
            .push(json!({"bufferView": view, "componentType": 5123, "count": data.len(), "type": "SCALAR"}));
        self.accessors.len() - 1
    }

    /// A primitive's JSON: positions, optional uvs, indices, material.
    fn primitive(
        &mut self,
        positions: &[Vec3],
        uvs: Option<&[[f32; 2]]>,
        tris: &[[u32; 3]],
        material: usize,
    ) -> Value {
        let p: Vec<f32> = positions.iter().flat_map(|v| v.to_array()).collect();
        let position = self.floats(&p, 3, "VEC3");
        // glTF requires the bounds of POSITION.
        let lo = positions.iter().fold(Vec3::INFINITY, |a, &b| a.min(b));
        let hi = positions.iter().fold(Vec3::NEG_INFINITY, |a, &b| a.max(b));
        self.accessors[position]["min"] = json!(lo.to_array());
        self.accessors[position]["max"] = json!(hi.to_array());
        let mut attributes = json!({"POSITION": position});
        if let Some(uv) = uvs {
            let t: Vec<f32> = uv.iter().flatten().copied().collect();
            attributes["TEXCOORD_0"] = json!(self.floats(&t, 2, "VEC2"));
        }
        let i: Vec<u32> = tris.iter().flatten().copied().collect();
        json!({"attributes": attributes, "indices": self.indices(&i), "material": material})
    }

    /// Writes `dir/<name>.gltf` (and `<name>.bin`) with `extra`'s top-level members.
    fn write(self, dir: &Path, name: &str, extra: Value) -> std::path::PathBuf {
        std::fs::write(dir.join(format!("{name}.bin")), &self.bin).unwrap();
        let mut root = json!({
            "asset": {"version": "2.0"},
            "buffers": [{"uri": format!("{name}.bin"), "byteLength": self.bin.len()}],
            "bufferViews": self.views,
            "accessors": self.accessors,
        });
        for (k, v) in extra.as_object().unwrap() {
            root[k] = v.clone();
        }
        let path = dir.join(format!("{name}.gltf"));
        std::fs::write(&path, serde_json::to_string_pretty(&root).unwrap()).unwrap();
        path
    }
}

/// The cube `[-1, 1]^3`, faces wound inward, each face's corners at uv (0,0) (1,0) (1,1) (0,1).
fn cube() -> (Vec<Vec3>, Vec<[f32; 2]>, Vec<[u32; 3]>) {
    let (mut p, mut uv, mut t) = (Vec::new(), Vec::new(), Vec::new());
    for axis in 0..3 {
        for side in [-1.0f32, 1.0] {
            let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
            let corner = |x: f32, y: f32| {
                let mut c = Vec3::ZERO;
                c[axis] = side;
                c[a] = x;
                c[b] = y;
                c
            };
            let quad = if side > 0.0 {
                [corner(-1.0, -1.0), corner(-1.0, 1.0), corner(1.0, 1.0), corner(1.0, -1.0)]
            } else {
                [corner(-1.0, -1.0), corner(1.0, -1.0), corner(1.0, 1.0), corner(-1.0, 1.0)]
            };
            let v = p.len() as u32;
            p.extend(quad);
            uv.extend([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]);
            t.extend([[v, v + 1, v + 2], [v, v + 2, v + 3]]);
        }
    }
    (p, uv, t)
}

/// A camera node at `eye` looking at `target` (+Y up): glTF cameras look down their -Z.
fn camera_node(eye: Vec3, target: Vec3, vfov_deg: f32) -> (Value, Value) {
    let f = (target - eye).normalize();
    let r = f.cross(Vec3::Y).normalize();
    let u = r.cross(f);
    let m = Mat4::from_cols(r.extend(0.0), u.extend(0.0), (-f).extend(0.0), eye.extend(1.0));
    (
        json!({"camera": 0, "matrix": m.to_cols_array()}),
        json!([{"type": "perspective", "perspective": {"yfov": vfov_deg.to_radians(), "aspectRatio": 1.0, "znear": 0.01}}]),
    )
}

/// The furnace cube as glTF with `material` (and `images`/`textures`/`samplers` in `extra`).
fn furnace(dir: &Path, name: &str, material: Value, extra: Value) -> Scene {
    let (p, uv, t) = cube();
    let mut g = Gltf::default();
    let prim = g.primitive(&p, Some(&uv), &t, 0);
    let (cam, cameras) = camera_node(Vec3::new(0.1, -0.2, 0.05), Vec3::new(0.4, 0.3, 1.0), 90.0);
    let mut top = json!({
        "scenes": [{"nodes": [0, 1]}],
        "nodes": [{"mesh": 0}, cam],
        "cameras": cameras,
        "meshes": [{"primitives": [prim]}],
        "materials": [material],
    });
    for (k, v) in extra.as_object().unwrap() {
        top[k] = v.clone();
    }
    let path = g.write(dir, name, top);
    Scene::load(path).unwrap()
}

fn furnace_material(base: Value, texture: Option<usize>) -> Value {
    let mut pbr = json!({"baseColorFactor": base, "metallicFactor": 0.0, "roughnessFactor": 1.0});
    if let Some(t) = texture {
        pbr["baseColorTexture"] = json!({"index": t});
    }
    json!({"name": "furnace", "pbrMetallicRoughness": pbr, "emissiveFactor": [1.0, 1.0, 1.0]})
}

fn settings() -> RenderSettings {
    RenderSettings {
        photons: Some(20_000),
        caustic_photons: Some(2_000),
        spp: Some(4),
        seed: Some(7),
        ..Default::default()
    }
}

fn same_pixels(a: &Film, b: &Film) -> bool {
    a.pixels
        .iter()
        .zip(&b.pixels)
        .all(|(x, y)| x.to_array().map(f32::to_bits) == y.to_array().map(f32::to_bits))
}

#[test]
fn the_gltf_furnace_renders_two() {
    let dir = tempfile::tempdir().unwrap();
    let s = furnace(dir.path(), "cube", furnace_material(json!([0.5, 0.5, 0.5, 1.0]), None), json!({}));
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    assert_eq!(s.materials, [Material::Emissive { kd: Vec3::splat(0.5), ke: Vec3::ONE }]);
    assert_eq!((s.camera.width, s.camera.height), (256, 256), "the glTF camera's default size");
    // Four seeds: one 16 × 16 render of 20 000 photons has about 0.7 % of noise in its mean.
    for integrator in [IntegratorKind::Photon, IntegratorKind::Path] {
        let mean = (7..11)
            .map(|seed| {
                let r = RenderSettings { integrator: Some(integrator), seed: Some(seed), ..settings() };
                render_checked(&s, &r, 16).film.mean()
            })
            .sum::<f64>()
            / 4.0;
        assert!((mean - 2.0).abs() < 0.02, "{integrator:?}: mean {mean}");
    }
}

#[test]
fn a_constant_png_base_colour_renders_as_its_constant_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    image::RgbImage::from_pixel(4, 4, image::Rgb([188, 188, 188])).save(d.join("grey.png")).unwrap();
    let png = std::fs::read(d.join("grey.png")).unwrap();
    let kd = (((188.0f64 / 255.0 + 0.055) / 1.055).powf(2.4)) as f32;
    let plain =
        furnace(d, "plain", furnace_material(json!([kd * 0.5, kd * 0.5, kd * 0.5, 1.0]), None), json!({}));
    let want = render_checked(&plain, &settings(), 16).film;
    // The same image three ways: a file beside the glTF, a data URI, and a buffer view of a GLB-less
    // glTF (in its own buffer, written as a second .bin).
    std::fs::write(d.join("img.bin"), &png).unwrap();
    let data_uri = format!("data:image/png;base64,{}", base64(&png));
    let sources = [
        json!({"images": [{"uri": "grey.png"}]}),
        json!({"images": [{"uri": data_uri}]}),
        json!({"images": [{"bufferView": 0, "mimeType": "image/png"}]}),
    ];
    for (i, images) in sources.into_iter().enumerate() {
        let mut extra = json!({"textures": [{"source": 0, "sampler": 0}], "samplers": [{"wrapS": 10497, "wrapT": 10497}]});
        extra["images"] = images["images"].clone();
        let s = if i == 2 {
            // The image in buffer view 0: build the file with the PNG's view first.
            let (p, uv, t) = cube();
            let mut g = Gltf::default();
            g.view(&png);
            let prim = g.primitive(&p, Some(&uv), &t, 0);
            let (cam, cameras) = camera_node(Vec3::new(0.1, -0.2, 0.05), Vec3::new(0.4, 0.3, 1.0), 90.0);
            extra["scenes"] = json!([{"nodes": [0, 1]}]);
            extra["nodes"] = json!([{"mesh": 0}, cam]);
            extra["cameras"] = cameras;
            extra["meshes"] = json!([{"primitives": [prim]}]);
            extra["materials"] = json!([furnace_material(json!([0.5, 0.5, 0.5, 1.0]), Some(0))]);
            Scene::load(g.write(d, "view", extra)).unwrap()
        } else {
            furnace(d, &format!("tex{i}"), furnace_material(json!([0.5, 0.5, 0.5, 1.0]), Some(0)), extra)
        };
        assert!(s.textured && s.warnings.is_empty(), "source {i}: {:?}", s.warnings);
        let got = render_checked(&s, &settings(), 16).film;
        assert!(same_pixels(&got, &want), "source {i}: the textured furnace differs from kd = {}", kd * 0.5);
    }
}

fn base64(bytes: &[u8]) -> String {
    const A: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::new();
    for c in bytes.chunks(3) {
        let n = (c[0] as u32) << 16 | (*c.get(1).unwrap_or(&0) as u32) << 8 | *c.get(2).unwrap_or(&0) as u32;
        for k in 0..=c.len() {
            s.push(A[(n >> (18 - 6 * k) & 63) as usize] as char);
        }
    }
    while s.len() % 4 != 0 {
        s.push('=');
    }
    s
}

#[test]
fn node_transforms_compose_parent_matrix_and_child_trs() {
    let dir = tempfile::tempdir().unwrap();
    let mut g = Gltf::default();
    // A triangle in the XY plane, facing +Z.
    let tri = [Vec3::ZERO, Vec3::X, Vec3::Y];
    let prim = g.primitive(&tri, None, &[[0, 1, 2]], 0);
    let parent =
        Mat4::from_scale_rotation_translation(Vec3::splat(2.0), Quat::IDENTITY, Vec3::new(1.0, 2.0, 3.0));
    let rot = Quat::from_rotation_z(std::f32::consts::FRAC_PI_2);
    let (t, s) = (Vec3::new(1.0, 0.0, 0.0), Vec3::new(1.0, 1.0, -1.0));
    let child = Mat4::from_scale_rotation_translation(s, rot, t);
    let path = g.write(
        dir.path(),
        "nodes",
        json!({
            "extensionsUsed": ["KHR_lights_punctual"],
            "extensions": {"KHR_lights_punctual": {"lights": [
                {"type": "spot", "color": [1.0, 0.5, 0.25], "intensity": 4.0, "spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.6}}
            ]}},
            "scenes": [{"nodes": [0]}],
            "nodes": [
                {"matrix": parent.to_cols_array(), "children": [1, 2]},
                {"mesh": 0, "translation": t.to_array(), "rotation": rot.to_array(), "scale": s.to_array()},
                {"translation": [0.0, 0.0, 1.0], "extensions": {"KHR_lights_punctual": {"light": 0}}, "children": [3]},
                {"camera": 0, "rotation": Quat::from_rotation_y(std::f32::consts::PI).to_array()}
            ],
            "cameras": [{"type": "perspective", "perspective": {"yfov": 1.0, "aspectRatio": 1.5, "znear": 0.1}}],
            "meshes": [{"primitives": [prim]}],
            "materials": [{"name": "m", "pbrMetallicRoughness": {"metallicFactor": 0.0}}]
        }),
    );
    let scene = Scene::load(&path).unwrap();
    let world = parent * child;
    let want: Vec<Vec3> = tri.iter().map(|&p| world.transform_point3(p)).collect();
    for (got, want) in scene.mesh.positions.iter().zip(&want) {
        assert!((*got - *want).length() < 1e-5, "{got} vs {want}");
    }
    // (1,2,3) + 2 * (rot (x, y, -z) + (1,0,0)): the vertices at (3,2,3), (3,4,3), (1,2,3).
    assert!((scene.mesh.positions[1] - Vec3::new(3.0, 4.0, 3.0)).length() < 1e-5);
    // The child mirrors z (determinant < 0): the winding is reversed so that the front face
    // is where the inverse transpose takes the front normal +Z.
    let n = scene.mesh.normal(0).unwrap();
    let want_n = (Mat4::inverse(&world).transpose().transform_vector3(Vec3::Z)).normalize();
    assert!((n - want_n).length() < 1e-5, "front normal {n}, expected {want_n}");
    // The spot light at the parent's (0,0,1): (1,2,5), pointing along the parent's -Z.
    match scene.lights[..] {
        [LightDesc::Spot { position, direction, intensity, cone_deg, falloff_deg }] => {
            assert!((position - Vec3::new(1.0, 2.0, 5.0)).length() < 1e-5, "{position}");
            assert!((direction - Vec3::NEG_Z).length() < 1e-5, "{direction}");
            assert_eq!(intensity, Vec3::new(4.0, 2.0, 1.0));
            assert!((cone_deg - 0.6f32.to_degrees()).abs() < 1e-4);
            assert!((falloff_deg - 0.4f32.to_degrees()).abs() < 1e-3);
        }
        ref other => panic!("lights {other:?}"),
    }
    // The camera under the light, turned to look down +Z; 1.5 aspect at the default height.
    let c = &scene.camera;
    assert!((c.eye - Vec3::new(1.0, 2.0, 5.0)).length() < 1e-5, "{}", c.eye);
    assert!((c.forward - Vec3::Z).length() < 1e-5, "{}", c.forward);
    assert!((c.up - Vec3::Y).length() < 1e-5);
    assert_eq!((c.width, c.height), (384, 256));
    assert!((c.tan_half_fov - 0.5f32.tan()).abs() < 1e-6);
    // Metallic 0, default roughness 1 and base colour 1: diffuse white.
    assert_eq!(scene.materials, [Material::Diffuse { kd: Vec3::ONE }]);
}

#[test]
fn the_gltf_cornell_box_renders_as_the_obj_one() {
    let obj = common::scene("cornell");
    let dir = tempfile::tempdir().unwrap();
    let mut g = Gltf::default();
    let mut primitives = Vec::new();
    let mut materials = Vec::new();
    for (id, m) in obj.materials.iter().enumerate() {
        // This material's triangles, with their own copy of the vertices.
        let mut p = Vec::new();
        let mut t = Vec::new();
        for (tri, _) in obj.mesh.indices.iter().zip(&obj.tri_material).filter(|(_, &k)| k as usize == id) {
            let v = p.len() as u32;
            p.extend(tri.iter().map(|&i| obj.mesh.positions[i as usize]));
            t.push([v, v + 1, v + 2]);
        }
        primitives.push(g.primitive(&p, None, &t, id));
        let pbr = |kd: Vec3| json!({"baseColorFactor": [kd.x, kd.y, kd.z, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0});
        let name = &obj.material_names[id];
        materials.push(match *m {
            Material::Diffuse { kd } => json!({"name": name, "pbrMetallicRoughness": pbr(kd)}),
            Material::Emissive { kd, ke } => {
                let s = ke.max_element();
                json!({"name": name, "pbrMetallicRoughness": pbr(kd), "emissiveFactor": (ke / s).to_array(),
                       "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": s}}})
            }
            other => panic!("the Cornell box has no {other:?}"),
        });
    }
    let c = &obj.camera;
    let vfov = (2.0 * c.tan_half_fov.atan()).to_degrees();
    let (cam, cameras) = camera_node(c.eye, c.eye + c.forward, vfov);
    let path = g.write(
        dir.path(),
        "cornell",
        json!({
            "extensionsUsed": ["KHR_materials_emissive_strength"],
            "scene": 0,
            "scenes": [{"nodes": [0, 1]}],
            "nodes": [{"mesh": 0}, cam],
            "cameras": cameras,
            "meshes": [{"primitives": primitives}],
            "materials": materials,
        }),
    );
    let gltf = Scene::load(&path).unwrap();
    assert!(gltf.warnings.is_empty(), "{:?}", gltf.warnings);
    assert_eq!(gltf.mesh.len(), obj.mesh.len());
    let r = RenderSettings { photons: Some(100_000), spp: Some(16), seed: Some(3), ..Default::default() };
    let a = render_checked(&obj, &r, 32).film;
    let b = render_checked(&gltf, &r, 32).film;
    let a2 = render_checked(&obj, &RenderSettings { seed: Some(4), ..r.clone() }, 32).film;
    let mean = |f: &Film| f.pixels.iter().copied().sum::<Vec3>() / f.pixels.len() as f32;
    let rmse = |x: &Film, y: &Film| {
        let s: f32 = x.pixels.iter().zip(&y.pixels).map(|(p, q)| (*p - *q).length_squared()).sum();
        (s / (3 * x.pixels.len()) as f32).sqrt()
    };
    let (ma, mb) = (mean(&a), mean(&b));
    let (same_seed, noise) = (rmse(&a, &b), rmse(&a, &a2));
    println!("obj {ma}, gltf {mb}; RMSE glTF vs OBJ {same_seed}, OBJ seed 3 vs 4 {noise}");
    for k in 0..3 {
        assert!((ma[k] - mb[k]).abs() < 0.01 * ma[k], "channel {k}: obj {ma} vs gltf {mb}");
    }
    assert!(same_seed <= 1.2 * noise, "RMSE {same_seed} against noise {noise}");
}

/// One triangle per material of `materials`, seen by a glTF camera.
fn triangles(dir: &Path, name: &str, materials: Value, extra: Value) -> Scene {
    let mut g = Gltf::default();
    let n = materials.as_array().unwrap().len();
    let mut prims: Vec<Value> = (0..n)
        .map(|i| {
            let z = -(i as f32) - 2.0;
            let tri = [Vec3::new(0.0, 0.0, z), Vec3::new(1.0, 0.0, z), Vec3::new(0.0, 1.0, z)];
            g.primitive(&tri, None, &[[0, 1, 2]], i)
        })
        .collect();
    // A LINES primitive: warned and skipped.
    let mut lines = prims[0].clone();
    lines["mode"] = json!(1);
    prims.push(lines);
    let mut top = json!({
        "scenes": [{"nodes": [0, 1]}],
        "nodes": [{"mesh": 0}, {"camera": 0, "translation": [0.0, 0.0, 1.0]}],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1}}],
        "meshes": [{"primitives": prims}],
        "materials": materials,
    });
    for (k, v) in extra.as_object().unwrap() {
        top[k] = v.clone();
    }
    Scene::load(g.write(dir, name, top)).unwrap()
}

#[test]
fn materials_map_as_the_readme_says_and_the_rest_is_warned() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    image::RgbImage::from_pixel(2, 2, image::Rgb([188, 188, 188])).save(d.join("grey.png")).unwrap();
    let pbr = |base: [f32; 3], metal: f32, rough: f32| json!({"baseColorFactor": [base[0], base[1], base[2], 1.0], "metallicFactor": metal, "roughnessFactor": rough});
    let materials = json!([
        {"name": "mirror", "pbrMetallicRoughness": pbr([0.9, 0.8, 0.7], 1.0, 0.0)},
        {"name": "metal", "pbrMetallicRoughness": pbr([0.9, 0.8, 0.7], 1.0, 0.5)},
        {"name": "plastic", "pbrMetallicRoughness": pbr([0.5, 0.25, 1.0], 0.0, 0.3)},
        {"name": "matte", "pbrMetallicRoughness": pbr([0.5, 0.25, 1.0], 0.0, 0.7), "alphaMode": "BLEND",
         "normalTexture": {"index": 0, "scale": 0.5}},
        {"name": "glass", "pbrMetallicRoughness": pbr([1.0, 1.0, 1.0], 0.0, 0.0),
         "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1.0}, "KHR_materials_ior": {"ior": 1.33}}},
        {"name": "lamp", "pbrMetallicRoughness": pbr([0.2, 0.2, 0.2], 0.0, 1.0), "emissiveFactor": [1.0, 0.5, 0.25],
         "emissiveTexture": {"index": 0},
         "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 4.0}}}
    ]);
    let extra = json!({
        "extensionsUsed": ["KHR_materials_transmission", "KHR_materials_ior", "KHR_materials_emissive_strength", "KHR_materials_clearcoat"],
        "textures": [{"source": 0}],
        "images": [{"uri": "grey.png"}]
    });
    let s = triangles(d, "materials", materials, extra);
    let grey = (((188.0f64 / 255.0 + 0.055) / 1.055).powf(2.4)) as f32;
    let by_name = |n: &str| s.materials[s.material_names.iter().position(|m| m == n).unwrap()];
    let base = Vec3::new(0.9, 0.8, 0.7);
    assert_eq!(by_name("mirror"), Material::Mirror { ks: base });
    assert_eq!(by_name("metal"), Material::principled(base, 1.0, 0.5));
    let colour = Vec3::new(0.5, 0.25, 1.0);
    assert_eq!(by_name("plastic"), Material::principled(colour, 0.0, 0.3));
    assert_eq!(by_name("matte"), Material::Diffuse { kd: colour });
    assert_eq!(by_name("glass"), Material::Glass { ior: 1.33 });
    match by_name("lamp") {
        Material::Emissive { kd, ke } => {
            assert_eq!(kd, Vec3::splat(0.2));
            assert!((ke - Vec3::new(4.0, 2.0, 1.0)).length() < 1e-5, "{ke}");
        }
        other => panic!("lamp: {other:?}"),
    }
    // The emissive texture (sRGB) multiplies emissiveFactor × strength texel by texel.
    let lamp = s.material_names.iter().position(|m| m == "lamp").unwrap();
    assert!(s.maps[lamp].ke.is_some(), "lamp's emissiveTexture is its ke map");
    assert!(s.emission_maps().is_some_and(|m| m[lamp].is_some()), "and the area lights read it");
    match s.material_at(
        s.tri_material.iter().position(|&m| m as usize == lamp).unwrap() as u32,
        glam::Vec2::ZERO,
        Vec3::ONE,
    ) {
        Material::Emissive { ke, .. } => {
            assert!((ke - Vec3::new(4.0, 2.0, 1.0) * grey).length() < 1e-5, "{ke}")
        }
        other => panic!("lamp: {other:?}"),
    }
    assert_eq!(s.mesh.len(), 6, "the LINES primitive is skipped");
    let warnings = s.warnings.join("\n");
    for want in [
        "KHR_materials_clearcoat is not read",
        "alphaMode BLEND (material matte): drawn as MASK with alphaCutoff 0.5",
        "mode Lines is not drawn",
        "no mesh has texture coordinates",
    ] {
        assert!(warnings.contains(want), "no warning `{want}` in:\n{warnings}");
    }
    assert_eq!(s.warnings.len(), 4, "{warnings}");
    // The normal map is the same image read as data (linear 188/255), not as a colour.
    let matte = s.material_names.iter().position(|m| m == "matte").unwrap();
    let normal = s.maps[matte].normal.expect("matte's normalTexture is a normal map");
    let texel =
        s.textures.get(normal.texture).sample(glam::Vec2::new(0.5, 0.5), photonmap::texture::Wrap::Repeat);
    assert!((texel.x - 188.0 / 255.0).abs() < 1e-6, "{texel}");
    // Its scale multiplies the x and y of `2 c - 1` (glTF 2.0, 3.9.3).
    assert_eq!(normal.factor, Vec3::new(0.5, 0.5, 1.0));
    assert_eq!((s.camera.width, s.camera.height), (256, 256));
}

/// glTF's `metallicRoughnessTexture` (blue the metallic value, green the roughness, linear,
/// times the factors) decides the material texel by texel: a model's metal parts are drawn as
/// metal and the rest as the plastic or matte surface the texture says. It was warned about
/// and left out, every texel drawn as the factors alone say.
#[test]
fn the_metallic_roughness_texture_decides_each_texels_material() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // Left to right: matte (metallic 0, roughness 1), plastic (0, 0.2), metal (1, 0.6), polished
    // metal (1, 0).
    let texels = [[0u8, 255, 0], [0, 51, 0], [0, 153, 255], [0, 0, 255]];
    image::RgbImage::from_fn(4, 1, |x, _| image::Rgb(texels[x as usize])).save(d.join("mr.png")).unwrap();
    let pbr = |rough: f32| {
        json!({"baseColorFactor": [0.5, 0.4, 0.3, 1.0], "metallicFactor": 1.0, "roughnessFactor": rough,
               "metallicRoughnessTexture": {"index": 0}})
    };
    let materials = json!([
        {"name": "parts", "pbrMetallicRoughness": pbr(1.0)},
        {"name": "chrome", "pbrMetallicRoughness": pbr(0.0)},
        {"name": "lens", "pbrMetallicRoughness": pbr(1.0),
         "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1.0}}}
    ]);
    let extra = json!({"textures": [{"source": 0, "sampler": 0}], "samplers": [{"wrapS": 33071, "wrapT": 33071}],
                       "images": [{"uri": "mr.png"}], "extensionsUsed": ["KHR_materials_transmission"]});
    let s = triangles(d, "mr", materials, extra);
    let warnings = s.warnings.join("\n");
    // Drawn where the material is metal, plastic or matte; said to be unused on glass.
    let about_it: Vec<&String> =
        s.warnings.iter().filter(|w| w.contains("metallicRoughnessTexture")).collect();
    assert_eq!(about_it.len(), 1, "{warnings}");
    assert!(
        about_it[0].contains("(material lens) is not used: the material is drawn as glass"),
        "{warnings}"
    );
    let id = |name: &str| s.material_names.iter().position(|m| m == name).unwrap();
    let at = |name: &str, u: f32| {
        let prim = s.tri_material.iter().position(|&m| m as usize == id(name)).unwrap() as u32;
        s.material_at(prim, glam::Vec2::new(u, 0.5), Vec3::ONE)
    };
    let base = Vec3::new(0.5, 0.4, 0.3);
    let plastic = |rough: f32| Material::principled(base, 0.0, rough);
    let metal = |rough: f32| Material::principled(base, 1.0, rough);
    // The factors alone make "parts" a rough metal, as every texel was drawn before.
    assert_eq!(s.materials[id("parts")], metal(1.0));
    assert_eq!(at("parts", 0.125), Material::Diffuse { kd: base });
    assert_eq!(at("parts", 0.375), plastic(51.0 / 255.0));
    assert_eq!(at("parts", 0.625), metal(153.0 / 255.0));
    // Roughness 0 where the factors do not make a mirror: the sharpest lobe (the scene finds its
    // mirrors, which caustics are aimed at, by the material).
    assert_eq!(at("parts", 0.875), metal(0.0));
    // roughnessFactor 0: every texel polished; the metal ones mirrors, as the material is.
    assert_eq!(s.materials[id("chrome")], Material::Mirror { ks: base });
    assert_eq!(at("chrome", 0.625), Material::Mirror { ks: base });
    assert_eq!(at("chrome", 0.125), plastic(0.0));
    let r = RenderSettings { integrator: Some(IntegratorKind::Photon), ..settings() };
    render_checked(&s, &r, 8);
    // A scene file that sets the material's constants takes it over: the texture is set aside.
    let toml = "[[mesh]]\ngltf = \"mr.gltf\"\n\n[materials.parts]\ntype = \"diffuse\"\n";
    std::fs::write(d.join("s.toml"), toml).unwrap();
    let s = Scene::load(d.join("s.toml")).unwrap();
    let parts = s.material_names.iter().position(|m| m == "parts").unwrap();
    assert!(s.maps[parts].metal_rough.is_none());
    let warnings = s.warnings.join("\n");
    assert!(
        warnings.contains("materials.parts.type is given, so the material's roughness and metallic textures"),
        "{warnings}"
    );
}

/// A material whose factors make it a mirror, but whose metallic-roughness texture makes it
/// polished plastic: its texels store photons, so the photon maps are traced (the scene's
/// analysis went by the factors alone, found nothing diffuse and skipped them).
#[test]
fn a_mirror_whose_texture_makes_it_plastic_still_gets_photon_maps() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    image::RgbImage::from_pixel(2, 2, image::Rgb([0, 0, 0])).save(d.join("plastic.png")).unwrap();
    let pbr = json!({"baseColorFactor": [0.8, 0.8, 0.8, 1.0], "metallicFactor": 1.0, "roughnessFactor": 0.0,
                     "metallicRoughnessTexture": {"index": 0}});
    let materials = json!([{"name": "chrome", "pbrMetallicRoughness": pbr}]);
    let extra = json!({"textures": [{"source": 0}], "images": [{"uri": "plastic.png"}]});
    let s = triangles(d, "plastic", materials, extra);
    assert_eq!(s.materials[0], Material::Mirror { ks: Vec3::splat(0.8) });
    let out = render_checked(&s, &settings(), 8);
    let indirect = out.stats.stages.iter().find(|st| st.name == "photons.indirect").expect("the stage");
    assert!(indirect.ran, "photons.indirect skipped: {}", indirect.reason);
}

#[test]
fn alpha_mask_cuts_at_the_cutoff_of_texture_alpha_times_factor_alpha() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // Alpha 0 on the left column, 1 on the right.
    image::RgbaImage::from_fn(2, 1, |x, _| image::Rgba([255, 255, 255, 255 * x as u8]))
        .save(d.join("leaf.png"))
        .unwrap();
    let base = |alpha: f32, texture: bool| {
        let mut b =
            json!({"baseColorFactor": [1.0, 1.0, 1.0, alpha], "metallicFactor": 0.0, "roughnessFactor": 1.0});
        if texture {
            b["baseColorTexture"] = json!({"index": 0});
        }
        b
    };
    let materials = json!([
        {"name": "leaf", "pbrMetallicRoughness": base(0.8, true), "alphaMode": "MASK", "alphaCutoff": 0.3},
        {"name": "ghost", "pbrMetallicRoughness": base(0.2, false), "alphaMode": "MASK"},
        {"name": "solid", "pbrMetallicRoughness": base(0.9, false), "alphaMode": "MASK"},
        {"name": "blend", "pbrMetallicRoughness": base(1.0, true), "alphaMode": "BLEND"}
    ]);
    let extra = json!({"textures": [{"source": 0}], "images": [{"uri": "leaf.png"}]});
    let s = triangles(d, "mask", materials, extra);
    let maps = |n: &str| s.maps[s.material_names.iter().position(|m| m == n).unwrap()];
    let leaf = maps("leaf").alpha.expect("MASK with a base colour texture is a cut-out");
    assert_eq!((leaf.channel, leaf.factor, leaf.cutoff), (3, 0.8, 0.3));
    let tex = &s.textures.list[leaf.texture.texture as usize];
    assert!(!leaf.opaque(tex, glam::Vec2::new(0.25, 0.5)) && leaf.opaque(tex, glam::Vec2::new(0.75, 0.5)));
    // 0.2 < the default cutoff 0.5: nothing is drawn; 0.9 passes everywhere: no cut-out.
    assert!(maps("ghost").alpha.is_some() && maps("solid").alpha.is_none());
    assert_eq!(maps("blend").alpha.map(|a| a.cutoff), Some(0.5));
    let warnings = s.warnings.join("\n");
    assert!(warnings.contains("baseColorFactor alpha 0.2 is below its alphaCutoff 0.5"), "{warnings}");
    assert!(warnings.contains("alphaMode BLEND (material blend)"), "{warnings}");
    // The fully transparent triangle is not hit; the others are cut-outs or opaque.
    let cut = s.cutouts().expect("cut-outs");
    let ghost = s.material_names.iter().position(|m| m == "ghost").unwrap() as u32;
    let prim = s.tri_material.iter().position(|&m| m == ghost).unwrap() as u32;
    assert!(cut.is_cutout(prim) && !cut.opaque(prim, 0.2, 0.2));
}

#[test]
fn a_scene_file_places_a_gltf_overrides_its_materials_and_adds_lights() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let fixture = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/gltf");
    for f in ["quad.gltf", "quad.bin"] {
        std::fs::copy(fixture.join(f), d.join(f)).unwrap();
    }
    let toml = "[[mesh]]\ngltf = \"quad.gltf\"\ntranslate = [0.0, 1.0, 0.0]\n\n\
                [materials.floor]\ntype = \"glossy\"\nks = [0.1, 0.1, 0.1]\nns = 20.0\n\n\
                [[light]]\ntype = \"distant\"\ndirection = [0.0, -1.0, 0.0]\nirradiance = [1.0, 1.0, 1.0]\n";
    std::fs::write(d.join("s.toml"), toml).unwrap();
    let s = Scene::load(d.join("s.toml")).unwrap();
    // The floor's diffuse 0.8 kept, the scene file's type, ks and ns over it.
    assert_eq!(s.materials, [Material::Glossy { kd: Vec3::splat(0.8), ks: Vec3::splat(0.1), ns: 20.0 }]);
    assert!(s.mesh.positions.iter().all(|p| p.y == 1.0), "translate moves the glTF's triangles");
    assert_eq!(s.lights.len(), 2, "the file's distant light and the glTF's point light");
    assert!(matches!(s.lights[1], LightDesc::Point { intensity, .. } if intensity == Vec3::splat(2.0)));
    // The glTF's camera stands in for a missing [camera]; moving the mesh is said not to move it.
    assert!((s.camera.eye - Vec3::new(0.0, 1.0, 3.0)).length() < 1e-5);
    assert!(s.warnings.iter().any(|w| w.contains("not its camera and lights")), "{:?}", s.warnings);
    // With a [camera], that one is used.
    let with_camera = format!(
        "[camera]\neye = [0.0, 2.0, 2.0]\ntarget = [0.0, 0.0, 0.0]\nup = [0.0, 1.0, 0.0]\nvfov_deg = 50.0\nwidth = 32\nheight = 24\n\n{toml}"
    );
    std::fs::write(d.join("s.toml"), with_camera).unwrap();
    let s = Scene::load(d.join("s.toml")).unwrap();
    assert_eq!((s.camera.eye, s.camera.width, s.camera.height), (Vec3::new(0.0, 2.0, 2.0), 32, 24));
}

#[test]
fn the_shipped_boxtextured_scene_loads_textured_without_warnings() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let s = Scene::load(root.join("scenes/boxtextured/boxtextured.toml")).unwrap();
    assert!(s.textured && s.warnings.is_empty(), "{:?}", s.warnings);
    assert_eq!(s.mesh.len(), 12 + 2);
    // Alone, BoxTextured has neither camera nor lights: it is framed and lit by a white sky, and
    // both stand-ins are said.
    let box_only = Scene::load(root.join("scenes/boxtextured/BoxTextured.gltf")).unwrap();
    assert_eq!(box_only.warnings.len(), 2, "{:?}", box_only.warnings);
}

#[test]
fn sparse_accessors_and_u8_indices_are_read() {
    let dir = tempfile::tempdir().unwrap();
    let mut g = Gltf::default();
    let base: Vec<u8> =
        [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0].iter().flat_map(|x| x.to_le_bytes()).collect();
    let base_view = g.view(&base);
    // Vertex 2 moved from (0,1,0) to (0,2,0) by a sparse value.
    let idx_view = g.view(&2u16.to_le_bytes());
    let val: Vec<u8> = [0.0f32, 2.0, 0.0].iter().flat_map(|x| x.to_le_bytes()).collect();
    let val_view = g.view(&val);
    g.accessors.push(json!({
        "bufferView": base_view, "componentType": 5126, "count": 3, "type": "VEC3",
        "min": [0.0, 0.0, 0.0], "max": [1.0, 2.0, 0.0],
        "sparse": {"count": 1, "indices": {"bufferView": idx_view, "componentType": 5123},
                   "values": {"bufferView": val_view}}
    }));
    let tri_view = g.view(&[0u8, 1, 2]);
    g.accessors.push(json!({"bufferView": tri_view, "componentType": 5121, "count": 3, "type": "SCALAR"}));
    let (cam, cameras) = camera_node(Vec3::new(0.0, 0.0, 3.0), Vec3::ZERO, 40.0);
    let path = g.write(
        dir.path(),
        "sparse",
        json!({
            "scenes": [{"nodes": [0, 1]}],
            "nodes": [{"mesh": 0}, cam],
            "cameras": cameras,
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}]
        }),
    );
    let s = Scene::load(path).unwrap();
    assert_eq!(s.mesh.positions, [Vec3::ZERO, Vec3::X, Vec3::new(0.0, 2.0, 0.0)]);
    assert_eq!(s.mesh.indices, [[0, 1, 2]]);
    assert_eq!(s.material_names, ["(default grey)"]);
}

#[test]
fn a_gltf_alone_whose_emitters_only_glow_is_lit_by_a_white_sky_as_well() {
    // Found on real models: controllers with a few glowing LEDs and no lights rendered black.
    // What emits no brighter than radiance 1 (glTF's emissiveFactor alone) and gives under a
    // quarter of what a white sky brings (7.4 W to the two triangles' bounding sphere; the
    // emitter's 0.5 m² give 1.3 W at ke 1) glows: the sky lights the model too. Brighter
    // (KHR_materials_emissive_strength, for lamps), or a whole room's walls, light it alone (the
    // furnace, `the_gltf_furnace_renders_two`).
    let dir = tempfile::tempdir().unwrap();
    let pbr = json!({"baseColorFactor": [0.8, 0.8, 0.8, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0});
    for (ke, strength, sky) in
        [(0.01, None, true), (1.0, None, true), (1.0, Some(1.0), true), (0.5, Some(4.0), false)]
    {
        let mut led =
            json!({"name": "led", "pbrMetallicRoughness": pbr, "emissiveFactor": [ke, ke / 2.0, ke]});
        let mut extra = json!({});
        if let Some(s) = strength {
            led["extensions"] = json!({"KHR_materials_emissive_strength": {"emissiveStrength": s}});
            extra = json!({"extensionsUsed": ["KHR_materials_emissive_strength"]});
        }
        let materials = json!([{"name": "body", "pbrMetallicRoughness": pbr}, led]);
        let s = triangles(dir.path(), &format!("led{ke}"), materials, extra);
        let warnings = s.warnings.join("\n");
        let lit = matches!(s.lights[..], [LightDesc::Environment { radiance: Vec3::ONE, map: None, .. }]);
        assert_eq!(lit, sky, "ke {ke} × {strength:?}: {:?}", s.lights);
        assert_eq!(warnings.contains("glows"), sky, "ke {ke} × {strength:?}: {warnings}");
    }
}

#[test]
fn a_gltf_alone_without_camera_or_lights_is_framed_and_lit_by_a_white_sky() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/boxtextured/BoxTextured.gltf");
    let s = Scene::load(&path).unwrap();
    let warnings = s.warnings.join("\n");
    assert!(warnings.contains("no perspective camera"), "{warnings}");
    assert!(warnings.contains("white sky"), "{warnings}");
    assert!(matches!(s.lights[..], [LightDesc::Environment { radiance: Vec3::ONE, map: None, .. }]));
    // The whole box is in view: every corner of its bounds projects inside the image.
    let (lo, hi) = (s.mesh.bounds().min, s.mesh.bounds().max);
    let cam = &s.camera;
    let (forward, right, up, half) = (cam.forward, cam.right, cam.up, cam.tan_half_fov);
    for i in 0..8 {
        let c = Vec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        );
        let d = c - cam.eye;
        let depth = d.dot(forward);
        assert!(depth > 0.0);
        assert!(
            d.dot(right).abs() < half * depth && d.dot(up).abs() < half * depth,
            "corner {c} out of view"
        );
    }
    // The sky shows in the corners (exactly 1: nothing else is there) and the box in the middle.
    let settings = RenderSettings { spp: Some(4), photons: Some(2000), seed: Some(1), ..Default::default() };
    let film = render_checked(&s, &settings, 16).film;
    let px = |x: usize, y: usize| film.pixels[y * film.width + x];
    assert_eq!(px(0, 0), Vec3::ONE);
    let centre = px(8, 8);
    assert!(centre.max_element() < 0.95 && centre.min_element() > 0.05, "the box at the centre: {centre}");
}

/// glTF's vertex colours (`COLOR_0`, linear, RGB or RGBA) multiply the base colour, as the
/// specification says: a grey material whose vertices are orange is orange where they are,
/// blended across the triangle. They were not read: the model was drawn grey.
#[test]
fn vertex_colours_multiply_the_base_colour() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mut g = Gltf::default();
    let tri = [Vec3::new(0.0, 0.0, -2.0), Vec3::new(1.0, 0.0, -2.0), Vec3::new(0.0, 1.0, -2.0)];
    let mut prim = g.primitive(&tri, None, &[[0, 1, 2]], 0);
    // RGBA: the alpha is not read.
    let rgba = [1.0, 0.5, 0.25, 0.3, 0.0, 1.0, 0.0, 1.0, 1.0, 0.5, 0.25, 1.0];
    prim["attributes"]["COLOR_0"] = json!(g.floats(&rgba, 4, "VEC4"));
    let top = json!({
        "scenes": [{"nodes": [0, 1]}],
        "nodes": [{"mesh": 0}, {"camera": 0, "translation": [0.0, 0.0, 1.0]}],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.1}}],
        "meshes": [{"primitives": [prim]}],
        "materials": [{"name": "grey", "pbrMetallicRoughness":
            {"baseColorFactor": [0.8, 0.8, 0.8, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0}}],
    });
    let s = Scene::load(g.write(d, "coloured", top)).unwrap();
    let corner = s.attributes.at([0, 1, 2], 0.0, 0.0).colour;
    assert_eq!(corner, Vec3::new(1.0, 0.5, 0.25));
    let between = s.attributes.at([0, 1, 2], 0.5, 0.0).colour;
    assert!((between - Vec3::new(0.5, 0.75, 0.125)).length() < 1e-6, "{between}");
    let m = s.material_at(0, glam::Vec2::ZERO, corner);
    assert_eq!(m, Material::Diffuse { kd: Vec3::new(0.8, 0.4, 0.2) });
    let r = RenderSettings { integrator: Some(IntegratorKind::Photon), ..settings() };
    render_checked(&s, &r, 8);
}

/// `KHR_texture_transform`'s offset and scale move a texture as glTF viewers move it (a
/// texture atlas: the right half of a red | blue image is the base colour); a rotation is
/// warned and left out; a texture without the extension is read as before. The extension was
/// warned as not read, and the whole atlas drawn.
#[test]
fn texture_transform_moves_the_texture() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    image::RgbImage::from_fn(8, 1, |x, _| image::Rgb(if x < 4 { [255, 0, 0] } else { [0, 0, 255] }))
        .save(d.join("atlas.png"))
        .unwrap();
    let textured = |transform: Value| {
        let mut info = json!({"index": 0});
        if !transform.is_null() {
            info["extensions"] = json!({"KHR_texture_transform": transform});
        }
        json!({"name": "m", "pbrMetallicRoughness": {"baseColorTexture": info, "metallicFactor": 0.0, "roughnessFactor": 1.0}})
    };
    let extra = json!({"textures": [{"source": 0}], "images": [{"uri": "atlas.png"}],
                       "extensionsUsed": ["KHR_texture_transform"]});
    let colour = |s: &Scene, u: f32| match s.material_at(0, glam::Vec2::new(u, 0.5), Vec3::ONE) {
        Material::Diffuse { kd } => kd,
        other => panic!("{other:?}"),
    };
    let (red, blue) = (Vec3::X, Vec3::Z);
    let plain = triangles(d, "plain", json!([textured(Value::Null)]), extra.clone());
    assert_eq!((colour(&plain, 0.25), colour(&plain, 0.75)), (red, blue));
    // The right half: u' = 0.5 + 0.5 u.
    let right = triangles(
        d,
        "right",
        json!([textured(json!({"offset": [0.5, 0.0], "scale": [0.5, 1.0]}))]),
        extra.clone(),
    );
    assert!(right.warnings.iter().all(|w| !w.contains("KHR_texture_transform")), "{:?}", right.warnings);
    assert_eq!((colour(&right, 0.25), colour(&right, 0.75)), (blue, blue));
    let turned = triangles(d, "turned", json!([textured(json!({"rotation": 0.5}))]), extra);
    assert!(
        turned.warnings.iter().any(|w| w.contains("rotation 0.5 is not applied")),
        "{:?}",
        turned.warnings
    );
}

/// `EXT_texture_webp`: a texture whose image is WebP (as `gltf-transform webp` writes it, with
/// no fallback `source`) is read; a texture with neither is refused naming it. Such files were
/// refused as a whole.
#[test]
fn a_webp_texture_is_read() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let img = image::RgbImage::from_pixel(4, 4, image::Rgb([255, 0, 0]));
    let file = std::fs::File::create(d.join("red.webp")).unwrap();
    image::codecs::webp::WebPEncoder::new_lossless(file)
        .encode(img.as_raw(), 4, 4, image::ExtendedColorType::Rgb8)
        .unwrap();
    let material = json!([{"name": "m", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}, "metallicFactor": 0.0, "roughnessFactor": 1.0}}]);
    let extra = json!({"textures": [{"extensions": {"EXT_texture_webp": {"source": 0}}}],
                       "images": [{"uri": "red.webp"}],
                       "extensionsUsed": ["EXT_texture_webp"], "extensionsRequired": ["EXT_texture_webp"]});
    let s = triangles(d, "webp", material.clone(), extra);
    assert!(s.warnings.iter().all(|w| !w.contains("EXT_texture_webp")), "{:?}", s.warnings);
    assert_eq!(s.material_at(0, glam::Vec2::new(0.5, 0.5), Vec3::ONE), Material::Diffuse { kd: Vec3::X });
    // Neither a WebP image nor a source: refused, naming the texture.
    let extra = json!({"textures": [{}], "images": [{"uri": "red.webp"}]});
    let mut g = Gltf::default();
    let tri = [Vec3::new(0.0, 0.0, -2.0), Vec3::new(1.0, 0.0, -2.0), Vec3::new(0.0, 1.0, -2.0)];
    let prim = g.primitive(&tri, None, &[[0, 1, 2]], 0);
    let mut top = json!({"scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}], "meshes": [{"primitives": [prim]}],
                         "materials": material});
    for (k, v) in extra.as_object().unwrap() {
        top[k] = v.clone();
    }
    let err = Scene::load(g.write(d, "empty", top)).err().unwrap().to_string();
    assert!(err.contains("textures[0]") && err.contains("has no image photonmap reads"), "{err}");
}

/// `KHR_mesh_quantization` (what `gltfpack` and `gltf-transform quantize` write): positions
/// as shorts scaled back by their node, normals as normalised bytes, texture coordinates as
/// normalised unsigned shorts. Such files were refused (positions had to be floats).
#[test]
fn quantized_meshes_are_read() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mut g = Gltf::default();
    let accessor = |g: &mut Gltf, bytes: Vec<u8>, ty: u32, normalized: bool, kind: &str| {
        let view = g.view(&bytes);
        g.accessors.push(json!({"bufferView": view, "componentType": ty, "normalized": normalized,
                                "count": 3, "type": kind}));
        g.accessors.len() - 1
    };
    // Shorts (5122), a VEC3 padded to 8 bytes as glTF aligns vertex attributes.
    let shorts: Vec<u8> = [[0i16, 0, 0, 0], [1000, 0, 0, 0], [0, 1000, 0, 0]]
        .iter()
        .flatten()
        .flat_map(|x| x.to_le_bytes())
        .collect();
    let position = accessor(&mut g, shorts, 5122, false, "VEC3");
    g.accessors[position]["min"] = json!([0, 0, 0]);
    g.accessors[position]["max"] = json!([1000, 1000, 0]);
    g.views[g.accessors[position]["bufferView"].as_u64().unwrap() as usize]["byteStride"] = json!(8);
    let normal = accessor(
        &mut g,
        [[0i8, 0, 127, 0]; 3].iter().flatten().map(|&x| x as u8).collect(),
        5120,
        true,
        "VEC3",
    );
    g.views[g.accessors[normal]["bufferView"].as_u64().unwrap() as usize]["byteStride"] = json!(4);
    let uv: Vec<u8> =
        [[0u16, 0], [65535, 0], [0, 65535]].iter().flatten().flat_map(|x| x.to_le_bytes()).collect();
    let texcoord = accessor(&mut g, uv, 5123, true, "VEC2");
    let indices = g.indices(&[0, 1, 2]);
    let prim = json!({"attributes": {"POSITION": position, "NORMAL": normal, "TEXCOORD_0": texcoord},
                      "indices": indices});
    let top = json!({
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "scale": [0.001, 0.001, 0.001], "translation": [0.0, 0.0, -2.0]}],
        "meshes": [{"primitives": [prim]}],
        "extensionsUsed": ["KHR_mesh_quantization"], "extensionsRequired": ["KHR_mesh_quantization"],
    });
    let s = Scene::load(g.write(d, "quantized", top)).unwrap();
    assert!(s.warnings.iter().all(|w| !w.contains("KHR_mesh_quantization")), "{:?}", s.warnings);
    let p = &s.mesh.positions;
    assert!(
        (p[1] - Vec3::new(1.0, 0.0, -2.0)).length() < 1e-6
            && (p[2] - Vec3::new(0.0, 1.0, -2.0)).length() < 1e-6,
        "{p:?}"
    );
    assert_eq!(s.attributes.normals[0], Vec3::Z);
    assert_eq!(s.attributes.uvs[1], glam::Vec2::new(1.0, 1.0));
}
