//! The triangle soup every accelerator is built from.

use super::Aabb;
use glam::Vec3;

/// Triangles over a shared vertex buffer. Winding is counter-clockwise seen from the front:
/// the geometric normal is `normalize((v1 - v0) x (v2 - v0))`.
#[derive(Clone, Debug, Default)]
pub struct TriangleMesh {
    pub positions: Vec<Vec3>,
    pub indices: Vec<[u32; 3]>,
}

/// Why a mesh cannot be used for ray casting.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum MeshError {
    #[error("vertex {index} has a non-finite coordinate {value:?}")]
    NonFiniteVertex { index: usize, value: [f32; 3] },
    #[error("triangle {triangle} uses vertex {vertex}, but there are only {count} vertices")]
    IndexOutOfRange { triangle: usize, vertex: u32, count: usize },
    #[error("{0} triangles is more than the 2^32 - 1 a mesh may hold")]
    TooManyTriangles(usize),
}

/// The unit normal `(v1 - v0) x (v2 - v0)` normalised, or `None` for a degenerate triangle
/// (zero or non-finite area).
#[inline(always)]
fn unit_normal([a, b, c]: [Vec3; 3]) -> Option<Vec3> {
    let n = (b - a).cross(c - a);
    let len = n.length();
    (len > 0.0 && len.is_finite()).then(|| n / len)
}

impl TriangleMesh {
    /// Checks that every coordinate is finite and every index is in range.
    pub fn validate(&self) -> Result<(), MeshError> {
        if self.indices.len() >= u32::MAX as usize || self.positions.len() >= u32::MAX as usize {
            return Err(MeshError::TooManyTriangles(self.indices.len()));
        }
        if let Some((index, p)) = self.positions.iter().enumerate().find(|(_, p)| !p.is_finite()) {
            return Err(MeshError::NonFiniteVertex { index, value: p.to_array() });
        }
        let count = self.positions.len();
        for (triangle, tri) in self.indices.iter().enumerate() {
            if let Some(&vertex) = tri.iter().find(|&&v| v as usize >= count) {
                return Err(MeshError::IndexOutOfRange { triangle, vertex, count });
            }
        }
        Ok(())
    }

    pub fn len(&self) -> usize {
        self.indices.len()
    }

    pub fn is_empty(&self) -> bool {
        self.indices.is_empty()
    }

    /// The three corners of triangle `i`.
    #[inline]
    pub fn triangle(&self, i: u32) -> [Vec3; 3] {
        let [a, b, c] = self.indices[i as usize];
        [self.positions[a as usize], self.positions[b as usize], self.positions[c as usize]]
    }

    /// Unnormalised geometric normal `(v1 - v0) x (v2 - v0)`; its length is twice the area.
    #[inline]
    pub fn normal_unnormalized(&self, i: u32) -> Vec3 {
        let [a, b, c] = self.triangle(i);
        (b - a).cross(c - a)
    }

    /// Unit geometric normal, or `None` for a degenerate triangle (zero or non-finite area).
    #[inline]
    pub fn normal(&self, i: u32) -> Option<Vec3> {
        unit_normal(self.triangle(i))
    }

    /// [`TriangleMesh::normal`] and [`TriangleMesh::point_and_error`] of one hit, from one
    /// fetch of the corners (the same floats).
    #[inline(always)]
    pub fn surface_point(&self, i: u32, u: f32, v: f32) -> Option<(Vec3, Vec3, Vec3)> {
        let t = self.triangle(i);
        let n = unit_normal(t)?;
        let b = [1.0 - u - v, u, v];
        Some((n, b[0] * t[0] + b[1] * t[1] + b[2] * t[2], super::barycentric_error(t, b)))
    }

    pub fn area(&self, i: u32) -> f32 {
        0.5 * self.normal_unnormalized(i).length()
    }

    /// Point at barycentrics `(u, v)`: `(1 - u - v) v0 + u v1 + v v2` (Embree's convention).
    #[inline]
    pub fn point(&self, i: u32, u: f32, v: f32) -> Vec3 {
        let [a, b, c] = self.triangle(i);
        (1.0 - u - v) * a + u * b + v * c
    }

