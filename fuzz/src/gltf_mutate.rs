//! glTF-aware mutations: a GLB is taken apart into its JSON document and BIN chunk, one of
//! them is mutated, and the container is written again with correct lengths
//! ([`gi_render::scene::cornell::glb`]), so that the mutation reaches the loader's accessor,
//! buffer and node code instead of stopping at the container check. `.gltf` text inputs get
//! the same JSON mutations, and their `data:` URIs are decoded, mutated and encoded again.
//!
//! Structural JSON mutations favour the fields that size allocations and index data:
//! `count`, `byteLength`, `byteOffset`, `byteStride` and every index (`bufferView`, `buffer`,
//! `POSITION`, `indices`, `children`, …) are set to boundary values such as 2³¹, 2³² − 1 and
//! 2⁶⁴ − 1; array elements are duplicated, removed and swapped; values change type; keys are
//! removed; subtrees are copied between inputs.

use base64::Engine as _;
use serde_json::{Map, Number, Value};

use crate::mutate::{INTERESTING_U64, mutate_bytes, mutate_text};
use crate::rng::Rng;

/// Keys whose numbers size buffers or count elements, and keys that index other objects.
const SIZE_KEYS: &[&str] = &["count", "byteLength", "byteOffset", "byteStride"];
const INDEX_KEYS: &[&str] = &[
    "bufferView",
    "buffer",
    "indices",
    "POSITION",
    "NORMAL",
    "TEXCOORD_0",
    "TEXCOORD_1",
    "material",
    "mesh",
    "node",
    "nodes",
    "children",
    "scene",
    "source",
    "index",
    "texCoord",
    "input",
    "output",
    "sampler",
    "camera",
    "light",
    "mode",
    "componentType",
];

/// Words of glTF documents for the text mutator.
pub const DICTIONARY: &[&str] = &[
    "count",
    "byteLength",
    "byteOffset",
    "byteStride",
    "bufferView",
    "bufferViews",
    "buffers",
    "accessors",
    "sparse",
    "indices",
    "values",
    "POSITION",
    "NORMAL",
    "TEXCOORD_0",
    "TEXCOORD_1",
    "VEC2",
    "VEC3",
    "VEC4",
    "MAT4",
    "SCALAR",
    "componentType",
    "normalized",
    "mode",
    "nodes",
    "children",
    "matrix",
    "rotation",
    "scale",
    "translation",
    "meshes",
    "primitives",
    "materials",
    "textures",
    "images",
    "samplers",
    "animations",
    "channels",
    "CUBICSPLINE",
    "STEP",
    "extensionsRequired",
    "extensionsUsed",
    "KHR_lights_punctual",
    "KHR_texture_transform",
    "KHR_materials_emissive_strength",
    "EXT_meshopt_compression",
    "KHR_meshopt_compression",
    "KHR_draco_mesh_compression",
    "fallback",
    "ATTRIBUTES",
    "TRIANGLES",
    "OCTAHEDRAL",
    "QUATERNION",
    "EXPONENTIAL",
    "COLOR",
    "uri",
    "data:application/octet-stream;base64,",
    "../",
    "%2e%2e/",
    "null",
    "true",
    "[]",
    "{}",
    "5126",
    "5125",
    "5123",
    "5121",
    "5120",
    "5122",
];

/// Upper bound on a mutated input's size (the largest seed plus some room).
pub const MAX_LEN: usize = 12 << 20;

/// The JSON and BIN chunks of a GLB (None when `bytes` is not a well-formed GLB).
pub fn split_glb(bytes: &[u8]) -> Option<(Vec<u8>, Vec<u8>)> {
    let word = |at: usize| -> Option<usize> {
        let b = bytes.get(at..at.checked_add(4)?)?;
        Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize)
    };
    if !bytes.starts_with(b"glTF") {
        return None;
    }
    let json_len = word(12)?;
    let json = bytes.get(20..20usize.checked_add(json_len)?)?.to_vec();
    let bin_at = 20 + json_len;
    let bin = match word(bin_at) {
        Some(len) => bytes.get(bin_at + 8..(bin_at + 8).checked_add(len)?)?.to_vec(),
        None => Vec::new(),
    };
    Some((json, bin))
}

