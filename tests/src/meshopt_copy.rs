//! Makes `EXT_meshopt_compression` copies of `.glb` files with the `meshopt` crate's
//! encoders, as gltfpack would: every accessor's data is moved into its own compressed view
//! (index accessors with the triangle index codec, the others with the vertex codec) over a
//! fallback buffer that holds no data. With `quantize`, normals become 8-bit octahedral
//! vectors (the OCTAHEDRAL filter, `KHR_mesh_quantization`'s normalized BYTE normals).

use serde_json::{Value, json};

/// The JSON and BIN chunks of a `.glb`.
fn split_glb(glb: &[u8]) -> (Value, Vec<u8>) {
    assert_eq!(&glb[..4], b"glTF", "not a .glb");
    let word = |at: usize| u32::from_le_bytes(glb[at..at + 4].try_into().expect("4 bytes")) as usize;
    let json_len = word(12);
    let json: Value = serde_json::from_slice(&glb[20..20 + json_len]).expect("the .glb's JSON parses");
    let bin_at = 20 + json_len;
    let bin = if bin_at + 8 <= glb.len() { glb[bin_at + 8..bin_at + 8 + word(bin_at)].to_vec() } else { Vec::new() };
    (json, bin)
}

/// A `.glb` of `json` and `bin` (both padded to 4 bytes).
fn join_glb(json: &Value, bin: Vec<u8>) -> Vec<u8> {
    gi_render::scene::cornell::glb(serde_json::to_vec(json).expect("JSON serialises"), bin)
}

fn component_size(component_type: u64) -> usize {
    match component_type {
        5120 | 5121 => 1,
        5122 | 5123 => 2,
        5125 | 5126 => 4,
        other => panic!("component type {other}"),
    }
}

fn multiplicity(ty: &str) -> usize {
    match ty {
        "SCALAR" => 1,
        "VEC2" => 2,
        "VEC3" => 3,
        "VEC4" | "MAT2" => 4,
        "MAT3" => 9,
        "MAT4" => 16,
        other => panic!("accessor type {other}"),
    }
}

