//! Image textures: loaded once per file however many materials use them, sampled bilinearly
//! with wrap-around (or clamped) at texture coordinates `(u, v)`, `v` up (OBJ's and, after
//! the loader's flip, glTF's convention: `v = 0` is the image's bottom row).
//!
//! 8-bit colour images (PNG, JPEG, TGA, BMP) are sRGB-encoded: they are kept as bytes (4 a
//! texel) and decoded to linear through a table at each lookup. 16-bit and floating-point
//! images (EXR, Radiance HDR) are linear and kept as `f32`. Data textures (alpha) are never
//! sRGB-decoded.

use glam::{Vec2, Vec3, Vec4};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Arc, OnceLock};

/// The largest texture side accepted: 32768 texels (a 32k × 32k 8-bit image is 4 GiB).
pub const MAX_SIDE: u32 = 32_768;

/// What to do outside `[0, 1)`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Wrap {
    /// Repeat the image (the default of OBJ/MTL and glTF).
    #[default]
    Repeat,
    /// Clamp to the edge texels (MTL `-clamp on`).
    Clamp,
}

/// What an image's values stand for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Encoding {
    /// A colour: 8- and 16-bit values are sRGB-encoded.
    Colour,
    /// Data (normal maps, masks): every value is linear.
    Data,
}

#[derive(Clone, Debug)]
enum Texels {
    /// sRGB-encoded RGBA bytes (alpha linear).
    Srgb8(Vec<[u8; 4]>),
    /// Linear RGBA bytes (`/ 255`).
    Unorm8(Vec<[u8; 4]>),
    /// Linear RGBA.
    Linear(Vec<Vec4>),
}

/// One image, ready to sample.
#[derive(Clone, Debug)]
pub struct Texture {
    pub path: PathBuf,
    width: u32,
    height: u32,
    /// Whether the image has an alpha channel (without one, every texel's alpha is 1).
    has_alpha: bool,
    texels: Texels,
}

/// The sRGB transfer function's inverse for each byte value (IEC 61966-2-1).
fn srgb_table() -> &'static [f32; 256] {
    static TABLE: OnceLock<[f32; 256]> = OnceLock::new();
    TABLE.get_or_init(|| {
        let mut t = [0.0; 256];
        for (i, v) in t.iter_mut().enumerate() {
            let c = i as f64 / 255.0;
            *v = if c <= 0.04045 { c / 12.92 } else { ((c + 0.055) / 1.055).powf(2.4) } as f32;
        }
        t
    })
}