/// One glTF-aware mutation of `data`, or a plain byte or text mutation when the input is
/// neither a GLB nor a JSON document.
pub fn mutate_gltf(rng: &mut Rng, data: &mut Vec<u8>, other: Option<&[u8]>) {
    if let Some((mut json, mut bin)) = split_glb(data) {
        match rng.below(16) {
            // The container itself: lengths, magic, chunk types.
            0 => mutate_bytes(rng, data, other, MAX_LEN),
            1 | 2 => {
                mutate_bytes(rng, &mut bin, None, MAX_LEN);
                *data = gi_render::scene::cornell::glb(json, bin);
            }
            3 | 4 => {
                mutate_text(rng, &mut json, DICTIONARY, None, MAX_LEN);
                *data = gi_render::scene::cornell::glb(json, bin);
            }
            _ => {
                let other_json = other.and_then(split_glb).map(|(j, _)| j);
                if let Some(mutated) = mutate_json_text(rng, &json, other_json.as_deref().or(other)) {
                    *data = gi_render::scene::cornell::glb(mutated, bin);
                } else {
                    mutate_bytes(rng, data, other, MAX_LEN);
                }
            }
        }
        return;
    }
    let looks_like_json = data.iter().find(|b| !b.is_ascii_whitespace()) == Some(&b'{');
    if looks_like_json
        && rng.below(6) != 0
        && let Some(mutated) = mutate_json_text(rng, data, other)
    {
        *data = mutated;
        return;
    }
    if looks_like_json || rng.one_in(2) {
        mutate_text(rng, data, DICTIONARY, other, MAX_LEN);
    } else {
        mutate_bytes(rng, data, other, MAX_LEN);
    }
}

/// Parses `json`, applies 1–3 structural mutations and serialises it (None when it does not parse).
fn mutate_json_text(rng: &mut Rng, json: &[u8], other: Option<&[u8]>) -> Option<Vec<u8>> {
    let mut doc: Value = serde_json::from_slice(json).ok()?;
    let donor: Option<Value> = other.and_then(|o| serde_json::from_slice(o).ok());
    for _ in 0..rng.range(1, 3) {
        mutate_json(rng, &mut doc, donor.as_ref());
    }
    serde_json::to_vec(&doc).ok()
}

/// A path to a value: object keys and array indices from the root.
#[derive(Clone, Debug)]
enum Step {
    Key(String),
    Index(usize),
}

/// Every value of `v` with its path and the key it sits under (None in arrays and at the root).
fn collect(v: &Value, path: &mut Vec<Step>, key: Option<&str>, out: &mut Vec<(Vec<Step>, Option<String>)>) {
    out.push((path.clone(), key.map(str::to_string)));
    match v {
        Value::Object(m) => {
            for (k, child) in m {
                path.push(Step::Key(k.clone()));
                collect(child, path, Some(k), out);
                path.pop();
            }
        }
        Value::Array(a) => {
            for (i, child) in a.iter().enumerate() {
                path.push(Step::Index(i));
                // Elements of `children`, `nodes`, … keep their parent's key: they are indices too.
                collect(child, path, key, out);
                path.pop();
            }
        }
        _ => {}
    }
}

/// The value at `path` in `v`.
fn at_mut<'v>(v: &'v mut Value, path: &[Step]) -> Option<&'v mut Value> {
    path.iter().try_fold(v, |v, step| match step {
        Step::Key(k) => v.get_mut(k.as_str()),
        Step::Index(i) => v.get_mut(*i),
    })
}

