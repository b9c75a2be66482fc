//! Tests of the glTF loader: the shared real-world scenes, valid synthetic files and bad inputs.

use super::*;
use std::sync::atomic::{AtomicUsize, Ordering};

use base64::Engine as _;
use glam::Vec2;

use super::container::{percent_decode, relative_components, uri_scheme};
use super::materials::uv_transform;
use super::meshes::{fan_to_list, strip_to_list};
use crate::scene::{LightKind, Material};

/// `assets/scenes/<rel>` of the repository (the real scenes, each with its licence); fails
/// (does not skip) when missing.
fn real_scene(rel: &str) -> PathBuf {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../assets/scenes").join(rel);
    assert!(path.is_file(), "real scene {} is missing from the repository's assets/scenes/", path.display());
    path
}

/// A fresh, empty directory under the system temp dir (removed by [`TempDir`]'s drop).
struct TempDir(PathBuf);

impl TempDir {
    fn new(name: &str) -> Self {
        static COUNTER: AtomicUsize = AtomicUsize::new(0);
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let dir = std::env::temp_dir().join(format!("gi-lab-gltf-{name}-{}-{n}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("create temp dir");
        Self(dir)
    }
    fn path(&self) -> &Path {
        &self.0
    }
    fn write(&self, rel: &str, bytes: &[u8]) -> PathBuf {
        let p = self.0.join(rel);
        if let Some(parent) = p.parent() {
            std::fs::create_dir_all(parent).expect("create dir");
        }
        std::fs::write(&p, bytes).expect("write file");
        p
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Binary data of one triangle: 3 VEC3 f32 positions (36 bytes) then 3 u16 indices (6 bytes, +2 padding).
fn triangle_bin(indices: [u16; 3]) -> Vec<u8> {
    let positions: [f32; 9] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];
    let mut bin: Vec<u8> = positions.iter().flat_map(|x| x.to_le_bytes()).collect();
    bin.extend(indices.iter().flat_map(|x| x.to_le_bytes()));
    bin.extend([0, 0]);
    bin
}

fn data_uri(bytes: &[u8]) -> String {
    format!("data:application/octet-stream;base64,{}", base64::engine::general_purpose::STANDARD.encode(bytes))
}

/// A one-triangle glTF whose buffer is `buffer` (a JSON fragment: `"uri":"…",` or empty),
/// with `count` positions and primitive `mode`.
fn triangle_gltf_with(buffer: &str, count: u64, mode: u32) -> String {
    format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
            "meshes":[{{"name":"tri","primitives":[{{"attributes":{{"POSITION":0}},"indices":1,"mode":{mode}}}]}}],
            "buffers":[{{{buffer}"byteLength":44}}],
            "bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":6}}],
            "accessors":[{{"bufferView":0,"componentType":5126,"count":{count},"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
                         {{"bufferView":1,"componentType":5123,"count":3,"type":"SCALAR"}}]}}"#
    )
}

fn triangle_gltf(uri: &str) -> String {
    triangle_gltf_with(&format!("\"uri\":\"{uri}\","), 3, 4)
}

/// Wraps JSON and BIN into a .glb (the same layout as `cornell::glb`).
fn make_glb(json: &str, bin: &[u8]) -> Vec<u8> {
    let mut json = json.as_bytes().to_vec();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = b"glTF".to_vec();
    for x in [2, total, json.len()] {
        out.extend((x as u32).to_le_bytes());
    }
    out.extend(b"JSON");
    out.extend(&json);
    out.extend((bin.len() as u32).to_le_bytes());
    out.extend(b"BIN\0");
    out.extend(bin);
    out
}

fn load_str(json: &str) -> Result<Scene, SceneError> {
    load_gltf_bytes(json.as_bytes(), None, &LoadOptions::default())
}

// ---- the shared real-world scenes -------------------------------------------------

#[test]
fn shared_cornell_box_loads_lit_by_its_emitter() {
    let scene = load_gltf_file(&real_scene("cornell-box/CornellBox-Original.gltf"), &LoadOptions::default())
        .expect("CornellBox-Original loads");
    assert_eq!(scene.triangle_count(), 32);
    assert_eq!(scene.name, "CornellBox-Original");
    assert!(scene.lights.is_empty(), "no default light: the file's emissive quad lights it");
    assert!(scene.has_emitters());
    assert!(scene.warnings.iter().any(|w| w.contains("lit by its emissive surfaces")), "{:?}", scene.warnings);
    let light = scene.materials.iter().find(|m| m.name == "Light").expect("Light material");
    assert_eq!(light.emissive, Vec3::ONE);
    // The mesh node is rotated +90° about X in the file; the floor ends up at y ≈ 0.
    let b = scene.bounds(0.0);
    assert!(b.min.y.abs() < 0.05 && (b.max.y - 1.99).abs() < 0.05, "{b:?}");
}

