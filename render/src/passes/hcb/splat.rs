//! Stage 6 of the HCB (Nguyen et al. §4.2–4.3): coherence-weighted splatting and Eq. 11.

use std::cell::Cell;

use crate::counters::prelude::*;

use super::{HcbFrame, HcbParams};
use crate::buffers::{BufferKind, BufferRegistry};
use crate::gpu::GpuContext;
use crate::gpu::bindings::{Bindings, Kind, binding};
use crate::passes::bins::{Bins, SplatMethod};
use crate::timing::PassRec;
use crate::timing::Slot;

/// Bind group `hcb.splat.inputs` of `shaders/hcb/splat.wgsl` (group 0 of the blended quads,
/// `vs_splat` and `fs_splat`; Nguyen 000 §4.2's coherence-weighted splatting).
pub const SPLAT_INPUTS_BINDINGS: Bindings = Bindings {
    label: "hcb.splat.inputs",
    shader: "hcb/splat.wgsl",
    group: 0,
    entry: Some("vs_splat+fs_splat"),
    visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
    list: &[
        binding(0, "camera", Kind::Uniform),
        binding(1, "hp", Kind::Uniform),
        binding(2, "samples", Kind::Storage { read_only: true }),
        binding(3, "g_position", Kind::Texture { filterable: false }),
        binding(4, "g_normal", Kind::Texture { filterable: false }),
        binding(5, "counter", Kind::Storage { read_only: true }),
    ],
};

/// Bind group `hcb.splat.binned` of `shaders/hcb/splat.wgsl` (group 0).
pub const SPLAT_BINNED_BINDINGS: Bindings = Bindings {
    label: "hcb.splat.binned",
    shader: "hcb/splat.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "camera", Kind::Uniform),
        binding(1, "hp", Kind::Uniform),
        binding(2, "samples", Kind::Storage { read_only: true }),
        binding(3, "g_position", Kind::Texture { filterable: false }),
        binding(4, "g_normal", Kind::Texture { filterable: false }),
        binding(5, "counter", Kind::Storage { read_only: true }),
        binding(6, "args", Kind::Storage { read_only: true }),
        binding(7, "prev_sum", Kind::Texture { filterable: false }),
        binding(8, "out_sum", Kind::StorageTexture(wgpu::TextureFormat::Rgba32Float)),
        binding(9, "rest", Kind::Storage { read_only: false }),
        binding(10, "prev_dir", Kind::Texture { filterable: false }),
        binding(11, "out_dir", Kind::StorageTexture(wgpu::TextureFormat::Rgba32Float)),
    ],
};

/// Bind group `hcb.normalize.inputs` of `shaders/hcb/normalize.wgsl` (group 0).
pub const NORMALIZE_INPUTS_BINDINGS: Bindings = Bindings {
    label: "hcb.normalize.inputs",
    shader: "hcb/normalize.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "accum", Kind::Texture { filterable: false }),
        binding(1, "g_normal", Kind::Texture { filterable: false }),
        binding(2, "out_light", Kind::StorageTexture(wgpu::TextureFormat::Rgba32Float)),
        binding(3, "uncovered", Kind::Storage { read_only: false }),
        binding(4, "g_albedo", Kind::Texture { filterable: false }),
        binding(5, "out_radiance", Kind::StorageTexture(wgpu::TextureFormat::Rgba32Float)),
        binding(6, "accum_dir", Kind::Texture { filterable: false }),
        binding(7, "g_position", Kind::Texture { filterable: false }),
        binding(8, "g_material", Kind::Texture { filterable: false }),
        binding(9, "hp", Kind::Uniform),
    ],
};

/// The G-buffer's position, normal, albedo and material views, as the splat and Eq. 11 read them.
pub type GViews<'a> = (&'a wgpu::TextureView, &'a wgpu::TextureView, &'a wgpu::TextureView, &'a wgpu::TextureView);

