//! Materials: each triangle's material name resolved to a [`Material`], from its MTL entry
//! and the scene file's `[materials.NAME]` (the file wins, field by field), with the texture
//! maps that vary it over the surface ([`MaterialMaps`]).

use super::file::{nonneg3, reflectance3, MaterialEntry, MaterialKind, SceneFile};
use super::obj::{relative_to, MtlMap, MtlMaterial, PBR_KEYWORDS};
use super::SceneError;
use crate::material::Material;
use crate::texture::{Encoding, Texture, Textures, Wrap};
use glam::{Vec2, Vec3};
use std::collections::HashMap;
use std::path::Path;

/// What material resolution gives the scene.
pub struct Resolved {
    /// Material index of each triangle.
    pub tri_material: Vec<u32>,
    pub materials: Vec<Material>,
    /// Each material's textures (indexed like `materials`).
    pub maps: Vec<MaterialMaps>,
    pub names: Vec<String>,
    pub textures: Textures,
    /// What the scene asks for that is not rendered, said once each.
    pub warnings: Vec<String>,
}

/// The materials the geometry files define, by name: MTL materials, and glTF materials read
/// as the MTL material they map to, with the texture maps already loaded (`preset`, into
/// `textures`) that glTF gives them.
#[derive(Default)]
pub struct Given {
    pub mtl: HashMap<String, MtlMaterial>,
    pub preset: HashMap<String, MaterialMaps>,
    pub textures: Textures,
}

/// Resolves every triangle's material name to an index, merging the geometry files' materials
/// with the scene file's `[materials.NAME]` entries (the file wins, field by field).
pub fn resolve(
    path: &Path,
    tri_names: &[Option<String>],
    given: Given,
    file: &SceneFile,
) -> Result<Resolved, SceneError> {
    let Given { mtl, preset, mut textures } = given;
    let mut index: HashMap<Option<&str>, u32> = HashMap::new();
    let mut materials = Vec::new();
    let mut maps = Vec::new();
    let mut names = Vec::new();
    let mut warnings = Vec::new();
    let mut tri_material = Vec::with_capacity(tri_names.len());
    for name in tri_names {
        let key = name.as_deref();
        let id = match index.get(&key) {
            Some(&id) => id,
            None => {
                let (m, textured) = match key {
                    None => (Material::Diffuse { kd: Vec3::splat(0.8) }, MaterialMaps::default()),
                    Some(n) => {
                        let principled = mtl.get(n).and_then(read_principled);
                        if let Some(b) = principled.as_ref().filter(|b| b.blender) {
                            let note = format!(
                                "{}: written by Blender: its materials are read as Blender's principled BSDF (roughness from Ns, metallic from Ka), as their glTF export would be",
                                b.file.display()
                            );
                            if !warnings.contains(&note) {
                                warnings.push(note);
                            }
                        }
                        let (m, e) = (principled.as_ref().or(mtl.get(n)), file.materials.get(n));
                        let material = material(path, n, m, e, &mut warnings)?;
                        let preset = preset.get(n).copied().unwrap_or_default();
                        let textured =
                            texture_maps(path, n, &material, preset, m, e, &mut textures, &mut warnings)?;
                        (material, textured)
                    }
                };
                let id = materials.len() as u32;
                materials.push(m);
                maps.push(textured);
                names.push(key.unwrap_or("(default grey)").to_owned());
                index.insert(key, id);
                id
            }
        };
        tri_material.push(id);
    }
    Ok(Resolved { tri_material, materials, maps, names, textures, warnings })
}

