//! Stage 7, composition and tone mapping (Knecht 002 §4.6 with Reinhard et al. [RSSF02]).
//! Shaders: `shaders/compose/compose.wgsl` (composes, tone maps with the previous frame's
//! exposure and reduces its tiles' log-luminance), `shaders/compose/luminance.wgsl` (the
//! log-average L̄w, Reinhard Eq. 1, for the next frame) and `shaders/compose/tonemap.wgsl`
//! (a tone-mapping pass of its own, only on the first frame of automatic exposure, whose L̄w
//! is not known before its compose: docs/architecture.md, "Read-backs, waits and what a
//! frame costs"). Writes `final.hdr` (linear radiance) and `final.ldr` (tone-mapped,
//! sRGB-encoded 8-bit).

use crate::counters::prelude::*;

use glam::Vec4;

use crate::buffers::{BufferKind, BufferRegistry};
use crate::gpu::GpuContext;
use crate::gpu::bindings::{Bindings, Kind, binding};
pub use crate::settings::compose::*;
use crate::timing::PassRec;

/// Uniform of the tone mapper; WGSL twin: `Params` in `shaders/compose/compose.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ToneParams {
    pub tone: Vec4,
}

/// The compose's uniform; WGSL twin: `Tone` in `shaders/compose/compose.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
struct ComposeTone {
    tone: Vec4,
    /// x: store final.hdr; y: store final.ldr and the tiles' log-luminance.
    store: [u32; 4],
}

/// Half floats, as `direct::RADIANCE_FORMAT` (the tone map reads the full-precision sum).
pub const HDR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
pub const LDR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;
/// The 1×1 black texture bound when a stage gives no light (16 zero bytes).
const NO_INDIRECT_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

pub struct ComposePass {
    compose: wgpu::ComputePipeline,
    tonemap: wgpu::ComputePipeline,
    luminance: wgpu::ComputePipeline,
    /// (Σ log(δ + Lw) in fixed point, count) per compose workgroup (TILE² pixels), i32.
    tiles: wgpu::Buffer,
    /// The compose's uniform (`Tone` in compose.wgsl): the tone mapping and what it stores.
    compose_tone: wgpu::Buffer,
    /// `final.hdr` when a read asks for it after a frame that did not store it (issue #53):
    /// the compose again over the frame's inputs, storing `final.hdr` alone (its own
    /// uniform, `hdr_only`).
    hdr_on_read: std::sync::Arc<crate::passes::on_read::OnRead>,
    hdr_only: wgpu::Buffer,
    /// The 1×1 `final.hdr` a frame binds when nothing reads it then.
    no_hdr: wgpu::TextureView,
    /// Whether `log_average` holds the previous frame's L̄w (automatic exposure ran then).
    exposure_known: bool,
    /// Whether this frame's compose tone-mapped final.ldr (else `tonemap` does).
    tone_mapped: bool,
    layout0: wgpu::BindGroupLayout,
    layout1: wgpu::BindGroupLayout,
    lum_layout: wgpu::BindGroupLayout,
    params: wgpu::Buffer,
    log_average: wgpu::Buffer,
    black: wgpu::TextureView,
    pub hdr: wgpu::Texture,
    pub ldr: wgpu::Texture,
}

/// What stage 7's compose adds up: the surfaces' emission, the direct light, the indirect
/// light and the near field (None: black), and the sky behind the scene (its parameters and
/// image, the camera uniform for the rays, the G-buffer's linear depth for its coverage).
#[derive(Clone, Copy)]
pub struct ComposeInputs<'a> {
    /// None: no material emits (the G-buffer left the target out, issue #53).
    pub emission: Option<&'a wgpu::TextureView>,
    pub direct: &'a wgpu::TextureView,
    pub indirect: Option<&'a wgpu::TextureView>,
    pub near_field: Option<&'a wgpu::TextureView>,
    pub sky: (&'a super::sky::SkyBackground, &'a wgpu::Buffer, &'a wgpu::TextureView),
}

const CS: wgpu::ShaderStages = wgpu::ShaderStages::COMPUTE;
const TEXTURE: Kind = Kind::Texture { filterable: false };
const READ: Kind = Kind::Storage { read_only: true };
const READ_WRITE: Kind = Kind::Storage { read_only: false };

