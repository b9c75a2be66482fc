//! Stage 1's world positions rebuilt from the camera G-buffer's linear depth (issue #53,
//! docs/architecture.md "The camera G-buffer's position"). Shader: `shaders/gbuffer/position.wgsl`.
//!
//! The camera's G-buffer writes the linear depth of Knecht 002 §4.2 (Eq. 4.2, unnormalised)
//! as its target 0, 4 bytes a pixel, where it wrote the world position and the depth in 16.
//! The passes that moved to it (the direct light, Knecht's gather, filter and merge) rebuild
//! the point themselves; the others, and every viewer, probe and read-back of
//! `gbuffer.position`, read this pass's texture, which is filled in the frame when one of
//! the frame's steps needs it, and otherwise only when it is read ([`Derived`]): a frame
//! that no one looks at the position of never writes it. The same kind of pass ([`Fill`])
//! unpacks `gbuffer.normal` from the G-buffer's packed normals (`shaders/gbuffer/normal.wgsl`)
//! and fills `gbuffer.emission` of a scene that the G-buffer draws without its emission target
//! (`shaders/gbuffer/no_emission.wgsl`).

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use glam::{Mat4, Vec3, Vec4};

use crate::buffers::Derived;
use crate::counters::prelude::*;
use crate::gpu::GpuContext;
use crate::gpu::bindings::{Bindings, Kind, binding};

/// `gbuffer.position`'s format (and the light views' and the hemispheres' target 0): world
/// position in xyz, linear depth in w.
pub const POSITION_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

pub const POSITION_BINDINGS: Bindings = Bindings {
    label: "gbuffer.position.inputs",
    shader: "gbuffer/position.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "camera", Kind::Uniform),
        binding(1, "linear_depth", Kind::Texture { filterable: false }),
        binding(2, "out_position", Kind::StorageTexture(POSITION_FORMAT)),
    ],
};

/// A compute pass that fills a derived buffer of the camera G-buffer (issue #53): made once
/// with its bind group, recorded in the frame when the frame's steps or read-backs need the
/// buffer, otherwise run when the buffer is read ([`Derived`]); `stale` says whether the
/// buffer lags what it is made from.
pub struct Fill {
    ctx: GpuContext,
    /// The pass's name: its timing scope and its objects' labels.
    name: &'static str,
    pipeline: wgpu::ComputePipeline,
    group: wgpu::BindGroup,
    size: (u32, u32),
    stale: AtomicBool,
}

impl Fill {
    /// The pass `name` running `entry` of `bindings`' shader over `size` pixels.
    fn new<'a>(
        ctx: &GpuContext,
        (name, bindings, entry): (&'static str, &Bindings, &str),
        resources: impl IntoIterator<Item = wgpu::BindingResource<'a>>,
        size: (u32, u32),
    ) -> Self {
        let device = &ctx.device;
        let layout = bindings.layout(device);
        let module = crate::shaders::create_module(device, bindings.shader);
        let pipeline = crate::passes::compute_pipeline(device, name, &module, entry, &[&layout]);
        let group = bindings.group(device, &layout, resources);
        Self { ctx: ctx.clone(), name, pipeline, group, size, stale: AtomicBool::new(false) }
    }

    /// Records the pass.
    pub fn record(
        &self,
        enc: &mut wgpu::CommandEncoder,
        timestamp_writes: Option<wgpu::ComputePassTimestampWrites<'_>>,
    ) {
        crate::passes::dispatch_2d(enc, self.name, &self.pipeline, &self.group, &[], timestamp_writes, self.size);
    }

    /// Takes the stale flag: whether the buffer needed filling (it is now the caller's to
    /// fill or to mark stale again with [`Self::set_stale`]). The frame takes it before it
    /// writes anything the pass reads, so that no read in the middle of the frame fills the
    /// buffer from half-written sources.
    pub fn take_stale(&self) -> bool {
        self.stale.swap(false, Ordering::SeqCst)
    }

    /// The pass's name (its timing scope).
    pub fn name(&self) -> &'static str {
        self.name
    }

    pub fn set_stale(&self, stale: bool) {
        self.stale.store(stale, Ordering::SeqCst);
    }
}

impl Derived for Fill {
    fn refresh(&self) {
        if !self.take_stale() {
            return;
        }
        self.ctx.make_current();
        let label = format!("{}.on_read", self.name);
        let mut enc = self.ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(&label) });
        crate::counters::traffic::begin_scope(self.name);
        self.record(&mut enc, None);
        crate::counters::traffic::end_scope();
        self.ctx.submit([enc.finish()]);
    }
}

/// The pass that fills `gbuffer.position` from `gbuffer.linear_depth`.
pub struct PositionPass {
    pub fill: Fill,
    /// The camera of the frame the linear depth was drawn for (copied from the frame's
    /// camera uniform when the G-buffer runs): a later read rebuilds the positions with it
    /// even after the next frame has written its own camera.
    camera: wgpu::Buffer,
}

