//! Render-farm frame lists, as Deadline, Royal Render and `blender -f` write them: `1,5,10-20`,
//! `0-100x10` or `0-100:10` (every 10th frame from 0).

use crate::scene::MAX_FRAMES;
use std::collections::HashSet;

/// Parses a render-farm frame list: comma-separated items `N`, `A-B` (inclusive), `A-BxK` or
/// `A-B:K` (every K-th from A); `step` (from --frame-step, ≥1) applies to ranges without their
/// own step. Returns the frames in the order given, duplicates removed (first occurrence kept).
///
/// Spaces around items and numbers are allowed. At most [`MAX_FRAMES`] frames may be named,
/// counted before duplicates are removed (so the work is bounded by the list itself).
pub fn parse_frames(spec: &str, step: u32) -> Result<Vec<u32>, String> {
    if step == 0 {
        return Err("--frame-step 0: the step must be at least 1".into());
    }
    if spec.trim().is_empty() {
        return Err(
            "the frame list is empty: give frames as N, A-B, A-BxK or A-B:K, separated by commas".into()
        );
    }
    let mut ranges = Vec::new();
    let mut count = 0u64;
    for (i, item) in spec.split(',').enumerate() {
        let item = item.trim();
        if item.is_empty() {
            return Err(format!("frame list {spec:?}: item {} is empty", i + 1));
        }
        let range = parse_item(item, step).map_err(|why| format!("frame list item {item:?}: {why}"))?;
        count += u64::from((range.1 - range.0) / range.2) + 1;
        if count > u64::from(MAX_FRAMES) {
            return Err(format!("frame list {spec:?} names more than {MAX_FRAMES} frames"));
        }
        ranges.push(range);
    }
    let mut seen = HashSet::new();
    let mut frames = Vec::new();
    for (start, end, step) in ranges {
        let all = (u64::from(start)..=u64::from(end)).step_by(step as usize);
        frames.extend(all.map(|f| f as u32).filter(|&f| seen.insert(f)));
    }
    Ok(frames)
}

/// One item as (first, last, step), `last` on or before the range's end.
fn parse_item(item: &str, default_step: u32) -> Result<(u32, u32, u32), String> {
    if item.starts_with('-') {
        return Err("frame numbers cannot be negative".into());
    }
    let (range, step) = match item.split_once(['x', ':']) {
        Some((range, step)) => (range, Some(number(step, "step")?)),
        None => (item, None),
    };
    let Some((start, end)) = range.split_once('-') else {
        if step.is_some() {
            return Err("a step needs a range (A-BxK or A-B:K)".into());
        }
        let frame = number(range, "frame")?;
        return Ok((frame, frame, 1));
    };
    let (start, end) = (number(start, "range start")?, number(end, "range end")?);
    if end < start {
        return Err(format!("the range ends ({end}) before it starts ({start})"));
    }
    let step = step.unwrap_or(default_step);
    if step == 0 {
        return Err("the step must be at least 1".into());
    }
    Ok((start, end, step))
}

/// A whole number from 0 to `u32::MAX`; `what` says which part of the item it is.
fn number(s: &str, what: &str) -> Result<u32, String> {
    let s = s.trim();
    if s.is_empty() {
        return Err(format!("the {what} is missing"));
    }
    if s.starts_with('-') {
        return Err(format!("the {what} {s} is negative"));
    }
    if !s.bytes().all(|b| b.is_ascii_digit()) {
        return Err(format!("the {what} {s:?} is not a whole number"));
    }
    s.parse().map_err(|_| format!("the {what} {s} is larger than {}", u32::MAX))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ok(spec: &str, step: u32) -> Vec<u32> {
        parse_frames(spec, step).unwrap_or_else(|e| panic!("{spec:?}: {e}"))
    }

    fn refused(spec: &str, step: u32, says: &[&str]) {
        let e = parse_frames(spec, step).expect_err(spec);
        for s in says {
            assert!(e.contains(s), "{spec:?}: `{s}` not in: {e}");
        }
        assert!(!e.contains('\n'), "{e:?}");
    }

    #[test]
    fn single_frames_and_ranges_in_the_order_given() {
        assert_eq!(ok("7", 1), [7]);
        assert_eq!(ok("1,5,3", 1), [1, 5, 3]);
        assert_eq!(ok("3-6", 1), [3, 4, 5, 6]);
        assert_eq!(ok("10-12,1-2", 1), [10, 11, 12, 1, 2]);
        assert_eq!(ok(" 1 , 3 - 4 ", 1), [1, 3, 4]);
        assert_eq!(ok("4-4", 1), [4]);
        assert_eq!(ok("4294967294-4294967295", 1), [u32::MAX - 1, u32::MAX]);
    }

    #[test]
    fn steps_in_x_and_colon_syntax_count_from_the_start() {
        assert_eq!(ok("0-10x5", 1), [0, 5, 10]);
        assert_eq!(ok("1-10:3", 1), [1, 4, 7, 10]);
        assert_eq!(ok("1-9x3", 1), [1, 4, 7]);
        assert_eq!(ok("2-3x10", 1), [2]);
        assert_eq!(ok("4294967290-4294967295x4", 1), [4294967290, 4294967294]);
    }

    #[test]
    fn frame_step_applies_to_ranges_without_their_own() {
        assert_eq!(ok("0-6", 2), [0, 2, 4, 6]);
        assert_eq!(ok("0-6,9", 3), [0, 3, 6, 9]);
        assert_eq!(ok("0-6x1,10-14", 2), [0, 1, 2, 3, 4, 5, 6, 10, 12, 14]);
    }

    #[test]
    fn duplicates_are_removed_keeping_the_first() {
        assert_eq!(ok("5,1-6,2", 1), [5, 1, 2, 3, 4, 6]);
        assert_eq!(ok("0-10x5,0-10", 1), [0, 5, 10, 1, 2, 3, 4, 6, 7, 8, 9]);
    }

    #[test]
    fn bad_lists_are_refused_naming_the_item() {
        refused("", 1, &["empty"]);
        refused("  ", 1, &["empty"]);
        refused("1,,3", 1, &["\"1,,3\"", "item 2 is empty"]);
        refused("1,3,", 1, &["item 3 is empty"]);
        refused("5-1", 1, &["\"5-1\"", "ends (1) before it starts (5)"]);
        refused("a-b", 1, &["\"a-b\"", "\"a\" is not a whole number"]);
        refused("1.5", 1, &["\"1.5\"", "not a whole number"]);
        refused("+3", 1, &["\"+3\"", "not a whole number"]);
        refused("-3", 1, &["\"-3\"", "negative"]);
        refused("5--3", 1, &["\"5--3\"", "range end -3 is negative"]);
        refused("1-9x-2", 1, &["step -2 is negative"]);
        refused("1-9x0", 1, &["\"1-9x0\"", "step must be at least 1"]);
        refused("1-9:0", 1, &["step must be at least 1"]);
        refused("1-9", 0, &["--frame-step 0"]);
        refused("5x2", 1, &["\"5x2\"", "a step needs a range"]);
        refused("5-", 1, &["\"5-\"", "range end is missing"]);
        refused("4294967296", 1, &["larger than 4294967295"]);
        refused("0-999999,1000000-1000000", 1, &[]);
        refused("0-4294967295", 1, &["more than 1000000 frames"]);
        refused("0-999999,0-999999", 1, &["more than 1000000 frames"]);
        assert_eq!(ok("0-999999", 1).len(), 1_000_000);
        assert_eq!(ok("0-1999999", 2).len(), 1_000_000);
    }
}
