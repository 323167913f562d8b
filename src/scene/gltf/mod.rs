//! glTF 2.0 input (Khronos, <https://registry.khronos.org/glTF/specs/2.0/glTF-2.0.html>):
//! `.gltf` (JSON with buffers and images in files or `data:` URIs) and `.glb` (binary).
//!
//! The default scene's node tree (or, without scenes, every root node) is walked with each
//! node's matrix or TRS composed onto its parent's; triangle primitives become triangles in
//! world space (normals by the inverse transpose, the winding reversed under a mirroring
//! transform so front faces stay counter-clockwise), `TEXCOORD_0` flipped to `v` up. Materials
//! are mapped in [`material`], `KHR_lights_punctual` lights become point, spot and distant
//! lights, and the first perspective camera met becomes the scene's camera. Whatever is not
//! drawn as the file asks is said once in the warnings; malformed input is an error naming
//! the file and the JSON path at fault.

mod data;
mod material;

use super::camera::Camera;
use super::obj::MtlMaterial;
use super::{MaterialMaps, SceneError};
use crate::geometry::{TriangleMesh, VertexAttributes};
use crate::light::LightDesc;
use crate::texture::Textures;
use data::{at, read_floats, read_indices, Buffers};
use glam::{Mat3, Mat4, Quat, Vec2, Vec3};
use gltf::accessor::DataType;
use gltf::mesh::Mode;
use gltf::Semantic;
use std::collections::{HashMap, HashSet};
use std::path::Path;

/// The image height a glTF camera gets (its width follows its aspect ratio, 1 if it gives none).
pub const CAMERA_HEIGHT: u32 = 256;

/// The extensions read here (others in `extensionsUsed` are named in the warnings).
/// The component types (and whether normalised) of positions and texture coordinates: floats,
/// and with `KHR_mesh_quantization` bytes and shorts, signed or not, normalised or not.
const QUANTIZED: [(DataType, bool); 9] = [
    (DataType::F32, false),
    (DataType::I8, false),
    (DataType::I8, true),
    (DataType::U8, false),
    (DataType::U8, true),
    (DataType::I16, false),
    (DataType::I16, true),
    (DataType::U16, false),
    (DataType::U16, true),
];

/// Of normals: floats, and with `KHR_mesh_quantization` normalised signed bytes and shorts.
const NORMALS: [(DataType, bool); 3] = [(DataType::F32, false), (DataType::I8, true), (DataType::I16, true)];

const READ: [&str; 7] = [
    "KHR_lights_punctual",
    "KHR_materials_emissive_strength",
    "KHR_materials_transmission",
    "KHR_materials_ior",
    "KHR_texture_transform",
    "EXT_texture_webp",
    "KHR_mesh_quantization",
];

/// What a glTF file gives the scene.
#[derive(Default)]
pub struct GltfData {
    pub mesh: TriangleMesh,
    pub attributes: VertexAttributes,
    /// Each triangle's material name (`None`: the primitive has no material).
    pub tri_material: Vec<Option<String>>,
    /// The file's materials by name, as MTL materials, with their texture maps.
    pub materials: Vec<(String, MtlMaterial, MaterialMaps)>,
    pub lights: Vec<LightDesc>,
    /// The first perspective camera in the node tree.
    pub camera: Option<Camera>,
    pub warnings: Vec<String>,
}

/// Warnings said once each: `say(key, message)` keeps the first message of each key and
/// counts the rest.
#[derive(Default)]
pub struct Warnings {
    seen: HashMap<String, usize>,
    list: Vec<(String, usize)>,
}

impl Warnings {
    pub fn say(&mut self, key: impl Into<String>, message: impl Into<String>) {
        let key = key.into();
        match self.seen.get(&key) {
            Some(&i) => self.list[i].1 += 1,
            None => {
                self.seen.insert(key, self.list.len());
                self.list.push((message.into(), 0));
            }
        }
    }

