//! Tests of compressed buffer views (`compression.rs`): a meshopt-compressed triangle made
//! with the `meshopt` crate's encoders decodes, and malformed or hostile compressed data is an
//! error, never a panic or an unbounded allocation.

use base64::Engine as _;
use serde_json::{Value, json};

use super::compression::{MAX_DECODED_BYTES, min_vertex_stream_len};
use super::{LoadOptions, SceneError, load_gltf_bytes};

const POSITIONS: [[f32; 3]; 3] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];

/// The encoded positions and indices of one triangle.
fn encoded() -> (Vec<u8>, Vec<u8>) {
    let vertices = meshopt::encode_vertex_buffer(&POSITIONS).expect("vertex encoding");
    let indices = meshopt::encode_index_buffer(&[0, 1, 2], 3).expect("index encoding");
    (vertices, indices)
}

/// A one-triangle glTF whose views are compressed: buffer 0 (a data URI) holds `data`,
/// buffer 1 is the fallback; view 0 (positions) and 1 (indices) carry `EXT_meshopt_compression`.
fn document(data: &[u8], vertex_len: usize, index_len: usize) -> Value {
    let uri =
        format!("data:application/octet-stream;base64,{}", base64::engine::general_purpose::STANDARD.encode(data));
    let index_at = vertex_len.next_multiple_of(4);
    json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": ["EXT_meshopt_compression"],
        "extensionsRequired": ["EXT_meshopt_compression"],
        "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
        "meshes": [{"name": "tri", "primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "buffers": [
            {"uri": uri, "byteLength": data.len()},
            {"byteLength": 44, "extensions": {"EXT_meshopt_compression": {"fallback": true}}}
        ],
        "bufferViews": [
            {"buffer": 1, "byteOffset": 0, "byteLength": 36, "byteStride": 12,
             "extensions": {"EXT_meshopt_compression": {"buffer": 0, "byteOffset": 0, "byteLength": vertex_len,
                            "byteStride": 12, "count": 3, "mode": "ATTRIBUTES"}}},
            {"buffer": 1, "byteOffset": 36, "byteLength": 6,
             "extensions": {"EXT_meshopt_compression": {"buffer": 0, "byteOffset": index_at, "byteLength": index_len,
                            "byteStride": 2, "count": 3, "mode": "TRIANGLES"}}}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}
        ]
    })
}

fn triangle() -> Value {
    let (v, i) = encoded();
    let mut data = v.clone();
    data.resize(v.len().next_multiple_of(4), 0);
    data.extend(&i);
    document(&data, v.len(), i.len())
}

fn load(doc: &Value) -> Result<crate::scene::Scene, SceneError> {
    load_gltf_bytes(&serde_json::to_vec(doc).expect("JSON"), None, &LoadOptions::default())
}

