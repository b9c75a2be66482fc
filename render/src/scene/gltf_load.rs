//! glTF 2.0 loading (`.gltf` JSON with external or embedded buffers, and `.glb` binary).
//!
//! The loader never trusts its input: every index, offset and length in the file is checked
//! with checked arithmetic before any data is read, so a malformed or hostile file gives a
//! [`SceneError`] that names the file and the problem, never a panic or an out-of-bounds read.
//!
//! Buffers and images are resolved here rather than by the `gltf` crate's importer: external
//! files must be plain relative paths inside the scene's folder (no `..`, no absolute paths,
//! no URL scheme other than `data:`), which is checked before and after resolving symbolic
//! links. The `gltf` crate's own validation is not used either: in gltf-json 1.4 it indexes
//! arrays with unchecked file indices and can panic on hostile input. This module reads the
//! deserialised JSON (`gltf::json`) directly and checks every reference it follows.
//!
//! Section numbers cite the glTF 2.0 specification (Khronos, version 2.0.1).

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use base64::Engine as _;
use glam::{Mat3, Mat4, Quat, Vec2, Vec3, Vec4};
use gltf::json;
use json::accessor::{ComponentType, GenericComponentType, IndexComponentType, Type as AccessorType};
use json::validation::Checked;

use super::{
    Animation, CameraDef, Channel, ChannelTarget, Interpolation, Light, LightKind, Material, Mesh, Node, Primitive,
    Projection, Scene, TextureImage, Transform, Vertex,
};

/// glTF extensions this loader understands; others are reported in [`Scene::warnings`].
const SUPPORTED_EXTENSIONS: &[&str] =
    &["KHR_lights_punctual", "KHR_texture_transform", "KHR_materials_emissive_strength"];

/// Required extensions without which the geometry itself cannot be read: loading fails.
const GEOMETRY_COMPRESSION_EXTENSIONS: &[&str] = &["KHR_draco_mesh_compression", "EXT_meshopt_compression"];

/// Upper bound on the elements of an accessor that has no buffer view (all zeros, §3.6.2.3),
/// so that a hostile `count` cannot make the loader allocate without limit.
const MAX_ZERO_ACCESSOR_ELEMENTS: usize = 1 << 22;

/// How a glTF file is turned into a [`Scene`].
#[derive(Clone, Debug, PartialEq)]
pub struct LoadOptions {
    /// Factor applied to all world positions (for example 0.001 for a file in millimetres).
    /// Implemented as an extra root node with this uniform scale above the file's roots.
    pub unit_scale: f32,
    /// Adds a default spot light (see [`Scene::ensure_light`]) when the file has no punctual light.
    pub add_default_light: bool,
}

impl Default for LoadOptions {
    fn default() -> Self {
        Self { unit_scale: 1.0, add_default_light: true }
    }
}

/// Why a glTF file could not be loaded. `file` names the file (or "embedded glTF" for data
/// loaded from memory); every message says what is wrong in terms a user can act on.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    #[error("cannot read {}: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{file}: not a glTF 2.0 file (neither a .glb binary starting with \"glTF\" nor a .gltf JSON document)")]
    NotGltf { file: String },
    #[error("{file}: malformed .glb container: {reason}")]
    BadGlb { file: String, reason: String },
    #[error("{file}: invalid glTF JSON: {message}")]
    Parse { file: String, message: String },
    #[error("{file}: unsupported glTF: {message}")]
    Unsupported { file: String, message: String },
    #[error("{file}: invalid glTF: {message}")]
    Invalid { file: String, message: String },
    #[error("{file}: buffer {buffer} ('{uri}') cannot be read: {reason}")]
    MissingBuffer { file: String, buffer: usize, uri: String, reason: String },
    #[error("{file}: image {image} ('{uri}') cannot be read: {reason}")]
    MissingImage { file: String, image: usize, uri: String, reason: String },
    #[error(
        "{file}: refused to read '{uri}' ({what}): {reason}; a scene may only reference files inside its own folder"
    )]
    UriEscapes { file: String, what: String, uri: String, reason: String },
    #[error("{file}: {what} has a malformed data URI: {reason}")]
    BadDataUri { file: String, what: String, reason: String },
    #[error(
        "{file}: buffer {buffer} ('{uri}') is too short: it declares byteLength {declared} but holds only {actual} bytes"
    )]
    BufferTooShort { file: String, buffer: usize, uri: String, declared: u64, actual: usize },
    #[error("{file}: accessor {accessor} ({what}) reads outside its data: {reason}")]
    AccessorOutOfRange { file: String, accessor: usize, what: String, reason: String },
    #[error(
        "{file}: mesh '{mesh}' primitive {primitive}: vertex index {index} is out of range (the primitive has {vertex_count} vertices)"
    )]
    IndexOutOfRange { file: String, mesh: String, primitive: usize, index: u32, vertex_count: usize },
    #[error(
        "{file}: mesh '{mesh}' primitive {primitive} draws {mode}; only triangles (TRIANGLES, TRIANGLE_STRIP, TRIANGLE_FAN) can be rendered, and the scene has no other geometry"
    )]
    NonTriangle { file: String, mesh: String, primitive: usize, mode: String },
    #[error("{file}: cannot decode image {image} ('{name}'): {reason}")]
    Image { file: String, image: usize, name: String, reason: String },
    #[error("{file}: the node hierarchy is not a tree: {reason}")]
    Cycle { file: String, reason: String },
    #[error("{file}: animation '{animation}': {reason}")]
    BadAnimation { file: String, animation: String, reason: String },
    #[error("{file}: the scene contains no triangles to render")]
    Empty { file: String },
    #[error("invalid load options: {0}")]
    BadOptions(String),
}

/// Loads a `.gltf` or `.glb` file. External buffers and images are resolved relative to the
/// file's folder and must stay inside it.
pub fn load_gltf_file(path: &Path, opts: &LoadOptions) -> Result<Scene, SceneError> {
    let bytes = std::fs::read(path).map_err(|source| SceneError::Io { path: path.to_path_buf(), source })?;
    let base_dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let label = path.display().to_string();
    let mut scene = load(&bytes, Some(base_dir), opts, &label)?;
    if let Some(stem) = path.file_stem() {
        scene.name = stem.to_string_lossy().into_owned();
    }
    Ok(scene)
}

/// Loads glTF data (`.glb` or `.gltf` JSON) from memory. With `base_dir` None, any reference
/// to an external file is an error (only the GLB BIN chunk and `data:` URIs can be used);
/// otherwise external files are resolved in `base_dir` under the same rules as
/// [`load_gltf_file`].
pub fn load_gltf_bytes(bytes: &[u8], base_dir: Option<&Path>, opts: &LoadOptions) -> Result<Scene, SceneError> {
    let label = match base_dir {
        Some(dir) => format!("glTF data for {}", dir.display()),
        None => "embedded glTF".to_string(),
    };
    load(bytes, base_dir, opts, &label)
}