    fn into_list(self, path: &Path) -> Vec<String> {
        let file = path.display();
        self.list
            .into_iter()
            .map(|(m, more)| match more {
                0 => format!("{file}: {m}"),
                n => format!("{file}: {m} (and {n} more like it)"),
            })
            .collect()
    }
}

/// Loads the glTF or GLB file at `path`, its textures into `textures`.
pub fn load(path: &Path, textures: &mut Textures) -> Result<GltfData, SceneError> {
    let bytes = std::fs::read(path).map_err(|error| SceneError::Io { path: path.to_owned(), error })?;
    let gltf::Gltf { document: doc, blob } = parse(path, &bytes)?;
    let buffers = Buffers::load(path, &doc, blob)?;
    let mut w = Warnings::default();
    for ext in doc.extensions_used() {
        if !READ.contains(&ext) {
            w.say(ext, format!("extensionsUsed: {ext} is not read; the file is drawn without it"));
        }
    }
    let mut out = GltfData::default();
    let names = material_names(path, &doc);
    let mut images =
        material::Images { path, doc: &doc, buffers: &buffers, textures, loaded: HashMap::new() };
    for (m, name) in doc.materials().zip(&names) {
        let field = format!("materials[{}]", m.index().unwrap_or(0));
        let (mtl, maps) = material::material(&field, name, &m, &mut images, &mut w)?;
        out.materials.push((name.clone(), mtl, maps));
    }
    let roots: Vec<gltf::Node> = match doc.default_scene().or_else(|| doc.scenes().next()) {
        Some(s) => {
            if doc.scenes().len() > 1 {
                w.say(
                    "scenes",
                    format!("{} scenes: only scenes[{}] is drawn", doc.scenes().len(), s.index()),
                );
            }
            s.nodes().collect()
        }
        None => {
            let children: HashSet<usize> =
                doc.nodes().flat_map(|n| n.children().map(|c| c.index())).collect();
            doc.nodes().filter(|n| !children.contains(&n.index())).collect()
        }
    };
    let mut visited = vec![false; doc.nodes().len()];
    let mut stack: Vec<(gltf::Node, Mat4)> = roots.into_iter().rev().map(|n| (n, Mat4::IDENTITY)).collect();
    while let Some((node, parent)) = stack.pop() {
        let field = format!("nodes[{}]", node.index());
        if std::mem::replace(&mut visited[node.index()], true) {
            return Err(at(
                path,
                field,
                "reached twice: the nodes must form trees (no shared children, no cycles)",
            ));
        }
        let world = parent * node_matrix(path, &field, &node)?;
        if !world.is_finite() {
            return Err(at(path, field, "its world transform overflows"));
        }
        if let Some(mesh) = node.mesh() {
            if node.skin().is_some() {
                w.say(
                    "skin",
                    format!("{field}: skinning is not applied; the mesh is drawn in its bind pose"),
                );
            }
            add_mesh(path, &mesh, world, &buffers, &names, &mut out, &mut w)?;
        }
        if let Some(c) = node.camera() {
            camera(path, &field, &c, world, &mut out, &mut w)?;
        }
        if let Some(l) = node.light() {
            out.lights.push(light(path, &field, &l, world, &mut w)?);
        }
        for child in node.children().collect::<Vec<_>>().into_iter().rev() {
            stack.push((child, world));
        }
    }
    if out.mesh.is_empty() {
        return Err(SceneError::file(path, "no triangles in the glTF's scene"));
    }
    out.warnings = w.into_list(path);
    Ok(out)
}

