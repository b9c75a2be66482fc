//! GI Lab's mix of Nguyen et al. and Soler et al. (issue #16 "Mixes"): stage 6's
//! screen-space gather at stage 5's HCB samples (`pipeline.shading_points = HcbSamples`,
//! `gather = ScreenSpace`, `reconstruction = CoherenceSplatting`). Every sample of the HCB's
//! list sums the rings of Soler's gathered levels around its pixel with itself as the
//! receiver (`shaders/soler/hcb_gather.wgsl`, one dispatch per level; CPU twin
//! `cpu::soler::gather_at`), and the HCB's coherence splatting spreads the result.

use crate::counters::prelude::*;

use super::gather::{GatherParams, LevelInputs};
use crate::gpu::GpuContext;
use crate::gpu::bindings::{Bindings, Kind, binding};
use crate::timing::PassRec;

/// Bind group `soler.hcb_gather.inputs` of `shaders/soler/hcb_gather.wgsl` (group 0).
pub const HCB_GATHER_INPUTS_BINDINGS: Bindings = Bindings {
    label: "soler.hcb_gather.inputs",
    shader: "soler/hcb_gather.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "params", Kind::UniformDynamic),
        binding(1, "level_position", Kind::Texture { filterable: false }),
        binding(2, "level_normal", Kind::Texture { filterable: false }),
        binding(3, "level_radiance", Kind::Texture { filterable: false }),
        binding(4, "grid", Kind::Storage { read_only: true }),
        binding(5, "counter", Kind::Storage { read_only: true }),
        binding(6, "list", Kind::Storage { read_only: false }),
    ],
};

/// Bind group `soler.hcb_gather.args` of `shaders/soler/hcb_gather.wgsl` (group 1).
pub const HCB_GATHER_ARGS_BINDINGS: Bindings = Bindings {
    label: "soler.hcb_gather.args",
    shader: "soler/hcb_gather.wgsl",
    group: 1,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[binding(0, "args", Kind::Storage { read_only: false })],
};

pub struct SolerHcbGather {
    layout: wgpu::BindGroupLayout,
    args_layout: wgpu::BindGroupLayout,
    args_pipeline: wgpu::ComputePipeline,
    pipeline: wgpu::ComputePipeline,
}

impl SolerHcbGather {
    pub fn new(ctx: &GpuContext) -> Self {
        let device = &ctx.device;
        let layout = HCB_GATHER_INPUTS_BINDINGS.layout(device);
        let args_layout = HCB_GATHER_ARGS_BINDINGS.layout(device);
        let module = crate::shaders::create_module(device, "soler/hcb_gather.wgsl");
        let args_pipeline = crate::passes::compute_pipeline(
            device,
            "soler.hcb_gather.args",
            &module,
            "cs_args",
            &[&layout, &args_layout],
        );
        let pipeline = crate::passes::compute_pipeline(device, "soler.hcb_gather", &module, "cs_gather", &[&layout]);
        Self { layout, args_layout, args_pipeline, pipeline }
    }

    /// Writes the HCB's indirect arguments (`args`) for its `list` of `counter` samples, then
    /// gathers `levels` (in order; the i-th with the parameter slot i of `params`) into each
    /// sample's light.
    pub fn run(
        &self,
        r: PassRec<'_, '_>,
        params: &wgpu::Buffer,
        levels: &[LevelInputs<'_>],
        (list, counter, args): (&wgpu::Buffer, &wgpu::Buffer, &wgpu::Buffer),
    ) {
        let PassRec { ctx, enc: encoder, slot } = r;
        let uniform = || crate::passes::dynamic_slot(params, std::mem::size_of::<GatherParams>());
        let tv = wgpu::BindingResource::TextureView;
        let groups: Vec<wgpu::BindGroup> = levels
            .iter()
            .map(|l| {
                let resources = vec![
                    uniform(),
                    tv(l.position),
                    tv(l.normal),
                    tv(l.radiance),
                    l.grid.as_entire_binding(),
                    counter.as_entire_binding(),
                    list.as_entire_binding(),
                ];
                HCB_GATHER_INPUTS_BINDINGS.group(&ctx.device, &self.layout, resources)
            })
            .collect();
        let Some(first) = groups.first() else { return };
        let args_group = HCB_GATHER_ARGS_BINDINGS.group(&ctx.device, &self.args_layout, [args.as_entire_binding()]);
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("soler.hcb_gather.args"),
                timestamp_writes: slot.as_ref().and_then(|s| s.compute(true, false)),
            });
            pass.set_pipe(&self.args_pipeline);
            pass.set_group(0, first, &[0]);
            pass.set_group(1, &args_group, &[]);
            pass.dispatch(1, 1, 1);
        }
        let n = groups.len();
        for (i, g) in groups.iter().enumerate() {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("soler.hcb_gather"),
                timestamp_writes: slot.as_ref().and_then(|s| s.compute(false, i + 1 == n)),
            });
            pass.set_pipe(&self.pipeline);
            pass.set_group(0, g, &[(i as u64 * super::STRIDE) as u32]);
            // Words 4–6 of the HCB's arguments: the dispatch over every sample.
            pass.dispatch_indirect(args, 16);
        }
    }
}
