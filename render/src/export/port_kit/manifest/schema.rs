//! The manifest's schema (`gi-lab-port-kit` version 2, docs/port-kit.md): what
//! `manifest.json` holds, field by field. [`super`] builds it from a capture.

use std::collections::BTreeMap;

use serde::Serialize;

use crate::export::port_kit::reflect::ModuleDecl;

pub const SCHEMA_NAME: &str = "gi-lab-port-kit";
pub const SCHEMA_VERSION: u32 = 2;

/// One golden file: a resource's contents (texture: every level, layers in order, rows
/// packed; buffer: its bytes), with an EXR of level 0, layer 0 for float textures.
#[derive(Clone, Debug, Serialize)]
pub struct GoldenFile {
    pub resource: String,
    /// Where a port writes this output in its outputs folder for `gi-lab verify`
    /// (`frame-K/NN-pass/resource.bin`), and where the kit keeps the golden bytes (the same
    /// path under `golden/`, or an earlier file with the same contents).
    pub path: String,
    pub file: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub exr: Option<String>,
    pub bytes: u64,
}

/// A pass's outputs in one frame.
#[derive(Clone, Debug, Serialize)]
pub struct GoldenPass {
    pub index: usize,
    pub name: String,
    pub outputs: Vec<GoldenFile>,
}

/// One frame of the goldens.
#[derive(Clone, Debug, Serialize)]
pub struct GoldenFrame {
    pub frame: u32,
    /// The `input` resources as the frame's passes read them (uploads: uniforms, scene data).
    pub inputs: Vec<GoldenFile>,
    pub passes: Vec<GoldenPass>,
}

/// A range of a texture's levels and layers as bound.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct ViewRange {
    pub base_mip: u32,
    pub mips: u32,
    pub base_layer: u32,
    pub layers: u32,
    pub dimension: String,
}

/// One binding in force for a step.
#[derive(Clone, Debug, Serialize)]
pub struct BindingUse {
    pub group: u32,
    pub binding: u32,
    /// The shader's name of the variable.
    pub name: String,
    pub kind: String,
    pub access: String,
    /// The resource's name (`resources[].name`).
    pub resource: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub view: Option<ViewRange>,
    /// Buffers: the bound range's offset and size in bytes (a dynamic offset added).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub offset: Option<u64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub size: Option<u64>,
    /// Uniform blocks in `passes` (the last frame): each member's value for this preset, by
    /// the block's layout ([`crate::export::port_kit::uniforms`]).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub values: Vec<(String, serde_json::Value)>,
}

/// A render target of a raster step.
#[derive(Clone, Debug, Serialize)]
pub struct Target {
    pub resource: String,
    pub view: Option<ViewRange>,
    /// Whether the old contents are kept (loaded) rather than cleared.
    pub load: bool,
    /// The clear value when not loaded: a colour's RGBA, or the depth in `[0]`.
    pub clear: [f64; 4],
}

/// One dispatch, draw or copy.
#[derive(Clone, Debug, Serialize)]
pub struct Step {
    /// `dispatch`, `dispatch_indirect`, `draw`, `draw_indexed`, `draw_indirect`, `copy`.
    pub kind: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pipeline: Option<String>,
    /// The pipeline's shader entry points: (module, entry).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub entry_points: Vec<(String, String)>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub constants: Vec<(String, f64)>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub bindings: Vec<BindingUse>,
    /// Workgroups (dispatch) or the draw's vertex/index and instance ranges.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub workgroups: Option<[u32; 3]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub draw: Option<serde_json::Value>,
    /// `workgroups` (x, y, z), or a draw's vertex or index count and instance count, each as
    /// an expression of the image's W and H where one fits ([`crate::export::port_kit::expressions`]); null:
    /// as captured.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub counts_expr: Vec<Option<String>>,
    /// The settings those counts change with ([`crate::export::port_kit::settings_probe`]).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub counts_depend_on: Vec<String>,
    /// Indirect arguments: the buffer and the byte offset.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub indirect: Option<(String, u64)>,
    /// Raster steps: which render pass of this pass they were drawn in (0, 1, …): draws of
    /// one render pass share it, so targets cleared at its start are cleared once.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub render_pass: Option<u32>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub targets: Vec<Target>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub depth_target: Option<Target>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub vertex_buffers: Vec<(u32, String)>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub index_buffer: Option<(String, String)>,
    /// Copies: source, destination and the texel or byte extent.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub copy: Option<serde_json::Value>,
    /// Clears: the buffer zeroed, its byte offset and size.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub clear: Option<(String, u64, u64)>,
    /// Uploads: bytes the CPU writes into a buffer the frame also writes (a counter reset, an
    /// indirect draw's constant part), applied before the pass's other steps.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub upload: Option<UploadStep>,
}