#[test]
fn shared_chair_scene_loads_with_its_sun() {
    let scene = load_gltf_file(&real_scene("chair-on-floor/MixedLightingExample.gltf"), &LoadOptions::default())
        .expect("MixedLightingExample loads");
    assert_eq!(scene.triangle_count(), 40898);
    assert_eq!(scene.lights.len(), 1);
    assert_eq!(scene.lights[0].kind, LightKind::Directional);
    assert_eq!(scene.lights[0].intensity, 2049.0);
    // Base colour images of the materials in use: fabric (Mango Velvet), label, wood (brown
    // and black share one image). Peacock Velvet is only a KHR_materials_variants alternative.
    let mut base: Vec<usize> = scene.materials.iter().filter_map(|m| m.base_color_texture).collect();
    base.sort();
    base.dedup();
    assert_eq!(base.len(), 3);
    // With the packed occlusion-metallic-roughness images of the wood and the occlusion
    // images (#37; the only normal map belongs to the unused Peacock variant).
    assert!(scene.materials.iter().any(|m| m.metallic_roughness_texture.is_some()));
    assert!(scene.materials.iter().any(|m| m.occlusion_texture.is_some()));
    assert_eq!(scene.textures.len(), 5);
    assert!(!scene.materials.iter().any(|m| m.name.contains("Peacock")));
    for t in &scene.textures {
        assert_eq!(t.rgba8.len(), (t.width * t.height * 4) as usize, "{}", t.name);
    }
    assert!(scene.warnings.iter().any(|w| w.contains("KHR_materials_sheen")), "{:?}", scene.warnings);
    assert!(!scene.warnings.iter().any(|w| w.contains("KHR_texture_transform")), "{:?}", scene.warnings);
}

#[test]
fn shared_hotel_room_loads_skipping_its_lines() {
    let opts = LoadOptions { unit_scale: 0.001, ..LoadOptions::default() };
    let scene = load_gltf_file(&real_scene("hotel-room/hotel-room.glb"), &opts).expect("hotel room loads");
    assert_eq!(scene.triangle_count(), 99029);
    assert_eq!(scene.lights.len(), 1);
    // A closed room: it opens inside, lit by a point light under the ceiling in view (#37).
    assert_eq!(scene.lights[0].name, "default point");
    assert!(scene.view.as_ref().is_some_and(|v| v.kind == crate::scene::framing::ViewKind::Interior));
    assert_eq!(scene.textures.len(), 6);
    assert!(scene.warnings.iter().any(|w| w.contains("LINES")), "{:?}", scene.warnings);
    // Millimetres scaled to metres: a room a few metres wide.
    let e = scene.bounds(0.0).extent();
    assert!(e.max_element() > 3.0 && e.max_element() < 20.0, "{e}");
}

// ---- valid synthetic files ---------------------------------------------------------

#[test]
fn triangle_from_data_uri_gets_flat_normals_and_default_light() {
    let scene = load_str(&triangle_gltf(&data_uri(&triangle_bin([0, 1, 2])))).expect("loads");
    assert_eq!(scene.triangle_count(), 1);
    let prim = &scene.meshes[0].primitives[0];
    assert_eq!(prim.indices, [0, 1, 2]);
    for v in &prim.vertices {
        assert_eq!(v.normal, [0.0, 0.0, 1.0]);
    }
    assert_eq!(scene.materials.len(), 1, "the default material");
    assert_eq!(scene.materials[prim.material], Material::default());
    assert_eq!(scene.lights.len(), 1);

    let no_light = LoadOptions { add_default_light: false, ..LoadOptions::default() };
    let scene =
        load_gltf_bytes(triangle_gltf(&data_uri(&triangle_bin([0, 1, 2]))).as_bytes(), None, &no_light).expect("loads");
    assert!(scene.lights.is_empty());
}

#[test]
fn external_bin_in_scene_folder_loads_and_glb_round_trips() {
    let dir = TempDir::new("external");
    dir.write("sub dir/tri.bin", &triangle_bin([0, 1, 2]));
    let path = dir.write("tri.gltf", triangle_gltf("sub%20dir/tri.bin").as_bytes());
    let scene = load_gltf_file(&path, &LoadOptions::default()).expect("loads");
    assert_eq!(scene.triangle_count(), 1);
    assert_eq!(scene.name, "tri");

    let glb = make_glb(&triangle_gltf_with("", 3, 4), &triangle_bin([0, 1, 2]));
    let scene = load_gltf_bytes(&glb, None, &LoadOptions::default()).expect("glb loads");
    assert_eq!(scene.triangle_count(), 1);
}

#[test]
fn unit_scale_scales_world_positions() {
    let json = triangle_gltf(&data_uri(&triangle_bin([0, 1, 2])));
    let opts = LoadOptions { unit_scale: 0.5, add_default_light: false, detect_units: false };
    let scene = load_gltf_bytes(json.as_bytes(), None, &opts).expect("loads");
    let b = scene.bounds(0.0);
    assert!((b.max - Vec3::new(0.5, 0.5, 0.0)).length() < 1e-6, "{b:?}");
    let bad = LoadOptions { unit_scale: 0.0, ..LoadOptions::default() };
    assert!(matches!(load_gltf_bytes(json.as_bytes(), None, &bad), Err(SceneError::BadOptions(_))));
}

#[test]
fn strips_and_fans_become_lists() {
    assert_eq!(strip_to_list(&[0, 1, 2, 3, 4]), [0, 1, 2, 1, 3, 2, 2, 3, 4]);
    assert_eq!(fan_to_list(&[0, 1, 2, 3]), [1, 2, 0, 2, 3, 0]);
    assert!(strip_to_list(&[0, 1]).is_empty());
    assert!(fan_to_list(&[]).is_empty());
    let scene = load_str(&triangle_gltf_with(&format!("\"uri\":\"{}\",", data_uri(&triangle_bin([0, 1, 2]))), 3, 5))
        .expect("a strip of 3 indices is one triangle");
    assert_eq!(scene.triangle_count(), 1);
}

