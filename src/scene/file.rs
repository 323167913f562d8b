//! The TOML scene file: its schema (serde, unknown keys rejected) and the checks on its values.

use super::SceneError;
use crate::config::RenderSettings;
use serde::de::value::{MapAccessDeserializer, SeqAccessDeserializer};
use serde::de::{Deserializer, MapAccess, SeqAccess, Visitor};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::fmt;
use std::path::{Path, PathBuf};

/// The scene file as written.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    /// Optional when a glTF mesh brings a camera.
    pub camera: Option<CameraEntries>,
    #[serde(default, rename = "mesh")]
    pub meshes: Vec<MeshEntry>,
    #[serde(default)]
    pub materials: BTreeMap<String, MaterialEntry>,
    #[serde(default, rename = "light")]
    pub lights: Vec<LightEntry>,
    #[serde(default, rename = "portal")]
    pub portals: Vec<PortalEntry>,
    #[serde(default)]
    pub render: RenderSettings,
}

/// `camera`: one `[camera]` table or an array of `[[camera]]` tables.
///
/// Deserialised by hand rather than as an untagged enum: an untagged enum reports only "data
/// did not match any variant", where this keeps the table's own error ("unknown field
/// `focal_length`") and its line.
#[derive(Debug)]
pub enum CameraEntries {
    One(CameraEntry),
    Many(Vec<CameraEntry>),
}

impl<'de> Deserialize<'de> for CameraEntries {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct Either;
        impl<'de> Visitor<'de> for Either {
            type Value = CameraEntries;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a [camera] table or [[camera]] tables")
            }
            fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<CameraEntries, A::Error> {
                CameraEntry::deserialize(MapAccessDeserializer::new(map)).map(CameraEntries::One)
            }
            fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<CameraEntries, A::Error> {
                Vec::deserialize(SeqAccessDeserializer::new(seq)).map(CameraEntries::Many)
            }
        }
        deserializer.deserialize_any(Either)
    }
}

/// `[camera]` or one of `[[camera]]`: a view, optionally animated by `[[camera.key]]`s or a
/// `turntable`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraEntry {
    /// Required in a `[[camera]]` array; a single `[camera]` is named `camera` by default.
    pub name: Option<String>,
    pub eye: [f32; 3],
    pub target: [f32; 3],
    pub up: [f32; 3],
    pub vfov_deg: f32,
    pub width: u32,
    pub height: u32,
    /// The thin lens's radius in metres; 0 (a pinhole) by default.
    pub aperture_radius: Option<f32>,
    /// Metres along the view direction to the plane in focus; the eye's distance to the
    /// target by default.
    pub focus_distance: Option<f32>,
    #[serde(default, rename = "key")]
    pub keys: Vec<KeyEntry>,
    pub turntable: Option<TurntableEntry>,
}

/// `[[camera.key]]`: the view at `frame`; fields left out take the camera's own values.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KeyEntry {
    pub frame: u32,
    pub eye: Option<[f32; 3]>,
    pub target: Option<[f32; 3]>,
    pub up: Option<[f32; 3]>,
    pub vfov_deg: Option<f32>,
    pub aperture_radius: Option<f32>,
    /// The camera's `focus_distance` if it gives one, else this key's eye-to-target distance.
    pub focus_distance: Option<f32>,
}

/// `turntable = { frames = N, center = [x, y, z], axis = [0, 1, 0], degrees = 360.0 }`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TurntableEntry {
    pub frames: u32,
    /// The camera's target by default.
    pub center: Option<[f32; 3]>,
    /// +Y by default.
    pub axis: Option<[f32; 3]>,
    /// 360 by default.
    pub degrees: Option<f32>,
}

/// A scale given as one number or per axis.
#[derive(Debug, Deserialize, Clone, Copy)]
#[serde(untagged)]
pub enum Scale {
    Uniform(f32),
    PerAxis([f32; 3]),
}