/// The compose's inputs and outputs (`compose/compose.wgsl`, group 0).
pub const COMPOSE_BINDINGS: Bindings = Bindings {
    label: "compose.inputs",
    shader: "compose/compose.wgsl",
    group: 0,
    entry: None,
    visibility: CS,
    list: &[
        binding(1, "direct", TEXTURE),
        binding(2, "indirect", TEXTURE),
        binding(3, "out_hdr", Kind::StorageTexture(HDR_FORMAT)),
        binding(4, "near_field", TEXTURE),
        binding(5, "emission", TEXTURE),
        binding(6, "sky", Kind::Uniform),
        binding(7, "sky_image", TEXTURE),
        binding(8, "camera", Kind::Uniform),
        binding(9, "gbuffer_depth", TEXTURE),
        binding(10, "tp", Kind::Uniform),
        binding(11, "log_average", READ),
        binding(12, "out_ldr", Kind::StorageTexture(LDR_FORMAT)),
        binding(13, "partials", READ_WRITE),
    ],
};

/// The separate tone-mapping pass (`compose/tonemap.wgsl`, group 0).
pub const TONEMAP_BINDINGS: Bindings = Bindings {
    label: "compose.tonemap",
    shader: "compose/tonemap.wgsl",
    group: 0,
    entry: None,
    visibility: CS,
    list: &[
        binding(0, "params", Kind::Uniform),
        binding(1, "hdr_in", TEXTURE),
        binding(2, "log_average", READ),
        binding(3, "out_ldr", Kind::StorageTexture(LDR_FORMAT)),
    ],
};

/// The log-average luminance's last reduction (`compose/luminance.wgsl`, group 0).
pub const LUMINANCE_BINDINGS: Bindings = Bindings {
    label: "compose.luminance",
    shader: "compose/luminance.wgsl",
    group: 0,
    entry: None,
    visibility: CS,
    list: &[binding(1, "result", READ_WRITE), binding(2, "partials", READ_WRITE)],
};

