//! The frame as recorded (issue #54 point 1; docs/port-kit.md): while a capture is on, every
//! texture, buffer, view, sampler, shader module, pipeline and bind group this thread creates
//! is described, and every command the timing scopes record — pipeline, bind groups,
//! dispatches, draws, render targets, copies — is listed under its pass. The port kit's
//! manifest is written from it, so that it lists what the frame does, not what someone
//! remembered to describe.
//!
//! The hooks are the counted wrappers every object and command already goes through
//! (`crate::counters`'s module docs; [`super::traffic`]): a capture adds nothing to a frame
//! when it is off but one thread-local check per call.

use std::cell::RefCell;
use std::collections::HashMap;

use serde::Serialize;

use super::key;

/// A texture as created.
#[derive(Clone, Debug, Serialize)]
pub struct TextureInfo {
    pub label: String,
    pub format: String,
    #[serde(skip)]
    pub texture_format: Option<wgpu::TextureFormat>,
    /// Width, height, and depth or layers.
    pub size: [u32; 3],
    pub mips: u32,
    pub dimension: String,
    /// Usage flags by name (`TEXTURE_BINDING`, `STORAGE_BINDING`, …).
    pub usage: Vec<String>,
}

/// A buffer as created.
#[derive(Clone, Debug, Serialize)]
pub struct BufferInfo {
    pub label: String,
    pub size: u64,
    pub usage: Vec<String>,
}

/// A sampler as created.
#[derive(Clone, Debug, Serialize)]
pub struct SamplerInfo {
    pub label: String,
    pub address_mode: [String; 3],
    pub filter: [String; 3],
    pub compare: Option<String>,
}

/// What a binding or an attachment holds.
#[derive(Clone, Debug, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Bound {
    /// Levels and layers of a texture (a key of [`Capture::textures`]).
    View {
        texture: u64,
        base_mip: u32,
        mips: u32,
        base_layer: u32,
        layers: u32,
        dimension: String,
    },
    Buffer {
        buffer: u64,
        offset: u64,
        size: u64,
    },
    Sampler {
        sampler: u64,
    },
    /// An object made before the capture started, or of a kind it does not describe.
    Unknown,
}

/// One programmable stage of a pipeline.
#[derive(Clone, Debug, Serialize)]
pub struct Stage {
    /// `shaders/`-relative path of the module's entry file (its imports resolved).
    pub module: String,
    pub entry: String,
    /// The stage's pipeline-overridable constants by name.
    pub constants: Vec<(String, f64)>,
}

/// A pipeline as created.
#[derive(Clone, Debug, Serialize)]
pub struct PipelineInfo {
    pub label: String,
    /// `compute` or `render`.
    pub kind: &'static str,
    pub stages: Vec<Stage>,
    /// Pipeline-overridable constants by name.
    pub constants: Vec<(String, f64)>,
    /// Render pipelines: each colour target's format, blend state and write mask.
    pub targets: Vec<TargetState>,
    /// The depth format, comparison, whether it writes depth, and its bias.
    pub depth: Option<serde_json::Value>,
    /// Topology, cull mode, front face, polygon mode and whether depth is clamped.
    pub primitive: Option<serde_json::Value>,
    /// Vertex buffers: stride, step mode and attributes (location, format, offset).
    pub vertex_buffers: Vec<VertexLayout>,
}

/// A colour target of a render pipeline.
#[derive(Clone, Debug, Serialize)]
pub struct TargetState {
    pub format: String,
    /// `{"color": {src, dst, operation}, "alpha": {…}}` by wgpu's names, or none.
    pub blend: Option<serde_json::Value>,
    /// Channels written: bits 1 red, 2 green, 4 blue, 8 alpha.
    pub write_mask: u32,
}

/// A vertex buffer layout of a render pipeline.
#[derive(Clone, Debug, Serialize)]
pub struct VertexLayout {
    pub stride: u64,
    pub step_mode: String,
    pub attributes: Vec<(u32, String, u64)>,
}

/// A bind group as created: its label and entries (binding number, what it holds).
#[derive(Clone, Debug, Serialize)]
pub struct GroupInfo {
    pub label: String,
    pub entries: Vec<(u32, Bound)>,
    /// The bindings its layout gives a dynamic offset, in binding order (the order of the
    /// offsets `set_bind_group` takes).
    pub dynamic: Vec<u32>,
}