#[derive(Debug, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct MeshEntry {
    /// Path of the OBJ file, relative to the scene file (exactly one of `obj` and `gltf`).
    pub obj: Option<PathBuf>,
    /// Path of a glTF 2.0 file (`.gltf` or `.glb`), relative to the scene file.
    pub gltf: Option<PathBuf>,
    /// Material for every face of this mesh, replacing the file's own.
    pub material: Option<String>,
    /// Applied to the vertices first, then `rotate`, then `translate`.
    pub scale: Option<Scale>,
    /// One rotation or a list of them, applied in the order listed (after `scale`).
    pub rotate: Option<Rotate>,
    pub translate: Option<[f32; 3]>,
    /// A whole affine transform instead of `scale`, `rotate` and `translate`: 12 (3x4) or 16
    /// (4x4, last row `[0, 0, 0, 1]`) numbers, row-major, acting on column vectors.
    pub matrix: Option<Vec<f32>>,
}

/// `rotate = { axis = [x, y, z], degrees = a }`: counter-clockwise seen from the tip of `axis`
/// (right-hand rule), about an axis through the origin.
#[derive(Debug, Deserialize, Clone, Copy)]
#[serde(deny_unknown_fields)]
pub struct Rotation {
    pub axis: [f32; 3],
    pub degrees: f32,
}

/// `rotate`: one [`Rotation`] table or an array of them.
///
/// Deserialised by hand as [`CameraEntries`] is, so a table keeps its own error ("unknown field
/// `angle`") and its line.
#[derive(Debug)]
pub enum Rotate {
    One(Rotation),
    Many(Vec<Rotation>),
}

impl<'de> Deserialize<'de> for Rotate {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct Either;
        impl<'de> Visitor<'de> for Either {
            type Value = Rotate;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a rotation { axis = [x, y, z], degrees = a } or an array of them")
            }
            fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<Rotate, A::Error> {
                Rotation::deserialize(MapAccessDeserializer::new(map)).map(Rotate::One)
            }
            fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<Rotate, A::Error> {
                Vec::deserialize(SeqAccessDeserializer::new(seq)).map(Rotate::Many)
            }
        }
        deserializer.deserialize_any(Either)
    }
}

/// Material kinds a scene file may name.
#[derive(Debug, Deserialize, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum MaterialKind {
    Diffuse,
    Glossy,
    Principled,
    Mirror,
    Glass,
    Emissive,
}

/// `[materials.NAME]`: sets the material of that name, or overrides fields of the MTL's.
#[derive(Debug, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct MaterialEntry {
    #[serde(rename = "type")]
    pub kind: Option<MaterialKind>,
    pub kd: Option<[f32; 3]>,
    pub ks: Option<[f32; 3]>,
    pub ns: Option<f32>,
    /// A principled material's metallic value and roughness (glTF's; its base colour is `kd`).
    pub metallic: Option<f32>,
    pub roughness: Option<f32>,
    pub ior: Option<f32>,
    pub ke: Option<[f32; 3]>,
    /// An image for `kd` (relative to the scene file), replacing the MTL's `map_Kd`.
    pub kd_texture: Option<std::path::PathBuf>,
    /// An image for `ks`, replacing the MTL's `map_Ks`.
    pub ks_texture: Option<std::path::PathBuf>,
    /// An image multiplying `ke` (emitted radiance; `ke` is 1 unless given), replacing the
    /// MTL's `map_Ke`.
    pub ke_texture: Option<std::path::PathBuf>,
    /// A tangent-space normal map, replacing the MTL's `norm` or colour `map_Bump`.
    pub normal_texture: Option<std::path::PathBuf>,
    /// A height map (its red channel, linear), replacing the MTL's grey `map_Bump`.
    pub bump_texture: Option<std::path::PathBuf>,
    /// Scene units of height per unit of `bump_texture` (MTL `-bm`; default 1).
    pub bump_scale: Option<f32>,
    /// An alpha cut-out mask (its alpha channel, or its red channel without one), replacing
    /// the MTL's `map_d` and the glTF's MASK.
    pub alpha_texture: Option<std::path::PathBuf>,
    /// Where the alpha mask cuts (default 0.5): below it the surface is not there.
    pub alpha_cutoff: Option<f32>,
}

/// `[[portal]]`: an opening distant lights send their photons through (see
/// [`crate::light::portal`]).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PortalEntry {
    /// Four corners in order around a parallelogram.
    pub corners: [[f32; 3]; 4],
}

