//! glTF's metallic-roughness materials (glTF 2.0 §3.9, with `KHR_materials_transmission`,
//! `KHR_materials_ior` and `KHR_materials_emissive_strength`) read as the MTL material they
//! map to, so that the scene file's `[materials.NAME]` overrides them field by field as it
//! does MTL materials. The mapping (README, "glTF 2.0"):
//!
//! | glTF | photonmap |
//! |---|---|
//! | emissive × strength ≠ 0 | `emissive`, `kd` = base colour, `ke` = emissive, times `emissiveTexture` texel by texel |
//! | transmission > 0.5 | `glass`, `ior` (default 1.5) |
//! | metallic ≥ 0.5, roughness 0 | `mirror`, `ks` = base colour |
//! | metallic ≥ 0.5 | `glossy`, `kd` = 0, `ks` = base colour, `ns` = 2/α² − 2, α = roughness² |
//! | metallic < 0.5, roughness < 0.5 | `glossy`, `kd` = 0.96 base colour, `ks` = 0.04, same `ns` |
//! | metallic < 0.5, roughness ≥ 0.5 | `diffuse`, `kd` = base colour |
//!
//! The last four rows are chosen from the factors, and again at every texel of a
//! `metallicRoughnessTexture` where there is one (`MetalRough`).
//!
//! `ns` is clamped to [0, 10⁴]. The base colour is `baseColorFactor × baseColorTexture` (the
//! factor rides on the texture reference). `alphaMode` MASK is an alpha cut-out at
//! `alphaCutoff` of the base colour's alpha (texture alpha × factor alpha); BLEND is drawn as
//! MASK at 0.5, warned. Textures not rendered are named in the warnings.

use super::super::materials::{
    AlphaMap, MaterialMaps, MetalRough, MetalRoughKind, Scalar, TextureRef, DEFAULT_ALPHA_CUTOFF,
};
use super::super::obj::MtlMaterial;
use super::super::SceneError;
use super::data::{at, uri_bytes, Buffers};
use super::Warnings;
use crate::texture::{Encoding, Texture, Textures, Wrap};
use glam::{Vec2, Vec3, Vec4};
use gltf::texture::WrappingMode;
use std::collections::HashMap;
use std::path::Path;

/// Images already turned into textures, by glTF image index.
pub struct Images<'a> {
    pub path: &'a Path,
    pub doc: &'a gltf::Document,
    pub buffers: &'a Buffers,
    pub textures: &'a mut Textures,
    pub loaded: HashMap<(usize, Encoding), u32>,
}

