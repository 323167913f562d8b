//! A glTF file's binary data: its buffers (the GLB's binary chunk, files beside it, base64
//! `data:` URIs) and the accessors that read them (glTF 2.0 §3.6), read here rather than
//! through the `gltf` crate's reader so that every byte range is checked (with checked
//! arithmetic) and a bad one named by its JSON path instead of panicking or coming back short.

use super::super::obj::relative_to;
use super::super::SceneError;
use gltf::accessor::{DataType, Dimensions};
use gltf::Document;
use std::path::Path;

/// The most elements an accessor without a buffer view (all zeros, or sparse) may have.
const MAX_VIEWLESS: usize = 1 << 22;

/// Every buffer's bytes, by index.
pub struct Buffers(pub Vec<Vec<u8>>);

/// An error at the JSON path `at` of `path`.
pub fn at(path: &Path, at: impl Into<String>, message: impl Into<String>) -> SceneError {
    SceneError::Json { path: path.to_owned(), at: at.into(), message: message.into() }
}

impl Buffers {
    /// Loads every buffer of `doc`; `blob` is the GLB's binary chunk.
    pub fn load(path: &Path, doc: &Document, blob: Option<Vec<u8>>) -> Result<Buffers, SceneError> {
        let mut blob = blob;
        let mut out = Vec::new();
        for b in doc.buffers() {
            let field = format!("buffers[{}]", b.index());
            let data = match b.source() {
                gltf::buffer::Source::Bin => blob.take().ok_or_else(|| {
                    at(path, &field, "no uri, and no GLB binary chunk (or one already used) to stand for it")
                })?,
                gltf::buffer::Source::Uri(uri) => uri_bytes(path, &format!("{field}.uri"), uri)?,
            };
            if data.len() < b.length() {
                return Err(at(
                    path,
                    format!("{field}.byteLength"),
                    format!("{} bytes, but the data has only {}", b.length(), data.len()),
                ));
            }
            out.push(data);
        }
        Ok(Buffers(out))
    }
}

/// The bytes a URI stands for: a `data:` URI's payload, or the file it names relative to `path`.
pub fn uri_bytes(path: &Path, field: &str, uri: &str) -> Result<Vec<u8>, SceneError> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let (head, payload) =
            rest.split_once(',').ok_or_else(|| at(path, field, "a data URI without a comma"))?;
        if !head.ends_with(";base64") {
            return Err(at(path, field, "a data URI that is not base64 (only base64 is read)"));
        }
        return base64(payload).ok_or_else(|| at(path, field, "malformed base64 in the data URI"));
    }
    let file = relative_to(path, Path::new(&percent_decode(uri)));
    std::fs::read(&file).map_err(|e| at(path, field, format!("{}: {e}", file.display())))
}

