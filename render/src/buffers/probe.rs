//! The pixel probe's depth reads: single texels of depth textures, which WebGPU cannot copy
//! partially, gathered into a buffer by a small compute pass (`shaders/view/probe.wgsl`).

use crate::counters::prelude::*;

use glam::UVec4;

use crate::gpu::GpuContext;
use crate::gpu::bindings::{Bindings, Kind, binding};

/// Bind group `probe.inputs` of `shaders/view/probe.wgsl` (group 0).
pub const PROBE_INPUTS_BINDINGS: Bindings = Bindings {
    label: "probe.inputs",
    shader: "view/probe.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "jobs", Kind::Uniform),
        binding(1, "depth_2d", Kind::Depth),
        binding(2, "depth_array", Kind::DepthArray),
        binding(3, "values", Kind::Storage { read_only: false }),
    ],
};

/// Most texels one probe dispatch reads (`texels` in `shaders/view/probe.wgsl`).
pub const PROBE_MAX_POINTS: usize = 64;

/// Uniform of the depth probe; WGSL twin: `Jobs` in `shaders/view/probe.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ProbeJobs {
    pub header: UVec4,
    pub texels: [UVec4; PROBE_MAX_POINTS],
}

/// Reads single texels of depth textures (which WebGPU cannot copy partially) into a
/// buffer, for the pixel probe.
pub struct DepthProbe {
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    dummy_2d: wgpu::TextureView,
    dummy_array: wgpu::TextureView,
}

impl DepthProbe {
    pub fn new(ctx: &GpuContext) -> Self {
        let device = &ctx.device;
        let layout = PROBE_INPUTS_BINDINGS.layout(device);
        let module = crate::shaders::create_module(device, "view/probe.wgsl");
        let pipeline = crate::gpu::compute_pipeline(device, "probe.depth", &module, "probe_depth", &[&layout]);
        let dummy = |label: &str, layers: u32, dimension| {
            device
                .counted_texture(&wgpu::TextureDescriptor {
                    label: Some(label),
                    size: wgpu::Extent3d { width: 1, height: 1, depth_or_array_layers: layers },
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format: wgpu::TextureFormat::Depth32Float,
                    usage: wgpu::TextureUsages::TEXTURE_BINDING,
                    view_formats: &[],
                })
                .counted_view(&wgpu::TextureViewDescriptor {
                    label: Some(label),
                    dimension: Some(dimension),
                    ..Default::default()
                })
        };
        Self {
            pipeline,
            layout,
            dummy_2d: dummy("probe.dummy_2d", 1, wgpu::TextureViewDimension::D2),
            dummy_array: dummy("probe.dummy_array", 2, wgpu::TextureViewDimension::D2Array),
        }
    }

    /// Records reads of `texels` (layer 0) of the depth texture `t` into `values`, starting at
    /// float index `first`. At most [`PROBE_MAX_POINTS`] texels.
    pub fn record(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        t: &wgpu::Texture,
        texels: &[(u32, u32)],
        values: &wgpu::Buffer,
        first: u32,
    ) {
        let n = texels.len().min(PROBE_MAX_POINTS);
        let array = t.depth_or_array_layers() > 1;
        let mut jobs =
            ProbeJobs { header: UVec4::new(n as u32, first, 0, array as u32), texels: [UVec4::ZERO; PROBE_MAX_POINTS] };
        for (j, &(x, y)) in jobs.texels.iter_mut().zip(texels) {
            *j = UVec4::new(x, y, 0, 0);
        }
        let uniform = wgpu::util::DeviceExt::create_buffer_init(
            &ctx.device,
            &wgpu::util::BufferInitDescriptor {
                label: Some("probe.jobs"),
                contents: bytemuck::bytes_of(&jobs),
                usage: wgpu::BufferUsages::UNIFORM,
            },
        );
        let dimension = if array { wgpu::TextureViewDimension::D2Array } else { wgpu::TextureViewDimension::D2 };
        let view = t.counted_view(&wgpu::TextureViewDescriptor {
            label: Some("probe.source"),
            dimension: Some(dimension),
            aspect: wgpu::TextureAspect::DepthOnly,
            ..Default::default()
        });
        let (v2, va) = if array { (&self.dummy_2d, &view) } else { (&view, &self.dummy_array) };
        let group = PROBE_INPUTS_BINDINGS.group(
            &ctx.device,
            &self.layout,
            [
                uniform.as_entire_binding(),
                wgpu::BindingResource::TextureView(v2),
                wgpu::BindingResource::TextureView(va),
                values.as_entire_binding(),
            ],
        );
        let mut pass = encoder
            .begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("probe.depth"), timestamp_writes: None });
        pass.set_pipe(&self.pipeline);
        pass.set_group(0, &group, &[]);
        pass.dispatch(1, 1, 1);
    }
}
