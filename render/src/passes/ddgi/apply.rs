//! DDGI at every pixel (Majercik et al. 2019 §3.4, Eq. 5–6; 2021 §4.2): `shaders/ddgi/apply.wgsl`
//! reads the probes at each G-buffer point (CPU twin `cpu::ddgi::sample`) into `ddgi.irradiance`
//! (E) and `ddgi.indirect` (c·DI/π·E, plus SI·E(r)/π with the glossy receiver: what the
//! compose adds); `shaders/ddgi/view.wgsl` copies
//! the atlases, the rays and the probes into textures for the buffer viewer.

use crate::counters::prelude::*;

use crate::gpu::GpuContext;
use crate::gpu::bindings::{Bindings, Kind, binding};

const READ: Kind = Kind::Storage { read_only: true };
const TEX: Kind = Kind::Texture { filterable: false };
const OUT: Kind = Kind::StorageTexture(wgpu::TextureFormat::Rgba32Float);

/// The per-pixel kernel's group 0.
pub const APPLY_BINDINGS: Bindings = Bindings {
    label: "ddgi.apply.inputs",
    shader: "ddgi/apply.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "ddgi_grid", READ),
        binding(1, "ddgi_probes", READ),
        binding(2, "ddgi_irradiance", READ),
        binding(3, "ddgi_distance", READ),
        binding(4, "g_position", TEX),
        binding(5, "g_normal", TEX),
        binding(6, "g_albedo", TEX),
        binding(7, "camera", Kind::Uniform),
        binding(8, "out_indirect", OUT),
        binding(9, "out_irradiance", OUT),
        binding(10, "g_material", TEX),
    ],
};

/// The viewer's copy's group 0.
pub const VIEW_BINDINGS: Bindings = Bindings {
    label: "ddgi.view.inputs",
    shader: "ddgi/view.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "ddgi", READ),
        binding(1, "ddgi_rays", READ),
        binding(2, "ddgi_irradiance", READ),
        binding(3, "ddgi_distance", READ),
        binding(4, "ddgi_probes", READ),
        binding(5, "view_irradiance", OUT),
        binding(6, "view_distance", OUT),
        binding(7, "view_rays", OUT),
        binding(8, "view_probes", OUT),
    ],
};

/// The per-pixel kernel and the viewer's copy.
pub struct DdgiApplyPass {
    pub layout: wgpu::BindGroupLayout,
    pub view_layout: wgpu::BindGroupLayout,
    apply: wgpu::ComputePipeline,
    view: wgpu::ComputePipeline,
}

impl DdgiApplyPass {
    pub fn new(ctx: &GpuContext) -> Self {
        let device = &ctx.device;
        let layout = APPLY_BINDINGS.layout(device);
        let view_layout = VIEW_BINDINGS.layout(device);
        let module = crate::shaders::create_module(device, "ddgi/apply.wgsl");
        let view_module = crate::shaders::create_module(device, "ddgi/view.wgsl");
        Self {
            apply: crate::passes::compute_pipeline(device, "ddgi.apply", &module, "cs_apply", &[&layout]),
            view: crate::passes::compute_pipeline(device, "ddgi.view", &view_module, "cs_view", &[&view_layout]),
            layout,
            view_layout,
        }
    }

    /// Records the per-pixel reading over `size` pixels.
    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        timestamps: Option<wgpu::ComputePassTimestampWrites<'_>>,
        group: &wgpu::BindGroup,
        (width, height): (u32, u32),
    ) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("ddgi.apply"),
            timestamp_writes: timestamps,
        });
        pass.set_pipe(&self.apply);
        pass.set_group(0, group, &[]);
        pass.dispatch(width.div_ceil(8), height.div_ceil(8), 1);
    }

    /// Records the viewer's copy over the largest of its textures (`size`).
    pub fn record_view(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        group: &wgpu::BindGroup,
        (width, height): (u32, u32),
    ) {
        let mut pass = encoder
            .begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("ddgi.view"), timestamp_writes: None });
        pass.set_pipe(&self.view);
        pass.set_group(0, group, &[]);
        pass.dispatch(width.div_ceil(8), height.div_ceil(8), 1);
    }
}
