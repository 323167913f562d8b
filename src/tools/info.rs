//! What a scene holds, for `photonmap info`: geometry, textures, cameras, materials (with the
//! triangles using each), lights with their power, portals. One [`SceneInfo`] is printed either
//! as aligned tables (its `Display`) or as JSON (`Serialize`), so the two never disagree.

use crate::light::{build_lights, Light, LightDesc};
use crate::material::Material;
use crate::scene::{Scene, TextureRef};
use glam::Vec3;
use serde::Serialize;
use std::fmt;

/// A scene's contents, ready to print.
#[derive(Debug, Serialize)]
pub struct SceneInfo {
    pub scene: String,
    pub triangles: usize,
    pub vertices: usize,
    /// Vertices with a shading normal (`vn`, glTF `NORMAL`).
    pub vertices_with_normals: usize,
    pub texture_coordinates: bool,
    /// Whether vertices carry colours (glTF `COLOR_0`, OBJ `v x y z r g b`).
    pub vertex_colours: bool,
    /// `[min, max]` corners of the mesh's bounding box.
    pub bounds: [[f32; 3]; 2],
    pub textures: Vec<TextureInfo>,
    pub cameras: Vec<CameraInfo>,
    pub materials: Vec<MaterialInfo>,
    pub lights: Vec<LightInfo>,
    pub portals: Vec<PortalInfo>,
}

#[derive(Debug, Serialize)]
pub struct TextureInfo {
    pub path: String,
    pub width: u32,
    pub height: u32,
    pub kib: usize,
}

#[derive(Debug, Serialize)]
pub struct CameraInfo {
    pub name: String,
    pub width: u32,
    pub height: u32,
    /// `[first, last]` frame of an animated camera; none for a still one.
    pub frames: Option<[u32; 2]>,
}