/// The whole load: container, JSON, buffers, hierarchy, meshes, animations, then the checks
/// on the result (no triangles → error) and the default light.
fn load(bytes: &[u8], base_dir: Option<&Path>, opts: &LoadOptions, file: &str) -> Result<Scene, SceneError> {
    if !(opts.unit_scale.is_finite() && opts.unit_scale > 0.0) {
        return Err(SceneError::BadOptions(format!(
            "unit_scale must be a positive finite number, got {}",
            opts.unit_scale
        )));
    }
    let (json_bytes, bin) = split_container(bytes, file)?;
    let root: json::Root = json::deserialize::from_slice(json_bytes)
        .map_err(|e| SceneError::Parse { file: file.to_string(), message: e.to_string() })?;

    let mut loader = Loader::new(file, &root, base_dir);
    loader.check_asset()?;
    loader.check_extensions()?;
    loader.load_buffers(bin)?;
    let (roots, reachable) = loader.hierarchy()?;
    loader.load_nodes(&reachable)?;
    loader.load_animations()?;
    loader.scene.roots = roots;
    loader.scene.name = loader.scene_name();

    let skipped = std::mem::take(&mut loader.skipped);
    let mut scene = loader.scene;
    if opts.unit_scale != 1.0 {
        scene.nodes.push(Node {
            name: format!("unit scale {}", opts.unit_scale),
            transform: Transform { scale: Vec3::splat(opts.unit_scale), ..Transform::default() },
            children: std::mem::take(&mut scene.roots),
            mesh: None,
            light: None,
            camera: None,
        });
        scene.roots = vec![scene.nodes.len() - 1];
    }

    let triangles = scene.triangle_count();
    if triangles == 0 {
        return Err(match skipped.into_iter().next() {
            Some(s) => {
                SceneError::NonTriangle { file: file.to_string(), mesh: s.mesh, primitive: s.primitive, mode: s.mode }
            }
            None => SceneError::Empty { file: file.to_string() },
        });
    }
    if opts.add_default_light {
        scene.ensure_light();
    }
    for w in &scene.warnings {
        log::debug!("{file}: {w}");
    }
    log::info!(
        "loaded {file}: {triangles} triangles, {} meshes, {} materials, {} textures, {} lights, {} cameras, {} animations",
        scene.meshes.len(),
        scene.materials.len(),
        scene.textures.len(),
        scene.lights.len(),
        scene.cameras.len(),
        scene.animations.len()
    );
    Ok(scene)
}

// ---------------------------------------------------------------------------------------
// Container (§4.4 binary glTF) and URIs
// ---------------------------------------------------------------------------------------