impl Images<'_> {
    /// The texture of image `image`, loaded once: a file through [`Textures::get_or_load`],
    /// a buffer view or `data:` URI decoded from memory.
    fn texture(&mut self, field: &str, image: gltf::Image, encoding: Encoding) -> Result<u32, SceneError> {
        if let Some(&t) = self.loaded.get(&(image.index(), encoding)) {
            return Ok(t);
        }
        let path = self.path;
        let name = format!("{}#images[{}]", path.display(), image.index());
        let t = match image.source() {
            gltf::image::Source::Uri { uri, .. } if !uri.starts_with("data:") => {
                let file = super::super::obj::relative_to(path, Path::new(&super::data::percent_decode(uri)));
                self.textures.get_or_load_as(&file, encoding).map_err(|e| at(path, field, e))?
            }
            gltf::image::Source::Uri { uri, .. } => {
                let bytes = uri_bytes(path, &format!("images[{}].uri", image.index()), uri)?;
                let t = Texture::from_memory_as(Path::new(&name), &bytes, encoding)
                    .map_err(|e| at(path, field, e))?;
                self.textures.push(t)
            }
            gltf::image::Source::View { view, .. } => {
                let buffer = &self.buffers.0[view.buffer().index()];
                let bytes = view
                    .offset()
                    .checked_add(view.length())
                    .and_then(|end| buffer.get(view.offset()..end))
                    .ok_or_else(|| {
                        at(
                            path,
                            format!("images[{}].bufferView", image.index()),
                            format!("bufferView {} runs past the end of its buffer", view.index()),
                        )
                    })?;
                let t = Texture::from_memory_as(Path::new(&name), bytes, encoding)
                    .map_err(|e| at(path, field, e))?;
                self.textures.push(t)
            }
        };
        self.loaded.insert((image.index(), encoding), t);
        Ok(t)
    }

    /// A texture reference for `info` (at `field`), multiplied by `factor`.
    fn reference(
        &mut self,
        field: &str,
        info: &gltf::texture::Info,
        factor: Vec3,
        warnings: &mut Warnings,
    ) -> Result<TextureRef, SceneError> {
        let (texture, tex_coord, transform) = (info.texture(), info.tex_coord(), Transform::of(info));
        self.reference_to(field, texture, tex_coord, transform, factor, Encoding::Colour, warnings)
    }

    /// A texture reference for texture `tex` read through `TEXCOORD_<tex_coord>` and moved by
    /// `KHR_texture_transform`'s `transform`, its image read as `encoding`.
    #[allow(clippy::too_many_arguments)] // a textureInfo's parts, and where messages go
    fn reference_to(
        &mut self,
        field: &str,
        tex: gltf::Texture,
        tex_coord: u32,
        transform: Option<Transform>,
        factor: Vec3,
        encoding: Encoding,
        warnings: &mut Warnings,
    ) -> Result<TextureRef, SceneError> {
        let (scale, offset) = match transform {
            None => (Vec2::ONE, Vec2::ZERO),
            Some(t) => t.scale_offset(self.path, field, warnings)?,
        };
        let tex_coord = transform.and_then(|t| t.tex_coord).unwrap_or(tex_coord);
        if tex_coord != 0 {
            warnings.say(
                format!("texcoord{tex_coord}"),
                format!("{field}: TEXCOORD_{tex_coord} is not read; TEXCOORD_0 is used"),
            );
        }
        let sampler = tex.sampler();
        let (s, t) = (sampler.wrap_s(), sampler.wrap_t());
        let wrap = match (s, t) {
            (WrappingMode::ClampToEdge, WrappingMode::ClampToEdge) => Wrap::Clamp,
            (WrappingMode::Repeat, WrappingMode::Repeat) => Wrap::Repeat,
            _ => {
                warnings.say(
                    "wrap",
                    format!("{field}: sampler wrap modes {s:?}/{t:?} are drawn as Repeat (only Repeat and ClampToEdge on both axes are)"),
                );
                Wrap::Repeat
            }
        };
        // `EXT_texture_webp`'s image where the texture has one (its `source`, if any, is the
        // fallback for viewers that cannot read WebP).
        let webp = tex.extension_value("EXT_texture_webp").map(|v| {
            let i = v.get("source").and_then(|s| s.as_u64()).and_then(|i| usize::try_from(i).ok());
            i.and_then(|i| self.doc.images().nth(i)).ok_or_else(|| {
                at(
                    self.path,
                    format!("textures[{}].extensions.EXT_texture_webp.source", tex.index()),
                    "not an image's index",
                )
            })
        });
        let image = match (webp.transpose()?, tex.source()) {
            (Some(image), _) | (None, Some(image)) => image,
            (None, None) => {
                return Err(at(self.path, format!("textures[{}]", tex.index()), "has no image photonmap reads (a `source`, or EXT_texture_webp's; KTX2 and DDS images are not read)"))
            }
        };
        let texture = self.texture(field, image, encoding)?;
        Ok(TextureRef { texture, scale, offset, wrap, factor })
    }
}

