//! The scene's alpha cut-outs (MTL `map_d`, `alpha_texture`, glTF `alphaMode` MASK) as the
//! accelerators take them: a [`Cutouts`] marking the triangles whose material has an alpha map,
//! with a test that interpolates the triangle's texture coordinates at the hit's barycentrics
//! (as shading does, [`VertexAttributes::at`](crate::geometry::VertexAttributes::at)) and
//! compares the map's value with its cutoff. Camera rays, shadow rays and photons all go
//! through the accelerator, so they all see the same holes.

use super::materials::AlphaMap;
use super::Scene;
use crate::accel::Cutouts;
use crate::texture::Texture;
use glam::Vec2;
use std::sync::Arc;

/// What the opacity test knows of one cut-out triangle.
struct CutTriangle {
    /// Texture coordinates of its corners (zero without any).
    uv: [Vec2; 3],
    /// Index into the test's maps.
    map: u32,
}

impl Scene {
    /// The alpha cut-outs of the scene, `None` when it has none. A material whose alpha map
    /// passes its cutoff at every texel cuts nothing and is left out, so such a scene renders
    /// bit for bit as without the map, at no cost.
    pub fn cutouts(&self) -> Option<Cutouts> {
        let mut maps: Vec<(AlphaMap, Arc<Texture>)> = Vec::new();
        let slot_of_material: Vec<Option<u32>> = self
            .maps
            .iter()
            .map(|m| {
                let a = m.alpha?;
                let texture = &self.textures.list[a.texture.texture as usize];
                if a.opaque_everywhere(texture) {
                    return None;
                }
                maps.push((a, Arc::clone(texture)));
                Some(maps.len() as u32 - 1)
            })
            .collect();
        if maps.is_empty() {
            return None;
        }
        let is_cutout: Vec<bool> =
            self.tri_material.iter().map(|&m| slot_of_material[m as usize].is_some()).collect();
        let mut slot = vec![u32::MAX; self.mesh.len()];
        let mut tris = Vec::new();
        for (prim, &m) in self.tri_material.iter().enumerate() {
            let Some(map) = slot_of_material[m as usize] else { continue };
            let corners = self.mesh.indices[prim];
            let uv = if self.attributes.has_uvs() {
                corners.map(|i| self.attributes.uvs[i as usize])
            } else {
                [Vec2::ZERO; 3]
            };
            slot[prim] = tris.len() as u32;
            tris.push(CutTriangle { uv, map });
        }
        let opaque = move |prim: u32, u: f32, v: f32| -> bool {
            let Some(t) = slot.get(prim as usize).and_then(|&s| tris.get(s as usize)) else { return true };
            let w = [1.0 - u - v, u, v];
            let uv = w[0] * t.uv[0] + w[1] * t.uv[1] + w[2] * t.uv[2];
            let (map, texture) = &maps[t.map as usize];
            map.opaque(texture, uv)
        };
        Some(Cutouts::new(&is_cutout, Arc::new(opaque)))
    }
}
