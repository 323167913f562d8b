//! Placing a mesh in the scene: the `[[mesh]]` entry's transform, applied to its positions and
//! (by the inverse transpose) its shading normals.
//!
//! An entry gives either `scale`, `rotate` and `translate`, applied in that order (scale, then
//! each rotation in the order listed, then translate: `p' = T R_n ... R_1 S p`, as Mitsuba's
//! `<transform>` applies its children in order), or one affine `matrix` (row-major, acting on
//! column vectors: `p' = M [p, 1]`), not both. A transform whose linear part has a negative
//! determinant mirrors the mesh, and the winding of every triangle is reversed so that front
//! faces stay counter-clockwise (the geometric normal keeps the side the inverse-transposed
//! shading normals keep).
//!
//! An entry with only `scale` and `translate` is applied in `f32` as `p * scale + translate`,
//! bit for bit as before rotations and matrices existed; any other transform is composed and
//! applied in `f64` and rounded once per coordinate.

use super::file::{self, finite3, Rotate, Rotation, Scale};
use super::SceneError;
use crate::geometry::{TriangleMesh, VertexAttributes};
use glam::{DMat3, DVec3, Vec3};
use std::path::Path;

/// A matrix whose linear part has `|det| <= SINGULAR * |c0| |c1| |c2|` (its columns' lengths:
/// the bound of Hadamard's inequality, so the ratio is the volume a unit cube keeps, relative
/// to its scale) is refused as singular: it would flatten the mesh.
const SINGULAR: f64 = 1e-6;

/// Applies mesh entry `i`'s transform to `mesh` and its `attributes`; a mirroring transform
/// also reverses the winding, so front faces stay counter-clockwise.
pub fn apply(
    path: &Path,
    i: usize,
    entry: &file::MeshEntry,
    mesh: &mut TriangleMesh,
    attributes: &mut VertexAttributes,
) -> Result<(), SceneError> {
    let mirrored = match (&entry.matrix, &entry.rotate) {
        (Some(m), _) => {
            if entry.scale.is_some() || entry.rotate.is_some() || entry.translate.is_some() {
                return Err(SceneError::field(
                    path,
                    format!("mesh[{i}].matrix"),
                    "given with scale, rotate or translate: a mesh has a matrix or those, not both",
                ));
            }
            let (linear, translate) = matrix(path, &format!("mesh[{i}].matrix"), m)?;
            affine(mesh, attributes, linear, translate)
        }
        (None, Some(rotate)) => {
            let scale = scale(path, i, entry.scale)?;
            let mut linear = DMat3::from_diagonal(scale.as_dvec3());
            linear = rotation_of(path, &format!("mesh[{i}].rotate"), rotate)? * linear;
            let translate =
                finite3(path, &format!("mesh[{i}].translate"), entry.translate.unwrap_or([0.0; 3]))?;
            affine(mesh, attributes, linear, translate.as_dvec3())
        }
        (None, None) => {
            let scale = scale(path, i, entry.scale)?;
            let translate =
                finite3(path, &format!("mesh[{i}].translate"), entry.translate.unwrap_or([0.0; 3]))?;
            for p in &mut mesh.positions {
                *p = *p * scale + translate;
            }
            // Normals go by the inverse transpose: a per-axis scale divides them.
            for n in &mut attributes.normals {
                *n = (*n / scale).try_normalize().unwrap_or(Vec3::ZERO);
            }
            scale.x * scale.y * scale.z < 0.0
        }
    };
    if mirrored {
        // A mirroring transform flips the winding; restore counter-clockwise front faces.
        for t in &mut mesh.indices {
            t.swap(1, 2);
        }
    }
    Ok(())
}

/// The entry's `scale` (1 if absent), finite and non-zero on every axis.
fn scale(path: &Path, i: usize, scale: Option<Scale>) -> Result<Vec3, SceneError> {
    let scale = match scale {
        None => Vec3::ONE,
        Some(Scale::Uniform(s)) => Vec3::splat(s),
        Some(Scale::PerAxis(s)) => Vec3::from(s),
    };
    if !scale.is_finite() || scale.cmpeq(Vec3::ZERO).any() {
        return Err(SceneError::field(path, format!("mesh[{i}].scale"), "must be finite and non-zero"));
    }
    Ok(scale)
}

/// The matrix of `rotate` (field `field`, e.g. `mesh[i].rotate`): its rotations composed in
/// the order they are listed, each checked under its own name (`field` or `field[k]`).
pub fn rotation_of(path: &Path, field: &str, rotate: &Rotate) -> Result<DMat3, SceneError> {
    match rotate {
        Rotate::One(r) => rotation(path, field, r),
        Rotate::Many(list) => list
            .iter()
            .enumerate()
            .try_fold(DMat3::IDENTITY, |m, (k, r)| Ok(rotation(path, &format!("{field}[{k}]"), r)? * m)),
    }
}