/// Parses and validates the JSON (of a `.gltf`, or inside a `.glb`).
fn parse(path: &Path, bytes: &[u8]) -> Result<gltf::Gltf, SceneError> {
    let (json, blob) = if bytes.starts_with(b"glTF") {
        // The header's length counts the header's own 12 bytes; `Glb::from_slice` takes them
        // off unchecked (gltf 1.4.1), which overflows on a shorter length (found by
        // `scripts/fuzz.sh gltf`).
        if let Some(&[a, b, c, d]) = bytes.get(8..12) {
            let length = u32::from_le_bytes([a, b, c, d]);
            if length < 12 {
                let e = format!(
                    "malformed GLB: its header gives a length of {length} bytes, less than its own 12"
                );
                return Err(SceneError::file(path, e));
            }
        }
        let glb = gltf::Glb::from_slice(bytes)
            .map_err(|e| SceneError::file(path, format!("malformed GLB: {e}")))?;
        (glb.json.into_owned(), glb.bin.map(|b| b.into_owned()))
    } else {
        (bytes.to_vec(), None)
    };
    let mut root = gltf::json::Root::from_slice(&json)
        .map_err(|e| SceneError::file(path, format!("malformed glTF JSON: {e}")))?;
    // Read here, but not among the extensions the `gltf` crate lets a file require.
    root.extensions_required.retain(|e| e != "KHR_mesh_quantization");
    // The `gltf` crate's own validation indexes the accessors with each primitive's POSITION
    // before checking it (gltf-json 1.4.1, `primitive_validate_hook`): check that first.
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            for (semantic, index) in &prim.attributes {
                if index.value() >= root.accessors.len() {
                    let name = match semantic {
                        gltf::json::validation::Checked::Valid(s) => s.to_string(),
                        gltf::json::validation::Checked::Invalid => "?".into(),
                    };
                    return Err(at(
                        path,
                        format!("meshes[{m}].primitives[{p}].attributes[\"{name}\"]"),
                        format!("index {} out of range ({} accessors)", index.value(), root.accessors.len()),
                    ));
                }
            }
        }
    }
    // Nor does it check that an image has its data, or a buffer view's image its MIME type,
    // which `Image::source` unwraps (gltf 1.4.1; found by `scripts/fuzz.sh gltf`).
    for (i, image) in root.images.iter().enumerate() {
        match (&image.uri, &image.buffer_view, &image.mime_type) {
            (None, None, _) => {
                return Err(at(
                    path,
                    format!("images[{i}]"),
                    "neither a uri nor a bufferView: the image has no data",
                ));
            }
            (_, Some(_), None) => {
                let e = "missing (glTF 2.0 requires it for an image in a bufferView)";
                return Err(at(path, format!("images[{i}].mimeType"), e));
            }
            _ => {}
        }
    }
    let document = gltf::Document::from_json(root).map_err(|e| match e {
        gltf::Error::Validation(errors) => {
            let (at_path, error) = &errors[0];
            let more = match errors.len() {
                1 => String::new(),
                n => format!(" (and {} more problems)", n - 1),
            };
            let value = serde_json::from_slice::<serde_json::Value>(&json)
                .ok()
                .and_then(|root| value_at(&root, at_path.as_str()).map(|v| v.to_string()));
            use gltf::json::validation::Error as E;
            let message = match (error, value) {
                (E::IndexOutOfBounds, Some(v)) => format!("index {v} out of range"),
                (E::IndexOutOfBounds, None) => "index out of range".into(),
                (E::Unsupported, _) => "an extension photonmap does not read".into(),
                (E::Missing, _) => "missing (glTF 2.0 requires it)".into(),
                (e, Some(v)) => format!("{}: {v}", e.to_string().to_lowercase()),
                (e, None) => e.to_string().to_lowercase(),
            };
            at(path, at_path.as_str(), format!("{message}{more}"))
        }
        e => SceneError::file(path, e.to_string()),
    })?;
    Ok(gltf::Gltf { document, blob })
}

