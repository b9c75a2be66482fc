//! The seed corpora: the inputs the mutations start from.
//!
//! - glTF: the embedded default scene, the real-world scenes of the repository (`assets/scenes`: the
//!   Cornell box `.gltf` with its buffer in a data URI, the chair scene turned into one GLB
//!   with its `.bin` and JPEG textures inside, the hotel room GLB, and "lite" copies of the
//!   two big ones whose images are a 1 × 1 PNG, so that mutations of their geometry run
//!   fast), and the hostile files of the loader's own tests rebuilt by [`crate::hostile`].
//! - preset: every `presets/*.ron`, the default settings written by `to_ron`, and presets of
//!   the older versions the migration reads.
//! - set: every `group.field` of [`LabSettings::all_paths`] with valid, boundary and invalid
//!   values, and the version-1 names `--set` still understands or explains.

use std::path::{Path, PathBuf};

use base64::Engine as _;
use gi_render::LabSettings;
use gi_render::settings::FieldKind;
use serde_json::{Value, json};

/// One corpus input with the name it is reported under.
#[derive(Clone, Debug)]
pub struct Seed {
    pub name: String,
    pub bytes: Vec<u8>,
}

impl Seed {
    /// A seed named `name`.
    pub fn new(name: impl Into<String>, bytes: impl Into<Vec<u8>>) -> Self {
        Self { name: name.into(), bytes: bytes.into() }
    }
}

/// Inputs of at least this many bytes are "large": picked rarely (see `Corpus`) and left
/// out of the CI test's corpus.
pub const LARGE: usize = 256 << 10;

/// The project root (the workspace folder above this crate).
pub fn project_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The real scenes of the repository (`assets/scenes`), if present.
pub fn real_scenes() -> Option<PathBuf> {
    let p = project_root().join("assets/scenes");
    p.is_dir().then_some(p)
}

/// A 1 × 1 PNG (the image of the "lite" seeds and of the texture hostile cases).
pub fn tiny_png() -> Vec<u8> {
    let mut png = Vec::new();
    let img = image::RgbaImage::from_pixel(1, 1, image::Rgba([200, 120, 40, 255]));
    // Encoding a 1 × 1 image into memory cannot fail; an empty seed would only be less useful.
    let _ = img.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png);
    png
}

/// A small image in `format` (PNG, JPEG, Radiance HDR or OpenEXR: the formats the loader's
/// image decoder is built with), for the texture seeds whose headers the mutations reach.
pub fn tiny_image(format: image::ImageFormat) -> Vec<u8> {
    let rgb = image::RgbImage::from_fn(8, 4, |x, y| image::Rgb([(x * 30) as u8, (y * 60) as u8, 90]));
    let img = match format {
        image::ImageFormat::Hdr | image::ImageFormat::OpenExr => {
            image::DynamicImage::ImageRgb32F(image::DynamicImage::ImageRgb8(rgb).into_rgb32f())
        }
        _ => image::DynamicImage::ImageRgb8(rgb),
    };
    let mut out = Vec::new();
    // Encoding a small image into memory does not fail; an empty seed would only be less useful.
    let _ = img.write_to(&mut std::io::Cursor::new(&mut out), format);
    out
}

