//! DDGI's probe update, its blend (Majercik et al. 2019 §3.3, Eq. 3–4; 2021 §5.2–5.3):
//! `shaders/ddgi/blend.wgsl` blends each probe's rays of the frame into its octahedral tiles
//! of irradiance and distance moments with the hysteresis, copies the tiles' borders, then
//! classifies and relocates each probe from the same rays. CPU twins:
//! `cpu::ddgi::{update_irradiance, update_distance, classify, relocate}`, `Atlas::fill_borders`.

use crate::counters::prelude::*;

use glam::{Mat3, Vec4};

use crate::gpu::GpuContext;
use crate::gpu::bindings::{Bindings, Kind, binding};

const READ: Kind = Kind::Storage { read_only: true };
const WRITE: Kind = Kind::Storage { read_only: false };

/// The blend's inputs (`ddgi/blend.wgsl`, group 0).
pub const BLEND_BINDINGS: Bindings = Bindings {
    label: "ddgi.blend.inputs",
    shader: "ddgi/blend.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "ddgi", READ),
        binding(1, "ddgi_rays", READ),
        binding(2, "ddgi_irradiance", WRITE),
        binding(3, "ddgi_distance", WRITE),
        binding(4, "ddgi_grid", READ),
        binding(5, "ddgi_probes", WRITE),
    ],
};

/// WGSL twin: `DdgiUpdate` in `shaders/ddgi/probes.wgsl` (the rotation's columns padded to
/// vec4, as WGSL lays out a mat3x3 in a storage buffer).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct DdgiUpdateParams {
    pub rotation: [Vec4; 3],
    /// Probes, rays per probe, irradiance and distance interior texels.
    pub counts: [u32; 4],
    /// Tiles per atlas row (irradiance, distance), whether the old values count, the frame's
    /// seed (the trace's shading samples).
    pub layout: [u32; 4],
    /// Hysteresis α, distance sharpness, max distance.
    pub blend: Vec4,
}

impl DdgiUpdateParams {
    /// The parameters of one update: the frame's ray rotation, the probe and ray counts, the
    /// two atlases' layouts, whether the old values count, the hysteresis α, the distance
    /// sharpness and the max distance (2019 §3.3).
    pub fn new(
        rotation: Mat3,
        (probes, rays): (u32, u32),
        (irradiance, distance): (&crate::cpu::ddgi::Atlas, &crate::cpu::ddgi::Atlas),
        keep_old: bool,
        hysteresis: f32,
        sharpness: f32,
        max_distance: f32,
    ) -> Self {
        Self {
            rotation: [rotation.x_axis.extend(0.0), rotation.y_axis.extend(0.0), rotation.z_axis.extend(0.0)],
            counts: [probes, rays, irradiance.interior, distance.interior],
            layout: [irradiance.columns, distance.columns, keep_old as u32, 0],
            blend: Vec4::new(hysteresis, sharpness, max_distance, 0.0),
        }
    }
}

/// The four kernels of the update after the trace.
pub struct DdgiBlendPass {
    pub layout: wgpu::BindGroupLayout,
    irradiance: wgpu::ComputePipeline,
    distance: wgpu::ComputePipeline,
    borders: wgpu::ComputePipeline,
    state: wgpu::ComputePipeline,
}

impl DdgiBlendPass {
    pub fn new(ctx: &GpuContext) -> Self {
        let device = &ctx.device;
        let layout = BLEND_BINDINGS.layout(device);
        let module = crate::shaders::create_module(device, "ddgi/blend.wgsl");
        let make =
            |label: &str, entry: &str| crate::passes::compute_pipeline(device, label, &module, entry, &[&layout]);
        Self {
            irradiance: make("ddgi.blend.irradiance", "cs_irradiance"),
            distance: make("ddgi.blend.distance", "cs_distance"),
            borders: make("ddgi.blend.borders", "cs_borders"),
            state: make("ddgi.blend.probe_state", "cs_probe_state"),
            layout,
        }
    }

    /// Records the blend: the interiors, then the borders, of both atlases of sizes
    /// `irradiance` and `distance` (texels), then the state of each of `probes` probes.
    pub fn record(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        timestamps: Option<wgpu::ComputePassTimestampWrites<'_>>,
        group: &wgpu::BindGroup,
        (irradiance, distance): ((u32, u32), (u32, u32)),
        probes: u32,
    ) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("ddgi.blend"),
            timestamp_writes: timestamps,
        });
        pass.set_group(0, group, &[]);
        let both = (irradiance.0.max(distance.0), irradiance.1.max(distance.1));
        for (pipeline, (w, h)) in [(&self.irradiance, irradiance), (&self.distance, distance), (&self.borders, both)] {
            pass.set_pipe(pipeline);
            pass.dispatch(w.div_ceil(8), h.div_ceil(8), 1);
        }
        pass.set_pipe(&self.state);
        pass.dispatch(probes.div_ceil(64), 1, 1);
    }
}