/// The JSON value at a path in the `gltf` crate's notation (`meshes[0].attributes["POSITION"]`).
fn value_at<'v>(root: &'v serde_json::Value, path: &str) -> Option<&'v serde_json::Value> {
    let mut v = root;
    let mut rest = path;
    while !rest.is_empty() {
        rest = rest.strip_prefix('.').unwrap_or(rest);
        if let Some(r) = rest.strip_prefix("[\"") {
            let end = r.find("\"]")?;
            v = v.get(&r[..end])?;
            rest = &r[end + 2..];
        } else if let Some(r) = rest.strip_prefix('[') {
            let end = r.find(']')?;
            v = v.get(r[..end].parse::<usize>().ok()?)?;
            rest = &r[end + 1..];
        } else {
            let end = rest.find(['.', '[']).unwrap_or(rest.len());
            v = v.get(&rest[..end])?;
            rest = &rest[end..];
        }
    }
    Some(v)
}

/// Each material's name: its own if it has one no other material of the file has, else
/// `<file stem>.materials[i]`, so that names are unique and the scene file can address them.
fn material_names(path: &Path, doc: &gltf::Document) -> Vec<String> {
    let stem = path.file_stem().map_or_else(String::new, |s| s.to_string_lossy().into_owned());
    let mut count: HashMap<&str, usize> = HashMap::new();
    for m in doc.materials() {
        *count.entry(m.name().unwrap_or("")).or_default() += 1;
    }
    doc.materials()
        .enumerate()
        .map(|(i, m)| match m.name() {
            Some(n) if !n.is_empty() && count[n] == 1 => n.to_owned(),
            _ => format!("{stem}.materials[{i}]"),
        })
        .collect()
}

/// The node's local transform, its numbers checked.
fn node_matrix(path: &Path, field: &str, node: &gltf::Node) -> Result<Mat4, SceneError> {
    let finite = |name: &str, v: &[f32]| {
        if v.iter().all(|x| x.is_finite()) {
            Ok(())
        } else {
            Err(at(path, format!("{field}.{name}"), format!("{v:?} is not finite")))
        }
    };
    match node.transform() {
        gltf::scene::Transform::Matrix { matrix } => {
            let m = Mat4::from_cols_array_2d(&matrix);
            finite("matrix", &m.to_cols_array())?;
            Ok(m)
        }
        gltf::scene::Transform::Decomposed { translation, rotation, scale } => {
            finite("translation", &translation)?;
            finite("rotation", &rotation)?;
            finite("scale", &scale)?;
            let q = Quat::from_array(rotation);
            if !(q.length() > 1e-6) {
                return Err(at(path, format!("{field}.rotation"), "a zero quaternion"));
            }
            Ok(Mat4::from_scale_rotation_translation(scale.into(), q.normalize(), translation.into()))
        }
    }
}

