//! Stage 5 of the HCB (Nguyen et al. §3): the levels, masks and samples (see the module above).

use crate::counters::prelude::*;

use bytemuck::Zeroable;

use super::{GpuHcbSample, HcbFrame, HcbLevel, HcbParams, MAX_LEVELS, STRIDE};
use crate::buffers::{BufferKind, BufferRegistry};
use crate::gpu::GpuContext;
use crate::gpu::bindings::{Bindings, Kind, binding};
use crate::timing::PassRec;

/// Bind group `hcb.level.inputs` of `shaders/hcb/base.wgsl` (group 0).
pub const LEVEL_INPUTS_BINDINGS: Bindings = Bindings {
    label: "hcb.level.inputs",
    shader: "hcb/base.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "hp", Kind::UniformDynamic),
        binding(1, "g_position", Kind::Texture { filterable: false }),
        binding(2, "g_normal", Kind::Texture { filterable: false }),
        binding(3, "out_position", Kind::StorageTexture(wgpu::TextureFormat::Rgba32Float)),
        binding(4, "out_normal", Kind::StorageTexture(wgpu::TextureFormat::Rgba32Float)),
        binding(5, "weight_sum", Kind::Texture { filterable: false }),
        binding(6, "out_incomplete", Kind::StorageTexture(wgpu::TextureFormat::R32Float)),
    ],
};

/// Bind group `hcb.samples.inputs` of `shaders/hcb/samples.wgsl` (group 0).
pub const SAMPLES_INPUTS_BINDINGS: Bindings = Bindings {
    label: "hcb.samples.inputs",
    shader: "hcb/samples.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "hp", Kind::UniformDynamic),
        binding(1, "level_normal", Kind::Texture { filterable: false }),
        binding(2, "mask_out", Kind::StorageTexture(wgpu::TextureFormat::R32Float)),
        binding(3, "mask_in", Kind::Texture { filterable: false }),
        binding(4, "samples_out", Kind::StorageTexture(wgpu::TextureFormat::R32Float)),
        binding(5, "counter", Kind::Storage { read_only: false }),
        binding(6, "level_position", Kind::Texture { filterable: false }),
        binding(7, "list", Kind::Storage { read_only: false }),
        binding(8, "cache_out", Kind::StorageTexture(wgpu::TextureFormat::R32Float)),
        binding(9, "group_out", Kind::StorageTexture(wgpu::TextureFormat::R32Float)),
    ],
};

/// The cache's textures the HCB build writes (§5.2): with them, level 0 is the supplementary
/// G-buffer (n^w = ±1 from `weight_sum`'s Σw), `incomplete` marks the incomplete texels and
/// new samples are marked in `cache` (2) and `recompute_group` (phase + 1).
pub struct CacheViews<'a> {
    pub weight_sum: &'a wgpu::TextureView,
    pub incomplete: &'a wgpu::TextureView,
    pub cache: &'a wgpu::TextureView,
    pub recompute_group: &'a wgpu::TextureView,
}

pub struct HcbPass {
    pub levels: Vec<HcbLevel>,
    /// `hcb.samples`: level + 1 at each sample's pixel, 0 elsewhere (G-buffer resolution).
    pub samples: wgpu::Texture,
    /// The number of samples (one u32).
    pub counter: wgpu::Buffer,
    /// The compact sample list ([`GpuHcbSample`]s).
    pub list: wgpu::Buffer,
    pub list_capacity: u32,
    io_layout: wgpu::BindGroupLayout,
    sample_layout: wgpu::BindGroupLayout,
    base_pipeline: wgpu::ComputePipeline,
    build_pipeline: wgpu::ComputePipeline,
    mask_pipeline: wgpu::ComputePipeline,
    clear_pipeline: wgpu::ComputePipeline,
    samples_pipeline: wgpu::ComputePipeline,
    params: wgpu::Buffer,
    dummy_storage: wgpu::Texture,
    dummy_sampled: wgpu::Texture,
    /// Stand-ins for the cache's textures without the cache (one each: two writable bindings
    /// of one texture in a dispatch would conflict).
    dummy_cache: [wgpu::Texture; 3],
    width: u32,
    height: u32,
}

/// Bytes of the sample counter: total, cached (reused), recomputed, invalid, surplus,
/// dropped (outside the view), 2 spare — see [`CacheCounts`].
pub const COUNTER_BYTES: u64 = 32;

/// Sizes of levels 0 … `levels` − 1 of a `width` × `height` G-buffer (each ⌈half⌉ of the
/// one below).
pub fn level_sizes(width: u32, height: u32, levels: u32) -> Vec<(u32, u32)> {
    let mut out = vec![(width.max(1), height.max(1))];
    for _ in 1..levels.clamp(1, MAX_LEVELS) {
        let (w, h) = *out.last().expect("level 0");
        out.push((w.div_ceil(2), h.div_ceil(2)));
    }
    out
}

