//! The scene file's cameras as [`SceneCamera`]s: one `[camera]` table (named `camera` unless
//! it says otherwise) or a `[[camera]]` array of named ones, each still, keyed
//! (`[[camera.key]]`) or a `turntable`. Errors name the field: `camera.vfov_deg` for the
//! single table, `camera[1].key[2].frame` in an array.

use super::camera::{CameraKey, Lens, MotionError, SceneCamera, Turntable};
use super::file::{finite3, CameraEntries, CameraEntry, KeyEntry, TurntableEntry};
use super::SceneError;
use crate::config::MAX_IMAGE_SIDE;
use glam::Vec3;
use std::path::Path;

/// Every camera of the file, in file order (at least one).
pub fn cameras(path: &Path, entries: &CameraEntries) -> Result<Vec<SceneCamera>, SceneError> {
    match entries {
        CameraEntries::One(entry) => {
            let name = match &entry.name {
                Some(name) => checked_name(path, "camera.name", name)?,
                None => "camera",
            };
            Ok(vec![camera(path, "camera", name, entry)?])
        }
        CameraEntries::Many(list) => {
            if list.is_empty() {
                return Err(SceneError::field(path, "camera", "an empty array: the scene needs a camera"));
            }
            let mut cameras: Vec<SceneCamera> = Vec::with_capacity(list.len());
            for (i, entry) in list.iter().enumerate() {
                let prefix = format!("camera[{i}]");
                let field = format!("{prefix}.name");
                let name = entry.name.as_deref().ok_or_else(|| {
                    SceneError::field(
                        path,
                        &field,
                        "missing: every [[camera]] needs a name (it goes into file names)",
                    )
                })?;
                let name = checked_name(path, &field, name)?;
                if let Some(j) = cameras.iter().position(|c| c.name == name) {
                    return Err(SceneError::field(
                        path,
                        field,
                        format!("duplicate camera name {name:?} (camera[{j}] has it too)"),
                    ));
                }
                cameras.push(camera(path, &prefix, name, entry)?);
            }
            Ok(cameras)
        }
    }
}

/// `name` if it can go into a file name: non-empty, made of `A-Z a-z 0-9 _ . -`, and neither
/// `.` nor `..`.
fn checked_name<'a>(path: &Path, field: &str, name: &'a str) -> Result<&'a str, SceneError> {
    let allowed = |c: char| c.is_ascii_alphanumeric() || matches!(c, '_' | '.' | '-');
    if name.is_empty() || !name.chars().all(allowed) || name == "." || name == ".." {
        return Err(SceneError::field(
            path,
            field,
            format!(
                "{name:?} is not a camera name: names go into file names, so they are non-empty, \
                 made of A-Z, a-z, 0-9, '_', '.' and '-', and not \".\" or \"..\""
            ),
        ));
    }
    Ok(name)
}

/// One camera; `prefix` is `camera` or `camera[i]`.
fn camera(path: &Path, prefix: &str, name: &str, c: &CameraEntry) -> Result<SceneCamera, SceneError> {
    let f = |field: &str| format!("{prefix}.{field}");
    let (eye, target) = (finite3(path, &f("eye"), c.eye)?, finite3(path, &f("target"), c.target)?);
    let base = CameraKey {
        eye,
        target,
        up: finite3(path, &f("up"), c.up)?,
        vfov_deg: vfov(path, &f("vfov_deg"), c.vfov_deg)?,
        lens: Lens {
            aperture_radius: aperture(path, &f("aperture_radius"), c.aperture_radius.unwrap_or(0.0))?,
            focus_distance: focus(path, &f("focus_distance"), c.focus_distance, eye, target)?,
        },
    };
    for (field, v) in [(f("width"), c.width), (f("height"), c.height)] {
        if v == 0 || v > MAX_IMAGE_SIDE {
            return Err(SceneError::field(path, field, format!("{v} is not in 1..={MAX_IMAGE_SIDE}")));
        }
    }
    let view = base.view(c.width, c.height).ok_or_else(|| {
        SceneError::field(
            path,
            prefix,
            "degenerate view: eye equals target or up is parallel to the view direction",
        )
    })?;
    let motion = |e: MotionError| SceneError::field(path, f(&e.field()), e.to_string());
    match (&c.keys[..], &c.turntable) {
        ([], None) => Ok(SceneCamera::still(name, view)),
        ([_, ..], Some(_)) => Err(SceneError::field(
            path,
            f("turntable"),
            "the camera has [[camera.key]]s as well: a camera has keys or a turntable, not both",
        )),
        (keys, None) => {
            let keys = keys
                .iter()
                .enumerate()
                .map(|(k, key)| {
                    let prefix = format!("{prefix}.key[{k}]");
                    Ok((key.frame, camera_key(path, &prefix, &base, c.focus_distance, key)?))
                })
                .collect::<Result<Vec<_>, SceneError>>()?;
            SceneCamera::keyed(name, c.width, c.height, keys).map_err(motion)
        }
        ([], Some(t)) => {
            let turntable = turntable(path, &f("turntable"), &base, t)?;
            SceneCamera::turntable(name, c.width, c.height, base, turntable).map_err(motion)
        }
    }
}