/// The matrix of one rotation: right-handed about the unit `axis` (any non-zero length).
fn rotation(path: &Path, field: &str, r: &Rotation) -> Result<DMat3, SceneError> {
    let axis = finite3(path, &format!("{field}.axis"), r.axis)?.as_dvec3();
    let axis = axis.try_normalize().ok_or_else(|| {
        SceneError::field(path, format!("{field}.axis"), "is zero: a rotation needs an axis")
    })?;
    if !r.degrees.is_finite() {
        return Err(SceneError::field(
            path,
            format!("{field}.degrees"),
            format!("{} is not finite", r.degrees),
        ));
    }
    Ok(DMat3::from_axis_angle(axis, f64::from(r.degrees).to_radians()))
}

/// The linear part and translation of a `matrix` of 12 or 16 numbers, row-major; refused when
/// a number is not finite, the last row of a 4x4 is not `[0, 0, 0, 1]` (projective), or the
/// linear part is singular.
fn matrix(path: &Path, field: &str, m: &[f32]) -> Result<(DMat3, DVec3), SceneError> {
    let refuse = |message: String| Err(SceneError::field(path, field, message));
    if m.len() != 12 && m.len() != 16 {
        return refuse(format!("has {} numbers: give 12 (3x4) or 16 (4x4), row-major", m.len()));
    }
    if let Some(k) = m.iter().position(|x| !x.is_finite()) {
        return refuse(format!("entry {k} (row {}, column {}) is {}: not finite", k / 4, k % 4, m[k]));
    }
    if m.len() == 16 && m[12..] != [0.0, 0.0, 0.0, 1.0] {
        return refuse(format!(
            "last row {:?} is not [0, 0, 0, 1]: only affine transforms are allowed",
            &m[12..]
        ));
    }
    let at = |row: usize, col: usize| f64::from(m[4 * row + col]);
    let column = |c: usize| DVec3::new(at(0, c), at(1, c), at(2, c));
    let linear = DMat3::from_cols(column(0), column(1), column(2));
    let det = linear.determinant();
    let volume = column(0).length() * column(1).length() * column(2).length();
    if !(det.abs() > SINGULAR * volume) {
        return refuse(format!(
            "is singular (determinant {det:.3e} against {volume:.3e} for the lengths of its columns): \
             it would flatten the mesh"
        ));
    }
    Ok((linear, column(3)))
}

