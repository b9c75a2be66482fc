//! The HCB's sample cache (Nguyen et al. 000 §5, Fig. 5): the samples of the previous frame
//! (double-buffered with the current sample list) are validated in the current view, the
//! invalid ones and the surplus ones around them removed (§5.1), the survivors reprojected
//! into the current list with their light, and a quarter of them (one period's phase)
//! marked for recomputation (§5.3). The frame then splats the cached samples, builds the HCB
//! over the supplementary G-buffer of the incomplete texels (§5.2, `HcbPass::run` with
//! [`CacheViews`]), gathers and splats the new samples on top. Shaders
//! `shaders/hcb/{cache,cache_removal}.wgsl`; CPU twins `cpu::hcb::{validate, advance_counter,
//! recompute_pattern, supplementary_base}`.

use crate::counters::prelude::*;

use glam::Vec4;

use crate::buffers::{BufferKind, BufferRegistry};
use crate::gpu::GpuContext;
use crate::gpu::bindings::{Bindings, Kind, binding};
use crate::passes::hcb::{COUNTER_BYTES, CacheViews, GpuHcbSample, HcbPass};
use crate::timing::PassRec;

/// Bind group `hcb.cache.inputs` of `shaders/hcb/cache.wgsl` (group 0).
pub const CACHE_INPUTS_BINDINGS: Bindings = Bindings {
    label: "hcb.cache.inputs",
    shader: "hcb/cache.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "camera", Kind::Uniform),
        binding(1, "cp", Kind::Uniform),
        binding(2, "prev_counter", Kind::Storage { read_only: false }),
        binding(3, "prev", Kind::Storage { read_only: false }),
        binding(4, "g_position", Kind::Texture { filterable: false }),
        binding(5, "g_normal", Kind::Texture { filterable: false }),
        binding(6, "counter", Kind::Storage { read_only: false }),
        binding(7, "list", Kind::Storage { read_only: false }),
        binding(8, "removal", Kind::Texture { filterable: false }),
        binding(9, "samples_out", Kind::StorageTexture(wgpu::TextureFormat::R32Float)),
        binding(10, "group_out", Kind::StorageTexture(wgpu::TextureFormat::R32Float)),
        binding(11, "queue", Kind::Storage { read_only: false }),
    ],
};

/// Bind group `hcb.cache.args` of `shaders/hcb/cache.wgsl` (group 1).
pub const CACHE_ARGS_BINDINGS: Bindings = Bindings {
    label: "hcb.cache.args",
    shader: "hcb/cache.wgsl",
    group: 1,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[binding(0, "args", Kind::Storage { read_only: false })],
};

/// Bind group `hcb.cache.removal.inputs` of `shaders/hcb/cache_removal.wgsl` (group 0).
pub const CACHE_REMOVAL_INPUTS_BINDINGS: Bindings = Bindings {
    label: "hcb.cache.removal.inputs",
    shader: "hcb/cache_removal.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
    list: &[
        binding(0, "camera", Kind::Uniform),
        binding(1, "cp", Kind::Uniform),
        binding(2, "prev", Kind::Storage { read_only: true }),
    ],
};

/// Uniform of the cache update; WGSL twin: `CacheParams` in `shaders/hcb/common.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct CacheParams {
    /// Distance threshold (scene units), cos of the normal threshold, removal quad side
    /// (pixels), recompute period.
    pub limits: Vec4,
}

/// The per-frame counts of the cache (the sample counter's words).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CacheCounts {
    /// Samples of this frame (cached and new).
    pub total: u32,
    /// Cached samples reused (§5.1).
    pub cached: u32,
    /// Cached samples whose light was gathered again (§5.3).
    pub recomputed: u32,
    /// Cached samples removed as invalid.
    pub invalid: u32,
    /// Valid cached samples removed inside an invalid one's quad.
    pub surplus: u32,
    /// Cached samples outside the view.
    pub dropped: u32,
}

impl CacheCounts {
    pub fn from_words(w: &[u32]) -> Self {
        let at = |i: usize| w.get(i).copied().unwrap_or(0);
        Self { total: at(0), cached: at(1), recomputed: at(2), invalid: at(3), surplus: at(4), dropped: at(5) }
    }

    /// Samples identified this frame.
    pub fn new_samples(&self) -> u32 {
        self.total.saturating_sub(self.cached)
    }

