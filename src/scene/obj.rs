//! Wavefront OBJ/MTL loading: the OBJ's geometry is read here, line by line, so that a
//! malformed file gets an error naming its line; MTL files are checked the same way and then
//! read by `tobj` (whose own errors carry no line).

use super::SceneError;
use crate::geometry::{TriangleMesh, VertexAttributes};
use crate::texture::srgb_decode;
use glam::{Vec2, Vec3};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// One material as an MTL file gives it (fields as in the file; absent ones `None`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MtlMaterial {
    pub kd: Option<[f32; 3]>,
    pub ks: Option<[f32; 3]>,
    pub ke: Option<[f32; 3]>,
    /// `Ka`: Blender writes a principled BSDF's metallic value there.
    pub ka: Option<[f32; 3]>,
    /// `Pr` and `Pm`, the PBR extension's roughness and metallic values.
    pub roughness: Option<f32>,
    pub metallic: Option<f32>,
    pub ns: Option<f32>,
    pub ni: Option<f32>,
    pub illum: Option<u8>,
    /// The texture maps (`map_Kd`, `bump`, ...) in file order.
    pub maps: Vec<MtlMap>,
    /// `d` (dissolve), as written.
    pub dissolve: Option<f32>,
    /// The MTL file, and the line of each numeric statement (`Kd`, `Ks`, `d`, `illum`, …;
    /// the last if repeated), for messages.
    pub file: PathBuf,
    pub lines: HashMap<String, usize>,
    /// Whether the file is Blender's export (its first comment says so): its `Ns`, `Ks` and
    /// `Ka` are a principled BSDF's roughness, specular and metallic values
    /// (read so by the scene's materials, `materials.rs`).
    pub blender: bool,
    /// Whether the scene's materials read it as a principled BSDF (`read_principled` in
    /// `materials.rs`): its `Pr`, `Pm` and their maps are then its roughness and metallic.
    pub principled: bool,
}

/// One texture statement of an MTL file: `map_Kd -s 2 2 wood.png`.
#[derive(Clone, Debug, PartialEq)]
pub struct MtlMap {
    /// The statement's keyword, lower-cased (`map_kd`, `map_bump`, `bump`, `norm`, ...).
    pub keyword: String,
    /// The image, relative to the MTL file's directory as written.
    pub file: PathBuf,
    /// Where the statement is, for messages.
    pub mtl: PathBuf,
    pub line: usize,
    /// `-s u v`: texture coordinates are scaled by this (default 1).
    pub scale: Vec2,
    /// `-o u v`: then offset by this (default 0).
    pub offset: Vec2,
    /// `-clamp on`.
    pub clamp: bool,
    /// `-bm m` of a `bump`/`map_Bump`: the height map's texels are multiplied by this (default 1).
    pub bump_multiplier: f32,
    /// Options read but not applied (`-mm`, `-bm` of a map other than a bump map, ...), by name.
    pub ignored: Vec<String>,
}

/// An OBJ file's triangles with, per triangle, the name of its material (if any).
pub struct ObjData {
    pub mesh: TriangleMesh,
    /// The mesh's vertex normals and texture coordinates (empty lists where the file has none).
    pub attributes: VertexAttributes,
    pub tri_material: Vec<Option<String>>,
    /// Each material name the OBJ uses, with the line of its first `usemtl`.
    pub used: Vec<(String, usize)>,
    pub materials: Vec<(String, MtlMaterial)>,
}