fn error(doc: &Value) -> String {
    match load(doc) {
        Ok(_) => panic!("loaded a broken file"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn a_meshopt_compressed_triangle_decodes() {
    let scene = load(&triangle()).expect("the compressed triangle loads");
    assert!(!scene.warnings.iter().any(|w| w.contains("extension")), "{:?}", scene.warnings);
    let p = &scene.meshes[0].primitives[0];
    assert_eq!(p.vertices.iter().map(|v| v.position).collect::<Vec<_>>(), POSITIONS);
    // The index codec may rotate a triangle's corners, never its winding.
    let mut rotated = p.indices.clone();
    let k = rotated.iter().position(|&i| i == 0).expect("corner 0");
    rotated.rotate_left(k);
    assert_eq!(rotated, [0, 1, 2]);

    // The same data under the ratified extension's name.
    let text = serde_json::to_string(&triangle()).expect("JSON").replace("EXT_meshopt", "KHR_meshopt");
    let khr: Value = serde_json::from_str(&text).expect("JSON");
    assert_eq!(load(&khr).expect("KHR_meshopt_compression loads").triangle_count(), 1);
}

#[test]
fn malformed_compressed_data_is_an_error_at_every_length() {
    let (v, i) = encoded();
    for cut in 0..v.len() {
        let mut data = v[..cut].to_vec();
        data.resize(cut.next_multiple_of(4), 0);
        data.extend(&i);
        let e = error(&document(&data, cut, i.len()));
        assert!(e.contains("buffer view 0") && e.contains("malformed"), "cut at {cut}: {e}");
    }
    for cut in 0..i.len() {
        let mut data = v.clone();
        data.resize(v.len().next_multiple_of(4), 0);
        data.extend(&i[..cut]);
        let e = error(&document(&data, v.len(), cut));
        assert!(e.contains("buffer view 1") && e.contains("malformed"), "cut at {cut}: {e}");
    }
}

/// Random bytes in the encoded streams decode to an error or to garbage that the ordinary
/// checks catch (indices out of range), never to a panic.
#[test]
fn mutated_compressed_data_never_panics() {
    let (v, i) = encoded();
    let mut data = v.clone();
    data.resize(v.len().next_multiple_of(4), 0);
    data.extend(&i);
    let mut state = 0x2545_f491_4f6c_dd1d_u64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    for _ in 0..2000 {
        let mut bytes = data.clone();
        for _ in 0..1 + next() % 3 {
            let at = (next() % bytes.len() as u64) as usize;
            bytes[at] = next() as u8;
        }
        let _ = load(&document(&bytes, v.len(), i.len()));
    }
}

/// A change to a [`triangle`] document.
type Edit = fn(&mut Value);

/// The extension object of view `view` of a [`triangle`] document.
fn ext(doc: &mut Value, view: usize) -> &mut Value {
    &mut doc["bufferViews"][view]["extensions"]["EXT_meshopt_compression"]
}

#[test]
fn compressed_view_fields_are_checked() {
    let cases: [(&str, Edit, &str); 16] = [
        ("unknown mode", (|d| ext(d, 0)["mode"] = json!("QUADS")), "mode"),
        ("missing count", (|d| _ = ext(d, 0).as_object_mut().map(|o| o.remove("count"))), "count"),
        ("negative count", (|d| ext(d, 0)["count"] = json!(-3)), "count"),
        ("attribute stride 6", (|d| ext(d, 0)["byteStride"] = json!(6)), "multiple of 4"),
        ("attribute stride 260", (|d| ext(d, 0)["byteStride"] = json!(260)), "multiple of 4"),
        ("index stride 3", (|d| ext(d, 1)["byteStride"] = json!(3)), "2 or 4"),
        ("4 triangle indices", (|d| ext(d, 1)["count"] = json!(4)), "multiple of 3"),
        ("filtered indices", (|d| ext(d, 1)["filter"] = json!("OCTAHEDRAL")), "filter"),
        ("unknown filter", (|d| ext(d, 0)["filter"] = json!("ZIGZAG")), "ZIGZAG"),
        ("COLOR in EXT", (|d| ext(d, 0)["filter"] = json!("COLOR")), "COLOR"),
        ("quaternions of 12 bytes", (|d| ext(d, 0)["filter"] = json!("QUATERNION")), "byteStride 12"),
        ("no such buffer", (|d| ext(d, 0)["buffer"] = json!(7)), "does not exist"),
        ("past the buffer", (|d| ext(d, 0)["byteOffset"] = json!(1000)), "has only"),
        ("offset overflow", (|d| ext(d, 0)["byteOffset"] = json!(u64::MAX)), "buffer view 0"),
        ("a terabyte of vertices", (|d| ext(d, 0)["count"] = json!(1u64 << 36)), "MiB"),
        ("just over the limit", (|d| ext(d, 0)["count"] = json!(MAX_DECODED_BYTES / 12 + 1)), "MiB"),
    ];
    for (what, edit, expected) in cases {
        let mut doc = triangle();
        edit(&mut doc);
        let e = error(&doc);
        assert!(e.contains(expected), "{what}: {e}");
    }
}

/// Found by the fuzzer (issue #19): a 37-byte vertex stream declaring 2²⁶ vertices of 12
/// bytes (768 MiB, under the per-file limit) made the loader allocate the whole destination
/// before the decoder refused the stream. Streams too short for their count are now refused
/// first, for the vertex codec and both index codecs.
#[test]
fn counts_the_encoded_data_cannot_hold_are_refused_before_decoding() {
    let cases: [(&str, Edit); 3] = [
        ("2^26 vertices", |d| ext(d, 0)["count"] = json!(1u64 << 26)),
        ("2^25 triangles", |d| ext(d, 1)["count"] = json!(3u64 << 25)),
        ("2^27 indices", |d| {
            ext(d, 1)["mode"] = json!("INDICES");
            ext(d, 1)["count"] = json!(1u64 << 27);
        }),
    ];
    for (what, edit) in cases {
        let mut doc = triangle();
        edit(&mut doc);
        let e = error(&doc);
        assert!(e.contains("malformed") && e.contains("need at least"), "{what}: {e}");
    }
}

/// The lower bound of the vertex stream's length holds for what meshoptimizer's encoder
/// writes, in both format versions, for the most and the least compressible data.
#[test]
fn the_vertex_stream_bound_never_refuses_real_streams() {
    let mut state = 0x9e37_79b9_u32;
    for stride in [4, 8, 12, 16, 20, 32, 64, 128, 252, 256] {
        for count in [0, 1, 15, 16, 17, 255, 256, 257, 511, 2000] {
            let zeros = vec![0u8; count * stride];
            let noise: Vec<u8> = (0..count * stride)
                .map(|_| {
                    state ^= state << 13;
                    state ^= state >> 17;
                    state ^= state << 5;
                    state as u8
                })
                .collect();
            for (data, version) in [(&zeros, 0), (&zeros, 1), (&noise, 0), (&noise, 1)] {
                // SAFETY: the output buffer has the encoder's own worst-case size, and `data`
                // holds count × stride bytes.
                let len = unsafe {
                    let mut out = vec![0u8; meshopt::ffi::meshopt_encodeVertexBufferBound(count, stride)];
                    meshopt::ffi::meshopt_encodeVertexBufferLevel(
                        out.as_mut_ptr(),
                        out.len(),
                        data.as_ptr().cast(),
                        count,
                        stride,
                        3,
                        version,
                    )
                };
                assert!(len > 0, "encoding failed");
                let min = min_vertex_stream_len(count, stride);
                assert!(len >= min, "stride {stride}, count {count}, version {version}: {len} < {min}");
            }
        }
    }
}

#[test]
fn a_plain_view_on_an_empty_fallback_buffer_is_an_error() {
    let mut doc = triangle();
    doc["bufferViews"][0].as_object_mut().expect("view").remove("extensions");
    let e = error(&doc);
    assert!(e.contains("buffer view 0") && e.contains("buffer 1 has only 0 bytes"), "{e}");
}

/// `KHR_mesh_quantization`: 16-bit positions padded to 8-byte elements (with the node's scale
/// as the dequantizing transform) and normalized 16-bit texture coordinates.
#[test]
fn quantized_attributes_are_read() {
    let mut bin = Vec::new();
    for p in [[0i16, 0, 0], [100, 0, 0], [0, 100, 0]] {
        bin.extend(p.iter().flat_map(|x| x.to_le_bytes()));
        bin.extend([0, 0]);
    }
    for uv in [[0u16, 0], [65535, 0], [0, 32768]] {
        bin.extend(uv.iter().flat_map(|x| x.to_le_bytes()));
    }
    bin.extend([0u16, 1, 2].iter().flat_map(|x| x.to_le_bytes()));
    bin.extend([0, 0]);
    let uri =
        format!("data:application/octet-stream;base64,{}", base64::engine::general_purpose::STANDARD.encode(&bin));
    let doc = json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_mesh_quantization"], "extensionsRequired": ["KHR_mesh_quantization"],
        "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0, "scale": [0.01, 0.01, 0.01]}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "indices": 2}]}],
        "buffers": [{"uri": uri, "byteLength": bin.len()}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 24, "byteStride": 8},
            {"buffer": 0, "byteOffset": 24, "byteLength": 12},
            {"buffer": 0, "byteOffset": 36, "byteLength": 6}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5122, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [100, 100, 0]},
            {"bufferView": 1, "componentType": 5123, "normalized": true, "count": 3, "type": "VEC2"},
            {"bufferView": 2, "componentType": 5123, "count": 3, "type": "SCALAR"}
        ]
    });
    let scene = load(&doc).expect("the quantized triangle loads");
    assert!(!scene.warnings.iter().any(|w| w.contains("extension")), "{:?}", scene.warnings);
    let v = &scene.meshes[0].primitives[0].vertices;
    assert_eq!(
        v.iter().map(|v| v.position).collect::<Vec<_>>(),
        [[0.0, 0.0, 0.0], [100.0, 0.0, 0.0], [0.0, 100.0, 0.0]]
    );
    assert_eq!(v[1].uv, [1.0, 0.0]);
    assert!((v[2].uv[1] - 32768.0 / 65535.0).abs() < 1e-6);
    let state = scene.evaluate(0.0);
    let world = state.draws[0].world.transform_point3(glam::Vec3::from(v[1].position));
    assert!((world - glam::Vec3::X).length() < 1e-5, "the node's scale dequantizes: {world}");
}
