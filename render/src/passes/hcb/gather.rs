//! Stage 6 of the HCB (Nguyen et al. §4.1): gathering the VPLs at the samples.

use crate::counters::prelude::*;

use glam::Vec4;

use super::build::HcbPass;
use crate::gpu::GpuContext;
use crate::gpu::bindings::{Bindings, Kind, binding};
use crate::timing::PassRec;

/// Bind group `hcb.gather.inputs` of `shaders/hcb/gather.wgsl` (group 0).
pub const GATHER_INPUTS_BINDINGS: Bindings = Bindings {
    label: "hcb.gather.inputs",
    shader: "hcb/gather.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "params", Kind::Uniform),
        binding(1, "vpls", Kind::Storage { read_only: true }),
        binding(2, "ism_atlas", Kind::Texture { filterable: false }),
        binding(3, "exact_atlas", Kind::Texture { filterable: false }),
        binding(4, "counter", Kind::Storage { read_only: true }),
        binding(5, "list", Kind::Storage { read_only: false }),
        binding(6, "args", Kind::Storage { read_only: false }),
        binding(7, "queue", Kind::Storage { read_only: true }),
    ],
};

/// Uniform of the gather at the samples; WGSL twin: `HcbGatherParams` in
/// `shaders/hcb/gather.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct HcbGatherParams {
    /// VPL count, visibility (0 none, 1 ISM, 2 exact), atlas columns, map size.
    pub counts: [u32; 4],
    /// The samples gathered ([`GatherSet`] as u32), 0, 0, 0.
    pub mode: [u32; 4],
    /// d_min², then as `interleave::GatherParams::shade`.
    pub shade: Vec4,
    /// x: the near field's cut² (senders closer are skipped; 0: none), y–w: 0.
    pub near: Vec4,
}

/// Which samples of the list a gather dispatch covers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GatherSet<'a> {
    /// Every sample (the per-frame HCB).
    All,
    /// The cached samples due for recomputation (§5.3): the list slots in the queue.
    Recompute(&'a wgpu::Buffer),
    /// The new samples after the cached ones (§5.2).
    New,
}

/// Stage 5 of the HCB technique (Nguyen et al. §4.1): the irradiance the VPLs send each
/// sample of the list (`shaders/hcb/gather.wgsl`), and the indirect arguments of this
/// dispatch and of the splat draws (`args`: 4 draw words for every sample, 3 dispatch words of
/// 64 samples per workgroup, one spare, 4 draw words for the samples after the cached ones,
/// §5.2, 3 dispatch words of a workgroup per sample, one spare).
pub struct HcbGatherPass {
    layout: wgpu::BindGroupLayout,
    args_pipeline: wgpu::ComputePipeline,
    /// A workgroup per sample (`cs_gather`) and an invocation per sample (`cs_gather_serial`).
    wide_pipeline: wgpu::ComputePipeline,
    serial_pipeline: wgpu::ComputePipeline,
    /// Whether the gather runs a workgroup per sample: on a GPU, not on a CPU renderer (whose
    /// workgroup barriers are dear); tests set it to check both on one device.
    pub wide: bool,
    /// The uniforms of the gathers of every sample / the new samples, and of the recomputed
    /// ones (both run in a cached frame).
    params: [wgpu::Buffer; 2],
    pub args: wgpu::Buffer,
    /// Bound as the recompute queue when there is none.
    no_queue: wgpu::Buffer,
    /// Bound in `args`'s place for the gather, which reads `args` as its indirect arguments
    /// (a buffer cannot be both in one dispatch).
    no_args: wgpu::Buffer,
    no_ism: wgpu::TextureView,
    no_exact: wgpu::TextureView,
}

