//! Scenes: a TOML file (camera, meshes, material overrides, lights, render settings) with
//! geometry and materials from Wavefront OBJ/MTL or glTF 2.0, or a glTF file alone. Conventions are those of `scenes/SCENES.md`: metres,
//! right-handed +Y up, counter-clockwise front faces, flat shading.
//!
//! Loading validates everything up front and reports the file and the line or field at fault.

mod camera;
mod cameras;
mod cutouts;
mod error;
mod file;
mod gltf;
mod materials;
mod obj;
mod transform;

pub use camera::{Camera, CameraKey, Lens, MotionError, SceneCamera, Turntable, MAX_FRAMES};
pub use error::{one_line, SceneError};
pub use file::{
    CameraEntries, CameraEntry, KeyEntry, LightEntry, MaterialEntry, MaterialKind, SceneFile, TurntableEntry,
};
pub use materials::{AlphaMap, MaterialMaps, MetalRough, MetalRoughKind, TextureRef, DEFAULT_ALPHA_CUTOFF};
pub use obj::{MtlMap, MtlMaterial};

use crate::config::RenderSettings;
use crate::geometry::{Aabb, TriangleMesh, VertexAttributes};
use crate::light::{EnvironmentMap, LightDesc, Portal};
use crate::material::Material;
use crate::texture::{Texture, Textures};
use file::{finite3, nonneg3};
use glam::{Vec2, Vec3};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// A camera for a scene that has none: 40° high, square, from the front (+Z, the way glTF
/// models face), a little above and to the right of the centre of `bounds`, far enough back
/// that the bounding sphere fits in the view.
fn framing(bounds: &crate::geometry::Aabb) -> Option<Camera> {
    let (centre, radius) = bounds.bounding_sphere();
    let vfov = 40.0f32;
    let radius = if radius > 0.0 { radius } else { 1.0 };
    let distance = 1.05 * radius / (0.5 * vfov).to_radians().sin();
    let eye = centre + distance * Vec3::new(0.45, 0.35, 1.0).normalize();
    let side = gltf::CAMERA_HEIGHT;
    Camera::look_at(eye, centre, Vec3::Y, vfov, side, side).filter(|_| eye.is_finite())
}

/// A loaded, validated scene.
#[derive(Clone, Debug)]
pub struct Scene {
    pub path: PathBuf,
    /// The first view of `cameras[0]` (its first frame, or any frame if it is still).
    pub camera: Camera,
    /// Every camera of the scene file, in file order (at least one).
    pub cameras: Vec<SceneCamera>,
    pub mesh: TriangleMesh,
    /// The mesh's per-vertex shading normals and texture coordinates.
    pub attributes: VertexAttributes,
    /// Material index of each triangle.
    pub tri_material: Vec<u32>,
    pub materials: Vec<Material>,
    /// Each material's texture maps (indexed like `materials`).
    pub maps: Vec<MaterialMaps>,
    /// Whether any material has a texture or any vertex a colour (if not, [`Scene::material_at`]
    /// is a lookup).
    pub textured: bool,
    pub textures: Textures,
    pub material_names: Vec<String>,
    /// What the scene asks for that is not rendered as asked, each said once (the command
    /// line prints them).
    pub warnings: Vec<String>,
    pub lights: Vec<LightDesc>,
    /// Openings distant lights send their photons through (`[[portal]]`).
    pub portals: Vec<Portal>,
    pub render: RenderSettings,
}

impl Scene {
    /// Loads the scene file at `path` and everything it references. A `.gltf` or `.glb` file
    /// is a scene by itself: its camera, lights and materials, the settings' defaults.
    pub fn load(path: impl AsRef<Path>) -> Result<Scene, SceneError> {
        let path = path.as_ref();
        let ext = path.extension().map(|e| e.to_string_lossy().to_lowercase());
        if matches!(ext.as_deref(), Some("gltf" | "glb")) {
            return Scene::from_gltf(path);
        }
        let text =
            std::fs::read_to_string(path).map_err(|error| SceneError::Io { path: path.to_owned(), error })?;
        Scene::from_str(path, &text)
    }

    /// Builds a scene from TOML `text`; paths inside are relative to `path`'s directory.
    pub fn from_str(path: &Path, text: &str) -> Result<Scene, SceneError> {
        Scene::from_file(path, SceneFile::parse(path, text)?)
    }