/// The sRGB encoding of a linear value in `[0, 1]` (for writing test images).
pub fn linear_to_srgb(x: f32) -> f32 {
    let x = x.clamp(0.0, 1.0);
    if x <= 0.003_130_8 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

impl Texture {
    /// Loads the image at `path` (any format the `image` crate reads here: PNG, JPEG, TGA, BMP,
    /// EXR, HDR). The error names the file.
    pub fn load(path: &Path) -> Result<Texture, String> {
        Texture::load_as(path, Encoding::Colour)
    }

    /// [`Texture::load`], the values read as `encoding` says.
    pub fn load_as(path: &Path, encoding: Encoding) -> Result<Texture, String> {
        let bytes = std::fs::read(path).map_err(|e| format!("texture {}: {e}", path.display()))?;
        Texture::from_memory_as(path, &bytes, encoding)
    }

    /// Decodes an image held in memory (a glTF's embedded image); `name` stands for its path
    /// in messages. The same formats and encodings as [`Texture::load`].
    pub fn from_memory(name: &Path, bytes: &[u8]) -> Result<Texture, String> {
        Texture::from_memory_as(name, bytes, Encoding::Colour)
    }

    /// [`Texture::from_memory`], the values read as `encoding` says.
    pub fn from_memory_as(name: &Path, bytes: &[u8], encoding: Encoding) -> Result<Texture, String> {
        let reader = image::ImageReader::new(std::io::Cursor::new(bytes))
            .with_guessed_format()
            .map_err(|e| format!("texture {}: {e}", name.display()))?;
        if reader.format().is_none() {
            return Err(format!("texture {}: not an image format photonmap reads", name.display()));
        }
        let (w, h) = reader.into_dimensions().map_err(|e| format!("texture {}: {e}", name.display()))?;
        if w == 0 || h == 0 || w > MAX_SIDE || h > MAX_SIDE {
            return Err(format!(
                "texture {}: {w}x{h} is not a usable size (1 to {MAX_SIDE} texels a side)",
                name.display()
            ));
        }
        let image = image::load_from_memory(bytes).map_err(|e| format!("texture {}: {e}", name.display()))?;
        Ok(Texture::from_image(name, image, encoding))
    }

    fn from_image(path: &Path, image: image::DynamicImage, encoding: Encoding) -> Texture {
        use image::DynamicImage as D;
        let (width, height) = (image.width(), image.height());
        let has_alpha = image.color().has_alpha();
        let texels = match image {
            D::ImageLuma8(_) | D::ImageLumaA8(_) | D::ImageRgb8(_) | D::ImageRgba8(_) => {
                let bytes = image.into_rgba8().pixels().map(|p| p.0).collect();
                match encoding {
                    Encoding::Colour => Texels::Srgb8(bytes),
                    Encoding::Data => Texels::Unorm8(bytes),
                }
            }
            other => {
                // 16-bit PNGs are sRGB-encoded colours like 8-bit ones; float images are linear.
                let float =
                    matches!(other, D::ImageRgb32F(_) | D::ImageRgba32F(_)) || encoding == Encoding::Data;
                Texels::Linear(
                    other
                        .into_rgba32f()
                        .pixels()
                        .map(|p| {
                            let [r, g, b, a] = p.0;
                            let c = Vec3::new(r, g, b);
                            let c = if float { c } else { c.map(srgb_decode) };
                            c.extend(a)
                        })
                        .collect(),
                )
            }
        };
        Texture { path: path.to_owned(), width, height, has_alpha, texels }
    }

    /// A texture of linear RGBA texels, `width × height`, rows from the top (for tests and
    /// generated images).
    pub fn from_linear(path: &Path, width: u32, height: u32, texels: Vec<Vec4>) -> Texture {
        assert_eq!(texels.len(), (width * height) as usize, "texel count");
        Texture { path: path.to_owned(), width, height, has_alpha: true, texels: Texels::Linear(texels) }
    }

    pub fn width(&self) -> u32 {
        self.width
    }

    pub fn height(&self) -> u32 {
        self.height
    }

    /// Bytes the texels take.
    pub fn bytes(&self) -> usize {
        match &self.texels {
            Texels::Srgb8(t) | Texels::Unorm8(t) => t.len() * 4,
            Texels::Linear(t) => t.len() * 16,
        }
    }

    #[inline]
    fn texel(&self, x: u32, y: u32) -> Vec4 {
        let i = (y * self.width + x) as usize;
        match &self.texels {
            Texels::Srgb8(t) => {
                let [r, g, b, a] = t[i];
                let s = srgb_table();
                Vec4::new(s[r as usize], s[g as usize], s[b as usize], a as f32 / 255.0)
            }
            Texels::Unorm8(t) => Vec4::from_array(t[i].map(|c| c as f32 / 255.0)),
            Texels::Linear(t) => t[i],
        }
    }

    /// The four texels around `uv` (top-left, top-right, bottom-left, bottom-right in image
    /// rows, row 0 at `v = 1`) and the position between them.
    #[inline]
    fn cell(&self, uv: Vec2, wrap: Wrap) -> ([Vec4; 4], f32, f32) {
        let (w, h) = (self.width, self.height);
        let u = if uv.x.is_finite() { uv.x } else { 0.0 };
        let v = if uv.y.is_finite() { uv.y } else { 0.0 };
        let x = u * w as f32 - 0.5;
        let y = (1.0 - v) * h as f32 - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let index = |i: f32, n: u32| -> u32 {
            match wrap {
                Wrap::Repeat => (i as i64).rem_euclid(n as i64) as u32,
                Wrap::Clamp => i.clamp(0.0, (n - 1) as f32) as u32,
            }
        };
        let (xa, xb) = (index(x0, w), index(x0 + 1.0, w));
        let (ya, yb) = (index(y0, h), index(y0 + 1.0, h));
        let corners = [self.texel(xa, ya), self.texel(xb, ya), self.texel(xa, yb), self.texel(xb, yb)];
        (corners, x - x0, y - y0)
    }

    /// Linear RGBA at `uv`, bilinearly filtered.
    #[inline]
    pub fn sample(&self, uv: Vec2, wrap: Wrap) -> Vec4 {
        let ([a, b, c, d], fx, fy) = self.cell(uv, wrap);
        a.lerp(b, fx).lerp(c.lerp(d, fx), fy)
    }

    /// The alpha channel at `uv`, bilinearly filtered (linear; 1 for an image without one).
    #[inline]
    pub fn alpha(&self, uv: Vec2, wrap: Wrap) -> f32 {
        self.channel(uv, wrap, 3)
    }

    /// Channel `channel` (0 red … 3 alpha) at `uv`, bilinearly filtered: the same value as that
    /// channel of [`Texture::sample`].
    #[inline]
    pub fn channel(&self, uv: Vec2, wrap: Wrap, channel: usize) -> f32 {
        let ([a, b, c, d], fx, fy) = self.cell(uv, wrap);
        let (a, b, c, d) = (a[channel], b[channel], c[channel], d[channel]);
        let top = a + (b - a) * fx;
        top + (c + (d - c) * fx - top) * fy
    }

    /// Whether the image has an alpha channel ([`Texture::alpha`] is 1 everywhere without).
    pub fn has_alpha(&self) -> bool {
        self.has_alpha
    }

    /// The smallest and largest value of channel `channel` (0 red … 3 alpha) over the texels:
    /// the bounds of what bilinear filtering returns anywhere.
    pub fn channel_range(&self, channel: usize) -> (f32, f32) {
        let mut range = (f32::INFINITY, f32::NEG_INFINITY);
        for y in 0..self.height {
            for x in 0..self.width {
                let c = self.texel(x, y)[channel];
                range = (range.0.min(c), range.1.max(c));
            }
        }
        range
    }

    /// The bilinear filter's derivatives at `uv`, `(d/du, d/dv)` per channel: the exact slopes of
    /// what [`Texture::sample`] returns, constant across each texel cell (for bump mapping).
    #[inline]
    pub fn gradient(&self, uv: Vec2, wrap: Wrap) -> (Vec4, Vec4) {
        let ([a, b, c, d], fx, fy) = self.cell(uv, wrap);
        let d_dx = (b - a).lerp(d - c, fy);
        let d_dy = c.lerp(d, fx) - a.lerp(b, fx);
        // x = u w - 1/2 and y = (1 - v) h - 1/2.
        (d_dx * self.width as f32, d_dy * -(self.height as f32))
    }

    /// Whether every texel is grey (red, green and blue equal): a height map, not a normal map.
    pub fn is_grey(&self) -> bool {
        (0..self.height).all(|y| {
            (0..self.width).all(|x| {
                let t = self.texel(x, y);
                t.x == t.y && t.y == t.z
            })
        })
    }

    /// The mean linear RGB over the image.
    pub fn mean(&self) -> Vec3 {
        let n = (self.width * self.height) as f64;
        let mut sum = glam::DVec3::ZERO;
        for y in 0..self.height {
            for x in 0..self.width {
                sum += self.texel(x, y).truncate().as_dvec3();
            }
        }
        (sum / n).as_vec3()
    }
}

/// The sRGB decoding of a value in `[0, 1]`.
pub fn srgb_decode(c: f32) -> f32 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// The textures of a scene, each file loaded once.
#[derive(Clone, Debug, Default)]
pub struct Textures {
    /// Shared, so that what outlives the scene's borrow (alpha cut-outs) can hold them.
    pub list: Vec<Arc<Texture>>,
    by_path: HashMap<(PathBuf, Encoding), u32>,
}

impl Textures {
    /// The index of the texture at `path`, loading it the first time it is asked for.
    pub fn get_or_load(&mut self, path: &Path) -> Result<u32, String> {
        self.get_or_load_as(path, Encoding::Colour)
    }

    /// [`Textures::get_or_load`] for an image of `encoding` (a file read both ways is two
    /// textures).
    pub fn get_or_load_as(&mut self, path: &Path, encoding: Encoding) -> Result<u32, String> {
        let key = (std::fs::canonicalize(path).unwrap_or_else(|_| path.to_owned()), encoding);
        if let Some(&i) = self.by_path.get(&key) {
            return Ok(i);
        }
        let t = Texture::load_as(path, encoding)?;
        let i = self.list.len() as u32;
        self.list.push(Arc::new(t));
        self.by_path.insert(key, i);
        Ok(i)
    }

    /// Adds an already-made texture.
    pub fn push(&mut self, t: Texture) -> u32 {
        self.list.push(Arc::new(t));
        (self.list.len() - 1) as u32
    }

    #[inline]
    pub fn get(&self, i: u32) -> &Texture {
        &self.list[i as usize]
    }

    pub fn is_empty(&self) -> bool {
        self.list.is_empty()
    }

    /// Bytes all the texels take.
    pub fn bytes(&self) -> usize {
        self.list.iter().map(|t| t.bytes()).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn checker() -> Texture {
        // 2 × 2: black, white / white, black (rows from the top).
        let (b, w) = (Vec4::new(0.0, 0.0, 0.0, 1.0), Vec4::ONE);
        Texture::from_linear(Path::new("checker"), 2, 2, vec![b, w, w, b])
    }

    #[test]
    fn bilinear_wraps_and_clamps() {
        let t = checker();
        // Texel centres.
        assert_eq!(t.sample(Vec2::new(0.25, 0.75), Wrap::Repeat).x, 0.0);
        assert_eq!(t.sample(Vec2::new(0.75, 0.75), Wrap::Repeat).x, 1.0);
        assert_eq!(t.sample(Vec2::new(0.25, 0.25), Wrap::Repeat).x, 1.0);
        // Halfway between two centres.
        assert!((t.sample(Vec2::new(0.5, 0.75), Wrap::Repeat).x - 0.5).abs() < 1e-6);
        // Wrapping: u = 1.25 is u = 0.25; u = 0 sits between the last and the first column.
        assert_eq!(
            t.sample(Vec2::new(1.25, 0.75), Wrap::Repeat),
            t.sample(Vec2::new(0.25, 0.75), Wrap::Repeat)
        );
        assert_eq!(
            t.sample(Vec2::new(-0.75, 0.75), Wrap::Repeat),
            t.sample(Vec2::new(0.25, 0.75), Wrap::Repeat)
        );
        assert!((t.sample(Vec2::new(0.0, 0.75), Wrap::Repeat).x - 0.5).abs() < 1e-6);
        assert_eq!(t.sample(Vec2::new(0.0, 0.75), Wrap::Clamp).x, 0.0);
        assert_eq!(
            t.sample(Vec2::new(f32::NAN, 0.75), Wrap::Repeat),
            t.sample(Vec2::new(0.0, 0.75), Wrap::Repeat)
        );
        assert!((t.mean().x - 0.5).abs() < 1e-6);
    }

    #[test]
    fn the_gradient_is_the_slope_of_the_bilinear_filter() {
        let texels = (0..12).map(|i| Vec4::splat(((i * 7) % 5) as f32 * 0.3)).collect();
        let t = Texture::from_linear(Path::new("g"), 4, 3, texels);
        for k in 0..50 {
            let uv = Vec2::new((k as f32 * 0.1237).fract(), (k as f32 * 0.3719).fract());
            let (du, dv) = t.gradient(uv, Wrap::Repeat);
            let h = 1e-3;
            let fd =
                |e: Vec2| (t.sample(uv + e, Wrap::Repeat) - t.sample(uv - e, Wrap::Repeat)).x / (2.0 * h);
            let (fu, fv) = (fd(Vec2::new(h, 0.0)), fd(Vec2::new(0.0, h)));
            // Away from cell edges (where the slope jumps) the finite difference is exact.
            let x = uv.x * 4.0 - 0.5;
            let y = (1.0 - uv.y) * 3.0 - 0.5;
            let near_edge = |c: f32, n: f32| (c - c.round()).abs() < h * n * 2.0;
            if !near_edge(x, 4.0) && !near_edge(y, 3.0) {
                assert!((du.x - fu).abs() < 2e-2, "d/du at {uv}: {} vs {fu}", du.x);
                assert!((dv.x - fv).abs() < 2e-2, "d/dv at {uv}: {} vs {fv}", dv.x);
            }
        }
        // A constant image has no slope anywhere, exactly.
        let flat = Texture::from_linear(Path::new("f"), 2, 2, vec![Vec4::splat(0.7); 4]);
        assert_eq!(flat.gradient(Vec2::new(0.3, 0.9), Wrap::Repeat), (Vec4::ZERO, Vec4::ZERO));
    }

    #[test]
    fn srgb_bytes_decode_to_linear() {
        let table = srgb_table();
        assert_eq!(table[0], 0.0);
        assert_eq!(table[255], 1.0);
        // sRGB 188 is linear 0.5029 (the nearest byte to 0.5).
        assert!((table[188] - 0.5029).abs() < 1e-3, "{}", table[188]);
        for i in 0..=255u8 {
            let back = (linear_to_srgb(table[i as usize]) * 255.0).round() as u8;
            assert_eq!(back, i);
        }
    }

    #[test]
    fn files_load_once_and_bad_ones_are_named() {
        let dir = tempfile::tempdir().unwrap();
        let png = dir.path().join("grey.png");
        image::RgbImage::from_pixel(3, 2, image::Rgb([188, 188, 188])).save(&png).unwrap();
        let mut set = Textures::default();
        let a = set.get_or_load(&png).unwrap();
        let b = set.get_or_load(&dir.path().join(".").join("grey.png")).unwrap();
        assert_eq!((a, b, set.list.len()), (0, 0, 1));
        let t = set.get(a);
        assert_eq!((t.width(), t.height(), t.bytes()), (3, 2, 24));
        assert!((t.sample(Vec2::new(0.3, 0.9), Wrap::Repeat).x - srgb_table()[188]).abs() < 1e-6);
        let bad = dir.path().join("bad.png");
        std::fs::write(&bad, b"not a png at all").unwrap();
        let e = set.get_or_load(&bad).unwrap_err();
        assert!(e.contains("bad.png"), "{e}");
        let e = set.get_or_load(&dir.path().join("missing.png")).unwrap_err();
        assert!(e.contains("missing.png"), "{e}");
    }
}
