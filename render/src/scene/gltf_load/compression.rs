//! Compressed buffer views: `EXT_meshopt_compression` and its ratified successor
//! `KHR_meshopt_compression` (Khronos extension specifications, "Compressing buffer views"
//! and "Filters"), decoded with the `meshopt` crate (meshoptimizer's own decoder, which is
//! safe on untrusted input: it returns an error or garbage, never reads out of bounds).
//!
//! A compressed view keeps its glTF meaning (the parent view's `buffer`, `byteOffset` and
//! `byteLength` describe the *decoded* bytes, usually in a "fallback" buffer with no data);
//! its extension names where the encoded bytes are and how to decode them. Every view is
//! decoded once, after the buffers are loaded (a stream too short for its declared `count` is
//! refused before the destination is allocated), and [`Loader::view_bytes`] serves the decoded
//! bytes from then on, so accessors, sparse data and images read compressed views through the
//! same range checks as plain ones.

use serde_json::Value;

use super::{Loader, SceneError, json};

/// The extension names that carry compressed views; the data formats are the same.
pub(super) const MESHOPT_EXTENSIONS: [&str; 2] = ["EXT_meshopt_compression", "KHR_meshopt_compression"];

/// Upper bound on the decoded bytes of one file. Meshopt streams compress runs of equal bytes
/// to a few bits per vertex, so a small hostile file could otherwise ask for gigabytes; real
/// scenes decode to a fraction of this (the Amazon Lumberyard Bistro, 2.8 M triangles,
/// decodes to about 200 MB).
pub(super) const MAX_DECODED_BYTES: usize = 1 << 30;

/// How a compressed view is encoded (the extension's `mode`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Mode {
    /// Vertex codec: `count` elements of `byteStride` bytes (a multiple of 4, at most 256).
    Attributes,
    /// Index codec for triangle lists: `count` (a multiple of 3) indices of 2 or 4 bytes.
    Triangles,
    /// Index-sequence codec: `count` indices of 2 or 4 bytes.
    Indices,
}

/// The filter applied after the vertex codec (the extension's `filter`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Filter {
    None,
    /// Octahedral unit vectors, K-bit X/Y in 8- or 16-bit components (stride 4 or 8).
    Octahedral,
    /// Quaternions, three 16-bit components and the index of the largest (stride 8).
    Quaternion,
    /// Floats as 8-bit exponent and 24-bit mantissa (stride a multiple of 4).
    Exponential,
    /// RGBA in YCoCg (KHR_meshopt_compression only; stride 4 or 8).
    Color,
}

/// The decoded fields of one view's extension object.
#[derive(Debug)]
struct Compressed {
    extension: &'static str,
    buffer: usize,
    offset: usize,
    length: usize,
    stride: usize,
    count: usize,
    mode: Mode,
    filter: Filter,
}

/// The extension object of buffer view `view`, if it is compressed.
fn extension_of(view: &json::buffer::View) -> Option<(&'static str, &Value)> {
    let others = &view.extensions.as_ref()?.others;
    MESHOPT_EXTENSIONS.iter().find_map(|name| others.get(*name).map(|v| (*name, v)))
}

/// Whether buffer `b` is a meshopt fallback buffer (`"fallback": true`): it may have no data,
/// since every view on it is compressed elsewhere.
pub(super) fn is_fallback(buffer: &json::Buffer) -> bool {
    buffer.extensions.as_ref().is_some_and(|e| {
        MESHOPT_EXTENSIONS
            .iter()
            .any(|name| e.others.get(*name).and_then(|v| v.get("fallback")) == Some(&Value::Bool(true)))
    })
}

