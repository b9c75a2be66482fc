//! Loader tests of glTF 2.0 materials (issue #37 point 4) and their bad inputs: alpha modes
//! and cutoffs, normal textures with file tangents (zero-length ones replaced) or generated
//! ones, metallic-roughness and occlusion textures, a missing texture file.

use base64::Engine as _;
use glam::Vec3;

use super::*;

/// A quad in the xz plane facing +y with UVs, optional TANGENTs (one per vertex), the
/// material JSON `material`, and the images `images` (JSON array body).
fn quad_gltf(material: &str, tangents: Option<[[f32; 4]; 4]>, images: &str, textures: &str) -> String {
    let positions: [[f32; 3]; 4] = [[0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 1.0], [1.0, 0.0, 0.0]];
    let normals = [[0.0f32, 1.0, 0.0]; 4];
    let uvs: [[f32; 2]; 4] = [[0.0, 0.0], [0.0, 1.0], [1.0, 1.0], [1.0, 0.0]];
    let indices: [u16; 6] = [0, 1, 2, 0, 2, 3];
    let mut bin = Vec::new();
    bin.extend(bytemuck::cast_slice::<_, u8>(&positions));
    bin.extend(bytemuck::cast_slice::<_, u8>(&normals));
    bin.extend(bytemuck::cast_slice::<_, u8>(&uvs));
    bin.extend(bytemuck::cast_slice::<_, u8>(&indices));
    bin.extend([0u8; 4]);
    let tangent_offset = bin.len();
    if let Some(t) = tangents {
        bin.extend(bytemuck::cast_slice::<_, u8>(&t));
    }
    let uri =
        format!("data:application/octet-stream;base64,{}", base64::engine::general_purpose::STANDARD.encode(&bin));
    let (tangent_attr, tangent_view, tangent_accessor) = if tangents.is_some() {
        (
            r#","TANGENT":4"#.to_string(),
            format!(r#",{{"buffer":0,"byteOffset":{tangent_offset},"byteLength":64}}"#),
            r#",{"bufferView":4,"componentType":5126,"count":4,"type":"VEC4"}"#.to_string(),
        )
    } else {
        (String::new(), String::new(), String::new())
    };
    format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"NORMAL":1,"TEXCOORD_0":2{tangent_attr}}},"indices":3,"material":0}}]}}],
        "materials":[{material}],"textures":[{textures}],"images":[{images}],
        "buffers":[{{"uri":"{uri}","byteLength":{len}}}],
        "bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":48}},{{"buffer":0,"byteOffset":48,"byteLength":48}},
            {{"buffer":0,"byteOffset":96,"byteLength":32}},{{"buffer":0,"byteOffset":128,"byteLength":12}}{tangent_view}],
        "accessors":[{{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[0,0,0],"max":[1,0,1]}},
            {{"bufferView":1,"componentType":5126,"count":4,"type":"VEC3"}},
            {{"bufferView":2,"componentType":5126,"count":4,"type":"VEC2"}},
            {{"bufferView":3,"componentType":5123,"count":6,"type":"SCALAR"}}{tangent_accessor}]}}"#,
        len = bin.len()
    )
}

fn png_uri(rgba: [u8; 4]) -> String {
    let mut png = Vec::new();
    image::RgbaImage::from_pixel(2, 2, image::Rgba(rgba))
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .expect("encode png");
    format!("data:image/png;base64,{}", base64::engine::general_purpose::STANDARD.encode(&png))
}

fn load(json: &str) -> Scene {
    load_gltf_bytes(json.as_bytes(), None, &LoadOptions::default()).expect("loads")
}