/// Stage 6 of the HCB (Nguyen et al. §4.2–4.3): the samples' coherence-weighted splats
/// (`hcb.weight_sum`: rgb Σ w E, a Σ w) and their normalisation (Eq. 11, `hcb.irradiance`;
/// a = 0 where a covered pixel got no weight, counted in `uncovered`), as blended quads (the
/// paper) or binned in compute (`passes::bins`). Shaders `shaders/hcb/{splat,normalize}.wgsl`.
pub struct HcbSplatPass {
    /// A ping-pong pair (the binned splat of the new samples adds to the other one's sums):
    /// `hcb.weight_sum` is `weight_sum[current]`.
    weight_sum: [wgpu::Texture; 2],
    /// Beside each of `weight_sum`: xyz Σ w·Σ lum(E_k) ω_k, the glossy receiver's direction
    /// sums (`hcb.weight_sum.direction`).
    weight_dir: [wgpu::Texture; 2],
    current: Cell<usize>,
    pub irradiance: wgpu::Texture,
    /// `hcb.indirect`: the indirect light the compose adds, c·DI/π × the splatted irradiance.
    pub indirect: wgpu::Texture,
    /// Covered pixels that no sample reached: the count (one u32 of four), then the first
    /// [`UNCOVERED_LIST`] of them as x | y << 16.
    pub uncovered: wgpu::Buffer,
    splat_layout: wgpu::BindGroupLayout,
    normalize_layout: wgpu::BindGroupLayout,
    splat_pipeline: wgpu::RenderPipeline,
    normalize_pipeline: wgpu::ComputePipeline,
    /// Binned: bind group 0 of `bin` and `accumulate`, the bins, the remainder's draw.
    binned_layout: wgpu::BindGroupLayout,
    bin: wgpu::ComputePipeline,
    accumulate: wgpu::ComputePipeline,
    bins: Bins,
    rest: wgpu::Buffer,
    /// The uniforms of the splat of every sample and of the new samples only (§5.2).
    params: [wgpu::Buffer; 2],
    width: u32,
    height: u32,
}

/// Most uncovered pixels `hcb/normalize.wgsl` lists (the count goes on).
pub const UNCOVERED_LIST: u32 = 65536;
/// Bytes of [`HcbSplatPass::uncovered`].
pub const UNCOVERED_BYTES: u64 = 16 + UNCOVERED_LIST as u64 * 4;

/// Format of `hcb.weight_sum` (additive blending of f32 needs FLOAT32_BLENDABLE, which the
/// renderer requires).
const ACCUM_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