/// One recorded command.
#[derive(Clone, Debug, Serialize)]
#[serde(tag = "command", rename_all = "snake_case")]
pub enum Command {
    /// A compute pass or render pass begins; a render pass with its targets (load: the old
    /// contents kept; otherwise cleared to `clear`: a colour's RGBA, the depth in `[0]`).
    ComputePass,
    RenderPass {
        colors: Vec<Attachment>,
        depth: Option<Attachment>,
    },
    Pipeline {
        pipeline: u64,
    },
    Group {
        index: u32,
        group: u64,
        offsets: Vec<u32>,
    },
    Dispatch {
        workgroups: [u32; 3],
    },
    DispatchIndirect {
        buffer: u64,
        offset: u64,
    },
    Draw {
        vertices: [u32; 2],
        instances: [u32; 2],
    },
    DrawIndexed {
        indices: [u32; 2],
        base_vertex: i32,
        instances: [u32; 2],
    },
    DrawIndirect {
        buffer: u64,
        offset: u64,
        indexed: bool,
    },
    VertexBuffer {
        slot: u32,
        buffer: u64,
    },
    IndexBuffer {
        buffer: u64,
        format: String,
    },
    /// A texture copy: the level and texel origin of each side, and the extent.
    CopyTexture {
        src: u64,
        src_mip: u32,
        src_origin: [u32; 3],
        dst: u64,
        dst_mip: u32,
        dst_origin: [u32; 3],
        size: [u32; 3],
    },
    CopyBuffer {
        src: u64,
        src_offset: u64,
        dst: u64,
        dst_offset: u64,
        size: u64,
    },
    ClearBuffer {
        buffer: u64,
        offset: u64,
        size: u64,
    },
    /// Bytes the CPU wrote into a buffer (applied before the pass's commands run).
    Upload {
        buffer: u64,
        offset: u64,
        #[serde(skip)]
        data: Vec<u8>,
    },
}

/// A render target: what it holds, whether its contents are loaded, else the clear value.
#[derive(Clone, Debug, Serialize)]
pub struct Attachment {
    pub bound: Bound,
    pub load: bool,
    pub clear: [f64; 4],
}

/// One timing scope's commands.
#[derive(Clone, Debug, Serialize)]
pub struct PassCommands {
    pub name: String,
    pub commands: Vec<Command>,
    /// With goldens on ([`start_with_goldens`]): the contents of every texture and buffer the
    /// pass bound, targeted, copied or cleared, read back when it ended.
    #[serde(skip)]
    pub snapshots: Vec<Snapshot>,
}

/// The contents of a resource after a pass: a texture's every level and layer (level by
/// level, layers in order, rows packed without padding) or a buffer's bytes.
#[derive(Clone, Debug)]
pub struct Snapshot {
    /// [`Capture::textures`] or [`Capture::buffers`] key.
    pub key: u64,
    pub texture: bool,
    pub bytes: Vec<u8>,
}

/// What a capture holds: the objects by key, and the passes of the frames recorded since
/// the last [`take_passes`].
#[derive(Default, Debug)]
pub struct Capture {
    pub textures: HashMap<u64, TextureInfo>,
    pub buffers: HashMap<u64, BufferInfo>,
    pub samplers: HashMap<u64, SamplerInfo>,
    views: HashMap<u64, Bound>,
    modules: HashMap<u64, String>,
    pub pipelines: HashMap<u64, PipelineInfo>,
    pub groups: HashMap<u64, GroupInfo>,
    /// Bind group layouts: the bindings with a dynamic offset.
    layouts: HashMap<u64, Vec<u32>>,
    /// Buffers filled by atomic appends, with their record size ([`mark_unordered`]).
    pub unordered: HashMap<u64, u64>,
    pub passes: Vec<PassCommands>,
    /// The objects themselves, for the goldens' read-backs.
    texture_handles: HashMap<u64, wgpu::Texture>,
    buffer_handles: HashMap<u64, wgpu::Buffer>,
    goldens: bool,
}

thread_local! {
    static CAPTURE: RefCell<Option<Capture>> = const { RefCell::new(None) };
}

/// Starts describing this thread's objects and commands (before the renderer is made, so
/// that its objects are known).
pub fn start() {
    CAPTURE.with(|c| *c.borrow_mut() = Some(Capture::default()));
}