/// `[[light]]`: explicit lights (emissive materials are area lights already).
#[derive(Debug, Deserialize)]
#[serde(tag = "type", rename_all = "lowercase", deny_unknown_fields)]
pub enum LightEntry {
    Point {
        position: [f32; 3],
        intensity: [f32; 3],
    },
    Spot {
        position: [f32; 3],
        direction: [f32; 3],
        intensity: [f32; 3],
        cone_deg: f32,
        #[serde(default)]
        falloff_deg: f32,
    },
    Distant {
        direction: [f32; 3],
        irradiance: [f32; 3],
    },
    /// The sky: `radiance` (default 1) times the equirectangular image `map` (relative to the
    /// scene file; EXR or HDR, or any texture format), or `radiance` alone; turned by `rotate`.
    Environment {
        radiance: Option<[f32; 3]>,
        map: Option<std::path::PathBuf>,
        rotate: Option<Rotate>,
    },
}

impl SceneFile {
    /// Parses the TOML text of `path`; syntax and schema errors carry line and column.
    pub fn parse(path: &Path, text: &str) -> Result<Self, SceneError> {
        toml::from_str(text).map_err(|e| {
            // The parser's message may run over several lines ("invalid string\nexpected ...").
            let mut message = e.message().trim().lines().map(str::trim).collect::<Vec<_>>().join("; ");
            message = with_hint(message);
            if let Some(span) = e.span() {
                // An error at the end of the file is shown at the end of its last line.
                let at = span.start.min(text.len());
                let at = if at == text.len() { text.trim_end().len() } else { at };
                let before = &text[..at];
                let line = before.matches('\n').count() + 1;
                let column = before.len() - before.rfind('\n').map_or(0, |i| i + 1) + 1;
                message = format!("line {line}, column {column}: {message}");
            }
            SceneError::Toml { path: path.to_owned(), message }
        })
    }
}

/// The parser's "unknown field `x`, expected one of …" with a hint first for the keys a user
/// is likely to try: command-line-only flags, the image size, and flag spellings
/// (`caustic-photons` for `caustic_photons`).
fn with_hint(message: String) -> String {
    let Some(rest) = message.strip_prefix("unknown field `") else { return message };
    let Some((key, tail)) = rest.split_once('`') else { return message };
    let hint = match key {
        "threads" | "quiet" | "checkpoint_every" | "exposure" | "tonemap" | "png" | "stats" | "frames"
        | "cameras" | "resume" => format!("a command-line flag only: --{}", key.replace('_', "-")),
        "width" | "height" => "the image size is the camera's: `[camera] width`/`height`".to_string(),
        _ if key.contains('-') && RenderSettings::FIELDS.iter().any(|f| f.name == key.replace('-', "_")) => {
            format!("keys are spelt with underscores: `{}`", key.replace('-', "_"))
        }
        _ => return message,
    };
    format!("unknown field `{key}` ({hint}){tail}")
}

/// Checks that `v` is finite, naming `field` otherwise.
pub fn finite3(path: &Path, field: &str, v: [f32; 3]) -> Result<glam::Vec3, SceneError> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(glam::Vec3::from(v))
    } else {
        Err(SceneError::field(path, field, format!("{v:?} is not finite")))
    }
}

/// Checks that `v` is finite and non-negative.
pub fn nonneg3(path: &Path, field: &str, v: [f32; 3]) -> Result<glam::Vec3, SceneError> {
    let v = finite3(path, field, v)?;
    if v.min_element() < 0.0 {
        return Err(SceneError::field(path, field, format!("{:?} has a negative component", v.to_array())));
    }
    Ok(v)
}

/// Checks a reflectance: every component in [0, 1].
pub fn reflectance3(path: &Path, field: &str, v: [f32; 3]) -> Result<glam::Vec3, SceneError> {
    let v = nonneg3(path, field, v)?;
    if v.max_element() > 1.0 {
        return Err(SceneError::field(
            path,
            field,
            format!("{:?} exceeds 1: a surface cannot reflect more than it receives", v.to_array()),
        ));
    }
    Ok(v)
}
