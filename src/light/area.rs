//! Diffuse area lights: the scene's emissive triangles (pbrt-v4 `DiffuseAreaLight` on
//! triangles, with pbrt-v4's area sampling; Jensen 2001, section 5.1.3, for photon emission).
//!
//! Each triangle emits constant radiance `ke` from its front face only (the side the geometric
//! normal `(v1 - v0) x (v2 - v0)` points to), so its flux is `pi ke A`. All emitters form one
//! [`AreaLights`] collection: a triangle is picked by a [`Distribution1D`] over
//! `area * luminance(ke)`, a point uniformly by area on it, and the area density is turned into
//! a solid-angle density `pdf_A d^2 / cos(theta_light)` for direct lighting.
//!
//! A triangle whose material has an emission texture (MTL `map_Ke`, the scene file's
//! `ke_texture`, glTF `emissiveTexture`) emits `ke * texture(uv)` instead. It is cut into `n²`
//! equal barycentric sub-triangles ("pieces", `n` from the texels its texture coordinates
//! cover, at most [`MAX_SUBDIVISION`]), each weighted by its area times the mean luminance of
//! the emission over it (estimated from a few lookups per piece). The triangle is picked by
//! `area * luminance(mean emission)`, then a piece by its weight, then a uniform point in the
//! piece: the area density is `pmf(triangle) pmf(piece) n² / area`, and a hit's density is
//! found from the piece its barycentrics fall in. Untextured triangles are sampled as before,
//! bit for bit.

use super::{luminance, EmissionSample, LightSample};
use crate::geometry::{barycentric_error, offset_distance, offset_ray_origin, TriangleMesh};
use crate::material::Material;
use crate::sampling::{
    cosine_hemisphere_pdf, sample_cosine_hemisphere, sample_uniform_triangle, Distribution1D, Frame,
};
use crate::texture::{Texture, Textures, Wrap};
use glam::{Vec2, Vec3};
use rayon::prelude::*;
use std::f32::consts::PI;

/// The largest `n` of the `n²` pieces a textured emitter is cut into (at most `2 n² = 512`
/// weights, 4 KiB, per triangle).
pub const MAX_SUBDIVISION: u32 = 16;

/// At most this many lookups per side of a piece estimate its mean emission (so at most 64
/// per piece, 16 384 per triangle).
const MAX_LOOKUPS_PER_SIDE: u32 = 8;

/// Share of a textured triangle's mean luminance every piece is given at least, so that a
/// piece whose lookups all missed a bright texel (a thin line) can still be sampled.
const PIECE_FLOOR: f32 = 1e-3;

/// An emission texture as a material uses it: radiance `ke * factor * texel(uv * scale +
/// offset)`, the texel bilinearly filtered with `wrap` (the same lookup as the scene's
/// `TextureRef`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EmissionMap {
    /// Index into the scene's [`Textures`].
    pub texture: u32,
    pub scale: Vec2,
    pub offset: Vec2,
    pub wrap: Wrap,
    pub factor: Vec3,
}

/// What textured emission needs beyond the mesh and its materials.
#[derive(Clone, Copy, Debug)]
pub struct EmissionTextures<'a> {
    /// Per-vertex texture coordinates (empty: every point is at `(0, 0)`).
    pub uvs: &'a [Vec2],
    pub textures: &'a Textures,
    /// Each material's emission texture (indexed like the materials; shorter: none).
    pub maps: &'a [Option<EmissionMap>],
}

/// The emission texture of one textured emitter, its own copy of the image.
#[derive(Clone, Debug)]
struct EmitterTexture {
    texture: Texture,
    scale: Vec2,
    offset: Vec2,
    wrap: Wrap,
    factor: Vec3,
}

impl EmitterTexture {
    /// The texture's linear RGB at `uv` times `factor` (as `TextureRef::rgb`).
    #[inline]
    fn rgb(&self, uv: Vec2) -> Vec3 {
        self.texture.sample(uv * self.scale + self.offset, self.wrap).truncate() * self.factor
    }
}

/// A textured emitter's pieces: slot `2 (i n + j) + d` is the sub-triangle of grid cell
/// `(i, j)` (`i + j < n`) in the coordinates `(s, t)` of `v0 + s (v1 - v0) + t (v2 - v0)`,
/// `d = 0` the one at the cell's corner `(i, j)`, `d = 1` the flipped one (zero weight where
/// `i + j = n - 1`).
#[derive(Clone, Debug)]
struct Pieces {
    /// Index into [`AreaLights`]'s emitter textures.
    map: u32,
    /// The material's constant `ke`, the texture's multiplier.
    ke: Vec3,
    uvs: [Vec2; 3],
    n: u32,
    distribution: Distribution1D,
}