/// One material from its MTL entry and/or scene-file entry.
fn material(
    path: &Path,
    name: &str,
    mtl: Option<&MtlMaterial>,
    entry: Option<&MaterialEntry>,
    warnings: &mut Vec<String>,
) -> Result<Material, SceneError> {
    if mtl.is_none() && entry.is_none() {
        return Err(SceneError::field(
            path,
            format!("materials.{name}"),
            "used by the mesh but defined neither in its MTL nor in the scene file",
        ));
    }
    let empty = MtlMaterial::default();
    if let Some(m) = mtl {
        mtl_warnings(name, m, entry.is_some_and(|e| e.kind.is_some()), warnings);
    }
    let mtl = mtl.unwrap_or(&empty);
    let none = MaterialEntry::default();
    let e = entry.unwrap_or(&none);
    let field = |f: &str| format!("materials.{name}.{f}");
    let kd = e.kd.or(mtl.kd).unwrap_or([0.0; 3]);
    let ks = e.ks.or(mtl.ks).unwrap_or([0.0; 3]);
    // An emission texture multiplies `ke`, which is then 1 unless given (and makes the
    // material emissive unless its type says otherwise).
    let ke_map = e.ke_texture.is_some() || mtl.maps.iter().any(|m| m.keyword == "map_ke");
    let ke = e.ke.or(mtl.ke).unwrap_or(if ke_map { [1.0; 3] } else { [0.0; 3] });
    let kind = e.kind.unwrap_or_else(|| {
        if ke_map && ke.iter().any(|&x| x > 0.0) {
            MaterialKind::Emissive
        } else {
            mtl_kind(mtl)
        }
    });
    let m = match kind {
        MaterialKind::Diffuse => Material::Diffuse { kd: reflectance3(path, &field("kd"), kd)? },
        MaterialKind::Glossy => {
            let mut kd = reflectance3(path, &field("kd"), kd)?;
            let mut ks = reflectance3(path, &field("ks"), ks)?;
            let sum = (kd + ks).max_element();
            if sum > 1.0 {
                if e.kd.is_some() || e.ks.is_some() {
                    return Err(SceneError::field(
                        path,
                        field("ks"),
                        "kd + ks exceeds 1: not energy conserving",
                    ));
                }
                // Blender's default export (`Kd 0.8`, `Ks 0.5`, `illum 2`): both are scaled so
                // that the surface reflects no more than it receives.
                let at = mtl_at(mtl, "Ks");
                let v = |x: Vec3| if x.x == x.y && x.y == x.z { format!("{}", x.x) } else { format!("{x}") };
                let (kd0, ks0) = (kd, ks);
                (kd, ks) = (kd / sum, ks / sum);
                warnings.push(format!(
                    "{at}material {name}: Kd {} + Ks {} exceeds 1; both scaled by {:.3} to conserve energy (Kd {}, Ks {})",
                    v(kd0),
                    v(ks0),
                    1.0 / sum,
                    v(kd),
                    v(ks)
                ));
            }
            let ns =
                e.ns.or(mtl.ns).ok_or_else(|| SceneError::field(path, field("ns"), "glossy needs ns"))?;
            if !(0.0..=1e6).contains(&ns) {
                return Err(SceneError::field(path, field("ns"), format!("{ns} is not in [0, 1e6]")));
            }
            Material::Glossy { kd, ks, ns }
        }
        MaterialKind::Principled => {
            let unit = |f: &str, v: Option<f32>, default: f32| match v {
                Some(x) if !(0.0..=1.0).contains(&x) => {
                    Err(SceneError::field(path, field(f), format!("{x} is not in [0, 1]")))
                }
                v => Ok(v.unwrap_or(default)),
            };
            let metallic = unit("metallic", e.metallic.or(mtl.metallic), 0.0)?;
            let roughness = unit("roughness", e.roughness.or(mtl.roughness), 0.5)?;
            Material::principled(reflectance3(path, &field("kd"), kd)?, metallic, roughness)
        }
        MaterialKind::Mirror => {
            let ks = if e.ks.is_none() && mtl.ks.is_none() { [1.0; 3] } else { ks };
            Material::Mirror { ks: reflectance3(path, &field("ks"), ks)? }
        }
        MaterialKind::Glass => {
            let ior = e.ior.or(mtl.ni).unwrap_or(1.5);
            if !(ior.is_finite() && ior > 0.0 && ior < 100.0) {
                return Err(SceneError::field(path, field("ior"), format!("{ior} is not in (0, 100)")));
            }
            Material::Glass { ior }
        }
        MaterialKind::Emissive => Material::Emissive {
            kd: reflectance3(path, &field("kd"), kd)?,
            ke: nonneg3(path, &field("ke"), ke)?,
        },
    };
    Ok(m)
}

/// `file:line: ` of statement `keyword` of an MTL material (empty when it has none).
fn mtl_at(mtl: &MtlMaterial, keyword: &str) -> String {
    mtl.lines.get(keyword).map_or(String::new(), |line| format!("{}:{line}: ", mtl.file.display()))
}

