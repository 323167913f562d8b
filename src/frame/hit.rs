//! The surface point a ray reaches, and rays leaving it.

use crate::accel::Hit;
use crate::geometry::{gamma, offset_ray_origin};
use crate::material::{face_forward, Normals};
use crate::scene::{Scene, TextureRef};
use glam::{Vec2, Vec3};

/// A surface point reached by a ray.
#[derive(Clone, Copy, Debug)]
pub struct SurfaceHit {
    pub p: Vec3,
    /// Bound on the rounding error of `p`, for robust ray origins.
    pub err: Vec3,
    /// Unit geometric normal (front side as wound).
    pub n: Vec3,
    /// Unit shading normal, interpolated from the vertex normals, on the side of `n`; `n`
    /// itself where the triangle is flat-shaded.
    pub ns: Vec3,
    /// Texture coordinates (zero where the mesh has none).
    pub uv: Vec2,
    /// The vertex colour, which multiplies the material's base colour (white where the mesh
    /// has none).
    pub colour: Vec3,
    /// Where rays leaving on the shading normal's side start from: `p` lifted onto the smooth
    /// surface the vertex normals describe (Hanika, "Hacking the shadow terminator", Ray
    /// Tracing Gems II, 2021), or `p` itself on a flat triangle or where the lift would go
    /// below the face (a saddle or a concave spot).
    pub lifted: Vec3,
    pub prim: u32,
    pub t: f32,
}

/// The triangle's `dp/du` and `dp/dv` (position per unit of texture coordinate), or `None`
/// where its texture coordinates are degenerate.
fn uv_tangents(scene: &Scene, tri: [u32; 3]) -> Option<(Vec3, Vec3)> {
    let [p0, p1, p2] = tri.map(|i| scene.mesh.positions[i as usize]);
    let [t0, t1, t2] = tri.map(|i| scene.attributes.uvs[i as usize]);
    let (dp1, dp2, d1, d2) = (p1 - p0, p2 - p0, t1 - t0, t2 - t0);
    let det = d1.x * d2.y - d2.x * d1.y;
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    Some(((dp1 * d2.y - dp2 * d1.y) / det, (dp2 * d1.x - dp1 * d2.x) / det))
}

/// The shading normal `ns` bent by a tangent-space normal map at `uv`: the map's `2 c - 1`
/// (times `factor`: glTF's `scale` for x and y, 1 otherwise)
/// in the frame of the triangle's `dp/du` (made perpendicular to `ns`), `dp/dv` and `ns`.
/// `None` where the triangle's texture coordinates are degenerate or the result would face
/// away from the face.
fn normal_mapped(
    scene: &Scene,
    tri: [u32; 3],
    n: Vec3,
    ns: Vec3,
    uv: Vec2,
    map: &TextureRef,
) -> Option<Vec3> {
    let (dpdu, dpdv) = uv_tangents(scene, tri)?;
    let t = (dpdu - ns * ns.dot(dpdu)).try_normalize()?;
    // The bitangent keeps the handedness of the texture's (v up) frame.
    let b = ns.cross(t) * if ns.cross(t).dot(dpdv) < 0.0 { -1.0 } else { 1.0 };
    let texel = scene.textures.get(map.texture).sample(uv * map.scale + map.offset, map.wrap).truncate();
    let c = (texel * 2.0 - Vec3::ONE) * map.factor;
    let bent = (t * c.x + b * c.y + ns * c.z).try_normalize()?;
    (bent.dot(n) > 0.0).then_some(bent)
}

