//! The film: a float RGB image of mean radiance per pixel, written as OpenEXR (float32 R, G, B,
//! row 0 at the top) and as an 8-bit sRGB PNG preview ([`Tonemap`]: an exposure, a tone curve,
//! then the sRGB transfer curve). Files are written atomically: to a temporary file beside the
//! target, then renamed over it, so an existing image is only ever replaced by a complete new one.

pub mod partial;
pub mod sums;
pub mod windows;

use glam::Vec3;
use std::path::{Path, PathBuf};

/// A `width × height` RGB image, row-major from the top-left pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct Film {
    pub width: usize,
    pub height: usize,
    pub pixels: Vec<Vec3>,
}

/// Why an image could not be read or written.
#[derive(Debug, thiserror::Error)]
pub enum ImageError {
    #[error("{}: {source}", path.display())]
    Io { path: PathBuf, source: std::io::Error },
    #[error("{}: {message}", path.display())]
    Format { path: PathBuf, message: String },
}

impl Film {
    pub fn new(width: usize, height: usize) -> Self {
        Film { width, height, pixels: vec![Vec3::ZERO; width * height] }
    }

    #[inline]
    pub fn get(&self, x: usize, y: usize) -> Vec3 {
        self.pixels[y * self.width + x]
    }

    /// Number of pixels with a NaN or infinite channel.
    pub fn nonfinite_count(&self) -> usize {
        self.pixels.iter().filter(|p| !p.is_finite()).count()
    }

    /// Mean over all pixels and channels.
    pub fn mean(&self) -> f64 {
        let sum: f64 = self.pixels.iter().map(|p| p.x as f64 + p.y as f64 + p.z as f64).sum();
        sum / (3 * self.pixels.len()).max(1) as f64
    }

    /// Box-downsamples by an integer `factor` (each output pixel is the mean of a block).
    pub fn downsample(&self, factor: usize) -> Film {
        assert!(
            factor >= 1 && self.width % factor == 0 && self.height % factor == 0,
            "factor must divide the size"
        );
        let (w, h) = (self.width / factor, self.height / factor);
        let mut out = Film::new(w, h);
        for y in 0..h {
            for x in 0..w {
                let mut sum = Vec3::ZERO;
                for dy in 0..factor {
                    for dx in 0..factor {
                        sum += self.get(x * factor + dx, y * factor + dy);
                    }
                }
                out.pixels[y * w + x] = sum / (factor * factor) as f32;
            }
        }
        out
    }

    /// The pixels `x0 <= x < x1`, `y0 <= y < y1` as a film of their own.
    ///
    /// # Panics
    /// If the rectangle is empty or does not lie within the film.
    pub fn crop(&self, x0: usize, y0: usize, x1: usize, y1: usize) -> Film {
        assert!(x0 < x1 && x1 <= self.width && y0 < y1 && y1 <= self.height, "a crop within the film");
        let mut out = Film::new(x1 - x0, y1 - y0);
        for y in y0..y1 {
            for x in x0..x1 {
                out.pixels[(y - y0) * out.width + (x - x0)] = self.get(x, y);
            }
        }
        out
    }

    /// Writes float32 RGB OpenEXR atomically.
    pub fn write_exr(&self, path: &Path) -> Result<(), ImageError> {
        self.write_exr_with(path, &[])
    }

    /// Writes float32 RGB OpenEXR atomically, with `meta` as text attributes of the header
    /// (how the image was made: [`read_exr_meta`](Film::read_exr_meta) reads them back).
    pub fn write_exr_with(&self, path: &Path, meta: &[(&str, String)]) -> Result<(), ImageError> {
        use exr::prelude::*;
        atomic_write(path, |tmp| {
            let channels = SpecificChannels::rgb(|Vec2(x, y): Vec2<usize>| {
                let p = self.get(x, y);
                (p.x, p.y, p.z)
            });
            let mut image = Image::from_channels((self.width, self.height), channels);
            for (name, value) in meta {
                image
                    .layer_data
                    .attributes
                    .other
                    .insert(Text::from(*name), AttributeValue::Text(Text::from(value.as_str())));
            }
            image.write().to_file(tmp).map_err(|e| e.to_string())
        })
    }