/// `KHR_texture_transform` on a texture reference: `uv' = offset + R(rotation) (scale ∘ uv)` in
/// glTF's texture coordinates (`v` down), and the set it reads.
#[derive(Clone, Copy, Debug)]
struct Transform {
    offset: [f32; 2],
    rotation: f32,
    scale: [f32; 2],
    tex_coord: Option<u32>,
}

impl Transform {
    /// The transform of a texture reference, if it has one.
    fn of(info: &gltf::texture::Info) -> Option<Transform> {
        info.texture_transform().map(|t| Transform {
            offset: t.offset(),
            rotation: t.rotation(),
            scale: t.scale(),
            tex_coord: t.tex_coord(),
        })
    }

    /// The transform from the raw JSON of an extension (for the texture references whose
    /// type does not read it: `normalTexture`); each number defaults as the extension says.
    fn from_json(v: &serde_json::Value) -> Transform {
        let pair = |k: &str, d: f32| {
            let a = v.get(k).and_then(|x| x.as_array());
            let at =
                |i: usize| a.and_then(|a| a.get(i)).and_then(|x| x.as_f64()).map_or(f32::NAN, |x| x as f32);
            if v.get(k).is_none() {
                [d, d]
            } else {
                [at(0), at(1)]
            }
        };
        Transform {
            offset: pair("offset", 0.0),
            rotation: v.get("rotation").map_or(0.0, |x| x.as_f64().map_or(f32::NAN, |x| x as f32)),
            scale: pair("scale", 1.0),
            tex_coord: v.get("texCoord").and_then(|x| x.as_u64()).map(|x| x as u32),
        }
    }

    /// The scale and offset of our texture coordinates (`v` up: `v = 1 − v_glTF`) that do what
    /// this does to glTF's: `u' = o_u + s_u u`, `v' = (1 − o_v − s_v) + s_v v`. A rotation is
    /// warned and left out.
    fn scale_offset(
        &self,
        path: &Path,
        field: &str,
        warnings: &mut Warnings,
    ) -> Result<(Vec2, Vec2), SceneError> {
        let ext = format!("{field}.extensions.KHR_texture_transform");
        let numbers = [self.offset[0], self.offset[1], self.scale[0], self.scale[1], self.rotation];
        if !numbers.iter().all(|x| x.is_finite()) {
            return Err(at(path, ext, "offset, rotation and scale must be finite numbers"));
        }
        if self.rotation != 0.0 {
            warnings.say(
                "uv-rotation",
                format!("{ext}: rotation {} is not applied (offset and scale are)", self.rotation),
            );
        }
        let [(ou, ov), (su, sv)] = [(self.offset[0], self.offset[1]), (self.scale[0], self.scale[1])];
        Ok((Vec2::new(su, sv), Vec2::new(ou, 1.0 - ov - sv)))
    }
}