impl HcbSplatPass {
    pub fn new(ctx: &GpuContext, width: u32, height: u32) -> Self {
        let device = &ctx.device;
        let splat_layout = SPLAT_INPUTS_BINDINGS.layout(device);
        let normalize_layout = NORMALIZE_INPUTS_BINDINGS.layout(device);
        let m_splat = crate::shaders::create_module(device, "hcb/splat.wgsl");
        let m_norm = crate::shaders::create_module(device, "hcb/normalize.wgsl");
        let pl = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("hcb.splat.pipeline_layout"),
            bind_group_layouts: &[Some(&splat_layout)],
            immediate_size: 0,
        });
        let add = wgpu::BlendComponent {
            src_factor: wgpu::BlendFactor::One,
            dst_factor: wgpu::BlendFactor::One,
            operation: wgpu::BlendOperation::Add,
        };
        let splat_pipeline = device.counted_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("hcb.splat"),
            layout: Some(&pl),
            vertex: wgpu::VertexState {
                module: &m_splat,
                entry_point: Some("vs_splat"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: Default::default(),
            depth_stencil: None,
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &m_splat,
                entry_point: Some("fs_splat"),
                compilation_options: Default::default(),
                targets: &[
                    Some(wgpu::ColorTargetState {
                        format: ACCUM_FORMAT,
                        blend: Some(wgpu::BlendState { color: add, alpha: add }),
                        write_mask: wgpu::ColorWrites::ALL,
                    }),
                    Some(wgpu::ColorTargetState {
                        format: ACCUM_FORMAT,
                        blend: Some(wgpu::BlendState { color: add, alpha: add }),
                        write_mask: wgpu::ColorWrites::ALL,
                    }),
                ],
            }),
            multiview_mask: None,
            cache: None,
        });
        let normalize_pipeline =
            crate::passes::compute_pipeline(device, "hcb.normalize", &m_norm, "cs_normalize", &[&normalize_layout]);
        let binned_layout = SPLAT_BINNED_BINDINGS.layout(device);
        let mut bins = Bins::new(ctx, "hcb.splat.bins");
        bins.ensure(ctx, width, height, width.max(1) * height.max(1));
        let layouts = [&binned_layout, bins.layout()];
        let bin = crate::passes::compute_pipeline(device, "hcb.splat.bin", &m_splat, "cs_bin", &layouts);
        let accumulate =
            crate::passes::compute_pipeline(device, "hcb.splat.accumulate", &m_splat, "cs_accumulate", &layouts);
        let rest = crate::passes::buffer(
            device,
            "hcb.splat.rest",
            16,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::INDIRECT,
        );
        let size = std::mem::size_of::<HcbParams>() as u64;
        let params = [
            crate::passes::uniform_buffer(device, "hcb.splat.params", size),
            crate::passes::uniform_buffer(device, "hcb.splat.new.params", size),
        ];
        let uncovered = crate::passes::buffer(
            device,
            "hcb.uncovered",
            UNCOVERED_BYTES,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
        );
        let (weight_sum, weight_dir, irradiance, indirect) = Self::targets(device, width, height);
        Self {
            weight_sum,
            weight_dir,
            current: Cell::new(0),
            irradiance,
            indirect,
            uncovered,
            splat_layout,
            normalize_layout,
            splat_pipeline,
            normalize_pipeline,
            binned_layout,
            bin,
            accumulate,
            bins,
            rest,
            params,
            width,
            height,
        }
    }

    #[allow(clippy::type_complexity)]
    fn targets(
        device: &wgpu::Device,
        width: u32,
        height: u32,
    ) -> ([wgpu::Texture; 2], [wgpu::Texture; 2], wgpu::Texture, wgpu::Texture) {
        let (w, h) = (width.max(1), height.max(1));
        // Blend draws into them, Binned writes them.
        let usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::STORAGE_BINDING;
        let weight_sum = [
            crate::passes::create_target(device, "hcb.weight_sum", w, h, ACCUM_FORMAT, usage),
            crate::passes::create_target(device, "hcb.weight_sum", w, h, ACCUM_FORMAT, usage),
        ];
        let weight_dir = [
            crate::passes::create_target(device, "hcb.weight_sum.direction", w, h, ACCUM_FORMAT, usage),
            crate::passes::create_target(device, "hcb.weight_sum.direction", w, h, ACCUM_FORMAT, usage),
        ];
        let storage = wgpu::TextureUsages::STORAGE_BINDING;
        let irradiance =
            crate::passes::create_target(device, "hcb.irradiance", w, h, wgpu::TextureFormat::Rgba32Float, storage);
        let indirect =
            crate::passes::create_target(device, "hcb.indirect", w, h, wgpu::TextureFormat::Rgba32Float, storage);
        (weight_sum, weight_dir, irradiance, indirect)
    }

    /// Resizes the targets. Returns whether they were recreated.
    pub fn ensure(&mut self, ctx: &GpuContext, width: u32, height: u32) -> bool {
        if (self.width, self.height) == (width, height) {
            return false;
        }
        (self.weight_sum, self.weight_dir, self.irradiance, self.indirect) = Self::targets(&ctx.device, width, height);
        self.current.set(0);
        self.bins.ensure(ctx, width, height, width.max(1) * height.max(1));
        (self.width, self.height) = (width, height);
        true
    }

    /// Registers the latest sums of the ping-pong pair (after each frame's splats).
    pub fn register_sums(&self, reg: &mut BufferRegistry) {
        reg.register(
            "hcb.weight_sum",
            BufferKind::Data,
            "HCB splatting (Nguyen §4.3): rgb Σ w·E and a Σ w over the samples coherent to each pixel (Eq. 10)",
            &self.weight_sum[self.current.get()],
        );
        reg.register(
            "hcb.weight_sum.direction",
            BufferKind::Data,
            "HCB splatting, the glossy receiver's direction sums (issue #51): xyz Σ w·Σ lum(E_k) ω_k over the samples coherent to each pixel",
            &self.weight_dir[self.current.get()],
        );
    }

    /// The texture of the latest direction sums (`hcb.weight_sum.direction`).
    pub fn weight_dir(&self) -> &wgpu::Texture {
        &self.weight_dir[self.current.get()]
    }

    /// The texture of the latest sums.
    pub fn weight_sum(&self) -> &wgpu::Texture {
        &self.weight_sum[self.current.get()]
    }

    /// Bins at most `items` samples (at least 32), drawing the rest as quads after them:
    /// for tests of the remainder, which otherwise needs more than 65,536 samples.
    pub fn limit_bins(&mut self, ctx: &GpuContext, items: u32) {
        self.bins.ensure(ctx, self.width, self.height, items.min(self.width.max(1) * self.height.max(1)));
    }

    /// The latest sums (`hcb.weight_sum`), as the cache's build reads them.
    pub fn weight_sum_view(&self) -> wgpu::TextureView {
        crate::passes::view(&self.weight_sum[self.current.get()], "hcb.weight_sum")
    }

    pub fn register(&self, reg: &mut BufferRegistry) {
        self.register_sums(reg);
        reg.register(
            "hcb.irradiance",
            BufferKind::Data,
            "HCB splatted light (Nguyen Eq. 11): Σ w·E / Σ w; a = 1 where a sample reached the pixel, 0 on covered pixels none reached",
            &self.irradiance,
        );
        reg.register(
            "hcb.indirect",
            BufferKind::Hdr,
            "HCB indirect light: each pixel's reflection of the splatted irradiance (c·DI/π, and the specular lobe from its mean direction with hcb.receiver = Glossy); a = 0 where no sample reached it",
            &self.indirect,
        );
    }

    /// Splats the samples of `list` (instance count from `draw_args`, a `DrawIndirectArgs`
    /// with 6 vertices) over the G-buffer and normalises.
    pub fn run(
        &self,
        r: PassRec<'_, '_>,
        camera: &wgpu::Buffer,
        g: GViews<'_>,
        samples: (&wgpu::Buffer, &wgpu::Buffer),
        draw_args: &wgpu::Buffer,
        (f, method): (HcbFrame, SplatMethod),
    ) {
        let PassRec { ctx, enc: encoder, slot } = r;
        self.splat(
            PassRec { ctx, enc: encoder, slot },
            camera,
            g,
            (samples, (draw_args, 0)),
            (false, false),
            (f, method),
        );
        self.normalize(ctx, encoder, slot, g);
    }

    /// Adds the splats of the samples of `samples` = (list, counter) to `hcb.weight_sum`
    /// (instance count from `draw_args` = (buffer, offset of a `DrawIndirectArgs`): 0 for
    /// every sample, 32 for the new ones): all of them onto zero sums, or with `new_only` the
    /// ones after the cached samples (counter word 1, §5.2) onto what the cached ones left.
    /// `slot`'s scope begins here and ends here with `ends_scope`, else with
    /// [`Self::normalize`]. `f` and `method`: the frame's HCB parameters and the splatting's
    /// implementation.
    pub fn splat(
        &self,
        r: PassRec<'_, '_>,
        camera: &wgpu::Buffer,
        g: GViews<'_>,
        (samples, draw_args): ((&wgpu::Buffer, &wgpu::Buffer), (&wgpu::Buffer, u64)),
        (new_only, ends_scope): (bool, bool),
        (f, method): (HcbFrame, SplatMethod),
    ) {
        let PassRec { ctx, enc: encoder, slot } = r;
        let params = &self.params[new_only as usize];
        ctx.queue.upload(params, 0, bytemuck::bytes_of(&f.params([new_only as u32, 0, 0, 0])));
        let tv = wgpu::BindingResource::TextureView;
        let inputs = [
            camera.as_entire_binding(),
            params.as_entire_binding(),
            samples.0.as_entire_binding(),
            tv(g.0),
            tv(g.1),
            samples.1.as_entire_binding(),
        ];
        let group = SPLAT_INPUTS_BINDINGS.group(&ctx.device, &self.splat_layout, inputs.clone());
        if method.on(ctx) == SplatMethod::Blend {
            if !new_only {
                self.current.set(0);
            }
            let load = if new_only { wgpu::LoadOp::Load } else { wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT) };
            let timestamps = slot.as_ref().and_then(|s| s.render(true, ends_scope));
            self.quads(encoder, &group, load, timestamps, draw_args);
            return;
        }
        let (src, dst) = if new_only { (self.current.get(), 1 - self.current.get()) } else { (1, 0) };
        let prev = crate::passes::view(&self.weight_sum[src], "hcb.weight_sum");
        let out = crate::passes::view(&self.weight_sum[dst], "hcb.weight_sum");
        let prev_dir = crate::passes::view(&self.weight_dir[src], "hcb.weight_sum.direction");
        let out_dir = crate::passes::view(&self.weight_dir[dst], "hcb.weight_sum.direction");
        let binned = SPLAT_BINNED_BINDINGS.group(
            &ctx.device,
            &self.binned_layout,
            inputs.into_iter().chain([
                draw_args.0.as_entire_binding(),
                tv(&prev),
                tv(&out),
                self.rest.as_entire_binding(),
                tv(&prev_dir),
                tv(&out_dir),
            ]),
        );
        // Samples beyond the bins (more than 65,536 at this size): their quads after them.
        let remainder = self.width as u64 * self.height as u64 > self.bins.capacity() as u64;
        let timestamps = slot.as_ref().and_then(|s| s.compute(true, ends_scope && !remainder));
        let pipelines = (&self.bin, &self.accumulate);
        let size = (self.width, self.height);
        let job = crate::passes::bins::SplatJob { pipelines, group: &binned, add: new_only, size };
        self.bins.splat(ctx, encoder, ("hcb.splat", timestamps), &job);
        self.current.set(dst);
        if remainder {
            let timestamps = slot.as_ref().and_then(|s| s.render(false, ends_scope));
            self.quads(encoder, &group, wgpu::LoadOp::Load, timestamps, (&self.rest, 0));
        }
    }

    /// Blend: the quads of `args` added into the latest sums.
    fn quads(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        group: &wgpu::BindGroup,
        load: wgpu::LoadOp<wgpu::Color>,
        timestamp_writes: Option<wgpu::RenderPassTimestampWrites<'_>>,
        args: (&wgpu::Buffer, u64),
    ) {
        let accum = crate::passes::view(&self.weight_sum[self.current.get()], "hcb.weight_sum");
        let dir = crate::passes::view(&self.weight_dir[self.current.get()], "hcb.weight_sum.direction");
        let attachment = |view| {
            Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations { load, store: wgpu::StoreOp::Store },
            })
        };
        let mut pass = encoder.begin_counted_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("hcb.splat"),
            color_attachments: &[attachment(&accum), attachment(&dir)],
            depth_stencil_attachment: None,
            timestamp_writes,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipe(&self.splat_pipeline);
        pass.set_group(0, group, &[]);
        pass.draw_indirect_counted(args.0, args.1);
    }

    /// Eq. 11 over `hcb.weight_sum`: `hcb.irradiance`, `hcb.indirect` and the uncovered count
    /// (ends `slot`'s scope).
    pub fn normalize(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        slot: Option<Slot<'_>>,
        g: GViews<'_>,
    ) {
        let tv = wgpu::BindingResource::TextureView;
        let accum = crate::passes::view(&self.weight_sum[self.current.get()], "hcb.weight_sum");
        let accum_dir = crate::passes::view(&self.weight_dir[self.current.get()], "hcb.weight_sum.direction");
        let out = crate::passes::view(&self.irradiance, "hcb.irradiance");
        let radiance = crate::passes::view(&self.indirect, "hcb.indirect");
        let ngroup = NORMALIZE_INPUTS_BINDINGS.group(
            &ctx.device,
            &self.normalize_layout,
            [
                tv(&accum),
                tv(g.1),
                tv(&out),
                self.uncovered.as_entire_binding(),
                tv(g.2),
                tv(&radiance),
                tv(&accum_dir),
                tv(g.0),
                tv(g.3),
                self.params[0].as_entire_binding(),
            ],
        );
        // The count only: the list is written up to it.
        encoder.counted_clear_buffer(&self.uncovered, 0, Some(16));
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("hcb.normalize"),
            timestamp_writes: slot.and_then(|s| s.compute(false, true)),
        });
        pass.set_pipe(&self.normalize_pipeline);
        pass.set_group(0, &ngroup, &[]);
        pass.dispatch(self.width.div_ceil(8), self.height.div_ceil(8), 1);
    }
}