    /// [`write_exr_with`](Film::write_exr_with), and with `error` a fourth float32 channel
    /// `error` holding its first channel (the per-pixel estimated error,
    /// [`sums::PassSums::error_film`]).
    pub fn write_exr_with_error(
        &self,
        path: &Path,
        meta: &[(&str, String)],
        error: Option<&Film>,
    ) -> Result<(), ImageError> {
        use exr::prelude::*;
        let Some(error) = error else { return self.write_exr_with(path, meta) };
        let mut channels: SmallVec<[AnyChannel<FlatSamples>; 4]> = SmallVec::new();
        for (c, name) in ["R", "G", "B"].into_iter().enumerate() {
            channels
                .push(AnyChannel::new(name, FlatSamples::F32(self.pixels.iter().map(|p| p[c]).collect())));
        }
        channels.push(AnyChannel::new("error", FlatSamples::F32(error.pixels.iter().map(|p| p.x).collect())));
        let mut attributes = LayerAttributes::default();
        for (name, value) in meta {
            attributes.other.insert(Text::from(*name), AttributeValue::Text(Text::from(value.as_str())));
        }
        let layer = Layer::new(
            (self.width, self.height),
            attributes,
            Encoding::default(),
            AnyChannels::sort(channels),
        );
        atomic_write(path, |tmp| Image::from_layer(layer).write().to_file(tmp).map_err(|e| e.to_string()))
    }

    /// The text attributes of an OpenEXR file's header (those [`write_exr_with`](Film::write_exr_with)
    /// wrote, among others), without reading its pixels.
    pub fn read_exr_meta(path: &Path) -> Result<std::collections::BTreeMap<String, String>, ImageError> {
        let meta = exr::meta::MetaData::read_from_file(path, false).map_err(|e| exr_error(path, e))?;
        let mut out = std::collections::BTreeMap::new();
        for header in &meta.headers {
            for (name, value) in header.shared_attributes.other.iter().chain(&header.own_attributes.other) {
                if let exr::meta::attribute::AttributeValue::Text(text) = value {
                    out.insert(name.to_string(), text.to_string());
                }
            }
        }
        Ok(out)
    }

    /// Writes an 8-bit sRGB PNG preview (radiance clamped to [0, 1], sRGB transfer curve)
    /// atomically.
    pub fn write_png(&self, path: &Path) -> Result<(), ImageError> {
        self.write_png_with(path, Tonemap::default())
    }

    /// Writes an 8-bit sRGB PNG preview of the radiance mapped by `tonemap`, atomically.
    pub fn write_png_with(&self, path: &Path, tonemap: Tonemap) -> Result<(), ImageError> {
        let bytes: Vec<u8> =
            self.pixels.iter().flat_map(|p| tonemap.apply(*p).to_array().map(srgb8)).collect();
        atomic_write(path, |tmp| {
            let file = std::fs::File::create(tmp).map_err(|e| e.to_string())?;
            let mut enc =
                png::Encoder::new(std::io::BufWriter::new(file), self.width as u32, self.height as u32);
            enc.set_color(png::ColorType::Rgb);
            enc.set_depth(png::BitDepth::Eight);
            let mut w = enc.write_header().map_err(|e| e.to_string())?;
            w.write_image_data(&bytes).map_err(|e| e.to_string())?;
            w.finish().map_err(|e| e.to_string())
        })
    }

    /// Reads the first RGB(A) layer of an OpenEXR file.
    pub fn read_exr(path: &Path) -> Result<Film, ImageError> {
        let image = exr::prelude::read_first_rgba_layer_from_file(
            path,
            |size, _| Film::new(size.width(), size.height()),
            |film: &mut Film, pos, (r, g, b, _a): (f32, f32, f32, f32)| {
                let w = film.width;
                film.pixels[pos.y() * w + pos.x()] = Vec3::new(r, g, b);
            },
        )
        .map_err(|e| exr_error(path, e))?;
        Ok(image.layer_data.channel_data.pixels)
    }
}