/// Warnings for what an MTL material says that is not rendered as written: a dissolve `d`
/// below 1 (no blending: drawn opaque), the constants of MTL's PBR extension (`Ps`, `Pc`, …;
/// `Pr` and `Pm` where the material was not read by them) and, unless the scene file gives the material's `type`
/// (`typed`), an `illum` model outside 0..=7 (read as diffuse).
fn mtl_warnings(name: &str, mtl: &MtlMaterial, typed: bool, warnings: &mut Vec<String>) {
    if let Some(d) = mtl.dissolve.filter(|&d| d < 1.0) {
        warnings.push(format!(
            "{}material {name}: d {d} (dissolve) is not rendered: drawn opaque (map_d cut-outs are)",
            mtl_at(mtl, "d")
        ));
    }
    let pbr: Vec<&str> = PBR_KEYWORDS.into_iter().filter(|k| mtl.lines.contains_key(*k)).collect();
    if let Some(first) = pbr.first() {
        warnings.push(format!(
            "{}material {name}: {} (MTL's PBR extension) not rendered",
            mtl_at(mtl, first),
            pbr.join(", ")
        ));
    }
    if let Some(illum) = mtl.illum.filter(|&i| i > 7 && !typed) {
        warnings.push(format!(
            "{}material {name}: illum {illum} is not a model photonmap renders: read as diffuse (Kd)",
            mtl_at(mtl, "illum")
        ));
    }
}

/// The MTL mapping: `Ke` → emissive; `illum 3/5` → mirror; `illum 4/6/7` → glass; `illum 2`
/// with a roughness (`Pr`, or one [`read_principled`] found) → principled; `illum 2` with `Ks`
/// and `Ns` → glossy; otherwise diffuse.
fn mtl_kind(m: &MtlMaterial) -> MaterialKind {
    let nonzero = |v: Option<[f32; 3]>| v.is_some_and(|v| v.iter().any(|&x| x > 0.0));
    if nonzero(m.ke) {
        return MaterialKind::Emissive;
    }
    match m.illum {
        Some(3) | Some(5) => MaterialKind::Mirror,
        Some(4) | Some(6) | Some(7) => MaterialKind::Glass,
        Some(2) if m.roughness.is_some() => MaterialKind::Principled,
        Some(2) if nonzero(m.ks) && m.ns.is_some() => MaterialKind::Glossy,
        _ => MaterialKind::Diffuse,
    }
}

/// One texture as a material uses it: the image, the transform of the texture coordinates
/// (`uv * scale + offset`, MTL's `-s` and `-o`), what happens outside `[0, 1)` and a colour
/// the texels are multiplied by (glTF's `baseColorFactor`; 1 for MTL maps).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TextureRef {
    pub texture: u32,
    pub scale: Vec2,
    pub offset: Vec2,
    pub wrap: Wrap,
    pub factor: Vec3,
}

impl TextureRef {
    /// The whole of texture `texture`, repeated, unscaled.
    pub fn plain(texture: u32) -> TextureRef {
        TextureRef { texture, scale: Vec2::ONE, offset: Vec2::ZERO, wrap: Wrap::Repeat, factor: Vec3::ONE }
    }

    /// Linear RGB at `uv`.
    #[inline]
    pub fn rgb(&self, textures: &Textures, uv: Vec2) -> Vec3 {
        textures.get(self.texture).sample(uv * self.scale + self.offset, self.wrap).truncate() * self.factor
    }
}

/// What a glTF metallic-roughness material (neither emissive nor transmissive) is drawn as,
/// by its metallic and roughness values (README, "glTF 2.0"): the glTF loader picks one from
/// the factors, [`MetalRough`] one per texel of a `metallicRoughnessTexture`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MetalRoughKind {
    /// Metallic ≥ 0.5, roughness 0: `mirror`, `ks` = base colour.
    Mirror,
    /// Metallic ≥ 0.5, or roughness < 0.5: `principled` (GGX, Schlick's Fresnel on the base
    /// colour by the metallic value, over 96 % of the base colour diffusely by the rest).
    Principled,
    /// Metallic < 0.5, roughness ≥ 0.5: `diffuse`, `kd` = base colour (its 4 % lobe, as wide
    /// as a diffuse one, is not drawn).
    Matte,
}

impl MetalRoughKind {
    pub fn of(metal: f32, rough: f32) -> MetalRoughKind {
        match (metal >= 0.5, rough) {
            (true, r) if r <= 0.0 => MetalRoughKind::Mirror,
            (false, r) if r >= 0.5 => MetalRoughKind::Matte,
            _ => MetalRoughKind::Principled,
        }
    }

