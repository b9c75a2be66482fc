//! Irradiance splatting and its resolve (Gautron et al. 003, "From Octree to Splatting":
//! "Principle"): each record's bounding quad, Ward's weight per covered pixel, RGB = w·E and
//! A = w added by the blending (`GL_ONE, GL_ONE` in the text) into float targets, then
//! E = RGB / A and the diffuse reflection c·DI·E/π. Shaders `gautron/splat.wgsl`,
//! `gautron/resolve.wgsl`; twin `cpu::gautron::{sphere_ndc_rect, accumulate}`.

use crate::counters::prelude::*;

use crate::buffers::{BufferKind, BufferRegistry};
use crate::gpu::GpuContext;
use crate::passes::gbuffer::GBufferViews;
use crate::passes::{bgl, bind_group, create_target, view};

pub const ACCUM_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

pub struct SplatPass {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    resolve: wgpu::ComputePipeline,
    resolve_layout: wgpu::BindGroupLayout,
    /// Σ w·E (rgb, with the gradients as set) and Σ w (a): `gautron.accum`.
    pub accum: wgpu::Texture,
    /// The same without any gradient: `gautron.accum.plain`.
    pub accum_plain: wgpu::Texture,
    /// The reflected indirect light the compose adds: `gautron.indirect`.
    pub indirect: wgpu::Texture,
    /// E = RGB / A (a: the coverage Σ w): `gautron.irradiance`.
    pub irradiance: wgpu::Texture,
    /// E without gradients: `gautron.irradiance.plain`.
    pub plain: wgpu::Texture,
    views: [wgpu::TextureView; 5],
}

