//! The records' hemispheres by rasterization (Gautron et al. 003, "Simple plane sampling"):
//! every new record of a round renders the scene through its wide camera into its tile of one
//! G-buffer atlas (one draw per scene draw for all the round's records: instance i·S + s,
//! clipped to tile s by clip distances; instance counts written by the GPU's creation pass),
//! the direct pass lights the atlas toward each record (`DirectPass::shade_atlas`), and a
//! compute pass reduces each tile to the record's irradiance, gradients and harmonic mean
//! distance with the per-texel table of `maths::hemisphere::HemisphereTable`. Shaders
//! `gautron/hemisphere.wgsl`, `gautron/reduce.wgsl`.

use crate::counters::prelude::*;

use super::{GautronSettings, atlas_grid};
use crate::buffers::{BufferKind, BufferRegistry};
use crate::gpu::GpuContext;
use crate::gpu::bindings::{Bindings, Kind, binding};
use crate::maths::hemisphere::HemisphereTable;
use crate::passes::gbuffer::{self, GBuffer};
use crate::scene::SceneState;
use crate::scene::upload::GpuScene;
use crate::timing::PassRec;

/// Bind group `gautron.hemisphere.cameras` of `shaders/gautron/hemisphere.wgsl` (group 0).
pub const HEMISPHERE_CAMERAS_BINDINGS: Bindings = Bindings {
    label: "gautron.hemisphere.cameras",
    shader: "gautron/hemisphere.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
    list: &[
        binding(0, "camera", Kind::Uniform),
        binding(1, "hemispheres", Kind::Storage { read_only: true }),
        binding(2, "params", Kind::Uniform),
    ],
};

/// Bind group `gautron.reduce` of `shaders/gautron/reduce.wgsl` (group 0).
pub const REDUCE_BINDINGS: Bindings = Bindings {
    label: "gautron.reduce",
    shader: "gautron/reduce.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "params", Kind::Uniform),
        binding(1, "state", Kind::Storage { read_only: true }),
        binding(2, "table", Kind::Storage { read_only: true }),
        binding(3, "cameras", Kind::Storage { read_only: true }),
        binding(4, "records", Kind::Storage { read_only: false }),
        binding(5, "radiance", Kind::Texture { filterable: false }),
        binding(6, "position", Kind::Texture { filterable: false }),
        binding(7, "normal", Kind::Texture { filterable: false }),
        binding(8, "object", Kind::Texture { filterable: false }),
    ],
};

/// Bytes of a round's indirect arguments ([`RoundArgs`]).
pub const ROUND_ARGS_BYTES: u64 = 48;

/// A round's indirect arguments, written by the GPU from the round's record count (issue #53;
/// `gautron/at_samples.wgsl`): the tile clears' draw (6 vertices, an instance per record) at
/// byte 0, the direct light's dispatch over the tiles' rows at 16, the reduction's (a
/// workgroup per record) at 32. A round of few records, or none, then costs what its tiles
/// cost instead of the whole atlas.
#[derive(Clone, Copy)]
pub struct RoundArgs<'a>(pub &'a wgpu::Buffer);

impl RoundArgs<'_> {
    pub const CLEAR: u64 = 0;
    pub const SHADE: u64 = 16;
    pub const REDUCE: u64 = 32;
}

/// The atlas, its pipelines and the texel table of one hemisphere resolution.
pub struct HemispherePass {
    single_sided: wgpu::RenderPipeline,
    double_sided: wgpu::RenderPipeline,
    /// The same for materials without textures (issue #53).
    plain_single_sided: wgpu::RenderPipeline,
    plain_double_sided: wgpu::RenderPipeline,
    /// The round's tiles cleared by quads (with [`RoundArgs`]).
    tile_clear: wgpu::RenderPipeline,
    raster_layout: wgpu::BindGroupLayout,
    reduce: wgpu::ComputePipeline,
    reduce_layout: wgpu::BindGroupLayout,
    pub atlas: GBuffer,
    pub radiance: wgpu::Texture,
    radiance_view: wgpu::TextureView,
    /// The solid angle Ω_p of each texel (r) and its border band's weight (g) (`gautron.solid_angle`).
    pub solid_angle: wgpu::Texture,
    pub table: wgpu::Buffer,
    /// Atlas size in texels.
    pub size: (u32, u32),
    /// (N, slots, aperture, compensation) the atlas and table were made for.
    key: (u32, u32, u32, u32),
}

