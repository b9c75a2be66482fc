//! Irradiance splatting and its resolve (Gautron et al. 003, "From Octree to Splatting":
//! "Principle"): each record's bounding rectangle, Ward's weight per covered pixel, RGB = w·E
//! and A = w added into float targets (the text's additive blending, or binned into 64-pixel
//! squares and summed per pixel in compute, in the blending's order: `passes::bins`), then
//! E = RGB / A and the diffuse reflection c·DI·E/π. Shaders `gautron/splat.wgsl`,
//! `gautron/resolve.wgsl`; twin `cpu::gautron::{sphere_ndc_rect, accumulate}`.

use std::cell::Cell;

use crate::counters::prelude::*;

use crate::buffers::{BufferKind, BufferRegistry};
use crate::gpu::GpuContext;
use crate::gpu::bindings::{Bindings, Kind, binding};
use crate::passes::bins::{Bins, SplatMethod};
use crate::passes::gbuffer::GBufferViews;
use crate::passes::{create_target, view};
use crate::timing::PassRec;

/// Bind group `gautron.splat` of `shaders/gautron/splat.wgsl` (group 0 of the binned splat,
/// `cs_bin` and `cs_accumulate`).
pub const SPLAT_BINDINGS: Bindings = Bindings {
    label: "gautron.splat",
    shader: "gautron/splat.wgsl",
    group: 0,
    entry: Some("cs_bin+cs_accumulate"),
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "params", Kind::Uniform),
        binding(1, "camera", Kind::Uniform),
        binding(2, "records", Kind::Storage { read_only: true }),
        binding(3, "g_position", Kind::Texture { filterable: false }),
        binding(4, "g_normal", Kind::Texture { filterable: false }),
        binding(5, "args", Kind::Storage { read_only: true }),
        binding(6, "prev_weighted", Kind::Texture { filterable: false }),
        binding(7, "prev_plain", Kind::Texture { filterable: false }),
        binding(8, "out_weighted", Kind::StorageTexture(wgpu::TextureFormat::Rgba32Float)),
        binding(9, "out_plain", Kind::StorageTexture(wgpu::TextureFormat::Rgba32Float)),
        binding(10, "prev_dir", Kind::Texture { filterable: false }),
        binding(11, "out_dir", Kind::StorageTexture(wgpu::TextureFormat::Rgba32Float)),
    ],
};

/// Bind group `gautron.splat.blend` of `shaders/gautron/splat.wgsl` (group 0 of the blended
/// quads, `vs_splat` and `fs_splat`).
pub const SPLAT_BLEND_BINDINGS: Bindings = Bindings {
    label: "gautron.splat.blend",
    shader: "gautron/splat.wgsl",
    group: 0,
    entry: Some("vs_splat+fs_splat"),
    visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
    list: &[
        binding(0, "params", Kind::Uniform),
        binding(1, "camera", Kind::Uniform),
        binding(2, "records", Kind::Storage { read_only: true }),
        binding(3, "g_position", Kind::Texture { filterable: false }),
        binding(4, "g_normal", Kind::Texture { filterable: false }),
    ],
};

/// Bind group `gautron.resolve` of `shaders/gautron/resolve.wgsl` (group 0).
pub const RESOLVE_BINDINGS: Bindings = Bindings {
    label: "gautron.resolve",
    shader: "gautron/resolve.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "accum", Kind::Texture { filterable: false }),
        binding(1, "accum_plain", Kind::Texture { filterable: false }),
        binding(2, "g_albedo", Kind::Texture { filterable: false }),
        binding(3, "out_indirect", Kind::StorageTexture(wgpu::TextureFormat::Rgba32Float)),
        binding(4, "out_irradiance", Kind::StorageTexture(wgpu::TextureFormat::Rgba32Float)),
        binding(5, "out_plain", Kind::StorageTexture(wgpu::TextureFormat::Rgba32Float)),
        binding(6, "accum_dir", Kind::Texture { filterable: false }),
        binding(7, "g_position", Kind::Texture { filterable: false }),
        binding(8, "g_normal", Kind::Texture { filterable: false }),
        binding(9, "g_material", Kind::Texture { filterable: false }),
        binding(10, "params", Kind::Uniform),
        binding(11, "camera", Kind::Uniform),
    ],
};

pub const ACCUM_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