/// The meshopt-compressed copy of `glb` (see the module doc). The source must have one
/// accessor per buffer view, tightly packed (as GI Lab's default scene has).
pub fn meshopt_copy(glb: &[u8], quantize: bool) -> Vec<u8> {
    let (mut doc, bin) = split_glb(glb);
    let mut index_accessors = std::collections::HashSet::new();
    let mut normal_accessors = std::collections::HashSet::new();
    for mesh in doc["meshes"].as_array().into_iter().flatten() {
        for p in mesh["primitives"].as_array().into_iter().flatten() {
            assert!(p["mode"].as_u64().is_none_or(|m| m == 4), "the copy encodes triangle lists only");
            if let Some(i) = p["indices"].as_u64() {
                index_accessors.insert(i);
            }
            if let Some(n) = p["attributes"]["NORMAL"].as_u64() {
                normal_accessors.insert(n);
            }
        }
    }
    let old_views = doc["bufferViews"].as_array().cloned().unwrap_or_default();
    let view_data = |v: &Value| {
        let at = v["byteOffset"].as_u64().unwrap_or(0) as usize;
        bin[at..at + v["byteLength"].as_u64().expect("byteLength") as usize].to_vec()
    };
    let mut new_bin = Vec::new();
    let mut fallback_len = 0usize;
    let mut views = Vec::new();
    let accessors = doc["accessors"].as_array_mut().expect("accessors");
    for (a_index, acc) in accessors.iter_mut().enumerate() {
        let Some(view) = acc["bufferView"].as_u64() else { continue };
        let old = &old_views[view as usize];
        assert!(old["byteStride"].is_null() && acc["byteOffset"].as_u64().unwrap_or(0) == 0, "tightly packed data");
        let data = view_data(old);
        let count = acc["count"].as_u64().expect("count") as usize;
        let element = component_size(acc["componentType"].as_u64().expect("componentType"))
            * multiplicity(acc["type"].as_str().expect("type"));
        let (encoded, stride, mode, filter) = if index_accessors.contains(&(a_index as u64)) {
            let indices: Vec<u32> = match element {
                2 => data.chunks_exact(2).map(|c| u32::from(u16::from_le_bytes([c[0], c[1]]))).collect(),
                4 => data.chunks_exact(4).map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect(),
                _ => panic!("index size {element}"),
            };
            let vertices = indices.iter().max().map_or(0, |&m| m as usize + 1);
            // The codec is the same for 16- and 32-bit indices; the decoder writes `stride` bytes.
            let encoded = meshopt::encode_index_buffer(&indices, vertices).expect("index encoding");
            (encoded, element, "TRIANGLES", None)
        } else if quantize && normal_accessors.contains(&(a_index as u64)) {
            let floats: Vec<[f32; 4]> = data
                .chunks_exact(12)
                .map(|c| {
                    let f = |k: usize| f32::from_le_bytes(c[4 * k..4 * k + 4].try_into().expect("4 bytes"));
                    [f(0), f(1), f(2), 0.0]
                })
                .collect();
            let oct: Vec<[i8; 4]> = meshopt::encode_filter_oct::<i8>(&floats, 8);
            let bytes: Vec<u8> = oct.iter().flat_map(|v| v.map(|x| x as u8)).collect();
            acc["componentType"] = json!(5120);
            acc["normalized"] = json!(true);
            acc.as_object_mut().expect("accessor object").remove("min");
            acc.as_object_mut().expect("accessor object").remove("max");
            (encode_vertices(&bytes, count, 4), 4, "ATTRIBUTES", Some("OCTAHEDRAL"))
        } else {
            assert!(element.is_multiple_of(4), "vertex codec needs 4-byte elements, accessor {a_index} has {element}");
            (encode_vertices(&data, count, element), element, "ATTRIBUTES", None)
        };
        while !new_bin.len().is_multiple_of(4) {
            new_bin.push(0);
        }
        let mut ext = json!({"buffer": 0, "byteOffset": new_bin.len(), "byteLength": encoded.len(),
                             "byteStride": stride, "count": count, "mode": mode});
        if let Some(f) = filter {
            ext["filter"] = json!(f);
        }
        new_bin.extend(&encoded);
        let mut v = json!({"buffer": 1, "byteOffset": fallback_len, "byteLength": count * stride,
                           "extensions": {"EXT_meshopt_compression": ext}});
        if mode == "ATTRIBUTES" {
            v["byteStride"] = json!(stride);
        }
        fallback_len += (count * stride).next_multiple_of(4);
        acc["bufferView"] = json!(views.len());
        views.push(v);
    }
    doc["bufferViews"] = Value::Array(views);
    doc["buffers"] = json!([
        {"byteLength": new_bin.len().next_multiple_of(4)},
        {"byteLength": fallback_len, "extensions": {"EXT_meshopt_compression": {"fallback": true}}}
    ]);
    let mut used = vec![json!("EXT_meshopt_compression")];
    if quantize {
        used.push(json!("KHR_mesh_quantization"));
    }
    for key in ["extensionsUsed", "extensionsRequired"] {
        let list = doc[key].as_array().cloned().unwrap_or_default();
        doc[key] = Value::Array(list.into_iter().chain(used.iter().cloned()).collect());
    }
    join_glb(&doc, new_bin)
}

/// `count` vertices of `stride` bytes through meshopt's vertex codec (the crate's typed
/// wrapper needs the vertex size at compile time).
fn encode_vertices(bytes: &[u8], count: usize, stride: usize) -> Vec<u8> {
    assert_eq!(bytes.len(), count * stride);
    // SAFETY: a pure function of two sizes.
    let bound = unsafe { meshopt::ffi::meshopt_encodeVertexBufferBound(count, stride) };
    let mut out = vec![0u8; bound];
    // SAFETY: `out` has the codec's bound for count × stride bytes, and `bytes` holds them.
    let n = unsafe {
        meshopt::ffi::meshopt_encodeVertexBuffer(out.as_mut_ptr(), out.len(), bytes.as_ptr().cast(), count, stride)
    };
    assert!(n > 0, "vertex encoding failed");
    out.truncate(n);
    out
}