/// A `.gltf` whose buffers and images are files next to it, as one GLB: every buffer is
/// appended to the BIN chunk (views are moved to the combined buffer) and every image
/// becomes a buffer view. None when a file is missing or the JSON is not an object.
pub fn gltf_to_glb(path: &Path) -> Option<Vec<u8>> {
    let dir = path.parent()?;
    let mut doc: Value = serde_json::from_slice(&std::fs::read(path).ok()?).ok()?;
    let mut bin: Vec<u8> = Vec::new();
    let mut buffer_base = Vec::new();
    for b in doc.get("buffers").and_then(Value::as_array).cloned().unwrap_or_default() {
        let uri = b.get("uri").and_then(Value::as_str)?;
        let data = if let Some((_, payload)) = uri.split_once(";base64,") {
            base64::engine::general_purpose::STANDARD.decode(payload).ok()?
        } else {
            std::fs::read(dir.join(uri)).ok()?
        };
        bin.resize(bin.len().next_multiple_of(4), 0);
        buffer_base.push(bin.len());
        bin.extend(data);
    }
    for v in doc.get_mut("bufferViews").and_then(Value::as_array_mut).into_iter().flatten() {
        let b = v.get("buffer").and_then(Value::as_u64).unwrap_or(0) as usize;
        let offset = v.get("byteOffset").and_then(Value::as_u64).unwrap_or(0) as usize;
        v["buffer"] = json!(0);
        v["byteOffset"] = json!(offset + buffer_base.get(b).copied().unwrap_or(0));
    }
    let images = doc.get("images").and_then(Value::as_array).cloned().unwrap_or_default();
    for (i, img) in images.iter().enumerate() {
        let Some(uri) = img.get("uri").and_then(Value::as_str) else { continue };
        let data = std::fs::read(dir.join(uri)).ok()?;
        bin.resize(bin.len().next_multiple_of(4), 0);
        let view = json!({"buffer": 0, "byteOffset": bin.len(), "byteLength": data.len()});
        bin.extend(data);
        let views = doc.get_mut("bufferViews")?.as_array_mut()?;
        views.push(view);
        let index = views.len() - 1;
        let mime = if uri.ends_with(".png") { "image/png" } else { "image/jpeg" };
        doc["images"][i] = json!({"bufferView": index, "mimeType": mime});
    }
    doc["buffers"] = json!([{"byteLength": bin.len()}]);
    Some(gi_render::scene::cornell::glb(serde_json::to_vec(&doc).ok()?, bin))
}

/// `glb` with every image replaced by a 1 × 1 PNG (the geometry, and the BIN bytes of the
/// old images, stay): the loader's texture decoding no longer dominates the execution time.
pub fn without_images(glb: &[u8]) -> Option<Vec<u8>> {
    let (json, mut bin) = crate::gltf_mutate::split_glb(glb)?;
    let mut doc: Value = serde_json::from_slice(&json).ok()?;
    let png = tiny_png();
    bin.resize(bin.len().next_multiple_of(4), 0);
    let at = bin.len();
    bin.extend(&png);
    let views = doc.get_mut("bufferViews")?.as_array_mut()?;
    views.push(json!({"buffer": 0, "byteOffset": at, "byteLength": png.len()}));
    let view = views.len() - 1;
    for img in doc.get_mut("images").and_then(Value::as_array_mut).into_iter().flatten() {
        *img = json!({"bufferView": view, "mimeType": "image/png"});
    }
    doc["buffers"][0]["byteLength"] = json!(bin.len());
    Some(gi_render::scene::cornell::glb(serde_json::to_vec(&doc).ok()?, bin))
}

/// The glTF seeds. `large`: include the seeds of [`LARGE`] bytes or more (the real chair
/// and hotel room scenes); the small ones are the default scene, the real Cornell box and
/// the hostile cases.
pub fn gltf_seeds(large: bool) -> Vec<Seed> {
    let mut seeds = vec![Seed::new("default-scene.glb", gi_render::scene::cornell::DEFAULT_SCENE_GLB)];
    if let Some(shared) = real_scenes() {
        if let Ok(b) = std::fs::read(shared.join("cornell-box/CornellBox-Original.gltf")) {
            seeds.push(Seed::new("CornellBox-Original.gltf", b));
        }
        if large {
            if let Some(chair) = gltf_to_glb(&shared.join("chair-on-floor/MixedLightingExample.gltf")) {
                if let Some(lite) = without_images(&chair) {
                    seeds.push(Seed::new("MixedLightingExample-lite.glb", lite));
                }
                seeds.push(Seed::new("MixedLightingExample.glb", chair));
            }
            if let Ok(hotel) = std::fs::read(shared.join("hotel-room/hotel-room.glb")) {
                if let Some(lite) = without_images(&hotel) {
                    seeds.push(Seed::new("hotel-room-lite.glb", lite));
                }
                seeds.push(Seed::new("hotel-room.glb", hotel));
            }
        }
    }
    seeds.extend(crate::hostile::gltf_cases());
    seeds
}

/// Every `presets/*.ron`, sorted by name.
pub fn preset_files() -> Vec<Seed> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(project_root().join("presets"))
        .map(|d| d.filter_map(Result::ok).map(|e| e.path()).collect())
        .unwrap_or_default();
    files.retain(|p| p.extension().is_some_and(|e| e == "ron"));
    files.sort();
    files.iter().filter_map(|p| Some(Seed::new(p.file_name()?.to_string_lossy(), std::fs::read(p).ok()?))).collect()
}