/// The shading normal `ns` bent by a height map at `uv` (pbrt's `BumpMap`, Mitsuba's
/// `bumpmap`): the surface displaced by `h` along `ns` has tangents `dp/du + (dh/du) ns` and
/// `dp/dv + (dh/dv) ns` (both made perpendicular to `ns` first; the change of `ns` itself
/// across the triangle is left out, as Mitsuba does), and its normal is their cross product,
/// on `ns`'s side. `dh/du` is the exact slope of the bilinear filter. Where the slope is zero
/// (a flat height map) the normal is `ns` exactly; `None` where the texture coordinates are
/// degenerate or the result would face away from the face.
fn bumped(scene: &Scene, tri: [u32; 3], n: Vec3, ns: Vec3, uv: Vec2, map: &TextureRef) -> Option<Vec3> {
    let texture = scene.textures.get(map.texture);
    let (du, dv) = texture.gradient(uv * map.scale + map.offset, map.wrap);
    let (hu, hv) = (du.x * map.scale.x * map.factor.x, dv.x * map.scale.y * map.factor.x);
    if hu == 0.0 && hv == 0.0 {
        return Some(ns);
    }
    let (dpdu, dpdv) = uv_tangents(scene, tri)?;
    let su = dpdu - ns * ns.dot(dpdu) + ns * hu;
    let sv = dpdv - ns * ns.dot(dpdv) + ns * hv;
    let m = su.cross(sv).try_normalize()?;
    let bent = if m.dot(ns) < 0.0 { -m } else { m };
    (bent.dot(n) > 0.0).then_some(bent)
}

impl SurfaceHit {
    /// The surface point of a backend's hit on `scene`'s mesh (`None` on a degenerate
    /// triangle, which every backend treats as a miss).
    #[inline]
    pub fn new(scene: &Scene, hit: Hit) -> Option<SurfaceHit> {
        let (n, p, err) = scene.mesh.surface_point(hit.prim, hit.u, hit.v)?;
        let mut at = SurfaceHit {
            p,
            err,
            n,
            ns: n,
            uv: Vec2::ZERO,
            colour: Vec3::ONE,
            lifted: p,
            prim: hit.prim,
            t: hit.t,
        };
        let a = &scene.attributes;
        if a.has_normals() || a.has_uvs() || a.has_colours() {
            let tri = scene.mesh.indices[hit.prim as usize];
            let s = a.at(tri, hit.u, hit.v);
            (at.uv, at.colour) = (s.uv, s.colour);
            // A shading normal behind the surface (vertex normals bent past the face) is no
            // use: that point is shaded flat.
            if let Some(ns) = s.normal.filter(|ns| ns.dot(n) > 0.0) {
                at.ns = ns;
                let w = [1.0 - hit.u - hit.v, hit.u, hit.v];
                let lifted: Vec3 = (0..3)
                    .map(|k| {
                        let (v, vn) = (scene.mesh.positions[tri[k] as usize], a.normals[tri[k] as usize]);
                        w[k] * (p - (p - v).dot(vn) * vn)
                    })
                    .sum();
                if (lifted - p).dot(n) > 0.0 && lifted.is_finite() {
                    at.lifted = lifted;
                }
            }
            if scene.textured && a.has_uvs() {
                let maps = &scene.maps[scene.tri_material[hit.prim as usize] as usize];
                if let Some(map) = maps.normal {
                    at.ns = normal_mapped(scene, tri, n, at.ns, at.uv, &map).unwrap_or(at.ns);
                } else if let Some(map) = maps.bump {
                    at.ns = bumped(scene, tri, n, at.ns, at.uv, &map).unwrap_or(at.ns);
                }
            }
        }
        Some(at)
    }

    /// A point on a flat surface (no shading normal, no texture coordinates).
    #[inline]
    pub fn flat(p: Vec3, err: Vec3, n: Vec3) -> SurfaceHit {
        SurfaceHit { p, err, n, ns: n, uv: Vec2::ZERO, colour: Vec3::ONE, lifted: p, prim: 0, t: 0.0 }
    }

    /// The geometric and shading normals, for the BSDF.
    #[inline]
    pub fn normals(&self) -> Normals {
        Normals::new(self.n, self.ns, self.lifted != self.p)
    }

    /// A robust origin for a ray leaving this point toward `w`: from the lifted point when `w`
    /// leaves on the shading normal's side (so a light the smooth surface faces is not hidden
    /// by the facet's own neighbours), else from `p`; offset off the face on `w`'s side.
    #[inline]
    pub fn spawn(&self, w: Vec3) -> Vec3 {
        let side = face_forward(self.n, w);
        if self.lifted != self.p && self.ns.dot(w) > 0.0 {
            // The lift's own rounding: a few ulps of the point and of the move.
            let err = self.err + gamma(8) * (self.lifted.abs() + (self.lifted - self.p).abs());
            return offset_ray_origin(self.lifted, err, side);
        }
        offset_ray_origin(self.p, self.err, side)
    }
}