/// [`start`], reading back after every pass what it touched (the port kit's goldens). The
/// timing scopes then submit and wait for each pass (`timing::GpuTimer::scope`).
pub fn start_with_goldens() {
    CAPTURE.with(|c| *c.borrow_mut() = Some(Capture { goldens: true, ..Capture::default() }));
}

/// Whether goldens are being read back (each pass is submitted and waited for).
pub fn goldens_on() -> bool {
    CAPTURE.with(|c| c.borrow().as_ref().is_some_and(|c| c.goldens))
}

/// The usage a new texture or buffer gets: with goldens on, COPY_SRC is added so that it can
/// be read back (not to buffers the CPU maps, which cannot have it).
pub(crate) fn texture_usage(u: wgpu::TextureUsages) -> wgpu::TextureUsages {
    if goldens_on() { u | wgpu::TextureUsages::COPY_SRC } else { u }
}

pub(crate) fn buffer_usage(u: wgpu::BufferUsages) -> wgpu::BufferUsages {
    let mapped = u.intersects(wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::MAP_WRITE);
    if goldens_on() && !mapped { u | wgpu::BufferUsages::COPY_SRC } else { u }
}

/// Stops and returns what was captured.
pub fn stop() -> Option<Capture> {
    CAPTURE.with(|c| c.borrow_mut().take())
}

/// The passes recorded since the last call (a frame's, when called after each frame).
pub fn take_passes() -> Vec<PassCommands> {
    CAPTURE.with(|c| c.borrow_mut().as_mut().map(|c| std::mem::take(&mut c.passes)).unwrap_or_default())
}

fn with(f: impl FnOnce(&mut Capture)) {
    CAPTURE.with(|c| {
        if let Some(c) = c.borrow_mut().as_mut() {
            f(c)
        }
    });
}

fn debug<T: std::fmt::Debug>(t: &T) -> String {
    format!("{t:?}")
}

/// Flags by name.
macro_rules! flag_names {
    ($f:expr) => {
        $f.iter_names().map(|(n, _)| n.to_string()).collect()
    };
}

fn blend_component(c: &wgpu::BlendComponent) -> serde_json::Value {
    serde_json::json!({"src": debug(&c.src_factor), "dst": debug(&c.dst_factor), "operation": debug(&c.operation)})
}

pub(crate) fn remember_texture(t: &wgpu::Texture, d: &wgpu::TextureDescriptor) {
    with(|c| {
        let info = TextureInfo {
            label: d.label.unwrap_or("(unlabelled texture)").to_string(),
            format: debug(&d.format),
            texture_format: Some(d.format),
            size: [d.size.width, d.size.height, d.size.depth_or_array_layers],
            mips: d.mip_level_count,
            dimension: debug(&d.dimension),
            usage: flag_names!(d.usage),
        };
        c.textures.insert(key(t), info);
        if c.goldens {
            c.texture_handles.insert(key(t), t.clone());
        }
    });
}

pub(crate) fn remember_buffer(b: &wgpu::Buffer, label: Option<&str>, usage: wgpu::BufferUsages) {
    with(|c| {
        let info = BufferInfo {
            label: label.unwrap_or("(unlabelled buffer)").to_string(),
            size: b.size(),
            usage: flag_names!(usage),
        };
        c.buffers.insert(key(b), info);
        if c.goldens && b.usage().contains(wgpu::BufferUsages::COPY_SRC) {
            c.buffer_handles.insert(key(b), b.clone());
        }
    });
}

pub(crate) fn remember_sampler(s: &wgpu::Sampler, d: &wgpu::SamplerDescriptor) {
    with(|c| {
        let info = SamplerInfo {
            label: d.label.unwrap_or("(unlabelled sampler)").to_string(),
            address_mode: [debug(&d.address_mode_u), debug(&d.address_mode_v), debug(&d.address_mode_w)],
            filter: [debug(&d.mag_filter), debug(&d.min_filter), debug(&d.mipmap_filter)],
            compare: d.compare.as_ref().map(debug),
        };
        c.samplers.insert(key(s), info);
    });
}

