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
    pub usage: String,
}

/// A buffer as created.
#[derive(Clone, Debug, Serialize)]
pub struct BufferInfo {
    pub label: String,
    pub size: u64,
    pub usage: String,
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
    /// The depth format, comparison and whether it writes depth.
    pub depth: Option<String>,
    /// Topology, cull mode and front face.
    pub primitive: Option<String>,
    /// Vertex buffers: stride, step mode and attributes (location, format, offset).
    pub vertex_buffers: Vec<VertexLayout>,
}

/// A colour target of a render pipeline.
#[derive(Clone, Debug, Serialize)]
pub struct TargetState {
    pub format: String,
    pub blend: Option<String>,
    pub write_mask: String,
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
}

/// One recorded command.
#[derive(Clone, Debug, Serialize)]
#[serde(tag = "command", rename_all = "snake_case")]
pub enum Command {
    /// A compute pass or render pass begins; a render pass with its targets (load: the old
    /// contents kept).
    ComputePass,
    RenderPass {
        colors: Vec<(Bound, bool)>,
        depth: Option<(Bound, bool)>,
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
    CopyTexture {
        src: u64,
        dst: u64,
        size: [u32; 3],
    },
    CopyBuffer {
        src: u64,
        dst: u64,
        size: u64,
    },
    ClearBuffer {
        buffer: u64,
        offset: u64,
        size: u64,
    },
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

pub(crate) fn remember_texture(t: &wgpu::Texture, d: &wgpu::TextureDescriptor) {
    with(|c| {
        let info = TextureInfo {
            label: d.label.unwrap_or("(unlabelled texture)").to_string(),
            format: debug(&d.format),
            texture_format: Some(d.format),
            size: [d.size.width, d.size.height, d.size.depth_or_array_layers],
            mips: d.mip_level_count,
            dimension: debug(&d.dimension),
            usage: debug(&d.usage),
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
            usage: debug(&usage),
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
            dimension: d.dimension.map(|x| debug(&x)).unwrap_or_else(|| "D2".into()),
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
            stages: vec![Stage { module: module_path(c, d.module), entry: d.entry_point.unwrap_or("main").into() }],
            constants: d.compilation_options.constants.iter().map(|(k, v)| (k.to_string(), *v)).collect(),
            targets: Vec::new(),
            depth: None,
            primitive: None,
            vertex_buffers: Vec::new(),
        };
        c.pipelines.insert(compute_key(p), info);
    });
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
        }];
        let mut targets = Vec::new();
        if let Some(f) = &d.fragment {
            stages.push(Stage { module: module_path(c, f.module), entry: f.entry_point.unwrap_or("fs_main").into() });
            targets = f
                .targets
                .iter()
                .flatten()
                .map(|t| TargetState {
                    format: debug(&t.format),
                    blend: t.blend.as_ref().map(debug),
                    write_mask: debug(&t.write_mask),
                })
                .collect();
        }
        let info = PipelineInfo {
            label: d.label.unwrap_or("(unlabelled pipeline)").to_string(),
            kind: "render",
            stages,
            constants: d.vertex.compilation_options.constants.iter().map(|(k, v)| (k.to_string(), *v)).collect(),
            targets,
            depth: d.depth_stencil.as_ref().map(|s| {
                format!(
                    "{:?}, compare {:?}, write {:?}, bias {:?}",
                    s.format, s.depth_compare, s.depth_write_enabled, s.bias
                )
            }),
            primitive: Some(format!(
                "{:?}, cull {:?}, front {:?}",
                d.primitive.topology, d.primitive.cull_mode, d.primitive.front_face
            )),
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

pub(crate) fn remember_group(g: &wgpu::BindGroup, d: &wgpu::BindGroupDescriptor) {
    with(|c| {
        let entries = d.entries.iter().map(|e| (e.binding, bound_of(c, &e.resource))).collect();
        let info = GroupInfo { label: d.label.unwrap_or("(unlabelled group)").to_string(), entries };
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
                .map(|a| (view(a.view), matches!(a.ops.load, wgpu::LoadOp::Load)))
                .collect(),
            depth: desc
                .depth_stencil_attachment
                .as_ref()
                .map(|d| (view(d.view), d.depth_ops.as_ref().is_some_and(|o| matches!(o.load, wgpu::LoadOp::Load)))),
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
                    for (b, _) in colors.iter().chain(depth.as_ref()) {
                        add(&mut keys, b);
                    }
                }
                Command::CopyTexture { src, dst, .. } => keys.extend([(true, *src), (true, *dst)]),
                Command::CopyBuffer { src, dst, .. } => keys.extend([(false, *src), (false, *dst)]),
                Command::ClearBuffer { buffer, .. } => keys.push((false, *buffer)),
                Command::DispatchIndirect { buffer, .. } | Command::DrawIndirect { buffer, .. } => {
                    keys.push((false, *buffer))
                }
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