impl HcbPass {
    pub fn new(ctx: &GpuContext, width: u32, height: u32, levels: u32) -> Self {
        let device = &ctx.device;
        let r32 = wgpu::TextureFormat::R32Float;
        let io_layout = LEVEL_INPUTS_BINDINGS.layout(device);
        let sample_layout = SAMPLES_INPUTS_BINDINGS.layout(device);
        let m_base = crate::shaders::create_module(device, "hcb/base.wgsl");
        let m_build = crate::shaders::create_module(device, "hcb/build.wgsl");
        let m_samples = crate::shaders::create_module(device, "hcb/samples.wgsl");
        let pipeline = |label, m, entry, layout| crate::passes::compute_pipeline(device, label, m, entry, &[layout]);
        let base_pipeline = pipeline("hcb.base", &m_base, "cs_base", &io_layout);
        let build_pipeline = pipeline("hcb.build", &m_build, "cs_build", &io_layout);
        let mask_pipeline = pipeline("hcb.mask", &m_samples, "cs_mask", &sample_layout);
        let clear_pipeline = pipeline("hcb.samples.clear", &m_samples, "cs_clear", &sample_layout);
        let samples_pipeline = pipeline("hcb.samples", &m_samples, "cs_samples", &sample_layout);
        let params = crate::passes::uniform_buffer(device, "hcb.params", STRIDE * (2 * MAX_LEVELS as u64 + 1));
        let storage = wgpu::TextureUsages::STORAGE_BINDING;
        let dummy_storage = crate::passes::create_target(device, "hcb.dummy_mask_out", 1, 1, r32, storage);
        let dummy_sampled = crate::passes::create_target(device, "hcb.dummy_mask_in", 1, 1, r32, storage);
        let dummy_cache = ["hcb.dummy_incomplete", "hcb.dummy_cache", "hcb.dummy_recompute_group"]
            .map(|label| crate::passes::create_target(device, label, 1, 1, r32, storage));
        let (levels_v, samples, list, list_capacity) = Self::targets(device, width, height, levels);
        let counter = crate::passes::buffer(
            device,
            "hcb.sample_count",
            COUNTER_BYTES,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
        );
        Self {
            levels: levels_v,
            samples,
            counter,
            list,
            list_capacity,
            io_layout,
            sample_layout,
            base_pipeline,
            build_pipeline,
            mask_pipeline,
            clear_pipeline,
            samples_pipeline,
            params,
            dummy_storage,
            dummy_sampled,
            dummy_cache,
            width,
            height,
        }
    }

    fn targets(
        device: &wgpu::Device,
        width: u32,
        height: u32,
        levels: u32,
    ) -> (Vec<HcbLevel>, wgpu::Texture, wgpu::Buffer, u32) {
        let storage = wgpu::TextureUsages::STORAGE_BINDING;
        let levels_v = level_sizes(width, height, levels)
            .into_iter()
            .enumerate()
            .map(|(k, (w, h))| HcbLevel {
                width: w,
                height: h,
                position: crate::passes::create_target(
                    device,
                    &format!("hcb.level.{k}.position"),
                    w,
                    h,
                    wgpu::TextureFormat::Rgba32Float,
                    storage,
                ),
                normal: crate::passes::create_target(
                    device,
                    &format!("hcb.level.{k}.normal"),
                    w,
                    h,
                    wgpu::TextureFormat::Rgba32Float,
                    storage,
                ),
                mask: crate::passes::create_target(
                    device,
                    &format!("hcb.mask.{k}"),
                    w,
                    h,
                    wgpu::TextureFormat::R32Float,
                    storage,
                ),
            })
            .collect();
        let samples = crate::passes::create_target(
            device,
            "hcb.samples",
            width.max(1),
            height.max(1),
            wgpu::TextureFormat::R32Float,
            storage,
        );
        // Every pixel could be a level-0 sample, as many as the device binds (`list_capacity`).
        let capacity = super::list_capacity(device, width, height);
        let list = crate::passes::buffer(
            device,
            "hcb.sample_list",
            std::mem::size_of::<GpuHcbSample>() as u64 * capacity as u64,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
        );
        // Samples are appended by an atomic counter (shaders/hcb/samples.wgsl): in any order.
        crate::counters::capture::mark_unordered(&list, std::mem::size_of::<GpuHcbSample>() as u64);
        (levels_v, samples, list, capacity)
    }

