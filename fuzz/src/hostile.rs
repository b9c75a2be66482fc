//! The hostile and synthetic glTF files of the loader's own tests
//! (`render/src/scene/gltf_load/tests.rs` and `compression_tests.rs`, which are private to
//! that crate), rebuilt here as fuzz seeds, plus the 2³¹-element accessors of issue #19.
//!
//! Each builder mirrors one test's file: the one-triangle document with its buffer in a data
//! URI or a GLB BIN chunk, counts past the data, offsets that overflow, out-of-range indices,
//! points and lines, URIs that leave the scene folder, malformed data URIs, files that are not
//! glTF, invalid JSON, bad references, cycles, animations, sparse accessors, textures and
//! meshopt-compressed views.

use base64::Engine as _;
use serde_json::{Value, json};

use crate::seeds::{Seed, tiny_image, tiny_png};

/// 2³¹, the element count of the accessors that must be refused before any allocation.
pub const HUGE_COUNT: u64 = 1 << 31;

/// Binary data of one triangle: 3 VEC3 f32 positions (36 bytes) then 3 u16 indices (+2 padding).
pub fn triangle_bin(indices: [u16; 3]) -> Vec<u8> {
    let positions: [f32; 9] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];
    let mut bin: Vec<u8> = positions.iter().flat_map(|x| x.to_le_bytes()).collect();
    bin.extend(indices.iter().flat_map(|x| x.to_le_bytes()));
    bin.extend([0, 0]);
    bin
}

/// A base64 `data:` URI of `bytes`.
pub fn data_uri(bytes: &[u8]) -> String {
    format!("data:application/octet-stream;base64,{}", base64::engine::general_purpose::STANDARD.encode(bytes))
}

/// A one-triangle glTF whose buffer is `buffer` (a JSON fragment: `"uri":"…",` or empty),
/// with `count` positions and primitive `mode`.
pub fn triangle_gltf_with(buffer: &str, count: u64, mode: u32) -> String {
    format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
            "meshes":[{{"name":"tri","primitives":[{{"attributes":{{"POSITION":0}},"indices":1,"mode":{mode}}}]}}],
            "buffers":[{{{buffer}"byteLength":44}}],
            "bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":6}}],
            "accessors":[{{"bufferView":0,"componentType":5126,"count":{count},"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
                         {{"bufferView":1,"componentType":5123,"count":3,"type":"SCALAR"}}]}}"#
    )
}

/// The one-triangle glTF with its buffer in a data URI.
pub fn triangle_gltf() -> String {
    triangle_gltf_with(&format!("\"uri\":\"{}\",", data_uri(&triangle_bin([0, 1, 2]))), 3, 4)
}

/// The one-triangle GLB with `count` positions.
pub fn triangle_glb(count: u64) -> Vec<u8> {
    gi_render::scene::cornell::glb(triangle_gltf_with("", count, 4).into_bytes(), triangle_bin([0, 1, 2]))
}

/// `json` (an object) with `extra` (`"key":value,…`) appended to its members.
fn with_members(json: &str, extra: &str) -> String {
    match json.trim_end().strip_suffix('}') {
        Some(head) => format!("{head},{extra}}}"),
        None => json.to_string(),
    }
}