/// Reads and checks the extension object of view `view` against the rules of the specification
/// ("Compressing buffer views": mode, stride and count constraints; filters only on attributes).
fn parse(view: usize, extension: &'static str, ext: &Value) -> Result<Compressed, String> {
    let field = |name: &str| -> Result<usize, String> {
        ext.get(name)
            .and_then(Value::as_u64)
            .map(|v| usize::try_from(v).unwrap_or(usize::MAX))
            .ok_or_else(|| format!("buffer view {view}: {extension}.{name} is missing or not a non-negative integer"))
    };
    let buffer = field("buffer")?;
    let offset = ext.get("byteOffset").map_or(Ok(0), |_| field("byteOffset"))?;
    let length = field("byteLength")?;
    let stride = field("byteStride")?;
    let count = field("count")?;
    let mode = match ext.get("mode").and_then(Value::as_str) {
        Some("ATTRIBUTES") => Mode::Attributes,
        Some("TRIANGLES") => Mode::Triangles,
        Some("INDICES") => Mode::Indices,
        other => {
            return Err(format!(
                "buffer view {view}: {extension}.mode is {other:?}, not ATTRIBUTES, TRIANGLES or INDICES"
            ));
        }
    };
    let filter = match ext.get("filter").and_then(Value::as_str) {
        None | Some("NONE") => Filter::None,
        Some("OCTAHEDRAL") => Filter::Octahedral,
        Some("QUATERNION") => Filter::Quaternion,
        Some("EXPONENTIAL") => Filter::Exponential,
        Some("COLOR") if extension == "KHR_meshopt_compression" => Filter::Color,
        Some(other) => return Err(format!("buffer view {view}: {extension}.filter '{other}' is not defined")),
    };
    let bad = |rule: &str| Err(format!("buffer view {view}: {extension} with mode {mode:?} {rule}"));
    match mode {
        Mode::Attributes if stride == 0 || stride % 4 != 0 || stride > 256 => {
            return bad(&format!("needs a byteStride that is a multiple of 4 up to 256, not {stride}"));
        }
        Mode::Triangles | Mode::Indices if stride != 2 && stride != 4 => {
            return bad(&format!("needs a byteStride of 2 or 4, not {stride}"));
        }
        Mode::Triangles if count % 3 != 0 => {
            return bad(&format!("needs a count that is a multiple of 3, not {count}"));
        }
        Mode::Triangles | Mode::Indices if filter != Filter::None => return bad("cannot have a filter"),
        _ => {}
    }
    let filter_ok = match filter {
        Filter::None => true,
        Filter::Octahedral | Filter::Color => stride == 4 || stride == 8,
        Filter::Quaternion => stride == 8,
        Filter::Exponential => stride % 4 == 0,
    };
    if !filter_ok {
        return Err(format!("buffer view {view}: {extension} filter {filter:?} cannot have byteStride {stride}"));
    }
    Ok(Compressed { extension, buffer, offset, length, stride, count, mode, filter })
}

/// The decoded bytes of a compressed view, kept in the `u32` words they were decoded into
/// (the filters read the destination as 16- and 32-bit components), so that serving them
/// as bytes needs no second copy of a possibly large buffer.
#[derive(Debug)]
pub(super) struct Decoded {
    words: Vec<u32>,
    len: usize,
}

impl Decoded {
    /// The decoded bytes, in the order the decoder wrote them.
    pub(super) fn bytes(&self) -> &[u8] {
        let bytes: &[u8] = bytemuck::cast_slice(&self.words);
        bytes.get(..self.len).unwrap_or(bytes)
    }
}

/// The fewest encoded bytes that can hold `c.count` elements: meshoptimizer's decoders refuse
/// anything shorter, so checking it first refuses a tiny stream that declares a huge `count`
/// before the destination is allocated. Index codec: a header byte, a byte per triangle (or
/// per index) and the 16-byte (or 4-byte) tail. Vertex codec: a header byte, per block of up to
/// 256 vertices at least a control byte per 4 bytes of a vertex (format version 1; version 0
/// needs more), and a tail of at least max(byteStride, 24) bytes.
fn min_encoded_len(c: &Compressed) -> usize {
    match c.mode {
        Mode::Triangles => 1 + c.count / 3 + 16,
        Mode::Indices => c.count.saturating_add(5),
        Mode::Attributes => min_vertex_stream_len(c.count, c.stride),
    }
}

/// [`min_encoded_len`] of the vertex codec: `count` vertices of `stride` bytes (a multiple of
/// 4 up to 256) in blocks of `(8192 / stride)` rounded down to 16, at most 256, vertices.
pub(super) fn min_vertex_stream_len(count: usize, stride: usize) -> usize {
    let block = ((8192 / stride.max(1)) & !15).clamp(16, 256);
    count.div_ceil(block).saturating_mul(stride / 4).saturating_add(1 + stride.max(24))
}

