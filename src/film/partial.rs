//! The partial film: what `photonmap render --pass-range A..B` writes, the exact sums of passes
//! `A..B` of an `N`-pass render ([`PassSums`]) as an OpenEXR file, for `photonmap merge` to add
//! up with the other ranges.
//!
//! One layer: `R`, `G`, `B` (float32) hold the image of the part's own passes
//! ([`PassSums::mean`]), so that any EXR viewer shows it; every sum of [`WORD_NAMES`] is four
//! `uint32` channels `NAME.0` … `NAME.3`, the little-endian words of its `i128` (fixed point,
//! 2⁻⁶⁰: see [`super::sums`]). The header
//! says what it is (`photonmap.kind`), its passes (`photonmap.pass_range`, of
//! `photonmap.passes`), what its passes say of their bias (`photonmap.bias`), and carries the
//! image record the caller gives (scene and settings hashes, camera, frame, version).

use super::sums::{Bias, PassSums, WORDS, WORD_NAMES};
use super::{atomic_write, exr_error, ImageError};
use std::collections::BTreeMap;
use std::ops::Range;
use std::path::Path;

pub const KIND: &str = "photonmap.kind";
pub const PARTIAL: &str = "partial film";
pub const PASS_RANGE: &str = "photonmap.pass_range";
pub const PASSES: &str = "photonmap.passes";
pub const BIAS: &str = "photonmap.bias";
pub const FIXED_POINT: &str = "photonmap.fixed_point";
const FIXED_POINT_VALUE: &str = "i128, 2^-60";

/// Passes `range` of a render of `total` passes, summed.
#[derive(Clone, Debug)]
pub struct PartialFilm {
    pub sums: PassSums,
    pub range: Range<u32>,
    pub total: u32,
    /// Every text attribute of the header (the caller's record among them).
    pub attributes: BTreeMap<String, String>,
}

impl PartialFilm {
    /// Writes `sums`, passes `range` of `total`, with `record` in the header, atomically.
    pub fn write(
        path: &Path,
        sums: &PassSums,
        range: Range<u32>,
        total: u32,
        record: &[(&str, String)],
    ) -> Result<(), ImageError> {
        use exr::prelude::*;
        let (w, h) = (sums.width, sums.height);
        let mean = sums.mean();
        let mut channels: SmallVec<[AnyChannel<FlatSamples>; 4]> = SmallVec::new();
        for (c, name) in ["R", "G", "B"].into_iter().enumerate() {
            let values = mean.pixels.iter().map(|p| p[c]).collect();
            channels.push(AnyChannel::new(name, FlatSamples::F32(values)));
        }
        for (k, name) in WORD_NAMES.iter().enumerate() {
            for word in 0..4 {
                let values = sums.values.iter().map(|v| (v[k] as u128 >> (32 * word)) as u32).collect();
                channels.push(AnyChannel::new(format!("{name}.{word}").as_str(), FlatSamples::U32(values)));
            }
        }
        let mut attributes = LayerAttributes::default();
        let header: Vec<(&str, String)> = [
            (KIND, PARTIAL.to_string()),
            (PASS_RANGE, format!("{}..{}", range.start, range.end)),
            (PASSES, total.to_string()),
            (BIAS, sums.bias.name().to_string()),
            (FIXED_POINT, FIXED_POINT_VALUE.to_string()),
        ]
        .into_iter()
        .chain(record.iter().cloned())
        .collect();
        for (name, value) in &header {
            attributes.other.insert(Text::from(*name), AttributeValue::Text(Text::from(value.as_str())));
        }
        let layer = Layer::new((w, h), attributes, Encoding::SMALL_LOSSLESS, AnyChannels::sort(channels));
        atomic_write(path, |tmp| Image::from_layer(layer).write().to_file(tmp).map_err(|e| e.to_string()))
    }

    /// Reads what a partial film's header says (not its pixels), checking it is one.
    pub fn read_header(path: &Path) -> Result<PartHeader, ImageError> {
        let bad = |message: String| ImageError::Format { path: path.to_owned(), message };
        let meta = exr::meta::MetaData::read_from_file(path, false).map_err(|e| exr_error(path, e))?;
        let header = meta.headers.first().ok_or_else(|| bad("no image in the file".into()))?;
        let mut attributes = BTreeMap::new();
        for (name, value) in header.shared_attributes.other.iter().chain(&header.own_attributes.other) {
            if let exr::meta::attribute::AttributeValue::Text(text) = value {
                attributes.insert(name.to_string(), text.to_string());
            }
        }
        let get = |key: &str| {
            attributes.get(key).ok_or_else(|| bad(format!("not a partial film (no {key} in its header)")))
        };
        if get(KIND)? != PARTIAL {
            return Err(bad(format!("not a partial film ({KIND} is {})", get(KIND)?)));
        }
        if get(FIXED_POINT)? != FIXED_POINT_VALUE {
            return Err(bad(format!("sums in another form ({FIXED_POINT} {})", get(FIXED_POINT)?)));
        }
        let range_text = get(PASS_RANGE)?;
        let range = parse_range(range_text)
            .ok_or_else(|| bad(format!("{PASS_RANGE} {range_text} is not a range A..B with A < B")))?;
        let total_text = get(PASSES)?;
        let total: u32 =
            total_text.parse().map_err(|_| bad(format!("{PASSES} {total_text} is not a count")))?;
        if range.end > total {
            return Err(bad(format!("passes {range_text} are not within the render's {total}")));
        }
        let bias_text = get(BIAS)?;
        let bias = Bias::from_name(bias_text).ok_or_else(|| bad(format!("{BIAS} {bias_text} unknown")))?;
        let size = header.layer_size;
        Ok(PartHeader { range, total, bias, width: size.width(), height: size.height(), attributes })
    }