/// The preset seeds: the shipped presets, the defaults and older-version files.
pub fn preset_seeds() -> Vec<Seed> {
    let mut seeds = preset_files();
    seeds.push(Seed::new("default-to_ron", LabSettings::default().to_ron()));
    for (name, text) in [
        ("version-0", "(direct: (pcf_radius: 2), tonemap: (exposure_ev: 1.5))"),
        (
            "version-1",
            "(version: 1, indirect: (technique: Hcb), ism: (visibility: Exact), reference: (visibility: false), \
             interleave: (filter: false), temporal: (enabled: false), hcb: (cache: true))",
        ),
        (
            "problems",
            "(version: 1, direct: (pcf_radius: 9, shadows: \"yes\", bogus: 1, depth_bias: 2.0), \
             nonsense: (a: 1), indirect: (technique: Magic), tonemap: (key: -3))",
        ),
        ("raw-none", "(version: 2, pipeline: (gather: r#None, temporal: None))"),
        ("powers", "(vpl: (light_gbuffer_size: 256), ism: (map_size: 128))"),
        ("comments", "/* block */ ( // line\n version: 2, tonemap: (key: 0.18, exposure_ev: -1e-3) )"),
    ] {
        seeds.push(Seed::new(name, text));
    }
    seeds
}

/// Values worth trying for a field: its default, range ends and the numbers just outside,
/// the boundary numbers and, for choices, every name.
fn values_for(kind: FieldKind, min: f64, max: f64, default: Option<String>) -> Vec<String> {
    let mut v: Vec<String> = default.into_iter().collect();
    match kind {
        FieldKind::F32 | FieldKind::U32 => {
            for x in [min, max, min - 1.0, max + 1.0, (min + max) / 2.0] {
                v.push(if kind == FieldKind::U32 { format!("{}", x.round()) } else { format!("{x}") });
            }
            v.extend(["-1", "NaN", "inf", "1e39", "2147483648", "4294967295", "1e-45", "x"].map(String::from));
        }
        FieldKind::Bool => v.extend(["true", "false", "on", "off", "1", "0", "yes"].map(String::from)),
        FieldKind::Choice(names) => {
            v.extend(names.iter().map(|n| n.to_string()));
            v.extend(names.iter().map(|n| n.to_lowercase()));
            v.push("Nonexistent".into());
        }
    }
    v
}

/// The `--set` seeds: one line per assignment, several assignments per seed.
pub fn set_seeds() -> Vec<Seed> {
    let defaults = LabSettings::default();
    let mut seeds = Vec::new();
    for (group, fields) in LabSettings::groups() {
        for m in fields {
            let path = format!("{group}.{}", m.name);
            let values = values_for(m.kind, m.min, m.max, defaults.get(&path).map(|d| d.to_string()));
            let lines: Vec<String> = values.iter().map(|v| format!("{path}={v}")).collect();
            seeds.push(Seed::new(path.clone(), lines.join("\n")));
        }
    }
    for (name, text) in [
        ("technique", "indirect.technique=ExactVpl\nindirect.technique=Hcb\nindirect.technique=Magic"),
        ("moved", "ism.visibility=Exact\nhcb.cache=true\ntemporal.enabled=false"),
        ("malformed", "garbage\n=\n.=1\na.b=c\n direct.pcf_radius = 2 \ndirect.pcf_radius=2=3"),
        ("power-of-two", "vpl.light_gbuffer_size=300\nism.map_size=100"),
    ] {
        seeds.push(Seed::new(name, text));
    }
    seeds
}

/// Words of presets and `--set` strings for the text mutator: group and field names, choice
/// names, RON keywords.
pub fn settings_dictionary() -> Vec<&'static str> {
    let mut words: Vec<&'static str> = vec![
        "version",
        "true",
        "false",
        "None",
        "Some",
        "r#None",
        "inf",
        "NaN",
        "indirect",
        "technique",
        "visibility",
        "filter",
        "enabled",
        "cache",
        "=",
        ".",
    ];
    for (group, fields) in LabSettings::groups() {
        words.push(group);
        for m in fields {
            words.push(m.name);
            if let FieldKind::Choice(names) = m.kind {
                words.extend(names.iter().copied());
            }
        }
    }
    words.sort_unstable();
    words.dedup();
    words
}