/// The triangle with a base colour texture whose image has `image_uri`.
fn textured(image_uri: &str) -> String {
    let json = triangle_gltf().replacen(r#""indices":1,"#, r#""indices":1,"material":0,"#, 1);
    with_members(
        &json,
        &format!(
            r#""materials":[{{"pbrMetallicRoughness":{{"baseColorTexture":{{"index":0,"extensions":{{"KHR_texture_transform":{{"offset":[0.5,0],"rotation":1.5,"scale":[2,2],"texCoord":0}}}}}}}},"emissiveFactor":[1,0.5,1],"emissiveTexture":{{"index":1,"texCoord":1}},"extensions":{{"KHR_materials_emissive_strength":{{"emissiveStrength":4}}}}}}],"textures":[{{"source":0}},{{"source":0}}],"images":[{{"uri":"{image_uri}"}}]"#
        ),
    )
}

/// The 2³¹-element accessors of issue #19: POSITION with 2³¹ elements on the triangle's
/// 36-byte view (GLB and data URI), indices with 2³¹ elements, 2³¹ zero-filled elements
/// (no buffer view, one sparse substitution), and 2³¹ elements on a view whose byteStride
/// is 4 over a one-byte buffer, and a meshopt-compressed view of 2³¹ vertices. The loader
/// must refuse each before it allocates.
pub fn huge_accessor_cases() -> Vec<Seed> {
    let bin = triangle_bin([0, 1, 2]);
    let mut huge_meshopt = meshopt_triangle();
    huge_meshopt["bufferViews"][0]["extensions"]["EXT_meshopt_compression"]["count"] = json!(HUGE_COUNT);
    let sparse = with_members(
        &triangle_gltf().replace(
            r#"{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}"#,
            &format!(
                r#"{{"componentType":5126,"count":{HUGE_COUNT},"type":"VEC3","sparse":{{"count":1,"indices":{{"bufferView":1,"componentType":5123}},"values":{{"bufferView":0}}}}}}"#
            ),
        ),
        r#""extras":{"case":"sparse"}"#,
    );
    let strided = format!(
        r#"{{"asset":{{"version":"2.0"}},"nodes":[{{"mesh":0}}],"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}}}}]}}],
            "buffers":[{{"byteLength":4}}],"bufferViews":[{{"buffer":0,"byteLength":1,"byteStride":4}}],
            "accessors":[{{"bufferView":0,"componentType":5121,"count":{HUGE_COUNT},"type":"VEC3"}}]}}"#
    );
    vec![
        Seed::new("huge-position-count.glb", triangle_glb(HUGE_COUNT)),
        Seed::new(
            "huge-position-count.gltf",
            triangle_gltf_with(&format!("\"uri\":\"{}\",", data_uri(&bin)), HUGE_COUNT, 4),
        ),
        Seed::new(
            "huge-index-count.glb",
            gi_render::scene::cornell::glb(
                triangle_gltf_with("", 3, 4)
                    .replace(
                        r#""componentType":5123,"count":3"#,
                        &format!(r#""componentType":5123,"count":{HUGE_COUNT}"#),
                    )
                    .into_bytes(),
                bin.clone(),
            ),
        ),
        Seed::new("huge-sparse-zero-count.gltf", sparse),
        Seed::new("huge-strided-count.glb", gi_render::scene::cornell::glb(strided.into_bytes(), vec![7; 4])),
        Seed::new("huge-meshopt-count.gltf", huge_meshopt.to_string()),
    ]
}