#[test]
fn texture_transform_matches_the_extension() {
    // Offset and scale: uv' = offset + scale · uv.
    let m = uv_transform([0.5, -1.0], 0.0, [2.0, 3.0]);
    assert!((m.transform_point2(Vec2::new(1.0, 1.0)) - Vec2::new(2.5, 2.0)).length() < 1e-6);
    // Rotation by +90°: (1, 0) ↦ (0, −1) with the ratified matrix (columns (cos, −sin), (sin, cos)).
    let r = uv_transform([0.0, 0.0], std::f32::consts::FRAC_PI_2, [1.0, 1.0]);
    assert!((r.transform_point2(Vec2::X) - Vec2::new(0.0, -1.0)).length() < 1e-6);
}

#[test]
fn sparse_accessor_substitutes_values() {
    // Base positions are the triangle; the sparse part moves vertex 2 to (0, 2, 0).
    let mut bin = triangle_bin([0, 1, 2]);
    bin.extend(2u16.to_le_bytes());
    bin.extend([0, 0]);
    bin.extend([0.0f32, 2.0, 0.0].iter().flat_map(|x| x.to_le_bytes()));
    let json = format!(
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
    );
    let scene = load_str(&json).expect("sparse accessor loads");
    let p = &scene.meshes[0].primitives[0].vertices;
    assert_eq!(p[2].position, [0.0, 2.0, 0.0]);
}

#[test]
fn embedded_png_texture_is_decoded() {
    let mut png = Vec::new();
    image::RgbaImage::from_pixel(2, 3, image::Rgba([10, 20, 30, 255]))
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .expect("encode png");
    let tri = data_uri(&triangle_bin([0, 1, 2]));
    let with_image = |image_uri: &str| {
        let json = triangle_gltf(&tri).replacen(r#""indices":1,"#, r#""indices":1,"material":0,"#, 1);
        let json = json.trim_end().strip_suffix('}').expect("object").to_string();
        format!(
            r#"{json},"materials":[{{"pbrMetallicRoughness":{{"baseColorTexture":{{"index":0}}}}}}],
                "textures":[{{"source":0}}],"images":[{{"uri":"{image_uri}"}}]}}"#
        )
    };
    let png_uri = format!("data:image/png;base64,{}", base64::engine::general_purpose::STANDARD.encode(&png));
    let scene = load_str(&with_image(&png_uri)).expect("loads");
    assert_eq!(scene.textures.len(), 1);
    let t = &scene.textures[0];
    assert_eq!((t.width, t.height), (2, 3));
    assert_eq!(&t.rgba8[..4], &[10, 20, 30, 255]);
    assert_eq!(scene.materials[0].base_color_texture, Some(0));

    // An undecodable image leaves the material on its factor, with a warning naming it (#37).
    let junk = format!("data:image/png;base64,{}", base64::engine::general_purpose::STANDARD.encode(b"not a png"));
    let scene = load_str(&with_image(&junk)).expect("loads on the factor");
    assert_eq!(scene.materials[0].base_color_texture, None);
    assert!(
        scene
            .warnings
            .iter()
            .any(|w| w.contains("base colour texture is not used") && w.contains("cannot decode image 0")),
        "{:?}",
        scene.warnings
    );
}

