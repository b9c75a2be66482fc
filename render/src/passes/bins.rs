//! Splats summed in compute (issue #38): the bins that Gautron's records (003, "From Octree
//! to Splatting") and the HCB's samples (Nguyen §4.3) are sorted into instead of quads added
//! by blending. The items of one splat are marked, one bit each, in every `BIN` × `BIN`
//! pixel square their rectangle overlaps; a 16 × 16 workgroup then sums, at each of its
//! pixels, the items that reach it in increasing index — the blending's order, so that both
//! methods give the same sums bit for bit. Shader `common/bins.wgsl` (bind group 1 of the
//! passes that use it); docs/architecture.md, "Read-backs, waits and the frame's traffic".

use crate::counters::prelude::*;
use crate::gpu::bindings::{Bindings, Kind, binding};

use crate::gpu::GpuContext;
pub use crate::settings::splat::SplatMethod;

/// Side in pixels of the squares the items are binned into (a multiple of the 16 × 16
/// accumulation workgroup).
pub const BIN: u32 = 64;

/// Most items one splat's bins hold (`BIN_MAX_WORDS` × 32 in `common/bins.wgsl`): a
/// workgroup keeps one bit per item of its square in 8 KB of shared memory.
pub const MAX_ITEMS: u32 = 65536;

/// Pixels per side of the accumulating workgroup.
pub const GROUP: u32 = 16;

/// The bins' bind group (group 1 of `shaders/common/bins.wgsl`, imported by the HCB's and
/// Gautron's splats); each user's bins carry their own label (`hcb.splat.bins`, …).
pub const BINS_BINDINGS: Bindings = Bindings {
    label: "bins",
    shader: "hcb/splat.wgsl",
    group: 1,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "bin_params", Kind::Uniform),
        binding(1, "bin_mask", Kind::Storage { read_only: false }),
        binding(2, "bin_rects", Kind::Storage { read_only: false }),
    ],
};

/// Rust twin of `BinParams` in `shaders/common/bins.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct BinParams {
    /// Squares across and down, mask words per square, `BIN`.
    pub bins: [u32; 4],
    /// x: 1 to add to the previous sums, 0 to start from zero.
    pub mode: [u32; 4],
}

/// One splat of [`Bins::splat`]: the technique's bin and accumulate pipelines, its bind
/// group 0, whether the splat adds to the last one's sums (`add`), and the target's size.
#[derive(Clone, Copy)]
pub struct SplatJob<'a> {
    pub pipelines: (&'a wgpu::ComputePipeline, &'a wgpu::ComputePipeline),
    pub group: &'a wgpu::BindGroup,
    pub add: bool,
    pub size: (u32, u32),
}

/// The bins of one splat: the mask, the items' rectangles and the two `BinParams`.
pub struct Bins {
    label: &'static str,
    layout: wgpu::BindGroupLayout,
    /// `BinParams` to start from zero (0) and to add (1).
    params: [wgpu::Buffer; 2],
    /// One bit per item per square (cleared before each splat).
    mask: wgpu::Buffer,
    /// Each item's rectangle in NDC.
    rects: wgpu::Buffer,
    /// (squares across, down, words per square) the mask is sized for.
    bins: (u32, u32, u32),
}

impl Bins {
    /// Empty bins named `label` (its mask `label.mask`, …); size them with [`Self::ensure`].
    pub fn new(ctx: &GpuContext, label: &'static str) -> Self {
        let device = &ctx.device;
        let layout = BINS_BINDINGS.layout_labelled(device, label);
        let storage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
        let size = std::mem::size_of::<BinParams>() as u64;
        Self {
            label,
            params: [
                crate::passes::uniform_buffer(device, &format!("{label}.params.clear"), size),
                crate::passes::uniform_buffer(device, &format!("{label}.params.add"), size),
            ],
            mask: crate::passes::buffer(device, &format!("{label}.mask"), 4, storage),
            rects: crate::passes::buffer(device, &format!("{label}.rects"), 16, storage),
            bins: (0, 0, 0),
            layout,
        }
    }

    /// The layout of bind group 1 of the passes that use the bins.
    pub fn layout(&self) -> &wgpu::BindGroupLayout {
        &self.layout
    }

    /// Sizes the bins for `items` items (at most [`MAX_ITEMS`]) on a `width` × `height`
    /// screen; nothing happens when they already are.
    pub fn ensure(&mut self, ctx: &GpuContext, width: u32, height: u32, items: u32) {
        let words = items.clamp(1, MAX_ITEMS).div_ceil(32);
        let bins = (width.max(1).div_ceil(BIN), height.max(1).div_ceil(BIN), words);
        if bins == self.bins {
            return;
        }
        self.bins = bins;
        let storage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
        let mask_words = bins.0 as u64 * bins.1 as u64 * bins.2 as u64;
        let label = self.label;
        self.mask = crate::passes::buffer(&ctx.device, &format!("{label}.mask"), mask_words * 4, storage);
        self.rects = crate::passes::buffer(&ctx.device, &format!("{label}.rects"), words as u64 * 32 * 16, storage);
        for (mode, buffer) in self.params.iter().enumerate() {
            let p = BinParams { bins: [bins.0, bins.1, bins.2, BIN], mode: [mode as u32, 0, 0, 0] };
            ctx.queue.upload(buffer, 0, bytemuck::bytes_of(&p));
        }
    }

    /// Items the bins hold.
    pub fn capacity(&self) -> u32 {
        self.bins.2 * 32
    }

    /// Bind group 1: start the sums from zero, or `add` to the previous ones.
    pub fn group(&self, device: &wgpu::Device, add: bool) -> wgpu::BindGroup {
        BINS_BINDINGS.group_labelled(
            device,
            self.label,
            &self.layout,
            [
                self.params[usize::from(add)].as_entire_binding(),
                self.mask.as_entire_binding(),
                self.rects.as_entire_binding(),
            ],
        )
    }

    /// Records one splat, a compute pass named `label`: the mask cleared, then the job's
    /// `bin` pipeline over every item the bins hold (64 per workgroup) and its `accumulate`
    /// over the `size` pixels (16 × 16 per workgroup), with its `group` as bind group 0 and
    /// [`Self::group`] as 1.
    pub fn splat(
        &self,
        ctx: &GpuContext,
        enc: &mut wgpu::CommandEncoder,
        (label, timestamp_writes): (&str, Option<wgpu::ComputePassTimestampWrites<'_>>),
        job: &SplatJob,
    ) {
        let SplatJob { pipelines: (bin, accumulate), group, add, size } = *job;
        let bins = self.group(&ctx.device, add);
        enc.counted_clear_buffer(&self.mask, 0, None);
        let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some(label), timestamp_writes });
        pass.set_group(0, group, &[]);
        pass.set_group(1, &bins, &[]);
        pass.set_pipe(bin);
        pass.dispatch(self.capacity().div_ceil(64), 1, 1);
        pass.set_pipe(accumulate);
        pass.dispatch(size.0.div_ceil(GROUP), size.1.div_ceil(GROUP), 1);
    }
}