/// Splits the input into the JSON document and the optional GLB BIN chunk.
fn split_container<'b>(bytes: &'b [u8], file: &str) -> Result<(&'b [u8], Option<&'b [u8]>), SceneError> {
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
fn is_data_uri(uri: &str) -> bool {
    uri.get(..5).is_some_and(|s| s.eq_ignore_ascii_case("data:"))
}

/// Decodes a base64 `data:` URI; the media type is not checked (images are sniffed).
fn decode_data_uri(uri: &str) -> Result<Vec<u8>, String> {
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
fn uri_scheme(uri: &str) -> Option<&str> {
    let (head, _) = uri.split_once(':')?;
    let mut chars = head.chars();
    let first = chars.next()?;
    (first.is_ascii_alphabetic() && chars.all(|c| c.is_ascii_alphanumeric() || "+-.".contains(c))).then_some(head)
}

/// Decodes `%XX` escapes (RFC 3986 §2.1); None for a malformed escape or invalid UTF-8.
fn percent_decode(s: &str) -> Option<String> {
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
fn relative_components(uri: &str) -> Result<Vec<String>, String> {
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

// ---------------------------------------------------------------------------------------
// Accessor data (§3.6.2)
// ---------------------------------------------------------------------------------------

/// A validated window on an accessor's elements: every element `i < count` lies in `bytes`.
struct Elements<'b> {
    bytes: &'b [u8],
    offset: usize,
    stride: usize,
    component: ComponentType,
    normalized: bool,
}

impl Elements<'_> {
    /// The bytes of component `c` of element `i`.
    fn raw(&self, i: usize, c: usize) -> Option<&[u8]> {
        let size = self.component.size();
        let at = i.checked_mul(self.stride)?.checked_add(self.offset)?.checked_add(c.checked_mul(size)?)?;
        self.bytes.get(at..at.checked_add(size)?)
    }

    /// Component `c` of element `i` as a float; normalized integers map to [0, 1] or
    /// [−1, 1] as in glTF 2.0 spec §3.11 (Animations, "Normalized integers").
    fn float(&self, i: usize, c: usize) -> f32 {
        let n = self.normalized;
        match (self.component, self.raw(i, c)) {
            (ComponentType::F32, Some(&[a, b, c, d])) => f32::from_le_bytes([a, b, c, d]),
            (ComponentType::U8, Some(&[a])) => {
                if n {
                    f32::from(a) / 255.0
                } else {
                    f32::from(a)
                }
            }
            (ComponentType::I8, Some(&[a])) => {
                let v = f32::from(a as i8);
                if n { (v / 127.0).max(-1.0) } else { v }
            }
            (ComponentType::U16, Some(&[a, b])) => {
                let v = f32::from(u16::from_le_bytes([a, b]));
                if n { v / 65535.0 } else { v }
            }
            (ComponentType::I16, Some(&[a, b])) => {
                let v = f32::from(i16::from_le_bytes([a, b]));
                if n { (v / 32767.0).max(-1.0) } else { v }
            }
            (ComponentType::U32, Some(&[a, b, c, d])) => u32::from_le_bytes([a, b, c, d]) as f32,
            _ => 0.0,
        }
    }

    /// Component `c` of element `i` as an unsigned integer (indices).
    fn uint(&self, i: usize, c: usize) -> u32 {
        match self.raw(i, c) {
            Some(&[a]) => u32::from(a),
            Some(&[a, b]) => u32::from(u16::from_le_bytes([a, b])),
            Some(&[a, b, c, d]) => u32::from_le_bytes([a, b, c, d]),
            _ => 0,
        }
    }
}

/// Converts a JSON size to usize; values that do not fit saturate and then fail the range checks.
fn to_usize(v: u64) -> usize {
    usize::try_from(v).unwrap_or(usize::MAX)
}

/// Texture coordinate set and KHR_texture_transform matrix a material's base colour texture uses.
#[derive(Clone, Copy, Debug, Default)]
struct UvUse {
    set: u32,
    transform: Option<Mat3>,
}

/// A non-triangle primitive that was skipped (reported as an error if nothing else is left).
struct Skipped {
    mesh: String,
    primitive: usize,
    mode: String,
}

/// The state of one load: the parsed document, its buffers and what has been built so far.
struct Loader<'a> {
    file: &'a str,
    root: &'a json::Root,
    base_dir: Option<&'a Path>,
    buffers: Vec<Vec<u8>>,
    scene: Scene,
    /// glTF material (None: the default material) → index into `scene.materials`.
    material_map: HashMap<Option<usize>, usize>,
    /// Per scene material: how its base colour texture is addressed.
    material_uv: Vec<UvUse>,
    /// glTF image → index into `scene.textures`.
    image_map: HashMap<usize, usize>,
    mesh_map: HashMap<usize, usize>,
    light_map: HashMap<usize, usize>,
    camera_map: HashMap<usize, Option<usize>>,
    skipped: Vec<Skipped>,
}

impl<'a> Loader<'a> {
    fn new(file: &'a str, root: &'a json::Root, base_dir: Option<&'a Path>) -> Self {
        Self {
            file,
            root,
            base_dir,
            buffers: Vec::new(),
            scene: Scene::default(),
            material_map: HashMap::new(),
            material_uv: Vec::new(),
            image_map: HashMap::new(),
            mesh_map: HashMap::new(),
            light_map: HashMap::new(),
            camera_map: HashMap::new(),
            skipped: Vec::new(),
        }
    }

    fn invalid(&self, message: String) -> SceneError {
        SceneError::Invalid { file: self.file.to_string(), message }
    }

    fn warn(&mut self, message: String) {
        if !self.scene.warnings.contains(&message) {
            self.scene.warnings.push(message);
        }
    }

    /// Checks `asset.version` and `asset.minVersion` (§3.2: loaders reject major versions they do not know).
    fn check_asset(&self) -> Result<(), SceneError> {
        let asset = &self.root.asset;
        let unsupported = |message: String| SceneError::Unsupported { file: self.file.to_string(), message };
        let major_minor = |v: &str| -> Option<(u32, u32)> {
            let mut parts = v.trim().split('.');
            Some((parts.next()?.parse().ok()?, parts.next().map_or(Some(0), |m| m.parse().ok())?))
        };
        if major_minor(&asset.version).is_none_or(|(major, _)| major != 2) {
            return Err(unsupported(format!("glTF version '{}'; only glTF 2.x is supported", asset.version)));
        }
        if let Some(min) = &asset.min_version
            && major_minor(min).is_none_or(|v| v > (2, 0))
        {
            return Err(unsupported(format!("the file needs glTF {min}; this loader implements glTF 2.0")));
        }
        Ok(())
    }

    /// Reports extensions we do not implement (§3.12): warnings, except for required
    /// geometry compression, without which there is no geometry to read.
    fn check_extensions(&mut self) -> Result<(), SceneError> {
        let root = self.root;
        for ext in &root.extensions_required {
            if SUPPORTED_EXTENSIONS.contains(&ext.as_str()) {
                continue;
            }
            if GEOMETRY_COMPRESSION_EXTENSIONS.contains(&ext.as_str()) {
                return Err(SceneError::Unsupported {
                    file: self.file.to_string(),
                    message: format!(
                        "the file requires {ext} (compressed geometry), which GI Lab cannot decode; \
                         decompress it first (for example with glTF-Transform)"
                    ),
                });
            }
            self.warn(format!(
                "required extension {ext} is not supported: the scene may look different from what its author intended"
            ));
        }
        for ext in &root.extensions_used {
            if !SUPPORTED_EXTENSIONS.contains(&ext.as_str()) && !root.extensions_required.contains(ext) {
                self.warn(format!("extension {ext} is not supported and is ignored"));
            }
        }
        Ok(())
    }

    /// Reads a file referenced by `uri` from the scene folder; see [`relative_components`] for
    /// the rules. After joining, the path is canonicalised and must still lie inside the
    /// canonicalised scene folder, which catches symbolic links that point elsewhere.
    fn read_external(
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

    /// Loads every buffer (§3.6.1): the GLB BIN chunk, a `data:` URI or a file in the scene
    /// folder; each must hold at least its declared `byteLength`, and is cut to that length
    /// so that all later range checks are against the declared size.
    fn load_buffers(&mut self, bin: Option<&[u8]>) -> Result<(), SceneError> {
        let root = self.root;
        for (i, b) in root.buffers.iter().enumerate() {
            let declared = b.byte_length.0;
            let (uri, mut data) = match b.uri.as_deref() {
                None => match bin {
                    Some(bin) if i == 0 => ("GLB BIN chunk".to_string(), bin.to_vec()),
                    _ => {
                        return Err(SceneError::MissingBuffer {
                            file: self.file.to_string(),
                            buffer: i,
                            uri: String::new(),
                            reason: "it has no uri and is not the first buffer of a .glb with a BIN chunk".to_string(),
                        });
                    }
                },
                Some(uri) if is_data_uri(uri) => {
                    let data = decode_data_uri(uri).map_err(|reason| SceneError::BadDataUri {
                        file: self.file.to_string(),
                        what: format!("buffer {i}"),
                        reason,
                    })?;
                    ("data URI".to_string(), data)
                }
                Some(uri) => {
                    let data = self.read_external(uri, &format!("buffer {i}"), |reason| SceneError::MissingBuffer {
                        file: self.file.to_string(),
                        buffer: i,
                        uri: uri.to_string(),
                        reason,
                    })?;
                    (uri.to_string(), data)
                }
            };
            if (data.len() as u64) < declared {
                return Err(SceneError::BufferTooShort {
                    file: self.file.to_string(),
                    buffer: i,
                    uri,
                    declared,
                    actual: data.len(),
                });
            }
            data.truncate(to_usize(declared));
            self.buffers.push(data);
        }
        Ok(())
    }

    /// The bytes of buffer view `view` (§3.6.2.2), checked against its buffer.
    fn view_bytes(&self, view: usize) -> Result<&[u8], String> {
        let v = self.root.buffer_views.get(view).ok_or_else(|| format!("buffer view {view} does not exist"))?;
        let b = v.buffer.value();
        let buffer = self
            .buffers
            .get(b)
            .ok_or_else(|| format!("buffer view {view} refers to buffer {b}, which does not exist"))?;
        let start = to_usize(v.byte_offset.map_or(0, |o| o.0));
        let len = to_usize(v.byte_length.0);
        start.checked_add(len).and_then(|end| buffer.get(start..end)).ok_or_else(|| {
            format!(
                "buffer view {view} covers {len} bytes from offset {start}, but buffer {b} has only {} bytes",
                buffer.len()
            )
        })
    }

    /// Locates `count` elements of `components` × `component` in buffer view `view` starting
    /// at `offset`, checking offset + (count − 1) · stride + element size ≤ view length
    /// (§3.6.2.4) with checked arithmetic. `tight` ignores the view's byteStride (sparse data).
    #[allow(clippy::too_many_arguments)]
    fn locate(
        &self,
        accessor: usize,
        what: &str,
        view: usize,
        offset: usize,
        count: usize,
        component: ComponentType,
        components: usize,
        normalized: bool,
        tight: bool,
    ) -> Result<Elements<'_>, SceneError> {
        let out_of_range = |reason: String| SceneError::AccessorOutOfRange {
            file: self.file.to_string(),
            accessor,
            what: what.to_string(),
            reason,
        };
        let bytes = self.view_bytes(view).map_err(out_of_range)?;
        let element = component.size() * components;
        let stride = match self.root.buffer_views.get(view).and_then(|v| v.byte_stride) {
            Some(s) if !tight => s.0,
            _ => element,
        };
        if stride < element {
            return Err(self.invalid(format!(
                "buffer view {view} has byteStride {stride}, smaller than the {element}-byte elements of accessor {accessor} ({what})"
            )));
        }
        if count > 0 {
            let end = (count - 1)
                .checked_mul(stride)
                .and_then(|x| x.checked_add(offset))
                .and_then(|x| x.checked_add(element));
            if end.is_none_or(|e| e > bytes.len()) {
                return Err(out_of_range(format!(
                    "{count} elements of {element} bytes (stride {stride}) from offset {offset} need {} bytes, but buffer view {view} has {}",
                    end.map_or_else(|| "more than 2^64".to_string(), |e| e.to_string()),
                    bytes.len()
                )));
            }
        }
        Ok(Elements { bytes, offset, stride, component, normalized })
    }

    /// Reads accessor `index` into a flat vector of `T` (count × components), with `get`
    /// converting one component. Checks the type against `types`, the component type with
    /// `component_ok`, all ranges, and applies sparse substitution (§3.6.2.3).
    fn read_accessor<T: Copy + Default>(
        &self,
        index: usize,
        what: &str,
        types: &[AccessorType],
        component_ok: impl Fn(ComponentType) -> bool,
        get: impl Fn(&Elements<'_>, usize, usize) -> T,
    ) -> Result<(Vec<T>, usize), SceneError> {
        let acc = self
            .root
            .accessors
            .get(index)
            .ok_or_else(|| self.invalid(format!("{what} refers to accessor {index}, which does not exist")))?;
        let Checked::Valid(ty) = acc.type_ else {
            return Err(self.invalid(format!("accessor {index} ({what}) has an unknown type")));
        };
        if !types.contains(&ty) {
            return Err(self.invalid(format!("accessor {index} ({what}) has type {ty:?}, expected one of {types:?}")));
        }
        let Checked::Valid(GenericComponentType(component)) = acc.component_type else {
            return Err(self.invalid(format!("accessor {index} ({what}) has an unknown componentType")));
        };
        if !component_ok(component) {
            return Err(self.invalid(format!(
                "accessor {index} ({what}) has componentType {component:?}, which is not allowed here"
            )));
        }
        let n = ty.multiplicity();
        let count = to_usize(acc.count.0);
        let out_of_range = |reason: String| SceneError::AccessorOutOfRange {
            file: self.file.to_string(),
            accessor: index,
            what: what.to_string(),
            reason,
        };
        let mut out = match acc.buffer_view {
            Some(view) => {
                let offset = to_usize(acc.byte_offset.map_or(0, |o| o.0));
                let el = self.locate(index, what, view.value(), offset, count, component, n, acc.normalized, false)?;
                let mut out = Vec::with_capacity(count * n); // bounded: the elements were found in the buffer
                for i in 0..count {
                    for c in 0..n {
                        out.push(get(&el, i, c));
                    }
                }
                out
            }
            None => {
                if acc.sparse.is_none() || count > MAX_ZERO_ACCESSOR_ELEMENTS {
                    return Err(out_of_range(format!(
                        "it has no buffer view and {}",
                        if acc.sparse.is_none() { "no sparse data".to_string() } else { format!("{count} elements") }
                    )));
                }
                vec![T::default(); count * n]
            }
        };
        if let Some(sparse) = &acc.sparse {
            let sparse_count = to_usize(sparse.count.0);
            let Checked::Valid(IndexComponentType(index_type)) = sparse.indices.component_type else {
                return Err(self.invalid(format!("accessor {index} ({what}) has sparse indices of an unknown type")));
            };
            let indices = self.locate(
                index,
                what,
                sparse.indices.buffer_view.value(),
                to_usize(sparse.indices.byte_offset.0),
                sparse_count,
                index_type,
                1,
                false,
                true,
            )?;
            let values = self.locate(
                index,
                what,
                sparse.values.buffer_view.value(),
                to_usize(sparse.values.byte_offset.0),
                sparse_count,
                component,
                n,
                acc.normalized,
                true,
            )?;
            for k in 0..sparse_count {
                let i = indices.uint(k, 0) as usize;
                if i >= count {
                    return Err(out_of_range(format!("sparse index {i} is not below the accessor's count {count}")));
                }
                for c in 0..n {
                    if let Some(slot) = out.get_mut(i * n + c) {
                        *slot = get(&values, k, c);
                    }
                }
            }
        }
        Ok((out, n))
    }

    /// Reads a float accessor of one of `types` (any component type; integers are converted,
    /// normalized ones per §3.11).
    fn read_floats(&self, index: usize, what: &str, types: &[AccessorType]) -> Result<Vec<f32>, SceneError> {
        self.read_accessor(index, what, types, |_| true, |el, i, c| el.float(i, c)).map(|(v, _)| v)
    }

    /// Reads an index accessor: SCALAR of unsigned byte, short or int (§3.7.2.1).
    fn read_indices(&self, index: usize, what: &str) -> Result<Vec<u32>, SceneError> {
        let ok = |c| matches!(c, ComponentType::U8 | ComponentType::U16 | ComponentType::U32);
        self.read_accessor(index, what, &[AccessorType::Scalar], ok, |el, i, c| el.uint(i, c)).map(|(v, _)| v)
    }

    // -----------------------------------------------------------------------------------
    // Node hierarchy (§3.5)
    // -----------------------------------------------------------------------------------

    /// Checks that the nodes form a forest (§3.5.2: "node hierarchy MUST be a set of disjoint
    /// strict trees"), picks the root nodes of the default scene (or scene 0, or all parentless
    /// nodes when there are no scenes) and returns them with the set of nodes under them.
    fn hierarchy(&self) -> Result<(Vec<usize>, Vec<bool>), SceneError> {
        let nodes = &self.root.nodes;
        let n = nodes.len();
        let cycle = |reason: String| SceneError::Cycle { file: self.file.to_string(), reason };
        let mut parent: Vec<Option<usize>> = vec![None; n];
        for (p, node) in nodes.iter().enumerate() {
            for c in node.children.iter().flatten() {
                let c = c.value();
                let Some(slot) = parent.get_mut(c) else {
                    return Err(self.invalid(format!("node {p} lists child {c}, which does not exist")));
                };
                if c == p {
                    return Err(cycle(format!("node {p} is its own child")));
                }
                if let Some(q) = *slot {
                    return Err(cycle(format!("node {c} is a child of both node {q} and node {p}")));
                }
                *slot = Some(p);
            }
        }
        // Every node now has at most one parent, so a node that is not below a parentless
        // node lies on (or below) a cycle.
        let parentless: Vec<usize> = (0..n).filter(|&i| parent.get(i).is_some_and(Option::is_none)).collect();
        let below_roots = self.reach(&parentless);
        if let Some(start) = below_roots.iter().position(|r| !r) {
            let mut path = vec![start];
            let mut cur = start;
            while let Some(Some(p)) = parent.get(cur) {
                if path.contains(p) || path.len() > n {
                    path.push(*p);
                    break;
                }
                path.push(*p);
                cur = *p;
            }
            let chain: Vec<String> = path.iter().map(usize::to_string).collect();
            return Err(cycle(format!("nodes form a cycle (child → parent: {})", chain.join(" → "))));
        }

        let scene_index = match self.root.scene {
            Some(s) => Some(s.value()),
            None if !self.root.scenes.is_empty() => Some(0),
            None => None,
        };
        let roots = match scene_index {
            Some(s) => {
                let scene = self
                    .root
                    .scenes
                    .get(s)
                    .ok_or_else(|| self.invalid(format!("the default scene {s} does not exist")))?;
                let mut roots = Vec::new();
                for r in &scene.nodes {
                    let r = r.value();
                    match parent.get(r) {
                        None => return Err(self.invalid(format!("scene {s} lists node {r}, which does not exist"))),
                        Some(Some(p)) => {
                            return Err(self.invalid(format!(
                                "scene {s} lists node {r} as a root, but it is a child of node {p} (§3.5.2: scene nodes must be roots)"
                            )));
                        }
                        Some(None) if !roots.contains(&r) => roots.push(r),
                        Some(None) => {}
                    }
                }
                roots
            }
            None => parentless,
        };
        let reachable = self.reach(&roots);
        Ok((roots, reachable))
    }

    /// Marks the nodes in the subtrees of `roots` (children indices must be valid).
    fn reach(&self, roots: &[usize]) -> Vec<bool> {
        let nodes = &self.root.nodes;
        let mut seen = vec![false; nodes.len()];
        let mut stack: Vec<usize> = roots.to_vec();
        while let Some(i) = stack.pop() {
            match seen.get_mut(i) {
                Some(s) if !*s => *s = true,
                _ => continue,
            }
            if let Some(node) = nodes.get(i) {
                stack.extend(node.children.iter().flatten().map(|c| c.value()));
            }
        }
        seen
    }

    /// A node's local transform: TRS, or a matrix decomposed into TRS (§3.5.3: matrices
    /// must be decomposable). Rotations are renormalised.
    fn node_transform(&mut self, i: usize, node: &json::Node) -> Result<Transform, SceneError> {
        let (scale, rotation, translation) = match node.matrix {
            Some(m) => {
                let m = Mat4::from_cols_array(&m);
                if !m.is_finite() {
                    return Err(self.invalid(format!("node {i} has a non-finite matrix")));
                }
                let (s, r, t) = m.to_scale_rotation_translation();
                (s, r, t)
            }
            None => (
                node.scale.map_or(Vec3::ONE, Vec3::from),
                node.rotation.map_or(Quat::IDENTITY, |q| Quat::from_array(q.0)),
                node.translation.map_or(Vec3::ZERO, Vec3::from),
            ),
        };
        if !(scale.is_finite() && translation.is_finite()) {
            return Err(self.invalid(format!("node {i} has a non-finite translation or scale")));
        }
        let len = rotation.length();
        let rotation = if rotation.is_finite() && len > 1e-6 {
            rotation / len
        } else {
            self.warn(format!("node {i} has an invalid rotation; using no rotation"));
            Quat::IDENTITY
        };
        Ok(Transform { translation, rotation, scale })
    }

    /// Builds all nodes (indices stay those of the file); meshes, lights and cameras are
    /// loaded for nodes in the active scene only.
    fn load_nodes(&mut self, reachable: &[bool]) -> Result<(), SceneError> {
        let root = self.root;
        for (i, jn) in root.nodes.iter().enumerate() {
            let transform = self.node_transform(i, jn)?;
            let active = reachable.get(i).copied().unwrap_or(false);
            let mesh = match jn.mesh {
                Some(m) if active => Some(self.mesh(m.value())?),
                _ => None,
            };
            let light_ref = jn.extensions.as_ref().and_then(|e| e.khr_lights_punctual.as_ref());
            let light = match light_ref {
                Some(l) if active => Some(self.light(l.light.value())?),
                _ => None,
            };
            let camera = match jn.camera {
                Some(c) if active => self.camera(c.value())?,
                _ => None,
            };
            if jn.skin.is_some() {
                self.warn("skinned meshes are drawn in their bind pose (skins are not supported)".to_string());
            }
            self.scene.nodes.push(Node {
                name: jn.name.clone().unwrap_or_else(|| format!("node {i}")),
                transform,
                children: jn.children.iter().flatten().map(|c| c.value()).collect(),
                mesh,
                light,
                camera,
            });
        }
        Ok(())
    }

    /// The name of the active glTF scene, or a generic one.
    fn scene_name(&self) -> String {
        let index = self.root.scene.map_or(0, |s| s.value());
        self.root.scenes.get(index).and_then(|s| s.name.clone()).unwrap_or_else(|| "glTF scene".to_string())
    }

    // -----------------------------------------------------------------------------------
    // Lights (KHR_lights_punctual) and cameras (§3.10)
    // -----------------------------------------------------------------------------------

    /// Loads KHR_lights_punctual light `index` (shared between nodes that use it).
    fn light(&mut self, index: usize) -> Result<usize, SceneError> {
        if let Some(&l) = self.light_map.get(&index) {
            return Ok(l);
        }
        use json::extensions::scene::khr_lights_punctual::Type;
        let lights = self.root.extensions.as_ref().and_then(|e| e.khr_lights_punctual.as_ref());
        let l = lights.and_then(|k| k.lights.get(index)).ok_or_else(|| {
            self.invalid(format!("a node refers to KHR_lights_punctual light {index}, which does not exist"))
        })?;
        let kind = match l.type_ {
            Checked::Valid(Type::Directional) => LightKind::Directional,
            Checked::Valid(Type::Point) => LightKind::Point,
            Checked::Valid(Type::Spot) => {
                let (inner, outer) = l
                    .spot
                    .as_ref()
                    .map_or((0.0, std::f32::consts::FRAC_PI_4), |s| (s.inner_cone_angle, s.outer_cone_angle));
                let outer_ok = outer.clamp(1e-3, std::f32::consts::FRAC_PI_2);
                let inner_ok = inner.clamp(0.0, outer_ok);
                if outer_ok != outer || inner_ok != inner || l.spot.is_none() {
                    self.warn(format!(
                        "spot light {index} has invalid or missing cone angles (inner {inner}, outer {outer}); \
                         using inner {inner_ok}, outer {outer_ok}"
                    ));
                }
                LightKind::Spot { inner_cone: inner_ok, outer_cone: outer_ok }
            }
            Checked::Invalid => {
                return Err(self.invalid(format!("KHR_lights_punctual light {index} has an unknown type")));
            }
        };
        let light = Light {
            name: l.name.clone().unwrap_or_else(|| format!("light {index}")),
            kind,
            color: Vec3::from(l.color),
            intensity: l.intensity.max(0.0),
            range: l.range.filter(|r| *r > 0.0 && r.is_finite()),
        };
        self.scene.lights.push(light);
        let id = self.scene.lights.len() - 1;
        self.light_map.insert(index, id);
        Ok(id)
    }

    /// Loads camera `index`; a camera with unusable parameters is dropped with a warning.
    fn camera(&mut self, index: usize) -> Result<Option<usize>, SceneError> {
        if let Some(&c) = self.camera_map.get(&index) {
            return Ok(c);
        }
        use json::camera::Type;
        let cam = self
            .root
            .cameras
            .get(index)
            .ok_or_else(|| self.invalid(format!("a node refers to camera {index}, which does not exist")))?;
        let projection = match (cam.type_, &cam.perspective, &cam.orthographic) {
            (Checked::Valid(Type::Perspective), Some(p), _)
                if p.yfov > 0.0 && p.yfov < std::f32::consts::PI && p.znear > 0.0 =>
            {
                Some(Projection::Perspective { yfov: p.yfov, znear: p.znear, zfar: p.zfar.filter(|f| *f > p.znear) })
            }
            (Checked::Valid(Type::Orthographic), _, Some(o)) if o.xmag != 0.0 && o.ymag != 0.0 && o.zfar > o.znear => {
                Some(Projection::Orthographic { xmag: o.xmag, ymag: o.ymag, znear: o.znear, zfar: o.zfar })
            }
            _ => None,
        };
        let id = match projection {
            Some(projection) => {
                let name = cam.name.clone().unwrap_or_else(|| format!("camera {index}"));
                self.scene.cameras.push(CameraDef { name, projection });
                Some(self.scene.cameras.len() - 1)
            }
            None => {
                self.warn(format!("camera {index} has a missing or invalid projection and is ignored"));
                None
            }
        };
        self.camera_map.insert(index, id);
        Ok(id)
    }

    // -----------------------------------------------------------------------------------
    // Materials and textures (§3.9, §3.8)
    // -----------------------------------------------------------------------------------

    /// Loads glTF material `index` (None: the default material of §3.9.6) as a scene material.
    fn material(&mut self, index: Option<usize>) -> Result<usize, SceneError> {
        if let Some(&m) = self.material_map.get(&index) {
            return Ok(m);
        }
        let (material, uv) = match index {
            None => (Material::default(), UvUse::default()),
            Some(i) => {
                let root = self.root;
                let m = root
                    .materials
                    .get(i)
                    .ok_or_else(|| self.invalid(format!("a primitive refers to material {i}, which does not exist")))?;
                let pbr = &m.pbr_metallic_roughness;
                let (texture, uv) = match &pbr.base_color_texture {
                    Some(info) => {
                        let transform = info.extensions.as_ref().and_then(|e| e.texture_transform.as_ref());
                        let uv = UvUse {
                            set: transform.and_then(|t| t.tex_coord).unwrap_or(info.tex_coord),
                            transform: transform.map(|t| uv_transform(t.offset.0, t.rotation.0, t.scale.0)),
                        };
                        (self.texture(info.index.value())?, uv)
                    }
                    None => (None, UvUse::default()),
                };
                let strength = m
                    .extensions
                    .as_ref()
                    .and_then(|e| e.emissive_strength.as_ref())
                    .map_or(1.0, |s| s.emissive_strength.0);
                let material = Material {
                    name: m.name.clone().unwrap_or_else(|| format!("material {i}")),
                    base_color: Vec4::from_array(pbr.base_color_factor.0),
                    base_color_texture: texture,
                    metallic: pbr.metallic_factor.0.clamp(0.0, 1.0),
                    roughness: pbr.roughness_factor.0.clamp(0.0, 1.0),
                    emissive: (Vec3::from(m.emissive_factor.0) * strength).max(Vec3::ZERO),
                    sample_weight: 1.0,
                    double_sided: m.double_sided,
                    specular_override: None,
                };
                (material, uv)
            }
        };
        self.scene.materials.push(material);
        self.material_uv.push(uv);
        let id = self.scene.materials.len() - 1;
        self.material_map.insert(index, id);
        Ok(id)
    }

    /// Loads the image of texture `index` (decoded to RGBA8; shared between textures that
    /// use the same image). A texture without an image (extension-only source) is skipped.
    fn texture(&mut self, index: usize) -> Result<Option<usize>, SceneError> {
        let root = self.root;
        let tex = root
            .textures
            .get(index)
            .ok_or_else(|| self.invalid(format!("a material refers to texture {index}, which does not exist")))?;
        let image = tex.source.value();
        if image == u32::MAX as usize {
            self.warn(format!("texture {index} has no image in a supported format and is ignored"));
            return Ok(None);
        }
        if let Some(&t) = self.image_map.get(&image) {
            return Ok(Some(t));
        }
        let img = root
            .images
            .get(image)
            .ok_or_else(|| self.invalid(format!("texture {index} refers to image {image}, which does not exist")))?;
        let name = img.name.clone().unwrap_or_else(|| format!("image {image}"));
        let missing = |uri: &str, reason: String| SceneError::MissingImage {
            file: self.file.to_string(),
            image,
            uri: uri.to_string(),
            reason,
        };
        let encoded: Vec<u8> =
            match (img.buffer_view, img.uri.as_deref()) {
                (Some(view), _) => self.view_bytes(view.value()).map_err(|r| missing("bufferView", r))?.to_vec(),
                (None, Some(uri)) if is_data_uri(uri) => decode_data_uri(uri).map_err(|reason| {
                    SceneError::BadDataUri { file: self.file.to_string(), what: format!("image {image}"), reason }
                })?,
                (None, Some(uri)) => self.read_external(uri, &format!("image {image}"), |r| missing(uri, r))?,
                (None, None) => return Err(self.invalid(format!("image {image} has neither a uri nor a bufferView"))),
            };
        let decoded = image::load_from_memory(&encoded).map_err(|e| SceneError::Image {
            file: self.file.to_string(),
            image,
            name: name.clone(),
            reason: e.to_string(),
        })?;
        let rgba = decoded.to_rgba8();
        self.scene.textures.push(TextureImage {
            name,
            width: rgba.width(),
            height: rgba.height(),
            rgba8: rgba.into_raw(),
        });
        let id = self.scene.textures.len() - 1;
        self.image_map.insert(image, id);
        Ok(Some(id))
    }

    // -----------------------------------------------------------------------------------
    // Meshes (§3.7)
    // -----------------------------------------------------------------------------------

    /// Loads mesh `index` (shared between nodes that use it).
    fn mesh(&mut self, index: usize) -> Result<usize, SceneError> {
        if let Some(&m) = self.mesh_map.get(&index) {
            return Ok(m);
        }
        let root = self.root;
        let m = root
            .meshes
            .get(index)
            .ok_or_else(|| self.invalid(format!("a node refers to mesh {index}, which does not exist")))?;
        let name = m.name.clone().unwrap_or_else(|| format!("mesh {index}"));
        let mut primitives = Vec::new();
        for (p, jp) in m.primitives.iter().enumerate() {
            if let Some(prim) = self.primitive(&name, p, jp)? {
                primitives.push(prim);
            }
        }
        self.scene.meshes.push(Mesh { name, primitives });
        let id = self.scene.meshes.len() - 1;
        self.mesh_map.insert(index, id);
        Ok(id)
    }

    /// Loads one primitive as a triangle list (§3.7.2). Strips and fans are converted;
    /// points and lines are skipped with a warning. Missing normals become flat normals
    /// (§3.7.2.1: "client implementations MUST calculate flat normals").
    fn primitive(&mut self, mesh: &str, p: usize, jp: &json::mesh::Primitive) -> Result<Option<Primitive>, SceneError> {
        use json::mesh::{Mode, Semantic};
        let mode = match jp.mode {
            Checked::Valid(m) => m,
            Checked::Invalid => return Err(self.invalid(format!("mesh '{mesh}' primitive {p} has an unknown mode"))),
        };
        if !matches!(mode, Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan) {
            let name = match mode {
                Mode::Points => "POINTS (mode 0)",
                Mode::Lines => "LINES (mode 1)",
                Mode::LineLoop => "LINE_LOOP (mode 2)",
                _ => "LINE_STRIP (mode 3)",
            };
            self.warn(format!("mesh '{mesh}' primitive {p} draws {name}, which cannot be rendered; it is skipped"));
            self.skipped.push(Skipped { mesh: mesh.to_string(), primitive: p, mode: name.to_string() });
            return Ok(None);
        }
        let material = self.material(jp.material.map(|m| m.value()))?;
        let uv_use = self.material_uv.get(material).copied().unwrap_or_default();
        let what = |attr: &str| format!("{attr} of mesh '{mesh}' primitive {p}");
        let attribute = |s: Semantic| jp.attributes.get(&Checked::Valid(s)).map(|a| a.value());

        let pos_index = attribute(Semantic::Positions)
            .ok_or_else(|| self.invalid(format!("mesh '{mesh}' primitive {p} has no POSITION attribute")))?;
        let positions = self.read_floats(pos_index, &what("POSITION"), &[AccessorType::Vec3])?;
        let n = positions.len() / 3;
        let normals = match attribute(Semantic::Normals) {
            Some(i) => {
                let v = self.read_floats(i, &what("NORMAL"), &[AccessorType::Vec3])?;
                if v.len() != positions.len() {
                    return Err(self.invalid(format!(
                        "mesh '{mesh}' primitive {p}: NORMAL has {} elements but POSITION has {n}",
                        v.len() / 3
                    )));
                }
                Some(v)
            }
            None => None,
        };
        let uv_name = format!("TEXCOORD_{}", uv_use.set);
        let uvs = match attribute(Semantic::TexCoords(uv_use.set)) {
            Some(i) => {
                let v = self.read_floats(i, &what(&uv_name), &[AccessorType::Vec2])?;
                if v.len() / 2 != n {
                    return Err(self.invalid(format!(
                        "mesh '{mesh}' primitive {p}: {uv_name} has {} elements but POSITION has {n}",
                        v.len() / 2
                    )));
                }
                Some(v)
            }
            None => None,
        };
        let raw_indices = match jp.indices {
            Some(i) => {
                let indices = self.read_indices(i.value(), &what("indices"))?;
                if let Some(&bad) = indices.iter().find(|&&x| x as usize >= n) {
                    return Err(SceneError::IndexOutOfRange {
                        file: self.file.to_string(),
                        mesh: mesh.to_string(),
                        primitive: p,
                        index: bad,
                        vertex_count: n,
                    });
                }
                indices
            }
            None => {
                let count = u32::try_from(n)
                    .map_err(|_| self.invalid(format!("mesh '{mesh}' primitive {p} has too many vertices ({n})")))?;
                (0..count).collect()
            }
        };
        let indices = match mode {
            Mode::TriangleStrip => strip_to_list(&raw_indices),
            Mode::TriangleFan => fan_to_list(&raw_indices),
            _ => {
                let mut list = raw_indices;
                if !list.len().is_multiple_of(3) {
                    self.warn(format!(
                        "mesh '{mesh}' primitive {p} has {} indices, not a multiple of 3; the last {} are ignored",
                        list.len(),
                        list.len() % 3
                    ));
                    list.truncate(list.len() - list.len() % 3);
                }
                list
            }
        };
        if indices.is_empty() {
            return Ok(None);
        }

        let vec3 = |v: &[f32], i: usize| match v.get(3 * i..3 * i + 3) {
            Some(&[x, y, z]) => [x, y, z],
            _ => [0.0; 3],
        };
        let uv = |i: usize| {
            let t = match uvs.as_deref().and_then(|v| v.get(2 * i..2 * i + 2)) {
                Some(&[u, v]) => Vec2::new(u, v),
                _ => Vec2::ZERO,
            };
            uv_use.transform.map_or(t, |m| m.transform_point2(t)).to_array()
        };
        let (vertices, indices) = match &normals {
            Some(normals) => {
                let vertices = (0..n)
                    .map(|i| Vertex { position: vec3(&positions, i), normal: vec3(normals, i), uv: uv(i) })
                    .collect();
                (vertices, indices)
            }
            None => {
                let mut vertices = Vec::with_capacity(indices.len());
                for tri in indices.chunks_exact(3) {
                    let corners = tri.iter().map(|&i| i as usize);
                    let p: Vec<Vec3> = corners.clone().map(|i| Vec3::from(vec3(&positions, i))).collect();
                    let normal = match p.as_slice() {
                        [a, b, c] => (*b - *a).cross(*c - *a).normalize_or(Vec3::Y),
                        _ => Vec3::Y,
                    };
                    for i in corners {
                        vertices.push(Vertex { position: vec3(&positions, i), normal: normal.to_array(), uv: uv(i) });
                    }
                }
                let count = u32::try_from(vertices.len())
                    .map_err(|_| self.invalid(format!("mesh '{mesh}' primitive {p} has too many triangles")))?;
                (vertices, (0..count).collect())
            }
        };
        Ok(Some(Primitive { vertices, indices, material }))
    }

    // -----------------------------------------------------------------------------------
    // Animations (§3.11)
    // -----------------------------------------------------------------------------------

    /// Loads translation, rotation and scale channels; morph target weights are ignored with
    /// a warning. Key times must be finite and non-decreasing, and the output count must be
    /// the key count (STEP, LINEAR) or three times it (CUBICSPLINE: in-tangent, value, out-tangent).
    fn load_animations(&mut self) -> Result<(), SceneError> {
        use json::animation::{Interpolation as JInterp, Property};
        let (root, file) = (self.root, self.file);
        for (ai, a) in root.animations.iter().enumerate() {
            let name = a.name.clone().unwrap_or_else(|| format!("animation {ai}"));
            let bad =
                |reason: String| SceneError::BadAnimation { file: file.to_string(), animation: name.clone(), reason };
            let mut channels = Vec::new();
            for (ci, ch) in a.channels.iter().enumerate() {
                let s = ch.sampler.value();
                let sampler = a
                    .samplers
                    .get(s)
                    .ok_or_else(|| bad(format!("channel {ci} refers to sampler {s}, which does not exist")))?;
                let node = ch.target.node.value();
                if node >= root.nodes.len() {
                    return Err(bad(format!("channel {ci} targets node {node}, which does not exist")));
                }
                let path = match ch.target.path {
                    Checked::Valid(Property::MorphTargetWeights) => {
                        self.warn("morph target weight animations are not supported and are ignored".to_string());
                        continue;
                    }
                    Checked::Valid(p) => p,
                    Checked::Invalid => return Err(bad(format!("channel {ci} animates an unknown property"))),
                };
                let interpolation = match sampler.interpolation {
                    Checked::Valid(JInterp::Linear) => Interpolation::Linear,
                    Checked::Valid(JInterp::Step) => Interpolation::Step,
                    Checked::Valid(JInterp::CubicSpline) => Interpolation::CubicSpline,
                    Checked::Invalid => return Err(bad(format!("sampler {s} has an unknown interpolation"))),
                };
                let times = self.read_floats(
                    sampler.input.value(),
                    &format!("key times of animation '{name}' channel {ci}"),
                    &[AccessorType::Scalar],
                )?;
                if times.iter().any(|t| !t.is_finite()) || times.windows(2).any(|w| matches!(w, [a, b] if b < a)) {
                    return Err(bad(format!("channel {ci} has key times that are not finite and increasing")));
                }
                if times.is_empty() {
                    self.warn(format!("animation '{name}' channel {ci} has no keys and is ignored"));
                    continue;
                }
                let ty = if path == Property::Rotation { AccessorType::Vec4 } else { AccessorType::Vec3 };
                let out = self.read_floats(
                    sampler.output.value(),
                    &format!("values of animation '{name}' channel {ci}"),
                    &[ty],
                )?;
                let per_key = if interpolation == Interpolation::CubicSpline { 3 } else { 1 };
                let values = out.len() / ty.multiplicity();
                if values != times.len() * per_key {
                    return Err(bad(format!(
                        "channel {ci} has {} key times but {values} output values; {interpolation:?} interpolation needs {}",
                        times.len(),
                        times.len() * per_key
                    )));
                }
                let target = match path {
                    Property::Rotation => {
                        let (quads, _) = out.as_chunks::<4>();
                        ChannelTarget::Rotation(
                            quads
                                .iter()
                                .map(|&q| {
                                    let q = Quat::from_array(q);
                                    // Cubic-spline tangents are not unit quaternions; values and
                                    // linear/step keys are renormalised.
                                    if interpolation == Interpolation::CubicSpline || q.length_squared() == 0.0 {
                                        q
                                    } else {
                                        q.normalize()
                                    }
                                })
                                .collect(),
                        )
                    }
                    _ => {
                        let (triples, _) = out.as_chunks::<3>();
                        let v = triples.iter().map(|&t| Vec3::from_array(t)).collect();
                        if path == Property::Translation {
                            ChannelTarget::Translation(v)
                        } else {
                            ChannelTarget::Scale(v)
                        }
                    }
                };
                channels.push(Channel { node, interpolation, times, target });
            }
            if !channels.is_empty() {
                self.scene.animations.push(Animation { name, channels });
            }
        }
        Ok(())
    }
}

/// KHR_texture_transform's UV matrix: translation × rotation × scale, with the rotation
/// matrix of the ratified extension text (columns (cos, −sin), (sin, cos)).
fn uv_transform(offset: [f32; 2], rotation: f32, scale: [f32; 2]) -> Mat3 {
    let (s, c) = rotation.sin_cos();
    let t = Mat3::from_translation(Vec2::from(offset));
    let r = Mat3::from_cols(Vec3::new(c, -s, 0.0), Vec3::new(s, c, 0.0), Vec3::Z);
    t * r * Mat3::from_scale(Vec2::from(scale))
}

/// Triangle strip → list (§3.7.2.1: triangle i is {v_i, v_{i+1+i%2}, v_{i+2−i%2}}).
fn strip_to_list(v: &[u32]) -> Vec<u32> {
    let mut out = Vec::with_capacity(v.len().saturating_sub(2) * 3);
    for (i, w) in v.windows(3).enumerate() {
        if let &[a, b, c] = w {
            if i % 2 == 0 {
                out.extend([a, b, c]);
            } else {
                out.extend([a, c, b]);
            }
        }
    }
    out
}

/// Triangle fan → list (§3.7.2.1: triangle i is {v_{i+1}, v_{i+2}, v_0}).
fn fan_to_list(v: &[u32]) -> Vec<u32> {
    let Some((&first, rest)) = v.split_first() else { return Vec::new() };
    let mut out = Vec::with_capacity(rest.len().saturating_sub(1) * 3);
    for w in rest.windows(2) {
        if let &[b, c] = w {
            out.extend([b, c, first]);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicUsize, Ordering};

    /// `../shared/scenes/<rel>` from the project root; fails (does not skip) when missing.
    fn shared_scene(rel: &str) -> PathBuf {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/scenes").join(rel);
        assert!(
            path.is_file(),
            "shared test scene {} is missing: the tests need the read-only ../shared/scenes folder next to the project",
            path.display()
        );
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
    fn shared_cornell_box_loads_with_default_light() {
        let scene = load_gltf_file(&shared_scene("cornell-box/CornellBox-Original.gltf"), &LoadOptions::default())
            .expect("CornellBox-Original loads");
        assert_eq!(scene.triangle_count(), 32);
        assert_eq!(scene.name, "CornellBox-Original");
        assert_eq!(scene.lights.len(), 1, "only the default light: the file has an emissive quad, no punctual light");
        assert_eq!(scene.lights[0].name, "default spot");
        assert!(scene.warnings.iter().any(|w| w.contains("no lights")), "{:?}", scene.warnings);
        let light = scene.materials.iter().find(|m| m.name == "Light").expect("Light material");
        assert_eq!(light.emissive, Vec3::ONE);
        // The mesh node is rotated +90° about X in the file; the floor ends up at y ≈ 0.
        let b = scene.bounds(0.0);
        assert!(b.min.y.abs() < 0.05 && (b.max.y - 1.99).abs() < 0.05, "{b:?}");
    }

    #[test]
    fn shared_chair_scene_loads_with_its_sun() {
        let scene = load_gltf_file(&shared_scene("chair-on-floor/MixedLightingExample.gltf"), &LoadOptions::default())
            .expect("MixedLightingExample loads");
        assert_eq!(scene.triangle_count(), 40898);
        assert_eq!(scene.lights.len(), 1);
        assert_eq!(scene.lights[0].kind, LightKind::Directional);
        assert_eq!(scene.lights[0].intensity, 2049.0);
        // Base colour images of the materials in use: fabric (Mango Velvet), label, wood (brown
        // and black share one image). Peacock Velvet is only a KHR_materials_variants alternative.
        assert_eq!(scene.textures.len(), 3);
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
        let scene = load_gltf_file(&shared_scene("hotel-room/hotel-room.glb"), &opts).expect("hotel room loads");
        assert_eq!(scene.triangle_count(), 99029);
        assert_eq!(scene.lights.len(), 1);
        assert_eq!(scene.lights[0].name, "default spot");
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
        let scene = load_gltf_bytes(triangle_gltf(&data_uri(&triangle_bin([0, 1, 2]))).as_bytes(), None, &no_light)
            .expect("loads");
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
        let opts = LoadOptions { unit_scale: 0.5, add_default_light: false };
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
        let scene =
            load_str(&triangle_gltf_with(&format!("\"uri\":\"{}\",", data_uri(&triangle_bin([0, 1, 2]))), 3, 5))
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

        let junk = format!("data:image/png;base64,{}", base64::engine::general_purpose::STANDARD.encode(b"not a png"));
        let err = load_str(&with_image(&junk)).unwrap_err();
        assert!(matches!(err, SceneError::Image { image: 0, .. }), "{err}");
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
                    *byte = if byte.is_ascii_digit() && next() % 2 == 0 {
                        b'0' + (next() % 10) as u8
                    } else {
                        next() as u8
                    };
                }
                let _ = load_gltf_bytes(&bytes, None, &LoadOptions::default());
            }
        }
    }
}