/// A boundary or random number for a field. Integers stay non-negative integers most of the
/// time (the JSON types are checked before anything else, so a negative `count` stops at
/// the parser); floats get the float boundaries.
fn number(rng: &mut Rng, current: &Number) -> Value {
    if current.is_f64() && !rng.one_in(8) {
        let x = [0.0, -0.0, 1.0, -1.0, 0.5, 1e39, -1e39, 1e-45, 3.4e38, f64::MAX, 2147483648.0, 1e-7];
        return Number::from_f64(*rng.pick(&x).unwrap_or(&0.0)).map_or(Value::from(0), Value::Number);
    }
    let cur = current.as_u64().unwrap_or(0);
    let n: u64 = match rng.below(6) {
        0 | 1 => *rng.pick(INTERESTING_U64).unwrap_or(&0),
        2 => 1u64 << rng.below(64),
        3 => cur.wrapping_add(rng.range(1, 16) as u64),
        4 => cur.saturating_sub(rng.range(1, 16) as u64),
        _ => rng.below(64) as u64,
    };
    match rng.below(32) {
        0 => Value::from(-(rng.range(1, 3) as i64)),
        1 => Number::from_f64(n as f64 + 0.5).map_or(Value::from(n), Value::Number),
        _ => Value::from(n),
    }
}

/// The value at `path` of `v`, read-only.
fn at<'v>(v: &'v Value, path: &[Step]) -> Option<&'v Value> {
    path.iter().try_fold(v, |v, step| match step {
        Step::Key(k) => v.get(k.as_str()),
        Step::Index(i) => v.get(*i),
    })
}

/// One structural mutation of `doc` (`donor`: another document to copy subtrees from).
/// Most mutations keep the JSON types (so that the document still deserialises and the
/// loader's own checks are reached); a few change them.
fn mutate_json(rng: &mut Rng, doc: &mut Value, donor: Option<&Value>) {
    let mut all = Vec::new();
    collect(doc, &mut Vec::new(), None, &mut all);
    let favoured = |(_, k): &&(Vec<Step>, Option<String>)| {
        k.as_deref().is_some_and(|k| SIZE_KEYS.contains(&k) || INDEX_KEYS.contains(&k))
    };
    let kind = rng.below(20);
    let candidates: Vec<&(Vec<Step>, Option<String>)> = match kind {
        // Numbers, mostly those that size or index.
        0..=9 => {
            let numbers = all.iter().filter(|(p, _)| at(doc, p).is_some_and(Value::is_number));
            let numbers: Vec<_> = numbers.collect();
            let sized: Vec<_> = numbers.iter().copied().filter(favoured).collect();
            if !sized.is_empty() && rng.below(3) != 0 { sized } else { numbers }
        }
        10..=12 => all.iter().filter(|(p, _)| at(doc, p).is_some_and(Value::is_array)).collect(),
        13 | 14 => all.iter().filter(|(p, _)| at(doc, p).is_some_and(Value::is_object)).collect(),
        15 | 16 => all.iter().filter(|(p, _)| at(doc, p).is_some_and(Value::is_string)).collect(),
        _ => all.iter().collect(),
    };
    let Some((path, key)) = rng.pick(&candidates).map(|c| (*c).clone()) else { return };
    // A value of the donor (or of the document) under the same key, for type-preserving copies.
    let same_key_value = |rng: &mut Rng| -> Option<Value> {
        let source = donor.unwrap_or(&*doc);
        let mut from = Vec::new();
        collect(source, &mut Vec::new(), None, &mut from);
        let kind_of = |v: Option<&Value>| v.map(std::mem::discriminant);
        let here = kind_of(at(doc, &path));
        let matching: Vec<_> =
            from.iter().filter(|(p, k)| k.is_some() && *k == key && kind_of(at(source, p)) == here).collect();
        rng.pick(&matching).and_then(|(p, _)| at(source, p)).cloned()
    };
    let copied = if kind == 17 { same_key_value(rng) } else { None };
    let Some(v) = at_mut(doc, &path) else { return };
    match kind {
        0..=9 => {
            if let Value::Number(n) = &*v {
                let n = n.clone();
                *v = number(rng, &n);
            }
        }
        10..=12 => {
            // Duplicate, remove or swap array elements (more primitives, fewer buffers, …).
            if let Value::Array(a) = v
                && !a.is_empty()
            {
                let i = rng.below(a.len());
                match rng.below(3) {
                    0 => {
                        let copy = a[i].clone();
                        let at = rng.below(a.len() + 1);
                        for _ in 0..rng.small_len(16) {
                            a.insert(at, copy.clone());
                        }
                    }
                    1 => {
                        a.remove(i);
                    }
                    _ => {
                        let j = rng.below(a.len());
                        a.swap(i, j);
                    }
                }
            }
        }
        13 | 14 => {
            // Remove a key, or add one copied from elsewhere.
            if let Value::Object(m) = v {
                let keys: Vec<String> = m.keys().cloned().collect();
                if let Some(k) = rng.pick(&keys) {
                    m.remove(k);
                }
            }
        }
        15 | 16 => {
            if let Value::String(s) = v {
                mutate_string(rng, s);
            }
        }
        17 => {
            if let Some(c) = copied {
                *v = c;
            }
        }
        18 => {
            *v = match rng.below(6) {
                0 => Value::Null,
                1 => Value::Bool(true),
                2 => Value::String("x".into()),
                3 => Value::Object(Map::new()),
                4 => Value::Array(Vec::new()),
                _ => Value::from(-1),
            };
        }
        _ => *v = Value::Array(vec![v.clone(), v.clone()]),
    }
}