/// `%XX` escapes decoded (URIs in glTF are percent-encoded); malformed escapes are kept.
pub fn percent_decode(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        let hex = |c: u8| (c as char).to_digit(16);
        if b[i] == b'%' && i + 2 < b.len() {
            if let (Some(h), Some(l)) = (hex(b[i + 1]), hex(b[i + 2])) {
                out.push((h * 16 + l) as u8);
                i += 3;
                continue;
            }
        }
        out.push(b[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// Standard base64 (RFC 4648 §4), padding optional; `None` on any other character.
fn base64(s: &str) -> Option<Vec<u8>> {
    let value = |c: u8| -> Option<u32> {
        Some(match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' => 62,
            b'/' => 63,
            _ => return None,
        } as u32)
    };
    let s = s.trim_end_matches('=').as_bytes();
    let mut out = Vec::with_capacity(s.len() * 3 / 4);
    for chunk in s.chunks(4) {
        if chunk.len() == 1 {
            return None;
        }
        let mut n = 0u32;
        for (k, &c) in chunk.iter().enumerate() {
            n |= value(c)? << (18 - 6 * k);
        }
        let bytes = n.to_be_bytes();
        out.extend_from_slice(&bytes[1..chunk.len()]);
    }
    Some(out)
}

/// The bytes of one accessor, every element packed (`count × element size`), sparse values
/// applied.
struct Packed {
    bytes: Vec<u8>,
    count: usize,
    ty: DataType,
    components: usize,
}

fn component_size(ty: DataType) -> usize {
    match ty {
        DataType::I8 | DataType::U8 => 1,
        DataType::I16 | DataType::U16 => 2,
        DataType::U32 | DataType::F32 => 4,
    }
}

/// `len` bytes at `offset` in buffer view `view`, with `stride` between elements of `elem`
/// bytes, `count` of them, as a packed vector.
#[allow(clippy::too_many_arguments)] // a strided copy's parameters, named for messages
fn strided(
    path: &Path,
    field: &str,
    buffers: &Buffers,
    view: &gltf::buffer::View,
    offset: usize,
    count: usize,
    elem: usize,
    stride: usize,
) -> Result<Vec<u8>, SceneError> {
    let bad = |what: String| at(path, field, what);
    let buffer = &buffers.0[view.buffer().index()];
    let view_end = view.offset().checked_add(view.length());
    let view_bytes = view_end
        .and_then(|end| buffer.get(view.offset()..end))
        .ok_or_else(|| bad(format!("bufferView {} runs past the end of its buffer", view.index())))?;
    if count == 0 {
        return Ok(Vec::new());
    }
    let end = stride
        .checked_mul(count - 1)
        .and_then(|x| x.checked_add(offset))
        .and_then(|x| x.checked_add(elem))
        .filter(|&end| end <= view_bytes.len())
        .ok_or_else(|| {
            bad(format!(
                "{count} elements of {elem} bytes (stride {stride}) from byte {offset} do not fit in bufferView {} ({} bytes)",
                view.index(),
                view_bytes.len()
            ))
        })?;
    let data = &view_bytes[offset..end];
    let mut out = Vec::with_capacity(count * elem);
    for i in 0..count {
        out.extend_from_slice(&data[i * stride..i * stride + elem]);
    }
    Ok(out)
}

fn pack(path: &Path, field: &str, buffers: &Buffers, a: &gltf::Accessor) -> Result<Packed, SceneError> {
    let ty = a.data_type();
    let components = a.dimensions().multiplicity();
    let csize = component_size(ty);
    let elem = csize * components;
    let count = a.count();
    let name = format!("accessor {}", a.index());
    let mut bytes = match a.view() {
        Some(view) => {
            let stride = view.stride().unwrap_or(elem);
            if stride < elem {
                return Err(at(
                    path,
                    field,
                    format!("{name}: byteStride {stride} is less than its {elem}-byte elements"),
                ));
            }
            strided(path, &format!("{field} ({name})"), buffers, &view, a.offset(), count, elem, stride)?
        }
        None => {
            if count > MAX_VIEWLESS {
                return Err(at(path, field, format!("{name}: {count} elements with no bufferView")));
            }
            vec![0; count * elem]
        }
    };
    if let Some(sparse) = a.sparse() {
        let n = sparse.count();
        let f = format!("{field} ({name}.sparse)");
        let idx = sparse.indices();
        let isize = idx.index_type().size();
        let raw = strided(path, &f, buffers, &idx.view(), idx.offset(), n, isize, isize)?;
        let values = sparse.values();
        let vals = strided(path, &f, buffers, &values.view(), values.offset(), n, elem, elem)?;
        for (k, ib) in raw.chunks_exact(isize).enumerate() {
            let i = match isize {
                1 => ib[0] as usize,
                2 => u16::from_le_bytes([ib[0], ib[1]]) as usize,
                _ => u32::from_le_bytes([ib[0], ib[1], ib[2], ib[3]]) as usize,
            };
            if i >= count {
                return Err(at(path, f, format!("sparse index {i} is not below the count {count}")));
            }
            bytes[i * elem..(i + 1) * elem].copy_from_slice(&vals[k * elem..(k + 1) * elem]);
        }
    }
    Ok(Packed { bytes, count, ty, components })
}

/// Reads accessor `a` (at JSON path `field`) as `n`-component float vectors: floats as they
/// are, normalised integers mapped to `[0, 1]` or `[-1, 1]` (glTF 2.0 §3.11), integers not
/// normalised as their values (`KHR_mesh_quantization`). `allowed` lists the component types
/// the attribute may have, each with whether normalised; anything else is an error naming it.
pub fn read_floats<const N: usize>(
    path: &Path,
    field: &str,
    buffers: &Buffers,
    a: &gltf::Accessor,
    allowed: &[(DataType, bool)],
) -> Result<Vec<[f32; N]>, SceneError> {
    let dims = match N {
        2 => Dimensions::Vec2,
        3 => Dimensions::Vec3,
        _ => Dimensions::Vec4,
    };
    if a.dimensions() != dims {
        return Err(at(
            path,
            field,
            format!("accessor {} is {:?}, expected {dims:?}", a.index(), a.dimensions()),
        ));
    }
    let normalized = a.normalized() && a.data_type() != DataType::F32;
    if !allowed.contains(&(a.data_type(), normalized)) {
        return Err(at(
            path,
            field,
            format!(
                "accessor {}: component type {:?}{} is not allowed here",
                a.index(),
                a.data_type(),
                if a.normalized() { " (normalized)" } else { "" }
            ),
        ));
    }
    let p = pack(path, field, buffers, a)?;
    debug_assert!(p.components == N);
    let csize = component_size(p.ty);
    let mut out = Vec::with_capacity(p.count);
    // Normalised integers are divided by their largest value (signed ones clamped at -1).
    let norm = |x: f32, most: f32| if normalized { (x / most).max(-1.0) } else { x };
    for e in p.bytes.chunks_exact(csize * N) {
        let mut v = [0.0f32; N];
        for (k, c) in e.chunks_exact(csize).enumerate() {
            v[k] = match p.ty {
                DataType::F32 => f32::from_le_bytes([c[0], c[1], c[2], c[3]]),
                DataType::U8 => norm(c[0] as f32, 255.0),
                DataType::I8 => norm(c[0] as i8 as f32, 127.0),
                DataType::U16 => norm(u16::from_le_bytes([c[0], c[1]]) as f32, 65535.0),
                DataType::I16 => norm(i16::from_le_bytes([c[0], c[1]]) as f32, 32767.0),
                DataType::U32 => norm(u32::from_le_bytes([c[0], c[1], c[2], c[3]]) as f32, u32::MAX as f32),
            };
        }
        if v.iter().any(|x| !x.is_finite()) {
            return Err(at(path, field, format!("accessor {}: a non-finite value {v:?}", a.index())));
        }
        out.push(v);
    }
    Ok(out)
}

/// Reads an index accessor: unsigned bytes, shorts or ints, scalar, not normalised.
pub fn read_indices(
    path: &Path,
    field: &str,
    buffers: &Buffers,
    a: &gltf::Accessor,
) -> Result<Vec<u32>, SceneError> {
    if a.dimensions() != Dimensions::Scalar
        || !matches!(a.data_type(), DataType::U8 | DataType::U16 | DataType::U32)
        || a.normalized()
    {
        return Err(at(
            path,
            field,
            format!(
                "accessor {} is {:?} {:?}: indices are unsigned scalars (UNSIGNED_BYTE, _SHORT or _INT)",
                a.index(),
                a.dimensions(),
                a.data_type()
            ),
        ));
    }
    let p = pack(path, field, buffers, a)?;
    let csize = component_size(p.ty);
    Ok(p.bytes
        .chunks_exact(csize)
        .map(|c| match csize {
            1 => c[0] as u32,
            2 => u16::from_le_bytes([c[0], c[1]]) as u32,
            _ => u32::from_le_bytes([c[0], c[1], c[2], c[3]]),
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_and_percent_escapes() {
        assert_eq!(base64("aGVsbG8=").unwrap(), b"hello");
        assert_eq!(base64("aGVsbG8").unwrap(), b"hello");
        assert_eq!(base64("AAEC").unwrap(), vec![0, 1, 2]);
        assert!(base64("a").is_none());
        assert!(base64("a*bc").is_none());
        assert_eq!(percent_decode("my%20tex.png"), "my tex.png");
        assert_eq!(percent_decode("100%"), "100%");
        assert_eq!(percent_decode("a%2"), "a%2");
    }
}