pub struct SplatPass {
    /// Blend: one quad per record.
    raster: wgpu::RenderPipeline,
    raster_layout: wgpu::BindGroupLayout,
    /// Binned: the bins, then the sums.
    bin: wgpu::ComputePipeline,
    accumulate: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    bins: Bins,
    /// Records the bins are sized for.
    capacity: u32,
    resolve: wgpu::ComputePipeline,
    resolve_layout: wgpu::BindGroupLayout,
    /// Σ w·E (rgb, with the gradients as set) and Σ w (a), a ping-pong pair:
    /// `gautron.accum` is `accum[current]`.
    accum: [wgpu::Texture; 2],
    /// The same without any gradient: `gautron.accum.plain`.
    accum_plain: [wgpu::Texture; 2],
    /// xyz Σ w·dir_k, the glossy receiver's direction sums: `gautron.accum.direction`.
    accum_dir: [wgpu::Texture; 2],
    /// Which of the pairs holds the latest sums.
    current: Cell<usize>,
    /// The reflected indirect light the compose adds: `gautron.indirect`.
    pub indirect: wgpu::Texture,
    /// E = RGB / A (a: the coverage Σ w): `gautron.irradiance`.
    pub irradiance: wgpu::Texture,
    /// E without gradients: `gautron.irradiance.plain`.
    pub plain: wgpu::Texture,
}

impl SplatPass {
    pub fn new(ctx: &GpuContext, width: u32, height: u32) -> Self {
        let device = &ctx.device;
        let module = crate::shaders::create_module(device, "gautron/splat.wgsl");
        let layout = SPLAT_BINDINGS.layout(device);
        let (raster, raster_layout) = raster_pipeline(device, &module);
        let bins = Bins::new(ctx, "gautron.splat.bins");
        let layouts = [&layout, bins.layout()];
        let bin = crate::passes::compute_pipeline(device, "gautron.splat.bin", &module, "cs_bin", &layouts);
        let accumulate =
            crate::passes::compute_pipeline(device, "gautron.splat.accumulate", &module, "cs_accumulate", &layouts);
        let resolve_layout = RESOLVE_BINDINGS.layout(device);
        let resolve_module = crate::shaders::create_module(device, "gautron/resolve.wgsl");
        let resolve = crate::passes::compute_pipeline(
            device,
            "gautron.resolve",
            &resolve_module,
            "cs_resolve",
            &[&resolve_layout],
        );
        let (accum, accum_plain, accum_dir, indirect, irradiance, plain) = targets(device, width, height);
        let mut pass = Self {
            raster,
            raster_layout,
            bin,
            accumulate,
            layout,
            bins,
            capacity: 1,
            resolve,
            resolve_layout,
            accum,
            accum_plain,
            accum_dir,
            current: Cell::new(0),
            indirect,
            irradiance,
            plain,
        };
        pass.ensure_bins(ctx, 1);
        pass
    }

    /// Recreates the targets for a new size; true when it did.
    pub fn resize(&mut self, ctx: &GpuContext, width: u32, height: u32) -> bool {
        if (self.accum[0].width(), self.accum[0].height()) == (width, height) {
            return false;
        }
        (self.accum, self.accum_plain, self.accum_dir, self.indirect, self.irradiance, self.plain) =
            targets(&ctx.device, width, height);
        self.current.set(0);
        self.bins.ensure(ctx, width, height, self.capacity);
        true
    }

    /// Sizes the bins for `capacity` records at the current size.
    pub fn ensure_bins(&mut self, ctx: &GpuContext, capacity: u32) {
        self.capacity = capacity.max(1);
        self.bins.ensure(ctx, self.accum[0].width(), self.accum[0].height(), self.capacity);
    }

