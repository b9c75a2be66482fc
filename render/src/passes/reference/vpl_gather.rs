//! Stage 6 for the exact-VPL reference: every pixel gathers the batch's VPLs with exact
//! visibility and the full BRDF at both ends (`shaders/reference/gather.wgsl`, the VPL shading of
//! Knecht 002 Eq. 4.7–4.9 without its approximations), writes the batch to `indirect.raw`
//! and averages the batches into `indirect.accum` (batch k has weight 1/(k+1)), which the
//! compose pass adds to the direct light.

use crate::counters::prelude::*;

use glam::Vec4;

use crate::buffers::{BufferKind, BufferRegistry};
use crate::gpu::GpuContext;
use crate::gpu::bindings::{Bindings, Kind, binding};
use crate::passes::gbuffer::GBufferViews;
use crate::timing::PassRec;

/// Bind group `indirect.gather.inputs` of `shaders/reference/gather.wgsl` (group 0).
pub const INDIRECT_GATHER_INPUTS_BINDINGS: Bindings = Bindings {
    label: "indirect.gather.inputs",
    shader: "reference/gather.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "camera", Kind::Uniform),
        binding(1, "params", Kind::Uniform),
        binding(2, "vpls", Kind::Storage { read_only: true }),
        binding(3, "atlas", Kind::Texture { filterable: false }),
        binding(4, "g_position", Kind::Texture { filterable: false }),
        binding(5, "g_normal", Kind::Texture { filterable: false }),
        binding(6, "g_albedo", Kind::Texture { filterable: false }),
        binding(7, "g_material", Kind::Texture { filterable: false }),
        binding(8, "accum_prev", Kind::Texture { filterable: false }),
        binding(9, "out_raw", Kind::StorageTexture(wgpu::TextureFormat::Rgba32Float)),
        binding(10, "out_accum", Kind::StorageTexture(wgpu::TextureFormat::Rgba32Float)),
    ],
};

pub const INDIRECT_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

/// Uniform of the gather; WGSL twin: `Params` in `shaders/reference/gather.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GatherParams {
    /// x: VPL count, y: atlas columns, z: face size, w: weight of this batch 1/(k+1).
    pub batch: Vec4,
    /// x: near, y: far, z: eye offset along the VPL normal, w: d_min.
    pub clip: Vec4,
    /// x: depth bias (texels), y: normal offset (texels), z: visibility on, w: receiver BRDF
    /// diffuse only (1) or full (0).
    pub bias: Vec4,
    /// x: the near field's cut² (senders closer are skipped; 0: none), y–w: 0.
    pub near: Vec4,
}

pub struct VplGatherPass {
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    params: wgpu::Buffer,
    pub raw: wgpu::Texture,
    pub accum: wgpu::Texture,
    /// Last frame's `accum` (the pass reads it and writes `accum`).
    accum_prev: wgpu::Texture,
    width: u32,
    height: u32,
}

impl VplGatherPass {
    pub fn new(ctx: &GpuContext, width: u32, height: u32) -> Self {
        let device = &ctx.device;
        let module = crate::shaders::create_module(device, "reference/gather.wgsl");
        let layout = INDIRECT_GATHER_INPUTS_BINDINGS.layout(device);
        let pipeline = crate::passes::compute_pipeline(device, "indirect.gather", &module, "cs_main", &[&layout]);
        let params = device.counted_buffer(&wgpu::BufferDescriptor {
            label: Some("indirect.gather.params"),
            size: std::mem::size_of::<GatherParams>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let (raw, accum, accum_prev) = Self::targets(device, width, height);
        Self { pipeline, layout, params, raw, accum, accum_prev, width, height }
    }

    fn targets(device: &wgpu::Device, width: u32, height: u32) -> (wgpu::Texture, wgpu::Texture, wgpu::Texture) {
        let storage = wgpu::TextureUsages::STORAGE_BINDING;
        let raw = crate::passes::create_target(device, "indirect.raw", width, height, INDIRECT_FORMAT, storage);
        let accum = crate::passes::create_target(device, "indirect.accum", width, height, INDIRECT_FORMAT, storage);
        let prev = crate::passes::create_target(
            device,
            "indirect.accum_prev",
            width,
            height,
            INDIRECT_FORMAT,
            wgpu::TextureUsages::COPY_DST,
        );
        (raw, accum, prev)
    }

    /// Recreates the targets for a new size (the accumulation restarts).
    pub fn resize(&mut self, ctx: &GpuContext, width: u32, height: u32) {
        if (width, height) != (self.width, self.height) {
            (self.raw, self.accum, self.accum_prev) = Self::targets(&ctx.device, width, height);
            self.width = width;
            self.height = height;
        }
    }

    pub fn register(&self, reg: &mut BufferRegistry) {
        reg.register(
            "indirect.raw",
            BufferKind::Hdr,
            "indirect radiance of this frame's VPL batch alone (exact-VPL reference)",
            &self.raw,
        );
        reg.register(
            "indirect.accum",
            BufferKind::Hdr,
            "indirect radiance averaged over the batches so far (exact-VPL reference)",
            &self.accum,
        );
    }

    /// The gather's uniform as the last `run` wrote it (`GatherParams`).
    pub fn params(&self) -> &wgpu::Buffer {
        &self.params
    }

    /// Gathers one batch and folds it into the average with weight `params.batch.w`.
    pub fn run(
        &self,
        r: PassRec<'_, '_>,
        camera: &wgpu::Buffer,
        gbuffer: &GBufferViews,
        vpl_list: &wgpu::Buffer,
        atlas: &wgpu::TextureView,
        params: GatherParams,
    ) {
        let PassRec { ctx, enc: encoder, slot } = r;
        ctx.queue.upload(&self.params, 0, bytemuck::bytes_of(&params));
        let raw = crate::passes::view(&self.raw, "indirect.raw");
        let accum = crate::passes::view(&self.accum, "indirect.accum");
        let prev = crate::passes::view(&self.accum_prev, "indirect.accum_prev");
        let tv = wgpu::BindingResource::TextureView;
        let group = INDIRECT_GATHER_INPUTS_BINDINGS.group(
            &ctx.device,
            &self.layout,
            [
                camera.as_entire_binding(),
                self.params.as_entire_binding(),
                vpl_list.as_entire_binding(),
                tv(atlas),
                tv(&gbuffer.position),
                tv(&gbuffer.normal),
                tv(&gbuffer.albedo),
                tv(&gbuffer.material),
                tv(&prev),
                tv(&raw),
                tv(&accum),
            ],
        );
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("indirect.gather"),
                timestamp_writes: slot.and_then(|s| s.compute(true, true)),
            });
            pass.set_pipe(&self.pipeline);
            pass.set_group(0, &group, &[]);
            pass.dispatch(self.width.div_ceil(crate::passes::TILE), self.height.div_ceil(crate::passes::TILE), 1);
        }
        encoder.counted_copy_texture(
            self.accum.as_image_copy(),
            self.accum_prev.as_image_copy(),
            wgpu::Extent3d { width: self.width, height: self.height, depth_or_array_layers: 1 },
        );
    }
}