/// Why `path` could not be read as OpenEXR: the file system's error, "not an OpenEXR file" when
/// it lacks the format's magic number (a PNG given to `compare`), else the decoder's message.
fn exr_error(path: &Path, e: exr::error::Error) -> ImageError {
    use std::io::Read;
    const MAGIC: [u8; 4] = [0x76, 0x2f, 0x31, 0x01];
    let mut head = [0u8; 4];
    let opened = std::fs::File::open(path).and_then(|mut f| f.read_exact(&mut head));
    match (opened, e) {
        (Err(source), _) if source.kind() != std::io::ErrorKind::UnexpectedEof => {
            ImageError::Io { path: path.to_owned(), source }
        }
        (_, _) if head != MAGIC => {
            ImageError::Format { path: path.to_owned(), message: "not an OpenEXR file".into() }
        }
        (_, exr::error::Error::Io(source)) => ImageError::Io { path: path.to_owned(), source },
        (_, e) => ImageError::Format { path: path.to_owned(), message: format!("damaged OpenEXR file: {e}") },
    }
}

crate::choice! {
    /// How a preview maps scene radiance (after the exposure) to display values in [0, 1].
    pub enum ToneCurve {
        /// Clamped at 1: exact below 1, every brighter value white.
        Clamp = "clamp",
        /// John Hable's filmic curve (Uncharted 2), white at 11.2, with his exposure bias of 2:
        /// a toe for the shadows and a long shoulder that keeps highlights from clipping.
        Filmic = "filmic",
        /// Krzysztof Narkowicz's fit of the ACES reference and output transforms (input × 0.6):
        /// more contrast than filmic, white reached at about 16.
        Aces = "aces",
    }
}

/// What an 8-bit preview shows of the linear radiance: `2^exposure` times it, through `curve`.
/// The EXR is always the linear radiance itself.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tonemap {
    /// Exposure in stops (EV): +1 doubles the radiance before the curve.
    pub exposure: f32,
    pub curve: ToneCurve,
}

impl Default for Tonemap {
    fn default() -> Self {
        Tonemap { exposure: 0.0, curve: ToneCurve::Clamp }
    }
}

impl Tonemap {
    /// The display value (linear, in [0, 1]) of radiance `v`; non-finite channels give 0.
    pub fn apply(&self, v: Vec3) -> Vec3 {
        let scale = self.exposure.exp2();
        let curve = |x: f32| -> f32 {
            let x = if x.is_finite() { (x * scale).max(0.0) } else { 0.0 };
            match self.curve {
                ToneCurve::Clamp => x.min(1.0),
                ToneCurve::Filmic => {
                    let f = |x: f32| {
                        let (a, b, c, d, e, f) = (0.15, 0.50, 0.10, 0.20, 0.02, 0.30);
                        (x * (a * x + c * b) + d * e) / (x * (a * x + b) + d * f) - e / f
                    };
                    // f(0) is 0 but rounds to 1e-8: black stays black.
                    if x == 0.0 {
                        0.0
                    } else {
                        (f(2.0 * x) / f(11.2)).clamp(0.0, 1.0)
                    }
                }
                ToneCurve::Aces => {
                    let x = 0.6 * x;
                    let (a, b, c, d, e) = (2.51, 0.03, 2.43, 0.59, 0.14);
                    ((x * (a * x + b)) / (x * (c * x + d) + e)).clamp(0.0, 1.0)
                }
            }
        };
        Vec3::new(curve(v.x), curve(v.y), curve(v.z))
    }
}

/// sRGB transfer curve of a linear value clamped to [0, 1], to 8 bits.
fn srgb8(v: f32) -> u8 {
    let v = if v.is_finite() { v.clamp(0.0, 1.0) } else { 0.0 };
    let s = if v <= 0.003_130_8 { 12.92 * v } else { 1.055 * v.powf(1.0 / 2.4) - 0.055 };
    (s * 255.0 + 0.5) as u8
}

