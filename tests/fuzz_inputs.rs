//! Fuzzing of scene loading with mutated inputs (proptest, runs in `cargo test`).
//!
//! The starting point is the canonical Cornell box (`scenes/cornell/`): its TOML, OBJ and MTL
//! are mutated line- and byte-wise (lines deleted, duplicated, swapped, inserted; numbers
//! replaced by NaN, infinities, huge, negative or garbage values; vertex references out of
//! range; truncation; non-UTF-8 bytes; very long lines) and loaded.
//!
//! The property is the project rule for bad input: loading returns `Ok` or `Err` and never
//! panics; an error is one line that names the file at fault (and, for an OBJ/MTL line error,
//! a line number within that file); a scene that loads has a valid mesh, a material for every
//! triangle and only finite numbers.
//!
//! `PROPTEST_CASES=N` sets the number of cases of each fuzz test (default: a count that keeps
//! this file well under a minute). Inputs that once crashed the loader are kept in
//! `tests/data/fuzz/` and replayed by `regression_inputs_fail_cleanly`.

use photonmap::scene::{one_line, Scene, SceneError};
use proptest::prelude::*;
use proptest::sample::Index;
use proptest::test_runner::Config;
use std::fs;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};

const TOML: &str = include_str!("../scenes/cornell/cornell.toml");
const OBJ: &str = include_str!("../scenes/cornell/cornell.obj");
const MTL: &str = include_str!("../scenes/cornell/cornell.mtl");

/// Cases per fuzz test unless `PROPTEST_CASES` says otherwise.
const DEFAULT_CASES: u32 = 1500;

fn config() -> Config {
    let cases = std::env::var("PROPTEST_CASES").ok().and_then(|s| s.parse().ok()).unwrap_or(DEFAULT_CASES);
    // Crashes found are minimised by hand into tests/data/fuzz/; no persistence files.
    Config { cases, failure_persistence: None, ..Config::default() }
}

// ---------------------------------------------------------------------------------------------
// Mutations
// ---------------------------------------------------------------------------------------------

/// Values that replace a number (or any word) of a line.
const NASTY_WORDS: &[&str] = &[
    "nan",
    "NaN",
    "-nan",
    "inf",
    "-inf",
    "infinity",
    "1e39",
    "-1e39",
    "3.4028236e38",
    "1e-45",
    "1e-300",
    "0",
    "-0",
    "-1",
    "-2",
    "-37",
    "37",
    "1.5",
    "255",
    "256",
    "-2147483649",
    "4294967295",
    "4294967296",
    "9223372036854775807",
    "-9223372036854775808",
    "18446744073709551615",
    "99999999999999999999999",
    "",
    "1.2.3",
    "0x10",
    "+1",
    "1e",
    "x",
    "#",
    "\"",
    "[",
    "]",
    "=",
    "{",
    "1/2/3/4",
    "1//",
    "//",
    "/",
    "/1",
    "1/0",
    "1/-1",
    "1/-99999999999",
    "1/1/-99999999999",
    "-99999999999/1/1",
    "1//-9223372036854775807",
    "1/9223372036854775807",
    "1/99999999999999999999",
    "-1/-1/-1",
    "é",
    "\u{2028}",
    "\u{feff}",
    "\t",
    "\r",
];

