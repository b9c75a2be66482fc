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

mod accessors;
mod animations;
mod compression;
#[cfg(test)]
mod compression_tests;
mod container;
#[cfg(test)]
mod material_tests;
mod materials;
mod meshes;
mod nodes;
mod tangents;
#[cfg(test)]
mod tests;

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use glam::{Mat3, Vec3};
use gltf::json;

use super::{Node, Scene, Transform};
use container::split_container;

/// glTF extensions this loader understands; others are reported in [`Scene::warnings`].
/// `KHR_mesh_quantization` needs no code of its own: accessors of any component type, normalized
/// or not, are read as floats (`accessors.rs`), and the dequantizing transform is the node's.
const SUPPORTED_EXTENSIONS: &[&str] = &[
    "KHR_lights_punctual",
    "KHR_texture_transform",
    "KHR_materials_emissive_strength",
    "KHR_mesh_quantization",
    compression::MESHOPT_EXTENSIONS[0],
    compression::MESHOPT_EXTENSIONS[1],
];

/// Required extensions without which the geometry itself cannot be read: loading fails.
/// Draco stays refused: no maintained Rust decoder exists (see the note on issue #18).
const GEOMETRY_COMPRESSION_EXTENSIONS: &[&str] = &["KHR_draco_mesh_compression"];

/// How a glTF file is turned into a [`Scene`].
#[derive(Clone, Debug, PartialEq)]
pub struct LoadOptions {
    /// Factor applied to all world positions (for example 0.001 for a file in millimetres).
    /// Implemented as an extra root node with this uniform scale above the file's roots.
    pub unit_scale: f32,
    /// Adds a default light (see [`Scene::ensure_light`]) when the file has no punctual
    /// light and no emitter, and chooses the view the scene opens on
    /// ([`crate::scene::framing`]).
    pub add_default_light: bool,
    /// With `unit_scale` 1: reads the unit from the scene's extent (millimetres,
    /// centimetres; [`crate::scene::framing::detect_unit_scale`]) and scales to metres,
    /// saying so in [`Scene::units`] and the warnings. Off when the user gave a unit scale.
    pub detect_units: bool,
}

impl Default for LoadOptions {
    fn default() -> Self {
        Self { unit_scale: 1.0, add_default_light: true, detect_units: true }
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
    loader.decode_compressed_views()?;
    let (roots, reachable) = loader.hierarchy()?;
    loader.load_nodes(&reachable)?;
    loader.load_animations()?;
    loader.scene.roots = roots;
    loader.scene.name = loader.scene_name();

    let skipped = std::mem::take(&mut loader.skipped);
    let mut scene = loader.scene;
    let mut unit_scale = opts.unit_scale;
    if opts.detect_units && unit_scale == 1.0 {
        let extent = scene.bounds(0.0).extent().max_element();
        if let Some((scale, unit)) = crate::scene::framing::detect_unit_scale(extent) {
            unit_scale = scale;
            let note = format!(
                "units: {unit} (the scene is {extent:.0} units across), scaled by {scale} to metres; --unit-scale overrides"
            );
            scene.warnings.push(note.clone());
            scene.units = Some((scale, note));
        }
    }
    if unit_scale != 1.0 {
        scene.nodes.push(Node {
            name: format!("unit scale {unit_scale}"),
            transform: Transform { scale: Vec3::splat(unit_scale), ..Transform::default() },
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
        // One BVH for the view and the light (the framing's probes are most of a load),
        // built only when either needs rays.
        let state = scene.evaluate(0.0);
        let needs_rays = state.cameras.is_empty() || (scene.lights.is_empty() && !scene.has_emitters());
        let bvh = needs_rays.then(|| crate::scene::bvh::SceneBvh::new(&scene, &state));
        let view = crate::scene::framing::choose_view_with(&scene, 16.0 / 9.0, Default::default(), bvh.as_ref());
        scene.view = Some(view);
        scene.ensure_light_with(bvh.as_ref());
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

/// Texture coordinate set and KHR_texture_transform matrix of a material's textures.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
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
    /// Decoded bytes of the compressed buffer views (`compression.rs`), by view index.
    decoded_views: HashMap<usize, compression::Decoded>,
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
    /// What the file may still make the loader allocate (`accessors.rs`, `meshes.rs`).
    budget: Budget,
}

/// Per-file limits on what declared counts can make the loader allocate. A count is checked
/// against the data that holds it, but data can be read many times (every primitive that
/// uses an accessor reads it again, strips and fans triple their indices) or not exist at all
/// (an accessor without buffer view is zeros), so a small file could otherwise ask for any
/// amount of memory (issue #19: a 730-byte file with four primitives on one zero-filled
/// accessor of 2²² vertices took 1.3 GB). Real scenes stay far below: the Amazon Lumberyard
/// Bistro (2.8 M triangles) reads about 24 M values. Together the budgets keep what one file
/// can make the loader hold below 512 MiB, the fuzzer's memory cap.
#[derive(Debug)]
struct Budget {
    /// Accessor values (elements × components) still to be read.
    values: std::cell::Cell<usize>,
    /// Elements of accessors without buffer view (zeros) still to be made.
    zeros: std::cell::Cell<usize>,
    /// Vertices still to be built.
    vertices: usize,
    /// Triangle-list indices still to be built.
    indices: usize,
}

/// Accessor values one file may read: 2²⁵ (128 MiB as f32).
const MAX_VALUES_PER_FILE: usize = 1 << 25;
/// Vertices one file may build: 2²³ (256 MiB of vertices).
const MAX_VERTICES_PER_FILE: usize = 1 << 23;
/// Triangle-list indices one file may build: 2²⁵ (11 M triangles, 128 MiB).
const MAX_INDICES_PER_FILE: usize = 1 << 25;

impl Default for Budget {
    fn default() -> Self {
        Self {
            values: std::cell::Cell::new(MAX_VALUES_PER_FILE),
            zeros: std::cell::Cell::new(accessors::MAX_ZERO_ACCESSOR_ELEMENTS),
            vertices: MAX_VERTICES_PER_FILE,
            indices: MAX_INDICES_PER_FILE,
        }
    }
}

/// Takes `n` from `left`; false (and nothing taken) when fewer are left.
fn spend(left: &std::cell::Cell<usize>, n: usize) -> bool {
    match left.get().checked_sub(n) {
        Some(rest) => {
            left.set(rest);
            true
        }
        None => false,
    }
}

impl<'a> Loader<'a> {
    fn new(file: &'a str, root: &'a json::Root, base_dir: Option<&'a Path>) -> Self {
        Self {
            file,
            root,
            base_dir,
            buffers: Vec::new(),
            decoded_views: HashMap::new(),
            scene: Scene::default(),
            material_map: HashMap::new(),
            material_uv: Vec::new(),
            image_map: HashMap::new(),
            mesh_map: HashMap::new(),
            light_map: HashMap::new(),
            camera_map: HashMap::new(),
            skipped: Vec::new(),
            budget: Budget::default(),
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
                         decompress it first or re-compress it with meshopt (for example \
                         `gltf-transform meshopt` or `gltfpack -cc`), which GI Lab reads"
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
}
