//! Stage 3 for the exact-VPL reference (issue #3): the light G-buffer of Knecht 002 §4.3
//! (`vpl.light_gbuffer.*`, this crate's G-buffer pass rendered from one light view) and VPLs
//! placed by stratified uniform sampling of its texels (`shaders/reference/sample.wgsl`: a
//! Halton point set over the view, randomly rotated by the seed).
//!
//! The reference renders many VPLs progressively: each frame is one *batch* of
//! [`ReferenceSettings::vpls_per_frame`] VPLs from one light view (the views of all lights
//! are taken in turn), each VPL's flux divided by its sampling density so that every batch
//! is an unbiased estimate of one-bounce light; `passes::reference::vpl_gather` averages the batches.
//! The light G-buffer's projection is jittered by a Halton (2, 3) sub-texel offset per
//! batch, so that VPL positions cover the surfaces continuously. The reference keeps this
//! uniform sampling; Knecht's importance-driven placement (hierarchical warping, §3.3 and
//! §4.4) is `passes::knecht::vpl_importance`.

use crate::counters::prelude::*;

use glam::{Mat4, Vec3, Vec4};

use crate::gpu::GpuContext;
use crate::gpu::bindings::{Bindings, Kind, binding};
use crate::passes::CameraUniform;
use crate::passes::gbuffer::GBufferPass;
use crate::passes::shadow::{GpuLight, LightView};
use crate::scene::SceneState;
use crate::scene::upload::GpuScene;
pub use crate::settings::reference::*;
use crate::timing::PassRec;

/// The uniform batch sampler's inputs (`reference/sample.wgsl`, group 0): its parameters, the
/// lights, the light G-buffer it samples, the VPL list it writes.
pub const SAMPLE_BINDINGS: Bindings = Bindings {
    label: "vpl.sample.inputs",
    shader: "reference/sample.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "params", Kind::Uniform),
        binding(1, "lights", Kind::Storage { read_only: true }),
        binding(2, "lg_position", Kind::Texture { filterable: false }),
        binding(3, "lg_normal", Kind::Texture { filterable: false }),
        binding(4, "lg_albedo", Kind::Texture { filterable: false }),
        binding(5, "lg_material", Kind::Texture { filterable: false }),
        binding(6, "vpls", Kind::Storage { read_only: false }),
    ],
};

/// One VPL; WGSL twin: `Vpl` in `shaders/common/vpl.wgsl` (size checked by a test).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuVpl {
    pub position: Vec4,
    pub normal: Vec4,
    pub flux: Vec4,
    pub incident: Vec4,
    pub albedo: Vec4,
}

/// Uniform of the sampling pass; WGSL twin: `Params` in `shaders/reference/sample.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SampleParams {
    pub eye: Vec4,
    pub forward: Vec4,
    pub scale: Vec4,
    pub seed: [u32; 4],
}

/// One batch's view: which light and which of its views.
#[derive(Clone, Copy, Debug)]
pub struct BatchView {
    pub light_index: u32,
    pub view: LightView,
}

pub struct VplSamplePass {
    pub light_gbuffer: GBufferPass,
    camera_buffer: wgpu::Buffer,
    camera_group: wgpu::BindGroup,
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    params: wgpu::Buffer,
    lights: wgpu::Buffer,
    light_capacity: usize,
    pub vpls: wgpu::Buffer,
    pub capacity: u32,
    size: u32,
}