/// Appends the triangle primitives of `mesh`, placed by `world`.
fn add_mesh(
    path: &Path,
    mesh: &gltf::Mesh,
    world: Mat4,
    buffers: &Buffers,
    names: &[String],
    out: &mut GltfData,
    w: &mut Warnings,
) -> Result<(), SceneError> {
    let linear = Mat3::from_mat4(world);
    let det = linear.determinant();
    let normal_matrix = if det != 0.0 { linear.inverse().transpose() } else { Mat3::ZERO };
    for prim in mesh.primitives() {
        let f = format!("meshes[{}].primitives[{}]", mesh.index(), prim.index());
        if prim.mode() != Mode::Triangles {
            let mode = prim.mode();
            w.say(
                format!("mode {mode:?}"),
                format!("{f}: mode {mode:?} is not drawn (only Triangles); skipped"),
            );
            continue;
        }
        if prim.morph_targets().len() > 0 {
            w.say("morph", format!("{f}: morph targets are not applied; the base shape is drawn"));
        }
        let attr = |name: &str| format!("{f}.attributes[\"{name}\"]");
        let pos = prim.get(&Semantic::Positions).ok_or_else(|| at(path, attr("POSITION"), "missing"))?;
        let positions = read_floats::<3>(path, &attr("POSITION"), buffers, &pos, &QUANTIZED)?;
        let n = positions.len();
        let same_count = |name: &str, len: usize| {
            if len == n {
                Ok(())
            } else {
                Err(at(path, attr(name), format!("{len} values for {n} positions")))
            }
        };
        let normals = match prim.get(&Semantic::Normals) {
            Some(a) => {
                let v = read_floats::<3>(path, &attr("NORMAL"), buffers, &a, &NORMALS)?;
                same_count("NORMAL", v.len())?;
                v
            }
            None => Vec::new(),
        };
        let uvs = match prim.get(&Semantic::TexCoords(0)) {
            Some(a) => {
                let v = read_floats::<2>(path, &attr("TEXCOORD_0"), buffers, &a, &QUANTIZED)?;
                same_count("TEXCOORD_0", v.len())?;
                v
            }
            None => Vec::new(),
        };
        // Vertex colours (linear, RGB or RGBA: the alpha is not read) multiply the base colour.
        let colours = match prim.get(&Semantic::Colors(0)) {
            Some(a) => {
                let allowed = [(DataType::F32, false), (DataType::U8, true), (DataType::U16, true)];
                let name = attr("COLOR_0");
                let v: Vec<[f32; 3]> = if a.dimensions() == gltf::accessor::Dimensions::Vec4 {
                    let rgba = read_floats::<4>(path, &name, buffers, &a, &allowed)?;
                    rgba.iter().map(|c| [c[0], c[1], c[2]]).collect()
                } else {
                    read_floats::<3>(path, &name, buffers, &a, &allowed)?
                };
                same_count("COLOR_0", v.len())?;
                if let Some(c) = v.iter().find(|c| !c.iter().all(|x| x.is_finite() && *x >= 0.0)) {
                    return Err(at(path, name, format!("colour {c:?} is negative or not finite")));
                }
                v
            }
            None => Vec::new(),
        };
        let indices = match prim.indices() {
            Some(a) => read_indices(path, &format!("{f}.indices"), buffers, &a)?,
            None => (0..n as u32).collect(),
        };
        if indices.len() % 3 != 0 {
            w.say(
                format!("{f} count"),
                format!("{f}: {} indices is not a multiple of 3; the rest is dropped", indices.len()),
            );
        }
        if let Some(&i) = indices.iter().find(|&&i| i as usize >= n) {
            return Err(at(
                path,
                format!("{f}.indices"),
                format!("vertex index {i} is not below the {n} positions"),
            ));
        }
        let base = out.mesh.positions.len();
        let part = TriangleMesh {
            positions: positions.iter().map(|&p| world.transform_point3(p.into())).collect(),
            indices: indices
                .chunks_exact(3)
                .map(|t| if det < 0.0 { [t[0], t[2], t[1]] } else { [t[0], t[1], t[2]] })
                .collect(),
        };
        let attributes = VertexAttributes {
            normals: normals
                .iter()
                .map(|&v| (normal_matrix * Vec3::from(v)).try_normalize().unwrap_or(Vec3::ZERO))
                .collect(),
            uvs: uvs.iter().map(|&[u, v]| Vec2::new(u, 1.0 - v)).collect(),
            colours: colours.iter().map(|&c| Vec3::from(c).min(Vec3::ONE)).collect(),
        };
        let material = prim.material().index().map(|i| names[i].clone());
        out.tri_material.extend(std::iter::repeat_n(material, part.len()));
        out.attributes.append(base, &attributes, n);
        out.mesh.append(&part);
    }
    Ok(())
}