/// Loads and triangulates `path` (fan triangulation: a quad becomes (0,1,2),(0,2,3)). Each
/// distinct `v/vt/vn` corner becomes a vertex; a triangle whose three corners have normals
/// is wound so that its geometric normal faces the side they point to (pbrt and Mitsuba shade
/// such triangles by their normals' side), the others keep the file's winding.
pub fn load_obj(path: &Path) -> Result<ObjData, SceneError> {
    let text = read(path)?;
    let parsed = parse_obj(path, &text)?;
    let dir = path.parent().unwrap_or(Path::new(".")).to_owned();
    let mut materials: Vec<(String, MtlMaterial)> = Vec::new();
    for (name, line) in &parsed.libraries {
        let mtl_path = dir.join(name);
        let t = read(&mtl_path)?;
        let (mut maps, mut lines) = check_mtl(&mtl_path, &t)?;
        let (loaded, _) = tobj::load_mtl_buf(&mut t.as_bytes()).map_err(|e| {
            SceneError::line(path, *line, format!("material library `{name}` could not be read: {e}"))
        })?;
        // Blender's exporters head the file `# Blender MTL File: …` or `# Blender 4.2.0 MTL
        // File: …`.
        let blender = t.lines().take_while(|l| l.trim_start().starts_with('#')).any(|l| {
            let l = l.trim_start().trim_start_matches('#').trim_start();
            l.starts_with("Blender") && l.contains("MTL File")
        });
        for m in loaded {
            let mtl = MtlMaterial {
                kd: m.diffuse,
                ks: m.specular,
                ke: m.emissive,
                ka: m.ambient,
                roughness: pbr_value(&m, "Pr"),
                metallic: pbr_value(&m, "Pm"),
                ns: m.shininess,
                ni: m.optical_density,
                illum: m.illumination_model,
                maps: maps.remove(&m.name).unwrap_or_default(),
                dissolve: m.dissolve,
                file: mtl_path.clone(),
                lines: lines.remove(&m.name).unwrap_or_default(),
                blender,
                principled: false,
            };
            if !materials.iter().any(|(n, _)| *n == m.name) {
                materials.push((m.name, mtl));
            }
        }
    }
    let mut tri_material = Vec::with_capacity(parsed.mesh.len());
    let mut used: Vec<(String, usize)> = Vec::new();
    for run in &parsed.runs {
        tri_material.extend(std::iter::repeat_n(run.material.clone(), run.triangles));
        if let Some(name) = &run.material {
            if !used.iter().any(|(n, _)| n == name) {
                used.push((name.clone(), run.line));
            }
        }
    }
    Ok(ObjData { mesh: parsed.mesh, attributes: parsed.attributes, tri_material, used, materials })
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

/// An OBJ's geometry, its material runs and its material libraries (name, line).
struct Parsed {
    mesh: TriangleMesh,
    attributes: VertexAttributes,
    runs: Vec<Run>,
    libraries: Vec<(String, usize)>,
}

/// Reads every statement of an OBJ, refusing with its line whatever cannot be rendered as
/// written (words split on whitespace, no trailing comments, as `tobj` and most readers take
/// them): `v` has 3, 4 (`w`, ignored as tobj ignores it) or 6 (RGB) finite numbers; `vt`/`vn`
/// have 2/3 finite numbers; every `f` has at least 3 vertex references and each of their
/// `v/vt/vn` indices parses and is in range (negative ones count from the end); `l` is a
/// polyline of at most 2 vertices (not rendered); `mtllib` names an existing file and
/// `usemtl` a material.
fn parse_obj(path: &Path, text: &str) -> Result<Parsed, SceneError> {
    let mut v: Vec<Vec3> = Vec::new();
    // Each `v`'s colour, where it has one (`v x y z r g b`).
    let mut vc: Vec<Option<Vec3>> = Vec::new();
    let mut vt: Vec<Vec2> = Vec::new();
    let mut vn: Vec<Vec3> = Vec::new();
    // Faces as corner lists; each corner (v, vt, vn), u32::MAX where absent.
    let mut corners: Vec<[u32; 3]> = Vec::new();
    let mut face_starts: Vec<usize> = Vec::new();
    let mut runs: Vec<Run> = Vec::new();
    let mut libraries: Vec<(String, usize)> = Vec::new();
    let mut material: Option<(String, usize)> = None;
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let mut words = raw.split_whitespace();
        let Some(keyword) = words.next() else { continue };
        let bad = |message: String| SceneError::line(path, line, message);
        // The rest of the line after the first space, as a name.
        let rest_name = raw.split_once(' ').map_or("", |(_, rest)| rest).trim();
        if matches!(keyword, "v" | "vt" | "vn" | "f" | "l") && raw.contains('#') {
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
                let xyz = finite_numbers(&nums[..3], "vertex coordinate").map_err(&bad)?;
                let rest = finite_numbers(&nums[3..], "vertex w or colour").map_err(&bad)?;
                v.push(Vec3::from_slice(&xyz));
                vc.push(match rest[..] {
                    [r, g, b] if [r, g, b].iter().all(|x| (0.0..=1.0).contains(x)) => {
                        Some(Vec3::new(r, g, b).map(srgb_decode))
                    }
                    [_, _, _] => return Err(bad("vertex colour values must be in [0, 1]".into())),
                    _ => None,
                });
            }
            "vt" | "vn" => {
                let need = if keyword == "vt" { 2 } else { 3 };
                let nums: Vec<&str> = words.take(need).collect();
                if nums.len() < need {
                    return Err(bad(format!("`{keyword}` needs {need} numbers")));
                }
                let x = finite_numbers(&nums, &format!("`{keyword}` value")).map_err(&bad)?;
                if keyword == "vt" {
                    vt.push(Vec2::new(x[0], x[1]));
                } else {
                    // A zero or unnormalisable normal is no normal.
                    vn.push(Vec3::from_slice(&x).try_normalize().unwrap_or(Vec3::ZERO));
                }
            }
            "f" | "l" => {
                let refs: Vec<&str> = words.collect();
                if keyword == "f" && refs.len() < 3 {
                    return Err(bad(format!("face needs 3 vertices, found {}", refs.len())));
                }
                let counts = [v.len(), vt.len(), vn.len()];
                let mut face = Vec::with_capacity(refs.len());
                for r in &refs {
                    face.push(
                        reference(r, counts)
                            .map_err(|m| bad(if r.contains('/') { format!("`{r}`: {m}") } else { m }))?,
                    );
                }
                if keyword == "l" {
                    if refs.len() > 2 {
                        return Err(bad(format!(
                            "polyline (`l`) of {} vertices: only faces (`f`) are rendered",
                            refs.len()
                        )));
                    }
                    continue;
                }
                face_starts.push(corners.len());
                corners.extend(face);
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
                if name.is_empty() || rest_name.is_empty() {
                    return Err(bad("usemtl needs a material name, after a space".into()));
                }
                material = Some((name.to_owned(), line));
            }
            "mtllib" => {
                // The name runs to the end of the line (it may hold spaces).
                let mtl = path.parent().unwrap_or(Path::new(".")).join(rest_name);
                if rest_name.is_empty() {
                    return Err(bad("mtllib needs a file name, after a space".into()));
                }
                if !mtl.is_file() {
                    return Err(bad(format!(
                        "material library `{rest_name}` not found at {}",
                        mtl.display()
                    )));
                }
                libraries.push((rest_name.to_owned(), line));
            }
            _ => {}
        }
    }
    if face_starts.is_empty() {
        return Err(SceneError::file(path, "no faces: the OBJ holds no triangles"));
    }
    Ok(assemble(&v, &vc, &vt, &vn, &corners, &face_starts, runs, libraries))
}

