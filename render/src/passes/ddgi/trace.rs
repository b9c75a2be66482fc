//! DDGI's probe rays (Majercik et al. 2019 §3.1; 2021 §5): `shaders/ddgi/trace.wgsl` casts each
//! probe's rays of the frame through the GPU ray caster (`passes::rays`, group 1) and lights
//! the hits as the GPU truth does (`rays/shade.wgsl`, group 0's bindings 0–4), plus the
//! previous frame's probes for infinite bounces. Each ray's record is `vec4(radiance,
//! ±distance)`, the layout `blend` reads.

use crate::counters::prelude::*;

use crate::gpu::GpuContext;
use crate::gpu::bindings::{Bindings, Kind, binding};

const READ: Kind = Kind::Storage { read_only: true };

/// The trace's group 0: the lights (0–4, `rays::shade::ShadeLights`) and the probes.
pub const TRACE_BINDINGS: Bindings = Bindings {
    label: "ddgi.trace.inputs",
    shader: "ddgi/trace.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "pt_shade", READ),
        binding(1, "pt_lights", READ),
        binding(2, "pt_emitters", READ),
        binding(3, "pt_sky_texels", READ),
        binding(4, "pt_sky_tables", READ),
        binding(5, "ddgi", READ),
        binding(6, "ddgi_grid", READ),
        binding(7, "ddgi_probes", READ),
        binding(8, "ddgi_irradiance", READ),
        binding(9, "ddgi_distance", READ),
        binding(10, "ddgi_rays", Kind::Storage { read_only: false }),
    ],
};

/// The trace kernel (its group 1 is the ray caster's scene, `RayScene::layout`).
pub struct DdgiTracePass {
    pub layout: wgpu::BindGroupLayout,
    pipeline: wgpu::ComputePipeline,
}

impl DdgiTracePass {
    pub fn new(ctx: &GpuContext, scene_layout: &wgpu::BindGroupLayout) -> Self {
        let layout = TRACE_BINDINGS.layout(&ctx.device);
        let module = crate::shaders::create_module(&ctx.device, "ddgi/trace.wgsl");
        let pipeline =
            crate::passes::compute_pipeline(&ctx.device, "ddgi.trace", &module, "cs_trace", &[&layout, scene_layout]);
        Self { layout, pipeline }
    }

    /// Records the trace of `rays` rays (every probe's).
    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        timestamps: Option<wgpu::ComputePassTimestampWrites<'_>>,
        (group, scene): (&wgpu::BindGroup, &wgpu::BindGroup),
        rays: u32,
    ) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("ddgi.trace"),
            timestamp_writes: timestamps,
        });
        pass.set_pipe(&self.pipeline);
        pass.set_group(0, group, &[]);
        pass.set_group(1, scene, &[]);
        pass.dispatch(rays.div_ceil(64), 1, 1);
    }
}