/// glTF material `m` (its JSON path `field`, its name `name` in messages) as an MTL material
/// and its texture maps.
pub fn material(
    field: &str,
    name: &str,
    m: &gltf::Material,
    images: &mut Images,
    warnings: &mut Warnings,
) -> Result<(MtlMaterial, MaterialMaps), SceneError> {
    let path = images.path;
    let pbr = m.pbr_metallic_roughness();
    let [r, g, b, alpha] = pbr.base_color_factor();
    let base = Vec3::new(r, g, b);
    let (metal, rough) = (pbr.metallic_factor(), pbr.roughness_factor());
    let finite = base.is_finite() && alpha.is_finite() && metal.is_finite() && rough.is_finite();
    if !finite {
        return Err(at(path, format!("{field}.pbrMetallicRoughness"), "a factor is not finite"));
    }
    let strength = m.emissive_strength().unwrap_or(1.0);
    let ke = Vec3::from(m.emissive_factor()) * strength;
    if !ke.is_finite() || ke.min_element() < 0.0 {
        return Err(at(
            path,
            format!("{field}.emissiveFactor"),
            format!("{ke} (× strength) is not finite and non-negative"),
        ));
    }
    let base_map = match pbr.base_color_texture() {
        Some(info) => Some(images.reference(
            &format!("{field}.pbrMetallicRoughness.baseColorTexture"),
            &info,
            base,
            warnings,
        )?),
        None => None,
    };
    // The emitted radiance is emissiveFactor × strength × the texel (sRGB).
    let ke_map = match m.emissive_texture() {
        Some(info) => {
            Some(images.reference(&format!("{field}.emissiveTexture"), &info, Vec3::ONE, warnings)?)
        }
        None => None,
    };
    let normal = match m.normal_texture() {
        None => None,
        Some(nt) => {
            let f = format!("{field}.normalTexture");
            if !nt.scale().is_finite() {
                return Err(at(path, format!("{f}.scale"), format!("{} is not a finite number", nt.scale())));
            }
            let transform = nt.extension_value("KHR_texture_transform").map(Transform::from_json);
            Some(images.reference_to(
                &f,
                nt.texture(),
                nt.tex_coord(),
                transform,
                // The glTF scale of the map's x and y (see `MaterialMaps::normal`).
                Vec3::new(nt.scale(), nt.scale(), 1.0),
                Encoding::Data,
                warnings,
            )?)
        }
    };
    // Baked ambient occlusion stands in for the shadowing of indirect light that the photons
    // and rays compute; read, it would count it twice.
    if m.occlusion_texture().is_some() {
        warnings.say(
            format!("occlusionTexture {name}"),
            format!("{field}.occlusionTexture (material {name}) is not read: the renderer computes occlusion itself (baked, it would count twice)"),
        );
    }
    let cutoff = match m.alpha_mode() {
        gltf::material::AlphaMode::Opaque => None,
        gltf::material::AlphaMode::Mask => {
            let c = m.alpha_cutoff().unwrap_or(DEFAULT_ALPHA_CUTOFF);
            if !(c.is_finite() && c >= 0.0) {
                return Err(at(
                    path,
                    format!("{field}.alphaCutoff"),
                    format!("{c} is not a finite number >= 0"),
                ));
            }
            Some(c)
        }
        gltf::material::AlphaMode::Blend => {
            warnings.say(
                format!("alpha {name}"),
                format!("{field}.alphaMode BLEND (material {name}): drawn as MASK with alphaCutoff 0.5 (a cut-out; blending is not implemented)"),
            );
            Some(DEFAULT_ALPHA_CUTOFF)
        }
    };
    // The cut-out: base colour alpha (its texture's alpha channel, 1 without) times the factor's.
    let alpha_map = match (cutoff, base_map) {
        (None, _) => None,
        (Some(cutoff), Some(t)) => Some(AlphaMap { texture: t, channel: 3, factor: alpha, cutoff }),
        (Some(cutoff), None) if alpha >= cutoff => None,
        (Some(cutoff), None) => {
            warnings.say(
                format!("invisible {name}"),
                format!("material {name}: baseColorFactor alpha {alpha} is below its alphaCutoff {cutoff}: the surface is not drawn"),
            );
            let texel =
                Texture::from_linear(Path::new(&format!("{name} (alpha {alpha})")), 1, 1, vec![Vec4::W]);
            let t = TextureRef::plain(images.textures.push(texel));
            Some(AlphaMap { texture: t, channel: 3, factor: alpha, cutoff })
        }
    };
    let transmission = m.transmission().map_or(0.0, |t| t.transmission_factor());
    if m.transmission().is_some_and(|t| t.transmission_texture().is_some()) {
        warnings.say(
            format!("tt {name}"),
            format!("{field}: transmissionTexture (material {name}) is not rendered"),
        );
    }
    // Blue the metallic value, green the roughness (linear), times the factors; read only where
    // the material is drawn by them (not emissive, not glass).
    let emissive_or_glass =
        (ke.max_element() > 0.0).then_some("emissive").or((transmission > 0.5).then_some("glass"));
    let metal_rough = match (pbr.metallic_roughness_texture(), emissive_or_glass) {
        (None, _) => None,
        (Some(_), Some(kind)) => {
            warnings.say(
                format!("mr-unused {name}"),
                format!("{field}.pbrMetallicRoughness.metallicRoughnessTexture (material {name}) is not used: the material is drawn as {kind}"),
            );
            None
        }
        (Some(info), None) => Some(images.reference_to(
            &format!("{field}.pbrMetallicRoughness.metallicRoughnessTexture"),
            info.texture(),
            info.tex_coord(),
            Transform::of(&info),
            Vec3::new(0.0, rough, metal),
            Encoding::Data,
            warnings,
        )?),
    };
    let mut mtl = MtlMaterial::default();
    let mut maps = MaterialMaps { normal, alpha: alpha_map, ..MaterialMaps::default() };
    let unit = |v: Vec3| v.clamp(Vec3::ZERO, Vec3::ONE).to_array();
    if ke.max_element() > 0.0 {
        mtl.ke = Some(ke.to_array());
        mtl.kd = Some(unit(base));
        mtl.illum = Some(1);
        maps.kd = base_map;
        maps.ke = ke_map;
        if metal >= 0.5 || transmission > 0.5 {
            warnings.say(
                format!("emissive-kind {name}"),
                format!("material {name}: emissive, so drawn as an emissive diffuse surface (its metal or transmission is not)"),
            );
        }
    } else if transmission > 0.5 {
        mtl.illum = Some(7);
        mtl.ni = Some(m.ior().unwrap_or(1.5));
        if base.cmpne(Vec3::ONE).any() || base_map.is_some() {
            warnings.say(
                format!("tint {name}"),
                format!("material {name}: glass is clear; its base colour does not tint it"),
            );
        }
    } else {
        maps.metal_rough = metal_rough.map(|texture| MetalRough {
            roughness: Scalar::Texel { texture, channel: 1 },
            metallic: Scalar::Texel { texture, channel: 2 },
            base,
            base_texture: base_map,
        });
        if MetalRoughKind::of(metal, rough).write_mtl(&mut mtl, base, metal, rough) {
            maps.ks = base_map;
        } else {
            maps.kd = base_map;
        }
    }
    if base.max_element() > 1.0 || base.min_element() < 0.0 {
        warnings.say(
            format!("clamp {name}"),
            format!("material {name}: baseColorFactor {base} clamped to [0, 1]"),
        );
    }
    Ok((mtl, maps))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A transform read from raw JSON (a `normalTexture`'s) takes the extension's defaults for
    /// what it leaves out, and maps to our `v`-up coordinates: `v' = (1 − o_v − s_v) + s_v v`.
    #[test]
    fn a_transform_from_json_and_in_our_coordinates() {
        let t = Transform::from_json(&serde_json::json!({"scale": [2.0, 3.0], "texCoord": 0}));
        assert_eq!((t.offset, t.rotation, t.scale, t.tex_coord), ([0.0, 0.0], 0.0, [2.0, 3.0], Some(0)));
        let mut w = Warnings::default();
        let (scale, offset) =
            t.scale_offset(Path::new("m.gltf"), "materials[0].normalTexture", &mut w).unwrap();
        assert_eq!((scale, offset), (Vec2::new(2.0, 3.0), Vec2::new(0.0, -2.0)));
        // glTF's v = 0.25 is ours 0.75; scaled by 3 in glTF's it is 0.75, ours 0.25.
        assert!((0.75 * scale.y + offset.y - 0.25).abs() < 1e-6);
        let bad = Transform::from_json(&serde_json::json!({"offset": ["a", 1]}));
        let err = bad.scale_offset(Path::new("m.gltf"), "f", &mut w).unwrap_err().to_string();
        assert!(err.contains("f.extensions.KHR_texture_transform"), "{err}");
    }
}