    pub fn register(&self, reg: &mut BufferRegistry) {
        self.register_sums(reg);
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
            "indirect light reflected from the interpolated irradiance: c·DI·E/π, and the specular lobe from its mean direction with gautron.receiver = Glossy",
            &self.indirect,
        );
    }

    /// Registers the latest sums of the ping-pong pairs (after each frame's splats).
    pub fn register_sums(&self, reg: &mut BufferRegistry) {
        reg.register(
            "gautron.accum",
            BufferKind::Data,
            "the splat's sums: rgb = Σ w_k·E_k (extrapolated by the gradients as set), a = the coverage Σ w_k (a pixel is covered from 1/a up)",
            &self.accum[self.current.get()],
        );
        reg.register(
            "gautron.accum.plain",
            BufferKind::Data,
            "the splat's sums without gradients: rgb = Σ w_k·E_k, a = Σ w_k",
            &self.accum_plain[self.current.get()],
        );
        reg.register(
            "gautron.accum.direction",
            BufferKind::Data,
            "the splat's direction sums of the glossy receiver (issue #51): xyz = Σ w_k·Σ lum(L) cos θ Ω ω over record k's hemisphere",
            &self.accum_dir[self.current.get()],
        );
    }

    /// Splats the records the creation's draw arguments `args` name (first … first + count)
    /// into the accumulators: from zero when `clear`, else added to the latest sums (Binned
    /// writes them into the other texture of each pair, which becomes the latest).
    /// `buffers`: the stage's uniform, the camera and the records.
    pub fn splat(
        &self,
        r: PassRec<'_, '_>,
        (method, clear): (SplatMethod, bool),
        buffers: [&wgpu::Buffer; 3],
        g: &GBufferViews,
        args: &wgpu::Buffer,
    ) {
        let [params, camera, records] = buffers;
        let PassRec { ctx, enc, slot } = r;
        let tv = wgpu::BindingResource::TextureView;
        if method.on(ctx) == SplatMethod::Blend {
            self.blend(PassRec { ctx, enc, slot }, clear, [params, camera, records], g, args);
            return;
        }
        let (src, dst) = if clear { (1, 0) } else { (self.current.get(), 1 - self.current.get()) };
        let v = |t: &wgpu::Texture, name: &str| view(t, name);
        let (prev, prev_plain) =
            (v(&self.accum[src], "gautron.accum"), v(&self.accum_plain[src], "gautron.accum.plain"));
        let (out, out_plain) = (v(&self.accum[dst], "gautron.accum"), v(&self.accum_plain[dst], "gautron.accum.plain"));
        let (prev_dir, out_dir) =
            (v(&self.accum_dir[src], "gautron.accum.direction"), v(&self.accum_dir[dst], "gautron.accum.direction"));
        let group = SPLAT_BINDINGS.group(
            &ctx.device,
            &self.layout,
            inputs([params, camera, records], g).into_iter().chain([
                args.as_entire_binding(),
                tv(&prev),
                tv(&prev_plain),
                tv(&out),
                tv(&out_plain),
                tv(&prev_dir),
                tv(&out_dir),
            ]),
        );
        let size = (self.accum[0].width(), self.accum[0].height());
        let timestamps = slot.and_then(|s| s.compute(true, true));
        let job = crate::passes::bins::SplatJob {
            pipelines: (&self.bin, &self.accumulate),
            group: &group,
            add: !clear,
            size,
        };
        self.bins.splat(ctx, enc, ("gautron.splat", timestamps), &job);
        self.current.set(dst);
    }

    /// Blend: the quads into the latest sums (cleared first when `clear`).
    fn blend(
        &self,
        r: PassRec<'_, '_>,
        clear: bool,
        [params, camera, records]: [&wgpu::Buffer; 3],
        g: &GBufferViews,
        args: &wgpu::Buffer,
    ) {
        let PassRec { ctx, enc, slot } = r;
        if clear {
            self.current.set(0);
        }
        let c = self.current.get();
        let group = SPLAT_BLEND_BINDINGS.group(&ctx.device, &self.raster_layout, inputs([params, camera, records], g));
        let (out, out_plain) =
            (view(&self.accum[c], "gautron.accum"), view(&self.accum_plain[c], "gautron.accum.plain"));
        let out_dir = view(&self.accum_dir[c], "gautron.accum.direction");
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
            color_attachments: &[att(&out), att(&out_plain), att(&out_dir)],
            depth_stencil_attachment: None,
            timestamp_writes: slot.and_then(|s| s.render(true, true)),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipe(&self.raster);
        pass.set_group(0, &group, &[]);
        pass.draw_indirect_counted(args, 0);
    }

    /// E = RGB / A and the reflected indirect light (`params`: the stage's uniform, whose
    /// rules.y chooses the receiver; `camera`: the eye).
    pub fn resolve(
        &self,
        ctx: &GpuContext,
        enc: &mut wgpu::CommandEncoder,
        slot: Option<crate::timing::Slot<'_>>,
        g: &GBufferViews,
        params: &wgpu::Buffer,
        camera: &wgpu::Buffer,
    ) {
        let tv = wgpu::BindingResource::TextureView;
        let c = self.current.get();
        let (accum, accum_plain) =
            (view(&self.accum[c], "gautron.accum"), view(&self.accum_plain[c], "gautron.accum.plain"));
        let accum_dir = view(&self.accum_dir[c], "gautron.accum.direction");
        let (indirect, irradiance, plain) = (
            view(&self.indirect, "gautron.indirect"),
            view(&self.irradiance, "gautron.irradiance"),
            view(&self.plain, "gautron.irradiance.plain"),
        );
        let group = RESOLVE_BINDINGS.group(
            &ctx.device,
            &self.resolve_layout,
            [
                tv(&accum),
                tv(&accum_plain),
                tv(&g.albedo),
                tv(&indirect),
                tv(&irradiance),
                tv(&plain),
                tv(&accum_dir),
                tv(&g.position),
                tv(&g.normal),
                tv(&g.material),
                params.as_entire_binding(),
                camera.as_entire_binding(),
            ],
        );
        let size = (self.accum[0].width(), self.accum[0].height());
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

    /// The latest direction sums and plain sums (`gautron.accum.direction`,
    /// `gautron.accum.plain`), as the resolve reads them.
    pub fn receiver_views(&self) -> (wgpu::TextureView, wgpu::TextureView) {
        let c = self.current.get();
        (view(&self.accum_dir[c], "gautron.accum.direction"), view(&self.accum_plain[c], "gautron.accum.plain"))
    }

    /// The latest sums (`gautron.accum`), as the creation's coverage test reads them.
    pub fn accum_view(&self) -> wgpu::TextureView {
        view(&self.accum[self.current.get()], "gautron.accum")
    }
}

