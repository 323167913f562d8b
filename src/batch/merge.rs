//! `photonmap merge`: partial films (passes `A..B` of one render each, written by `render
//! --pass-range`) added up into the image that one process rendering every pass makes, bit for
//! bit: the parts hold exact sums ([`crate::film::sums`]), so neither the split nor the order
//! changes a bit. Parts of another scene, other settings, another view or another program
//! version, overlapping passes and missing ones are refused, each naming the file and why.
//!
//! Parts holding consecutive passes also merge into one larger part ([`Coverage::Contiguous`]),
//! so that many parts can be added up in a tree (on each node, then across nodes) rather than
//! all read by one merge.

use super::meta::{CAMERA, FINISHED, FRAME, SCENE_HASH, SETTINGS_HASH, STATE, VERSION, VIEW_HASH};
use crate::film::partial::{PartHeader, PartialFilm};
use crate::film::sums::PassSums;
use serde::Serialize;
use std::ops::Range;
use std::path::{Path, PathBuf};

/// Which passes the parts must hold.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Coverage {
    /// Every pass of the render.
    Whole,
    /// Any: the missing ones are listed ([`Merged::missing`]).
    Partial,
    /// One run of consecutive passes, not necessarily from 0 or to the end (a larger part).
    Contiguous,
}

/// The parts, added up.
#[derive(Debug)]
pub struct Merged {
    pub sums: PassSums,
    /// From the first pass of the first part to the end of the last.
    pub range: Range<u32>,
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

/// Reads and adds up `paths`, refusing overlaps and, as `coverage` says, missing passes. Every
/// header is checked before any pixel is read, and the parts are then read one at a time: a
/// merge holds two images' sums, however many parts.
pub fn merge(paths: &[PathBuf], coverage: Coverage) -> Result<Merged, String> {
    let mut parts: Vec<(PathBuf, PartHeader)> = Vec::with_capacity(paths.len());
    for path in paths {
        let part = PartialFilm::read_header(path).map_err(|e| e.to_string())?;
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
    let range = parts[order[0]].1.range.start..next;
    let list = |gaps: &[Range<u32>]| {
        gaps.iter().map(|r| format!("{}..{}", r.start, r.end)).collect::<Vec<_>>().join(", ")
    };
    match coverage {
        Coverage::Whole if !missing.is_empty() => {
            return Err(format!(
                "passes {} of {total} are missing (no part holds them); --partial merges the passes there are",
                list(&missing)
            ));
        }
        Coverage::Contiguous => {
            let gaps: Vec<Range<u32>> =
                missing.iter().filter(|g| g.start > range.start && g.end < range.end).cloned().collect();
            if !gaps.is_empty() {
                return Err(format!(
                    "passes {} are missing between {}..{}: a part holds consecutive passes",
                    list(&gaps),
                    range.start,
                    range.end
                ));
            }
        }
        _ => {}
    }
    let mut sums = PassSums::new(first.width, first.height, first.bias);
    for &i in &order {
        let (path, header) = &parts[i];
        let part = PartialFilm::read(path).map_err(|e| e.to_string())?;
        if part.range != header.range || part.attributes != header.attributes {
            return Err(format!("{}: changed while being merged", path.display()));
        }
        sums.add(&part.sums);
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
    Ok(Merged { sums, range, total, missing, record, parts: reports })
}

/// Refuses `part` (at `path`) unless it is of the same render as `first`.
fn check_same(path: &Path, part: &PartHeader, first_path: &Path, first: &PartHeader) -> Result<(), String> {
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
    let (a, b) = ((part.width, part.height), (first.width, first.height));
    if a != b {
        return refuse("another size", &format!("{}x{}", a.0, a.1), &format!("{}x{}", b.0, b.1));
    }
    Ok(())
}