impl HemispherePass {
    pub fn new(ctx: &GpuContext, scene: &GpuScene, s: &GautronSettings) -> Self {
        let device = &ctx.device;
        let module = crate::shaders::create_module(device, "gautron/hemisphere.wgsl");
        let raster_layout = HEMISPHERE_CAMERAS_BINDINGS.layout(device);
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("gautron.hemisphere.layout"),
            bind_group_layouts: &[Some(&raster_layout), Some(&scene.instance_layout), Some(&scene.material_layout)],
            immediate_size: 0,
        });
        let [single_sided, double_sided] =
            [Some(wgpu::Face::Back), None].map(|cull| raster_pipeline(device, &layout, &module, (cull, true)));
        let [plain_single_sided, plain_double_sided] =
            [Some(wgpu::Face::Back), None].map(|cull| raster_pipeline(device, &layout, &module, (cull, false)));
        let tile_clear = tile_clear_pipeline(device, &raster_layout, &module);
        let reduce_layout = REDUCE_BINDINGS.layout(device);
        let reduce_module = crate::shaders::create_module(device, "gautron/reduce.wgsl");
        let reduce =
            crate::passes::compute_pipeline(device, "gautron.reduce", &reduce_module, "cs_reduce", &[&reduce_layout]);
        let radiance = crate::passes::create_target(
            device,
            "gautron.hemisphere.radiance",
            1,
            1,
            crate::passes::direct::RADIANCE_FORMAT,
            wgpu::TextureUsages::STORAGE_BINDING,
        );
        let radiance_view = crate::passes::view(&radiance, "gautron.hemisphere.radiance");
        let solid_angle = crate::passes::create_target(
            device,
            "gautron.solid_angle",
            1,
            1,
            wgpu::TextureFormat::Rgba32Float,
            wgpu::TextureUsages::COPY_DST,
        );
        let mut pass = Self {
            single_sided,
            double_sided,
            plain_single_sided,
            plain_double_sided,
            tile_clear,
            raster_layout,
            reduce,
            reduce_layout,
            atlas: gbuffer::create_targets(ctx, 1, 1, "gautron.hemisphere"),
            radiance,
            radiance_view,
            solid_angle,
            table: crate::passes::buffer(device, "gautron.table", 64, wgpu::BufferUsages::STORAGE),
            size: (1, 1),
            key: (0, 0, 0, 0),
        };
        pass.ensure(ctx, s);
        pass
    }

    /// Remakes the atlas and the table when the resolution, the slots, the aperture or the
    /// compensation changed; true when it did.
    pub fn ensure(&mut self, ctx: &GpuContext, s: &GautronSettings) -> bool {
        let n = s.hemisphere_resolution.max(1);
        let key = (n, s.records_per_round, s.aperture_deg.to_bits(), s.border_compensation as u32);
        if key == self.key {
            return false;
        }
        self.key = key;
        let device = &ctx.device;
        let (per_row, rows) = atlas_grid(s.records_per_round);
        let max = ctx.limits.max_texture_dimension_2d;
        self.size = ((per_row * n).min(max), (rows * n).min(max));
        let (w, h) = self.size;
        self.atlas = gbuffer::create_targets(ctx, w, h, "gautron.hemisphere");
        self.radiance = crate::passes::create_target(
            device,
            "gautron.hemisphere.radiance",
            w,
            h,
            crate::passes::direct::RADIANCE_FORMAT,
            wgpu::TextureUsages::STORAGE_BINDING,
        );
        self.radiance_view = crate::passes::view(&self.radiance, "gautron.hemisphere.radiance");
        let table = HemisphereTable::new(n, s.aperture_deg, s.border_compensation);
        self.table = crate::passes::buffer(
            device,
            "gautron.table",
            (table.texels.len() * 64) as u64,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        );
        ctx.queue.upload(&self.table, 0, bytemuck::cast_slice(&table.texels));
        self.solid_angle = crate::passes::create_target(
            device,
            "gautron.solid_angle",
            n,
            n,
            wgpu::TextureFormat::Rgba32Float,
            wgpu::TextureUsages::COPY_DST,
        );
        let texels: Vec<[f32; 4]> =
            table.texels.iter().map(|t| [t.dir[3], t.band[0], t.dir[2] * t.dir[3] + t.band[0], t.band[1]]).collect();
        ctx.queue.write_texture(
            self.solid_angle.as_image_copy(),
            bytemuck::cast_slice(&texels),
            wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(n * 16), rows_per_image: Some(n) },
            wgpu::Extent3d { width: n, height: n, depth_or_array_layers: 1 },
        );
        true
    }

    pub fn register(&self, reg: &mut BufferRegistry) {
        let t = &self.atlas;
        reg.register(
            "gautron.hemisphere.radiance",
            BufferKind::Hdr,
            "the last round's hemispheres, one tile per new record: the radiance arriving at the record (direct light and emission of what it sees)",
            &self.radiance,
        );
        reg.register(
            "gautron.hemisphere.position",
            BufferKind::Data,
            "the last round's hemispheres: the world position each texel sees (w: the main camera's depth, unused)",
            &t.position,
        );
        reg.register(
            "gautron.hemisphere.normal",
            BufferKind::Direction,
            "the last round's hemispheres: the normal each texel sees (w = 1 where it sees geometry)",
            &t.normal,
        );
        reg.register(
            "gautron.hemisphere.object",
            BufferKind::Data,
            "the last round's hemispheres: r = the index of the scene draw each texel sees (the record cache invalidates a record when one it saw moves)",
            &t.motion,
        );
        reg.register(
            "gautron.solid_angle",
            BufferKind::Data,
            "one hemisphere tile's weights: r = solid angle Ω_p = A·cos³θ, g = the border band's irradiance weight, b = the texel's whole irradiance weight cosθ·Ω_p + band, a = the band's solid angle",
            &self.solid_angle,
        );
    }

    /// Renders the round's hemispheres into the atlas (`args`: the indirect draws, one per
    /// scene draw, written by the creation pass; `camera`: the eye's uniform, `cameras`: the
    /// slots' cameras).
    pub fn raster(
        &self,
        r: PassRec<'_, '_>,
        scene: &GpuScene,
        state: &SceneState,
        (camera, cameras): (&wgpu::Buffer, &wgpu::Buffer),
        params: &wgpu::Buffer,
        (args, round): (&wgpu::Buffer, Option<RoundArgs<'_>>),
    ) {
        let PassRec { ctx, enc, slot } = r;
        let group = HEMISPHERE_CAMERAS_BINDINGS.group(
            &ctx.device,
            &self.raster_layout,
            [camera.as_entire_binding(), cameras.as_entire_binding(), params.as_entire_binding()],
        );
        let (label, timestamps) = ("gautron.hemisphere.pass", slot.and_then(|s| s.render(true, false)));
        let mut pass = match round {
            Some(_) => self.atlas.begin_load_pass(enc, label, timestamps),
            None => self.atlas.begin_clear_pass(enc, label, timestamps),
        };
        pass.set_group(0, &group, &[]);
        if let Some(RoundArgs(round)) = round {
            pass.set_pipe(&self.tile_clear);
            pass.draw_indirect_counted(round, RoundArgs::CLEAR);
        }
        pass.set_group(1, &scene.instance_group, &[]);
        let pipelines =
            ((&self.single_sided, &self.double_sided), (&self.plain_single_sided, &self.plain_double_sided));
        scene.draw_indirect(&mut pass, state, 2, pipelines, args);
    }

    /// The indirect draw arguments of the scene's draws for `slots` slots: draw i renders
    /// instances i·S … i·S + n (n written by the creation pass into word 1).
    pub fn draw_args(scene: &GpuScene, state: &SceneState, slots: u32) -> Vec<u32> {
        scene
            .indexed_draws(state)
            .iter()
            .flat_map(|&(first, count, base, i)| [count, 0, first, base as u32, i * slots])
            .collect()
    }

    /// Reduces each new or refreshed record's tile to its terms (`gautron/reduce.wgsl`).
    pub fn reduce(
        &self,
        r: PassRec<'_, '_>,
        params: &wgpu::Buffer,
        state: &wgpu::Buffer,
        cameras: &wgpu::Buffer,
        records: &wgpu::Buffer,
        (slots, round): (u32, Option<RoundArgs<'_>>),
    ) {
        let PassRec { ctx, enc, slot } = r;
        let tv = wgpu::BindingResource::TextureView;
        let group = REDUCE_BINDINGS.group(
            &ctx.device,
            &self.reduce_layout,
            [
                params.as_entire_binding(),
                state.as_entire_binding(),
                self.table.as_entire_binding(),
                cameras.as_entire_binding(),
                records.as_entire_binding(),
                tv(&self.radiance_view),
                tv(&self.atlas.views.position),
                tv(&self.atlas.views.normal),
                tv(&self.atlas.views.motion),
            ],
        );
        let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("gautron.reduce"),
            timestamp_writes: slot.and_then(|s| s.compute(false, true)),
        });
        pass.set_pipe(&self.reduce);
        pass.set_group(0, &group, &[]);
        match round {
            Some(RoundArgs(round)) => pass.dispatch_indirect(round, RoundArgs::REDUCE),
            None => pass.dispatch(slots, 1, 1),
        }
    }

    pub fn radiance_view(&self) -> &wgpu::TextureView {
        &self.radiance_view
    }
}