impl PositionPass {
    /// The pass from the camera G-buffer's `linear_depth` into `position` (`size` pixels).
    pub fn new(
        ctx: &GpuContext,
        linear_depth: &wgpu::TextureView,
        position: &wgpu::TextureView,
        size: (u32, u32),
    ) -> Arc<Self> {
        let bytes = std::mem::size_of::<crate::passes::CameraUniform>() as u64;
        let camera = crate::passes::uniform_buffer(&ctx.device, "gbuffer.position.camera", bytes);
        let tv = wgpu::BindingResource::TextureView;
        let resources = [camera.as_entire_binding(), tv(linear_depth), tv(position)];
        let fill = Fill::new(ctx, ("gbuffer.position", &POSITION_BINDINGS, "cs_position"), resources, size);
        Arc::new(Self { fill, camera })
    }

    /// Keeps the camera the G-buffer was just drawn with (`camera`: the frame's uniform);
    /// the fill reads it.
    pub fn keep_camera(&self, enc: &mut wgpu::CommandEncoder, camera: &wgpu::Buffer) {
        enc.counted_copy_buffer(camera, 0, &self.camera, 0, self.camera.size());
    }
}

impl Derived for PositionPass {
    fn refresh(&self) {
        self.fill.refresh();
    }
}

pub const NO_EMISSION_BINDINGS: Bindings = Bindings {
    label: "gbuffer.no_emission.inputs",
    shader: "gbuffer/no_emission.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "linear_depth", Kind::Texture { filterable: false }),
        binding(1, "out_emission", Kind::StorageTexture(wgpu::TextureFormat::Rgba16Float)),
    ],
};

/// Fills `gbuffer.emission` when it is read while the G-buffer leaves it out (no material
/// emits nor has an occlusion texture, issue #53): rgb 0 and a 1 where geometry covers the
/// pixel (`shaders/gbuffer/no_emission.wgsl`), what the raster would have written.
pub fn no_emission_pass(
    ctx: &GpuContext,
    linear_depth: &wgpu::TextureView,
    emission: &wgpu::TextureView,
    size: (u32, u32),
) -> Arc<Fill> {
    let tv = wgpu::BindingResource::TextureView;
    let what = ("gbuffer.no_emission", &NO_EMISSION_BINDINGS, "cs_no_emission");
    Arc::new(Fill::new(ctx, what, [tv(linear_depth), tv(emission)], size))
}

pub const NORMAL_BINDINGS: Bindings = Bindings {
    label: "gbuffer.normal.inputs",
    shader: "gbuffer/normal.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "packed", Kind::UintTexture),
        binding(1, "out_normal", Kind::StorageTexture(wgpu::TextureFormat::Rgba16Float)),
    ],
};

/// Fills the camera's `gbuffer.normal` (unit normal in half floats, `gbuffer::NORMAL_FORMAT`, w =
/// 1 where geometry covers the pixel) from the G-buffer's packed normals (`gbuffer::PACKED_NORMAL_FORMAT`,
/// issue #53, `shaders/gbuffer/normal.wgsl`): in the frame when a step reads it, otherwise
/// when it is read. The passes that read the packed word shade with these same values.
pub fn normal_pass(
    ctx: &GpuContext,
    packed: &wgpu::TextureView,
    normal: &wgpu::TextureView,
    size: (u32, u32),
) -> Arc<Fill> {
    let tv = wgpu::BindingResource::TextureView;
    Arc::new(Fill::new(ctx, ("gbuffer.normal", &NORMAL_BINDINGS, "cs_normal"), [tv(packed), tv(normal)], size))
}

pub const MATERIAL_BINDINGS: Bindings = Bindings {
    label: "gbuffer.material.inputs",
    shader: "gbuffer/material.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "shading", Kind::Texture { filterable: false }),
        binding(1, "albedo", Kind::Texture { filterable: false }),
        binding(2, "out_material", Kind::StorageTexture(wgpu::TextureFormat::Rgba16Float)),
    ],
};

/// Fills the camera's `gbuffer.material` (SI, SP, metallic, roughness) from the G-buffer's SI
/// and SP (`passes::gbuffer::SHADING_FORMAT`) and the albedo's DI when it is read (issue #53,
/// `shaders/gbuffer/material.wgsl`).
pub fn material_pass(
    ctx: &GpuContext,
    (shading, albedo): (&wgpu::TextureView, &wgpu::TextureView),
    material: &wgpu::TextureView,
    size: (u32, u32),
) -> Arc<Fill> {
    let tv = wgpu::BindingResource::TextureView;
    let what = ("gbuffer.material", &MATERIAL_BINDINGS, "cs_material");
    Arc::new(Fill::new(ctx, what, [tv(shading), tv(albedo), tv(material)], size))
}

/// CPU twin of `world_from_linear_depth` (shaders/common/camera.wgsl): the world point of
/// pixel `p`'s centre at linear view depth `depth`, for a camera with `view_proj` and `view`
/// at `eye` and a `size`-pixel image.
pub fn world_from_linear_depth(
    view_proj: Mat4,
    view: Mat4,
    eye: Vec3,
    size: (u32, u32),
    p: (u32, u32),
    depth: f32,
) -> Vec3 {
    let uv = (glam::Vec2::new(p.0 as f32, p.1 as f32) + 0.5) / glam::Vec2::new(size.0 as f32, size.1 as f32);
    let far = view_proj.inverse() * Vec4::new(uv.x * 2.0 - 1.0, 1.0 - uv.y * 2.0, 1.0, 1.0);
    let dir = far.truncate() / far.w - eye;
    let forward = -Vec3::new(view.x_axis.z, view.y_axis.z, view.z_axis.z);
    eye + dir * (depth / dir.dot(forward))
}