#[derive(Debug, Serialize)]
pub struct MaterialInfo {
    pub name: String,
    /// `diffuse`, `glossy`, `mirror`, `glass` or `emissive` (the scene file's `type`).
    #[serde(rename = "type")]
    pub kind: &'static str,
    pub triangles: usize,
    /// The constants, by their scene-file names (`kd`, `ks`, `ns`, `ior`, `ke`).
    #[serde(serialize_with = "as_map")]
    pub parameters: Vec<(&'static str, Vec<f32>)>,
    /// The textures, by slot (`kd`, `ks`, `ke`, `normal`, `bump`, `alpha`,
    /// `metallic_roughness`) and file.
    #[serde(serialize_with = "as_map")]
    pub textures: Vec<(&'static str, String)>,
}

#[derive(Debug, Serialize)]
pub struct LightInfo {
    /// `point`, `spot`, `distant`, `environment` or `area` (all emissive triangles).
    #[serde(rename = "type")]
    pub kind: &'static str,
    /// Emitted power in W per channel (for distant and environment lights: through the disc
    /// of the scene's bounding sphere, as photons are emitted).
    pub power: [f32; 3],
    /// The light's own values, by their scene-file names.
    #[serde(serialize_with = "as_map")]
    pub parameters: Vec<(&'static str, Vec<f32>)>,
    /// The environment map's file.
    pub map: Option<String>,
}

#[derive(Debug, Serialize)]
pub struct PortalInfo {
    pub corner: [f32; 3],
    pub edge_u: [f32; 3],
    pub edge_v: [f32; 3],
    pub area: f32,
}

/// `(name, value)` pairs as a JSON object in their order; a one-number value as a number.
fn as_map<S: serde::Serializer, V: Serialize>(pairs: &[(&'static str, V)], s: S) -> Result<S::Ok, S::Error> {
    use serde::ser::SerializeMap;
    let mut map = s.serialize_map(Some(pairs.len()))?;
    for (k, v) in pairs {
        match serde_json::to_value(v) {
            Ok(serde_json::Value::Array(a)) if a.len() == 1 => map.serialize_entry(k, &a[0])?,
            _ => map.serialize_entry(k, v)?,
        }
    }
    map.end()
}

impl SceneInfo {
    /// What `scene` holds.
    pub fn of(scene: &Scene) -> SceneInfo {
        let b = scene.bounds();
        let a = &scene.attributes;
        let vertices_with_normals =
            if a.has_normals() { a.normals.iter().filter(|n| **n != Vec3::ZERO).count() } else { 0 };
        let textures = scene
            .textures
            .list
            .iter()
            .map(|t| TextureInfo {
                path: t.path.display().to_string(),
                width: t.width(),
                height: t.height(),
                kib: t.bytes() / 1024,
            })
            .collect();
        let cameras = scene
            .cameras
            .iter()
            .map(|c| CameraInfo {
                name: c.name.clone(),
                width: c.width,
                height: c.height,
                frames: c.frames().map(|f| [*f.start(), *f.end()]),
            })
            .collect();
        let counts = scene.triangles_per_material();
        let materials = scene
            .material_names
            .iter()
            .zip(&scene.materials)
            .zip(&scene.maps)
            .zip(counts)
            .map(|(((name, m), maps), triangles)| {
                let file = |t: TextureRef| scene.textures.get(t.texture).path.display().to_string();
                let mr = maps.metal_rough;
                let slots = [
                    ("kd", maps.kd),
                    ("ks", maps.ks),
                    ("ke", maps.ke),
                    ("normal", maps.normal),
                    ("bump", maps.bump),
                    ("alpha", maps.alpha.map(|a| a.texture)),
                    ("roughness", mr.and_then(|m| m.roughness.texture())),
                    ("metallic", mr.and_then(|m| m.metallic.texture())),
                ];
                let textures = slots.into_iter().filter_map(|(slot, t)| Some((slot, file(t?)))).collect();
                let (kind, parameters) = material_parameters(m);
                MaterialInfo { name: name.clone(), kind, triangles, parameters, textures }
            })
            .collect();
        // The lights as the renderer builds them (textured emitters included), for their power.
        let built = scene.with_emission(|emission| {
            build_lights(
                &scene.lights,
                &scene.mesh,
                &scene.tri_material,
                &scene.materials,
                &scene.portals,
                emission,
            )
        });
        let lights = built
            .iter()
            .enumerate()
            .filter_map(|(i, l)| match (scene.lights.get(i), l) {
                (Some(desc), _) => Some(light_info(desc, l.power())),
                (None, Light::Area(area)) => Some(LightInfo {
                    kind: "area",
                    power: area.power().to_array(),
                    parameters: vec![("triangles", vec![area.len() as f32])],
                    map: None,
                }),
                // build_lights adds nothing after the descriptions but the area lights.
                (None, _) => None,
            })
            .collect();
        let portals = scene
            .portals
            .iter()
            .map(|p| PortalInfo {
                corner: p.corner.to_array(),
                edge_u: p.edge_u.to_array(),
                edge_v: p.edge_v.to_array(),
                area: p.edge_u.cross(p.edge_v).length(),
            })
            .collect();
        SceneInfo {
            scene: scene.path.display().to_string(),
            triangles: scene.mesh.len(),
            vertices: scene.mesh.positions.len(),
            vertices_with_normals,
            texture_coordinates: a.has_uvs(),
            vertex_colours: a.has_colours(),
            bounds: [b.min.to_array(), b.max.to_array()],
            textures,
            cameras,
            materials,
            lights,
            portals,
        }
    }
}

fn material_parameters(m: &Material) -> (&'static str, Vec<(&'static str, Vec<f32>)>) {
    let v = |x: Vec3| x.to_array().to_vec();
    match *m {
        Material::Diffuse { kd } => ("diffuse", vec![("kd", v(kd))]),
        Material::Glossy { kd, ks, ns } => ("glossy", vec![("kd", v(kd)), ("ks", v(ks)), ("ns", vec![ns])]),
        Material::Principled { base, metallic, alpha, .. } => (
            "principled",
            vec![("kd", v(base)), ("metallic", vec![metallic]), ("roughness", vec![alpha.sqrt()])],
        ),
        Material::Mirror { ks } => ("mirror", vec![("ks", v(ks))]),
        Material::Glass { ior } => ("glass", vec![("ior", vec![ior])]),
        Material::Emissive { kd, ke } => ("emissive", vec![("kd", v(kd)), ("ke", v(ke))]),
    }
}

fn light_info(l: &LightDesc, power: Vec3) -> LightInfo {
    let v = |x: Vec3| x.to_array().to_vec();
    let power = power.to_array();
    let (kind, parameters, map) = match l {
        LightDesc::Point { position, intensity } => {
            ("point", vec![("position", v(*position)), ("intensity", v(*intensity))], None)
        }
        LightDesc::Spot { position, direction, intensity, cone_deg, falloff_deg } => (
            "spot",
            vec![
                ("position", v(*position)),
                ("direction", v(*direction)),
                ("intensity", v(*intensity)),
                ("cone_deg", vec![*cone_deg]),
                ("falloff_deg", vec![*falloff_deg]),
            ],
            None,
        ),
        LightDesc::Distant { direction, irradiance } => {
            ("distant", vec![("direction", v(*direction)), ("irradiance", v(*irradiance))], None)
        }
        LightDesc::Environment { radiance, map, .. } => (
            "environment",
            vec![("radiance", v(*radiance))],
            map.as_ref().map(|m| m.0.path.display().to_string()),
        ),
    };
    LightInfo { kind, power, parameters, map }
}

/// A number in at most 4 significant digits, without trailing zeros (`0.725`, `17`, `1.2e+04`).
fn num(x: f32) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let a = x.abs();
    if !(1e-3..1e5).contains(&a) {
        return format!("{x:.3e}");
    }
    let decimals = (3 - a.log10().floor() as i32).max(0) as usize;
    let s = format!("{x:.decimals$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// A value as the scene file would write it: one number, or `[r, g, b]`-like when they differ.
fn values(v: &[f32]) -> String {
    match v {
        [x] => num(*x),
        [x, rest @ ..] if rest.iter().all(|y| y == x) => num(*x),
        _ => v.iter().map(|x| num(*x)).collect::<Vec<_>>().join(" "),
    }
}

fn parameters(p: &[(&'static str, Vec<f32>)]) -> String {
    p.iter().map(|(k, v)| format!("{k} {}", values(v))).collect::<Vec<_>>().join(", ")
}

/// `rows` as columns padded to their widest cell, each line indented by `indent`.
fn table(f: &mut fmt::Formatter<'_>, title: &str, header: &[&str], rows: &[Vec<String>]) -> fmt::Result {
    let mut widths: Vec<usize> = header.iter().map(|h| h.chars().count()).collect();
    for r in rows {
        for (w, c) in widths.iter_mut().zip(r) {
            *w = (*w).max(c.chars().count());
        }
    }
    writeln!(f)?;
    let line = |f: &mut fmt::Formatter<'_>, lead: &str, cells: &[String]| {
        let mut s = format!("{lead:<10}");
        for (i, (c, w)) in cells.iter().zip(&widths).enumerate() {
            if i + 1 == cells.len() {
                s.push_str(c);
            } else {
                s.push_str(&format!("{c:<w$}  "));
            }
        }
        writeln!(f, "{}", s.trim_end())
    };
    line(f, title, &header.iter().map(|h| h.to_string()).collect::<Vec<_>>())?;
    for r in rows {
        line(f, "", r)?;
    }
    Ok(())
}

fn plural(n: usize, one: &str, many: &str) -> String {
    format!("{n} {}", if n == 1 { one } else { many })
}

impl fmt::Display for SceneInfo {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let p3 = |p: &[f32; 3]| values(&[p[0], p[1], p[2]][..]).replace(' ', ", ");
        let p3 = |p: &[f32; 3]| {
            if p.iter().all(|x| *x == p[0]) {
                format!("({0}, {0}, {0})", num(p[0]))
            } else {
                format!("({})", p3(p))
            }
        };
        writeln!(f, "{:<10}{}", "scene", self.scene)?;
        writeln!(
            f,
            "{:<10}{}, {} ({} with normals), {}{}",
            "geometry",
            plural(self.triangles, "triangle", "triangles"),
            plural(self.vertices, "vertex", "vertices"),
            self.vertices_with_normals,
            if self.texture_coordinates { "texture coordinates" } else { "no texture coordinates" },
            if self.vertex_colours { ", vertex colours" } else { "" }
        )?;
        let [lo, hi] = &self.bounds;
        let size = [hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]];
        writeln!(f, "{:<10}{} .. {}, size {}", "bounds", p3(lo), p3(hi), size.map(num).join(" x "))?;
        let cams: Vec<Vec<String>> = self
            .cameras
            .iter()
            .map(|c| {
                let frames = c.frames.map_or("still".into(), |[a, b]| format!("frames {a}..={b}"));
                vec![c.name.clone(), format!("{}x{}", c.width, c.height), frames]
            })
            .collect();
        table(f, "cameras", &["name", "size", "frames"], &cams)?;
        if !self.textures.is_empty() {
            let rows: Vec<Vec<String>> = self
                .textures
                .iter()
                .map(|t| vec![t.path.clone(), format!("{}x{}", t.width, t.height), format!("{} KiB", t.kib)])
                .collect();
            table(f, "textures", &["file", "size", "memory"], &rows)?;
        }
        let rows: Vec<Vec<String>> = self
            .materials
            .iter()
            .map(|m| {
                let mut what = parameters(&m.parameters);
                for (slot, file) in &m.textures {
                    what.push_str(&format!(", {slot} texture {file}"));
                }
                vec![m.name.clone(), m.kind.into(), m.triangles.to_string(), what]
            })
            .collect();
        table(f, "materials", &["name", "type", "triangles", "parameters"], &rows)?;
        if self.lights.is_empty() {
            writeln!(f, "\n{:<10}none: the image will be black", "lights")?;
        } else {
            let rows: Vec<Vec<String>> = self
                .lights
                .iter()
                .map(|l| {
                    let mut what = parameters(&l.parameters);
                    if let Some(m) = &l.map {
                        what.push_str(&format!(", map {m}"));
                    }
                    vec![l.kind.into(), values(&l.power), what]
                })
                .collect();
            table(f, "lights", &["type", "power (W)", "parameters"], &rows)?;
        }
        if !self.portals.is_empty() {
            let rows: Vec<Vec<String>> = self
                .portals
                .iter()
                .map(|p| vec![p3(&p.corner), p3(&p.edge_u), p3(&p.edge_v), format!("{} m²", num(p.area))])
                .collect();
            table(f, "portals", &["corner", "edge u", "edge v", "area"], &rows)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::num;

    #[test]
    fn numbers_keep_four_significant_digits_and_no_trailing_zeros() {
        assert_eq!(num(0.725), "0.725");
        assert_eq!(num(17.0), "17");
        assert_eq!(num(39.30764), "39.31");
        assert_eq!(num(-0.8), "-0.8");
        assert_eq!(num(12345.0), "12345");
        assert_eq!(num(1.5e-5), "1.500e-5");
        assert_eq!(num(0.0), "0");
    }
}