    /// Samples whose light was gathered this frame (new and recomputed).
    pub fn gathered(&self) -> u32 {
        self.new_samples() + self.recomputed
    }
}

impl std::fmt::Display for CacheCounts {
    /// One line, aligned for a column of frames.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{:>7} samples = {:>7} cached + {:>6} new; {:>6} recomputed; removed {:>5} invalid, {:>5} surplus, {:>5} outside the view",
            self.total,
            self.cached,
            self.new_samples(),
            self.recomputed,
            self.invalid,
            self.surplus,
            self.dropped
        )
    }
}

/// What the cache update needs of the frame.
#[derive(Clone, Copy, Debug)]
pub struct CacheFrame {
    pub max_distance: f32,
    pub max_normal_deg: f32,
    pub quad_px: u32,
    pub period: u32,
}

pub struct HcbCachePass {
    /// The sample cache: the previous frame's list and counter (swapped with the HCB's at
    /// the start of each frame, [`Self::swap`]).
    pub prev_list: wgpu::Buffer,
    pub prev_counter: wgpu::Buffer,
    /// `hcb.incomplete`: 1 where the cached samples' Σw is below the threshold (§5.2).
    pub incomplete: wgpu::Texture,
    /// `hcb.cache`: 1 reused sample, 2 new sample, 3 removed (an invalid sample's quad).
    pub cache: wgpu::Texture,
    /// `hcb.recompute_group`: the recompute phase + 1 at each sample's pixel (§5.3, Fig. 8b).
    pub recompute_group: wgpu::Texture,
    /// The list slots of the samples to recompute this frame (the gather's mode 1).
    pub queue: wgpu::Buffer,
    depth: wgpu::Texture,
    layout: wgpu::BindGroupLayout,
    args_layout: wgpu::BindGroupLayout,
    removal_layout: wgpu::BindGroupLayout,
    args_pipeline: wgpu::ComputePipeline,
    validate_pipeline: wgpu::ComputePipeline,
    compact_pipeline: wgpu::ComputePipeline,
    removal_pipeline: wgpu::RenderPipeline,
    params: wgpu::Buffer,
    args: wgpu::Buffer,
    width: u32,
    height: u32,
}

const CACHE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Float;
const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