/// Bytes written by the CPU: into `buffer` at `offset`, from the kit's `file`.
#[derive(Clone, Debug, Serialize)]
pub struct UploadStep {
    pub buffer: String,
    pub offset: u64,
    pub bytes: u64,
    pub file: String,
}

/// A timing scope of the frame with its steps.
#[derive(Clone, Debug, Serialize)]
pub struct Pass {
    pub index: usize,
    pub name: String,
    /// `engine`: the G-buffer and the direct light, which an engine has and feeds in;
    /// `technique`: the preset's passes, the port; `tail`: composition and tone mapping;
    /// `between`: copies and clears recorded between timed passes.
    pub role: &'static str,
    pub steps: Vec<Step>,
    /// Dispatches of one pipeline repeated one after another (a loop over a pyramid's
    /// levels): where each begins, how many, and how many as an expression; with the kit's
    /// expressions also a single dispatch whose count follows a setting (a loop that ran
    /// once).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub runs: Vec<Run>,
}

/// Passes repeated per round (one name) or per level (`soler.gather.{k}`): which, how many,
/// and for levels the first level's number, each with its expression.
#[derive(Clone, Debug, Serialize)]
pub struct PassRepeat {
    /// The passes' name, `{k}` standing for a level's number.
    pub name: String,
    /// Their indices in `passes`.
    pub passes: Vec<usize>,
    pub count: u64,
    /// The count as an expression of W, H and the settings; null: none fits.
    pub count_expr: Option<String>,
    /// The first level's number `k` (names with `{k}`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub first: Option<u64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub first_expr: Option<String>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub depends_on: Vec<String>,
}

/// A loop of the frame: `count` steps of one pipeline from `first` on, one per level of a
/// pyramid or per batch ([`crate::export::port_kit::settings_probe`] fits `count_expr`).
#[derive(Clone, Debug, Serialize)]
pub struct Run {
    pub kind: String,
    pub pipeline: Option<String>,
    pub first: usize,
    pub count: u64,
    /// The count as an expression of W, H and the settings; null: none fits.
    pub count_expr: Option<String>,
    /// The settings the count changes with.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub depends_on: Vec<String>,
    /// Each iteration's workgroups (x, y, z) as expressions of `i` (0 for the first), `n` (the
    /// count), W, H and the settings, where one gives every iteration of every capture.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub iteration_expr: Vec<Option<String>>,
}

/// The runs of `steps`: every group of consecutive dispatches of one pipeline (of one or more:
/// `all`, to find a loop's count where it ran once; of two or more otherwise).
pub fn runs_of(steps: &[Step], all: bool) -> Vec<Run> {
    let mut out: Vec<Run> = Vec::new();
    for (i, s) in steps.iter().enumerate() {
        match out.last_mut() {
            Some(r) if r.kind == s.kind && r.pipeline == s.pipeline && r.first + r.count as usize == i => r.count += 1,
            _ => out.push(Run {
                kind: s.kind.clone(),
                pipeline: s.pipeline.clone(),
                first: i,
                count: 1,
                count_expr: None,
                depends_on: Vec::new(),
                iteration_expr: Vec::new(),
            }),
        }
    }
    // Copies and clears in a row are not a loop's, nor draws (one per mesh of the scene).
    out.retain(|r| r.kind.starts_with("dispatch") && r.pipeline.is_some() && (all || r.count > 1));
    out
}

/// A texture, buffer or sampler the frame touches.
#[derive(Clone, Debug, Serialize)]
pub struct Resource {
    pub name: String,
    /// `texture`, `buffer` or `sampler`.
    pub kind: &'static str,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub format: Option<String>,
    /// Texture: width, height, depth or layers; buffer: bytes.
    pub size: Vec<u64>,
    /// Each of `size` as an expression of the image's W and H, where one fits
    /// ([`crate::export::port_kit::expressions`]); null: as captured.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub size_expr: Vec<Option<String>>,
    /// The settings its size changes with ([`crate::export::port_kit::settings_probe`]).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub depends_on: Vec<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mips: Option<u32>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dimension: Option<String>,
    /// Usage flags by wgpu's names (`TEXTURE_BINDING`, `STORAGE_BINDING`, `UNIFORM`, …).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub usage: Option<Vec<String>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sampler: Option<serde_json::Value>,
    /// Buffers filled by atomic appends: the record size in bytes. The records' order
    /// depends on the GPU's scheduling, so a port's may differ; `gi-lab verify` compares
    /// the buffer as a set of records.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub unordered_records: Option<u64>,
    /// `input`: read, never written by the frame (uploaded by the host: the scene, the
    /// uniforms, lookup tables); `history`: read before the frame writes it, so it carries the
    /// last frame's contents (reset: zeroed, or see the pass); `frame`: written before it is
    /// read (transient).
    pub lifetime: &'static str,
    pub written_by: Vec<String>,
    pub read_by: Vec<String>,
}

