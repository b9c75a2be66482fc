//! GI Lab's mix of Nguyen et al. 000 and Gautron et al. 003 (issue #17 "Mixes"): records'
//! hemispheres computed at the HCB's samples (`pipeline.shading_points = HcbSamples` with
//! `pipeline.gather = Hemispheres`), spread by the HCB's coherence splatting. Both are
//! sparse shading points: the mix compares where Nguyen's coherence places them with where
//! Gautron's coverage test does, at the same hemisphere per point
//! (`gi-lab bench --suite gautron` prints both). The chunking kernels are
//! `shaders/gautron/at_samples.wgsl`; the orchestration is `GautronStage::gather_at_samples`.

use crate::counters::prelude::*;

use crate::gpu::GpuContext;
use crate::gpu::bindings::{Bindings, Kind, binding};

/// Bind group `gautron.at_samples` of `shaders/gautron/at_samples.wgsl` (group 0).
pub const AT_SAMPLES_BINDINGS: Bindings = Bindings {
    label: "gautron.at_samples",
    shader: "gautron/at_samples.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "params", Kind::Uniform),
        binding(1, "round", Kind::UniformDynamic),
        binding(2, "state", Kind::Storage { read_only: false }),
        binding(3, "slots", Kind::Storage { read_only: false }),
        binding(4, "records", Kind::Storage { read_only: false }),
        binding(5, "raster_args", Kind::Storage { read_only: false }),
        binding(6, "counter", Kind::Storage { read_only: true }),
        binding(7, "list", Kind::Storage { read_only: false }),
        binding(8, "args", Kind::Storage { read_only: false }),
    ],
};

/// Bytes of one HCB sample (`passes::hcb::GpuHcbSample`).
pub const HCB_SAMPLE_BYTES: u64 = std::mem::size_of::<crate::passes::hcb::GpuHcbSample>() as u64;
/// Bytes between the chunks' uniforms (dynamic offsets).
const CHUNK_STRIDE: u64 = 256;

pub struct AtSamplesPass {
    layout: wgpu::BindGroupLayout,
    begin: wgpu::ComputePipeline,
    store: wgpu::ComputePipeline,
    /// The chunks' indices, one per [`CHUNK_STRIDE`].
    chunks: wgpu::Buffer,
    capacity: u32,
}

impl AtSamplesPass {
    pub fn new(ctx: &GpuContext) -> Self {
        let device = &ctx.device;
        let layout = AT_SAMPLES_BINDINGS.layout(device);
        let module = crate::shaders::create_module(device, "gautron/at_samples.wgsl");
        let pipeline = |entry: &str| {
            crate::passes::compute_pipeline(device, &format!("gautron.{entry}"), &module, entry, &[&layout])
        };
        let (begin, store) = (pipeline("cs_samples_begin"), pipeline("cs_samples_store"));
        let chunks = crate::passes::uniform_buffer(device, "gautron.at_samples.chunks", CHUNK_STRIDE);
        Self { layout, begin, store, chunks, capacity: 1 }
    }

    /// Makes room for `chunks` chunk indices.
    pub fn ensure_chunks(&mut self, ctx: &GpuContext, chunks: u32) {
        if chunks > self.capacity || self.capacity == 1 {
            self.capacity = chunks.max(self.capacity).next_power_of_two();
            self.chunks = crate::passes::uniform_buffer(
                &ctx.device,
                "gautron.at_samples.chunks",
                CHUNK_STRIDE * self.capacity as u64,
            );
            let words: Vec<[u32; 4]> = (0..self.capacity).map(|k| [k, 0, 0, 0]).collect();
            ctx.queue.write_buffer(
                &self.chunks,
                0,
                &crate::passes::strided_bytes(CHUNK_STRIDE, self.capacity as usize, &words),
            );
        }
    }

    /// The bind group over Gautron's (params, state, slots, records), the raster's draws
    /// and the HCB's (counter, list, args).
    pub fn group(
        &self,
        ctx: &GpuContext,
        (params, state, slots, records): (&wgpu::Buffer, &wgpu::Buffer, &wgpu::Buffer, &wgpu::Buffer),
        raster_args: &wgpu::BufferBinding<'_>,
        (counter, list, args): (&wgpu::Buffer, &wgpu::Buffer, &wgpu::Buffer),
    ) -> wgpu::BindGroup {
        AT_SAMPLES_BINDINGS.group(
            &ctx.device,
            &self.layout,
            [
                params.as_entire_binding(),
                crate::passes::dynamic_slot(&self.chunks, 16),
                state.as_entire_binding(),
                slots.as_entire_binding(),
                records.as_entire_binding(),
                wgpu::BindingResource::Buffer(raster_args.clone()),
                counter.as_entire_binding(),
                list.as_entire_binding(),
                args.as_entire_binding(),
            ],
        )
    }

    /// Chunk `k`'s samples into the slots' records (and the raster's instance counts).
    pub fn begin(&self, pass: &mut wgpu::ComputePass<'_>, group: &wgpu::BindGroup, k: u32) {
        pass.set_pipeline(&self.begin);
        pass.set_group(0, group, &[(k as u64 * CHUNK_STRIDE) as u32]);
        pass.dispatch_workgroups(1, 1, 1);
    }

    /// Chunk `k`'s records' irradiance into its samples' light.
    pub fn store(&self, pass: &mut wgpu::ComputePass<'_>, group: &wgpu::BindGroup, k: u32, slots: u32) {
        pass.set_pipeline(&self.store);
        pass.set_group(0, group, &[(k as u64 * CHUNK_STRIDE) as u32]);
        pass.dispatch_workgroups(slots.div_ceil(64), 1, 1);
    }
}