impl Pieces {
    /// The pieces of a triangle with texture coordinates `uvs` emitting `ke` times
    /// `maps[map]`, and the mean emission over it. `n` is about half the square root of the
    /// texels the triangle covers (so a piece covers a few texels), at most
    /// [`MAX_SUBDIVISION`]; each piece's mean is that of `k²` stratified lookups, `k` about the
    /// texels across a piece, at most [`MAX_LOOKUPS_PER_SIDE`].
    fn build(map: u32, ke: Vec3, uvs: [Vec2; 3], maps: &[EmitterTexture]) -> (Pieces, Vec3) {
        let m = &maps[map as usize];
        let (d1, d2) = ((uvs[1] - uvs[0]) * m.scale, (uvs[2] - uvs[0]) * m.scale);
        let uv_area = 0.5 * (d1.x * d2.y - d1.y * d2.x).abs();
        let texels = uv_area * m.texture.width() as f32 * m.texture.height() as f32;
        let texels = if texels.is_finite() { texels } else { 0.0 };
        let n = ((texels.sqrt() * 0.5).ceil() as u32).clamp(1, MAX_SUBDIVISION);
        let per_piece = texels / (n * n) as f32;
        let k = ((per_piece.sqrt() * 1.5).ceil() as u32).clamp(1, MAX_LOOKUPS_PER_SIDE);
        let mut p = Pieces { map, ke, uvs, n, distribution: Distribution1D::default() };
        let slots = 2 * (n * n) as usize;
        let mut means = vec![Vec3::ZERO; slots];
        let mut sum = Vec3::ZERO;
        for (slot, mean) in means.iter_mut().enumerate() {
            if !p.exists(slot) {
                continue;
            }
            let mut acc = Vec3::ZERO;
            for a in 0..k {
                for c in 0..k {
                    let u = [(a as f32 + 0.5) / k as f32, (c as f32 + 0.5) / k as f32];
                    acc += p.radiance(maps, p.barycentrics(slot, sample_uniform_triangle(u)));
                }
            }
            *mean = acc / (k * k) as f32;
            sum += *mean;
        }
        let tri_mean = sum / (n * n) as f32;
        let floor = PIECE_FLOOR * luminance(tri_mean.max(Vec3::ZERO));
        let weights: Vec<f32> = means
            .iter()
            .enumerate()
            .map(|(slot, m)| if p.exists(slot) { luminance(m.max(Vec3::ZERO)) + floor } else { 0.0 })
            .collect();
        p.distribution = Distribution1D::new(&weights);
        (p, tri_mean)
    }

    /// Whether slot `k` is a piece of the triangle: cell `(i, j)` with `i + j < n`, and its
    /// flipped half only with `i + j < n - 1`.
    fn exists(&self, k: usize) -> bool {
        let n = self.n as usize;
        let (cell, d) = (k / 2, k % 2);
        cell / n + cell % n + d < n
    }

    /// The corners, in `(s, t)`, of slot `k`.
    fn corners(&self, k: usize) -> [Vec2; 3] {
        let n = self.n as usize;
        let (cell, d) = (k / 2, k % 2);
        let (i, j) = ((cell / n) as f32, (cell % n) as f32);
        let inv = 1.0 / self.n as f32;
        let c = |a: f32, b: f32| Vec2::new(a * inv, b * inv);
        if d == 0 {
            [c(i, j), c(i + 1.0, j), c(i, j + 1.0)]
        } else {
            [c(i + 1.0, j + 1.0), c(i, j + 1.0), c(i + 1.0, j)]
        }
    }

    /// The slot `(s, t)` falls in.
    fn slot(&self, st: Vec2) -> usize {
        let n = self.n as f32;
        let (x, y) = (st.x * n, st.y * n);
        let i = x.floor().clamp(0.0, n - 1.0);
        let j = y.floor().clamp(0.0, (n - 1.0 - i).max(0.0));
        let flipped = (x - i) + (y - j) > 1.0 && i + j + 1.0 < n;
        2 * (i as usize * self.n as usize + j as usize) + flipped as usize
    }

    /// The barycentrics `(1 - s - t, s, t)` of the point `b` (barycentrics within the piece)
    /// of slot `k`.
    fn barycentrics(&self, k: usize, b: [f32; 3]) -> [f32; 3] {
        let [c0, c1, c2] = self.corners(k);
        let st = b[0] * c0 + b[1] * c1 + b[2] * c2;
        [1.0 - st.x - st.y, st.x, st.y]
    }