/// Keeps the first perspective camera: it looks down its node's -Z with +Y up.
fn camera(
    path: &Path,
    field: &str,
    c: &gltf::Camera,
    world: Mat4,
    out: &mut GltfData,
    w: &mut Warnings,
) -> Result<(), SceneError> {
    let p = match c.projection() {
        gltf::camera::Projection::Perspective(p) => p,
        gltf::camera::Projection::Orthographic(_) => {
            w.say("ortho", format!("{field}: orthographic cameras are not drawn; skipped"));
            return Ok(());
        }
    };
    if out.camera.is_some() {
        w.say("cameras", format!("{field}: more than one camera; the first is used"));
        return Ok(());
    }
    let f = format!("cameras[{}].perspective", c.index());
    let vfov = p.yfov().to_degrees();
    let tan_half = (0.5 * p.yfov()).tan();
    if !(vfov > 0.0 && vfov < 180.0 && tan_half > 0.0 && tan_half.is_finite()) {
        return Err(at(
            path,
            format!("{f}.yfov"),
            format!("{} rad is not in (0, π), or too small to be used", p.yfov()),
        ));
    }
    let aspect = p.aspect_ratio().unwrap_or(1.0);
    if !(aspect.is_finite() && (1e-3..=1e3).contains(&aspect)) {
        return Err(at(path, format!("{f}.aspectRatio"), format!("{aspect} is not in [0.001, 1000]")));
    }
    let width = ((CAMERA_HEIGHT as f32 * aspect).round() as u32).clamp(1, crate::config::MAX_IMAGE_SIDE);
    let eye = world.transform_point3(Vec3::ZERO);
    let forward = world.transform_vector3(Vec3::NEG_Z);
    let up = world.transform_vector3(Vec3::Y);
    let cam = Camera::look_at(eye, eye + forward, up, vfov, width, CAMERA_HEIGHT).ok_or_else(|| {
        at(path, format!("{f}.yfov"), format!("a camera with yfov {vfov} degrees and its node's transform cannot be built (fov in (0, 180), a non-degenerate frame)"))
    })?;
    out.camera = Some(cam);
    Ok(())
}

/// A `KHR_lights_punctual` light; intensity (cd, lx) is read as W/sr, W/m² per unit colour.
fn light(
    path: &Path,
    field: &str,
    l: &gltf::khr_lights_punctual::Light,
    world: Mat4,
    w: &mut Warnings,
) -> Result<LightDesc, SceneError> {
    use gltf::khr_lights_punctual::Kind;
    let f = format!("extensions.KHR_lights_punctual.lights[{}]", l.index());
    let power = Vec3::from(l.color()) * l.intensity();
    if !power.is_finite() || power.min_element() < 0.0 {
        return Err(at(
            path,
            format!("{f}.intensity"),
            format!("colour × intensity {power} is not finite and non-negative"),
        ));
    }
    if l.range().is_some() {
        w.say("range", format!("{f}.range: ignored (lights fall off as 1/d² without a cut-off)"));
    }
    let position = world.transform_point3(Vec3::ZERO);
    let direction = world
        .transform_vector3(Vec3::NEG_Z)
        .try_normalize()
        .ok_or_else(|| at(path, field, "the light's node transform collapses its -Z axis"))?;
    Ok(match l.kind() {
        Kind::Point => LightDesc::Point { position, intensity: power },
        Kind::Directional => LightDesc::Distant { direction, irradiance: power },
        Kind::Spot { inner_cone_angle, outer_cone_angle } => {
            let (inner, outer) = (inner_cone_angle.to_degrees(), outer_cone_angle.to_degrees());
            if !(outer > 0.0 && outer <= 90.0 && inner >= 0.0 && inner <= outer) {
                return Err(at(
                    path,
                    format!("{f}.spot"),
                    format!("cone angles inner {inner}° and outer {outer}° are not 0 ≤ inner ≤ outer ≤ 90°, outer > 0"),
                ));
            }
            LightDesc::Spot {
                position,
                direction,
                intensity: power,
                cone_deg: outer,
                falloff_deg: outer - inner,
            }
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn json_paths_are_followed() {
        let v: serde_json::Value =
            serde_json::from_str(r#"{"meshes":[{"primitives":[{"attributes":{"POSITION":7}}]}]}"#).unwrap();
        let got = value_at(&v, "meshes[0].primitives[0].attributes[\"POSITION\"]");
        assert_eq!(got, Some(&serde_json::json!(7)));
        assert_eq!(value_at(&v, "meshes[1]"), None);
    }
}