impl VplSamplePass {
    pub fn new(ctx: &GpuContext, scene: &GpuScene, size: u32, capacity: u32) -> Self {
        let device = &ctx.device;
        let light_gbuffer = GBufferPass::light_view(ctx, scene, size, "vpl.light_gbuffer");
        let camera_buffer = device.counted_buffer(&wgpu::BufferDescriptor {
            label: Some("vpl.light_gbuffer.camera"),
            size: std::mem::size_of::<CameraUniform>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let camera_group = crate::passes::gbuffer::CAMERA_BINDINGS.group_labelled(
            device,
            "vpl.light_gbuffer.camera",
            &light_gbuffer.camera_layout,
            [camera_buffer.as_entire_binding()],
        );
        let module = crate::shaders::create_module(device, "reference/sample.wgsl");
        let layout = SAMPLE_BINDINGS.layout(device);
        let pipeline = crate::passes::compute_pipeline(device, "vpl.sample", &module, "cs_main", &[&layout]);
        let params = device.counted_buffer(&wgpu::BufferDescriptor {
            label: Some("vpl.sample.params"),
            size: std::mem::size_of::<SampleParams>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let (lights, light_capacity) = Self::light_buffer(device, 4);
        let vpls = Self::vpl_buffer(device, capacity);
        Self {
            light_gbuffer,
            camera_buffer,
            camera_group,
            pipeline,
            layout,
            params,
            lights,
            light_capacity,
            vpls,
            capacity,
            size,
        }
    }

    fn light_buffer(device: &wgpu::Device, capacity: usize) -> (wgpu::Buffer, usize) {
        let buffer = device.counted_buffer(&wgpu::BufferDescriptor {
            label: Some("vpl.sample.lights"),
            size: (std::mem::size_of::<GpuLight>() * capacity) as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        (buffer, capacity)
    }

    fn vpl_buffer(device: &wgpu::Device, capacity: u32) -> wgpu::Buffer {
        device.counted_buffer(&wgpu::BufferDescriptor {
            label: Some("vpl.list"),
            size: (std::mem::size_of::<GpuVpl>() as u64) * capacity.max(1) as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        })
    }

    /// Makes the light G-buffer `size`² and the VPL list hold `capacity` VPLs. Returns whether
    /// the light G-buffer was recreated (its registry entries must be refreshed).
    pub fn ensure(&mut self, ctx: &GpuContext, size: u32, capacity: u32) -> bool {
        if capacity > self.capacity {
            self.vpls = Self::vpl_buffer(&ctx.device, capacity);
            self.capacity = capacity;
        }
        if size != self.size {
            self.light_gbuffer.resize(ctx, size, size);
            self.size = size;
            return true;
        }
        false
    }

    /// Renders the light G-buffer of `view`, its projection shifted by `jitter` texels.
    pub fn render_view(
        &self,
        r: PassRec<'_, '_>,
        scene: &GpuScene,
        state: &SceneState,
        view: &LightView,
        jitter: (f32, f32),
    ) {
        let PassRec { ctx, enc: encoder, slot } = r;
        let size = self.size as f32;
        let v = view;
        let jitter_m = Mat4::from_translation(Vec3::new(2.0 * jitter.0 / size, -2.0 * jitter.1 / size, 0.0));
        let view_proj = jitter_m * v.proj * v.view;
        let cam = CameraUniform {
            view_proj,
            prev_view_proj: view_proj,
            inv_view_proj: view_proj.inverse(),
            view: v.view,
            position: v.eye.extend(1.0),
            viewport: Vec4::new(size, size, 1.0 / size, 1.0 / size),
            params: Vec4::ZERO,
            // The reference keeps the surfaces' own colour (no §4.3 blur).
            lod: Vec4::new(-1.0, 0.0, 0.0, 0.0),
        };
        ctx.queue.upload(&self.camera_buffer, 0, bytemuck::bytes_of(&cam));
        self.light_gbuffer.run(encoder, slot, &self.camera_group, scene, state);
    }

    /// Samples `count` VPLs uniformly from the light G-buffer of `batch.view`; their flux is
    /// multiplied by `flux_scale` (R² · V / N × intensity scale). `seed` is (the setting, the
    /// batch index, the batch index within this view): VPL i of the view's b-th batch is point
    /// b·N + i of the seed's rotated Halton set ([`crate::cpu::knecht::reference_uv`]).
    pub fn sample(
        &mut self,
        r: PassRec<'_, '_>,
        lights: &[GpuLight],
        batch: BatchView,
        count: u32,
        flux_scale: f32,
        seed: [u32; 3],
    ) {
        let PassRec { ctx, enc: encoder, slot } = r;
        let size = self.size as f32;
        let v = batch.view;
        if lights.len() > self.light_capacity {
            (self.lights, self.light_capacity) = Self::light_buffer(&ctx.device, lights.len().next_power_of_two());
        }
        ctx.queue.upload(&self.lights, 0, bytemuck::cast_slice(lights));
        let params = SampleParams {
            eye: v.eye.extend(if v.orthographic { 1.0 } else { 0.0 }),
            forward: v.forward.extend(v.pixel_extent / size),
            scale: Vec4::new(flux_scale, count as f32, 0.0, 0.0),
            seed: [seed[0], seed[1], batch.light_index, seed[2]],
        };
        ctx.queue.upload(&self.params, 0, bytemuck::bytes_of(&params));
        let t = &self.light_gbuffer.targets.views;
        let tv = wgpu::BindingResource::TextureView;
        let group = SAMPLE_BINDINGS.group(
            &ctx.device,
            &self.layout,
            [
                self.params.as_entire_binding(),
                self.lights.as_entire_binding(),
                tv(&t.position),
                tv(&t.normal),
                tv(&t.albedo),
                tv(&t.material),
                self.vpls.as_entire_binding(),
            ],
        );
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("vpl.sample"),
            timestamp_writes: slot.and_then(|s| s.compute(true, true)),
        });
        pass.set_pipe(&self.pipeline);
        pass.set_group(0, &group, &[]);
        pass.dispatch(count.div_ceil(64), 1, 1);
    }
}