    /// The material of this kind for base colour `base` (in [0, 1]), metallic value `metal`
    /// and roughness `rough`.
    pub fn material(self, base: Vec3, metal: f32, rough: f32) -> Material {
        match self {
            MetalRoughKind::Mirror => Material::Mirror { ks: base },
            MetalRoughKind::Principled => Material::principled(base, metal, rough),
            MetalRoughKind::Matte => Material::Diffuse { kd: base },
        }
    }

    /// Writes a material of this kind into the MTL fields the scene's materials read it from
    /// (`mtl_kind`): the base colour as `Kd` (`Ks` for the mirror), `illum`, and for a
    /// principled one the roughness and metallic values as the PBR extension's `Pr` and `Pm`.
    /// Whether the base colour's map is the `ks` map (the mirror's) is returned.
    pub fn write_mtl(self, mtl: &mut MtlMaterial, base: Vec3, metal: f32, rough: f32) -> bool {
        let base = base.clamp(Vec3::ZERO, Vec3::ONE).to_array();
        (mtl.kd, mtl.ks, mtl.ns) = (Some(base), None, None);
        // Kept for every kind: roughness and metallic maps decide the kind texel by texel.
        (mtl.roughness, mtl.metallic) = (Some(rough), Some(metal));
        match self {
            MetalRoughKind::Mirror => (mtl.illum, mtl.ks) = (Some(3), Some(base)),
            MetalRoughKind::Principled => mtl.illum = Some(2),
            MetalRoughKind::Matte => mtl.illum = Some(1),
        }
        self == MetalRoughKind::Mirror
    }
}

/// Reads a material of an MTL that holds a principled BSDF as that BSDF, as a glTF
/// material is read ([`MetalRoughKind`]): one with the PBR extension's roughness `Pr` (and
/// metallic `Pm`, else 0, or 1 with `illum 3`), or any of Blender's export. Blender writes the
/// BSDF's values into the MTL's Phong fields (`io/wavefront_obj/exporter/obj_export_mtl.cc`):
/// `Ns` = (1 − roughness)² × 1000 (in some earlier versions ((1 − roughness) × 30)², which reads
/// back within a few hundredths), `Ks` = the specular value (0.5, an F0 of 4 %, by default),
/// `Ka` = the metallic value where it is not 0 (then `illum 3`), `illum 2` otherwise (`illum
/// 1` where the specular value is 0: diffuse already), and `Pr`, `Pm` besides with its PBR
/// option. Read as Phong, the default material (`Kd 0.8`, `Ks 0.5`, `Ns 250`, `illum 2`) was
/// a glossy lobe of 38 % after scaling to conserve energy, and any metallic material a perfect
/// mirror. `None` for any other material, and for emitters, glass and `illum` beyond 3, which
/// keep the MTL mapping.
fn read_principled(mtl: &MtlMaterial) -> Option<MtlMaterial> {
    let emits = mtl.ke.is_some_and(|k| k.iter().any(|&x| x > 0.0));
    let pr_map = mtl.maps.iter().any(|m| m.keyword == "map_pr");
    let by_pbr = (mtl.roughness.is_some() || pr_map) && mtl.illum.is_none_or(|i| i <= 3);
    // Blender writes `illum 1` where the specular value is 0: diffuse as read.
    let by_blender = mtl.blender && matches!(mtl.illum, Some(2) | Some(3));
    if emits || !(by_pbr || by_blender) {
        return None;
    }
    let rough = mtl.roughness.unwrap_or_else(|| blender_roughness(mtl.ns)).clamp(0.0, 1.0);
    let metal = match mtl.metallic {
        Some(m) => m,
        None if mtl.illum == Some(3) => mtl.ka.filter(|_| mtl.blender).map_or(1.0, |a| a[0]),
        None => 0.0,
    }
    .clamp(0.0, 1.0);
    let mut mtl = mtl.clone();
    mtl.principled = true;
    // Read: not among the extension's constants warned as not rendered.
    mtl.lines.remove("Pr");
    mtl.lines.remove("Pm");
    let base = Vec3::from(mtl.kd.unwrap_or([0.8; 3]));
    let on_ks = MetalRoughKind::of(metal, rough).write_mtl(&mut mtl, base, metal, rough);
    // The base colour's map: the mirror's `ks`, otherwise the base colour (`kd`).
    mtl.maps.retain(|m| m.keyword != "map_ks");
    for m in mtl.maps.iter_mut().filter(|m| m.keyword == "map_kd" && on_ks) {
        m.keyword = "map_ks".to_string();
    }
    Some(mtl)
}

