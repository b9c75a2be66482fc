//! The container (§4.4 binary glTF), `data:` URIs and references to files in the scene folder.

use base64::Engine as _;

use super::{Loader, SceneError};

// ---------------------------------------------------------------------------------------
// Container (§4.4 binary glTF) and URIs
// ---------------------------------------------------------------------------------------

/// Splits the input into the JSON document and the optional GLB BIN chunk.
pub(super) fn split_container<'b>(bytes: &'b [u8], file: &str) -> Result<(&'b [u8], Option<&'b [u8]>), SceneError> {
    if bytes.starts_with(b"glTF") {
        return split_glb(bytes, file);
    }
    let text = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    match text.iter().find(|b| !b.is_ascii_whitespace()) {
        Some(b'{') => Ok((text, None)),
        _ => Err(SceneError::NotGltf { file: file.to_string() }),
    }
}

/// Reads a little-endian u32 at `at`, None past the end.
fn read_u32(bytes: &[u8], at: usize) -> Option<u32> {
    let b = bytes.get(at..at.checked_add(4)?)?;
    Some(u32::from_le_bytes(b.try_into().ok()?))
}

/// Parses the GLB layout of glTF 2.0 spec §4.4: a 12-byte header (magic, version 2, total
/// length), a JSON chunk, an optional BIN chunk, and chunks of unknown type (ignored, §4.4.3.1).
fn split_glb<'b>(bytes: &'b [u8], file: &str) -> Result<(&'b [u8], Option<&'b [u8]>), SceneError> {
    const CHUNK_JSON: u32 = 0x4E4F_534A;
    const CHUNK_BIN: u32 = 0x004E_4942;
    let bad = |reason: String| SceneError::BadGlb { file: file.to_string(), reason };
    let (Some(version), Some(length)) = (read_u32(bytes, 4), read_u32(bytes, 8)) else {
        return Err(bad(format!("truncated: the file has {} bytes, fewer than the 12-byte header", bytes.len())));
    };
    if version != 2 {
        return Err(bad(format!("container version {version}; only glTF 2.0 binaries (version 2) are supported")));
    }
    let length = usize::try_from(length).unwrap_or(usize::MAX);
    if length > bytes.len() {
        return Err(bad(format!(
            "truncated: the header declares {length} bytes but the file has only {}",
            bytes.len()
        )));
    }
    let body = bytes.get(12..length).ok_or_else(|| {
        bad(format!("the header declares a total length of {length} bytes, less than the header itself"))
    })?;
    let mut pos = 0usize;
    let mut index = 0usize;
    let mut json = None;
    let mut bin = None;
    while pos < body.len() {
        let (Some(chunk_len), Some(kind)) = (read_u32(body, pos), read_u32(body, pos + 4)) else {
            return Err(bad(format!("truncated: chunk {index} has an incomplete 8-byte header")));
        };
        let start = pos + 8;
        let data = usize::try_from(chunk_len)
            .ok()
            .and_then(|len| start.checked_add(len))
            .and_then(|end| body.get(start..end))
            .ok_or_else(|| {
                bad(format!(
                    "truncated: chunk {index} declares {chunk_len} bytes but only {} remain",
                    body.len().saturating_sub(start)
                ))
            })?;
        match (index, kind) {
            (0, CHUNK_JSON) => json = Some(data),
            (0, _) => return Err(bad("the first chunk is not the JSON chunk".to_string())),
            (1, CHUNK_BIN) => bin = Some(data),
            _ => {} // unknown chunk types are skipped (§4.4.3.1)
        }
        // Chunks start on 4-byte boundaries (§4.4.3.1); tolerate unpadded writers.
        pos = (start + data.len()).saturating_add(3) & !3;
        index += 1;
    }
    let json = json.ok_or_else(|| bad("the file has no JSON chunk".to_string()))?;
    Ok((json, bin))
}

/// True when `uri` is a `data:` URI (RFC 2397), which glTF allows for buffers and images (§3.6.1.1, §3.8.2).
pub(super) fn is_data_uri(uri: &str) -> bool {
    uri.get(..5).is_some_and(|s| s.eq_ignore_ascii_case("data:"))
}