    /// Resizes for a `width` × `height` G-buffer and `levels` levels. Returns whether the
    /// textures were recreated.
    pub fn ensure(&mut self, ctx: &GpuContext, width: u32, height: u32, levels: u32) -> bool {
        let want = level_sizes(width, height, levels);
        let have: Vec<(u32, u32)> = self.levels.iter().map(|l| (l.width, l.height)).collect();
        if want == have && (self.width, self.height) == (width, height) {
            return false;
        }
        (self.levels, self.samples, self.list, self.list_capacity) = Self::targets(&ctx.device, width, height, levels);
        (self.width, self.height) = (width, height);
        true
    }

    pub fn register(&self, reg: &mut BufferRegistry) {
        for (k, l) in self.levels.iter().enumerate() {
            reg.register(
                &format!("hcb.level.{k}.position"),
                BufferKind::Data,
                "HCB level (Nguyen §3.2, §3.5): world position of the block's centre texel; w: a^w, the radius of the sphere around every pixel the texel stands for",
                &l.position,
            );
            reg.register(
                &format!("hcb.level.{k}.normal"),
                BufferKind::Data,
                "HCB level (Nguyen §3.2–3.4): normal of the block's centre texel; w: n^w, the group coherence of Algorithm 1 (0: incoherent or background, 1 at level 0)",
                &l.normal,
            );
            reg.register(
                &format!("hcb.mask.{k}"),
                BufferKind::Data,
                "HCB mask buffer (Nguyen §3.6): 1 inside the 3×3 splat of a coherent texel of the level above, 0 outside",
                &l.mask,
            );
        }
        reg.register(
            "hcb.samples",
            BufferKind::Data,
            "HCB samples (Nguyen §3.6) at G-buffer resolution: level + 1 at the pixel of each sample, 0 elsewhere",
            &self.samples,
        );
    }

    /// The bind group of `shaders/hcb/samples.wgsl` (mask, clear and sample passes) over the
    /// parameter slots: `views` = level normal, mask out, mask in, `hcb.samples`, level
    /// position, `hcb.cache`, `hcb.recompute_group`.
    fn sample_group(&self, ctx: &GpuContext, views: [&wgpu::TextureView; 7]) -> wgpu::BindGroup {
        let tv = wgpu::BindingResource::TextureView;
        let uniform = wgpu::BindingResource::Buffer(wgpu::BufferBinding {
            buffer: &self.params,
            offset: 0,
            size: std::num::NonZeroU64::new(std::mem::size_of::<HcbParams>() as u64),
        });
        let [normal, mask_out, mask_in, samples, position, cache, group] = views;
        SAMPLES_INPUTS_BINDINGS.group(
            &ctx.device,
            &self.sample_layout,
            [
                uniform,
                tv(normal),
                tv(mask_out),
                tv(mask_in),
                tv(samples),
                self.counter.as_entire_binding(),
                tv(position),
                self.list.as_entire_binding(),
                tv(cache),
                tv(group),
            ],
        )
    }