    /// Point at barycentrics `(u, v)` and a conservative bound on its rounding error.
    #[inline]
    pub fn point_and_error(&self, i: u32, u: f32, v: f32) -> (Vec3, Vec3) {
        let t = self.triangle(i);
        let b = [1.0 - u - v, u, v];
        (b[0] * t[0] + b[1] * t[1] + b[2] * t[2], super::barycentric_error(t, b))
    }

    pub fn bounds(&self) -> Aabb {
        self.indices.iter().flatten().fold(Aabb::EMPTY, |b, &v| b.grow(self.positions[v as usize]))
    }

    /// A closed sphere-like surface for tests and benchmarks: `rings` latitude bands and
    /// `segments` longitudes, single-vertex poles on ±Z, outward winding, vertex positions from
    /// `point(theta, phi)` (polar angle from +Z, azimuth); `2 segments (rings - 1)` triangles.
    pub fn parametric_sphere(rings: u32, segments: u32, point: impl Fn(f32, f32) -> Vec3) -> Self {
        assert!(rings >= 2 && segments >= 3, "a sphere needs at least 2 rings and 3 segments");
        let mut positions = vec![point(0.0, 0.0)];
        for i in 1..rings {
            let theta = std::f32::consts::PI * i as f32 / rings as f32;
            for j in 0..segments {
                positions.push(point(theta, std::f32::consts::TAU * j as f32 / segments as f32));
            }
        }
        let south = positions.len() as u32;
        positions.push(point(std::f32::consts::PI, 0.0));
        let ring = |i: u32, j: u32| 1 + (i - 1) * segments + j % segments;
        let mut indices = Vec::with_capacity(2 * (rings * segments) as usize);
        for j in 0..segments {
            indices.push([0, ring(1, j), ring(1, j + 1)]);
            indices.push([south, ring(rings - 1, j + 1), ring(rings - 1, j)]);
        }
        for i in 1..rings - 1 {
            for j in 0..segments {
                let (a, b, c, d) = (ring(i, j), ring(i, j + 1), ring(i + 1, j), ring(i + 1, j + 1));
                indices.push([a, c, d]);
                indices.push([a, d, b]);
            }
        }
        TriangleMesh { positions, indices }
    }

    /// Appends another mesh, offsetting its indices.
    pub fn append(&mut self, other: &TriangleMesh) {
        let base = self.positions.len() as u32;
        self.positions.extend_from_slice(&other.positions);
        self.indices.extend(other.indices.iter().map(|t| t.map(|v| v + base)));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quad() -> TriangleMesh {
        TriangleMesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y],
            indices: vec![[0, 1, 2], [0, 2, 3]],
        }
    }

    #[test]
    fn normals_area_and_points() {
        let m = quad();
        assert_eq!(m.normal(0), Some(Vec3::Z));
        assert_eq!(m.area(0) + m.area(1), 1.0);
        assert_eq!(m.point(0, 1.0, 0.0), Vec3::X);
        assert_eq!(m.bounds().max, Vec3::new(1.0, 1.0, 0.0));
        let degenerate =
            TriangleMesh { positions: vec![Vec3::ZERO, Vec3::X, Vec3::X * 2.0], indices: vec![[0, 1, 2]] };
        assert_eq!(degenerate.normal(0), None);
    }

    #[test]
    fn validate_rejects_bad_indices_and_nan() {
        let mut m = quad();
        assert!(m.validate().is_ok());
        m.indices.push([0, 1, 7]);
        assert_eq!(m.validate(), Err(MeshError::IndexOutOfRange { triangle: 2, vertex: 7, count: 4 }));
        let mut m = quad();
        m.positions[1].y = f32::NAN;
        assert!(matches!(m.validate(), Err(MeshError::NonFiniteVertex { index: 1, .. })));
    }

    #[test]
    fn append_offsets_indices() {
        let mut m = quad();
        m.append(&quad());
        assert_eq!(m.indices[3], [4, 6, 7]);
        assert!(m.validate().is_ok());
    }
}