pub(crate) fn remember_view(v: &wgpu::TextureView, t: &wgpu::Texture, d: &wgpu::TextureViewDescriptor) {
    with(|c| {
        let mips = t.mip_level_count();
        let all_layers = if t.dimension() == wgpu::TextureDimension::D3 { 1 } else { t.depth_or_array_layers() };
        let bound = Bound::View {
            texture: key(t),
            base_mip: d.base_mip_level,
            mips: d.mip_level_count.unwrap_or(mips.saturating_sub(d.base_mip_level)),
            base_layer: d.base_array_layer,
            layers: d.array_layer_count.unwrap_or(all_layers.saturating_sub(d.base_array_layer)),
            dimension: d.dimension.map(|x| debug(&x)).unwrap_or_else(|| {
                // The default view: the texture's own dimension, 2D textures with several
                // layers (and no layer count given) as arrays.
                match t.dimension() {
                    wgpu::TextureDimension::D1 => "D1".into(),
                    wgpu::TextureDimension::D3 => "D3".into(),
                    wgpu::TextureDimension::D2 => {
                        let layers = d.array_layer_count.unwrap_or(all_layers.saturating_sub(d.base_array_layer));
                        if layers > 1 || t.depth_or_array_layers() > 1 && d.array_layer_count.is_none() {
                            "D2Array".into()
                        } else {
                            "D2".into()
                        }
                    }
                }
            }),
        };
        c.views.insert(key(v), bound);
    });
}

pub(crate) fn remember_module(m: &wgpu::ShaderModule, path: &str) {
    with(|c| {
        c.modules.insert(key(m), path.to_string());
    });
}

fn module_path(c: &Capture, m: &wgpu::ShaderModule) -> String {
    c.modules.get(&key(m)).cloned().unwrap_or_else(|| "(unknown module)".into())
}

pub(crate) fn remember_compute(p: &wgpu::ComputePipeline, d: &wgpu::ComputePipelineDescriptor) {
    with(|c| {
        let info = PipelineInfo {
            label: d.label.unwrap_or("(unlabelled pipeline)").to_string(),
            kind: "compute",
            stages: vec![Stage {
                module: module_path(c, d.module),
                entry: d.entry_point.unwrap_or("main").into(),
                constants: constants_of(&d.compilation_options),
            }],
            constants: constants_of(&d.compilation_options),
            targets: Vec::new(),
            depth: None,
            primitive: None,
            vertex_buffers: Vec::new(),
        };
        c.pipelines.insert(compute_key(p), info);
    });
}

fn constants_of(o: &wgpu::PipelineCompilationOptions) -> Vec<(String, f64)> {
    o.constants.iter().map(|(k, v)| (k.to_string(), *v)).collect()
}

/// Keys of pipelines: compute and render pipelines share [`Capture::pipelines`], and their
/// ids come from separate spaces, so each kind hashes with its own tag.
pub(crate) fn compute_key(p: &wgpu::ComputePipeline) -> u64 {
    key(&(1u8, p))
}

pub(crate) fn render_key(p: &wgpu::RenderPipeline) -> u64 {
    key(&(2u8, p))
}

pub(crate) fn remember_render(p: &wgpu::RenderPipeline, d: &wgpu::RenderPipelineDescriptor) {
    with(|c| {
        let mut stages = vec![Stage {
            module: module_path(c, d.vertex.module),
            entry: d.vertex.entry_point.unwrap_or("vs_main").into(),
            constants: constants_of(&d.vertex.compilation_options),
        }];
        let mut targets = Vec::new();
        if let Some(f) = &d.fragment {
            stages.push(Stage {
                module: module_path(c, f.module),
                entry: f.entry_point.unwrap_or("fs_main").into(),
                constants: constants_of(&f.compilation_options),
            });
            targets = f
                .targets
                .iter()
                .flatten()
                .map(|t| TargetState {
                    format: debug(&t.format),
                    blend: t.blend.as_ref().map(
                        |b| serde_json::json!({"color": blend_component(&b.color), "alpha": blend_component(&b.alpha)}),
                    ),
                    write_mask: t.write_mask.bits(),
                })
                .collect();
        }
        let info = PipelineInfo {
            label: d.label.unwrap_or("(unlabelled pipeline)").to_string(),
            kind: "render",
            constants: {
                // Every stage's constants (the translations bake them into each entry point).
                let mut all: Vec<(String, f64)> = Vec::new();
                for (k, v) in stages.iter().flat_map(|s| s.constants.iter()) {
                    if !all.iter().any(|(n, _)| n == k) {
                        all.push((k.clone(), *v));
                    }
                }
                all
            },
            stages,
            targets,
            depth: d.depth_stencil.as_ref().map(|s| {
                serde_json::json!({
                    "format": debug(&s.format),
                    "compare": s.depth_compare.map(|c| debug(&c)),
                    "write": s.depth_write_enabled.unwrap_or(false),
                    "bias": {"constant": s.bias.constant, "slope_scale": s.bias.slope_scale, "clamp": s.bias.clamp},
                })
            }),
            primitive: Some(serde_json::json!({
                "topology": debug(&d.primitive.topology),
                "strip_index_format": d.primitive.strip_index_format.map(|f| debug(&f)),
                "cull_mode": d.primitive.cull_mode.map(|c| debug(&c)),
                "front_face": debug(&d.primitive.front_face),
                "polygon_mode": debug(&d.primitive.polygon_mode),
                "unclipped_depth": d.primitive.unclipped_depth,
            })),
            vertex_buffers: d
                .vertex
                .buffers
                .iter()
                .flatten()
                .map(|b| VertexLayout {
                    stride: b.array_stride,
                    step_mode: debug(&b.step_mode),
                    attributes: b.attributes.iter().map(|a| (a.shader_location, debug(&a.format), a.offset)).collect(),
                })
                .collect(),
        };
        c.pipelines.insert(render_key(p), info);
    });
}