/// Whole lines inserted into OBJ, MTL or TOML text.
const NASTY_LINES: &[&str] = &[
    "f",
    "f 1",
    "f 1 2",
    "f 1 2 3",
    "f 1 1 1",
    "f 0 1 2",
    "f -1 -2 -3",
    "f -1 -2 -999",
    "f 1 2 99999999999",
    "f 1/1 2/2 3/3",
    "f 1/1/1 2/2/2 3/3/3",
    "f 1//1 2//2 3//3",
    "f 1/-1 2/-1 3/-1",
    "f 1/-99999999999999 2 3",
    "f 1/9223372036854775807 2 3",
    "f 1//-9223372036854775807 2 3",
    "f 1//9223372036854775807 2 3",
    "f 1/5 2/5 3/5",
    "f 1//5 2//5 3//5",
    "l 1 2",
    "l 1 2 3",
    "l 1 2 3 4",
    "l 1/-99999999999999 2 3",
    "p 1",
    "v",
    "v 1 2",
    "v 1 2 3 4",
    "v 1 2 3 0",
    "v 1 2 3 1e-45",
    "v 1 2 3 nan",
    "v 1 2 3 1 0 0",
    "v 1 2 3 1 0",
    "v 1 2 3 1 0 0 0",
    "v 1 2 3 # comment",
    "v 3e38 3e38 3e38",
    "vt",
    "vt 0",
    "vt 0 0",
    "vt 0.5 0.5 0",
    "vn 0 0 1",
    "vn 0 0",
    "o",
    "o x",
    " o x",
    "g",
    "g a b",
    "\u{3000}o x",
    "s off",
    "usemtl",
    "usemtl ",
    "usemtl\twhite",
    " usemtl white",
    "usemtl white # comment",
    "usemtl nosuch",
    "usemtl é",
    "mtllib",
    "mtllib nosuch.mtl",
    "mtllib\tcornell.mtl",
    " mtllib cornell.mtl",
    "mtllib cornell.mtl # comment",
    "mtllib cornell.obj",
    "mtllib .",
    "mtllib /",
    "newmtl",
    "newmtl white",
    "newmtl x",
    "Kd",
    "Kd 1 2",
    "Kd 0.5 0.5 0.5",
    "Kd 2 2 2",
    "Kd -1 0 0",
    "Ka 1",
    "Ks 1 1 1",
    "Ke 1 1 1",
    "Ke 1e39 0 0",
    "Ns",
    "Ns -5",
    "Ns 1e30",
    "Ni 0",
    "Ni -1",
    "d 2",
    "Tr",
    "Tf 1",
    "illum",
    "illum 2",
    "illum 3",
    "illum 7",
    "illum 2.5",
    "illum 300",
    "illum -1",
    "map_Kd",
    "map_Kd tex.png",
    "bump",
    "#",
    "",
    "[camera]",
    "[render]",
    "[[mesh]]",
    "[[light]]",
    "[materials.white]",
    "[materials.\"a\\nb\"]",
    "type = \"point\"",
    "type = \"plastic\"",
    "type = \"glossy\"",
    "type = \"glass\"",
    "type = \"mirror\"",
    "type = \"emissive\"",
    "obj = \"\"",
    "obj = \"nosuch.obj\"",
    "obj = \"cornell.mtl\"",
    "obj = \".\"",
    "obj = \"a\\nb.obj\"",
    "material = \"nosuch\"",
    "material = \"a\\nb\"",
    "material = \"light\"",
    "scale = 0",
    "scale = -1",
    "scale = 1e30",
    "scale = [1, -1, 1]",
    "scale = nan",
    "translate = [1e38, 0, 0]",
    "translate = [inf, 0, 0]",
    "position = [0, 0, 0]",
    "intensity = [1, 1, 1]",
    "direction = [0, 0, 0]",
    "cone_deg = 30",
    "falloff_deg = 40",
    "irradiance = [1, 1, 1]",
    "photons = 1000000000000",
    "photons = -1",
    "spp = 0",
    "gather_radius = nan",
    "gather_radius = -1",
    "caustic_gather_radius = inf",
    "accel = \"nosuch\"",
    "kernel = \"box\"",
    "indirect = \"final-gather\"",
    "width = 0",
    "width = 100000",
    "height = 4294967296",
    "vfov_deg = 180",
    "vfov_deg = 1e-40",
    "eye = [1e38, 1e38, 1e38]",
    "eye = [0.278, 0.273, 0.0]",
    "up = [0, 0, 1]",
    "up = [1e38, 1e38, 1e38]",
    "target = [-3e38, 0, 0]",
    "ior = 0",
    "ior = 1e30",
    "ns = nan",
    "kd = [1, 1, 1]",
    "ke = [-1, 0, 0]",
    "ks = [0.5, 0.5, 0.5]",
    "kd = \"red\"",
    "kd = [1, 2]",
    "unknown = 1",
    "a = 1\na = 2",
    "x = [",
    "'''",
    "\"\"\"",
];