    /// Emitted radiance at barycentrics `b`.
    #[inline]
    fn radiance(&self, maps: &[EmitterTexture], b: [f32; 3]) -> Vec3 {
        let uv = b[0] * self.uvs[0] + b[1] * self.uvs[1] + b[2] * self.uvs[2];
        maps[self.map as usize].rgb(uv) * self.ke
    }

    /// Density per unit area (of the whole triangle, area 1) of slot `k`: `pmf n²`.
    #[inline]
    fn density(&self, k: usize) -> f32 {
        self.distribution.pmf(k) * (self.n * self.n) as f32
    }
}

/// One emitting triangle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EmitterTriangle {
    /// Index of the triangle in the scene mesh.
    pub prim: u32,
    pub vertices: [Vec3; 3],
    /// Unit front-face normal.
    pub normal: Vec3,
    pub area: f32,
    /// Emitted radiance (W m^-2 sr^-1); for a textured emitter, its mean over the triangle
    /// (as estimated from the pieces' lookups).
    pub ke: Vec3,
    /// Index into the collection's textured pieces, for a textured emitter.
    pieces: Option<u32>,
}

impl EmitterTriangle {
    /// Whether the emission varies over the triangle (an emission texture).
    pub fn is_textured(&self) -> bool {
        self.pieces.is_some()
    }

    /// Flux `pi ke A`.
    pub fn power(&self) -> Vec3 {
        PI * self.ke * self.area
    }

    /// A uniform point and the bound on its rounding error.
    fn point_and_error(&self, u: [f32; 2]) -> (Vec3, Vec3) {
        let b = sample_uniform_triangle(u);
        let [v0, v1, v2] = self.vertices;
        (b[0] * v0 + b[1] * v1 + b[2] * v2, barycentric_error(self.vertices, b))
    }

    /// The point of barycentrics `b` and the bound on its rounding error.
    fn point_at(&self, b: [f32; 3]) -> (Vec3, Vec3) {
        let [v0, v1, v2] = self.vertices;
        (b[0] * v0 + b[1] * v1 + b[2] * v2, barycentric_error(self.vertices, b))
    }

    /// The `(s, t)` of `q` (a point in the triangle's plane): `q = v0 + s (v1 - v0) + t (v2 - v0)`.
    fn st_of(&self, q: Vec3) -> Vec2 {
        let [v0, v1, v2] = self.vertices;
        let (e1, e2, d) = (v1 - v0, v2 - v0, q - v0);
        let (d00, d01, d11) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
        let (d20, d21) = (d.dot(e1), d.dot(e2));
        let det = d00 * d11 - d01 * d01;
        if !(det > 0.0) {
            return Vec2::ZERO;
        }
        Vec2::new((d11 * d20 - d01 * d21) / det, (d00 * d21 - d01 * d20) / det)
    }
}

/// A sampled point on one emitter: where, its error bound, the radiance there and the area
/// density of picking it among the triangle's points (`1 / area` untextured).
struct PointSample {
    p: Vec3,
    err: Vec3,
    le: Vec3,
    /// Density per unit area within the triangle, times the area (1 untextured).
    density: f32,
}

/// All emissive triangles of a scene, sorted by `prim`.
#[derive(Clone, Debug, Default)]
pub struct AreaLights {
    triangles: Vec<EmitterTriangle>,
    distribution: Distribution1D,
    /// The textured emitters' pieces (see [`EmitterTriangle::is_textured`]).
    pieces: Vec<Pieces>,
    /// The emission textures the pieces read.
    maps: Vec<EmitterTexture>,
}

impl AreaLights {
    /// Collects every triangle whose material (`materials[tri_material[i]]`) emits and whose area
    /// is non-zero. Triangles without a valid material index are skipped.
    pub fn from_mesh(mesh: &TriangleMesh, tri_material: &[u32], materials: &[Material]) -> Self {
        Self::from_mesh_textured(mesh, tri_material, materials, None)
    }

