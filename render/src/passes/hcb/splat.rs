//! Stage 6 of the HCB (Nguyen et al. §4.2–4.3): coherence-weighted splatting and Eq. 11.

use crate::counters::prelude::*;

use super::{HcbFrame, HcbParams};
use crate::buffers::{BufferKind, BufferRegistry};
use crate::gpu::GpuContext;
use crate::passes::bgl;
use crate::timing::Slot;

/// Stage 6 of the HCB (Nguyen et al. §4.2–4.3): the samples' coherence-weighted splats
/// (`hcb.weight_sum`: rgb Σ w E, a Σ w) and their normalisation (Eq. 11, `hcb.irradiance`;
/// a = 0 where a covered pixel got no weight, counted in `uncovered`). Shaders
/// `shaders/hcb/{splat,normalize}.wgsl`.
pub struct HcbSplatPass {
    pub weight_sum: wgpu::Texture,
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
    pub fn new(ctx: &GpuContext, camera_entry: wgpu::BindGroupLayoutEntry, width: u32, height: u32) -> Self {
        let device = &ctx.device;
        let (vs, fs, cs) = (wgpu::ShaderStages::VERTEX, wgpu::ShaderStages::FRAGMENT, wgpu::ShaderStages::COMPUTE);
        let camera_entry = wgpu::BindGroupLayoutEntry { visibility: vs | fs, ..camera_entry };
        let splat_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("hcb.splat.inputs"),
            entries: &[
                camera_entry,
                bgl::uniform(1, vs | fs),
                bgl::storage(2, vs | fs, true),
                bgl::texture(3, fs, false),
                bgl::texture(4, fs, false),
                bgl::storage(5, vs, true),
            ],
        });
        let normalize_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("hcb.normalize.inputs"),
            entries: &[
                bgl::texture(0, cs, false),
                bgl::texture(1, cs, false),
                bgl::storage_texture(2, wgpu::TextureFormat::Rgba32Float),
                bgl::storage(3, cs, false),
                bgl::texture(4, cs, false),
                bgl::storage_texture(5, wgpu::TextureFormat::Rgba32Float),
            ],
        });
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
        let splat_pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
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
                targets: &[Some(wgpu::ColorTargetState {
                    format: ACCUM_FORMAT,
                    blend: Some(wgpu::BlendState { color: add, alpha: add }),
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            multiview_mask: None,
            cache: None,
        });
        let normalize_pipeline =
            crate::passes::compute_pipeline(device, "hcb.normalize", &m_norm, "cs_normalize", &[&normalize_layout]);
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
        let (weight_sum, irradiance, indirect) = Self::targets(device, width, height);
        Self {
            weight_sum,
            irradiance,
            indirect,
            uncovered,
            splat_layout,
            normalize_layout,
            splat_pipeline,
            normalize_pipeline,
            params,
            width,
            height,
        }
    }

    fn targets(device: &wgpu::Device, width: u32, height: u32) -> (wgpu::Texture, wgpu::Texture, wgpu::Texture) {
        let (w, h) = (width.max(1), height.max(1));
        let weight_sum = crate::passes::create_target(
            device,
            "hcb.weight_sum",
            w,
            h,
            ACCUM_FORMAT,
            wgpu::TextureUsages::RENDER_ATTACHMENT,
        );
        let storage = wgpu::TextureUsages::STORAGE_BINDING;
        let irradiance =
            crate::passes::create_target(device, "hcb.irradiance", w, h, wgpu::TextureFormat::Rgba32Float, storage);
        let indirect =
            crate::passes::create_target(device, "hcb.indirect", w, h, wgpu::TextureFormat::Rgba32Float, storage);
        (weight_sum, irradiance, indirect)
    }

    /// Resizes the targets. Returns whether they were recreated.
    pub fn ensure(&mut self, ctx: &GpuContext, width: u32, height: u32) -> bool {
        if (self.width, self.height) == (width, height) {
            return false;
        }
        (self.weight_sum, self.irradiance, self.indirect) = Self::targets(&ctx.device, width, height);
        (self.width, self.height) = (width, height);
        true
    }

    pub fn register(&self, reg: &mut BufferRegistry) {
        reg.register(
            "hcb.weight_sum",
            BufferKind::Data,
            "HCB splatting (Nguyen §4.3): rgb Σ w·E and a Σ w over the samples coherent to each pixel (Eq. 10)",
            &self.weight_sum,
        );
        reg.register(
            "hcb.irradiance",
            BufferKind::Data,
            "HCB splatted light (Nguyen Eq. 11): Σ w·E / Σ w; a = 1 where a sample reached the pixel, 0 on covered pixels none reached",
            &self.irradiance,
        );
        reg.register(
            "hcb.indirect",
            BufferKind::Hdr,
            "HCB indirect light: each pixel's diffuse reflection c·DI/π of the splatted irradiance; a = 0 where no sample reached it",
            &self.indirect,
        );
    }

    /// Splats the samples of `list` (instance count from `draw_args`, a `DrawIndirectArgs`
    /// with 6 vertices) over the G-buffer and normalises.
    #[allow(clippy::too_many_arguments)]
    pub fn run(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        slot: Option<Slot<'_>>,
        camera: &wgpu::Buffer,
        g: (&wgpu::TextureView, &wgpu::TextureView, &wgpu::TextureView),
        samples: (&wgpu::Buffer, &wgpu::Buffer),
        draw_args: &wgpu::Buffer,
        f: HcbFrame,
    ) {
        self.splat(ctx, encoder, slot, camera, g, samples, (draw_args, 0), false, false, f);
        self.normalize(ctx, encoder, slot, g);
    }

    /// Adds the splats of the samples of `samples` = (list, counter) to `hcb.weight_sum`
    /// (instance count from `draw_args` = (buffer, offset of a `DrawIndirectArgs`)): all of
    /// them onto a cleared target, or with `new_only` the ones after the cached samples
    /// (counter word 1, §5.2) onto what the cached ones left. `slot`'s scope begins here and
    /// ends here with `ends_scope`, else with [`Self::normalize`].
    #[allow(clippy::too_many_arguments)]
    pub fn splat(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        slot: Option<Slot<'_>>,
        camera: &wgpu::Buffer,
        g: (&wgpu::TextureView, &wgpu::TextureView, &wgpu::TextureView),
        samples: (&wgpu::Buffer, &wgpu::Buffer),
        draw_args: (&wgpu::Buffer, u64),
        new_only: bool,
        ends_scope: bool,
        f: HcbFrame,
    ) {
        let params = &self.params[new_only as usize];
        ctx.queue.write_buffer(params, 0, bytemuck::bytes_of(&f.params([new_only as u32, 0, 0, 0])));
        let tv = wgpu::BindingResource::TextureView;
        let group = ctx.device.counted_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("hcb.splat.inputs"),
            layout: &self.splat_layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: camera.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: params.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 2, resource: samples.0.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 3, resource: tv(g.0) },
                wgpu::BindGroupEntry { binding: 4, resource: tv(g.1) },
                wgpu::BindGroupEntry { binding: 5, resource: samples.1.as_entire_binding() },
            ],
        });
        let accum = crate::passes::view(&self.weight_sum, "hcb.weight_sum");
        let load = if new_only { wgpu::LoadOp::Load } else { wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT) };
        let mut pass = encoder.begin_counted_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("hcb.splat"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &accum,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations { load, store: wgpu::StoreOp::Store },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: slot.as_ref().and_then(|s| s.render(true, ends_scope)),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.splat_pipeline);
        pass.set_group(0, &group, &[]);
        pass.draw_indirect(draw_args.0, draw_args.1);
    }

    /// Eq. 11 over `hcb.weight_sum`: `hcb.irradiance`, `hcb.indirect` and the uncovered count
    /// (ends `slot`'s scope).
    pub fn normalize(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        slot: Option<Slot<'_>>,
        g: (&wgpu::TextureView, &wgpu::TextureView, &wgpu::TextureView),
    ) {
        let tv = wgpu::BindingResource::TextureView;
        let accum = crate::passes::view(&self.weight_sum, "hcb.weight_sum");
        let out = crate::passes::view(&self.irradiance, "hcb.irradiance");
        let radiance = crate::passes::view(&self.indirect, "hcb.indirect");
        let ngroup = ctx.device.counted_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("hcb.normalize.inputs"),
            layout: &self.normalize_layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: tv(&accum) },
                wgpu::BindGroupEntry { binding: 1, resource: tv(g.1) },
                wgpu::BindGroupEntry { binding: 2, resource: tv(&out) },
                wgpu::BindGroupEntry { binding: 3, resource: self.uncovered.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 4, resource: tv(g.2) },
                wgpu::BindGroupEntry { binding: 5, resource: tv(&radiance) },
            ],
        });
        // The count only: the list is written up to it.
        encoder.clear_buffer(&self.uncovered, 0, Some(16));
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("hcb.normalize"),
            timestamp_writes: slot.and_then(|s| s.compute(false, true)),
        });
        pass.set_pipeline(&self.normalize_pipeline);
        pass.set_group(0, &ngroup, &[]);
        pass.dispatch_workgroups(self.width.div_ceil(8), self.height.div_ceil(8), 1);
    }
}