/// The G-buffer's pipeline with the record cameras' vertex stage: the record's view has
/// rows (t, b, −n) so that the image's x and y are the table's t and b
/// (`cpu::gautron::frame`), a mirror (determinant −1), so front faces wind clockwise.
fn raster_pipeline(
    device: &wgpu::Device,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    cull_textured: (Option<wgpu::Face>, bool),
) -> wgpu::RenderPipeline {
    gbuffer::GBufferPass::pipeline(
        device,
        layout,
        module,
        ("vs_hemisphere", "fs_hemisphere", wgpu::FrontFace::Cw),
        cull_textured,
        "gautron.hemisphere",
    )
}

/// The tile clears' pipeline: a quad over each of the round's tiles writing the G-buffer's
/// clear values (zero, depth 1) whatever the depth there.
fn tile_clear_pipeline(
    device: &wgpu::Device,
    raster_layout: &wgpu::BindGroupLayout,
    module: &wgpu::ShaderModule,
) -> wgpu::RenderPipeline {
    let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("gautron.hemisphere.tile_clear.layout"),
        bind_group_layouts: &[Some(raster_layout)],
        immediate_size: 0,
    });
    device.counted_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("gautron.hemisphere.tile_clear"),
        layout: Some(&layout),
        vertex: wgpu::VertexState {
            module,
            entry_point: Some("vs_tile_clear"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        primitive: wgpu::PrimitiveState { topology: wgpu::PrimitiveTopology::TriangleList, ..Default::default() },
        depth_stencil: Some(wgpu::DepthStencilState {
            format: gbuffer::DEPTH_FORMAT,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::Always),
            stencil: Default::default(),
            bias: Default::default(),
        }),
        multisample: Default::default(),
        fragment: Some(wgpu::FragmentState {
            module,
            entry_point: Some("fs_tile_clear"),
            compilation_options: Default::default(),
            targets: &gbuffer::color_targets(),
        }),
        multiview_mask: None,
        cache: None,
    })
}