/// A string's mutation: a `data:` URI's payload is decoded, byte-mutated and encoded again
/// (the buffers and images inside `.gltf` files); other strings get text mutations.
fn mutate_string(rng: &mut Rng, s: &mut String) {
    if let Some((head, payload)) = s.split_once(";base64,") {
        let engine = base64::engine::general_purpose::STANDARD;
        if let Ok(mut bytes) = engine.decode(payload) {
            for _ in 0..rng.small_len(4) {
                mutate_bytes(rng, &mut bytes, None, MAX_LEN);
            }
            *s = format!("{head};base64,{}", engine.encode(bytes));
            return;
        }
    }
    let mut bytes = s.clone().into_bytes();
    mutate_text(rng, &mut bytes, DICTIONARY, None, 4096);
    *s = String::from_utf8_lossy(&bytes).into_owned();
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn glb_round_trips_and_mutations_keep_the_container_valid() {
        let glb = gi_render::scene::cornell::glb(
            br#"{"asset":{"version":"2.0"},"accessors":[{"count":3}]}"#.to_vec(),
            vec![1, 2, 3, 4],
        );
        let (json, bin) = split_glb(&glb).expect("a GLB");
        assert_eq!(bin, [1, 2, 3, 4]);
        assert!(json.starts_with(b"{\"asset\""));
        let mut rng = Rng::new(5);
        let mut valid = 0;
        for _ in 0..500 {
            let mut d = glb.clone();
            mutate_gltf(&mut rng, &mut d, Some(&glb));
            valid += usize::from(split_glb(&d).is_some());
        }
        assert!(valid > 400, "most mutations keep a well-formed container: {valid}");
    }

    #[test]
    fn size_fields_get_boundary_values() {
        let mut rng = Rng::new(9);
        let mut seen_huge = false;
        for _ in 0..300 {
            let mut doc: Value = serde_json::from_str(r#"{"accessors":[{"count":3,"type":"VEC3"}]}"#).expect("json");
            mutate_json(&mut rng, &mut doc, None);
            seen_huge |= doc["accessors"][0]["count"].as_u64().is_some_and(|c| c >= 1 << 31);
        }
        assert!(seen_huge);
    }
}