    /// The scene of the glTF (or GLB) file at `path` alone, as if a scene file held just
    /// `[[mesh]] gltf = "<path>"`.
    pub fn from_gltf(path: &Path) -> Result<Scene, SceneError> {
        let name = path.file_name().map(PathBuf::from).unwrap_or_else(|| path.to_owned());
        let file = SceneFile {
            camera: None,
            meshes: vec![file::MeshEntry { gltf: Some(name), ..Default::default() }],
            materials: Default::default(),
            lights: Vec::new(),
            portals: Vec::new(),
            render: RenderSettings::default(),
        };
        Scene::build(path, file, true)
    }

    /// Builds the scene `file` describes; paths inside are relative to `path`'s directory.
    pub fn from_file(path: &Path, file: SceneFile) -> Result<Scene, SceneError> {
        Scene::build(path, file, false)
    }

    /// [`Scene::from_file`]; for a glTF file given alone (`gltf_alone`), what it lacks is made
    /// up and warned: a camera framing its bounds, and a white sky if it has no lights and
    /// nothing emits, or what emits only glows (`Scene::sky_for_a_model`).
    fn build(path: &Path, file: SceneFile, gltf_alone: bool) -> Result<Scene, SceneError> {
        if file.meshes.is_empty() {
            return Err(SceneError::field(path, "mesh", "no [[mesh]]: the scene has no geometry"));
        }
        let mut mesh = TriangleMesh::default();
        let mut attributes = VertexAttributes::default();
        let mut tri_names: Vec<Option<String>> = Vec::new();
        let mut given = materials::Given::default();
        let mut warnings = Vec::new();
        let mut gltf_lights = Vec::new();
        let mut gltf_camera = None;
        for (i, entry) in file.meshes.iter().enumerate() {
            let (mut part, mut part_attributes, names) = match (&entry.obj, &entry.gltf) {
                (Some(obj), None) => load_obj_entry(path, obj, entry, &file, &mut given.mtl)?,
                (None, Some(g)) => {
                    let g = self::gltf::load(&obj::relative_to(path, g), &mut given.textures)?;
                    let moved = entry.scale.is_some() || entry.translate.is_some();
                    if moved && (g.camera.is_some() || !g.lights.is_empty()) {
                        warnings.push(format!(
                            "mesh[{i}]: scale and translate move the glTF's triangles, not its camera and lights"
                        ));
                    }
                    for (name, m, maps) in g.materials {
                        if given.mtl.contains_key(&name) {
                            warnings.push(format!(
                                "mesh[{i}]: material {name} is defined by an earlier mesh file too; that one is used"
                            ));
                        } else {
                            given.preset.insert(name.clone(), maps);
                            given.mtl.insert(name, m);
                        }
                    }
                    warnings.extend(g.warnings);
                    gltf_lights.extend(g.lights);
                    gltf_camera = gltf_camera.or(g.camera);
                    (g.mesh, g.attributes, g.tri_material)
                }
                _ => {
                    return Err(SceneError::field(
                        path,
                        format!("mesh[{i}]"),
                        "give exactly one of `obj` and `gltf`",
                    ))
                }
            };
            transform::apply(path, i, entry, &mut part, &mut part_attributes)?;
            if let Some(m) = &entry.material {
                tri_names.extend(std::iter::repeat_n(Some(m.clone()), part.len()));
            } else {
                tri_names.extend(names);
            }
            attributes.append(mesh.positions.len(), &part_attributes, part.positions.len());
            mesh.append(&part);
        }
        let cameras = match (&file.camera, gltf_camera) {
            (Some(c), _) => cameras::cameras(path, c)?,
            (None, Some(view)) => vec![SceneCamera::still("camera", view)],
            (None, None) if gltf_alone => {
                warnings.push(
                    "the glTF has no perspective camera: one frames its bounds from the front (+Z), above and to the right".into(),
                );
                vec![SceneCamera::still(
                    "camera",
                    framing(&mesh.bounds()).ok_or_else(|| {
                        SceneError::file(path, "no camera, and its geometry has no finite bounds to frame")
                    })?,
                )]
            }
            (None, None) => {
                return Err(SceneError::field(
                    path,
                    "camera",
                    "missing: no [camera] in the scene file and no perspective camera in its glTF files",
                ))
            }
        };
        let camera = cameras[0].view(cameras[0].frames().map_or(0, |f| *f.start()));
        mesh.validate().map_err(|e| SceneError::file(path, format!("after transforms: {e}")))?;
        attributes
            .validate(mesh.positions.len())
            .map_err(|e| SceneError::file(path, format!("after transforms: {e}")))?;
        let resolved = materials::resolve(path, &tri_names, given, &file)?;
        let resolved_emits = resolved.materials.iter().any(|m| m.emission().max_element() > 0.0);
        warnings.extend(resolved.warnings);
        let textured = resolved
            .maps
            .iter()
            .any(|m| !m.is_empty() || m.normal.is_some() || m.bump.is_some() || m.alpha.is_some());
        if textured && !attributes.has_uvs() {
            warnings.push(
                "textures are used but no mesh has texture coordinates (OBJ vt, glTF TEXCOORD_0): each shows one colour".into(),
            );
        }
        // Vertex colours vary the materials as textures do.
        let textured = textured || attributes.has_colours();
        let mut lights: Vec<LightDesc> =
            file.lights.iter().enumerate().map(|(i, l)| light(path, i, l)).collect::<Result<Vec<_>, _>>()?;
        lights.extend(gltf_lights);
        // (A glTF alone without lights is lit by a white sky instead: below.)
        if lights.is_empty() && !resolved_emits && !gltf_alone {
            warnings.push(format!(
                "{}: no [[light]] and no emissive material: the image will be black",
                path.display()
            ));
        }
        warnings.extend(unused_materials(path, &file, &tri_names));
        let portals =
            file.portals.iter().enumerate().map(|(i, p)| portal(path, i, p)).collect::<Result<_, _>>()?;
        validate_render(path, &file.render, &cameras)?;
        let mut scene = Scene {
            path: path.to_owned(),
            camera,
            cameras,
            mesh,
            attributes,
            tri_material: resolved.tri_material,
            materials: resolved.materials,
            maps: resolved.maps,
            textured,
            textures: resolved.textures,
            material_names: resolved.names,
            warnings,
            lights,
            portals,
            render: file.render,
        };
        if gltf_alone && scene.lights.is_empty() {
            if let Some(warning) = scene.sky_for_a_model() {
                scene.warnings.push(warning);
                scene.lights.push(white_sky());
            }
        }
        Ok(scene)
    }