impl HcbCachePass {
    pub fn new(ctx: &GpuContext, width: u32, height: u32) -> Self {
        let device = &ctx.device;
        let layout = CACHE_INPUTS_BINDINGS.layout(device);
        let args_layout = CACHE_ARGS_BINDINGS.layout(device);
        let removal_layout = CACHE_REMOVAL_INPUTS_BINDINGS.layout(device);
        let m_cache = crate::shaders::create_module(device, "hcb/cache.wgsl");
        let m_removal = crate::shaders::create_module(device, "hcb/cache_removal.wgsl");
        let args_pipeline =
            crate::passes::compute_pipeline(device, "hcb.cache.args", &m_cache, "cs_args", &[&layout, &args_layout]);
        let validate_pipeline =
            crate::passes::compute_pipeline(device, "hcb.cache.validate", &m_cache, "cs_validate", &[&layout]);
        let compact_pipeline =
            crate::passes::compute_pipeline(device, "hcb.cache.compact", &m_cache, "cs_compact", &[&layout]);
        let pl = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("hcb.cache.removal.pipeline_layout"),
            bind_group_layouts: &[Some(&removal_layout)],
            immediate_size: 0,
        });
        let removal_pipeline = device.counted_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("hcb.cache.removal"),
            layout: Some(&pl),
            vertex: wgpu::VertexState {
                module: &m_removal,
                entry_point: Some("vs_removal"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: Default::default(),
            depth_stencil: Some(wgpu::DepthStencilState {
                format: DEPTH_FORMAT,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::Less),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &m_removal,
                entry_point: Some("fs_removal"),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState {
                    format: CACHE_FORMAT,
                    blend: None,
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            multiview_mask: None,
            cache: None,
        });
        let params =
            crate::passes::uniform_buffer(device, "hcb.cache.params", std::mem::size_of::<CacheParams>() as u64);
        let args = crate::passes::buffer(
            device,
            "hcb.cache.indirect_args",
            32,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::INDIRECT,
        );
        let (prev_list, prev_counter, incomplete, cache, recompute_group, depth, queue) =
            Self::targets(device, width, height);
        Self {
            prev_list,
            prev_counter,
            incomplete,
            cache,
            recompute_group,
            queue,
            depth,
            layout,
            args_layout,
            removal_layout,
            args_pipeline,
            validate_pipeline,
            compact_pipeline,
            removal_pipeline,
            params,
            args,
            width,
            height,
        }
    }

    #[allow(clippy::type_complexity)]
    fn targets(
        device: &wgpu::Device,
        width: u32,
        height: u32,
    ) -> (wgpu::Buffer, wgpu::Buffer, wgpu::Texture, wgpu::Texture, wgpu::Texture, wgpu::Texture, wgpu::Buffer) {
        let (w, h) = (width.max(1), height.max(1));
        let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC;
        // The HCB's list capacity: every pixel could be a level-0 sample, as many as the
        // device binds.
        let capacity = super::list_capacity(device, w, h) as u64;
        let list = crate::passes::buffer(
            device,
            "hcb.sample_cache",
            std::mem::size_of::<GpuHcbSample>() as u64 * capacity,
            usage,
        );
        // Kept samples are appended by an atomic counter (shaders/hcb/cache.wgsl).
        crate::counters::capture::mark_unordered(&list, std::mem::size_of::<GpuHcbSample>() as u64);
        let counter = crate::passes::buffer(device, "hcb.sample_cache_count", COUNTER_BYTES, usage);
        let storage = wgpu::TextureUsages::STORAGE_BINDING;
        let incomplete = crate::passes::create_target(device, "hcb.incomplete", w, h, CACHE_FORMAT, storage);
        let cache = crate::passes::create_target(
            device,
            "hcb.cache",
            w,
            h,
            CACHE_FORMAT,
            storage | wgpu::TextureUsages::RENDER_ATTACHMENT,
        );
        let group = crate::passes::create_target(device, "hcb.recompute_group", w, h, CACHE_FORMAT, storage);
        let depth = device.counted_texture(&wgpu::TextureDescriptor {
            label: Some("hcb.cache.depth"),
            size: wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: DEPTH_FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            view_formats: &[],
        });
        let queue =
            crate::passes::buffer(device, "hcb.recompute_queue", 4 * (w * h) as u64, wgpu::BufferUsages::STORAGE);
        (list, counter, incomplete, cache, group, depth, queue)
    }

    /// Resizes for a `width` × `height` G-buffer (the cache starts empty). Returns whether the
    /// targets were recreated.
    pub fn ensure(&mut self, ctx: &GpuContext, width: u32, height: u32) -> bool {
        if (self.width, self.height) == (width, height) {
            return false;
        }
        (
            self.prev_list,
            self.prev_counter,
            self.incomplete,
            self.cache,
            self.recompute_group,
            self.depth,
            self.queue,
        ) = Self::targets(&ctx.device, width, height);
        (self.width, self.height) = (width, height);
        true
    }

    /// Empties the cache: the next frame identifies all its samples anew (after a change of
    /// the HCB's settings, which the cached samples do not follow).
    pub fn reset(&self, encoder: &mut wgpu::CommandEncoder) {
        encoder.counted_clear_buffer(&self.prev_counter, 0, None);
    }

    /// Double buffering (§5.1): the HCB's list of the last frame becomes the cache, and the
    /// old cache's storage the list this frame fills.
    pub fn swap(&mut self, hcb: &mut HcbPass) {
        std::mem::swap(&mut self.prev_list, &mut hcb.list);
        std::mem::swap(&mut self.prev_counter, &mut hcb.counter);
    }

    pub fn register(&self, reg: &mut BufferRegistry) {
        reg.register(
            "hcb.incomplete",
            BufferKind::Data,
            "HCB cache (Nguyen §5.2): 1 on the incomplete texels — where the cached samples' splatted weight Σw is below the threshold — that get new samples; 0 elsewhere",
            &self.incomplete,
        );
        reg.register(
            "hcb.cache",
            BufferKind::Data,
            "HCB cache (Nguyen §5.1–5.2): 1 at a reused cached sample, 2 at a new sample, 3 inside the removal quad of an invalid cached sample (its surplus neighbours went with it)",
            &self.cache,
        );
        reg.register(
            "hcb.recompute_group",
            BufferKind::Data,
            "HCB cache (Nguyen §5.3, Fig. 8b): each sample's recompute phase + 1 from the randomized 4×4 index pattern; a sample's light is gathered again when its counter reaches the period",
            &self.recompute_group,
        );
    }

    /// The views [`HcbPass::run`] needs to build over the supplementary G-buffer.
    pub fn views(&self) -> (wgpu::TextureView, wgpu::TextureView, wgpu::TextureView) {
        (
            crate::passes::view(&self.incomplete, "hcb.incomplete"),
            crate::passes::view(&self.cache, "hcb.cache"),
            crate::passes::view(&self.recompute_group, "hcb.recompute_group"),
        )
    }

    /// §5.1 "updating cache": validates the cached samples in the current view, removes the
    /// invalid and surplus ones, and appends the survivors (reprojected, their recompute
    /// counter advanced) to `hcb`'s emptied list; marks them in `hcb.samples`, `hcb.cache`
    /// and `hcb.recompute_group`.
    pub fn update(
        &self,
        r: PassRec<'_, '_>,
        camera: &wgpu::Buffer,
        g: (&wgpu::TextureView, &wgpu::TextureView),
        hcb: &HcbPass,
        f: CacheFrame,
    ) {
        let PassRec { ctx, enc: encoder, slot } = r;
        let p = CacheParams {
            limits: Vec4::new(
                f.max_distance,
                f.max_normal_deg.to_radians().cos(),
                f.quad_px.max(1) as f32,
                f.period.clamp(1, 16) as f32,
            ),
        };
        ctx.queue.upload(&self.params, 0, bytemuck::bytes_of(&p));
        let (_, cache_view, group_view) = self.views();
        encoder.counted_clear_buffer(&hcb.counter, 0, None);
        hcb.clear_marks(ctx, encoder, &group_view);
        let samples_view = crate::passes::view(&hcb.samples, "hcb.samples");
        let tv = wgpu::BindingResource::TextureView;
        let group = CACHE_INPUTS_BINDINGS.group(
            &ctx.device,
            &self.layout,
            [
                camera.as_entire_binding(),
                self.params.as_entire_binding(),
                self.prev_counter.as_entire_binding(),
                self.prev_list.as_entire_binding(),
                tv(g.0),
                tv(g.1),
                hcb.counter.as_entire_binding(),
                hcb.list.as_entire_binding(),
                tv(&cache_view),
                tv(&samples_view),
                tv(&group_view),
                self.queue.as_entire_binding(),
            ],
        );
        let args_group = CACHE_ARGS_BINDINGS.group(&ctx.device, &self.args_layout, [self.args.as_entire_binding()]);
        let removal_group = CACHE_REMOVAL_INPUTS_BINDINGS.group(
            &ctx.device,
            &self.removal_layout,
            [camera.as_entire_binding(), self.params.as_entire_binding(), self.prev_list.as_entire_binding()],
        );
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("hcb.cache.args"),
                timestamp_writes: slot.and_then(|s| s.compute(true, false)),
            });
            pass.set_pipe(&self.args_pipeline);
            pass.set_group(0, &group, &[]);
            pass.set_group(1, &args_group, &[]);
            pass.dispatch(1, 1, 1);
        }
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("hcb.cache.validate"),
                timestamp_writes: None,
            });
            pass.set_pipe(&self.validate_pipeline);
            pass.set_group(0, &group, &[]);
            pass.dispatch_indirect(&self.args, 16);
        }
        {
            let cache = crate::passes::view(&self.cache, "hcb.cache");
            let depth = crate::passes::view(&self.depth, "hcb.cache.depth");
            let mut pass = encoder.begin_counted_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("hcb.cache.removal"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &cache,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &depth,
                    depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(1.0), store: wgpu::StoreOp::Discard }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipe(&self.removal_pipeline);
            pass.set_group(0, &removal_group, &[]);
            pass.draw_indirect_counted(&self.args, 0);
        }
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("hcb.cache.compact"),
            timestamp_writes: slot.and_then(|s| s.compute(false, true)),
        });
        pass.set_pipe(&self.compact_pipeline);
        pass.set_group(0, &group, &[]);
        pass.dispatch_indirect(&self.args, 16);
    }
}

/// The views of `cache` for [`HcbPass::run`] with `weight_sum` the cached samples' splat.
pub fn cache_views<'a>(
    weight_sum: &'a wgpu::TextureView,
    views: &'a (wgpu::TextureView, wgpu::TextureView, wgpu::TextureView),
) -> CacheViews<'a> {
    CacheViews { weight_sum, incomplete: &views.0, cache: &views.1, recompute_group: &views.2 }
}