/// Found with the fuzzer's texture seeds (issue #19): a JPEG of 8 × 4 pixels whose header
/// says 12800 × 12800 loaded (as a grey image) after allocating 1.7 GB. Images are checked
/// against `MAX_IMAGE_PIXELS` before they are decoded.
#[test]
fn images_larger_than_the_limit_are_refused_before_decoding() {
    let mut jpeg = Vec::new();
    image::RgbImage::from_pixel(8, 4, image::Rgb([200, 100, 50]))
        .write_to(&mut std::io::Cursor::new(&mut jpeg), image::ImageFormat::Jpeg)
        .expect("encode jpeg");
    let with_jpeg = |jpeg: &[u8]| {
        let uri = format!("data:image/jpeg;base64,{}", base64::engine::general_purpose::STANDARD.encode(jpeg));
        let json = triangle_gltf(&data_uri(&triangle_bin([0, 1, 2]))).replacen(
            r#""indices":1,"#,
            r#""indices":1,"material":0,"#,
            1,
        );
        let json = json.trim_end().strip_suffix('}').expect("object").to_string();
        format!(
            r#"{json},"materials":[{{"pbrMetallicRoughness":{{"baseColorTexture":{{"index":0}}}}}}],
                "textures":[{{"source":0}}],"images":[{{"uri":"{uri}"}}]}}"#
        )
    };
    let scene = load_str(&with_jpeg(&jpeg)).expect("the real JPEG loads");
    assert_eq!((scene.textures[0].width, scene.textures[0].height), (8, 4));
    // The baseline frame header (SOF0): marker, length, precision, height, width (big-endian).
    let sof = jpeg.windows(2).position(|w| w == [0xFF, 0xC0]).expect("SOF0");
    for (h, w) in [(12800u16, 12800u16), (65535, 65535), (8193, 8192)] {
        let mut big = jpeg.clone();
        big[sof + 5..sof + 7].copy_from_slice(&h.to_be_bytes());
        big[sof + 7..sof + 9].copy_from_slice(&w.to_be_bytes());
        let scene = load_str(&with_jpeg(&big)).expect("loads on the factor");
        assert_eq!(scene.materials[0].base_color_texture, None);
        let warning = scene.warnings.iter().find(|x| x.contains("cannot decode image 0")).expect("a warning");
        assert!(warning.contains(&format!("{w} × {h} pixels")) && warning.contains("8192"), "{warning}");
    }
    assert_eq!(super::materials::MAX_IMAGE_PIXELS, 8192 * 8192);

    // Found by the fuzzer: an OpenEXR image whose display window says 8 × 5,373,956 pixels
    // (within the pixel limit) decodes to 12-byte float pixels, 516 MB. The decoded size
    // is checked too.
    let mut exr = Vec::new();
    image::DynamicImage::ImageRgb32F(image::Rgb32FImage::from_pixel(8, 4, image::Rgb([0.5, 1.0, 0.25])))
        .write_to(&mut std::io::Cursor::new(&mut exr), image::ImageFormat::OpenExr)
        .expect("encode exr");
    let with_exr = |exr: &[u8]| {
        let uri = format!("data:image/x-exr;base64,{}", base64::engine::general_purpose::STANDARD.encode(exr));
        with_jpeg(&[]).replace("data:image/jpeg;base64,", &uri)
    };
    let scene = load_str(&with_exr(&exr)).expect("the real EXR loads");
    let t = &scene.textures[0];
    assert_eq!((t.width, t.height, t.rgba8.len()), (8, 4, 8 * 4 * 4));
    assert_eq!(t.rgba8[3], 255, "opaque");
    // displayWindow: name, type, size 16, then xMin, yMin, xMax, yMax (little-endian i32).
    let at = exr.windows(14).position(|w| w == b"displayWindow\0").expect("displayWindow") + 14 + 6 + 4;
    exr[at + 12..at + 16].copy_from_slice(&5_373_955i32.to_le_bytes());
    let scene = load_str(&with_exr(&exr)).expect("loads on the factor");
    let warning = scene.warnings.iter().find(|x| x.contains("cannot decode image 0")).expect("a warning");
    assert!(warning.contains("8 × 5373956 pixels") && warning.contains("256 MiB"), "{warning}");
}