/// Applies `p' = linear p + translate` to the positions and the inverse transpose of `linear`
/// to the normals (renormalised; a zero normal stays zero), in place; whether `linear`
/// mirrors (negative determinant).
fn affine(
    mesh: &mut TriangleMesh,
    attributes: &mut VertexAttributes,
    linear: DMat3,
    translate: DVec3,
) -> bool {
    for p in &mut mesh.positions {
        *p = (linear * p.as_dvec3() + translate).as_vec3();
    }
    let normal = linear.inverse().transpose();
    for n in &mut attributes.normals {
        *n = (normal * n.as_dvec3()).try_normalize().map_or(Vec3::ZERO, |n| n.as_vec3());
    }
    linear.determinant() < 0.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::file::MeshEntry;
    use std::path::PathBuf;

    fn entry(toml: &str) -> MeshEntry {
        toml::from_str(&format!("obj = \"m.obj\"\n{toml}")).unwrap()
    }

    /// One triangle (0, 1, 2) at the given positions, every vertex with `normal`.
    fn triangle(p: [Vec3; 3], normal: Vec3) -> (TriangleMesh, VertexAttributes) {
        let mesh = TriangleMesh { positions: p.to_vec(), indices: vec![[0, 1, 2]] };
        (mesh, VertexAttributes { normals: vec![normal; 3], ..Default::default() })
    }

    fn placed(toml: &str, p: [Vec3; 3], normal: Vec3) -> Result<(TriangleMesh, VertexAttributes), String> {
        let (mut mesh, mut attributes) = triangle(p, normal);
        apply(&PathBuf::from("s.toml"), 0, &entry(toml), &mut mesh, &mut attributes)
            .map_err(|e| e.to_string())?;
        Ok((mesh, attributes))
    }

    fn close(a: Vec3, b: Vec3) -> bool {
        (a - b).length() < 1e-6
    }

    const XYZ: [Vec3; 3] = [Vec3::X, Vec3::Y, Vec3::Z];

    #[test]
    fn a_rotation_turns_a_known_point_by_the_right_hand_rule() {
        // 90 degrees about +Y takes +X to -Z and +Z to +X; about +Z, +X goes to +Y.
        let (m, _) = placed("rotate = { axis = [0, 2, 0], degrees = 90 }", XYZ, Vec3::Z).unwrap();
        assert!(close(m.positions[0], -Vec3::Z), "{:?}", m.positions);
        assert!(close(m.positions[1], Vec3::Y));
        assert!(close(m.positions[2], Vec3::X));
        let (m, _) = placed("rotate = { axis = [0, 0, 1], degrees = 90 }", XYZ, Vec3::Z).unwrap();
        assert!(close(m.positions[0], Vec3::Y));
        // 120 degrees about (1, 1, 1) cycles the axes.
        let (m, _) = placed("rotate = { axis = [1, 1, 1], degrees = 120 }", XYZ, Vec3::Z).unwrap();
        assert!(close(m.positions[0], Vec3::Y) && close(m.positions[1], Vec3::Z), "{:?}", m.positions);
        assert_eq!(m.indices, vec![[0, 1, 2]], "a rotation keeps the winding");
    }

    #[test]
    fn scale_then_rotations_in_order_then_translate() {
        let toml = "scale = [2, 1, 1]\ntranslate = [0, 0, 10]\nrotate = [\n  { axis = [0, 0, 1], degrees = 90 },\n  { axis = [1, 0, 0], degrees = 90 },\n]";
        let (m, _) = placed(toml, XYZ, Vec3::Z).unwrap();
        // +X: scaled to (2, 0, 0), about +Z to (0, 2, 0), about +X to (0, 0, 2), moved to z = 12.
        assert!(close(m.positions[0], Vec3::new(0.0, 0.0, 12.0)), "{:?}", m.positions);
        // The same as one matrix T R2 R1 S.
        let matrix = "matrix = [0, -1, 0, 0,  0, 0, -1, 0,  2, 0, 0, 10]";
        let (n, _) = placed(matrix, XYZ, Vec3::Z).unwrap();
        for (a, b) in m.positions.iter().zip(&n.positions) {
            assert!(close(*a, *b), "{a} vs {b}");
        }
        // The other order of the rotations lands elsewhere: about +X first keeps +X, about +Z
        // then takes (2, 0, 0) to (0, 2, 0).
        let swapped = toml.replace(
            "[0, 0, 1], degrees = 90 },\n  { axis = [1, 0, 0]",
            "[1, 0, 0], degrees = 90 },\n  { axis = [0, 0, 1]",
        );
        let (s, _) = placed(&swapped, XYZ, Vec3::Z).unwrap();
        assert!(close(s.positions[0], Vec3::new(0.0, 2.0, 10.0)), "{:?}", s.positions);
        // A 4x4 with the affine last row is the 3x4.
        let (f, _) =
            placed("matrix = [0, -1, 0, 0,  0, 0, -1, 0,  2, 0, 0, 10,  0, 0, 0, 1]", XYZ, Vec3::Z).unwrap();
        assert_eq!(f.positions, n.positions);
    }

    #[test]
    fn normals_stay_perpendicular_to_tangents_under_non_uniform_scale_and_rotation() {
        // A slanted triangle with its true normal at every vertex, then a zero normal.
        let p = [Vec3::ZERO, Vec3::new(1.0, 0.3, 0.0), Vec3::new(0.2, 0.5, 1.0)];
        let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize();
        let toml = "scale = [3, 0.5, -1.5]\nrotate = [{ axis = [1, 2, 3], degrees = 37 }, { axis = [0, 1, 0], degrees = -80 }]\ntranslate = [1, 2, 3]";
        for matrix in [false, true] {
            let (m, a) = if matrix {
                // Some general affine matrix with a negative determinant.
                placed("matrix = [1, 2, 0, 5,  0, 1, 3, 0,  -2, 0, 1, 1]", p, n).unwrap()
            } else {
                placed(toml, p, n).unwrap()
            };
            let q = &m.positions;
            let [i, j, k] = m.indices[0].map(|x| x as usize);
            for t in [q[1] - q[0], q[2] - q[0], q[2] - q[1]] {
                assert!(a.normals[0].dot(t).abs() < 1e-5 * t.length(), "{:?} against {t}", a.normals[0]);
            }
            assert!((a.normals[0].length() - 1.0).abs() < 1e-6);
            // Mirrored, so the winding was swapped: the geometric normal keeps the shading
            // normal's side.
            assert_eq!(m.indices, vec![[0, 2, 1]], "matrix {matrix}");
            assert!((q[j] - q[i]).cross(q[k] - q[i]).dot(a.normals[0]) > 0.0);
        }
        let (_, a) = placed(toml, p, Vec3::ZERO).unwrap();
        assert!(a.normals.iter().all(|n| *n == Vec3::ZERO), "no normal stays none");
    }

    #[test]
    fn a_negative_determinant_flips_the_winding() {
        let matrix = |m: &str| placed(&format!("matrix = [{m}]"), XYZ, Vec3::Z).unwrap().0.indices;
        assert_eq!(matrix("-1, 0, 0, 0,  0, 1, 0, 0,  0, 0, 1, 0"), vec![[0, 2, 1]]);
        assert_eq!(matrix("-1, 0, 0, 0,  0, -1, 0, 0,  0, 0, 1, 0"), vec![[0, 1, 2]]);
        let rotated =
            |s: &str| placed(&format!("{s}\nrotate = {{ axis = [0, 1, 0], degrees = 45 }}"), XYZ, Vec3::Z);
        assert_eq!(rotated("scale = [1, -1, 1]").unwrap().0.indices, vec![[0, 2, 1]]);
        assert_eq!(rotated("scale = -1").unwrap().0.indices, vec![[0, 2, 1]]);
        assert_eq!(rotated("scale = [-1, -1, 1]").unwrap().0.indices, vec![[0, 1, 2]]);
    }

    #[test]
    fn scale_and_translate_alone_are_applied_as_before() {
        let p = [Vec3::new(0.1, 0.7, -0.3), Vec3::new(1e5, 3.3, 0.2), Vec3::new(-7.1, 0.0, 2.9)];
        let (m, _) = placed("scale = [0.3, -1.7, 2.1]\ntranslate = [0.01, 5, -3]", p, Vec3::Z).unwrap();
        let (s, t) = (Vec3::new(0.3, -1.7, 2.1), Vec3::new(0.01, 5.0, -3.0));
        assert_eq!(m.positions, p.map(|p| p * s + t).to_vec(), "bit for bit");
    }

    #[test]
    fn bad_transforms_name_the_field() {
        for (toml, expected) in [
            ("rotate = { axis = [0, 0, 0], degrees = 10 }", "field `mesh[0].rotate.axis`: is zero"),
            (
                "rotate = { axis = [0, nan, 1], degrees = 10 }",
                "field `mesh[0].rotate.axis`: [0.0, NaN, 1.0] is not finite",
            ),
            (
                "rotate = [{ axis = [0, 1, 0], degrees = 10 }, { axis = [0, 1, 0], degrees = inf }]",
                "field `mesh[0].rotate[1].degrees`: inf is not finite",
            ),
            ("rotate = { axis = [0, 1, 0], degrees = 10 }\nscale = 0", "field `mesh[0].scale`"),
            (
                "rotate = { axis = [0, 1, 0], degrees = 10 }\ntranslate = [0, 0, nan]",
                "field `mesh[0].translate`",
            ),
            ("matrix = [1, 0, 0, 0,  0, 1, 0, 0,  0, 0, 1]", "field `mesh[0].matrix`: has 11 numbers"),
            (
                "matrix = [1, 0, 0, 0,  0, 1, 0, 0,  0, 0, 1, nan]",
                "field `mesh[0].matrix`: entry 11 (row 2, column 3) is NaN",
            ),
            (
                "matrix = [1, 0, 0, 0,  0, 1, 0, 0,  0, 0, 1, 0,  0, 0.5, 0, 1]",
                "field `mesh[0].matrix`: last row [0.0, 0.5, 0.0, 1.0] is not [0, 0, 0, 1]",
            ),
            ("matrix = [1, 0, 0, 0,  0, 1, 0, 0,  0, 0, 1, 0,  0, 0, 0, 2]", "is not [0, 0, 0, 1]"),
            ("matrix = [1, 2, 3, 0,  2, 4, 6, 0,  0, 0, 1, 0]", "field `mesh[0].matrix`: is singular"),
            ("matrix = [1e-9, 0, 0, 0,  0, 1e9, 0, 0,  0, 0, 1, 0]", "ok"),
            // Columns nearly parallel: singular. A tiny column alone is a tiny scale: not.
            ("matrix = [1, 1, 0, 0,  0, 1e-8, 0, 0,  0, 0, 1, 0]", "field `mesh[0].matrix`: is singular"),
            ("matrix = [1, 0, 0, 0,  0, 1, 0, 0,  1, 1, 1e-8, 0]", "ok"),
            (
                "matrix = [1, 0, 0, 0,  0, 1, 0, 0,  0, 0, 1, 0]\ntranslate = [1, 0, 0]",
                "field `mesh[0].matrix`: given with scale",
            ),
        ] {
            match placed(toml, XYZ, Vec3::Z) {
                Ok(_) => assert_eq!(expected, "ok", "{toml}"),
                Err(e) => assert!(e.starts_with("s.toml: ") && e.contains(expected), "{toml}: {e}"),
            }
        }
    }
}