/// Parses finite numbers, or says which word is not one (`what` names a non-finite one).
fn finite_numbers(words: &[&str], what: &str) -> Result<Vec<f32>, String> {
    words
        .iter()
        .map(|w| match w.parse::<f32>() {
            Ok(x) if x.is_finite() => Ok(x),
            Ok(x) => Err(format!("{what} {x} is not finite")),
            Err(_) => Err(format!("`{w}` is not a number")),
        })
        .collect()
}

/// Fans the faces into triangles over one vertex per distinct corner.
#[allow(clippy::too_many_arguments)] // the statements read, each list as parsed
fn assemble(
    v: &[Vec3],
    vc: &[Option<Vec3>],
    vt: &[Vec2],
    vn: &[Vec3],
    corners: &[[u32; 3]],
    face_starts: &[usize],
    runs: Vec<Run>,
    libraries: Vec<(String, usize)>,
) -> Parsed {
    const NONE: u32 = u32::MAX;
    let has_uv = corners.iter().any(|c| c[1] != NONE);
    let has_normal = corners.iter().any(|c| c[2] != NONE && vn[c[2] as usize] != Vec3::ZERO);
    let has_colour = corners.iter().any(|c| vc[c[0] as usize].is_some());
    let mut mesh = TriangleMesh::default();
    let mut attributes = VertexAttributes::default();
    let mut vertex_of: HashMap<[u32; 3], u32> = HashMap::new();
    let mut vertex = |c: [u32; 3], mesh: &mut TriangleMesh, attributes: &mut VertexAttributes| -> u32 {
        let key = [c[0], if has_uv { c[1] } else { NONE }, if has_normal { c[2] } else { NONE }];
        *vertex_of.entry(key).or_insert_with(|| {
            mesh.positions.push(v[c[0] as usize]);
            if has_uv {
                attributes.uvs.push(if c[1] == NONE { Vec2::ZERO } else { vt[c[1] as usize] });
            }
            if has_normal {
                attributes.normals.push(if c[2] == NONE { Vec3::ZERO } else { vn[c[2] as usize] });
            }
            if has_colour {
                attributes.colours.push(vc[c[0] as usize].unwrap_or(Vec3::ONE));
            }
            (mesh.positions.len() - 1) as u32
        })
    };
    for (f, &start) in face_starts.iter().enumerate() {
        let end = face_starts.get(f + 1).copied().unwrap_or(corners.len());
        let face = &corners[start..end];
        for k in 2..face.len() {
            let mut tri = [face[0], face[k - 1], face[k]].map(|c| vertex(c, &mut mesh, &mut attributes));
            if has_normal {
                let n: Vec3 = tri.iter().map(|&i| attributes.normals[i as usize]).sum();
                let [a, b, c] = tri.map(|i| mesh.positions[i as usize]);
                if tri.iter().all(|&i| attributes.normals[i as usize] != Vec3::ZERO)
                    && (b - a).cross(c - a).dot(n) < 0.0
                {
                    tri.swap(1, 2);
                }
            }
            mesh.indices.push(tri);
        }
    }
    Parsed { mesh, attributes, runs, libraries }
}