/// The principled BSDF's roughness Blender's `Ns` stands for: `1 − √(Ns / 1000)` (0.5 where
/// the MTL gives no `Ns`).
fn blender_roughness(ns: Option<f32>) -> f32 {
    ns.map_or(0.5, |ns| 1.0 - (ns.clamp(0.0, 1000.0) / 1000.0).sqrt())
}

/// A roughness or metallic value over a surface: a constant, or one channel of a linear
/// texture times the factor the texture reference holds in that channel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Scalar {
    Constant(f32),
    Texel { texture: TextureRef, channel: usize },
}

impl Scalar {
    #[inline]
    fn at(&self, textures: &Textures, uv: Vec2) -> f32 {
        match *self {
            Scalar::Constant(x) => x,
            Scalar::Texel { texture, channel } => texture.rgb(textures, uv)[channel],
        }
    }

    /// The texture read, if any.
    pub fn texture(&self) -> Option<TextureRef> {
        match *self {
            Scalar::Constant(_) => None,
            Scalar::Texel { texture, .. } => Some(texture),
        }
    }
}

/// A material whose roughness or metallic value varies over the surface (glTF's
/// `metallicRoughnessTexture`: linear, blue the metallic value, green the roughness, times the
/// factors; MTL's `map_Pr` and `map_Pm`: their red channel), with its base colour: the
/// material at each texel is what [`MetalRoughKind`] makes of that texel's values, so the metal
/// parts of a model are drawn as metal and the rest as the plastic or matte surface the
/// textures say. A texel is drawn as a mirror only where the material's constants make it one
/// too (the scene's analysis finds its specular surfaces, for caustics, by the material, not by
/// the texel); elsewhere a roughness of 0 is the sharpest lobe
/// ([`MIN_ALPHA`](crate::material::MIN_ALPHA)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MetalRough {
    pub roughness: Scalar,
    pub metallic: Scalar,
    /// The base colour (`baseColorFactor`'s, or `Kd`).
    pub base: Vec3,
    /// `baseColorTexture`, its factor `baseColorFactor`'s colour (or `map_Kd`).
    pub base_texture: Option<TextureRef>,
}

impl MetalRough {
    /// The material at `uv` of a material whose constants alone make it `m`.
    #[inline]
    pub fn at(&self, m: Material, textures: &Textures, uv: Vec2) -> Material {
        let (metal, rough) = match (self.metallic, self.roughness) {
            // glTF's one texture for both: read once.
            (Scalar::Texel { texture: a, channel: i }, Scalar::Texel { texture: b, channel: j })
                if a == b =>
            {
                let t = a.rgb(textures, uv);
                (t[i], t[j])
            }
            (metal, rough) => (metal.at(textures, uv), rough.at(textures, uv)),
        };
        let (metal, rough) = (metal.clamp(0.0, 1.0), rough.clamp(0.0, 1.0));
        let base = self.base_texture.map_or(self.base, |b| b.rgb(textures, uv)).clamp(Vec3::ZERO, Vec3::ONE);
        match MetalRoughKind::of(metal, rough) {
            MetalRoughKind::Mirror if !m.is_specular() => Material::principled(base, metal, rough),
            kind => kind.material(base, metal, rough),
        }
    }
}

/// The textures of one material: each replaces the constant it is named after (an MTL
/// `map_Kd` is the diffuse colour, whatever `Kd` says, as Blender and 3ds Max read it).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MaterialMaps {
    /// `map_Kd` / `kd_texture`: the diffuse albedo of diffuse, glossy and emissive materials.
    pub kd: Option<TextureRef>,
    /// `map_Ks` / `ks_texture`: the specular albedo of glossy materials and mirrors.
    pub ks: Option<TextureRef>,
    /// `norm`, or `map_Bump`/`bump` with a colour image: a tangent-space normal map (`+Z` out
    /// of the surface, `+X` along increasing `u`, `+Y` along increasing `v`; linear values
    /// `2 c - 1`, times `factor`: glTF's `normalTexture.scale` for x and y, 1 for z and for
    /// MTL maps) that bends the shading normal.
    pub normal: Option<TextureRef>,
    /// A grey `map_Bump`/`bump` (or `bump_texture`): a height map whose slopes bend the shading
    /// normal (pbrt's and Mitsuba's bump mapping): the surface is displaced along its shading
    /// normal by the texel value times `factor` (MTL `-bm`, `bump_scale`), in scene units.
    pub bump: Option<TextureRef>,
    /// `map_Ke` / `ke_texture` / glTF `emissiveTexture`: multiplies an emissive material's `ke`
    /// (the emitted radiance is `ke` times the texel).
    pub ke: Option<TextureRef>,
    /// `map_d` / `alpha_texture` / glTF `alphaMode` MASK: an alpha cut-out (see [`AlphaMap`]).
    pub alpha: Option<AlphaMap>,
    /// glTF's `metallicRoughnessTexture`: the material's kind and constants decided texel by
    /// texel (see [`MetalRough`]); over `kd` and `ks`, which hold the base colour map for the
    /// kind the factors alone give.
    pub metal_rough: Option<MetalRough>,
}

