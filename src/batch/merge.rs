//! `photonmap merge`: partial films (passes `A..B` of one render each, written by `render
//! --pass-range`) added up into the image that one process rendering every pass makes, bit for
//! bit: the parts hold exact sums ([`crate::film::sums`]), so neither the split nor the order
//! changes a bit. Parts of another scene, other settings, another view or another program
//! version, overlapping passes and missing ones are refused, each naming the file and why.

use super::meta::{CAMERA, FINISHED, FRAME, SCENE_HASH, SETTINGS_HASH, STATE, VERSION, VIEW_HASH};
use crate::film::partial::PartialFilm;
use crate::film::sums::PassSums;
use serde::Serialize;
use std::ops::Range;
use std::path::{Path, PathBuf};

/// The parts, added up.
#[derive(Debug)]
pub struct Merged {
    pub sums: PassSums,
    /// Passes of the whole render.
    pub total: u32,
    /// Ranges of passes no part holds (empty unless merged with `partial`).
    pub missing: Vec<Range<u32>>,
    /// The record for the image's header: the parts' (scene, settings, view, camera, frame,
    /// version) and the state, finished or which passes it holds.
    pub record: Vec<(&'static str, String)>,
    pub parts: Vec<PartReport>,
}

/// One part, as the report lists it.
#[derive(Debug, Serialize)]
pub struct PartReport {
    pub path: String,
    pub first_pass: u32,
    pub end_pass: u32,
}

/// What two parts of one render share, with how each is called in an error.
const SAME: [(&str, &str); 5] = [
    (SCENE_HASH, "another scene"),
    (SETTINGS_HASH, "other settings"),
    (VIEW_HASH, "another view"),
    (CAMERA, "another camera"),
    (FRAME, "another frame"),
];

/// Reads and adds up `paths`; with `partial`, missing passes are allowed (not overlaps).
pub fn merge(paths: &[PathBuf], partial: bool) -> Result<Merged, String> {
    let mut parts: Vec<(PathBuf, PartialFilm)> = Vec::with_capacity(paths.len());
    for path in paths {
        let part = PartialFilm::read(path).map_err(|e| e.to_string())?;
        let version = part.attributes.get(VERSION).map_or("an unknown version", String::as_str);
        if version != env!("CARGO_PKG_VERSION") {
            return Err(format!(
                "{}: written by photonmap {version}, this is {}: render the part again with this version",
                path.display(),
                env!("CARGO_PKG_VERSION")
            ));
        }
        if let Some((first_path, first)) = parts.first() {
            check_same(path, &part, first_path, first)?;
        }
        parts.push((path.clone(), part));
    }
    let Some((_, first)) = parts.first() else { return Err("no parts to merge".into()) };
    let total = first.total;
    let mut order: Vec<usize> = (0..parts.len()).collect();
    order.sort_by_key(|&i| (parts[i].1.range.start, parts[i].1.range.end));
    let mut missing = Vec::new();
    let mut next = 0u32;
    for pair in order.windows(2) {
        let ((pa, a), (pb, b)) = (&parts[pair[0]], &parts[pair[1]]);
        if b.range.start < a.range.end {
            return Err(format!(
                "{}: passes {}..{} overlap {}'s passes {}..{}",
                pb.display(),
                b.range.start,
                b.range.end,
                pa.display(),
                a.range.start,
                a.range.end
            ));
        }
    }
    for &i in &order {
        let r = &parts[i].1.range;
        if r.start > next {
            missing.push(next..r.start);
        }
        next = r.end;
    }
    if next < total {
        missing.push(next..total);
    }
    if !missing.is_empty() && !partial {
        let list: Vec<String> = missing.iter().map(|r| format!("{}..{}", r.start, r.end)).collect();
        return Err(format!(
            "passes {} of {total} are missing (no part holds them); --partial merges the passes there are",
            list.join(", ")
        ));
    }
    let mut sums = PassSums::new(first.sums.width, first.sums.height, first.sums.bias);
    for &i in &order {
        sums.add(&parts[i].1.sums);
    }
    let state = if missing.is_empty() {
        FINISHED.to_string()
    } else {
        format!("partial: {} of {total} passes", sums.passes)
    };
    let record = [SCENE_HASH, SETTINGS_HASH, VIEW_HASH, CAMERA, FRAME, VERSION]
        .into_iter()
        .map(|key| (key, first.attributes.get(key).cloned().unwrap_or_default()))
        .chain(std::iter::once((STATE, state)))
        .collect();
    let reports = order
        .iter()
        .map(|&i| PartReport {
            path: parts[i].0.display().to_string(),
            first_pass: parts[i].1.range.start,
            end_pass: parts[i].1.range.end,
        })
        .collect();
    Ok(Merged { sums, total, missing, record, parts: reports })
}

/// Refuses `part` (at `path`) unless it is of the same render as `first`.
fn check_same(path: &Path, part: &PartialFilm, first_path: &Path, first: &PartialFilm) -> Result<(), String> {
    let refuse = |what: &str, ours: &str, theirs: &str| {
        Err(format!("{}: {what} than {} ({ours}, not {theirs})", path.display(), first_path.display()))
    };
    for (key, what) in SAME {
        let (ours, theirs) = (part.attributes.get(key), first.attributes.get(key));
        if ours != theirs {
            let show = |v: Option<&String>| format!("{key} {}", v.map_or("missing", String::as_str));
            return refuse(what, &show(ours), &show(theirs));
        }
    }
    if part.total != first.total {
        return refuse("another pass count", &format!("{} passes", part.total), &format!("{}", first.total));
    }
    let (a, b) = ((part.sums.width, part.sums.height), (first.sums.width, first.sums.height));
    if a != b {
        return refuse("another size", &format!("{}x{}", a.0, a.1), &format!("{}x{}", b.0, b.1));
    }
    Ok(())
}