/// Decodes `c` from `encoded` into `count × stride` bytes.
fn decode(view: usize, c: &Compressed, encoded: &[u8]) -> Result<Decoded, String> {
    let size = c.count.checked_mul(c.stride).filter(|&s| s <= MAX_DECODED_BYTES).ok_or_else(|| {
        format!(
            "buffer view {view}: {} decodes to {} × {} bytes, more than the {} MiB GI Lab accepts per file",
            c.extension,
            c.count,
            c.stride,
            MAX_DECODED_BYTES >> 20
        )
    })?;
    let needed = min_encoded_len(c);
    if encoded.len() < needed {
        return Err(format!(
            "buffer view {view}: the {} data ({} bytes, mode {:?}) is malformed: {} elements of {} bytes need at \
             least {needed} encoded bytes (the data is truncated or the count is wrong)",
            c.extension,
            encoded.len(),
            c.mode,
            c.count,
            c.stride
        ));
    }
    let mut words = vec![0u32; size.div_ceil(4)];
    let dst = words.as_mut_ptr().cast::<std::ffi::c_void>();
    // SAFETY: `words` holds at least count × stride bytes (checked above), which is what
    // every decoder writes; the encoded slice is passed with its own length, and the
    // meshoptimizer decoders never read past it ("safe to use for untrusted input"). The
    // filters rewrite count × stride bytes in place, with the stride checked in `parse`.
    let code = unsafe {
        match c.mode {
            Mode::Attributes => {
                meshopt::ffi::meshopt_decodeVertexBuffer(dst, c.count, c.stride, encoded.as_ptr(), encoded.len())
            }
            Mode::Triangles => {
                meshopt::ffi::meshopt_decodeIndexBuffer(dst, c.count, c.stride, encoded.as_ptr(), encoded.len())
            }
            Mode::Indices => {
                meshopt::ffi::meshopt_decodeIndexSequence(dst, c.count, c.stride, encoded.as_ptr(), encoded.len())
            }
        }
    };
    if code != 0 {
        return Err(format!(
            "buffer view {view}: the {} data ({} bytes, mode {:?}) is malformed (meshoptimizer error {code})",
            c.extension,
            encoded.len(),
            c.mode
        ));
    }
    // SAFETY: as above; the filters only touch count × stride bytes.
    unsafe {
        match c.filter {
            Filter::None => {}
            Filter::Octahedral => meshopt::ffi::meshopt_decodeFilterOct(dst, c.count, c.stride),
            Filter::Quaternion => meshopt::ffi::meshopt_decodeFilterQuat(dst, c.count, c.stride),
            Filter::Exponential => meshopt::ffi::meshopt_decodeFilterExp(dst, c.count, c.stride),
            Filter::Color => meshopt::ffi::meshopt_decodeFilterColor(dst, c.count, c.stride),
        }
    }
    Ok(Decoded { words, len: size })
}

impl Loader<'_> {
    /// Decodes every compressed buffer view (after [`Loader::load_buffers`]); from then on
    /// [`Loader::view_bytes`] returns the decoded bytes of these views.
    pub(super) fn decode_compressed_views(&mut self) -> Result<(), SceneError> {
        let root = self.root;
        let mut total = 0usize;
        for (i, v) in root.buffer_views.iter().enumerate() {
            let Some((extension, ext)) = extension_of(v) else { continue };
            let invalid = |message: String| SceneError::Invalid { file: self.file.to_string(), message };
            let c = parse(i, extension, ext).map_err(invalid)?;
            let encoded = self
                .buffers
                .get(c.buffer)
                .and_then(|b| c.offset.checked_add(c.length).and_then(|end| b.get(c.offset..end)))
                .ok_or_else(|| {
                    invalid(format!(
                        "buffer view {i}: {extension} reads {} bytes from offset {} of buffer {}, which {}",
                        c.length,
                        c.offset,
                        c.buffer,
                        self.buffers
                            .get(c.buffer)
                            .map_or("does not exist".to_string(), |b| format!("has only {} bytes", b.len()))
                    ))
                })?;
            let decoded = decode(i, &c, encoded).map_err(invalid)?;
            total = total.saturating_add(decoded.len);
            if total > MAX_DECODED_BYTES {
                return Err(invalid(format!(
                    "the compressed buffer views decode to more than the {} MiB GI Lab accepts per file",
                    MAX_DECODED_BYTES >> 20
                )));
            }
            self.decoded_views.insert(i, decoded);
        }
        Ok(())
    }
}