impl HcbGatherPass {
    pub fn new(ctx: &GpuContext) -> Self {
        let device = &ctx.device;
        let layout = GATHER_INPUTS_BINDINGS.layout(device);
        let module = crate::shaders::create_module(device, "hcb/gather.wgsl");
        let args_pipeline = crate::passes::compute_pipeline(device, "hcb.gather.args", &module, "cs_args", &[&layout]);
        let wide_pipeline = crate::passes::compute_pipeline(device, "hcb.gather", &module, "cs_gather", &[&layout]);
        let serial_pipeline =
            crate::passes::compute_pipeline(device, "hcb.gather.serial", &module, "cs_gather_serial", &[&layout]);
        let wide = ctx.adapter_info.device_type != wgpu::DeviceType::Cpu;
        let size = std::mem::size_of::<HcbGatherParams>() as u64;
        let params = [
            crate::passes::uniform_buffer(device, "hcb.gather.params", size),
            crate::passes::uniform_buffer(device, "hcb.gather.recompute.params", size),
        ];
        let no_queue = crate::passes::buffer(device, "hcb.no_recompute_queue", 16, wgpu::BufferUsages::STORAGE);
        let args = crate::passes::buffer(
            device,
            "hcb.indirect_args",
            64,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::INDIRECT | wgpu::BufferUsages::COPY_SRC,
        );
        let no_args = crate::passes::buffer(device, "hcb.no_args", 64, wgpu::BufferUsages::STORAGE);
        let (no_ism, no_exact) = crate::passes::reference::vpl_visibility::no_visibility_atlases(device, "hcb.gather");
        Self {
            layout,
            args_pipeline,
            wide_pipeline,
            serial_pipeline,
            wide,
            params,
            args,
            no_args,
            no_queue,
            no_ism,
            no_exact,
        }
    }

    /// Gathers at the samples `set` of `hcb`'s list from stage 3's VPLs with stage 4's
    /// visibility.
    pub fn run(
        &self,
        r: PassRec<'_, '_>,
        hcb: &HcbPass,
        (set_of_vpls, vis): (
            &crate::passes::stages::VplSet,
            &crate::passes::reference::vpl_visibility::GatherVisibility,
        ),
        set: GatherSet<'_>,
    ) {
        let PassRec { ctx, enc: encoder, slot } = r;
        let (vpls, vpl_count) = (&set_of_vpls.list, set_of_vpls.count);
        let (d_min, near_cut) = (set_of_vpls.min_distance, set_of_vpls.near_cut);
        let (code, ism, exact, cols, size, shade) = vis.parts(&self.no_ism, &self.no_exact);
        let (mode, queue) = match set {
            GatherSet::All => (0, &self.no_queue),
            GatherSet::Recompute(q) => (1, q),
            GatherSet::New => (2, &self.no_queue),
        };
        let p = HcbGatherParams {
            counts: [vpl_count, code, cols, size],
            mode: [mode, 0, 0, 0],
            shade: Vec4::new(d_min * d_min, shade.y, shade.z, shade.w),
            near: Vec4::new(near_cut * near_cut, 0.0, 0.0, 0.0),
        };
        let params = &self.params[(mode == 1) as usize];
        ctx.queue.upload(params, 0, bytemuck::bytes_of(&p));
        let tv = wgpu::BindingResource::TextureView;
        let group = |args: &wgpu::Buffer| {
            GATHER_INPUTS_BINDINGS.group(
                &ctx.device,
                &self.layout,
                [
                    params.as_entire_binding(),
                    vpls.as_entire_binding(),
                    tv(ism),
                    tv(exact),
                    hcb.counter.as_entire_binding(),
                    hcb.list.as_entire_binding(),
                    args.as_entire_binding(),
                    queue.as_entire_binding(),
                ],
            )
        };
        let (args_group, gather_group) = (group(&self.args), group(&self.no_args));
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("hcb.gather"),
            timestamp_writes: slot.and_then(|s| s.compute(true, true)),
        });
        pass.set_group(0, &args_group, &[]);
        pass.set_pipe(&self.args_pipeline);
        pass.dispatch(1, 1, 1);
        pass.set_group(0, &gather_group, &[]);
        // The dispatch words: 12–14 (a workgroup per sample) or 4–6 (64 samples per workgroup).
        let (pipeline, offset) = if self.wide { (&self.wide_pipeline, 48) } else { (&self.serial_pipeline, 16) };
        pass.set_pipe(pipeline);
        pass.dispatch_indirect(&self.args, offset);
    }
}