/// One edit of a text seen as lines (or, for the byte edits, as bytes).
#[derive(Clone, Debug)]
enum Mutation {
    Delete(Index),
    Duplicate(Index),
    Swap(Index, Index),
    /// Replace a word of a line (a number, usually) by a nasty one.
    Word(Index, Index, &'static str),
    /// Replace a word by random printable junk.
    Junk(Index, Index, String),
    Insert(Index, &'static str),
    /// Replace a whole line by one of the nasty lines.
    Replace(Index, &'static str),
    /// Cut the text at a byte offset.
    Truncate(Index),
    /// Insert arbitrary bytes (not necessarily UTF-8) at a byte offset.
    Bytes(Index, Vec<u8>),
    /// Repeat a word of a line many times, making a very long line.
    Long(Index, Index, usize),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    let word = prop::sample::select(NASTY_WORDS);
    let line = prop::sample::select(NASTY_LINES);
    prop_oneof![
        2 => any::<Index>().prop_map(Mutation::Delete),
        1 => any::<Index>().prop_map(Mutation::Duplicate),
        1 => (any::<Index>(), any::<Index>()).prop_map(|(a, b)| Mutation::Swap(a, b)),
        6 => (any::<Index>(), any::<Index>(), word).prop_map(|(l, w, s)| Mutation::Word(l, w, s)),
        1 => (any::<Index>(), any::<Index>(), "[ -~]{0,12}").prop_map(|(l, w, s)| Mutation::Junk(l, w, s)),
        4 => (any::<Index>(), line.clone()).prop_map(|(i, s)| Mutation::Insert(i, s)),
        2 => (any::<Index>(), line).prop_map(|(i, s)| Mutation::Replace(i, s)),
        1 => any::<Index>().prop_map(Mutation::Truncate),
        1 => (any::<Index>(), prop::collection::vec(any::<u8>(), 1..8)).prop_map(|(i, b)| Mutation::Bytes(i, b)),
        1 => (any::<Index>(), any::<Index>(), 1000usize..60_000).prop_map(|(l, w, n)| Mutation::Long(l, w, n)),
    ]
}

fn mutations() -> impl Strategy<Value = Vec<Mutation>> {
    prop::collection::vec(mutation(), 1..5)
}

/// Splits on `\n`, keeping the pieces as bytes (a trailing newline gives a last empty piece).
fn split_lines(text: &[u8]) -> Vec<Vec<u8>> {
    text.split(|&b| b == b'\n').map(<[u8]>::to_vec).collect()
}

/// Byte ranges of the whitespace-separated words of `line`.
fn word_spans(line: &[u8]) -> Vec<(usize, usize)> {
    let mut spans = Vec::new();
    let mut start = None;
    for (i, &b) in line.iter().enumerate() {
        let space = b == b' ' || b == b'\t';
        match (start, space) {
            (None, false) => start = Some(i),
            (Some(s), true) => {
                spans.push((s, i));
                start = None;
            }
            _ => {}
        }
    }
    if let Some(s) = start {
        spans.push((s, line.len()));
    }
    spans
}

fn replace_word(line: &mut Vec<u8>, w: Index, with: &[u8]) {
    let spans = word_spans(line);
    if spans.is_empty() {
        line.extend_from_slice(b" ");
        line.extend_from_slice(with);
        return;
    }
    let (s, e) = spans[w.index(spans.len())];
    line.splice(s..e, with.iter().copied());
}

fn apply(text: &str, muts: &[Mutation]) -> Vec<u8> {
    let mut bytes = text.as_bytes().to_vec();
    for m in muts {
        match m {
            Mutation::Truncate(i) => {
                let at = i.index(bytes.len() + 1);
                bytes.truncate(at);
                continue;
            }
            Mutation::Bytes(i, b) => {
                let at = i.index(bytes.len() + 1);
                bytes.splice(at..at, b.iter().copied());
                continue;
            }
            _ => {}
        }
        let mut lines = split_lines(&bytes);
        let n = lines.len();
        match m {
            Mutation::Delete(i) => {
                lines.remove(i.index(n));
            }
            Mutation::Duplicate(i) => {
                let l = lines[i.index(n)].clone();
                lines.insert(i.index(n), l);
            }
            Mutation::Swap(a, b) => lines.swap(a.index(n), b.index(n)),
            Mutation::Word(l, w, s) => replace_word(&mut lines[l.index(n)], *w, s.as_bytes()),
            Mutation::Junk(l, w, s) => replace_word(&mut lines[l.index(n)], *w, s.as_bytes()),
            Mutation::Insert(i, s) => lines.insert(i.index(n + 1), s.as_bytes().to_vec()),
            Mutation::Replace(i, s) => lines[i.index(n)] = s.as_bytes().to_vec(),
            Mutation::Long(l, w, count) => {
                let line = &mut lines[l.index(n)];
                let spans = word_spans(line);
                let word = match spans.get(w.index(spans.len().max(1))) {
                    Some(&(s, e)) => line[s..e].to_vec(),
                    None => b"9".to_vec(),
                };
                for _ in 0..*count {
                    line.push(b' ');
                    line.extend_from_slice(&word);
                }
            }
            Mutation::Truncate(_) | Mutation::Bytes(..) => unreachable!(),
        }
        bytes = lines.join(&b'\n');
    }
    bytes
}

// ---------------------------------------------------------------------------------------------
// The property
// ---------------------------------------------------------------------------------------------

/// A directory holding the Cornell box under its usual names.
fn cornell_dir() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("cornell.toml"), TOML).unwrap();
    fs::write(dir.path().join("cornell.obj"), OBJ).unwrap();
    fs::write(dir.path().join("cornell.mtl"), MTL).unwrap();
    dir
}

/// Lines of a file as an editor counts them: a final newline does not start a new line.
fn line_count(bytes: &[u8]) -> usize {
    let newlines = bytes.iter().filter(|&&b| b == b'\n').count();
    newlines + usize::from(!bytes.is_empty() && !bytes.ends_with(b"\n"))
}

/// `Err(reason)` if the error breaks the rule: one line, naming its file, with a line number
/// inside that file. `texts` gives the content of files loaded from memory; `files`, if not
/// empty, the names of the files an error may blame.
fn check_error(e: &SceneError, texts: &[(&Path, &[u8])], files: &[&str]) -> Result<(), String> {
    let shown = e.to_string();
    if shown.contains('\n') || shown.contains('\r') {
        return Err(format!("error is not one line: {shown:?}"));
    }
    let path = e.path();
    let name = path.file_name().map_or_else(|| path.to_string_lossy(), |n| n.to_string_lossy());
    // Errors show names with control characters escaped, to stay on one line.
    if !shown.contains(&one_line(&name)) {
        return Err(format!("error does not name the file {name:?}: {shown:?}"));
    }
    if !files.is_empty() && !files.iter().any(|f| *f == name) {
        return Err(format!("error blames {}, not one of {files:?}: {shown:?}", path.display()));
    }
    let content = || -> Option<Vec<u8>> {
        match texts.iter().find(|(p, _)| *p == path) {
            Some((_, t)) => Some(t.to_vec()),
            None => fs::read(path).ok(),
        }
    };
    match e {
        SceneError::Line { line, .. } => {
            if !shown.contains(&format!(":{line}:")) {
                return Err(format!("line error without `:{line}:`: {shown:?}"));
            }
            let Some(bytes) = content() else {
                return Err(format!("line error for a missing file: {shown:?}"));
            };
            let count = line_count(&bytes);
            if *line == 0 || *line > count {
                return Err(format!("line {line} is not within the file's {count} lines: {shown:?}"));
            }
        }
        SceneError::Toml { message, .. } => {
            // "line L, column C: ..." when the parser knows where.
            if let Some(rest) = message.strip_prefix("line ") {
                let line: usize = rest.split(',').next().and_then(|l| l.parse().ok()).unwrap_or(0);
                let count = content().map_or(0, |b| line_count(&b));
                if line == 0 || line > count.max(1) {
                    return Err(format!(
                        "TOML line {line} is not within the file's {count} lines: {shown:?}"
                    ));
                }
            }
        }
        _ => {}
    }
    Ok(())
}

/// `Err(reason)` if a scene that loaded is not sound.
fn check_scene(scene: &Scene) -> Result<(), String> {
    scene.mesh.validate().map_err(|e| format!("loaded mesh does not validate: {e}"))?;
    if scene.mesh.is_empty() {
        return Err("loaded scene has no triangles".into());
    }
    if scene.tri_material.len() != scene.mesh.len() {
        return Err(format!("{} triangles but {} material ids", scene.mesh.len(), scene.tri_material.len()));
    }
    if let Some(m) = scene.tri_material.iter().find(|&&m| m as usize >= scene.materials.len()) {
        return Err(format!("material id {m} of {} materials", scene.materials.len()));
    }
    if scene.material_names.len() != scene.materials.len() {
        return Err("a material without a name".into());
    }
    let numbers = format!("{:?} {:?} {:?}", scene.camera, scene.materials, scene.lights);
    if numbers.contains("NaN") || numbers.contains("inf") {
        return Err(format!("non-finite number in the scene: {numbers}"));
    }
    if !scene.camera.tan_half_fov.is_finite() || scene.camera.tan_half_fov <= 0.0 {
        return Err(format!("camera tan_half_fov {}", scene.camera.tan_half_fov));
    }
    // Render settings must resolve or refuse, cleanly.
    if let Err(e) = scene.render.resolve(scene.camera.width, scene.camera.height) {
        let shown = e.to_string();
        if shown.contains('\n') {
            return Err(format!("render settings error is not one line: {shown:?}"));
        }
    }
    Ok(())
}

/// Runs `load` and turns a panic, a bad error or an unsound scene into `Err(reason)`.
fn outcome(
    load: impl FnOnce() -> Result<Scene, SceneError>,
    texts: &[(&Path, &[u8])],
    files: &[&str],
) -> Result<(), String> {
    match catch_unwind(AssertUnwindSafe(|| {
        let r = load();
        match &r {
            Ok(s) => check_scene(s),
            Err(e) => check_error(e, texts, files),
        }
    })) {
        Ok(r) => r,
        Err(panic) => {
            let msg = panic
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_default();
            Err(format!("PANIC: {msg}"))
        }
    }
}

/// Shows a mutated input in a failure message (lossy, long lines cut).
fn show(bytes: &[u8]) -> String {
    let text = String::from_utf8_lossy(bytes);
    let cut = |l: &str| match l.char_indices().nth(200) {
        Some((i, _)) => format!("{}... ({} bytes)", &l[..i], l.len()),
        None => l.to_owned(),
    };
    text.lines().map(cut).collect::<Vec<_>>().join("\n")
}

/// The files of a Cornell box directory: errors about a mutated OBJ or MTL blame one of them.
const CORNELL_FILES: &[&str] = &["cornell.toml", "cornell.obj", "cornell.mtl"];

/// Which of the Cornell files a fuzz case replaces.
#[derive(Clone, Copy, Debug)]
enum Target {
    Obj,
    Mtl,
}

fn load_with(dir: &Path, target: Target, bytes: &[u8]) -> Result<(), String> {
    let file = dir.join(match target {
        Target::Obj => "cornell.obj",
        Target::Mtl => "cornell.mtl",
    });
    fs::write(&file, bytes).unwrap();
    outcome(|| Scene::load(dir.join("cornell.toml")), &[], CORNELL_FILES)
}

// ---------------------------------------------------------------------------------------------
// The fuzz tests
// ---------------------------------------------------------------------------------------------

/// Found by `fuzz_scene_toml`: a mesh path with a newline in it. The error must stay on one
/// line and name the file as it escapes it.
#[test]
fn a_file_name_with_a_newline_is_named_escaped() {
    let dir = cornell_dir();
    let path = dir.path().join("cornell.toml");
    let text = TOML.replacen("obj = \"cornell.obj\"", "obj = \"a\\nb.obj\"", 1);
    assert_ne!(text, TOML);
    let e = Scene::from_str(&path, &text).expect_err("no such file");
    let shown = e.to_string();
    assert!(shown.contains("a\\nb.obj") && !shown.contains('\n'), "{shown:?}");
    check_error(&e, &[(&path, text.as_bytes())], &[]).unwrap();
}

#[test]
fn the_unmutated_inputs_load() {
    let dir = cornell_dir();
    let scene = Scene::load(dir.path().join("cornell.toml")).unwrap();
    check_scene(&scene).unwrap();
    let path = dir.path().join("cornell.toml");
    outcome(|| Scene::from_str(&path, TOML), &[], CORNELL_FILES).unwrap();
}

#[test]
fn fuzz_scene_toml() {
    let dir = cornell_dir();
    let path = dir.path().join("cornell.toml");
    proptest!(config(), |(muts in mutations())| {
        let bytes = apply(TOML, &muts);
        // Scene::from_str takes text; non-UTF-8 bytes go through Scene::load below.
        let text = String::from_utf8_lossy(&bytes).into_owned();
        let r = outcome(|| Scene::from_str(&path, &text), &[(&path, text.as_bytes())], &[]);
        prop_assert!(r.is_ok(), "{}\n--- mutations {:?}\n--- scene text:\n{}", r.unwrap_err(), muts, show(text.as_bytes()));
        if std::str::from_utf8(&bytes).is_err() {
            fs::write(&path, &bytes).unwrap();
            let r = outcome(|| Scene::load(&path), &[], &[]);
            fs::write(&path, TOML).unwrap();
            prop_assert!(r.is_ok(), "{}\n--- non-UTF-8 scene file:\n{}", r.unwrap_err(), show(&bytes));
        }
    });
}

/// The Cornell OBJ with texture coordinates and normals, every face as `v/vt/vn`, so that
/// mutations reach the `vt` and `vn` references too.
fn obj_with_vt_vn() -> String {
    let mut out = String::new();
    for line in OBJ.lines() {
        if let Some(refs) = line.strip_prefix("f ") {
            let refs: Vec<String> =
                refs.split_whitespace().enumerate().map(|(i, v)| format!("{v}/{}/1", i % 3 + 1)).collect();
            out += &format!("f {}\n", refs.join(" "));
        } else {
            out += line;
            out += "\n";
            if line.starts_with("mtllib") {
                out += "vt 0 0\nvt 1 0\nvt 1 1\nvn 0 1 0\n";
            }
        }
    }
    out
}

#[test]
fn fuzz_obj() {
    let dir = cornell_dir();
    let with_vt_vn = obj_with_vt_vn();
    proptest!(config(), |(muts in mutations(), vt_vn in any::<bool>())| {
        let base = if vt_vn { with_vt_vn.as_str() } else { OBJ };
        let bytes = apply(base, &muts);
        let r = load_with(dir.path(), Target::Obj, &bytes);
        prop_assert!(r.is_ok(), "{}\n--- mutations {:?}\n--- OBJ:\n{}", r.unwrap_err(), muts, show(&bytes));
    });
}

#[test]
fn fuzz_mtl() {
    let dir = cornell_dir();
    // The scene file's [materials] would override the MTL's; fuzz the MTL on its own.
    let bare = TOML.split("[materials.").next().unwrap();
    fs::write(dir.path().join("cornell.toml"), bare).unwrap();
    proptest!(config(), |(muts in mutations())| {
        let bytes = apply(MTL, &muts);
        let r = load_with(dir.path(), Target::Mtl, &bytes);
        prop_assert!(r.is_ok(), "{}\n--- mutations {:?}\n--- MTL:\n{}", r.unwrap_err(), muts, show(&bytes));
    });
}

/// OBJ text made from scratch: random vertex and face statements with small and extreme
/// indices, closer to the index checks than mutations of a valid file get.
fn obj_statement() -> impl Strategy<Value = String> {
    let num = prop_oneof![
        4 => (-3i32..4).prop_map(|i| i.to_string()),
        1 => prop::sample::select(NASTY_WORDS).prop_map(str::to_owned),
    ];
    let index = prop_oneof![
        6 => (-6i64..8).prop_map(|i| i.to_string()),
        1 => prop::sample::select(&[
            "0", "-9223372036854775808", "-9223372036854775807", "-4611686018427387904", "-99999999999999",
            "9223372036854775807", "4294967296", "99999999999999999999", "",
        ][..]).prop_map(str::to_owned),
    ];
    let reference = prop_oneof![
        4 => index.clone(),
        1 => (index.clone(), index.clone()).prop_map(|(a, b)| format!("{a}/{b}")),
        1 => (index.clone(), index.clone()).prop_map(|(a, b)| format!("{a}//{b}")),
        1 => (index.clone(), index.clone(), index.clone()).prop_map(|(a, b, c)| format!("{a}/{b}/{c}")),
    ];
    prop_oneof![
        4 => prop::collection::vec(num.clone(), 0..8).prop_map(|n| format!("v {}", n.join(" "))),
        1 => prop::collection::vec(num.clone(), 0..4).prop_map(|n| format!("vt {}", n.join(" "))),
        1 => prop::collection::vec(num, 0..4).prop_map(|n| format!("vn {}", n.join(" "))),
        4 => prop::collection::vec(reference.clone(), 0..6).prop_map(|r| format!("f {}", r.join(" "))),
        1 => prop::collection::vec(reference, 0..5).prop_map(|r| format!("l {}", r.join(" "))),
        1 => prop::sample::select(&["usemtl white", "usemtl red", "usemtl light", "o a", "g b", "usemtl mirror"][..])
            .prop_map(str::to_owned),
    ]
}

#[test]
fn fuzz_obj_from_scratch() {
    let dir = cornell_dir();
    proptest!(config(), |(statements in prop::collection::vec(obj_statement(), 0..24))| {
        let text = format!("mtllib cornell.mtl\n{}\n", statements.join("\n"));
        let r = load_with(dir.path(), Target::Obj, text.as_bytes());
        prop_assert!(r.is_ok(), "{}\n--- OBJ:\n{}", r.unwrap_err(), text);
    });
}

// ---------------------------------------------------------------------------------------------
// Regression inputs
// ---------------------------------------------------------------------------------------------

fn fuzz_data() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/fuzz")
}

