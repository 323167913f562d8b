//! What an output image records of how it was made, in its OpenEXR header: hashes of the scene
//! as loaded and of every setting that changes the image, the camera and frame, the program's
//! version, and whether the image is finished or a checkpoint of one. `--resume` skips an image
//! whose record matches the one it would write.
//!
//! The hashes are FNV-1a (64 bits) over the loaded content, not over the files: any edit that
//! changes the geometry, a material, a light, a portal, the view or a setting changes them, and
//! reformatting a file does not. They are stable across runs and machines (no random keys).

use crate::config::RenderConfig;
use crate::scene::{Camera, Scene};
use std::collections::BTreeMap;

/// Header attribute names.
pub const SCENE_HASH: &str = "photonmap.scene_hash";
pub const SETTINGS_HASH: &str = "photonmap.settings_hash";
pub const VIEW_HASH: &str = "photonmap.view_hash";
pub const CAMERA: &str = "photonmap.camera";
pub const FRAME: &str = "photonmap.frame";
pub const VERSION: &str = "photonmap.version";
/// `finished`, or `checkpoint after N passes`.
pub const STATE: &str = "photonmap.state";
pub const FINISHED: &str = "finished";

/// The record of one image.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ImageMeta {
    pub scene_hash: u64,
    pub settings_hash: u64,
    pub view_hash: u64,
    pub camera: String,
    pub frame: u32,
}

impl ImageMeta {
    /// The record of `camera`'s `view` at `frame` rendered from `scene` as `cfg` says.
    pub fn new(scene: &Scene, cfg: &RenderConfig, camera: &str, frame: u32, view: &Camera) -> Self {
        ImageMeta {
            scene_hash: scene_hash(scene),
            settings_hash: settings_hash(cfg),
            view_hash: view_hash(view),
            camera: camera.to_string(),
            frame,
        }
    }

    /// The header attributes of the image in `state` ([`FINISHED`] or a checkpoint's).
    pub fn attributes(&self, state: &str) -> Vec<(&'static str, String)> {
        vec![
            (SCENE_HASH, format!("{:016x}", self.scene_hash)),
            (SETTINGS_HASH, format!("{:016x}", self.settings_hash)),
            (VIEW_HASH, format!("{:016x}", self.view_hash)),
            (CAMERA, self.camera.clone()),
            (FRAME, self.frame.to_string()),
            (VERSION, env!("CARGO_PKG_VERSION").to_string()),
            (STATE, state.to_string()),
        ]
    }

    /// Whether `attributes` (read from a header) record this very image, finished.
    pub fn is_finished_in(&self, attributes: &BTreeMap<String, String>) -> bool {
        let expected = self.attributes(FINISHED);
        expected.iter().all(|(name, value)| attributes.get(*name) == Some(value))
    }
}

/// FNV-1a, 64 bits.
pub fn fnv1a(bytes: &[u8]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for &b in bytes {
        h ^= b as u64;
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    h
}

/// The view: eye, frame, field of view, resolution and lens (every field of the camera). A
/// pinhole's is hashed without its lens, as it was before cameras had one, so `--resume` still
/// recognises pinhole images written then.
pub fn view_hash(view: &Camera) -> u64 {
    let described = format!("{view:?}");
    if view.lens.is_pinhole() {
        return fnv1a(described.replace(&format!(", lens: {:?}", view.lens), "").as_bytes());
    }
    fnv1a(described.as_bytes())
}

/// The scene's content as loaded: vertices, triangles and their materials, materials, lights
/// and portals (not the cameras: each image records its own view).
pub fn scene_hash(scene: &Scene) -> u64 {
    let mut bytes = Vec::with_capacity(scene.mesh.positions.len() * 12 + scene.mesh.indices.len() * 16);
    for p in &scene.mesh.positions {
        for v in p.to_array() {
            bytes.extend_from_slice(&v.to_bits().to_le_bytes());
        }
    }
    for (tri, m) in scene.mesh.indices.iter().zip(&scene.tri_material) {
        for i in tri.iter().chain(std::iter::once(m)) {
            bytes.extend_from_slice(&i.to_le_bytes());
        }
    }
    let described =
        format!("{:?}|{:?}|{:?}|{:?}", scene.materials, scene.material_names, scene.lights, scene.portals);
    bytes.extend_from_slice(described.as_bytes());
    fnv1a(&bytes)
}

/// Every setting that changes the image (the resolved configuration: integrator, budgets,
/// seed, resolution, accelerator; thread counts and output paths are not in it).
pub fn settings_hash(cfg: &RenderConfig) -> u64 {
    fnv1a(format!("{cfg:?}").as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fnv1a_matches_its_published_values() {
        assert_eq!(fnv1a(b""), 0xcbf2_9ce4_8422_2325);
        assert_eq!(fnv1a(b"a"), 0xaf63_dc4c_8601_ec8c);
        assert_eq!(fnv1a(b"foobar"), 0x8594_4171_f739_67e8);
    }

    #[test]
    fn the_view_hash_includes_the_lens() {
        use crate::scene::Lens;
        use glam::Vec3;
        let pinhole = Camera::look_at(Vec3::ZERO, Vec3::Z, Vec3::Y, 40.0, 8, 8).unwrap();
        let lens = |aperture_radius, focus_distance| {
            view_hash(&pinhole.with_lens(Lens { aperture_radius, focus_distance }).unwrap())
        };
        assert_eq!(lens(0.0, 3.0), view_hash(&pinhole), "a pinhole's focus changes nothing");
        // A pinhole hashes as cameras did before they had a lens (their derived Debug text).
        let before =
            "Camera { eye: Vec3(0.0, 0.0, 0.0), forward: Vec3(0.0, 0.0, 1.0), right: Vec3(-1.0, 0.0, 0.0), \
                      up: Vec3(0.0, 1.0, -0.0), tan_half_fov: 0.36397022, width: 8, height: 8 }";
        assert_eq!(view_hash(&pinhole), fnv1a(before.as_bytes()));
        let hashes = [view_hash(&pinhole), lens(0.01, 1.0), lens(0.02, 1.0), lens(0.01, 2.0)];
        for i in 0..hashes.len() {
            for j in 0..i {
                assert_ne!(hashes[i], hashes[j], "{i} {j}");
            }
        }
    }
}
