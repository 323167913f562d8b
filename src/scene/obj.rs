//! Wavefront OBJ/MTL loading through `tobj`, preceded by a line-by-line check so that a
//! malformed file gets an error naming its line (tobj's own errors carry none).

use super::SceneError;
use crate::geometry::TriangleMesh;
use glam::Vec3;
use std::cell::RefCell;
use std::path::{Path, PathBuf};

/// One material as an MTL file gives it (fields as in the file; absent ones `None`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MtlMaterial {
    pub kd: Option<[f32; 3]>,
    pub ks: Option<[f32; 3]>,
    pub ke: Option<[f32; 3]>,
    pub ns: Option<f32>,
    pub ni: Option<f32>,
    pub illum: Option<u8>,
}

/// An OBJ file's triangles with, per triangle, the name of its material (if any).
pub struct ObjData {
    pub mesh: TriangleMesh,
    pub tri_material: Vec<Option<String>>,
    /// Each material name the OBJ uses, with the line of its first `usemtl`.
    pub used: Vec<(String, usize)>,
    pub materials: Vec<(String, MtlMaterial)>,
}

/// Loads and triangulates `path` (fan triangulation: a quad becomes (0,1,2),(0,2,3)).
pub fn load_obj(path: &Path) -> Result<ObjData, SceneError> {
    let text = read(path)?;
    let runs = check_obj(path, &text)?;
    let dir = path.parent().unwrap_or(Path::new(".")).to_owned();
    let mtl_error: RefCell<Option<SceneError>> = RefCell::new(None);
    let options =
        tobj::LoadOptions { triangulate: true, single_index: false, ignore_points: true, ignore_lines: true };
    let loaded = tobj::load_obj_buf(&mut text.as_bytes(), &options, |mtl| {
        let mtl_path = dir.join(mtl);
        let result = read(&mtl_path).and_then(|t| check_mtl(&mtl_path, &t).map(|_| t));
        match result {
            Ok(t) => tobj::load_mtl_buf(&mut t.as_bytes()),
            Err(e) => {
                *mtl_error.borrow_mut() = Some(e);
                Err(tobj::LoadError::OpenFileFailed)
            }
        }
    });
    let (models, materials) =
        loaded.map_err(|e| SceneError::file(path, format!("OBJ could not be read: {e}")))?;
    if let Some(e) = mtl_error.into_inner() {
        return Err(e);
    }
    let materials = materials.map_err(|e| SceneError::file(path, format!("MTL could not be read: {e}")))?;

    let mut mesh = TriangleMesh::default();
    for model in &models {
        let m = &model.mesh;
        let part = TriangleMesh {
            positions: m.positions.chunks_exact(3).map(|p| Vec3::new(p[0], p[1], p[2])).collect(),
            indices: m.indices.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect(),
        };
        mesh.append(&part);
    }
    // Materials by the OBJ's own `usemtl` runs (tobj drops names its MTL lacks, which the
    // scene file may still define). tobj keeps faces in file order and fans an n-gon into
    // n - 2 triangles, so the runs line up with its triangles.
    let mut tri_material = Vec::with_capacity(mesh.len());
    let mut used: Vec<(String, usize)> = Vec::new();
    for run in &runs {
        tri_material.extend(std::iter::repeat_n(run.material.clone(), run.triangles));
        if let Some(name) = &run.material {
            if !used.iter().any(|(n, _)| n == name) {
                used.push((name.clone(), run.line));
            }
        }
    }
    if tri_material.len() != mesh.len() {
        return Err(SceneError::file(
            path,
            format!("{} triangles read but {} counted from the faces", mesh.len(), tri_material.len()),
        ));
    }
    let materials = materials
        .into_iter()
        .map(|m| {
            let mtl = MtlMaterial {
                kd: m.diffuse,
                ks: m.specular,
                ke: m.emissive,
                ns: m.shininess,
                ni: m.optical_density,
                illum: m.illumination_model,
            };
            (m.name, mtl)
        })
        .collect();
    Ok(ObjData { mesh, tri_material, used, materials })
}