/// The MTL `map_d` and glTF `alphaCutoff` threshold when none is given.
pub const DEFAULT_ALPHA_CUTOFF: f32 = 0.5;

/// An alpha cut-out (leaves, fences): where a channel of the texture times `factor` is below
/// `cutoff`, the surface is not there: camera rays, shadow rays and photons go through it (glTF
/// `alphaMode` MASK). Only the coordinate transform and wrap of `texture` are used.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AlphaMap {
    pub texture: TextureRef,
    /// The channel read: 3 (alpha), or 0 (red) for an MTL `map_d` image without alpha.
    pub channel: usize,
    /// The value's factor (glTF `baseColorFactor`'s alpha; 1 for MTL and the scene file).
    pub factor: f32,
    pub cutoff: f32,
}

impl AlphaMap {
    /// Whether the surface is there at `uv`; `texture` is the one `self.texture` names.
    #[inline]
    pub fn opaque(&self, texture: &Texture, uv: Vec2) -> bool {
        let t = &self.texture;
        texture.channel(uv * t.scale + t.offset, t.wrap, self.channel) * self.factor >= self.cutoff
    }

    /// Whether every texel passes the threshold, so the cut-out cuts nothing and can be left out
    /// (bilinear filtering never leaves the texels' range).
    pub fn opaque_everywhere(&self, texture: &Texture) -> bool {
        let (lo, hi) = texture.channel_range(self.channel);
        let lowest = if self.factor >= 0.0 { lo * self.factor } else { hi * self.factor };
        lowest >= self.cutoff
    }
}

impl MaterialMaps {
    /// Whether no texture changes the material's constants (a normal map may still bend it).
    pub fn is_empty(&self) -> bool {
        self.kd.is_none() && self.ks.is_none() && self.ke.is_none() && self.metal_rough.is_none()
    }

    /// `m` with its textured constants looked up at `uv`. Albedos are clamped to `[0, 1]`, and
    /// a glossy material's `kd + ks` scaled down to 1 where a texture pushes it past.
    #[inline]
    pub fn apply(&self, m: Material, textures: &Textures, uv: Vec2) -> Material {
        if let Some(mr) = &self.metal_rough {
            return mr.at(m, textures, uv);
        }
        let albedo = |t: Option<TextureRef>, c: Vec3| {
            t.map_or(c, |t| t.rgb(textures, uv).clamp(Vec3::ZERO, Vec3::ONE))
        };
        match m {
            Material::Diffuse { kd } => Material::Diffuse { kd: albedo(self.kd, kd) },
            Material::Emissive { kd, ke } => Material::Emissive {
                kd: albedo(self.kd, kd),
                ke: self.ke.map_or(ke, |t| t.rgb(textures, uv) * ke),
            },
            Material::Glossy { kd, ks, ns } => {
                let (kd, ks) = (albedo(self.kd, kd), albedo(self.ks, ks));
                let over = (kd + ks).max(Vec3::ONE);
                Material::Glossy { kd: kd / over, ks: ks / over, ns }
            }
            Material::Principled { base, metallic, alpha, parts } => {
                Material::Principled { base: albedo(self.kd, base), metallic, alpha, parts }
            }
            Material::Mirror { ks } => Material::Mirror { ks: albedo(self.ks, ks) },
            Material::Glass { .. } => m,
        }
    }
}