    /// [`AreaLights::from_mesh`], the materials with an emission texture in `emission`
    /// emitting it (see the module's notes). A textured triangle whose emission is black
    /// everywhere the lookups see is no emitter (zero power).
    pub fn from_mesh_textured(
        mesh: &TriangleMesh,
        tri_material: &[u32],
        materials: &[Material],
        emission: Option<EmissionTextures<'_>>,
    ) -> Self {
        // One copy of each emission texture an emissive material the mesh uses has.
        let mut maps: Vec<EmitterTexture> = Vec::new();
        let mut map_of: Vec<Option<u32>> = vec![None; materials.len()];
        if let Some(e) = emission {
            let mut used = vec![false; materials.len()];
            for &m in tri_material {
                if let Some(u) = used.get_mut(m as usize) {
                    *u = true;
                }
            }
            for (id, m) in materials.iter().enumerate() {
                let Some(Some(map)) = e.maps.get(id) else { continue };
                if used[id] && m.emission().max_element() > 0.0 {
                    map_of[id] = Some(maps.len() as u32);
                    maps.push(EmitterTexture {
                        texture: e.textures.get(map.texture).clone(),
                        scale: map.scale,
                        offset: map.offset,
                        wrap: map.wrap,
                        factor: map.factor,
                    });
                }
            }
        }
        // The triangles in parallel (their pieces' lookups are the work), kept in mesh order.
        let built: Vec<(EmitterTriangle, Option<Pieces>)> = (0..mesh.len() as u32)
            .into_par_iter()
            .filter_map(|prim| {
                let id = *tri_material.get(prim as usize)? as usize;
                let ke = materials.get(id)?.emission();
                let normal = mesh.normal(prim)?;
                let area = mesh.area(prim);
                if !(ke.max_element() > 0.0 && area > 0.0) {
                    return None;
                }
                let vertices = mesh.triangle(prim);
                let (Some(e), Some(index)) = (emission, map_of[id]) else {
                    return Some((EmitterTriangle { prim, vertices, normal, area, ke, pieces: None }, None));
                };
                let tri = mesh.indices[prim as usize];
                let uvs = if e.uvs.is_empty() { [Vec2::ZERO; 3] } else { tri.map(|v| e.uvs[v as usize]) };
                let (p, mean) = Pieces::build(index, ke, uvs, &maps);
                if !(luminance(mean.max(Vec3::ZERO)) > 0.0) {
                    return None;
                }
                Some((EmitterTriangle { prim, vertices, normal, area, ke: mean, pieces: None }, Some(p)))
            })
            .collect();
        let mut pieces: Vec<Pieces> = Vec::new();
        let triangles: Vec<EmitterTriangle> = built
            .into_iter()
            .map(|(mut t, p)| {
                if let Some(p) = p {
                    t.pieces = Some(pieces.len() as u32);
                    pieces.push(p);
                }
                t
            })
            .collect();
        let weights: Vec<f32> = triangles.iter().map(|t| t.area * luminance(t.ke.max(Vec3::ZERO))).collect();
        AreaLights { distribution: Distribution1D::new(&weights), triangles, pieces, maps }
    }

    /// Emitted radiance of emitter `i` at its point `q` (constant untextured).
    pub fn radiance_at(&self, i: usize, q: Vec3) -> Vec3 {
        let tri = &self.triangles[i];
        match tri.pieces {
            None => tri.ke,
            Some(k) => {
                let st = tri.st_of(q);
                self.pieces[k as usize].radiance(&self.maps, [1.0 - st.x - st.y, st.x, st.y])
            }
        }
    }

    /// A point on emitter `i` from `u`: uniform by area, or for a textured emitter a piece by
    /// its power and a uniform point in it.
    #[inline]
    fn sample_point(&self, i: usize, u: [f32; 2]) -> Option<PointSample> {
        let tri = &self.triangles[i];
        match tri.pieces {
            None => {
                let (p, err) = tri.point_and_error(u);
                Some(PointSample { p, err, le: tri.ke, density: 1.0 })
            }
            Some(k) => {
                let pieces = &self.pieces[k as usize];
                let (slot, _, u0) = pieces.distribution.sample(u[0])?;
                let b = pieces.barycentrics(slot, sample_uniform_triangle([u0, u[1]]));
                let (p, err) = tri.point_at(b);
                Some(PointSample {
                    p,
                    err,
                    le: pieces.radiance(&self.maps, b),
                    density: pieces.density(slot),
                })
            }
        }
    }

    /// The area density (times the area) with which [`AreaLights::sample_point`] picks the
    /// point `q` of emitter `i`: 1 untextured, the density of `q`'s piece otherwise.
    #[inline]
    fn point_density(&self, i: usize, q: Vec3) -> f32 {
        let tri = &self.triangles[i];
        match tri.pieces {
            None => 1.0,
            Some(k) => {
                let pieces = &self.pieces[k as usize];
                pieces.density(pieces.slot(tri.st_of(q)))
            }
        }
    }

    /// The emitters, sorted by mesh triangle index.
    pub fn triangles(&self) -> &[EmitterTriangle] {
        &self.triangles
    }

    pub fn len(&self) -> usize {
        self.triangles.len()
    }

    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    /// Probability that light sampling picks emitter `i` (index into [`AreaLights::triangles`]).
    pub fn triangle_pmf(&self, i: usize) -> f32 {
        self.distribution.pmf(i)
    }

    /// Index into [`AreaLights::triangles`] of mesh triangle `prim`, if it emits.
    pub fn find(&self, prim: u32) -> Option<usize> {
        self.triangles.binary_search_by_key(&prim, |t| t.prim).ok()
    }