fn bound_of(c: &Capture, r: &wgpu::BindingResource) -> Bound {
    match r {
        wgpu::BindingResource::Buffer(b) => buffer_bound(b),
        wgpu::BindingResource::TextureView(v) => c.views.get(&key(*v)).cloned().unwrap_or(Bound::Unknown),
        wgpu::BindingResource::Sampler(s) => Bound::Sampler { sampler: key(*s) },
        _ => Bound::Unknown,
    }
}

fn buffer_bound(b: &wgpu::BufferBinding) -> Bound {
    let size = b.size.map_or(b.buffer.size().saturating_sub(b.offset), |s| s.get());
    Bound::Buffer { buffer: key(b.buffer), offset: b.offset, size }
}

/// Marks `b` as a list filled by atomic appends (records of `stride` bytes, whose order
/// depends on the GPU's scheduling): the port kit says so, and `gi-lab verify` compares it
/// as a set of records (docs/port-kit.md, "Verifying a port").
pub fn mark_unordered(b: &wgpu::Buffer, stride: u64) {
    with(|c| {
        c.unordered.insert(key(b), stride);
    });
}

/// A bind group layout: which of its bindings take a dynamic offset.
pub(crate) fn remember_layout(l: &wgpu::BindGroupLayout, entries: &[wgpu::BindGroupLayoutEntry]) {
    with(|c| {
        let mut dynamic: Vec<u32> = entries
            .iter()
            .filter(|e| matches!(e.ty, wgpu::BindingType::Buffer { has_dynamic_offset: true, .. }))
            .map(|e| e.binding)
            .collect();
        dynamic.sort_unstable();
        c.layouts.insert(key(l), dynamic);
    });
}

pub(crate) fn remember_group(g: &wgpu::BindGroup, d: &wgpu::BindGroupDescriptor) {
    with(|c| {
        let entries = d.entries.iter().map(|e| (e.binding, bound_of(c, &e.resource))).collect();
        let dynamic = c.layouts.get(&key(d.layout)).cloned().unwrap_or_default();
        let info = GroupInfo { label: d.label.unwrap_or("(unlabelled group)").to_string(), entries, dynamic };
        c.groups.insert(key(g), info);
    });
}

/// Opens the pass `name` (timing scopes).
pub(crate) fn begin_scope(name: &str) {
    with(|c| c.passes.push(PassCommands { name: name.into(), commands: Vec::new(), snapshots: Vec::new() }));
}

/// Closes the open pass: commands until the next scope go to "(between passes)".
pub(crate) fn end_scope() {
    with(|c| {
        c.passes.push(PassCommands { name: "(between passes)".into(), commands: Vec::new(), snapshots: Vec::new() })
    });
}

/// Records `command` in the open pass.
pub(crate) fn record(command: impl FnOnce(&Capture) -> Command) {
    with(|c| {
        let cmd = command(c);
        if c.passes.is_empty() {
            c.passes.push(PassCommands {
                name: "(between passes)".into(),
                commands: Vec::new(),
                snapshots: Vec::new(),
            });
        }
        if let Some(p) = c.passes.last_mut() {
            p.commands.push(cmd);
        }
    });
}