impl SplatPass {
    pub fn new(ctx: &GpuContext, width: u32, height: u32) -> Self {
        let device = &ctx.device;
        let module = crate::shaders::create_module(device, "gautron/splat.wgsl");
        let vf = wgpu::ShaderStages::VERTEX_FRAGMENT;
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("gautron.splat"),
            entries: &[
                bgl::uniform(0, vf),
                bgl::uniform(1, vf),
                bgl::storage(2, vf, true),
                bgl::texture(3, wgpu::ShaderStages::FRAGMENT, false),
                bgl::texture(4, wgpu::ShaderStages::FRAGMENT, false),
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("gautron.splat.layout"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let additive = wgpu::BlendComponent {
            src_factor: wgpu::BlendFactor::One,
            dst_factor: wgpu::BlendFactor::One,
            operation: wgpu::BlendOperation::Add,
        };
        let target = Some(wgpu::ColorTargetState {
            format: ACCUM_FORMAT,
            blend: Some(wgpu::BlendState { color: additive, alpha: additive }),
            write_mask: wgpu::ColorWrites::ALL,
        });
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("gautron.splat.pipeline"),
            layout: Some(&pipeline_layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_splat"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: None,
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs_splat"),
                compilation_options: Default::default(),
                targets: &[target.clone(), target],
            }),
            multiview_mask: None,
            cache: None,
        });
        let cs = wgpu::ShaderStages::COMPUTE;
        let resolve_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("gautron.resolve"),
            entries: &[
                bgl::texture(0, cs, false),
                bgl::texture(1, cs, false),
                bgl::texture(2, cs, false),
                bgl::storage_texture(3, ACCUM_FORMAT),
                bgl::storage_texture(4, ACCUM_FORMAT),
                bgl::storage_texture(5, ACCUM_FORMAT),
            ],
        });
        let resolve_module = crate::shaders::create_module(device, "gautron/resolve.wgsl");
        let resolve = crate::passes::compute_pipeline(
            device,
            "gautron.resolve",
            &resolve_module,
            "cs_resolve",
            &[&resolve_layout],
        );
        let (accum, accum_plain, indirect, irradiance, plain, views) = targets(device, width, height);
        Self { pipeline, layout, resolve, resolve_layout, accum, accum_plain, indirect, irradiance, plain, views }
    }

    /// Recreates the targets for a new size; true when it did.
    pub fn resize(&mut self, ctx: &GpuContext, width: u32, height: u32) -> bool {
        if (self.accum.width(), self.accum.height()) == (width, height) {
            return false;
        }
        let (a, ap, i, e, p, v) = targets(&ctx.device, width, height);
        (self.accum, self.accum_plain, self.indirect, self.irradiance, self.plain, self.views) = (a, ap, i, e, p, v);
        true
    }

    pub fn register(&self, reg: &mut BufferRegistry) {
        reg.register(
            "gautron.accum",
            BufferKind::Data,
            "the splat's sums: rgb = Σ w_k·E_k (extrapolated by the gradients as set), a = the coverage Σ w_k (a pixel is covered from 1/a up)",
            &self.accum,
        );
        reg.register(
            "gautron.accum.plain",
            BufferKind::Data,
            "the splat's sums without gradients: rgb = Σ w_k·E_k, a = Σ w_k",
            &self.accum_plain,
        );
        reg.register(
            "gautron.irradiance",
            BufferKind::Hdr,
            "the interpolated irradiance E = Σ w·E / Σ w with the gradients as set (W/m²; a: Σ w)",
            &self.irradiance,
        );
        reg.register(
            "gautron.irradiance.plain",
            BufferKind::Hdr,
            "the interpolated irradiance without any gradient (a: Σ w)",
            &self.plain,
        );
        reg.register(
            "gautron.indirect",
            BufferKind::Hdr,
            "indirect light reflected from the interpolated irradiance, c·DI·E/π",
            &self.indirect,
        );
    }

    /// Splats `instances` (the indirect draw in `args`: records first … first + count) into
    /// the accumulators, clearing them first when `clear`.
    #[allow(clippy::too_many_arguments)]
    pub fn splat(
        &self,
        ctx: &GpuContext,
        enc: &mut wgpu::CommandEncoder,
        slot: Option<crate::timing::Slot<'_>>,
        clear: bool,
        params: &wgpu::Buffer,
        camera: &wgpu::Buffer,
        records: &wgpu::Buffer,
        g: &GBufferViews,
        args: &wgpu::Buffer,
    ) {
        let tv = wgpu::BindingResource::TextureView;
        let group = bind_group(
            &ctx.device,
            "gautron.splat",
            &self.layout,
            vec![
                params.as_entire_binding(),
                camera.as_entire_binding(),
                records.as_entire_binding(),
                tv(&g.position),
                tv(&g.normal),
            ],
        );
        let load = if clear { wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT) } else { wgpu::LoadOp::Load };
        let att = |view| {
            Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations { load, store: wgpu::StoreOp::Store },
            })
        };
        let mut pass = enc.begin_counted_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("gautron.splat.pass"),
            color_attachments: &[att(&self.views[0]), att(&self.views[1])],
            depth_stencil_attachment: None,
            timestamp_writes: slot.and_then(|s| s.render(true, true)),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_group(0, &group, &[]);
        pass.draw_indirect(args, 0);
    }

    /// E = RGB / A and the reflected indirect light.
    pub fn resolve(
        &self,
        ctx: &GpuContext,
        enc: &mut wgpu::CommandEncoder,
        slot: Option<crate::timing::Slot<'_>>,
        albedo: &wgpu::TextureView,
    ) {
        let tv = wgpu::BindingResource::TextureView;
        let v = &self.views;
        let group = bind_group(
            &ctx.device,
            "gautron.resolve",
            &self.resolve_layout,
            vec![tv(&v[0]), tv(&v[1]), tv(albedo), tv(&v[2]), tv(&v[3]), tv(&v[4])],
        );
        let size = (self.accum.width(), self.accum.height());
        crate::passes::dispatch_2d(
            enc,
            "gautron.resolve",
            &self.resolve,
            &group,
            &[],
            slot.and_then(|s| s.compute(true, true)),
            size,
        );
    }

    pub fn indirect_view(&self) -> wgpu::TextureView {
        view(&self.indirect, "gautron.indirect")
    }

    pub fn accum_view(&self) -> &wgpu::TextureView {
        &self.views[0]
    }
}

type Targets = (wgpu::Texture, wgpu::Texture, wgpu::Texture, wgpu::Texture, wgpu::Texture, [wgpu::TextureView; 5]);

fn targets(device: &wgpu::Device, width: u32, height: u32) -> Targets {
    let rt = wgpu::TextureUsages::RENDER_ATTACHMENT;
    let st = wgpu::TextureUsages::STORAGE_BINDING;
    let accum = create_target(device, "gautron.accum", width, height, ACCUM_FORMAT, rt);
    let accum_plain = create_target(device, "gautron.accum.plain", width, height, ACCUM_FORMAT, rt);
    let indirect = create_target(device, "gautron.indirect", width, height, ACCUM_FORMAT, st);
    let irradiance = create_target(device, "gautron.irradiance", width, height, ACCUM_FORMAT, st);
    let plain = create_target(device, "gautron.irradiance.plain", width, height, ACCUM_FORMAT, st);
    let views = [
        view(&accum, "gautron.accum"),
        view(&accum_plain, "gautron.accum.plain"),
        view(&indirect, "gautron.indirect"),
        view(&irradiance, "gautron.irradiance"),
        view(&plain, "gautron.irradiance.plain"),
    ];
    (accum, accum_plain, indirect, irradiance, plain, views)
}