/// Resolves one `v`, `v/vt`, `v//vn` or `v/vt/vn` reference against the `v`, `vt` and `vn`
/// counts so far (1-based; negative counts back from the last one) to 0-based indices,
/// `u32::MAX` for a part that is absent.
fn reference(r: &str, counts: [usize; 3]) -> Result<[u32; 3], String> {
    let parts: Vec<&str> = r.split('/').collect();
    if parts.len() > 3 || parts[0].is_empty() {
        return Err("not a vertex reference (v, v/vt, v//vn or v/vt/vn)".into());
    }
    let mut out = [u32::MAX; 3];
    for (k, (part, what)) in parts.iter().zip(["vertex", "texture coordinate", "normal"]).enumerate() {
        if part.is_empty() {
            continue;
        }
        let count = counts[k] as i64;
        let idx: i64 = part.parse().map_err(|_| format!("`{part}` is not a {what} index"))?;
        let resolved = if idx < 0 { count.saturating_add(idx) } else { idx - 1 };
        if idx == 0 || resolved < 0 || resolved >= count {
            return Err(format!("{what} index {idx} out of range: {count} defined so far"));
        }
        out[k] = resolved as u32;
    }
    Ok(out)
}

/// Checks the numeric MTL statements the renderer uses.
/// Texture statements are read here too: `map_Kd`, `map_Ks`, `map_Ke`, `map_d`, `map_Ns`,
/// `map_Ka`, `bump`/`map_Bump`, `norm`, `disp`, `decal`, `refl`, each with its options, per
/// material.
/// Also returns, per material, the line of each numeric statement.
type StatementLines = HashMap<String, HashMap<String, usize>>;

fn check_mtl(path: &Path, text: &str) -> Result<(HashMap<String, Vec<MtlMap>>, StatementLines), SceneError> {
    let mut maps: HashMap<String, Vec<MtlMap>> = HashMap::new();
    let mut lines: StatementLines = HashMap::new();
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
            "Ns" | "Ni" | "d" | "Tr" | "illum" | "Pr" | "Pm" => 1,
            // The PBR extension's constants: recorded where they are, for the warning that they
            // are not rendered, and not checked (they were never read).
            k if PBR_KEYWORDS.contains(&k) => {
                if let Some(name) = &current {
                    lines.entry(name.clone()).or_default().insert(keyword.to_string(), line);
                }
                continue;
            }
            k if is_map(k) => {
                let Some(name) = &current else {
                    return Err(SceneError::line(path, line, format!("`{keyword}` before any newmtl")));
                };
                let map = parse_map(path, line, keyword, &args)?;
                maps.entry(name.clone()).or_default().push(map);
                continue;
            }
            _ => continue,
        };
        let Some(name) = &current else {
            return Err(SceneError::line(path, line, format!("`{keyword}` before any newmtl")));
        };
        lines.entry(name.clone()).or_default().insert(keyword.to_string(), line);
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
    Ok((maps, lines))
}