    /// Bounds of all triangles.
    pub fn bounds(&self) -> Aabb {
        self.mesh.bounds()
    }

    /// The scene moved so that its bounding box is centred on the origin, or `None` when its
    /// centre is already within one bounding-box diagonal of the origin. Floats are densest near
    /// zero: far from it every surface point is rounded more and the robust ray offsets, which
    /// scale with the coordinates, grow with it (10⁵ away, pbrt's bound `gamma(7) |p|` is 4 cm,
    /// and the furnace moved there rendered 1 % dark in strips along its edges). Radiance does
    /// not depend on where the scene is, so the renderer works on the moved copy. The move is
    /// exact for every coordinate within a factor of two of the centre's (Sterbenz).
    pub fn recentred(&self) -> Option<Scene> {
        let b = self.bounds();
        if b.is_empty() {
            return None;
        }
        let c = b.center();
        if !(c.length() > (b.max - b.min).length()) {
            return None;
        }
        let mut s = self.clone();
        for p in &mut s.mesh.positions {
            *p -= c;
        }
        s.camera.eye -= c;
        s.cameras = s.cameras.iter().map(|k| k.translated(c)).collect();
        for l in &mut s.lights {
            match l {
                LightDesc::Point { position, .. } | LightDesc::Spot { position, .. } => *position -= c,
                LightDesc::Distant { .. } | LightDesc::Environment { .. } => {}
            }
        }
        for p in &mut s.portals {
            *p = p.translated(-c);
        }
        Some(s)
    }

    /// Whether a distant light (a sun) lights the scene.
    pub fn has_distant_light(&self) -> bool {
        self.lights.iter().any(|l| matches!(l, LightDesc::Distant { .. }))
    }

    /// The material of triangle `prim`, untextured (its kind and constants as the files give
    /// them).
    #[inline]
    pub fn material(&self, prim: u32) -> &Material {
        &self.materials[self.tri_material[prim as usize] as usize]
    }

    /// The material of triangle `prim` at texture coordinates `uv`, its textures looked up,
    /// its base colour times the vertex colour `colour`.
    #[inline]
    pub fn material_at(&self, prim: u32, uv: Vec2, colour: Vec3) -> Material {
        let id = self.tri_material[prim as usize] as usize;
        let m = self.materials[id];
        if !self.textured {
            return m;
        }
        let maps = &self.maps[id];
        let m = if maps.is_empty() { m } else { maps.apply(m, &self.textures, uv) };
        if colour == Vec3::ONE {
            m
        } else {
            m.tinted(colour)
        }
    }