/// A shader module of the kit: its file under `shaders/` and its declarations.
#[derive(Clone, Debug, Serialize)]
pub struct Shader {
    pub module: String,
    pub file: String,
    #[serde(flatten)]
    pub decl: ModuleDecl,
}

/// The manifest.
#[derive(Clone, Debug, Serialize)]
pub struct Manifest {
    pub schema: &'static str,
    pub schema_version: u32,
    pub preset: String,
    /// The kit's image: width and height.
    pub size: [u32; 2],
    /// Frames drawn from a fresh start (histories zero), each recorded in `golden` and listed
    /// in `frame_passes`; `passes` is the last.
    pub frames: u32,
    /// The engine export of the preset (`preset.json`): settings in use, provenance,
    /// resolved values.
    pub preset_file: &'static str,
    /// What the device must have: features beyond WebGPU's core and limits above its
    /// defaults.
    pub device: DeviceNeeds,
    /// The last frame's passes in order (what the README lists).
    pub passes: Vec<Pass>,
    /// Every frame's passes, frame 0 first: the first frame may run passes the later ones do
    /// not (a tone mapping of its own before an exposure exists), and resources used in turns
    /// (a history read in one frame and written in the next, `temporal.history.0` / `.1`) swap
    /// between frames. A port runs frame K's list as frame K, and then alternates the last two.
    pub frame_passes: Vec<Vec<Pass>>,
    pub resources: Vec<Resource>,
    /// Every pipeline the frames use, by the label the steps name: kind, stages, constants,
    /// and for render pipelines the colour targets (format, blend, write mask), depth state,
    /// primitive state and vertex buffer layouts.
    pub pipelines: Vec<crate::counters::capture::PipelineInfo>,
    pub shaders: Vec<Shader>,
    /// Every entry point the frame runs with its constants, translated by naga into SPIR-V,
    /// GLSL, HLSL and MSL (files under `shaders/<language>/`, or naga's error).
    pub translations: Vec<crate::export::port_kit::translate::Translation>,
    /// Per frame from the fresh start, the files of the goldens: the inputs the host uploads and
    /// each pass's outputs (`docs/port-kit.md`, "Goldens").
    pub golden: Vec<GoldenFrame>,
    /// How the sizes' expressions were fitted: the probe sizes, and how many values got an
    /// expression and how many were left as captured (docs/port-kit.md, "Sizes as
    /// expressions"); null when the kit was exported without them.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub expressions: Option<serde_json::Value>,
    /// Passes of `passes` repeated per round or per level, with how many as expressions
    /// ([`crate::export::port_kit::loops`]); only with the kit's expressions.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub repeated_passes: Vec<PassRepeat>,
    /// What the kit does not hold yet (docs/port-kit.md, "Not yet in the kit").
    pub not_yet: Vec<&'static str>,
}

/// The device features and limits the kit's frame needs (`crate::gpu`'s required features; the
/// G-buffer's colour attachment bytes).
#[derive(Clone, Debug, Serialize)]
pub struct DeviceNeeds {
    /// wgpu's names: required, and used when present (read-write storage textures of more
    /// formats).
    pub features: Vec<String>,
    pub optional_features: Vec<String>,
    /// Limits above WebGPU's defaults, by wgpu's field names.
    pub limits: BTreeMap<String, u64>,
}

impl DeviceNeeds {
    pub(super) fn of_gi_lab() -> Self {
        let names = |f: wgpu::Features| f.iter_names().map(|(n, _)| n.to_string()).collect();
        let mut limits = BTreeMap::new();
        limits
            .insert("max_color_attachment_bytes_per_sample".into(), crate::gpu::REQUIRED_COLOR_BYTES_PER_SAMPLE as u64);
        DeviceNeeds {
            features: names(crate::gpu::REQUIRED_FEATURES),
            optional_features: names(wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES),
            limits,
        }
    }
}

/// What the kit does not hold yet; said in the manifest, the kit's README and docs/port-kit.md.
pub const NOT_YET: &[&str] = &[
    "a loop's count and its iterations' workgroups are expressions (a pass's runs), but a resource of a level the preset does not have (hcb.level.7 at a larger hcb.levels) is not written, and a loop over the ISM atlas (the pull-push levels, halving an atlas whose size follows several settings) has no expression for its iterations",
    "passes repeated per level or round are listed once per repetition at the preset's settings, with how many as an expression (repeated_passes), but the steps of a repetition the preset does not run (a fifth Soler level) are not written",
    "a size or count that no expression of the families fits, or that two expressions fit which part between the captured settings, names its settings and keeps the image's expression or the captured value",
];

/// The role of a pass by its name (docs/port-kit.md, "Roles").
pub fn role_of(name: &str) -> &'static str {
    let first = name.split('.').next().unwrap_or(name);
    match first {
        "gbuffer" | "direct" | "sky" | "shadow" => "engine",
        "compose" | "tonemap" => "tail",
        "(between passes)" => "between",
        _ => "technique",
    }
}