/// A key's values, the camera's own where it leaves them out; a key without `focus_distance`
/// takes the camera's (`camera_focus`) if it gives one, else focuses at the key's own target.
fn camera_key(
    path: &Path,
    prefix: &str,
    base: &CameraKey,
    camera_focus: Option<f32>,
    k: &KeyEntry,
) -> Result<CameraKey, SceneError> {
    let f = |field: &str| format!("{prefix}.{field}");
    let vec = |field: &str, v: Option<[f32; 3]>, default: Vec3| match v {
        Some(v) => finite3(path, &f(field), v),
        None => Ok(default),
    };
    let (eye, target) = (vec("eye", k.eye, base.eye)?, vec("target", k.target, base.target)?);
    Ok(CameraKey {
        eye,
        target,
        up: vec("up", k.up, base.up)?,
        vfov_deg: match k.vfov_deg {
            Some(v) => vfov(path, &f("vfov_deg"), v)?,
            None => base.vfov_deg,
        },
        lens: Lens {
            aperture_radius: match k.aperture_radius {
                Some(a) => aperture(path, &f("aperture_radius"), a)?,
                None => base.lens.aperture_radius,
            },
            focus_distance: match (k.focus_distance, camera_focus) {
                (Some(d), _) => focus(path, &f("focus_distance"), Some(d), eye, target)?,
                (None, Some(_)) => base.lens.focus_distance,
                (None, None) => focus(path, &f("focus_distance"), None, eye, target)?,
            },
        },
    })
}

/// A thin lens's radius: finite and `>= 0` metres.
fn aperture(path: &Path, field: &str, radius: f32) -> Result<f32, SceneError> {
    if !(radius >= 0.0 && radius.is_finite()) {
        return Err(SceneError::field(
            path,
            field,
            format!("{radius} is not a radius in metres: it must be finite and >= 0 (0: a pinhole)"),
        ));
    }
    Ok(radius)
}

/// The focus distance given (finite and `> 0` metres), or the eye's distance to the target.
fn focus(path: &Path, field: &str, given: Option<f32>, eye: Vec3, target: Vec3) -> Result<f32, SceneError> {
    match given {
        Some(d) if d > 0.0 && d.is_finite() => Ok(d),
        Some(d) => Err(SceneError::field(
            path,
            field,
            format!("{d} is not a distance in metres: it must be finite and > 0"),
        )),
        // A degenerate view (eye at the target) is refused with the view.
        None => Ok((target - eye).length()),
    }
}

fn turntable(
    path: &Path,
    prefix: &str,
    base: &CameraKey,
    t: &TurntableEntry,
) -> Result<Turntable, SceneError> {
    let f = |field: &str| format!("{prefix}.{field}");
    let degrees = t.degrees.unwrap_or(360.0);
    if !degrees.is_finite() {
        return Err(SceneError::field(path, f("degrees"), format!("{degrees} is not finite")));
    }
    Ok(Turntable {
        frames: t.frames,
        center: match t.center {
            Some(c) => finite3(path, &f("center"), c)?,
            None => base.target,
        },
        axis: finite3(path, &f("axis"), t.axis.unwrap_or([0.0, 1.0, 0.0]))?,
        degrees,
    })
}

/// A vertical field of view in (0, 180) degrees whose half-angle tangent is usable.
fn vfov(path: &Path, field: &str, vfov_deg: f32) -> Result<f32, SceneError> {
    // A field of view so small that its tangent rounds to 0 would give every pixel one ray.
    let tan_half = (0.5 * vfov_deg.to_radians()).tan();
    if !(vfov_deg > 0.0 && vfov_deg < 180.0 && tan_half > 0.0 && tan_half.is_finite()) {
        return Err(SceneError::field(
            path,
            field,
            format!("{vfov_deg} is not in (0, 180), or too small to be used"),
        ));
    }
    Ok(vfov_deg)
}
