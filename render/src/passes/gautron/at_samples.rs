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
        binding(9, "queue", Kind::Storage { read_only: true }),
        binding(10, "round_args", Kind::Storage { read_only: false }),
    ],
};

/// Bytes of one HCB sample (`passes::hcb::GpuHcbSample`).
pub const HCB_SAMPLE_BYTES: u64 = std::mem::size_of::<crate::passes::hcb::GpuHcbSample>() as u64;
/// Bytes between the chunks' uniforms (dynamic offsets).
const CHUNK_STRIDE: u64 = 256;
/// The dispatches' sample sets (`round.y` in the shader): every sample; the cached ones due
/// for recomputation and the new ones.
pub const MODES: u32 = 2;

/// Which of the HCB's samples a frame's hemispheres light (as `hcb::GatherSet`).
#[derive(Clone, Copy, Debug)]
pub enum SampleSet<'a> {
    /// Every sample of the list (no cache).
    All,
    /// With the HCB's sample cache: the cached samples due for recomputation (Nguyen §5.3;
    /// their list slots in the queue), then the new samples after the cached ones (§5.2).
    DueAndNew(&'a wgpu::Buffer),
}

impl SampleSet<'_> {
    pub fn mode(&self) -> u32 {
        match self {
            Self::All => 0,
            Self::DueAndNew(_) => 1,
        }
    }
}

pub struct AtSamplesPass {
    layout: wgpu::BindGroupLayout,
    begin: wgpu::ComputePipeline,
    store: wgpu::ComputePipeline,
    cached_args: wgpu::ComputePipeline,
    /// The chunks' (index, mode), one per [`CHUNK_STRIDE`]: mode m's chunk k at m·capacity + k.
    chunks: wgpu::Buffer,
    capacity: u32,
    /// Whether `chunks` holds its indices (made once, remade only when it grows).
    written: bool,
    /// Bound as the queue when the set has none.
    no_queue: wgpu::Buffer,
    /// The chunk's round arguments (`hemisphere::RoundArgs`), written by `begin`.
    pub round_args: wgpu::Buffer,
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
        let cached_args = pipeline("cs_cached_args");
        let chunks = crate::passes::uniform_buffer(device, "gautron.at_samples.chunks", CHUNK_STRIDE * MODES as u64);
        let no_queue = crate::passes::buffer(device, "gautron.at_samples.no_queue", 16, wgpu::BufferUsages::STORAGE);
        let round_args = crate::passes::buffer(
            device,
            "gautron.at_samples.round_args",
            super::hemisphere::ROUND_ARGS_BYTES,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::INDIRECT,
        );
        Self { layout, begin, store, cached_args, chunks, capacity: 1, written: false, no_queue, round_args }
    }

    /// Makes room for `chunks` chunk indices.
    pub fn ensure_chunks(&mut self, ctx: &GpuContext, chunks: u32) {
        // The first call writes the indices (the buffer of `new` holds none yet).
        if chunks > self.capacity || !self.written {
            self.written = true;
            self.capacity = chunks.max(self.capacity).next_power_of_two();
            let entries = (self.capacity * MODES) as usize;
            self.chunks =
                crate::passes::uniform_buffer(&ctx.device, "gautron.at_samples.chunks", CHUNK_STRIDE * entries as u64);
            let words: Vec<[u32; 4]> = (0..MODES).flat_map(|m| (0..self.capacity).map(move |k| [k, m, 0, 0])).collect();
            ctx.queue.upload(&self.chunks, 0, &crate::passes::strided_bytes(CHUNK_STRIDE, entries, &words));
        }
    }

    /// The bind group over Gautron's (params, state, slots, records), the raster's draws,
    /// the HCB's (counter, list, args) and the set's queue.
    pub fn group(
        &self,
        ctx: &GpuContext,
        (params, state, slots, records): (&wgpu::Buffer, &wgpu::Buffer, &wgpu::Buffer, &wgpu::Buffer),
        raster_args: &wgpu::BufferBinding<'_>,
        (counter, list, args): (&wgpu::Buffer, &wgpu::Buffer, &wgpu::Buffer),
        set: SampleSet<'_>,
    ) -> wgpu::BindGroup {
        let queue = match set {
            SampleSet::DueAndNew(q) => q,
            SampleSet::All => &self.no_queue,
        };
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
                queue.as_entire_binding(),
                self.round_args.as_entire_binding(),
            ],
        )
    }

    /// The dynamic offset of chunk `k` of `mode`'s dispatch.
    fn offset(&self, mode: u32, k: u32) -> u32 {
        ((mode * self.capacity + k) as u64 * CHUNK_STRIDE) as u32
    }

    /// Chunk `k`'s samples of `mode`'s set into the slots' records (and the raster's
    /// instance counts).
    pub fn begin(&self, pass: &mut wgpu::ComputePass<'_>, group: &wgpu::BindGroup, (mode, k): (u32, u32)) {
        pass.set_pipe(&self.begin);
        pass.set_group(0, group, &[self.offset(mode, k)]);
        pass.dispatch(1, 1, 1);
    }

    /// The HCB splat's indirect arguments over the cached samples (between the cache's
    /// update and the build).
    pub fn cached_args(&self, pass: &mut wgpu::ComputePass<'_>, group: &wgpu::BindGroup) {
        pass.set_pipe(&self.cached_args);
        pass.set_group(0, group, &[0]);
        pass.dispatch(1, 1, 1);
    }

    /// Chunk `k`'s records' irradiance into its samples' light.
    pub fn store(&self, pass: &mut wgpu::ComputePass<'_>, group: &wgpu::BindGroup, (mode, k): (u32, u32), slots: u32) {
        pass.set_pipe(&self.store);
        pass.set_group(0, group, &[self.offset(mode, k)]);
        pass.dispatch(slots.div_ceil(64), 1, 1);
    }
}