    /// Total flux `pi sum(ke A)`.
    pub fn power(&self) -> Vec3 {
        self.triangles.iter().map(EmitterTriangle::power).sum()
    }

    /// Samples a point on an emitter as seen from `p`: `li = ke`, `pdf` in solid angle, `dist`
    /// to the sampled point. `None` if `p` is behind (or in the plane of) that emitter's front.
    ///
    /// `end_error` is the distance along `wi` from the sampled point to the plane where pbrt-v4's
    /// `OffsetRayOrigin` would move it toward `p` (its error bound along the normal, over the
    /// cosine at the light): far from the origin the rounding of the point is larger than any
    /// fixed fraction of `dist`, and a shadow ray stopping only a fraction short would hit the
    /// emitter itself (the furnace moved by 1e5 lost 11 % of its direct light that way).
    #[inline]
    pub fn sample_li(&self, p: Vec3, u: [f32; 2]) -> Option<LightSample> {
        let (i, pmf, u0) = self.distribution.sample(u[0])?;
        let tri = &self.triangles[i];
        let PointSample { p: q, err, le, density } = self.sample_point(i, [u0, u[1]])?;
        let d = q - p;
        let dist2 = d.length_squared();
        let dist = dist2.sqrt();
        if dist <= 0.0 || !dist.is_finite() {
            return None;
        }
        let wi = d / dist;
        let cos_light = -tri.normal.dot(wi);
        if cos_light <= 0.0 {
            return None;
        }
        let pdf = (if tri.pieces.is_none() { pmf } else { pmf * density }) / tri.area * dist2 / cos_light;
        // Twice the offset: room for its final rounding by a float per coordinate.
        let end_error = 2.0 * offset_distance(q, err, tri.normal) / cos_light;
        (pdf.is_finite() && pdf > 0.0).then_some(LightSample {
            wi,
            dist,
            end_error,
            li: le,
            pdf,
            delta: false,
        })
    }

    /// Solid-angle density with which [`AreaLights::sample_li`] from `p` produces direction `wi`
    /// hitting mesh triangle `prim` at `hit_point` (for MIS when a BSDF-sampled ray hits an
    /// emitter). Zero for non-emitters and for hits on the back face.
    pub fn pdf_li(&self, p: Vec3, wi: Vec3, prim: u32, hit_point: Vec3) -> f32 {
        let Some(i) = self.find(prim) else { return 0.0 };
        let tri = &self.triangles[i];
        let cos_light = -tri.normal.dot(wi);
        if cos_light <= 0.0 {
            return 0.0;
        }
        let pmf = self.distribution.pmf(i);
        let pmf = if tri.pieces.is_none() { pmf } else { pmf * self.point_density(i, hit_point) };
        pmf / tri.area * (hit_point - p).length_squared() / cos_light
    }

    /// A photon from the whole collection: emitter by `area * luminance(ke)` (`u_pos[0]`,
    /// remapped), uniform point, cosine-distributed direction on the front side.
    pub fn sample_emission(&self, u_pos: [f32; 2], u_dir: [f32; 2]) -> Option<EmissionSample> {
        let (i, pmf, u0) = self.distribution.sample(u_pos[0])?;
        let mut e = self.sample_emission_on_triangle(i, [u0, u_pos[1]], u_dir)?;
        e.pdf_pos *= pmf;
        Some(e)
    }