    /// Clears `hcb.samples` and the cache's `recompute_group` before the cache pass marks the
    /// reused samples (§5.1) and [`Self::run`] the new ones.
    pub fn clear_marks(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        recompute_group: &wgpu::TextureView,
    ) {
        let slot = 2 * MAX_LEVELS as u64;
        let mut p = HcbParams::zeroed();
        p.level[2] = 1;
        ctx.queue.upload(&self.params, slot * STRIDE, bytemuck::bytes_of(&p));
        let view = |t: &wgpu::Texture| crate::passes::view(t, "hcb.view");
        let (samples, mask_out, mask_in, level) =
            (view(&self.samples), view(&self.dummy_storage), view(&self.dummy_sampled), view(&self.levels[0].normal));
        let dummies = self.dummy_cache.each_ref().map(view);
        let group =
            self.sample_group(ctx, [&level, &mask_out, &mask_in, &samples, &mask_in, &dummies[1], recompute_group]);
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("hcb.samples.clear"),
            timestamp_writes: None,
        });
        pass.set_pipe(&self.clear_pipeline);
        pass.set_group(0, &group, &[(slot * STRIDE) as u32]);
        pass.dispatch(self.width.div_ceil(8), self.height.div_ceil(8), 1);
    }

    /// Builds every level from the G-buffer's position and normal, the masks and the samples.
    /// Without `cache` the sample counter and `hcb.samples` start empty; with it (§5.2) the
    /// base is the supplementary G-buffer and the new samples are appended to the cached
    /// ones the cache pass put in the list (and `hcb.samples`).
    pub fn run(
        &self,
        r: PassRec<'_, '_>,
        g_position: &wgpu::TextureView,
        g_normal: &wgpu::TextureView,
        f: HcbFrame,
        cache: Option<CacheViews<'_>>,
    ) {
        let PassRec { ctx, enc: encoder, slot } = r;
        let n = self.levels.len() as u32;
        let cached = cache.is_some() as u32;
        let spread = f.thresholds.spread_incomplete as u32;
        let mut params: Vec<HcbParams> = (0..n).map(|k| f.params([(k + 1 == n) as u32, k, cached, spread])).collect();
        // The clear of hcb.samples (and the recompute groups) uses the last slot.
        params.push(f.params([0, 0, cached, spread]));
        ctx.queue.upload(&self.params, 0, &crate::passes::strided_bytes(STRIDE, params.len(), &params));
        let uniform = wgpu::BindingResource::Buffer(wgpu::BufferBinding {
            buffer: &self.params,
            offset: 0,
            size: std::num::NonZeroU64::new(std::mem::size_of::<HcbParams>() as u64),
        });
        let view = |t: &wgpu::Texture| crate::passes::view(t, "hcb.view");
        fn tv(v: &wgpu::TextureView) -> wgpu::BindingResource<'_> {
            wgpu::BindingResource::TextureView(v)
        }
        let (samples_view, dummy_out, dummy_in) =
            (view(&self.samples), view(&self.dummy_storage), view(&self.dummy_sampled));
        let dummies = self.dummy_cache.each_ref().map(view);
        let (weight_sum, incomplete, cache_view, group_view) = match &cache {
            Some(c) => (c.weight_sum, c.incomplete, c.cache, c.recompute_group),
            None => (&dummy_in, &dummies[0], &dummies[1], &dummies[2]),
        };
        let io_group = |a: &wgpu::TextureView,
                        b: &wgpu::TextureView,
                        c: &wgpu::TextureView,
                        d: &wgpu::TextureView,
                        weights: &wgpu::TextureView,
                        marks: &wgpu::TextureView| {
            LEVEL_INPUTS_BINDINGS.group(
                &ctx.device,
                &self.io_layout,
                [uniform.clone(), tv(a), tv(b), tv(c), tv(d), tv(weights), tv(marks)],
            )
        };
        let views: Vec<(wgpu::TextureView, wgpu::TextureView, wgpu::TextureView)> =
            self.levels.iter().map(|l| (view(&l.position), view(&l.normal), view(&l.mask))).collect();
        let mut io_groups = vec![io_group(g_position, g_normal, &views[0].0, &views[0].1, weight_sum, incomplete)];
        for k in 1..n as usize {
            io_groups.push(io_group(
                &views[k - 1].0,
                &views[k - 1].1,
                &views[k].0,
                &views[k].1,
                &dummy_in,
                &dummies[0],
            ));
        }
        let sample_group = |position: &wgpu::TextureView,
                            normal: &wgpu::TextureView,
                            mask_out: &wgpu::TextureView,
                            mask_in: &wgpu::TextureView| {
            self.sample_group(ctx, [normal, mask_out, mask_in, &samples_view, position, cache_view, group_view])
        };
        // Mask k − 1 from level k's coherence; the top's mask stays all outside.
        let mask_groups: Vec<wgpu::BindGroup> =
            (1..n as usize).map(|k| sample_group(&views[k].0, &views[k].1, &views[k - 1].2, &dummy_in)).collect();
        let level_groups: Vec<wgpu::BindGroup> = (0..n as usize)
            .map(|k| {
                let mask_in = if k + 1 == n as usize { &dummy_in } else { &views[k].2 };
                sample_group(&views[k].0, &views[k].1, &dummy_out, mask_in)
            })
            .collect();
        if cache.is_none() {
            encoder.counted_clear_buffer(&self.counter, 0, None);
        }
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("hcb"),
            timestamp_writes: slot.and_then(|s| s.compute(true, true)),
        });
        let groups = |w: u32, h: u32| (w.div_ceil(8), h.div_ceil(8));
        let offset = |k: usize| [(k as u64 * STRIDE) as u32];
        for (k, l) in self.levels.iter().enumerate() {
            pass.set_pipe(if k == 0 { &self.base_pipeline } else { &self.build_pipeline });
            pass.set_group(0, &io_groups[k], &offset(k));
            let (gx, gy) = groups(l.width, l.height);
            pass.dispatch(gx, gy, 1);
        }
        pass.set_pipe(&self.mask_pipeline);
        for k in (1..n as usize).rev() {
            pass.set_group(0, &mask_groups[k - 1], &offset(k));
            let (gx, gy) = groups(self.levels[k - 1].width, self.levels[k - 1].height);
            pass.dispatch(gx, gy, 1);
        }
        if cache.is_none() {
            pass.set_pipe(&self.clear_pipeline);
            pass.set_group(0, &level_groups[0], &offset(n as usize));
            let (gx, gy) = groups(self.width, self.height);
            pass.dispatch(gx, gy, 1);
        }
        pass.set_pipe(&self.samples_pipeline);
        for (k, l) in self.levels.iter().enumerate() {
            pass.set_group(0, &level_groups[k], &offset(k));
            let (gx, gy) = groups(l.width, l.height);
            pass.dispatch(gx, gy, 1);
        }
    }
}