/// The texture maps of material `name`: the scene file's `kd_texture`/`ks_texture`/`ke_texture`
/// (relative to the scene file) over the MTL's `map_Kd`/`map_Ks`/`map_Ke` over the glTF's
/// (`preset`). Maps the
/// material cannot use, and the MTL maps not rendered yet, are named in `warnings`.
#[allow(clippy::too_many_arguments)] // one material's three sources, and where the results go
fn texture_maps(
    path: &Path,
    name: &str,
    m: &Material,
    preset: MaterialMaps,
    mtl: Option<&MtlMaterial>,
    entry: Option<&MaterialEntry>,
    textures: &mut Textures,
    warnings: &mut Vec<String>,
) -> Result<MaterialMaps, SceneError> {
    let mut maps = preset;
    let from_mtl = |map: &MtlMap,
                    textures: &mut Textures,
                    warnings: &mut Vec<String>,
                    encoding: Encoding|
     -> Result<TextureRef, SceneError> {
        let file = relative_to(&map.mtl, &map.file);
        let texture =
            textures.get_or_load_as(&file, encoding).map_err(|e| SceneError::line(&map.mtl, map.line, e))?;
        if !map.ignored.is_empty() {
            warnings.push(format!(
                "{}:{}: {} options {} are not applied",
                map.mtl.display(),
                map.line,
                map.keyword,
                map.ignored.join(", ")
            ));
        }
        let wrap = if map.clamp { Wrap::Clamp } else { Wrap::Repeat };
        Ok(TextureRef { texture, scale: map.scale, offset: map.offset, wrap, factor: Vec3::ONE })
    };
    let principled = mtl.filter(|m| m.principled);
    let (mut pr, mut pm) = (None, None);
    for map in mtl.map_or(&[][..], |m| &m.maps[..]) {
        match map.keyword.as_str() {
            "map_pr" | "map_pm" if principled.is_some() => {
                let t = Some(from_mtl(map, textures, warnings, Encoding::Data)?);
                *(if map.keyword == "map_pr" { &mut pr } else { &mut pm }) = t;
            }
            "map_kd" => maps.kd = Some(from_mtl(map, textures, warnings, Encoding::Colour)?),
            "map_ks" => maps.ks = Some(from_mtl(map, textures, warnings, Encoding::Colour)?),
            "map_ke" => maps.ke = Some(from_mtl(map, textures, warnings, Encoding::Colour)?),
            "norm" | "map_bump" | "bump" => {
                let mut t = from_mtl(map, textures, warnings, Encoding::Data)?;
                if map.keyword != "norm" && textures.get(t.texture).is_grey() {
                    t.factor = Vec3::splat(map.bump_multiplier);
                    maps.bump = Some(t);
                    maps.normal = None;
                } else {
                    if map.bump_multiplier != 1.0 {
                        warnings.push(format!(
                            "{}:{}: `{}` (material {name}) is a normal map: its -bm is not applied",
                            map.mtl.display(),
                            map.line,
                            map.keyword
                        ));
                    }
                    maps.normal = Some(t);
                    maps.bump = None;
                }
            }
            "map_d" => {
                let t = from_mtl(map, textures, warnings, Encoding::Data)?;
                maps.alpha = Some(alpha_map(t, textures, 1.0, DEFAULT_ALPHA_CUTOFF));
            }
            other => warnings.push(format!(
                "{}:{}: `{other}` (material {name}) is not rendered yet; the material is drawn without it",
                map.mtl.display(),
                map.line
            )),
        }
    }
    // MTL's PBR maps, their red channel, replace the constants `Pr` and `Pm`.
    if let Some(p) = principled.filter(|_| pr.is_some() || pm.is_some()) {
        let scalar = |t: Option<TextureRef>, constant: f32| {
            t.map_or(Scalar::Constant(constant), |texture| Scalar::Texel { texture, channel: 0 })
        };
        maps.metal_rough = Some(MetalRough {
            roughness: scalar(pr, p.roughness.unwrap_or(0.5)),
            metallic: scalar(pm, p.metallic.unwrap_or(0.0)),
            base: Vec3::from(p.kd.or(p.ks).unwrap_or([0.8; 3])),
            base_texture: maps.kd.or(maps.ks),
        });
    }
    let from_file = |field: &str, file: &Path, textures: &mut Textures, encoding: Encoding| {
        let texture = textures
            .get_or_load_as(&relative_to(path, file), encoding)
            .map_err(|e| SceneError::field(path, format!("materials.{name}.{field}"), e))?;
        Ok::<_, SceneError>(TextureRef::plain(texture))
    };
    if let Some(e) = entry {
        if let Some(f) = &e.kd_texture {
            maps.kd = Some(from_file("kd_texture", f, textures, Encoding::Colour)?);
        }
        if let Some(f) = &e.ks_texture {
            maps.ks = Some(from_file("ks_texture", f, textures, Encoding::Colour)?);
        }
        if let Some(f) = &e.ke_texture {
            maps.ke = Some(from_file("ke_texture", f, textures, Encoding::Colour)?);
        }
        if e.normal_texture.is_some() && e.bump_texture.is_some() {
            return Err(SceneError::field(
                path,
                format!("materials.{name}.bump_texture"),
                "a material takes a normal map or a bump map, not both",
            ));
        }
        if let Some(f) = &e.normal_texture {
            maps.normal = Some(from_file("normal_texture", f, textures, Encoding::Data)?);
            maps.bump = None;
        }
        if let Some(f) = &e.bump_texture {
            maps.bump = Some(from_file("bump_texture", f, textures, Encoding::Data)?);
            maps.normal = None;
        }
        if let Some(f) = &e.alpha_texture {
            let t = from_file("alpha_texture", f, textures, Encoding::Data)?;
            maps.alpha = Some(alpha_map(t, textures, 1.0, DEFAULT_ALPHA_CUTOFF));
        }
        if let Some(cutoff) = e.alpha_cutoff {
            let field = format!("materials.{name}.alpha_cutoff");
            if !(0.0..=1.0).contains(&cutoff) {
                return Err(SceneError::field(path, field, format!("{cutoff} is not in [0, 1]")));
            }
            match maps.alpha.as_mut() {
                Some(a) => a.cutoff = cutoff,
                None => {
                    return Err(SceneError::field(
                        path,
                        field,
                        "the material has no alpha texture (alpha_texture, MTL map_d, glTF alphaMode MASK) to cut at",
                    ))
                }
            }
        }
        if let Some(scale) = e.bump_scale {
            let field = format!("materials.{name}.bump_scale");
            if !scale.is_finite() {
                return Err(SceneError::field(path, field, format!("{scale} is not a finite number")));
            }
            match maps.bump.as_mut() {
                Some(b) => b.factor = Vec3::splat(scale),
                None => return Err(SceneError::field(path, field, "the material has no bump map to scale")),
            }
        }
    }
    if let (Some(_), Some(e)) = (maps.metal_rough, entry) {
        let set = [
            ("type", e.kind.is_some()),
            ("kd", e.kd.is_some()),
            ("ks", e.ks.is_some()),
            ("ns", e.ns.is_some()),
            ("metallic", e.metallic.is_some()),
            ("roughness", e.roughness.is_some()),
            ("kd_texture", e.kd_texture.is_some()),
            ("ks_texture", e.ks_texture.is_some()),
        ];
        if let Some((field, _)) = set.iter().find(|(_, given)| *given) {
            warnings.push(format!(
                "{}: materials.{name}.{field} is given, so the material's roughness and metallic textures (glTF's metallicRoughnessTexture, MTL's map_Pr and map_Pm) are not used",
                path.display()
            ));
            maps.metal_rough = None;
        }
    }
    let uses_kd = matches!(
        m,
        Material::Diffuse { .. }
            | Material::Glossy { .. }
            | Material::Principled { .. }
            | Material::Emissive { .. }
    );
    let uses_ks = matches!(m, Material::Glossy { .. } | Material::Mirror { .. });
    let kind = format!("{m:?}");
    let kind = kind.split_whitespace().next().unwrap_or("").to_lowercase();
    if maps.kd.is_some() && !uses_kd {
        warnings.push(format!("material {name}: a {kind} material has no kd; its kd texture is not used"));
        maps.kd = None;
    }
    if maps.ks.is_some() && !uses_ks {
        warnings.push(format!("material {name}: a {kind} material has no ks; its ks texture is not used"));
        maps.ks = None;
    }
    if maps.ke.is_some() && m.emission() == Vec3::ZERO {
        warnings
            .push(format!("material {name}: a {kind} material emits nothing; its ke texture is not used"));
        maps.ke = None;
    }
    if maps.alpha.is_some() && matches!(m, Material::Emissive { .. }) {
        warnings.push(format!(
            "material {name}: an emissive material's cut-out is seen by rays, but light leaves its transparent parts too"
        ));
    }
    Ok(maps)
}

/// The cut-out of texture reference `t`: its alpha channel, or its red channel (a grey mask) if
/// the image has no alpha.
pub fn alpha_map(t: TextureRef, textures: &Textures, factor: f32, cutoff: f32) -> AlphaMap {
    let channel = if textures.get(t.texture).has_alpha() { 3 } else { 0 };
    AlphaMap { texture: t, channel, factor, cutoff }
}