/// Found while fuzzing (issue #19): counts are checked against the data that holds them, but
/// data can be read again by every primitive, or not exist (zero-filled accessors): a
/// 730-byte file with four primitives on one zero-filled accessor of 2²² vertices took
/// 1.3 GB. Each file has a budget of zeros, accessor values, vertices and indices.
#[test]
fn per_file_budgets_bound_what_declared_counts_allocate() {
    let tri = data_uri(&triangle_bin([0, 1, 2]));
    let zero_filled = |primitives: usize| {
        let prims = vec![r#"{"attributes":{"POSITION":0},"indices":1}"#; primitives].join(",");
        format!(
            r#"{{"asset":{{"version":"2.0"}},"nodes":[{{"mesh":0}}],"meshes":[{{"primitives":[{prims}]}}],
                "buffers":[{{"uri":"{tri}","byteLength":44}}],
                "bufferViews":[{{"buffer":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":6}}],
                "accessors":[{{"componentType":5126,"count":{},"type":"VEC3",
                               "sparse":{{"count":1,"indices":{{"bufferView":1,"componentType":5123}},"values":{{"bufferView":0}}}}}},
                             {{"bufferView":1,"componentType":5123,"count":3,"type":"SCALAR"}}]}}"#,
            super::accessors::MAX_ZERO_ACCESSOR_ELEMENTS / 2
        )
    };
    assert_eq!(load_str(&zero_filled(2)).expect("two halves of the zeros budget").triangle_count(), 2);
    let err = load_str(&zero_filled(3)).unwrap_err();
    assert!(matches!(err, SceneError::AccessorOutOfRange { accessor: 0, .. }), "{err}");
    assert!(err.to_string().contains("zero-filled accessors GI Lab makes per file"), "{err}");

    // The values and vertices budgets, made small on a loader of two one-triangle primitives.
    let json = triangle_gltf(&tri).replacen(
        r#""primitives":[{"attributes":{"POSITION":0},"indices":1,"mode":4}]"#,
        r#""primitives":[{"attributes":{"POSITION":0},"indices":1},{"attributes":{"POSITION":0},"indices":1}]"#,
        1,
    );
    let root: json::Root = json::deserialize::from_slice(json.as_bytes()).expect("JSON");
    let load_mesh = |budget: Budget| {
        let mut loader = Loader::new("budget test", &root, None);
        loader.budget = budget;
        loader.load_buffers(None)?;
        loader.mesh(0)
    };
    assert!(load_mesh(Budget::default()).is_ok());
    // Each primitive reads 9 position and 3 index values, and builds 3 vertices.
    let values = Budget { values: std::cell::Cell::new(20), ..Budget::default() };
    let err = load_mesh(values).unwrap_err();
    assert!(matches!(&err, SceneError::Unsupported { message, .. } if message.contains("accessor values")), "{err}");
    let indices = Budget { indices: 5, ..Budget::default() };
    let err = load_mesh(indices).unwrap_err();
    assert!(
        matches!(&err, SceneError::Unsupported { message, .. } if message.contains("primitive 1 builds 3 indices")),
        "{err}"
    );
    let vertices = Budget { vertices: 5, ..Budget::default() };
    let err = load_mesh(vertices).unwrap_err();
    assert!(
        matches!(&err, SceneError::Unsupported { message, .. } if message.contains("primitive 1 builds 3 vertices")),
        "{err}"
    );
}

#[test]
fn emissive_textures_are_loaded_with_the_base_colours_uvs() {
    let mut png = Vec::new();
    image::RgbaImage::from_pixel(2, 2, image::Rgba([200, 100, 50, 255]))
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .expect("encode png");
    let png_uri = format!("data:image/png;base64,{}", base64::engine::general_purpose::STANDARD.encode(&png));
    let tri = data_uri(&triangle_bin([0, 1, 2]));
    let with_material = |material: &str| {
        let json = triangle_gltf(&tri).replacen(r#""indices":1,"#, r#""indices":1,"material":0,"#, 1);
        let json = json.trim_end().strip_suffix('}').expect("object").to_string();
        format!(
            r#"{json},"materials":[{material}],"textures":[{{"source":0}},{{"source":0}}],"images":[{{"uri":"{png_uri}"}}]}}"#
        )
    };
    let emissive_only = with_material(r#"{"emissiveFactor":[1,0.5,1],"emissiveTexture":{"index":1}}"#);
    let scene = load_str(&emissive_only).expect("loads");
    let m = &scene.materials[0];
    assert_eq!((m.base_color_texture, m.emissive_texture), (None, Some(0)), "one image, decoded once");
    assert_eq!(m.emissive, Vec3::new(1.0, 0.5, 1.0));
    let about_uvs = |s: &Scene| s.warnings.iter().any(|w| w.contains("texture coordinates"));
    assert!(!about_uvs(&scene), "{:?}", scene.warnings);

    // Both textures on set 0: no warning; the emissive texture on set 1: read with set 0.
    let both = |emissive_uv: &str| {
        with_material(&format!(
            r#"{{"pbrMetallicRoughness":{{"baseColorTexture":{{"index":0}}}},"emissiveFactor":[1,1,1],"emissiveTexture":{{"index":1{emissive_uv}}}}}"#
        ))
    };
    let same = load_str(&both("")).expect("loads");
    assert_eq!(same.materials[0].emissive_texture, Some(0));
    assert!(!about_uvs(&same), "{:?}", same.warnings);
    let other = load_str(&both(r#","texCoord":1"#)).expect("loads");
    assert_eq!(other.materials[0].emissive_texture, Some(0));
    assert!(
        other.warnings.iter().any(|w| w.contains("emissive texture uses other texture coordinates")),
        "{:?}",
        other.warnings
    );
}

#[test]
fn unsupported_required_extension_is_a_warning() {
    let json = triangle_gltf(&data_uri(&triangle_bin([0, 1, 2]))).replacen(
        r#""asset":{"version":"2.0"},"#,
        r#""asset":{"version":"2.0"},"extensionsRequired":["KHR_materials_pbrSpecularGlossiness"],"extensionsUsed":["KHR_materials_pbrSpecularGlossiness","EXT_foo"],"#,
        1,
    );
    let scene = load_str(&json).expect("loads despite the unsupported extension");
    assert!(scene.warnings.iter().any(|w| w.contains("required extension KHR_materials_pbrSpecularGlossiness")));
    assert!(scene.warnings.iter().any(|w| w.contains("EXT_foo")));

    let draco = json.replace("KHR_materials_pbrSpecularGlossiness", "KHR_draco_mesh_compression");
    let err = load_str(&draco).unwrap_err();
    assert!(matches!(err, SceneError::Unsupported { .. }) && err.to_string().contains("draco"), "{err}");
}

// ---- bad inputs --------------------------------------------------------------------

#[test]
fn truncated_glb_is_an_error_at_every_length() {
    let glb = make_glb(&triangle_gltf_with("", 3, 4), &triangle_bin([0, 1, 2]));
    for cut in 0..glb.len() {
        let result = load_gltf_bytes(&glb[..cut], None, &LoadOptions::default());
        match result {
            Err(SceneError::BadGlb { reason, .. }) => assert!(cut >= 4, "{cut}: {reason}"),
            Err(SceneError::NotGltf { .. }) => assert!(cut < 4),
            // Cutting inside the trailing BIN chunk also shortens the declared total.
            other => panic!("cut at {cut}: expected a .glb error, got {other:?}"),
        }
    }
    let err = load_gltf_bytes(&glb[..glb.len() - 10], None, &LoadOptions::default()).unwrap_err();
    assert!(err.to_string().contains("truncated"), "{err}");
    let dir = TempDir::new("truncated");
    let path = dir.write("cut.glb", &glb[..40]);
    let err = load_gltf_file(&path, &LoadOptions::default()).unwrap_err();
    assert!(matches!(err, SceneError::BadGlb { .. }) && err.to_string().contains("cut.glb"), "{err}");
}

#[test]
fn missing_bin_file_is_reported() {
    let dir = TempDir::new("missing");
    let path = dir.write("scene.gltf", triangle_gltf("scene.bin").as_bytes());
    let err = load_gltf_file(&path, &LoadOptions::default()).unwrap_err();
    assert!(matches!(&err, SceneError::MissingBuffer { buffer: 0, uri, .. } if uri == "scene.bin"), "{err}");
    assert!(err.to_string().contains("scene.gltf") && err.to_string().contains("scene.bin"), "{err}");

    // From memory there is no folder to look in.
    let err = load_str(&triangle_gltf("scene.bin")).unwrap_err();
    assert!(matches!(err, SceneError::MissingBuffer { .. }) && err.to_string().contains("memory"), "{err}");

    // A buffer without uri outside a .glb.
    let err = load_str(&triangle_gltf_with("", 3, 4)).unwrap_err();
    assert!(matches!(err, SceneError::MissingBuffer { .. }), "{err}");
}

#[test]
fn short_buffer_is_reported() {
    let bin = triangle_bin([0, 1, 2]);
    let err = load_str(&triangle_gltf(&data_uri(&bin[..30]))).unwrap_err();
    assert!(matches!(err, SceneError::BufferTooShort { declared: 44, actual: 30, .. }), "{err}");
}

#[test]
fn accessor_out_of_range_is_reported() {
    let uri = format!("\"uri\":\"{}\",", data_uri(&triangle_bin([0, 1, 2])));
    for count in [4, 1000, u64::MAX / 2, u64::MAX] {
        let err = load_str(&triangle_gltf_with(&uri, count, 4)).unwrap_err();
        assert!(matches!(err, SceneError::AccessorOutOfRange { accessor: 0, .. }), "count {count}: {err}");
        assert!(err.to_string().contains("POSITION of mesh 'tri'"), "{err}");
    }
    // A buffer view that runs past its buffer.
    let json = triangle_gltf(&data_uri(&triangle_bin([0, 1, 2])))
        .replace(r#""byteOffset":36,"byteLength":6"#, r#""byteOffset":40,"byteLength":6"#);
    let err = load_str(&json).unwrap_err();
    assert!(matches!(err, SceneError::AccessorOutOfRange { accessor: 1, .. }), "{err}");
    let json = triangle_gltf(&data_uri(&triangle_bin([0, 1, 2])))
        .replace(r#""byteOffset":36,"byteLength":6"#, r#""byteOffset":18446744073709551615,"byteLength":6"#);
    let err = load_str(&json).unwrap_err();
    assert!(matches!(err, SceneError::AccessorOutOfRange { accessor: 1, .. }), "{err}");
}

#[test]
fn index_out_of_range_is_reported() {
    let err = load_str(&triangle_gltf(&data_uri(&triangle_bin([0, 1, 7])))).unwrap_err();
    assert!(
        matches!(&err, SceneError::IndexOutOfRange { index: 7, vertex_count: 3, mesh, .. } if mesh == "tri"),
        "{err}"
    );
}

#[test]
fn points_and_lines_are_refused_when_nothing_else_is_left() {
    let uri = format!("\"uri\":\"{}\",", data_uri(&triangle_bin([0, 1, 2])));
    for (mode, name) in [(0, "POINTS"), (1, "LINES"), (2, "LINE_LOOP"), (3, "LINE_STRIP")] {
        let err = load_str(&triangle_gltf_with(&uri, 3, mode)).unwrap_err();
        assert!(matches!(&err, SceneError::NonTriangle { mesh, .. } if mesh == "tri"), "{err}");
        assert!(err.to_string().contains(name), "{err}");
    }
    let err = load_str(&triangle_gltf_with(&uri, 3, 9)).unwrap_err();
    assert!(matches!(err, SceneError::Invalid { .. }), "{err}");
}

/// Sets up `scene/` with a `secret.bin` next to it (a valid triangle buffer, so reading it
/// would make the load succeed) and checks that `uri` is refused with UriEscapes.
fn assert_escape_refused(uri: &str) {
    let dir = TempDir::new("escape");
    let secret = dir.write("secret.bin", &triangle_bin([0, 1, 2]));
    let uri = uri.replace("SECRET", &secret.display().to_string());
    let path = dir.write("scene/scene.gltf", triangle_gltf(&uri).as_bytes());
    let err = load_gltf_file(&path, &LoadOptions::default()).unwrap_err();
    assert!(matches!(err, SceneError::UriEscapes { .. }), "{uri}: {err}");
    assert!(err.to_string().contains("only reference files inside its own folder"), "{err}");
}

#[test]
fn uris_that_leave_the_scene_folder_are_refused() {
    for uri in [
        "../secret.bin",
        "./../secret.bin",
        "sub/../../secret.bin",
        "..\\\\secret.bin",
        "%2e%2e/secret.bin",
        "%2E%2E%2Fsecret.bin",
        "SECRET",
        "file://SECRET",
        "FILE:SECRET",
        "http://example.com/secret.bin",
        "C:/secret.bin",
        "\\\\\\\\server\\\\share\\\\secret.bin",
        "%2Fetc%2Fpasswd",
        "../../etc/passwd",
        "/etc/passwd",
        "file:///etc/passwd",
    ] {
        assert_escape_refused(uri);
    }
    // Images follow the same rules.
    let dir = TempDir::new("escape-image");
    dir.write("secret.png", b"x");
    let tri = data_uri(&triangle_bin([0, 1, 2]));
    let json = triangle_gltf(&tri).replacen(r#""indices":1,"#, r#""indices":1,"material":0,"#, 1);
    let json = format!(
        r#"{},"materials":[{{"pbrMetallicRoughness":{{"baseColorTexture":{{"index":0}}}}}}],"textures":[{{"source":0}}],"images":[{{"uri":"../secret.png"}}]}}"#,
        json.trim_end().strip_suffix('}').expect("object")
    );
    let path = dir.write("scene/scene.gltf", json.as_bytes());
    let err = load_gltf_file(&path, &LoadOptions::default()).unwrap_err();
    assert!(matches!(&err, SceneError::UriEscapes { what, .. } if what == "image 0"), "{err}");
}

#[cfg(unix)]
#[test]
fn symlink_out_of_the_scene_folder_is_refused() {
    let dir = TempDir::new("symlink");
    let secret = dir.write("secret.bin", &triangle_bin([0, 1, 2]));
    let path = dir.write("scene/scene.gltf", triangle_gltf("link.bin").as_bytes());
    std::os::unix::fs::symlink(&secret, dir.path().join("scene/link.bin")).expect("symlink");
    let err = load_gltf_file(&path, &LoadOptions::default()).unwrap_err();
    assert!(matches!(&err, SceneError::UriEscapes { reason, .. } if reason.contains("symbolic link")), "{err}");
    // A symlink that stays inside the folder is fine.
    std::fs::copy(&secret, dir.path().join("scene/real.bin")).expect("copy");
    std::os::unix::fs::symlink(dir.path().join("scene/real.bin"), dir.path().join("scene/inside.bin"))
        .expect("symlink");
    let path = dir.write("scene/inside.gltf", triangle_gltf("inside.bin").as_bytes());
    assert!(load_gltf_file(&path, &LoadOptions::default()).is_ok());
}

#[test]
fn malformed_data_uris_are_reported() {
    for uri in [
        "data:application/octet-stream;base64,@@@not base64@@@",
        "data:application/octet-stream,plain",
        "data:application/octet-stream;base64",
    ] {
        let err = load_str(&triangle_gltf(uri)).unwrap_err();
        assert!(matches!(&err, SceneError::BadDataUri { what, .. } if what == "buffer 0"), "{uri}: {err}");
    }
}

#[test]
fn files_that_are_not_gltf_are_reported() {
    let dir = TempDir::new("not-gltf");
    let mut png = Vec::new();
    image::RgbaImage::new(1, 1)
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .expect("encode png");
    let mut state = 0x2545_f491_u32;
    let random: Vec<u8> = (0..256)
        .map(|_| {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            (state >> 24) as u8 | 0x80 // never '{' or whitespace
        })
        .collect();
    for (name, bytes) in [("image.png", png.as_slice()), ("random.gltf", &random), ("empty.glb", b"")] {
        let path = dir.write(name, bytes);
        let err = load_gltf_file(&path, &LoadOptions::default()).unwrap_err();
        assert!(matches!(err, SceneError::NotGltf { .. }), "{name}: {err}");
        assert!(err.to_string().contains(name), "{err}");
    }
    let err = load_gltf_file(&dir.path().join("absent.gltf"), &LoadOptions::default()).unwrap_err();
    assert!(matches!(err, SceneError::Io { .. }) && err.to_string().contains("absent.gltf"), "{err}");
}

#[test]
fn invalid_json_is_reported() {
    let dir = TempDir::new("bad-json");
    for (name, text) in [
        ("syntax.gltf", r#"{"asset": {"version": "2.0"}, "nodes": ["#),
        ("no-asset.gltf", r#"{"nodes": []}"#),
        ("wrong-type.gltf", r#"{"asset": {"version": "2.0"}, "nodes": [{"mesh": -1}]}"#),
    ] {
        let path = dir.write(name, text.as_bytes());
        let err = load_gltf_file(&path, &LoadOptions::default()).unwrap_err();
        assert!(matches!(err, SceneError::Parse { .. }), "{name}: {err}");
        assert!(err.to_string().contains(name), "{err}");
    }
    for asset in [r#"{"version":"1.0"}"#, r#"{"version":"two"}"#, r#"{"version":"2.0","minVersion":"2.1"}"#] {
        let err = load_str(&format!(r#"{{"asset":{asset}}}"#)).unwrap_err();
        assert!(matches!(err, SceneError::Unsupported { .. }), "{asset}: {err}");
    }
    let err = load_str(r#"{"asset":{"version":"2.0"}}"#).unwrap_err();
    assert!(matches!(err, SceneError::Empty { .. }), "{err}");
}

#[test]
fn bad_references_are_errors_not_panics() {
    let tri = data_uri(&triangle_bin([0, 1, 2]));
    let base = triangle_gltf(&tri);
    for (from, to) in [
        (r#""nodes":[{"mesh":0}]"#, r#""nodes":[{"mesh":5}]"#),
        (r#""scenes":[{"nodes":[0]}]"#, r#""scenes":[{"nodes":[3]}]"#),
        (r#""scene":0"#, r#""scene":2"#),
        (r#""POSITION":0"#, r#""POSITION":9"#),
        (r#""indices":1"#, r#""indices":0"#),
        (r#""indices":1,"#, r#""indices":1,"material":4,"#),
        (r#""buffer":0,"byteOffset":0"#, r#""buffer":3,"byteOffset":0"#),
        (r#""componentType":5123"#, r#""componentType":5126"#),
        (r#""componentType":5123"#, r#""componentType":1"#),
        (r#""type":"VEC3""#, r#""type":"MAT4""#),
        (r#""nodes":[{"mesh":0}]"#, r#""nodes":[{"mesh":0,"camera":2}]"#),
        (r#""nodes":[{"mesh":0}]"#, r#""nodes":[{"mesh":0,"extensions":{"KHR_lights_punctual":{"light":0}}}]"#),
        (r#""nodes":[{"mesh":0}]"#, r#""nodes":[{"mesh":0,"children":[7]}]"#),
    ] {
        let json = base.replacen(from, to, 1);
        assert_ne!(json, base, "{from} not found");
        let err = load_str(&json).unwrap_err();
        assert!(!err.to_string().is_empty(), "{to}");
    }
}

#[test]
fn cycles_and_shared_children_are_reported() {
    let tri = data_uri(&triangle_bin([0, 1, 2]));
    for (nodes, scenes) in [
        (r#"[{"mesh":0,"children":[1]},{"children":[0]}]"#, r#"[]"#),
        (r#"[{"mesh":0,"children":[1]},{"children":[2]},{"children":[1]}]"#, r#"[{"nodes":[0]}]"#),
        (r#"[{"mesh":0,"children":[0]}]"#, r#"[]"#),
        (r#"[{"mesh":0,"children":[2]},{"children":[2]},{}]"#, r#"[{"nodes":[0,1]}]"#),
    ] {
        let json = triangle_gltf(&tri).replacen(
            r#""scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}]"#,
            &format!(r#""scenes":{scenes},"nodes":{nodes}"#),
            1,
        );
        let err = load_str(&json).unwrap_err();
        assert!(matches!(err, SceneError::Cycle { .. }), "{nodes}: {err}");
    }
}

#[test]
fn animation_counts_are_checked() {
    // Times [0, 1] (8 bytes) after the triangle; outputs: 2 VEC3 translations (24 bytes).
    let mut bin = triangle_bin([0, 1, 2]);
    bin.extend([0.0f32, 1.0].iter().flat_map(|x| x.to_le_bytes()));
    bin.extend([0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0].iter().flat_map(|x| x.to_le_bytes()));
    let json = |interp: &str, out_count: usize| {
        let base =
            triangle_gltf(&data_uri(&bin)).replace(r#""byteLength":44"#, &format!(r#""byteLength":{}"#, bin.len()));
        let base = base.trim_end().strip_suffix("]}").expect("ends with accessors").to_string();
        let base = base.replacen(
            r#"{"buffer":0,"byteOffset":36,"byteLength":6}"#,
            r#"{"buffer":0,"byteOffset":36,"byteLength":6},{"buffer":0,"byteOffset":44,"byteLength":8},{"buffer":0,"byteOffset":52,"byteLength":24}"#,
            1,
        );
        format!(
            r#"{base},{{"bufferView":2,"componentType":5126,"count":2,"type":"SCALAR","min":[0],"max":[1]}},
                {{"bufferView":3,"componentType":5126,"count":{out_count},"type":"VEC3"}}],
                "animations":[{{"name":"slide","channels":[{{"sampler":0,"target":{{"node":0,"path":"translation"}}}}],
                "samplers":[{{"input":2,"output":3,"interpolation":"{interp}"}}]}}]}}"#
        )
    };
    let scene = load_str(&json("LINEAR", 2)).expect("valid animation loads");
    assert_eq!(scene.animations.len(), 1);
    assert_eq!(scene.animations[0].duration(), 1.0);
    let x = scene.evaluate(0.5).node_world[0].transform_point3(Vec3::ZERO).x;
    assert!((x - 0.5).abs() < 1e-6);

    let err = load_str(&json("LINEAR", 1)).unwrap_err();
    assert!(matches!(&err, SceneError::BadAnimation { animation, .. } if animation == "slide"), "{err}");
    let err = load_str(&json("CUBICSPLINE", 2)).unwrap_err();
    assert!(matches!(err, SceneError::BadAnimation { .. }) && err.to_string().contains("needs 6"), "{err}");
    let err = load_str(&json("LINEAR", 3)).unwrap_err();
    assert!(matches!(err, SceneError::AccessorOutOfRange { accessor: 3, .. }), "{err}");
}

#[test]
fn uri_helpers() {
    assert_eq!(percent_decode("a%20b%2e").as_deref(), Some("a b."));
    assert_eq!(percent_decode("%2"), None);
    assert_eq!(percent_decode("%+1"), None);
    assert_eq!(uri_scheme("data:x"), Some("data"));
    assert_eq!(uri_scheme("a/b:c"), None);
    assert_eq!(relative_components("./a//b\\c.bin"), Ok(vec!["a".into(), "b".into(), "c.bin".into()]));
    assert!(relative_components("").is_err());
    assert!(relative_components("a/%00.bin").is_err());
    assert!(relative_components("a.bin:stream").is_err());
}

/// Deterministic byte mutations of valid files must never panic.
#[test]
fn mutated_files_never_panic() {
    let glb = make_glb(&triangle_gltf_with("", 3, 4), &triangle_bin([0, 1, 2]));
    let gltf = triangle_gltf(&data_uri(&triangle_bin([0, 1, 2]))).into_bytes();
    let mut state = 0x9e37_79b9_7f4a_7c15_u64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    for base in [glb, gltf] {
        for _ in 0..1500 {
            let mut bytes = base.clone();
            for _ in 0..1 + next() % 3 {
                let at = (next() % bytes.len() as u64) as usize;
                let byte = &mut bytes[at];
                // Digits stay digits half of the time, so JSON numbers change but still parse.
                *byte =
                    if byte.is_ascii_digit() && next() % 2 == 0 { b'0' + (next() % 10) as u8 } else { next() as u8 };
            }
            let _ = load_gltf_bytes(&bytes, None, &LoadOptions::default());
        }
    }
}