/// Every hostile and synthetic case as a seed.
pub fn gltf_cases() -> Vec<Seed> {
    let bin = triangle_bin([0, 1, 2]);
    let tri_uri = format!("\"uri\":\"{}\",", data_uri(&bin));
    let mut s = vec![
        Seed::new("triangle.gltf", triangle_gltf()),
        Seed::new("triangle.glb", triangle_glb(3)),
        Seed::new(
            "index-out-of-range.gltf",
            triangle_gltf_with(&format!("\"uri\":\"{}\",", data_uri(&triangle_bin([0, 1, 7]))), 3, 4),
        ),
        Seed::new("short-buffer.gltf", triangle_gltf_with(&format!("\"uri\":\"{}\",", data_uri(&bin[..30])), 3, 4)),
        Seed::new("buffer-without-uri.gltf", triangle_gltf_with("", 3, 4)),
        Seed::new("external-bin.gltf", triangle_gltf_with("\"uri\":\"scene.bin\",", 3, 4)),
        Seed::new(
            "offset-overflow.gltf",
            triangle_gltf()
                .replace(r#""byteOffset":36,"byteLength":6"#, r#""byteOffset":18446744073709551615,"byteLength":6"#),
        ),
        Seed::new("strip.gltf", triangle_gltf_with(&tri_uri, 3, 5)),
        Seed::new("fan.gltf", triangle_gltf_with(&tri_uri, 3, 6)),
    ];
    for count in [4, 1000, u64::MAX / 2, u64::MAX] {
        s.push(Seed::new(format!("count-{count}.gltf"), triangle_gltf_with(&tri_uri, count, 4)));
    }
    for mode in [0, 1, 2, 3, 9] {
        s.push(Seed::new(format!("mode-{mode}.gltf"), triangle_gltf_with(&tri_uri, 3, mode)));
    }
    for uri in ["../secret.bin", "%2e%2e/secret.bin", "file:///etc/passwd", "C:/secret.bin", "\\\\\\\\server\\\\share"]
    {
        s.push(Seed::new(format!("escape-{}.gltf", s.len()), triangle_gltf_with(&format!("\"uri\":\"{uri}\","), 3, 4)));
    }
    for uri in [
        "data:application/octet-stream;base64,@@@not base64@@@",
        "data:application/octet-stream,plain",
        "data:application/octet-stream;base64",
    ] {
        s.push(Seed::new(
            format!("bad-data-uri-{}.gltf", s.len()),
            triangle_gltf_with(&format!("\"uri\":\"{uri}\","), 3, 4),
        ));
    }
    let glb = triangle_glb(3);
    s.push(Seed::new("truncated.glb", glb[..glb.len() - 10].to_vec()));
    s.push(Seed::new("not-gltf.png", tiny_png()));
    s.push(Seed::new("empty", Vec::new()));
    for (i, text) in [
        r#"{"asset": {"version": "2.0"}, "nodes": ["#,
        r#"{"nodes": []}"#,
        r#"{"asset": {"version": "2.0"}, "nodes": [{"mesh": -1}]}"#,
        r#"{"asset":{"version":"1.0"}}"#,
        r#"{"asset":{"version":"2.0","minVersion":"2.1"}}"#,
        r#"{"asset":{"version":"2.0"}}"#,
    ]
    .iter()
    .enumerate()
    {
        s.push(Seed::new(format!("json-{i}.gltf"), *text));
    }
    let base = triangle_gltf();
    for (i, (from, to)) in [
        (r#""nodes":[{"mesh":0}]"#, r#""nodes":[{"mesh":5}]"#),
        (r#""scene":0"#, r#""scene":2"#),
        (r#""POSITION":0"#, r#""POSITION":9"#),
        (r#""indices":1"#, r#""indices":0"#),
        (r#""componentType":5123"#, r#""componentType":1"#),
        (r#""type":"VEC3""#, r#""type":"MAT4""#),
        (r#""nodes":[{"mesh":0}]"#, r#""nodes":[{"mesh":0,"camera":0}],"cameras":[{"type":"perspective","perspective":{"yfov":0.8,"znear":0.01,"zfar":100}},{"type":"orthographic","orthographic":{"xmag":1,"ymag":1,"znear":0,"zfar":5}}]"#),
        (r#""nodes":[{"mesh":0}]"#, r#""nodes":[{"mesh":0,"extensions":{"KHR_lights_punctual":{"light":0}}}],"extensions":{"KHR_lights_punctual":{"lights":[{"type":"spot","spot":{"innerConeAngle":0.2,"outerConeAngle":0.5},"intensity":10,"range":5},{"type":"directional"}]}}"#),
        (r#""nodes":[{"mesh":0}]"#, r#""nodes":[{"mesh":0,"children":[1]},{"children":[0]}]"#),
        (r#""nodes":[{"mesh":0}]"#, r#""nodes":[{"mesh":0,"children":[1,2]},{"matrix":[2,0,0,0,0,2,0,0,0,0,2,0,1,2,3,1]},{"rotation":[0,0,0,0],"scale":[1,1,1]}]"#),
        (r#""asset":{"version":"2.0"},"#, r#""asset":{"version":"2.0"},"extensionsRequired":["KHR_draco_mesh_compression"],"extensionsUsed":["EXT_foo"],"#),
    ]
    .iter()
    .enumerate()
    {
        s.push(Seed::new(format!("reference-{i}.gltf"), base.replacen(from, to, 1)));
    }
    s.push(Seed::new("animation.gltf", animated()));
    s.push(Seed::new("sparse.gltf", sparse()));
    let png_uri = format!("data:image/png;base64,{}", base64::engine::general_purpose::STANDARD.encode(tiny_png()));
    s.push(Seed::new("texture.gltf", textured(&png_uri)));
    s.push(Seed::new("bad-texture.gltf", textured(&data_uri(b"not a png"))));
    for (name, format) in
        [("jpeg", image::ImageFormat::Jpeg), ("hdr", image::ImageFormat::Hdr), ("exr", image::ImageFormat::OpenExr)]
    {
        let uri = format!(
            "data:image/{name};base64,{}",
            base64::engine::general_purpose::STANDARD.encode(tiny_image(format))
        );
        s.push(Seed::new(format!("texture-{name}.gltf"), textured(&uri)));
    }
    // A JPEG whose frame header declares 12800 × 12800 pixels (its data holds 8 × 4).
    let mut jpeg = tiny_image(image::ImageFormat::Jpeg);
    if let Some(sof) = jpeg.windows(2).position(|w| w == [0xFF, 0xC0]) {
        for k in [5, 7] {
            if let Some(dim) = jpeg.get_mut(sof + k..sof + k + 2) {
                dim.copy_from_slice(&12800u16.to_be_bytes());
            }
        }
    }
    let uri = format!("data:image/jpeg;base64,{}", base64::engine::general_purpose::STANDARD.encode(jpeg));
    s.push(Seed::new("texture-jpeg-declaring-12800x12800.gltf", textured(&uri)));
    s.push(Seed::new("meshopt.gltf", meshopt_triangle().to_string()));
    s.push(Seed::new("meshopt-khr.gltf", meshopt_triangle().to_string().replace("EXT_meshopt", "KHR_meshopt")));
    s.push(Seed::new("quantized.gltf", quantized().to_string()));
    s.extend(huge_accessor_cases());
    s
}

/// The triangle with a LINEAR translation animation (times [0, 1], two VEC3 values).
fn animated() -> String {
    let mut bin = triangle_bin([0, 1, 2]);
    bin.extend([0.0f32, 1.0].iter().flat_map(|x| x.to_le_bytes()));
    bin.extend([0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0].iter().flat_map(|x| x.to_le_bytes()));
    let base = triangle_gltf_with(&format!("\"uri\":\"{}\",", data_uri(&bin)), 3, 4)
        .replace(r#""byteLength":44"#, &format!(r#""byteLength":{}"#, bin.len()))
        .replacen(
            r#"{"buffer":0,"byteOffset":36,"byteLength":6}"#,
            r#"{"buffer":0,"byteOffset":36,"byteLength":6},{"buffer":0,"byteOffset":44,"byteLength":8},{"buffer":0,"byteOffset":52,"byteLength":24}"#,
            1,
        );
    let base = base.trim_end().strip_suffix("]}").unwrap_or(&base).to_string();
    format!(
        r#"{base},{{"bufferView":2,"componentType":5126,"count":2,"type":"SCALAR","min":[0],"max":[1]}},
            {{"bufferView":3,"componentType":5126,"count":2,"type":"VEC3"}}],
            "animations":[{{"name":"slide","channels":[{{"sampler":0,"target":{{"node":0,"path":"translation"}}}},{{"sampler":1,"target":{{"node":0,"path":"scale"}}}}],
            "samplers":[{{"input":2,"output":3,"interpolation":"LINEAR"}},{{"input":2,"output":3,"interpolation":"STEP"}}]}}]}}"#
    )
}

/// The triangle whose vertex 2 is moved by a sparse substitution.
fn sparse() -> String {
    let mut bin = triangle_bin([0, 1, 2]);
    bin.extend(2u16.to_le_bytes());
    bin.extend([0, 0]);
    bin.extend([0.0f32, 2.0, 0.0].iter().flat_map(|x| x.to_le_bytes()));
    format!(
        r#"{{"asset":{{"version":"2.0"}},"nodes":[{{"mesh":0}}],
            "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1}}]}}],
            "buffers":[{{"uri":"{}","byteLength":{}}}],
            "bufferViews":[{{"buffer":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":6}},
                           {{"buffer":0,"byteOffset":44,"byteLength":2}},{{"buffer":0,"byteOffset":48,"byteLength":12}}],
            "accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,2,0],
                           "sparse":{{"count":1,"indices":{{"bufferView":2,"componentType":5123}},"values":{{"bufferView":3}}}}}},
                         {{"bufferView":1,"componentType":5123,"count":3,"type":"SCALAR"}}]}}"#,
        data_uri(&bin),
        bin.len()
    )
}

/// A one-triangle document whose views are compressed with EXT_meshopt_compression.
pub fn meshopt_triangle() -> Value {
    let positions: [[f32; 3]; 3] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    let v = meshopt::encode_vertex_buffer(&positions).unwrap_or_default();
    let i = meshopt::encode_index_buffer(&[0, 1, 2], 3).unwrap_or_default();
    let mut data = v.clone();
    data.resize(v.len().next_multiple_of(4), 0);
    let index_at = data.len();
    data.extend(&i);
    json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": ["EXT_meshopt_compression"],
        "extensionsRequired": ["EXT_meshopt_compression"],
        "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
        "meshes": [{"name": "tri", "primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "buffers": [
            {"uri": data_uri(&data), "byteLength": data.len()},
            {"byteLength": 44, "extensions": {"EXT_meshopt_compression": {"fallback": true}}}
        ],
        "bufferViews": [
            {"buffer": 1, "byteOffset": 0, "byteLength": 36, "byteStride": 12,
             "extensions": {"EXT_meshopt_compression": {"buffer": 0, "byteOffset": 0, "byteLength": v.len(),
                            "byteStride": 12, "count": 3, "mode": "ATTRIBUTES", "filter": "NONE"}}},
            {"buffer": 1, "byteOffset": 36, "byteLength": 6,
             "extensions": {"EXT_meshopt_compression": {"buffer": 0, "byteOffset": index_at, "byteLength": i.len(),
                            "byteStride": 2, "count": 3, "mode": "TRIANGLES"}}}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}
        ]
    })
}

/// The KHR_mesh_quantization triangle: 16-bit positions padded to 8 bytes, normalized UVs.
fn quantized() -> Value {
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
    json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_mesh_quantization"], "extensionsRequired": ["KHR_mesh_quantization"],
        "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0, "scale": [0.01, 0.01, 0.01]}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "indices": 2}]}],
        "buffers": [{"uri": data_uri(&bin), "byteLength": bin.len()}],
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
    })
}