fn read(path: &Path) -> Result<String, SceneError> {
    let bytes = std::fs::read(path).map_err(|error| SceneError::Io { path: path.to_owned(), error })?;
    String::from_utf8(bytes).map_err(|e| {
        let line = 1 + e.as_bytes()[..e.utf8_error().valid_up_to()].iter().filter(|&&b| b == b'\n').count();
        SceneError::line(path, line, "not UTF-8 text")
    })
}

/// Consecutive faces sharing a material: `triangles` after fan triangulation; `line` of the
/// `usemtl` that started the run.
struct Run {
    material: Option<String>,
    triangles: usize,
    line: usize,
}

/// Checks each statement tobj reads, as tobj reads it (words split on whitespace, no trailing
/// comments), so that whatever tobj would refuse, or panic on, is refused here with a line:
/// `v` has 3, 4 (`w`) or 6 (RGB) finite numbers; `vt`/`vn` have 2/3 numbers; every `f` has at
/// least 3 vertex references and each of their `v/vt/vn` indices parses and is in range
/// (negative ones count from the end); `l` is a polyline of at most 2 vertices; `mtllib` names
/// an existing file and `usemtl` a material.
fn check_obj(path: &Path, text: &str) -> Result<Vec<Run>, SceneError> {
    let mut counts = [0i64; 3]; // v, vt, vn defined so far
    let mut faces = 0usize;
    let mut runs: Vec<Run> = Vec::new();
    let mut material: Option<(String, usize)> = None;
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let mut words = raw.split_whitespace();
        let Some(keyword) = words.next() else { continue };
        let bad = |message: String| SceneError::line(path, line, message);
        // tobj reads the rest of the line after the first space as a name.
        let tobj_name = raw.split_once(' ').map_or("", |(_, rest)| rest).trim();
        if matches!(keyword, "v" | "f" | "l") && raw.contains('#') {
            return Err(bad(format!(
                "`#` in a `{keyword}` statement: comments must be on lines of their own"
            )));
        }
        match keyword {
            "v" => {
                let nums: Vec<&str> = words.collect();
                if !matches!(nums.len(), 3 | 4 | 6) {
                    return Err(bad(format!(
                        "vertex needs 3 coordinates (then a w, or an RGB colour), found {} number(s)",
                        nums.len()
                    )));
                }
                let mut xyzw = [1.0f32; 4];
                for (k, n) in nums.iter().enumerate() {
                    match n.parse::<f32>() {
                        Ok(x) if x.is_finite() => xyzw[k.min(3)] = x,
                        Ok(x) => return Err(bad(format!("vertex coordinate {x} is not finite"))),
                        Err(_) => return Err(bad(format!("`{n}` is not a number"))),
                    }
                }
                if nums.len() == 4 && !xyzw[..3].iter().all(|x| (x / xyzw[3]).is_finite()) {
                    return Err(bad(format!("vertex w = {} gives non-finite coordinates", xyzw[3])));
                }
                counts[0] += 1;
            }
            "vt" | "vn" => {
                let (need, slot) = if keyword == "vt" { (2, 1) } else { (3, 2) };
                let nums: Vec<&str> = words.take(need).collect();
                if nums.len() < need || nums.iter().any(|n| n.parse::<f32>().is_err()) {
                    return Err(bad(format!("`{keyword}` needs {need} numbers")));
                }
                counts[slot] += 1;
            }
            "f" | "l" => {
                let refs: Vec<&str> = words.collect();
                if keyword == "f" && refs.len() < 3 {
                    return Err(bad(format!("face needs 3 vertices, found {}", refs.len())));
                }
                for r in &refs {
                    check_reference(r, &counts)
                        .map_err(|m| bad(if r.contains('/') { format!("`{r}`: {m}") } else { m }))?;
                }
                if keyword == "l" {
                    // tobj would read a polyline of 3 or more vertices as a face.
                    if refs.len() > 2 {
                        return Err(bad(format!(
                            "polyline (`l`) of {} vertices: only faces (`f`) are rendered",
                            refs.len()
                        )));
                    }
                    continue;
                }
                faces += 1;
                let name = material.as_ref().map(|(n, _)| n);
                match runs.last_mut() {
                    Some(run) if run.material.as_ref() == name => run.triangles += refs.len() - 2,
                    _ => runs.push(Run {
                        material: name.cloned(),
                        triangles: refs.len() - 2,
                        line: material.as_ref().map_or(line, |(_, l)| *l),
                    }),
                }
            }
            "usemtl" => {
                let name = raw.split('#').next().unwrap_or("").trim()["usemtl".len()..].trim();
                if name.is_empty() || tobj_name.is_empty() {
                    return Err(bad("usemtl needs a material name, after a space".into()));
                }
                material = Some((name.to_owned(), line));
            }
            "mtllib" => {
                // The name runs to the end of the line (it may hold spaces), as tobj reads it.
                let mtl = path.parent().unwrap_or(Path::new(".")).join(tobj_name);
                if tobj_name.is_empty() {
                    return Err(bad("mtllib needs a file name, after a space".into()));
                }
                if !mtl.is_file() {
                    return Err(bad(format!(
                        "material library `{tobj_name}` not found at {}",
                        mtl.display()
                    )));
                }
            }
            _ => {}
        }
    }
    if faces == 0 {
        return Err(SceneError::file(path, "no faces: the OBJ holds no triangles"));
    }
    Ok(runs)
}