    /// A photon from emitter `i` (index into [`AreaLights::triangles`]) alone, for a caller that
    /// stratifies over each emitter itself: `pdf_pos = 1 / area`, so the photon power
    /// `le cos / (pdf_pos pdf_dir)` is the triangle's flux `pi ke A` (for a textured emitter,
    /// `pdf_pos` is its piece's density and the power about that flux). `None` where a textured
    /// emitter is black.
    pub fn sample_emission_on_triangle(
        &self,
        i: usize,
        u_pos: [f32; 2],
        u_dir: [f32; 2],
    ) -> Option<EmissionSample> {
        let tri = self.triangles.get(i)?;
        let PointSample { p, err, le, density } = self.sample_point(i, u_pos)?;
        if tri.pieces.is_some() && le == Vec3::ZERO {
            return None;
        }
        let local = sample_cosine_hemisphere(u_dir);
        if local.z <= 0.0 {
            return None;
        }
        let dir = Frame::from_z(tri.normal).from_local(local).normalize();
        Some(EmissionSample {
            ray_origin: offset_ray_origin(p, err, tri.normal),
            dir,
            normal: Some(tri.normal),
            pdf_pos: if tri.pieces.is_none() { 1.0 / tri.area } else { density / tri.area },
            pdf_dir: cosine_hemisphere_pdf(local.z),
            le,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::sample_uniform_hemisphere;
    use rand::{Rng, SeedableRng};
    use rand_pcg::Pcg64;

    const KE: Vec3 = Vec3::new(17.0, 12.0, 4.0);

    /// A unit square at height `h` facing down (-z), light material 1; plus a white floor.
    fn scene(h: f32) -> (TriangleMesh, Vec<u32>, Vec<Material>) {
        let positions = vec![
            Vec3::new(0.0, 0.0, h),
            Vec3::new(0.0, 1.0, h),
            Vec3::new(1.0, 1.0, h),
            Vec3::new(1.0, 0.0, h),
            Vec3::new(-5.0, -5.0, -1.0),
            Vec3::new(5.0, -5.0, -1.0),
            Vec3::new(0.0, 5.0, -1.0),
            Vec3::new(2.0, 2.0, 2.0), // degenerate emitter
        ];
        let mesh = TriangleMesh { positions, indices: vec![[4, 5, 6], [0, 1, 2], [0, 2, 3], [7, 7, 7]] };
        let materials = vec![
            Material::Diffuse { kd: Vec3::splat(0.5) },
            Material::Emissive { kd: Vec3::splat(0.78), ke: KE },
        ];
        (mesh, vec![0, 1, 1, 1], materials)
    }

    /// Form factor from a differential area to a parallel rectangle `a x b` at distance `c`, with
    /// the element's normal through a corner (Howell's catalogue, B-3 form).
    fn corner_form_factor(a: f64, b: f64, c: f64) -> f64 {
        let (x, y) = (a / c, b / c);
        let (sx, sy) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
        (x / sx * (y / sx).atan() + y / sy * (x / sy).atan()) / (2.0 * std::f64::consts::PI)
    }

    fn irradiance_mc(lights: &AreaLights, p: Vec3, n: Vec3, samples: usize, seed: u64) -> Vec3 {
        let mut rng = Pcg64::seed_from_u64(seed);
        let mut sum = Vec3::ZERO;
        for _ in 0..samples {
            if let Some(s) = lights.sample_li(p, [rng.gen(), rng.gen()]) {
                assert!((lights.pdf_li(p, s.wi, lights.triangles()[0].prim, p + s.dist * s.wi) > 0.0));
                sum += s.li * n.dot(s.wi).max(0.0) / s.pdf;
            }
        }
        sum / samples as f32
    }

    #[test]
    fn collects_front_facing_emitters_with_their_power() {
        let (mesh, tm, mats) = scene(0.5);
        let l = AreaLights::from_mesh(&mesh, &tm, &mats);
        assert_eq!(l.len(), 2, "the floor and the degenerate triangle are skipped");
        assert_eq!(l.find(2), Some(1));
        assert_eq!(l.find(0), None);
        assert!((l.power() - PI * KE).abs().max_element() < 1e-4);
        assert!(l.triangles().iter().all(|t| t.normal == Vec3::NEG_Z));
        assert!(AreaLights::from_mesh(&mesh, &[0; 4], &mats).is_empty());
    }

    #[test]
    fn irradiance_matches_the_analytic_form_factor() {
        let h = 0.5;
        let (mesh, tm, mats) = scene(h);
        let l = AreaLights::from_mesh(&mesh, &tm, &mats);
        // Below the centre: four corner rectangles 0.5 x 0.5; below a corner: one 1 x 1.
        let cases = [
            (Vec3::new(0.5, 0.5, 0.0), 4.0 * corner_form_factor(0.5, 0.5, h as f64)),
            (Vec3::new(0.0, 0.0, 0.0), corner_form_factor(1.0, 1.0, h as f64)),
        ];
        for (k, (p, f)) in cases.into_iter().enumerate() {
            let e = irradiance_mc(&l, p, Vec3::Z, 200_000, k as u64);
            let expected = KE * (std::f64::consts::PI * f) as f32;
            let rel = ((e - expected) / expected).abs().max_element();
            assert!(rel < 0.02, "case {k}: {e} vs {expected}");
        }
    }

    #[test]
    fn nothing_reaches_points_behind_the_emitter_and_pdfs_agree() {
        let (mesh, tm, mats) = scene(0.5);
        let l = AreaLights::from_mesh(&mesh, &tm, &mats);
        let above = Vec3::new(0.5, 0.5, 1.0);
        assert!(l.sample_li(above, [0.3, 0.6]).is_none());
        let p = Vec3::new(0.2, 0.7, -0.3);
        let mut rng = Pcg64::seed_from_u64(5);
        for _ in 0..100 {
            let s = l.sample_li(p, [rng.gen(), rng.gen()]).unwrap();
            let hit = p + s.dist * s.wi;
            let prim = if (hit.x - hit.y) > 0.0 { 2 } else { 1 }; // which half of the quad
            let pdf = l.pdf_li(p, s.wi, prim, hit);
            assert!((pdf - s.pdf).abs() < 1e-3 * s.pdf, "{pdf} vs {}", s.pdf);
            assert_eq!(l.pdf_li(p, s.wi, 0, hit), 0.0, "not an emitter");
            assert_eq!(l.pdf_li(above, -s.wi, prim, hit), 0.0, "back face");
        }
    }

    #[test]
    fn power_equals_the_integral_of_emission() {
        let (mesh, tm, mats) = scene(0.5);
        let l = AreaLights::from_mesh(&mesh, &tm, &mats);
        // Independent estimate: uniform points by area, uniform hemisphere directions.
        let mut rng = Pcg64::seed_from_u64(3);
        let (n, total_area) = (200_000, 1.0f32);
        let mut sum = Vec3::ZERO;
        for _ in 0..n {
            let w = sample_uniform_hemisphere([rng.gen(), rng.gen()]);
            sum += KE * w.z * 2.0 * PI * total_area; // le cos / (pdf_dir pdf_pos)
        }
        let mc = sum / n as f32;
        assert!(((mc - l.power()) / l.power()).abs().max_element() < 0.01, "{mc} vs {}", l.power());
        // Photons: equal power, front side, cosine-distributed (E[cos] = 2/3).
        let mut mean_cos = 0.0;
        for _ in 0..n {
            let e = l.sample_emission([rng.gen(), rng.gen()], [rng.gen(), rng.gen()]).unwrap();
            assert!((e.photon_power() - l.power()).abs().max_element() < 1e-3 * l.power().max_element());
            assert!(e.ray_origin.z < 0.5, "offset to the front side");
            mean_cos += e.dir.dot(e.normal.unwrap()) / n as f32;
        }
        assert!((mean_cos - 2.0 / 3.0).abs() < 0.005);
        // Per-triangle emission carries that triangle's flux.
        let e = l.sample_emission_on_triangle(1, [0.2, 0.3], [0.4, 0.5]).unwrap();
        assert!((e.photon_power() - l.triangles()[1].power()).abs().max_element() < 1e-3);
    }

    #[test]
    fn emitters_are_picked_by_area_times_luminance() {
        let (mesh, tm, mut mats) = scene(0.5);
        mats.push(Material::Emissive { kd: Vec3::ZERO, ke: Vec3::new(0.0, 0.0, 10.0) });
        let tm = vec![tm[0], tm[1], 2, tm[3]];
        let l = AreaLights::from_mesh(&mesh, &tm, &mats);
        let (w0, w1) = (luminance(KE), luminance(Vec3::new(0.0, 0.0, 10.0)));
        assert!((l.triangle_pmf(0) - w0 / (w0 + w1)).abs() < 1e-6);
        let e = l.sample_emission([0.999, 0.5], [0.5, 0.5]).unwrap();
        assert!((luminance(e.photon_power()) - PI * 0.5 * (w0 + w1)).abs() < 1e-3, "equal luminance");
    }

    /// The test scene's emitter with `texture` (its uvs are the square's `x, y`).
    fn textured(texture: crate::texture::Texture) -> (AreaLights, Textures) {
        let (mesh, tm, mats) = scene(0.5);
        let mut textures = Textures::default();
        let t = textures.push(texture);
        let mut uvs = vec![Vec2::ZERO; mesh.positions.len()];
        for (uv, p) in uvs.iter_mut().zip(&mesh.positions).take(4) {
            *uv = p.truncate();
        }
        let map = EmissionMap {
            texture: t,
            scale: Vec2::ONE,
            offset: Vec2::ZERO,
            wrap: Wrap::Repeat,
            factor: Vec3::ONE,
        };
        let maps = [None, Some(map)];
        let e = EmissionTextures { uvs: &uvs, textures: &textures, maps: &maps };
        (AreaLights::from_mesh_textured(&mesh, &tm, &mats, Some(e)), textures)
    }

    /// 32 × 32: white where `u < 0.5`, black elsewhere, times a ramp in `v` (from 0.5 to 1.5).
    fn half_white() -> crate::texture::Texture {
        let texels = (0..32 * 32)
            .map(|i| {
                let (x, y) = (i % 32, i / 32);
                let ramp = 0.5 + (31 - y) as f32 / 31.0;
                glam::Vec4::new(1.0, 1.0, 1.0, 1.0) * if x < 16 { ramp } else { 0.0 }
            })
            .collect();
        crate::texture::Texture::from_linear(std::path::Path::new("half"), 32, 32, texels)
    }

    #[test]
    fn textured_density_integrates_to_one_and_sampling_agrees_with_it() {
        let (l, _) = textured(half_white());
        assert_eq!(l.len(), 2);
        assert!(l.triangles().iter().all(|t| t.is_textured()));
        let mut rng = Pcg64::seed_from_u64(11);
        // The density of every piece, integrated by uniform points over each triangle.
        let mut total = 0.0f64;
        for (i, tri) in l.triangles().iter().enumerate() {
            let n = 100_000;
            let mut sum = 0.0f64;
            for _ in 0..n {
                let (q, _) = tri.point_and_error([rng.gen(), rng.gen()]);
                sum += l.point_density(i, q) as f64;
            }
            let mean = sum / n as f64;
            assert!((mean - 1.0).abs() < 0.02, "triangle {i}: the piece densities average {mean}");
            total += l.triangle_pmf(i) as f64 * mean;
        }
        assert!((total - 1.0).abs() < 0.02, "{total}");
        // Power: the mean of the texture (half of it white, times a ramp averaging 1).
        assert!(
            (l.power() - 0.5 * PI * KE).abs().max_element() < 0.02 * PI * KE.max_element(),
            "{}",
            l.power()
        );
        // What sample_li returns is what pdf_li and radiance_at say at the point it picked.
        let p = Vec3::new(0.3, 0.6, -0.4);
        let mut dark = 0;
        for _ in 0..2000 {
            let Some(s) = l.sample_li(p, [rng.gen(), rng.gen()]) else { continue };
            let hit = p + s.dist * s.wi;
            let prim = if (hit.x - hit.y) > 0.0 { 2 } else { 1 };
            let pdf = l.pdf_li(p, s.wi, prim, hit);
            assert!((pdf - s.pdf).abs() < 1e-3 * s.pdf, "{pdf} vs {}", s.pdf);
            dark += (s.li == Vec3::ZERO) as u32;
            let i = l.find(prim).unwrap();
            assert!((l.radiance_at(i, hit) - s.li).abs().max_element() < 1e-3 * KE.max_element());
        }
        // Only the pieces across the edge of the white half (and the pieces' floor) give
        // points on the black half.
        assert!(dark <= 40, "{dark} of 2000 samples on the black half");
    }

    #[test]
    fn textured_irradiance_matches_uniform_area_sampling() {
        let (l, _) = textured(half_white());
        let mut rng = Pcg64::seed_from_u64(12);
        for p in [Vec3::new(0.25, 0.5, 0.0), Vec3::new(0.75, 0.5, 0.0), Vec3::new(0.5, 0.1, -0.5)] {
            let by_light = irradiance_mc(&l, p, Vec3::Z, 200_000, 13);
            // Independent: uniform points on the square, the radiance looked up there.
            let n = 400_000;
            let mut sum = Vec3::ZERO;
            for _ in 0..n {
                let q = Vec3::new(rng.gen(), rng.gen(), 0.5);
                let i = l.find(if (q.x - q.y) > 0.0 { 2 } else { 1 }).unwrap();
                let d = q - p;
                let g = d.z * d.z / d.length_squared().powi(2); // cos at both ends / d^2
                sum += l.radiance_at(i, q) * g;
            }
            let uniform = sum / n as f32;
            let rel = ((by_light - uniform) / uniform).abs().max_element();
            assert!(rel < 0.02, "at {p}: {by_light} by light sampling vs {uniform} uniformly");
        }
    }

    #[test]
    fn a_black_emission_texture_emits_nothing() {
        let black = crate::texture::Texture::from_linear(
            std::path::Path::new("black"),
            4,
            4,
            vec![glam::Vec4::W; 16],
        );
        let (l, _) = textured(black);
        assert!(l.is_empty() && l.power() == Vec3::ZERO);
        assert!(
            l.sample_li(Vec3::ZERO, [0.5, 0.5]).is_none() && l.sample_emission([0.5; 2], [0.5; 2]).is_none()
        );
    }

    #[test]
    fn textured_photons_carry_the_flux_on_average() {
        let (l, _) = textured(half_white());
        let mut rng = Pcg64::seed_from_u64(14);
        let n = 200_000;
        let (mut sum, mut black) = (Vec3::ZERO, 0);
        for _ in 0..n {
            match l.sample_emission([rng.gen(), rng.gen()], [rng.gen(), rng.gen()]) {
                Some(e) => sum += e.photon_power(),
                None => black += 1,
            }
        }
        assert!(black < n / 50, "{black} photons from the black half");
        let mean = sum / n as f32;
        assert!(((mean - l.power()) / l.power()).abs().max_element() < 0.01, "{mean} vs {}", l.power());
    }
}