/// Every file in `tests/data/fuzz/` once crashed (or misreported) the loader. Each is put in
/// place of the Cornell box's file of the same kind and must now fail with a clean error.
#[test]
fn regression_inputs_fail_cleanly() {
    let mut files: Vec<PathBuf> =
        fs::read_dir(fuzz_data()).unwrap().map(|e| e.unwrap().path()).filter(|p| p.is_file()).collect();
    files.sort();
    let mut failures = Vec::new();
    let mut count = 0;
    for file in &files {
        let ext = file.extension().and_then(|e| e.to_str()).unwrap_or("");
        if !matches!(ext, "obj" | "mtl" | "toml") {
            continue;
        }
        count += 1;
        let bytes = fs::read(file).unwrap();
        let dir = cornell_dir();
        let target = dir.path().join(format!("cornell.{ext}"));
        fs::write(&target, &bytes).unwrap();
        let scene = dir.path().join("cornell.toml");
        let r = catch_unwind(AssertUnwindSafe(|| Scene::load(&scene)));
        let problem = match r {
            Err(_) => Some("panicked".to_owned()),
            Ok(Ok(_)) => Some("loaded, but it is bad input".to_owned()),
            Ok(Err(e)) => {
                let shown = e.to_string();
                let wanted = format!("cornell.{ext}");
                check_error(&e, &[], CORNELL_FILES).err().or_else(|| {
                    (!shown.contains(&wanted)).then(|| format!("error does not name {wanted}: {shown}"))
                })
            }
        };
        if let Some(p) = problem {
            failures.push(format!("{}: {p}", file.display()));
        }
    }
    assert!(count > 0, "no regression inputs in {}", fuzz_data().display());
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

// ---------------------------------------------------------------------------------------------
// glTF
// ---------------------------------------------------------------------------------------------

/// A small glTF (a floor quad with normals, texture coordinates and u16 indices, a camera
/// and a point light under nodes with TRS) and its buffer.
const GLTF: &str = include_str!("data/gltf/quad.gltf");
const GLTF_BIN: &[u8] = include_bytes!("data/gltf/quad.bin");

/// Numbers that stay valid JSON but not valid glTF, or not sane: indices past the end,
/// counts and offsets that overflow, non-finite after the f32 conversion.
const NASTY_JSON_NUMBERS: &[&str] = &[
    "0",
    "-0",
    "1",
    "2",
    "3",
    "4",
    "7",
    "-1",
    "12",
    "48",
    "139",
    "141",
    "255",
    "65535",
    "4294967295",
    "18446744073709551615",
    "1e39",
    "-1e39",
    "1e-45",
    "0.5",
    "2.5",
    "5120",
    "5121",
    "5125",
    "5126",
    "34962",
];

/// Byte spans of the JSON numbers in `text`.
fn number_spans(text: &[u8]) -> Vec<(usize, usize)> {
    let mut spans = Vec::new();
    let mut i = 0;
    while i < text.len() {
        let starts =
            text[i].is_ascii_digit() || (text[i] == b'-' && text.get(i + 1).is_some_and(u8::is_ascii_digit));
        if starts && (i == 0 || !text[i - 1].is_ascii_alphanumeric()) {
            let s = i;
            i += 1;
            while i < text.len() && (text[i].is_ascii_digit() || b".eE+-".contains(&text[i])) {
                i += 1;
            }
            spans.push((s, i));
        } else {
            i += 1;
        }
    }
    spans
}

/// The glTF's numbers replaced (`numbers`), then the generic mutations (`muts`, maybe none).
fn mutate_gltf(numbers: &[(Index, &'static str)], muts: &[Mutation]) -> Vec<u8> {
    let mut bytes = GLTF.as_bytes().to_vec();
    for (i, with) in numbers {
        let spans = number_spans(&bytes);
        if spans.is_empty() {
            break;
        }
        let (s, e) = spans[i.index(spans.len())];
        bytes.splice(s..e, with.bytes());
    }
    if muts.is_empty() {
        bytes
    } else {
        apply(&String::from_utf8_lossy(&bytes), muts)
    }
}

/// A GLB of the fixture: its JSON and buffer as the two chunks.
fn glb(json: &[u8], bin: &[u8]) -> Vec<u8> {
    let pad = |mut v: Vec<u8>, with: u8| {
        while v.len() % 4 != 0 {
            v.push(with);
        }
        v
    };
    // The buffer without a uri is the GLB's binary chunk.
    let json = String::from_utf8_lossy(json).replacen("\"uri\": \"quad.bin\",", "", 1).into_bytes();
    let (json, bin) = (pad(json, b' '), pad(bin.to_vec(), 0));
    let mut out = b"glTF".to_vec();
    out.extend(2u32.to_le_bytes());
    out.extend(((12 + 8 + json.len() + 8 + bin.len()) as u32).to_le_bytes());
    out.extend((json.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(&json);
    out.extend((bin.len() as u32).to_le_bytes());
    out.extend(b"BIN\0");
    out.extend(&bin);
    out
}

#[test]
fn the_unmutated_gltf_loads_as_gltf_and_glb() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("quad.gltf"), GLTF).unwrap();
    fs::write(dir.path().join("quad.bin"), GLTF_BIN).unwrap();
    fs::write(dir.path().join("quad.glb"), glb(GLTF.as_bytes(), GLTF_BIN)).unwrap();
    for name in ["quad.gltf", "quad.glb"] {
        let s = Scene::load(dir.path().join(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
        check_scene(&s).unwrap();
        assert_eq!((s.mesh.len(), s.lights.len()), (2, 1), "{name}");
        assert!(s.warnings.is_empty(), "{name}: {:?}", s.warnings);
    }
}

#[test]
fn fuzz_gltf() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("quad.bin"), GLTF_BIN).unwrap();
    let files = &["quad.gltf", "quad.bin"];
    let numbers = prop::collection::vec((any::<Index>(), prop::sample::select(NASTY_JSON_NUMBERS)), 0..4);
    let generic = prop_oneof![1 => Just(Vec::new()), 1 => mutations()];
    proptest!(config(), |(numbers in numbers, muts in generic)| {
        let bytes = mutate_gltf(&numbers, &muts);
        let path = dir.path().join("quad.gltf");
        fs::write(&path, &bytes).unwrap();
        let r = outcome(|| Scene::load(&path), &[], files);
        prop_assert!(r.is_ok(), "{}\n--- numbers {:?} mutations {:?}\n--- glTF:\n{}", r.unwrap_err(), numbers, muts, show(&bytes));
    });
}

#[test]
fn a_glb_whose_length_is_shorter_than_its_header_is_an_error() {
    // Found by `scripts/fuzz.sh gltf`: the header's length field below the header's own 12
    // bytes made the `gltf` crate's subtraction overflow (a panic where overflow is checked).
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("quad.glb");
    for length in [0u32, 11] {
        let mut bytes = glb(GLTF.as_bytes(), GLTF_BIN);
        bytes[8..12].copy_from_slice(&length.to_le_bytes());
        fs::write(&path, &bytes).unwrap();
        let r = outcome(|| Scene::load(&path), &[], &["quad.glb"]);
        assert!(r.is_ok(), "length {length}: {}", r.unwrap_err());
        let e = Scene::load(&path).unwrap_err().to_string();
        assert!(e.contains("length of") && e.contains("quad.glb"), "{e}");
    }
}

#[test]
fn fuzz_glb_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let base = glb(GLTF.as_bytes(), GLTF_BIN);
    let edits = prop::collection::vec((any::<Index>(), any::<u8>()), 1..6);
    proptest!(config(), |(edits in edits, cut in prop::option::of(any::<Index>()))| {
        let mut bytes = base.clone();
        for (i, b) in &edits {
            let at = i.index(bytes.len());
            bytes[at] = *b;
        }
        if let Some(c) = cut {
            bytes.truncate(c.index(bytes.len() + 1));
        }
        let path = dir.path().join("quad.glb");
        fs::write(&path, &bytes).unwrap();
        let r = outcome(|| Scene::load(&path), &[], &["quad.glb"]);
        prop_assert!(r.is_ok(), "{}\n--- edits {:?} cut {:?}", r.unwrap_err(), edits, cut);
    });
}

#[test]
fn an_image_without_its_mime_type_or_any_source_is_an_error() {
    // Found by fuzzing the gltf target from a real GLB: an image in a buffer view without its
    // `mimeType` (or with neither `uri` nor `bufferView`) passed the `gltf` crate's validation
    // and its `Image::source` unwrapped the missing field (gltf 1.4.1).
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("quad.bin"), GLTF_BIN).unwrap();
    let path = dir.path().join("quad.gltf");
    for (image, field) in [
        (serde_json::json!({ "bufferView": 0 }), "images[0].mimeType"),
        (serde_json::json!({}), "images[0]"),
        (serde_json::json!({ "name": "x" }), "images[0]"),
    ] {
        let mut v: serde_json::Value = serde_json::from_str(GLTF).unwrap();
        v["images"] = serde_json::json!([image]);
        v["textures"] = serde_json::json!([{ "source": 0 }]);
        v["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = serde_json::json!({ "index": 0 });
        fs::write(&path, serde_json::to_vec(&v).unwrap()).unwrap();
        let r = outcome(|| Scene::load(&path), &[], &["quad.gltf"]);
        assert!(r.is_ok(), "{image}: {}", r.unwrap_err());
        let e = Scene::load(&path).unwrap_err().to_string();
        assert!(e.contains(field) && e.contains("quad.gltf"), "{image}: {e}");
    }
}