#[test]
fn alpha_modes_and_cutoffs_are_read_and_bad_cutoffs_are_clamped_with_a_warning() {
    let cases = [
        (r#"{"name":"opaque"}"#, None, false),
        (r#"{"name":"mask","alphaMode":"MASK"}"#, Some(0.5), false),
        (r#"{"name":"mask3","alphaMode":"MASK","alphaCutoff":0.3}"#, Some(0.3), false),
        (r#"{"name":"glass","alphaMode":"BLEND"}"#, Some(0.5), true),
        (r#"{"name":"high","alphaMode":"MASK","alphaCutoff":7.5}"#, Some(1.0), true),
        (r#"{"name":"low","alphaMode":"MASK","alphaCutoff":-2}"#, Some(0.0), true),
    ];
    for (material, cutoff, warns) in cases {
        let scene = load(&quad_gltf(material, None, "", ""));
        let m = &scene.materials[0];
        assert_eq!(m.alpha_cutoff, cutoff, "{material}");
        let named = scene.warnings.iter().any(|w| w.contains(&format!("material '{}'", m.name)));
        assert_eq!(named, warns, "{material}: {:?}", scene.warnings);
    }
}

#[test]
fn normal_textures_use_file_tangents_or_mikktspace_and_replace_zero_ones() {
    let tex = r#"{"source":0}"#;
    let image = format!(r#"{{"uri":"{}"}}"#, png_uri([128, 128, 255, 255]));
    let material = r#"{"name":"bumpy","normalTexture":{"index":0,"scale":0.5}}"#;
    // The file's tangents: kept (normalised), with their handedness.
    let given = [[2.0, 0.0, 0.0, -1.0]; 4];
    let scene = load(&quad_gltf(material, Some(given), &image, tex));
    let m = &scene.materials[0];
    assert_eq!((m.normal_texture, m.normal_scale), (Some(0), 0.5));
    for v in &scene.meshes[0].primitives[0].vertices {
        assert_eq!(v.tangent, [1.0, 0.0, 0.0, -1.0]);
    }
    // None in the file: MikkTSpace's. u runs along +x, v along +z; n × t = y × x = −z runs
    // against v, so the handedness is −1.
    let scene = load(&quad_gltf(material, None, &image, tex));
    for v in &scene.meshes[0].primitives[0].vertices {
        let t = glam::Vec4::from(v.tangent);
        assert!((t.truncate() - Vec3::X).length() < 1e-5 && t.w == -1.0, "{t}");
    }
    // Zero-length tangents: replaced by MikkTSpace's, with a warning.
    let scene = load(&quad_gltf(material, Some([[0.0; 4]; 4]), &image, tex));
    assert!(scene.warnings.iter().any(|w| w.contains("zero length")), "{:?}", scene.warnings);
    for v in &scene.meshes[0].primitives[0].vertices {
        assert!((Vec3::new(v.tangent[0], v.tangent[1], v.tangent[2]) - Vec3::X).length() < 1e-5);
    }
}

#[test]
fn metallic_roughness_and_occlusion_textures_are_loaded() {
    let image = format!(r#"{{"uri":"{}"}},{{"uri":"{}"}}"#, png_uri([0, 128, 255, 255]), png_uri([200, 0, 0, 255]));
    let material = r#"{"name":"m","pbrMetallicRoughness":{"metallicRoughnessTexture":{"index":0}},"occlusionTexture":{"index":1}}"#;
    let scene = load(&quad_gltf(material, None, &image, r#"{"source":0},{"source":1}"#));
    let m = &scene.materials[0];
    assert_eq!((m.metallic_roughness_texture, m.occlusion_texture), (Some(0), Some(1)));
    assert_eq!(scene.textures.len(), 2);
}

#[test]
fn a_missing_texture_file_leaves_the_factor_with_a_warning_naming_it() {
    let dir = std::env::temp_dir().join(format!("gi-lab-missing-texture-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let json = quad_gltf(
        r#"{"name":"wood","pbrMetallicRoughness":{"baseColorFactor":[0.5,0.4,0.3,1],"baseColorTexture":{"index":0}}}"#,
        None,
        r#"{"uri":"wood.png"}"#,
        r#"{"source":0}"#,
    );
    let path = dir.join("scene.gltf");
    std::fs::write(&path, json).expect("write");
    let scene = load_gltf_file(&path, &LoadOptions::default()).expect("loads without its texture");
    let m = &scene.materials[0];
    assert_eq!(m.base_color_texture, None);
    assert_eq!(m.base_color.truncate(), Vec3::new(0.5, 0.4, 0.3));
    assert!(
        scene.warnings.iter().any(|w| w.contains("material 'wood'") && w.contains("wood.png")),
        "{:?}",
        scene.warnings
    );
    let _ = std::fs::remove_dir_all(&dir);
}