impl ComposePass {
    pub fn new(ctx: &GpuContext, width: u32, height: u32) -> Self {
        let device = &ctx.device;
        let module = crate::shaders::create_module(device, "compose/compose.wgsl");
        let tone_module = crate::shaders::create_module(device, "compose/tonemap.wgsl");
        let lum_module = crate::shaders::create_module(device, "compose/luminance.wgsl");
        let layout0 = COMPOSE_BINDINGS.layout(device);
        let layout1 = TONEMAP_BINDINGS.layout(device);
        let lum_layout = LUMINANCE_BINDINGS.layout(device);
        let compose = super::compute_pipeline(device, "compose.compose", &module, "cs_compose", &[&layout0]);
        let tonemap = super::compute_pipeline(device, "compose.tonemap", &tone_module, "cs_tonemap", &[&layout1]);
        let luminance = super::compute_pipeline(device, "compose.luminance", &lum_module, "cs_final", &[&lum_layout]);
        let params = device.counted_buffer(&wgpu::BufferDescriptor {
            label: Some("compose.params"),
            size: std::mem::size_of::<ToneParams>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let compose_tone = device.counted_buffer(&wgpu::BufferDescriptor {
            label: Some("compose.tone"),
            size: std::mem::size_of::<ComposeTone>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let log_average = device.counted_buffer(&wgpu::BufferDescriptor {
            label: Some("compose.log_average"),
            size: 16,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let black_tex = super::create_target(
            device,
            "compose.no_indirect",
            1,
            1,
            NO_INDIRECT_FORMAT,
            wgpu::TextureUsages::COPY_DST,
        );
        ctx.queue.write_texture(
            black_tex.as_image_copy(),
            &[0u8; 16],
            wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(16), rows_per_image: Some(1) },
            wgpu::Extent3d { width: 1, height: 1, depth_or_array_layers: 1 },
        );
        let black = super::view(&black_tex, "compose.no_indirect");
        let hdr_only = device.counted_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("compose.tone.hdr_only"),
            contents: bytemuck::bytes_of(&ComposeTone { tone: Vec4::ZERO, store: [1, 0, 0, 0] }),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let no_hdr =
            super::create_target(device, "final.hdr.stand_in", 1, 1, HDR_FORMAT, wgpu::TextureUsages::STORAGE_BINDING);
        let no_hdr = super::view(&no_hdr, "final.hdr.stand_in");
        let (hdr, ldr) = Self::targets(ctx, width, height);
        let tiles = Self::tile_buffer(ctx, width, height);
        Self {
            compose,
            tonemap,
            luminance,
            tiles,
            compose_tone,
            hdr_on_read: Self::hdr_on_read(ctx, width, height),
            hdr_only,
            no_hdr,
            exposure_known: false,
            tone_mapped: false,
            layout0,
            layout1,
            lum_layout,
            params,
            log_average,
            black,
            hdr,
            ldr,
        }
    }

    fn tile_buffer(ctx: &GpuContext, width: u32, height: u32) -> wgpu::Buffer {
        let tiles = width.div_ceil(super::TILE) as u64 * height.div_ceil(super::TILE) as u64;
        ctx.device.counted_buffer(&wgpu::BufferDescriptor {
            label: Some("compose.luminance_tiles"),
            size: tiles * 8,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        })
    }

    fn targets(ctx: &GpuContext, width: u32, height: u32) -> (wgpu::Texture, wgpu::Texture) {
        let st = wgpu::TextureUsages::STORAGE_BINDING;
        let hdr = super::create_target(&ctx.device, "final.hdr", width, height, HDR_FORMAT, st);
        let ldr = ctx.device.counted_texture(&wgpu::TextureDescriptor {
            label: Some("final.ldr"),
            size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: LDR_FORMAT,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_SRC | st,
            // The app samples final.ldr through an sRGB view so that egui gets linear values.
            view_formats: &[wgpu::TextureFormat::Rgba8UnormSrgb],
        });
        (hdr, ldr)
    }

    fn hdr_on_read(ctx: &GpuContext, width: u32, height: u32) -> std::sync::Arc<crate::passes::on_read::OnRead> {
        crate::passes::on_read::OnRead::new(ctx, "compose.hdr", (width, height))
    }

    pub fn resize(&mut self, ctx: &GpuContext, width: u32, height: u32) {
        (self.hdr, self.ldr) = Self::targets(ctx, width, height);
        self.hdr_on_read = Self::hdr_on_read(ctx, width, height);
        self.tiles = Self::tile_buffer(ctx, width, height);
    }

    pub fn register(&self, reg: &mut BufferRegistry) {
        reg.register_derived(
            "final.hdr",
            BufferKind::Hdr,
            "direct + indirect radiance before tone mapping (W/(m²·sr))",
            &self.hdr,
            self.hdr_on_read.clone(),
        );
        reg.register("final.ldr", BufferKind::Ldr, "tone-mapped image (Reinhard), sRGB-encoded", &self.ldr);
    }

    /// final.hdr = emission + direct + indirect + near field, and the sky where the G-buffer
    /// is empty (`sky`: its parameters and image, `camera`: the camera uniform for the rays,
    /// `normal`: the G-buffer's coverage); final.ldr tone-mapped in the same pass unless
    /// automatic exposure has no previous L̄w yet (then `tonemap` does it after `luminance`).
    /// final.hdr is stored when `store_hdr` (a read-back of this frame copies it) or the
    /// separate tone mapping reads it; otherwise a read of it after the frame composes it
    /// again from the same inputs (issue #53: 8 bytes a pixel a frame that nothing reads).
    pub fn compose(&mut self, r: PassRec<'_, '_>, settings: &TonemapSettings, inputs: &ComposeInputs, store_hdr: bool) {
        let PassRec { ctx, enc: encoder, slot } = r;
        let ComposeInputs { emission, direct, indirect, near_field, sky: (sky, camera, depth) } = *inputs;
        let mode = match (settings.auto_exposure, self.exposure_known) {
            (false, _) => 1.0,
            (true, true) => 2.0,
            (true, false) => 0.0,
        };
        self.tone_mapped = mode > 0.0;
        let store_hdr = store_hdr || !self.tone_mapped;
        // Known next frame when this frame's luminance pass computes it.
        self.exposure_known = settings.auto_exposure;
        let [x, y, z, _] = tone_vector(settings).to_array();
        let tone = ComposeTone { tone: Vec4::new(x, y, z, mode), store: [store_hdr as u32, 1, 0, 0] };
        ctx.queue.upload(&self.compose_tone, 0, bytemuck::bytes_of(&tone));
        let sky_view = super::view(&sky.texture, "sky.background.image");
        let hdr_view = super::view(&self.hdr, "final.hdr");
        let ldr_view = super::view(&self.ldr, "final.ldr");
        fn tv(v: &wgpu::TextureView) -> wgpu::BindingResource<'_> {
            wgpu::BindingResource::TextureView(v)
        }
        let group = |hdr: &wgpu::TextureView, tone: &wgpu::Buffer| {
            COMPOSE_BINDINGS.group(
                &ctx.device,
                &self.layout0,
                [
                    tv(direct),
                    tv(indirect.unwrap_or(&self.black)),
                    tv(hdr),
                    tv(near_field.unwrap_or(&self.black)),
                    tv(emission.unwrap_or(&self.black)),
                    sky.params.as_entire_binding(),
                    tv(&sky_view),
                    camera.as_entire_binding(),
                    tv(depth),
                    tone.as_entire_binding(),
                    self.log_average.as_entire_binding(),
                    tv(&ldr_view),
                    self.tiles.as_entire_binding(),
                ],
            )
        };
        let later = (!store_hdr).then(|| (&self.compose, group(&hdr_view, &self.hdr_only)));
        self.hdr_on_read.arm(later);
        let group = group(if store_hdr { &hdr_view } else { &self.no_hdr }, &self.compose_tone);
        // The tiles' sums are atomic additions: they start from zero.
        encoder.counted_clear_buffer(&self.tiles, 0, None);
        self.dispatch(encoder, slot, "compose.compose", &self.compose, &group, self.screen_groups());
    }

    /// The log-average luminance of final.hdr from the compose's tiles, when automatic
    /// exposure is on (the pass is empty otherwise, so that its timing row stays).
    pub fn luminance(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        slot: Option<crate::timing::Slot<'_>>,
        settings: &TonemapSettings,
    ) {
        let resources = [self.log_average.as_entire_binding(), self.tiles.as_entire_binding()];
        let group = LUMINANCE_BINDINGS.group(&ctx.device, &self.lum_layout, resources);
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("compose.luminance"),
            timestamp_writes: slot.and_then(|s| s.compute(true, true)),
        });
        if settings.auto_exposure {
            pass.set_group(0, &group, &[]);
            pass.set_pipe(&self.luminance);
            pass.dispatch(1, 1, 1);
        }
    }

    /// Whether this frame's compose tone-mapped final.ldr; if not, `tonemap` must run after
    /// `luminance`.
    pub fn tone_mapped(&self) -> bool {
        self.tone_mapped
    }

    /// Reinhard tone mapping of final.hdr into final.ldr, as a pass of its own (see `compose`).
    pub fn tonemap(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        slot: Option<crate::timing::Slot<'_>>,
        settings: &TonemapSettings,
    ) {
        let p = ToneParams { tone: tone_vector(settings) };
        ctx.queue.upload(&self.params, 0, bytemuck::bytes_of(&p));
        let hdr_view = super::view(&self.hdr, "final.hdr");
        let ldr_view = super::view(&self.ldr, "final.ldr");
        let tv = wgpu::BindingResource::TextureView;
        let resources =
            [self.params.as_entire_binding(), tv(&hdr_view), self.log_average.as_entire_binding(), tv(&ldr_view)];
        let group = TONEMAP_BINDINGS.group(&ctx.device, &self.layout1, resources);
        self.dispatch(encoder, slot, "compose.tonemap", &self.tonemap, &group, self.screen_groups());
    }

    /// Forgets the last L̄w (a new scene or camera): the next automatic-exposure frame tone
    /// maps after its own log-average.
    pub fn forget_exposure(&mut self) {
        self.exposure_known = false;
    }

    fn screen_groups(&self) -> (u32, u32) {
        (self.hdr.width().div_ceil(super::TILE), self.hdr.height().div_ceil(super::TILE))
    }

    /// One compute pass with its own timestamps (a scope per pass: on lavapipe, timestamps
    /// of a scope spanning several compute passes were measured wrong).
    fn dispatch(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        slot: Option<crate::timing::Slot<'_>>,
        label: &str,
        pipeline: &wgpu::ComputePipeline,
        group: &wgpu::BindGroup,
        groups: (u32, u32),
    ) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(label),
            timestamp_writes: slot.and_then(|s| s.compute(true, true)),
        });
        if groups.0 > 0 && groups.1 > 0 {
            pass.set_pipe(pipeline);
            pass.set_group(0, group, &[]);
            pass.dispatch(groups.0, groups.1, 1);
        }
    }
}

/// (2^EV, key a, L_white, automatic exposure 1 or manual 0): `tone` of reinhard.wgsl.
fn tone_vector(settings: &TonemapSettings) -> Vec4 {
    Vec4::new(settings.exposure_ev.exp2(), settings.key, settings.white_point, settings.auto_exposure as u32 as f32)
}