/// A render pass's targets.
pub(crate) fn render_pass(desc: &wgpu::RenderPassDescriptor) {
    record(|c| {
        let view = |v: &wgpu::TextureView| c.views.get(&key(v)).cloned().unwrap_or(Bound::Unknown);
        Command::RenderPass {
            colors: desc
                .color_attachments
                .iter()
                .flatten()
                .map(|a| {
                    let (load, clear) = match a.ops.load {
                        wgpu::LoadOp::Clear(c) => (false, [c.r, c.g, c.b, c.a]),
                        _ => (true, [0.0; 4]),
                    };
                    Attachment { bound: view(a.view), load, clear }
                })
                .collect(),
            depth: desc.depth_stencil_attachment.as_ref().map(|d| {
                let (load, clear) = match d.depth_ops.as_ref().map(|o| o.load) {
                    Some(wgpu::LoadOp::Clear(z)) => (false, [z as f64, 0.0, 0.0, 0.0]),
                    _ => (true, [0.0; 4]),
                };
                Attachment { bound: view(d.view), load, clear }
            }),
        }
    });
}

/// The key of a buffer, for commands that name one.
pub(crate) fn buffer_key(b: &wgpu::Buffer) -> u64 {
    key(b)
}

/// The key of a texture.
pub(crate) fn texture_key(t: &wgpu::Texture) -> u64 {
    key(t)
}

/// The key of a pipeline or bind group.
pub(crate) fn object_key<T: std::hash::Hash>(t: &T) -> u64 {
    key(t)
}

/// A texture or buffer the open pass touched, to read back (its key, and the object).
pub(crate) struct Target {
    pub key: u64,
    pub texture: Option<wgpu::Texture>,
    pub buffer: Option<wgpu::Buffer>,
}

/// With goldens on: every texture and buffer the open pass bound, targeted, copied or cleared
/// (`readback::read_back_open_pass` reads them after the pass has run).
pub(crate) fn open_pass_targets() -> Vec<Target> {
    CAPTURE.with(|c| {
        let c = c.borrow();
        let Some(c) = c.as_ref().filter(|c| c.goldens) else { return Vec::new() };
        let Some(pass) = c.passes.last() else { return Vec::new() };
        let mut keys: Vec<(bool, u64)> = Vec::new();
        fn add(keys: &mut Vec<(bool, u64)>, b: &Bound) {
            match b {
                Bound::View { texture, .. } => keys.push((true, *texture)),
                Bound::Buffer { buffer, .. } => keys.push((false, *buffer)),
                _ => {}
            }
        }
        for cmd in &pass.commands {
            match cmd {
                Command::Group { group, .. } => {
                    for (_, b) in c.groups.get(group).map(|g| g.entries.as_slice()).unwrap_or(&[]) {
                        add(&mut keys, b);
                    }
                }
                Command::RenderPass { colors, depth } => {
                    for a in colors.iter().chain(depth.as_ref()) {
                        add(&mut keys, &a.bound);
                    }
                }
                Command::CopyTexture { src, dst, .. } => keys.extend([(true, *src), (true, *dst)]),
                Command::CopyBuffer { src, dst, .. } => keys.extend([(false, *src), (false, *dst)]),
                Command::ClearBuffer { buffer, .. } => keys.push((false, *buffer)),
                Command::DispatchIndirect { buffer, .. }
                | Command::DrawIndirect { buffer, .. }
                | Command::VertexBuffer { buffer, .. }
                | Command::IndexBuffer { buffer, .. } => keys.push((false, *buffer)),
                _ => {}
            }
        }
        keys.sort_unstable();
        keys.dedup();
        keys.into_iter()
            .filter_map(|(texture, k)| {
                if texture {
                    c.texture_handles.get(&k).map(|t| Target { key: k, texture: Some(t.clone()), buffer: None })
                } else {
                    c.buffer_handles.get(&k).map(|b| Target { key: k, texture: None, buffer: Some(b.clone()) })
                }
            })
            .collect()
    })
}

/// Hands the open pass its read-backs.
pub(crate) fn set_open_pass_snapshots(snapshots: Vec<Snapshot>) {
    with(|c| {
        if let Some(p) = c.passes.last_mut() {
            p.snapshots = snapshots;
        }
    });
}