type Targets =
    ([wgpu::Texture; 2], [wgpu::Texture; 2], [wgpu::Texture; 2], wgpu::Texture, wgpu::Texture, wgpu::Texture);

fn targets(device: &wgpu::Device, width: u32, height: u32) -> Targets {
    let st = wgpu::TextureUsages::STORAGE_BINDING;
    // Blend draws into them, Binned writes them.
    let rt = wgpu::TextureUsages::RENDER_ATTACHMENT | st;
    let pair = |name: &str| {
        [
            create_target(device, name, width, height, ACCUM_FORMAT, rt),
            create_target(device, name, width, height, ACCUM_FORMAT, rt),
        ]
    };
    let accum = pair("gautron.accum");
    let accum_plain = pair("gautron.accum.plain");
    let accum_dir = pair("gautron.accum.direction");
    let indirect = create_target(device, "gautron.indirect", width, height, ACCUM_FORMAT, st);
    let irradiance = create_target(device, "gautron.irradiance", width, height, ACCUM_FORMAT, st);
    let plain = create_target(device, "gautron.irradiance.plain", width, height, ACCUM_FORMAT, st);
    (accum, accum_plain, accum_dir, indirect, irradiance, plain)
}

/// Blend's pipeline: the quads of `vs_splat`, `fs_splat`'s two outputs added by blending.
fn raster_pipeline(
    device: &wgpu::Device,
    module: &wgpu::ShaderModule,
) -> (wgpu::RenderPipeline, wgpu::BindGroupLayout) {
    let layout = SPLAT_BLEND_BINDINGS.layout(device);
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("gautron.splat.blend.layout"),
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
    let pipeline = device.counted_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("gautron.splat.blend.pipeline"),
        layout: Some(&pipeline_layout),
        vertex: wgpu::VertexState {
            module,
            entry_point: Some("vs_splat"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil: None,
        multisample: Default::default(),
        fragment: Some(wgpu::FragmentState {
            module,
            entry_point: Some("fs_splat"),
            compilation_options: Default::default(),
            targets: &[target.clone(), target.clone(), target],
        }),
        multiview_mask: None,
        cache: None,
    });
    (pipeline, layout)
}

/// Bindings 0–4 of both splat groups: (params, camera, records) and the G-buffer.
fn inputs<'a>([params, camera, records]: [&'a wgpu::Buffer; 3], g: &'a GBufferViews) -> [wgpu::BindingResource<'a>; 5] {
    let tv = wgpu::BindingResource::TextureView;
    [
        params.as_entire_binding(),
        camera.as_entire_binding(),
        records.as_entire_binding(),
        tv(&g.position),
        tv(&g.normal),
    ]
}
