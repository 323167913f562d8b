//! What shading reads beside the triangles: per-vertex normals, texture coordinates and
//! colours, kept apart from [`TriangleMesh`](super::TriangleMesh) so the accelerators see
//! positions only.

use glam::{Vec2, Vec3};

/// Per-vertex shading attributes of a mesh, indexed like its `positions`. Each list is either
/// empty (no vertex has one) or one entry per vertex. A zero normal marks a vertex without
/// one: a triangle is smooth-shaded only when all three of its vertices have a normal.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct VertexAttributes {
    /// Unit shading normals (zero: none).
    pub normals: Vec<Vec3>,
    /// Texture coordinates `(u, v)`, `v` up as in OBJ and glTF's flipped convention.
    pub uvs: Vec<Vec2>,
    /// Linear RGB colours that multiply the material's base colour (glTF's `COLOR_0`, an OBJ
    /// `v x y z r g b`); white where a mesh has none and another has.
    pub colours: Vec<Vec3>,
}

/// The shading attributes at a point of a triangle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadingPoint {
    /// The interpolated unit normal, `None` for a flat-shaded triangle (or one whose vertex
    /// normals cancel at the point).
    pub normal: Option<Vec3>,
    /// The interpolated texture coordinates (zero without any).
    pub uv: Vec2,
    /// The interpolated vertex colour (white without any).
    pub colour: Vec3,
}

impl VertexAttributes {
    /// Appends the attributes of `other`, which belong to `other_vertices` vertices appended
    /// after `self_vertices` ones; a list only one side has is padded with zeros.
    pub fn append(&mut self, self_vertices: usize, other: &VertexAttributes, other_vertices: usize) {
        fn join<T: Copy>(a: &mut Vec<T>, a_len: usize, b: &[T], b_len: usize, pad: T) {
            if a.is_empty() && b.is_empty() {
                return;
            }
            a.resize(a_len, pad);
            if b.is_empty() {
                a.resize(a_len + b_len, pad);
            } else {
                a.extend_from_slice(b);
            }
        }
        join(&mut self.normals, self_vertices, &other.normals, other_vertices, Vec3::ZERO);
        join(&mut self.uvs, self_vertices, &other.uvs, other_vertices, Vec2::ZERO);
        join(&mut self.colours, self_vertices, &other.colours, other_vertices, Vec3::ONE);
    }

    /// Whether any vertex has a normal.
    pub fn has_normals(&self) -> bool {
        !self.normals.is_empty()
    }

    /// Whether any vertex has texture coordinates.
    pub fn has_uvs(&self) -> bool {
        !self.uvs.is_empty()
    }

    /// Whether any vertex has a colour.
    pub fn has_colours(&self) -> bool {
        !self.colours.is_empty()
    }

    /// The attributes of triangle `tri` (vertex indices) at barycentrics `(u, v)` (Embree's
    /// convention: weight `1 - u - v` on the first vertex).
    #[inline]
    pub fn at(&self, tri: [u32; 3], u: f32, v: f32) -> ShadingPoint {
        let w = [1.0 - u - v, u, v];
        let normal = if self.normals.is_empty() {
            None
        } else {
            let n = tri.map(|i| self.normals[i as usize]);
            if n.contains(&Vec3::ZERO) {
                None
            } else {
                (w[0] * n[0] + w[1] * n[1] + w[2] * n[2]).try_normalize()
            }
        };
        let uv = if self.uvs.is_empty() {
            Vec2::ZERO
        } else {
            let t = tri.map(|i| self.uvs[i as usize]);
            w[0] * t[0] + w[1] * t[1] + w[2] * t[2]
        };
        let colour = if self.colours.is_empty() {
            Vec3::ONE
        } else {
            let c = tri.map(|i| self.colours[i as usize]);
            w[0] * c[0] + w[1] * c[1] + w[2] * c[2]
        };
        ShadingPoint { normal, uv, colour }
    }

    /// Checks the lists' lengths against `vertices` and that every value is finite.
    pub fn validate(&self, vertices: usize) -> Result<(), String> {
        let lists = [
            ("normals", self.normals.len()),
            ("texture coordinates", self.uvs.len()),
            ("colours", self.colours.len()),
        ];
        for (name, len) in lists {
            if len != 0 && len != vertices {
                return Err(format!("{len} vertex {name} for {vertices} vertices"));
            }
        }
        if let Some(i) = self.normals.iter().position(|n| !n.is_finite()) {
            return Err(format!("vertex {i} has a non-finite normal"));
        }
        if let Some(i) = self.uvs.iter().position(|t| !t.is_finite()) {
            return Err(format!("vertex {i} has non-finite texture coordinates"));
        }
        if let Some(i) = self.colours.iter().position(|c| !(c.is_finite() && c.min_element() >= 0.0)) {
            return Err(format!("vertex {i} has a colour that is negative or not finite"));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn append_pads_the_side_without_a_list() {
        let mut a = VertexAttributes::default();
        let b = VertexAttributes { normals: vec![Vec3::Z; 2], uvs: vec![], colours: vec![Vec3::X; 2] };
        a.append(3, &b, 2);
        assert_eq!(a.normals, vec![Vec3::ZERO, Vec3::ZERO, Vec3::ZERO, Vec3::Z, Vec3::Z]);
        assert!(a.uvs.is_empty());
        // A mesh without colours is white beside one with.
        assert_eq!(a.colours, vec![Vec3::ONE, Vec3::ONE, Vec3::ONE, Vec3::X, Vec3::X]);
        a.append(5, &VertexAttributes::default(), 1);
        assert_eq!(a.normals.len(), 6);
        assert!(a.validate(6).is_ok());
        assert!(a.validate(7).is_err());
    }

    #[test]
    fn interpolation_and_flat_triangles() {
        let attrs = VertexAttributes {
            normals: vec![Vec3::X, Vec3::Y, Vec3::Z, Vec3::ZERO],
            uvs: vec![Vec2::ZERO, Vec2::X, Vec2::Y, Vec2::ONE],
            colours: vec![Vec3::ONE, Vec3::ZERO, Vec3::X, Vec3::Y],
        };
        let p = attrs.at([0, 1, 2], 0.5, 0.0);
        assert!((p.normal.unwrap() - Vec3::new(1.0, 1.0, 0.0).normalize()).length() < 1e-6);
        assert_eq!(p.uv, Vec2::new(0.5, 0.0));
        assert_eq!(p.colour, Vec3::splat(0.5));
        // A vertex without a normal makes the triangle flat.
        assert_eq!(attrs.at([0, 1, 3], 0.2, 0.2).normal, None);
        // Normals that cancel give none either.
        let opposite = VertexAttributes { normals: vec![Vec3::X, -Vec3::X, Vec3::X], ..Default::default() };
        assert_eq!(opposite.at([0, 1, 2], 0.5, 0.0).normal, None);
    }
}