/// The value of the PBR extension's `key` (`Pr`, `Pm`) in `m` (checked a finite number by
/// `check_mtl`).
fn pbr_value(m: &tobj::Material, key: &str) -> Option<f32> {
    m.unknown_param.get(key)?.split_whitespace().next()?.parse().ok()
}

/// The constants of MTL's PBR extension (roughness, metallic, sheen, clearcoat, anisotropy);
/// all but `Pr` and `Pm`, which a principled reading takes (`materials.rs`), are not rendered:
/// the material is drawn from `Kd`, `Ks`, `Ns` and `illum`.
pub const PBR_KEYWORDS: [&str; 7] = ["Pr", "Pm", "Ps", "Pc", "Pcr", "aniso", "anisor"];

/// Whether an MTL keyword names a texture map.
fn is_map(keyword: &str) -> bool {
    let k = keyword.to_ascii_lowercase();
    k.starts_with("map_") || matches!(k.as_str(), "bump" | "norm" | "disp" | "decal" | "refl")
}

/// A texture statement's options and file name (the rest of the line: it may hold spaces).
fn parse_map(path: &Path, line: usize, keyword: &str, args: &[&str]) -> Result<MtlMap, SceneError> {
    let bad = |m: String| SceneError::line(path, line, format!("`{keyword}`: {m}"));
    let mut map = MtlMap {
        keyword: keyword.to_ascii_lowercase(),
        file: PathBuf::new(),
        mtl: path.to_owned(),
        line,
        scale: Vec2::ONE,
        offset: Vec2::ZERO,
        clamp: false,
        bump_multiplier: 1.0,
        ignored: Vec::new(),
    };
    let bump = matches!(map.keyword.as_str(), "bump" | "map_bump");
    let mut i = 0;
    while i < args.len() && args[i].starts_with('-') && args[i].len() > 1 {
        let option = args[i];
        // How many values each option takes (up to, for -s/-o/-t: 1 to 3 numbers).
        let (min, max) = match option {
            "-s" | "-o" | "-t" => (1, 3),
            "-mm" => (2, 2),
            "-bm" | "-boost" | "-texres" => (1, 1),
            "-blendu" | "-blendv" | "-clamp" | "-cc" | "-imfchan" | "-type" => (1, 1),
            _ => return Err(bad(format!("unknown option `{option}`"))),
        };
        let mut values = Vec::new();
        while values.len() < max && i + 1 + values.len() < args.len() {
            let v = args[i + 1 + values.len()];
            let numeric = v.parse::<f32>().is_ok();
            if (min == max && values.len() < min) || numeric {
                values.push(v);
            } else {
                break;
            }
        }
        if values.len() < min {
            return Err(bad(format!("option `{option}` needs {min} value(s)")));
        }
        let numbers = || -> Result<Vec<f32>, SceneError> {
            values
                .iter()
                .map(|v| {
                    v.parse::<f32>()
                        .ok()
                        .filter(|x| x.is_finite())
                        .ok_or_else(|| bad(format!("option `{option}`: `{v}` is not a finite number")))
                })
                .collect()
        };
        match option {
            "-s" => {
                let n = numbers()?;
                map.scale = Vec2::new(n[0], *n.get(1).unwrap_or(&n[0]));
            }
            "-o" => {
                let n = numbers()?;
                map.offset = Vec2::new(n[0], *n.get(1).unwrap_or(&0.0));
            }
            "-clamp" => match values[0] {
                "on" => map.clamp = true,
                "off" => map.clamp = false,
                v => return Err(bad(format!("option `-clamp`: `{v}` is neither on nor off"))),
            },
            "-bm" if bump => map.bump_multiplier = numbers()?[0],
            _ => map.ignored.push(option.to_owned()),
        }
        i += 1 + values.len();
    }
    let file = args[i.min(args.len())..].join(" ");
    if file.is_empty() {
        return Err(bad("needs an image file name".into()));
    }
    map.file = PathBuf::from(file);
    Ok(map)
}

/// Resolves `name` relative to the directory of `base`.
pub fn relative_to(base: &Path, name: &Path) -> PathBuf {
    if name.is_absolute() {
        name.to_owned()
    } else {
        base.parent().unwrap_or(Path::new(".")).join(name)
    }
}
