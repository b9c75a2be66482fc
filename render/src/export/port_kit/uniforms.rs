//! The uniform blocks' values for this preset (issue #54 point 1; docs/port-kit.md, "Uniform
//! values"): every uniform binding of the listed frame's steps decoded, member by member, by
//! the block's layout (naga's reflection, [`super::reflect`]) from the bytes the goldens hold
//! for that frame (`golden/frame-K/inputs/`). A port compares its own uniform values with
//! these before it compares any image.

use std::path::PathBuf;

use super::manifest::Manifest;
use super::reflect::Member;

/// Decodes the uniform bindings of `m.passes` (the last frame) from the goldens in `files`.
/// Returns how many bindings were decoded.
pub fn decode(m: &mut Manifest, files: &[(PathBuf, Vec<u8>)]) -> usize {
    let Some(last) = m.golden.last() else { return 0 };
    let bytes_of = |resource: &str| -> Option<&[u8]> {
        let f = last.inputs.iter().find(|f| f.resource == resource)?;
        files.iter().find(|(p, _)| p.to_string_lossy() == f.file).map(|(_, b)| b.as_slice())
    };
    let mut decoded = Vec::new();
    for (pi, pass) in m.passes.iter().enumerate() {
        for (si, step) in pass.steps.iter().enumerate() {
            for (bi, b) in step.bindings.iter().enumerate() {
                if b.kind != "uniform" {
                    continue;
                }
                let decl = step
                    .entry_points
                    .iter()
                    .filter_map(|(module, _)| m.shaders.iter().find(|s| &s.module == module))
                    .flat_map(|s| s.decl.bindings.iter())
                    .find(|d| d.group == b.group && d.binding == b.binding);
                let (Some(decl), Some(bytes)) = (decl, bytes_of(&b.resource)) else { continue };
                let at = b.offset.unwrap_or(0) as usize;
                let Some(block) = bytes.get(at..) else { continue };
                let values = if decl.members.is_empty() {
                    vec![(decl.name.clone(), value(&decl.ty, block, decl.size.unwrap_or(0) as usize))]
                } else {
                    decl.members.iter().map(|mem| (mem.name.clone(), member(mem, block))).collect()
                };
                decoded.push((pi, si, bi, values));
            }
        }
    }
    let n = decoded.len();
    for (pi, si, bi, values) in decoded {
        m.passes[pi].steps[si].bindings[bi].values = values;
    }
    n
}

fn member(m: &Member, block: &[u8]) -> serde_json::Value {
    match block.get(m.offset as usize..(m.offset + m.size) as usize) {
        Some(b) => value(&m.ty, b, m.size as usize),
        None => serde_json::Value::Null,
    }
}

fn word(b: &[u8], at: usize) -> Option<[u8; 4]> {
    b.get(at..at + 4).and_then(|w| w.try_into().ok())
}

fn scalar(kind: &str, b: &[u8], at: usize) -> serde_json::Value {
    let Some(w) = word(b, at) else { return serde_json::Value::Null };
    match kind {
        "f32" => {
            let f = f32::from_le_bytes(w);
            if f.is_finite() { serde_json::json!(f) } else { serde_json::json!(format!("{f}")) }
        }
        "u32" => serde_json::json!(u32::from_le_bytes(w)),
        "i32" => serde_json::json!(i32::from_le_bytes(w)),
        _ => serde_json::Value::Null,
    }
}

/// A value of the WGSL type `ty` (as [`super::reflect`] names it) at the start of `b`, of
/// `size` bytes: scalars, vectors, matrices (columns) and fixed arrays of those; a struct's
/// value is left out (null) — its layout is the block's own declaration.
fn value(ty: &str, b: &[u8], size: usize) -> serde_json::Value {
    if matches!(ty, "f32" | "u32" | "i32") {
        return scalar(ty, b, 0);
    }
    if let Some(rest) = ty.strip_prefix("vec")
        && let Some((n, kind)) = rest.split_once('<')
    {
        let n: usize = n.parse().unwrap_or(0);
        let kind = kind.trim_end_matches('>');
        return serde_json::Value::Array((0..n).map(|i| scalar(kind, b, 4 * i)).collect());
    }
    if let Some(rest) = ty.strip_prefix("mat")
        && let Some((dims, kind)) = rest.split_once('<')
        && let Some((c, r)) = dims.split_once('x')
    {
        let (c, r): (usize, usize) = (c.parse().unwrap_or(0), r.parse().unwrap_or(0));
        let kind = kind.trim_end_matches('>');
        let stride = if r == 2 { 8 } else { 16 };
        return serde_json::Value::Array(
            (0..c)
                .map(|col| serde_json::Value::Array((0..r).map(|i| scalar(kind, b, col * stride + 4 * i)).collect()))
                .collect(),
        );
    }
    if let Some(inner) = ty.strip_prefix("array<").and_then(|t| t.strip_suffix('>'))
        && let Some((elem, n)) = inner.rsplit_once(", ")
        && let Ok(n) = n.parse::<usize>()
        && n > 0
    {
        let stride = size / n;
        return serde_json::Value::Array(
            (0..n).map(|i| b.get(i * stride..).map_or(serde_json::Value::Null, |e| value(elem, e, stride))).collect(),
        );
    }
    serde_json::Value::Null
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blocks_decode_by_their_members_types() {
        let mut b = Vec::new();
        for f in [1.0f32, 2.0, 3.0, 4.0] {
            b.extend(f.to_le_bytes());
        }
        assert_eq!(value("vec3<f32>", &b, 12), serde_json::json!([1.0, 2.0, 3.0]));
        assert_eq!(value("u32", &7u32.to_le_bytes(), 4), serde_json::json!(7));
        // A mat2x2's columns are 8 bytes apart, a mat3x3's 16.
        assert_eq!(value("mat2x2<f32>", &b, 16), serde_json::json!([[1.0, 2.0], [3.0, 4.0]]));
        let mut m3 = b.clone();
        m3.extend(&b);
        m3.extend(&b);
        assert_eq!(value("mat3x3<f32>", &m3, 48)[1], serde_json::json!([1.0, 2.0, 3.0]));
        assert_eq!(value("array<vec2<f32>, 2>", &b, 16), serde_json::json!([[1.0, 2.0], [3.0, 4.0]]));
        assert_eq!(value("Light", &b, 16), serde_json::Value::Null);
    }
}