/// Runs `write` on a temporary path in the target's directory, then renames it over `path`.
/// On failure the temporary file is removed and `path` is left untouched.
fn atomic_write(path: &Path, write: impl FnOnce(&Path) -> Result<(), String>) -> Result<(), ImageError> {
    let name = path
        .file_name()
        .ok_or_else(|| ImageError::Format { path: path.to_owned(), message: "not a file name".into() })?;
    let mut tmp_name = std::ffi::OsString::from(".");
    tmp_name.push(name);
    tmp_name.push(format!(".{}.tmp", std::process::id()));
    let tmp = path.with_file_name(tmp_name);
    let result = write(&tmp).map_err(|message| ImageError::Format { path: path.to_owned(), message });
    let result = result.and_then(|_| {
        std::fs::rename(&tmp, path).map_err(|source| ImageError::Io { path: path.to_owned(), source })
    });
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// Error of `a` against reference `b`: RMSE over all pixels and channels, and relative MSE
/// `mean((a - b)^2 / (b^2 + 0.01))` (the metric of `scenes/SCENES.md`).
pub fn compare(a: &Film, b: &Film) -> Option<(f64, f64)> {
    if a.width != b.width || a.height != b.height {
        return None;
    }
    let (mut se, mut rel) = (0.0f64, 0.0f64);
    for (p, q) in a.pixels.iter().zip(&b.pixels) {
        for c in 0..3 {
            let (x, r) = (p[c] as f64, q[c] as f64);
            se += (x - r) * (x - r);
            rel += (x - r) * (x - r) / (r * r + 0.01);
        }
    }
    let n = (3 * a.pixels.len()) as f64;
    Some(((se / n).sqrt(), rel / n))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tone_curves_are_monotone_bounded_and_exposure_is_in_stops() {
        for curve in [ToneCurve::Clamp, ToneCurve::Filmic, ToneCurve::Aces] {
            let t = Tonemap { exposure: 0.0, curve };
            let mut last = -1.0;
            for i in 0..=2000 {
                let x = i as f32 * 0.01;
                let y = t.apply(Vec3::splat(x)).x;
                assert!((0.0..=1.0).contains(&y) && y >= last, "{curve:?} at {x}: {y} after {last}");
                last = y;
            }
            assert_eq!(t.apply(Vec3::ZERO), Vec3::ZERO, "{curve:?}");
            assert_eq!(t.apply(Vec3::new(f32::NAN, f32::INFINITY, -1.0)), Vec3::ZERO, "{curve:?}");
            let up = Tonemap { exposure: 1.0, curve };
            assert_eq!(up.apply(Vec3::splat(0.1)), t.apply(Vec3::splat(0.2)), "{curve:?}");
        }
        // The filmic and ACES curves keep highlights apart that clamping makes white.
        for curve in [ToneCurve::Filmic, ToneCurve::Aces] {
            let t = Tonemap { exposure: 0.0, curve };
            assert!(t.apply(Vec3::splat(4.0)).x < t.apply(Vec3::splat(8.0)).x - 0.02, "{curve:?}");
            assert!(t.apply(Vec3::splat(0.18)).x > 0.05, "{curve:?} crushes mid-grey");
        }
        let clamp = Tonemap::default();
        assert_eq!(clamp.apply(Vec3::new(0.5, 2.0, 0.25)), Vec3::new(0.5, 1.0, 0.25));
    }

    #[test]
    fn exr_round_trip_is_exact_and_atomic() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.exr");
        let mut f = Film::new(5, 3);
        for (i, p) in f.pixels.iter_mut().enumerate() {
            *p = Vec3::new(i as f32, 0.5 * i as f32, 1e-3);
        }
        f.write_exr(&path).unwrap();
        assert_eq!(Film::read_exr(&path).unwrap(), f);
        // Only the final file is left behind.
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
        f.write_png(&dir.path().join("a.png")).unwrap();
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 2);
        // Text attributes come back as written, and the pixels are unchanged by them.
        let meta = [("photonmap.frame", "7".to_string()), ("photonmap.camera", "front".to_string())];
        f.write_exr_with(&path, &meta).unwrap();
        let read = Film::read_exr_meta(&path).unwrap();
        assert_eq!(read.get("photonmap.frame").map(String::as_str), Some("7"));
        assert_eq!(read.get("photonmap.camera").map(String::as_str), Some("front"));
        assert_eq!(Film::read_exr(&path).unwrap(), f);
    }

    #[test]
    fn failed_write_leaves_the_old_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.exr");
        std::fs::write(&path, b"old").unwrap();
        let r = atomic_write(&path, |_| Err("boom".into()));
        assert!(r.is_err());
        assert_eq!(std::fs::read(&path).unwrap(), b"old");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    #[test]
    fn metrics_and_downsampling() {
        let mut a = Film::new(2, 2);
        let b = Film::new(2, 2);
        a.pixels[0] = Vec3::splat(2.0);
        let (rmse, _) = compare(&a, &b).unwrap();
        assert!((rmse - 1.0).abs() < 1e-12);
        assert_eq!(a.downsample(2).pixels[0], Vec3::splat(0.5));
        assert_eq!(srgb8(1.0), 255);
        assert_eq!(srgb8(f32::NAN), 0);
    }
}