/// Checks one `v`, `v/vt`, `v//vn` or `v/vt/vn` reference against the `v`, `vt` and `vn`
/// counts so far (1-based; negative counts back from the last one).
fn check_reference(r: &str, counts: &[i64; 3]) -> Result<(), String> {
    let parts: Vec<&str> = r.split('/').collect();
    if parts.len() > 3 || parts[0].is_empty() {
        return Err("not a vertex reference (v, v/vt, v//vn or v/vt/vn)".into());
    }
    for ((part, &count), what) in parts.iter().zip(counts).zip(["vertex", "texture coordinate", "normal"]) {
        if part.is_empty() {
            continue;
        }
        let idx: i64 = part.parse().map_err(|_| format!("`{part}` is not a {what} index"))?;
        let resolved = if idx < 0 { count.saturating_add(idx) } else { idx - 1 };
        if idx == 0 || resolved < 0 || resolved >= count {
            return Err(format!("{what} index {idx} out of range: {count} defined so far"));
        }
    }
    Ok(())
}

/// Checks the numeric MTL statements the renderer uses.
fn check_mtl(path: &Path, text: &str) -> Result<(), SceneError> {
    let mut current: Option<String> = None;
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        // Words as tobj splits them: a `#` starts a comment only as the first word.
        let mut words = raw.split_whitespace();
        let Some(keyword) = words.next() else { continue };
        if keyword.starts_with('#') {
            continue;
        }
        let args: Vec<&str> = words.collect();
        let arity = match keyword {
            "newmtl" => {
                if args.is_empty() {
                    return Err(SceneError::line(path, line, "newmtl needs a name"));
                }
                current = Some(args.join(" "));
                continue;
            }
            "Kd" | "Ks" | "Ke" | "Ka" | "Tf" => 3,
            "Ns" | "Ni" | "d" | "Tr" | "illum" => 1,
            _ => continue,
        };
        if current.is_none() {
            return Err(SceneError::line(path, line, format!("`{keyword}` before any newmtl")));
        }
        if args.len() < arity {
            return Err(SceneError::line(path, line, format!("`{keyword}` needs {arity} number(s)")));
        }
        if keyword == "illum" && args[0].parse::<u8>().is_err() {
            return Err(SceneError::line(
                path,
                line,
                format!("`illum`: `{}` is not a model number 0..=255", args[0]),
            ));
        }
        for a in &args[..arity] {
            match a.parse::<f32>() {
                Ok(x) if x.is_finite() => {}
                _ => {
                    return Err(SceneError::line(
                        path,
                        line,
                        format!("`{keyword}`: `{a}` is not a finite number"),
                    ))
                }
            }
        }
    }
    Ok(())
}

/// Resolves `name` relative to the directory of `base`.
pub fn relative_to(base: &Path, name: &Path) -> PathBuf {
    if name.is_absolute() {
        name.to_owned()
    } else {
        base.parent().unwrap_or(Path::new(".")).join(name)
    }
}
