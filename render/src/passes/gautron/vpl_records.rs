//! GI Lab's mix of Gautron et al. 003 and Knecht 002 (issue #17 "Mixes"): the round's
//! irradiance records lit by the VPLs of stages 3–4 (instant radiosity at the records)
//! instead of their rasterized hemispheres (`pipeline.shading_points = IrradianceRecords`
//! with `pipeline.gather = Vpl`). The creation, the clamps, the splatting and the cache are
//! Gautron's; only the record's E, H and gradients come from the VPL sums of
//! `shaders/gautron/vpl_records.wgsl` (CPU twin `cpu::gautron::vpl_record`, where the
//! ⚠[gautron.vpl-record-h] reading of H is documented).

use crate::counters::prelude::*;

use glam::Vec4;

use crate::gpu::GpuContext;
use crate::gpu::bindings::{Bindings, Kind, binding};
use crate::passes::stages::{Visibility, VplSet};
use crate::timing::PassRec;

/// Bind group `gautron.vpl_records` of `shaders/gautron/vpl_records.wgsl` (group 0).
pub const VPL_RECORDS_BINDINGS: Bindings = Bindings {
    label: "gautron.vpl_records",
    shader: "gautron/vpl_records.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "params", Kind::Uniform),
        binding(1, "vparams", Kind::Uniform),
        binding(2, "state", Kind::Storage { read_only: true }),
        binding(3, "cameras", Kind::Storage { read_only: true }),
        binding(4, "records", Kind::Storage { read_only: false }),
        binding(5, "vpls", Kind::Storage { read_only: true }),
        binding(6, "ism_atlas", Kind::Texture { filterable: false }),
        binding(7, "exact_atlas", Kind::Texture { filterable: false }),
    ],
};

/// Uniform of the VPL-lit records; WGSL twin: `VplRecordParams` in
/// `shaders/gautron/vpl_records.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct VplRecordParams {
    /// VPL count, visibility (0 none, 1 ISM, 2 exact), atlas columns, map size.
    pub counts: [u32; 4],
    /// d_min², then the visibility's parameters as `interleave::GatherParams::shade`.
    pub shade: Vec4,
    /// The near field's cut², ε of the translational differences (scene units), ε of the
    /// rotational ones (radians), 0.
    pub misc: Vec4,
}

/// The step of the translational differences, relative to the scene's radius.
pub const EPS_T: f32 = 1e-3;
/// The step of the rotational differences (radians).
pub const EPS_R: f32 = 1e-2;

pub struct VplRecordPass {
    layout: wgpu::BindGroupLayout,
    /// A workgroup per slot (`cs_vpl_records`) and an invocation per slot
    /// (`cs_vpl_records_serial`).
    wide_pipeline: wgpu::ComputePipeline,
    serial_pipeline: wgpu::ComputePipeline,
    /// Whether a workgroup lights each slot: on a GPU, not on a CPU renderer (whose workgroup
    /// barriers are dear); tests set it to check both on one device.
    pub wide: bool,
    params: wgpu::Buffer,
    no_ism: wgpu::TextureView,
    no_exact: wgpu::TextureView,
}

impl VplRecordPass {
    pub fn new(ctx: &GpuContext) -> Self {
        let device = &ctx.device;
        let layout = VPL_RECORDS_BINDINGS.layout(device);
        let module = crate::shaders::create_module(device, "gautron/vpl_records.wgsl");
        let wide_pipeline =
            crate::passes::compute_pipeline(device, "gautron.vpl_records", &module, "cs_vpl_records", &[&layout]);
        let serial_pipeline = crate::passes::compute_pipeline(
            device,
            "gautron.vpl_records.serial",
            &module,
            "cs_vpl_records_serial",
            &[&layout],
        );
        let wide = ctx.adapter_info.device_type != wgpu::DeviceType::Cpu;
        let params = crate::passes::uniform_buffer(
            device,
            "gautron.vpl_records.params",
            std::mem::size_of::<VplRecordParams>() as u64,
        );
        let (no_ism, no_exact) =
            crate::passes::reference::vpl_visibility::no_visibility_atlases(device, "gautron.vpl_records");
        Self { layout, wide_pipeline, serial_pipeline, wide, params, no_ism, no_exact }
    }

    /// Lights the records of the round's slots (`cameras` says which) with `light`.
    pub fn run(
        &self,
        r: PassRec<'_, '_>,
        (gautron_params, state, cameras, records): (&wgpu::Buffer, &wgpu::Buffer, &wgpu::Buffer, &wgpu::Buffer),
        (vpls, vis): (&VplSet, &Visibility),
        radius: f32,
        slots: u32,
    ) {
        let PassRec { ctx, enc, slot } = r;
        let (code, ism, exact, cols, size, shade) = vis.parts(&self.no_ism, &self.no_exact);
        let d_min = vpls.min_distance;
        let p = VplRecordParams {
            counts: [vpls.count, code, cols, size],
            shade: Vec4::new(d_min * d_min, shade.y, shade.z, shade.w),
            misc: Vec4::new(vpls.near_cut * vpls.near_cut, EPS_T * radius.max(1e-6), EPS_R, 0.0),
        };
        ctx.queue.upload(&self.params, 0, bytemuck::bytes_of(&p));
        let tv = wgpu::BindingResource::TextureView;
        let group = VPL_RECORDS_BINDINGS.group(
            &ctx.device,
            &self.layout,
            [
                gautron_params.as_entire_binding(),
                self.params.as_entire_binding(),
                state.as_entire_binding(),
                cameras.as_entire_binding(),
                records.as_entire_binding(),
                vpls.list.as_entire_binding(),
                tv(ism),
                tv(exact),
            ],
        );
        let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("gautron.vpl_records"),
            timestamp_writes: slot.and_then(|s| s.compute(true, true)),
        });
        pass.set_group(0, &group, &[]);
        if self.wide {
            pass.set_pipe(&self.wide_pipeline);
            pass.dispatch(slots.max(1), 1, 1);
        } else {
            pass.set_pipe(&self.serial_pipeline);
            pass.dispatch(slots.div_ceil(64), 1, 1);
        }
    }
}
