//! Placing a mesh in the scene: the `[[mesh]]` entry's `scale` and `translate`, applied to its
//! positions and (by the inverse transpose) its shading normals.

use super::file::{self, finite3, Scale};
use super::SceneError;
use crate::geometry::{TriangleMesh, VertexAttributes};
use glam::Vec3;
use std::path::Path;

/// Applies mesh entry `i`'s transform to `mesh` and its `attributes`; a mirroring transform
/// also reverses the winding, so front faces stay counter-clockwise.
pub fn apply(
    path: &Path,
    i: usize,
    entry: &file::MeshEntry,
    mesh: &mut TriangleMesh,
    attributes: &mut VertexAttributes,
) -> Result<(), SceneError> {
    let scale = match entry.scale {
        None => Vec3::ONE,
        Some(Scale::Uniform(s)) => Vec3::splat(s),
        Some(Scale::PerAxis(s)) => Vec3::from(s),
    };
    if !scale.is_finite() || scale.cmpeq(Vec3::ZERO).any() {
        return Err(SceneError::field(path, format!("mesh[{i}].scale"), "must be finite and non-zero"));
    }
    let translate = finite3(path, &format!("mesh[{i}].translate"), entry.translate.unwrap_or([0.0; 3]))?;
    let mirrored = scale.x * scale.y * scale.z < 0.0;
    for p in &mut mesh.positions {
        *p = *p * scale + translate;
    }
    // Normals go by the inverse transpose: a per-axis scale divides them.
    for n in &mut attributes.normals {
        *n = (*n / scale).try_normalize().unwrap_or(Vec3::ZERO);
    }
    if mirrored {
        // A mirroring scale flips the winding; restore counter-clockwise front faces.
        for t in &mut mesh.indices {
            t.swap(1, 2);
        }
    }
    Ok(())
}