    /// Reads a partial film, checking it is one and whole.
    pub fn read(path: &Path) -> Result<PartialFilm, ImageError> {
        use exr::prelude::*;
        let bad = |message: String| ImageError::Format { path: path.to_owned(), message };
        let PartHeader { range, total, bias, width: w, height: h, attributes } = Self::read_header(path)?;
        let image = read()
            .no_deep_data()
            .largest_resolution_level()
            .all_channels()
            .first_valid_layer()
            .all_attributes()
            .from_file(path)
            .map_err(|e| exr_error(path, e))?;
        let layer = &image.layer_data;
        if (layer.size.width(), layer.size.height()) != (w, h) {
            return Err(bad(format!(
                "its pixels are {}x{}, its header says {w}x{h}",
                layer.size.width(),
                layer.size.height()
            )));
        }
        let mut sums = PassSums::new(w, h, bias);
        sums.passes = range.len() as u32;
        (sums.first_passes, sums.quarter_passes) = PassSums::batch_counts(range.clone(), total);
        for (k, name) in WORD_NAMES.iter().enumerate() {
            for word in 0..4 {
                let channel_name = format!("{name}.{word}");
                let channel = layer
                    .channel_data
                    .list
                    .iter()
                    .find(|c| c.name.to_string() == channel_name)
                    .ok_or_else(|| bad(format!("no channel {channel_name}")))?;
                let FlatSamples::U32(values) = &channel.sample_data else {
                    return Err(bad(format!("channel {channel_name} is not uint32")));
                };
                if values.len() != w * h {
                    return Err(bad(format!(
                        "channel {channel_name} has {} samples for {w}x{h}",
                        values.len()
                    )));
                }
                for (v, &x) in sums.values.iter_mut().zip(values) {
                    v[k] = (v[k] as u128 | (x as u128) << (32 * word)) as i128;
                }
            }
        }
        debug_assert_eq!(WORD_NAMES.len(), WORDS);
        Ok(PartialFilm { sums, range, total, attributes })
    }
}

/// What a partial film's header says: its passes, of how many, what its passes know of their
/// bias, its size, and every text attribute (the render's record among them).
#[derive(Clone, Debug)]
pub struct PartHeader {
    pub range: Range<u32>,
    pub total: u32,
    pub bias: Bias,
    pub width: usize,
    pub height: usize,
    pub attributes: BTreeMap<String, String>,
}

/// `A..B` with `A < B`.
pub fn parse_range(text: &str) -> Option<Range<u32>> {
    let (a, b) = text.split_once("..")?;
    let (a, b): (u32, u32) = (a.trim().parse().ok()?, b.trim().parse().ok()?);
    (a < b).then_some(a..b)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::film::Film;
    use glam::Vec3;

    #[test]
    fn a_partial_film_reads_back_as_written() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("part.exr");
        let mut sums = PassSums::new(3, 2, Bias::Probed);
        for i in 0..3 {
            let film = Film {
                width: 3,
                height: 2,
                pixels: (0..6).map(|p| Vec3::splat(p as f32 * 1e5 - i as f32)).collect(),
            };
            let probe = Film { pixels: film.pixels.iter().map(|p| -*p * 1e-9).collect(), ..film.clone() };
            // Of passes 4..7 of 10, pass 4 alone is in the first half, 5 and 6 in the third quarter.
            sums.add_pass(&film, Some(&probe), Some(PassSums::quarter(4 + i, 10)));
        }
        PartialFilm::write(&path, &sums, 4..7, 10, &[("photonmap.scene_hash", "00ff".into())]).unwrap();
        let back = PartialFilm::read(&path).unwrap();
        assert_eq!(back.sums, sums);
        assert_eq!((back.range, back.total), (4..7, 10));
        assert_eq!(back.attributes["photonmap.scene_hash"], "00ff");
        // Any viewer sees the part's mean.
        assert_eq!(Film::read_exr(&path).unwrap(), sums.mean());
        // A plain image is refused, named.
        let plain = dir.path().join("plain.exr");
        sums.mean().write_exr(&plain).unwrap();
        let e = PartialFilm::read(&plain).unwrap_err().to_string();
        assert!(e.contains("plain.exr") && e.contains("not a partial film"), "{e}");
    }

    #[test]
    fn ranges_parse() {
        assert_eq!(parse_range("0..4"), Some(0..4));
        assert_eq!(parse_range("4..4"), None);
        assert_eq!(parse_range("5..1"), None);
        assert_eq!(parse_range("a..b"), None);
        assert_eq!(parse_range("3"), None);
    }
}