    /// Each material's emission texture, for the area lights (`None` for all when no
    /// material has one).
    pub fn emission_maps(&self) -> Option<Vec<Option<crate::light::EmissionMap>>> {
        let maps: Vec<_> = self
            .maps
            .iter()
            .map(|m| {
                m.ke.map(|t| crate::light::EmissionMap {
                    texture: t.texture,
                    scale: t.scale,
                    offset: t.offset,
                    wrap: t.wrap,
                    factor: t.factor,
                })
            })
            .collect();
        maps.iter().any(Option::is_some).then_some(maps)
    }

    /// `f` of what textured emission needs ([`Scene::emission_maps`], the texture coordinates
    /// and the textures; `None` where no material has an emission texture).
    pub fn with_emission<T>(&self, f: impl FnOnce(Option<crate::light::EmissionTextures<'_>>) -> T) -> T {
        let maps = self.emission_maps();
        f(maps.as_deref().map(|maps| crate::light::EmissionTextures {
            uvs: &self.attributes.uvs,
            textures: &self.textures,
            maps,
        }))
    }

    /// Whether a model without lights is lit by a white sky, as glTF viewers light one, said as
    /// its warning: where nothing emits, or what emits only glows (LEDs and screens on a model,
    /// not the lamps that light it): nothing brighter than radiance 1 (glTF's emissiveFactor
    /// alone; brighter takes `KHR_materials_emissive_strength`, made for lamps), and all of it
    /// giving less than [`GLOW`] of the power a white sky brings to the model's bounding sphere.
    fn sky_for_a_model(&self) -> Option<String> {
        if self.materials.iter().all(|m| m.emission().max_element() <= 0.0) {
            return Some(
                "the glTF has no lights and nothing emits: it is lit by a white sky (radiance 1)".into(),
            );
        }
        let brightest = self
            .tri_material
            .iter()
            .map(|&m| self.materials[m as usize].emission().max_element())
            .fold(0.0, f32::max);
        let area = self.with_emission(|emission| {
            crate::light::AreaLights::from_mesh_textured(
                &self.mesh,
                &self.tri_material,
                &self.materials,
                emission,
            )
        });
        let emitted = area.power().element_sum() / 3.0;
        let radius = 0.5 * self.mesh.bounds().extent().length();
        let sky = std::f32::consts::PI * std::f32::consts::PI * radius * radius;
        (brightest <= 1.0 && emitted < GLOW * sky).then(|| {
            format!(
                "the glTF has no lights, and what emits glows (radiance {brightest} at most, {emitted:.3e} W against \
                 the {sky:.3e} W a white sky brings): a white sky (radiance 1) lights the model, as glTF viewers light one"
            )
        })
    }

    /// How many triangles use each material (by index: two materials with equal values are
    /// counted apart).
    pub fn triangles_per_material(&self) -> Vec<usize> {
        let mut count = vec![0; self.materials.len()];
        for &m in &self.tri_material {
            count[m as usize] += 1;
        }
        count
    }
}

/// An OBJ `[[mesh]]` entry's triangles, their attributes and material names; its MTL
/// materials go into `mtl` (the first of each name wins).
fn load_obj_entry(
    path: &Path,
    obj: &Path,
    entry: &file::MeshEntry,
    file: &SceneFile,
    mtl: &mut HashMap<String, MtlMaterial>,
) -> Result<(TriangleMesh, VertexAttributes, Vec<Option<String>>), SceneError> {
    let obj_path = obj::relative_to(path, obj);
    let data = obj::load_obj(&obj_path)?;
    for (name, line) in &data.used {
        if entry.material.is_none()
            && !file.materials.contains_key(name)
            && !data.materials.iter().any(|(n, _)| n == name)
        {
            return Err(SceneError::Line {
                path: obj_path.clone(),
                line: *line,
                message: format!(
                    "usemtl {name}: defined neither in the MTL nor in the scene file's [materials]"
                ),
            });
        }
    }
    for (name, m) in data.materials {
        mtl.entry(name).or_insert(m);
    }
    Ok((data.mesh, data.attributes, data.tri_material))
}

fn light(path: &Path, i: usize, l: &LightEntry) -> Result<LightDesc, SceneError> {
    let f = |name: &str| format!("light[{i}].{name}");
    let unit = |name: &str, v: [f32; 3]| -> Result<Vec3, SceneError> {
        finite3(path, &f(name), v)?
            .try_normalize()
            .ok_or_else(|| SceneError::field(path, f(name), "zero vector"))
    };
    Ok(match *l {
        LightEntry::Point { position, intensity } => LightDesc::Point {
            position: finite3(path, &f("position"), position)?,
            intensity: nonneg3(path, &f("intensity"), intensity)?,
        },
        LightEntry::Spot { position, direction, intensity, cone_deg, falloff_deg } => {
            if !(cone_deg > 0.0 && cone_deg <= 180.0) {
                return Err(SceneError::field(path, f("cone_deg"), format!("{cone_deg} is not in (0, 180]")));
            }
            if !(falloff_deg >= 0.0 && falloff_deg <= cone_deg) {
                return Err(SceneError::field(
                    path,
                    f("falloff_deg"),
                    format!("{falloff_deg} is not in [0, cone_deg]"),
                ));
            }
            LightDesc::Spot {
                position: finite3(path, &f("position"), position)?,
                direction: unit("direction", direction)?,
                intensity: nonneg3(path, &f("intensity"), intensity)?,
                cone_deg,
                falloff_deg,
            }
        }
        LightEntry::Distant { direction, irradiance } => LightDesc::Distant {
            direction: unit("direction", direction)?,
            irradiance: nonneg3(path, &f("irradiance"), irradiance)?,
        },
        LightEntry::Environment { radiance, ref map, ref rotate } => {
            let radiance = nonneg3(path, &f("radiance"), radiance.unwrap_or([1.0; 3]))?;
            let map = match map {
                None => None,
                Some(m) => {
                    let t = Texture::load(&obj::relative_to(path, m))
                        .map_err(|e| SceneError::field(path, f("map"), e))?;
                    Some(EnvironmentMap(std::sync::Arc::new(t)))
                }
            };
            let to_world = match rotate {
                None => glam::Mat3::IDENTITY,
                Some(r) => transform::rotation_of(path, &f("rotate"), r)?.as_mat3(),
            };
            LightDesc::Environment { radiance, map, to_world }
        }
    })
}

fn portal(path: &Path, i: usize, p: &file::PortalEntry) -> Result<Portal, SceneError> {
    let field = format!("portal[{i}].corners");
    let mut c = [Vec3::ZERO; 4];
    for (k, corner) in p.corners.iter().enumerate() {
        c[k] = finite3(path, &format!("{field}[{k}]"), *corner)?;
    }
    Portal::from_corners(c).map_err(|e| SceneError::field(path, field, e))
}

/// The most of a white sky's power that emitters no brighter than it may give and still be taken
/// for glows ([`Scene::sky_for_a_model`]). The controllers of the `@webxr-input-profiles/assets` npm package
/// whose LEDs glow give 3e-5 to 0.13 of it (11 of its 82 models, black or nearly without the
/// sky); a closed box whose walls all emit (the glTF furnace of `tests/gltf.rs`) 2.5.
const GLOW: f32 = 0.25;

/// The constant sky of radiance 1 a glTF alone is lit by where it has no lights of its own.
fn white_sky() -> LightDesc {
    LightDesc::Environment { radiance: Vec3::ONE, map: None, to_world: glam::Mat3::IDENTITY }
}

/// A warning for each `[materials.NAME]` of the scene file that no triangle uses (a typo such
/// as `[materials.whte]` would otherwise change nothing, silently), naming the ones in use.
fn unused_materials(path: &Path, file: &SceneFile, tri_names: &[Option<String>]) -> Vec<String> {
    let used: std::collections::BTreeSet<&str> = tri_names.iter().flatten().map(String::as_str).collect();
    file.materials
        .keys()
        .filter(|name| !used.contains(name.as_str()))
        .map(|name| {
            let names: Vec<&str> = used.iter().copied().collect();
            format!(
                "{}: [materials.{name}] is used by no triangle (the meshes' materials: {})",
                path.display(),
                if names.is_empty() { "none".to_string() } else { names.join(", ") }
            )
        })
        .collect()
}

/// Refuses `[render]` settings that cannot be honoured, before any work is done: the table is
/// resolved at each camera's size by the same checks every render runs.
fn validate_render(path: &Path, r: &RenderSettings, cameras: &[SceneCamera]) -> Result<(), SceneError> {
    for (i, c) in cameras.iter().enumerate() {
        if let Err(e) = r.resolve(c.width, c.height) {
            let at = if i == 0 {
                String::new()
            } else {
                format!(" (at camera[{i}] {:?}'s {}x{})", c.name, c.width, c.height)
            };
            return Err(SceneError::field(path, format!("render.{}", e.field), format!("{}{at}", e.message)));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests;