/// Decodes a base64 `data:` URI; the media type is not checked (images are sniffed).
pub(super) fn decode_data_uri(uri: &str) -> Result<Vec<u8>, String> {
    let rest = uri.get(5..).unwrap_or_default();
    let Some((meta, data)) = rest.split_once(',') else {
        return Err("it has no ',' separating the media type from the data".to_string());
    };
    if !meta.to_ascii_lowercase().ends_with(";base64") {
        return Err(format!("only base64 data URIs are supported, this one is '{meta}'"));
    }
    let engine = base64::engine::GeneralPurpose::new(
        &base64::alphabet::STANDARD,
        base64::engine::GeneralPurposeConfig::new()
            .with_decode_padding_mode(base64::engine::DecodePaddingMode::Indifferent),
    );
    engine.decode(data.trim()).map_err(|e| format!("invalid base64: {e}"))
}

/// The URL scheme of `uri` (RFC 3986 §3.1: a letter, then letters, digits, `+ - .`, then `:`).
pub(super) fn uri_scheme(uri: &str) -> Option<&str> {
    let (head, _) = uri.split_once(':')?;
    let mut chars = head.chars();
    let first = chars.next()?;
    (first.is_ascii_alphabetic() && chars.all(|c| c.is_ascii_alphanumeric() || "+-.".contains(c))).then_some(head)
}

/// Decodes `%XX` escapes (RFC 3986 §2.1); None for a malformed escape or invalid UTF-8.
pub(super) fn percent_decode(s: &str) -> Option<String> {
    let bytes = s.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while let Some(&b) = bytes.get(i) {
        if b == b'%' {
            let hex = bytes.get(i + 1..i + 3)?;
            if !hex.iter().all(u8::is_ascii_hexdigit) {
                return None;
            }
            out.push(u8::from_str_radix(std::str::from_utf8(hex).ok()?, 16).ok()?);
            i += 3;
        } else {
            out.push(b);
            i += 1;
        }
    }
    String::from_utf8(out).ok()
}

/// Splits a relative URI reference (§3.1: URIs are relative to the glTF file) into path
/// components, refusing anything that could leave the scene folder: URL schemes, absolute
/// and drive or UNC paths, and `..` components, all after percent-decoding.
pub(super) fn relative_components(uri: &str) -> Result<Vec<String>, String> {
    if let Some(scheme) = uri_scheme(uri) {
        return Err(if scheme.len() == 1 {
            "Windows drive paths are not allowed".to_string()
        } else {
            format!("the URL scheme '{scheme}:' is not allowed (only relative file paths and data: URIs are)")
        });
    }
    let decoded = percent_decode(uri).ok_or("it has a malformed percent-encoding")?;
    if decoded.contains('\0') {
        return Err("it contains a NUL character".to_string());
    }
    if decoded.starts_with('/') || decoded.starts_with('\\') {
        return Err("absolute paths are not allowed".to_string());
    }
    if decoded.contains(':') {
        return Err("':' is not allowed in a relative path (drive letter, URL scheme or stream name)".to_string());
    }
    let mut parts = Vec::new();
    for part in decoded.split(['/', '\\']) {
        match part {
            "" | "." => {}
            ".." => return Err("'..' would leave the scene folder".to_string()),
            p => parts.push(p.to_string()),
        }
    }
    if parts.is_empty() {
        return Err("the path is empty".to_string());
    }
    Ok(parts)
}

impl Loader<'_> {
    /// Reads a file referenced by `uri` from the scene folder; see [`relative_components`] for
    /// the rules. After joining, the path is canonicalised and must still lie inside the
    /// canonicalised scene folder, which catches symbolic links that point elsewhere.
    pub(super) fn read_external(
        &self,
        uri: &str,
        what: &str,
        missing: impl Fn(String) -> SceneError,
    ) -> Result<Vec<u8>, SceneError> {
        let escapes = |reason: String| SceneError::UriEscapes {
            file: self.file.to_string(),
            what: what.to_string(),
            uri: uri.to_string(),
            reason,
        };
        let parts = relative_components(uri).map_err(escapes)?;
        let Some(base) = self.base_dir else {
            return Err(missing(
                "the scene was loaded from memory, so there is no folder to resolve external files in".to_string(),
            ));
        };
        let base = base
            .canonicalize()
            .map_err(|e| missing(format!("cannot open the scene folder {}: {e}", base.display())))?;
        let joined = parts.iter().fold(base.clone(), |p, c| p.join(c));
        let real = joined.canonicalize().map_err(|e| missing(format!("{}: {e}", joined.display())))?;
        if !real.starts_with(&base) {
            return Err(escapes(format!(
                "it resolves to {}, outside the scene folder {} (through a symbolic link)",
                real.display(),
                base.display()
            )));
        }
        std::fs::read(&real).map_err(|e| missing(format!("{}: {e}", real.display())))
    }
}
