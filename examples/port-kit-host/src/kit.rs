//! The parts of a kit's `manifest.json` (schema `gi-lab-port-kit` 2, docs/port-kit.md) that
//! a host needs, read with serde. Every field is what the kit writes; nothing is assumed.

use std::collections::BTreeMap;

use serde::Deserialize;

#[derive(Debug, Deserialize)]
pub struct Manifest {
    pub preset: String,
    pub frames: u32,
    pub device: DeviceNeeds,
    pub frame_passes: Vec<Vec<Pass>>,
    pub resources: Vec<Resource>,
    pub pipelines: Vec<Pipeline>,
    pub shaders: Vec<Shader>,
    pub golden: Vec<GoldenFrame>,
}

#[derive(Debug, Deserialize)]
pub struct DeviceNeeds {
    pub features: Vec<String>,
    #[serde(default)]
    pub optional_features: Vec<String>,
    #[serde(default)]
    pub limits: BTreeMap<String, u64>,
}

#[derive(Debug, Deserialize)]
pub struct Pass {
    pub index: usize,
    pub name: String,
    pub steps: Vec<Step>,
}

#[derive(Debug, Deserialize)]
pub struct Step {
    pub kind: String,
    pub pipeline: Option<String>,
    #[serde(default)]
    pub bindings: Vec<Binding>,
    pub workgroups: Option<[u32; 3]>,
    pub draw: Option<Draw>,
    pub indirect: Option<(String, u64)>,
    pub render_pass: Option<u32>,
    #[serde(default)]
    pub targets: Vec<Target>,
    pub depth_target: Option<Target>,
    #[serde(default)]
    pub vertex_buffers: Vec<(u32, String)>,
    pub index_buffer: Option<(String, String)>,
    pub copy: Option<Copy>,
    pub clear: Option<(String, u64, u64)>,
    pub upload: Option<Upload>,
}

/// Bytes the CPU writes into a buffer before the pass's commands.
#[derive(Debug, Deserialize)]
pub struct Upload {
    pub buffer: String,
    pub offset: u64,
    pub file: String,
}

#[derive(Debug, Deserialize)]
pub struct Draw {
    pub vertices: Option<[u32; 2]>,
    pub indices: Option<[u32; 2]>,
    #[serde(default)]
    pub base_vertex: i32,
    pub instances: [u32; 2],
}

#[derive(Debug, Deserialize)]
pub struct Copy {
    pub src: String,
    pub dst: String,
    /// Texture copies.
    pub texels: Option<[u32; 3]>,
    #[serde(default)]
    pub src_mip: u32,
    #[serde(default)]
    pub dst_mip: u32,
    #[serde(default)]
    pub src_origin: [u32; 3],
    #[serde(default)]
    pub dst_origin: [u32; 3],
    /// Buffer copies.
    pub bytes: Option<u64>,
    #[serde(default)]
    pub src_offset: u64,
    #[serde(default)]
    pub dst_offset: u64,
}

#[derive(Clone, Debug, Deserialize, PartialEq)]
pub struct ViewRange {
    pub base_mip: u32,
    pub mips: u32,
    pub base_layer: u32,
    pub layers: u32,
    pub dimension: String,
}

#[derive(Debug, Deserialize)]
pub struct Binding {
    pub group: u32,
    pub binding: u32,
    pub name: String,
    pub kind: String,
    pub access: String,
    pub resource: String,
    pub view: Option<ViewRange>,
    pub offset: Option<u64>,
    pub size: Option<u64>,
}

#[derive(Debug, Deserialize, PartialEq)]
pub struct Target {
    pub resource: String,
    pub view: Option<ViewRange>,
    pub load: bool,
    #[serde(default)]
    pub clear: [f64; 4],
}

#[derive(Debug, Deserialize)]
pub struct Resource {
    pub name: String,
    pub kind: String,
    pub format: Option<String>,
    pub size: Vec<u64>,
    pub mips: Option<u32>,
    pub dimension: Option<String>,
    #[serde(default)]
    pub usage: Vec<String>,
    pub sampler: Option<SamplerDesc>,
}

#[derive(Debug, Deserialize)]
pub struct SamplerDesc {
    pub address_mode: [String; 3],
    pub filter: [String; 3],
    pub compare: Option<String>,
}

#[derive(Debug, Deserialize)]
pub struct Pipeline {
    pub label: String,
    pub kind: String,
    pub stages: Vec<Stage>,
    #[serde(default)]
    pub targets: Vec<TargetState>,
    pub depth: Option<DepthState>,
    pub primitive: Option<Primitive>,
    #[serde(default)]
    pub vertex_buffers: Vec<VertexLayout>,
}

#[derive(Debug, Deserialize)]
pub struct Stage {
    pub module: String,
    pub entry: String,
    /// The stage's pipeline-overridable constants.
    #[serde(default)]
    pub constants: Vec<(String, f64)>,
}

#[derive(Debug, Deserialize)]
pub struct TargetState {
    pub format: String,
    pub blend: Option<Blend>,
    pub write_mask: u32,
}

#[derive(Debug, Deserialize)]
pub struct Blend {
    pub color: BlendComponent,
    pub alpha: BlendComponent,
}

#[derive(Debug, Deserialize)]
pub struct BlendComponent {
    pub src: String,
    pub dst: String,
    pub operation: String,
}

#[derive(Debug, Deserialize)]
pub struct DepthState {
    pub format: String,
    pub compare: Option<String>,
    pub write: bool,
    pub bias: DepthBias,
}

#[derive(Debug, Deserialize)]
pub struct DepthBias {
    pub constant: i32,
    pub slope_scale: f32,
    pub clamp: f32,
}

#[derive(Debug, Deserialize)]
pub struct Primitive {
    pub topology: String,
    pub strip_index_format: Option<String>,
    pub cull_mode: Option<String>,
    pub front_face: String,
    pub polygon_mode: String,
    pub unclipped_depth: bool,
}

#[derive(Debug, Deserialize)]
pub struct VertexLayout {
    pub stride: u64,
    pub step_mode: String,
    pub attributes: Vec<(u32, String, u64)>,
}

#[derive(Debug, Deserialize)]
pub struct Shader {
    pub module: String,
    pub file: String,
    pub bindings: Vec<ShaderBinding>,
}

#[derive(Debug, Deserialize)]
pub struct ShaderBinding {
    pub group: u32,
    pub binding: u32,
    pub dimension: Option<String>,
    pub sample: Option<String>,
}

#[derive(Debug, Deserialize)]
pub struct GoldenFrame {
    pub inputs: Vec<GoldenFile>,
    pub passes: Vec<GoldenPass>,
}

#[derive(Debug, Deserialize)]
pub struct GoldenPass {
    pub index: usize,
    pub outputs: Vec<GoldenFile>,
}

#[derive(Debug, Deserialize)]
pub struct GoldenFile {
    pub resource: String,
    pub path: String,
    pub file: String,
    pub bytes: u64,
}
