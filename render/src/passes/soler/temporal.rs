//! Stage 7 "warped blend" (Soler et al. 004 §4 "Temporal filtering", Eq. 6): the history,
//! warped through the movement buffer and rejected on depth and normal disagreement, is
//! blended with this frame's screen-space indirect light by an a adapted to motion and
//! glossiness. Shader `shaders/soler/temporal.wgsl`; CPU twin `cpu::soler_temporal::blend`.
//!
//! Buffers: `soler.temporal` (F_i, what compose adds), `soler.temporal.warped` (W of the
//! history), `soler.temporal.rejection` (r depth, g normal, b no history), `soler.temporal.a`
//! (the effective a) and `soler.temporal.history` (what the next frame warps: F_i or I_i as
//! `soler.temporal_history` says, depth in a). The history and the normals are
//! double-buffered by copy, as in `knecht::temporal`.

use super::{SolerSettings, TemporalHistory, TemporalQuantity};
use crate::buffers::{BufferKind, BufferRegistry};
use crate::counters::prelude::CountedQueue;
use crate::gpu::GpuContext;
use crate::gpu::bindings::{Bindings, Kind, binding};
use crate::passes::gbuffer::{GBufferViews, NORMAL_FORMAT};
use crate::timing::PassRec;

/// Bind group `soler.temporal.inputs` of `shaders/soler/temporal.wgsl` (group 0).
pub const TEMPORAL_INPUTS_BINDINGS: Bindings = Bindings {
    label: "soler.temporal.inputs",
    shader: "soler/temporal.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "params", Kind::Uniform),
        binding(1, "camera", Kind::Uniform),
        binding(2, "current", Kind::Texture { filterable: false }),
        binding(3, "g_position", Kind::Texture { filterable: false }),
        binding(4, "g_normal", Kind::UintTexture),
        binding(5, "g_motion", Kind::Texture { filterable: false }),
        binding(6, "g_material", Kind::Texture { filterable: false }),
        binding(7, "prev_normal", Kind::Texture { filterable: false }),
        binding(8, "history_prev", Kind::Texture { filterable: false }),
        binding(9, "out_filtered", Kind::StorageTexture(wgpu::TextureFormat::Rgba16Float)),
        binding(10, "out_history", Kind::StorageTexture(wgpu::TextureFormat::Rgba32Float)),
        binding(11, "out_warped", Kind::StorageTexture(wgpu::TextureFormat::Rgba16Float)),
        binding(12, "out_mask", Kind::StorageTexture(wgpu::TextureFormat::Rgba8Unorm)),
        binding(13, "out_a", Kind::StorageTexture(wgpu::TextureFormat::R32Float)),
        binding(14, "out_normal", Kind::StorageTexture(wgpu::TextureFormat::Rgba16Float)),
        binding(15, "g_albedo", Kind::Texture { filterable: false }),
        binding(16, "specular", Kind::Texture { filterable: false }),
        binding(17, "spec_history_prev", Kind::Texture { filterable: false }),
        binding(18, "out_spec_history", Kind::StorageTexture(wgpu::TextureFormat::Rgba16Float)),
    ],
};

/// Rust twin of `TemporalParams` in `shaders/soler/temporal.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct TemporalParams {
    /// a, m½, k_g, 1 when the history holds a frame.
    pub blend: [f32; 4],
    /// τ_z, τ_n, 1 when the history keeps I_{i−1}; what is blended: 0 the radiance, 1 the
    /// irradiance (Fig. 4), 2 the irradiance with glossy light to leave out.
    pub reject: [f32; 4],
}

impl TemporalParams {
    /// `specular`: a glossy light was added into the current light (`SolerStage::indirect_specular`).
    pub fn of(s: &SolerSettings, valid: bool, specular: bool) -> Self {
        let quantity = match s.temporal_quantity {
            TemporalQuantity::Radiance => 0.0,
            TemporalQuantity::Irradiance => 1.0 + specular as u32 as f32,
        };
        Self {
            blend: [s.temporal_a, s.temporal_motion_px, s.temporal_gloss, valid as u32 as f32],
            reject: [
                s.reject_depth,
                s.reject_normal,
                (s.temporal_history == TemporalHistory::Raw) as u32 as f32,
                quantity,
            ],
        }
    }
}

pub struct SolerTemporal {
    size: (u32, u32),
    /// F_i.
    pub filtered: wgpu::Texture,
    /// Ping-pong pairs (issue #38: no copies): `history[current]` and `normals[current]` were
    /// written by the last frame (its history and G-buffer normals); the next frame reads them
    /// and writes the other pair.
    history: [wgpu::Texture; 2],
    normals: [wgpu::Texture; 2],
    /// The glossy light's history pair (irradiance blend with the glossy reflection).
    spec_history: [wgpu::Texture; 2],
    current: usize,
    pub warped: wgpu::Texture,
    pub rejection: wgpu::Texture,
    pub a: wgpu::Texture,
    /// Whether the last pair holds a frame.
    valid: bool,
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::ComputePipeline,
    params: wgpu::Buffer,
    /// Stand-in for the glossy light when there is none (never read).
    no_specular: wgpu::Texture,
}

struct Targets {
    filtered: wgpu::Texture,
    history: [wgpu::Texture; 2],
    spec_history: [wgpu::Texture; 2],
    normals: [wgpu::Texture; 2],
    warped: wgpu::Texture,
    rejection: wgpu::Texture,
    a: wgpu::Texture,
}

/// `soler.temporal` (F, which the compose adds) and `soler.temporal.warped` (W, a debug view):
/// light as half floats, as Knecht's filtered light (issue #38; a step of 2⁻¹⁰ to 2⁻¹¹
/// relative). The history keeps `Rgba32Float` for the linear depth in its alpha.
pub const LIGHT_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
/// `soler.temporal.rejection`: three 0/1 flags.
pub const MASK_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

fn targets(device: &wgpu::Device, (w, h): (u32, u32)) -> Targets {
    let st = wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::COPY_SRC | wgpu::TextureUsages::COPY_DST;
    let t = |label, f| crate::passes::create_target(device, label, w, h, f, st);
    let rgba = wgpu::TextureFormat::Rgba32Float;
    Targets {
        filtered: t("soler.temporal", LIGHT_FORMAT),
        history: [t("soler.temporal.history.0", rgba), t("soler.temporal.history.1", rgba)],
        spec_history: [
            t("soler.temporal.specular_history.0", LIGHT_FORMAT),
            t("soler.temporal.specular_history.1", LIGHT_FORMAT),
        ],
        normals: [t("soler.temporal.prev_normal.0", NORMAL_FORMAT), t("soler.temporal.prev_normal.1", NORMAL_FORMAT)],
        warped: t("soler.temporal.warped", LIGHT_FORMAT),
        rejection: t("soler.temporal.rejection", MASK_FORMAT),
        a: t("soler.temporal.a", wgpu::TextureFormat::R32Float),
    }
}

impl SolerTemporal {
    /// The glossy light's history the last blend read (last frame's).
    pub fn spec_history_prev(&self) -> &wgpu::Texture {
        &self.spec_history[1 - self.current]
    }

    pub fn new(ctx: &GpuContext, size: (u32, u32)) -> Self {
        let device = &ctx.device;
        let layout = TEMPORAL_INPUTS_BINDINGS.layout(device);
        let module = crate::shaders::create_module(device, "soler/temporal.wgsl");
        let pipeline = crate::passes::compute_pipeline(device, "soler.temporal", &module, "cs_temporal", &[&layout]);
        let params = crate::passes::uniform_buffer(
            device,
            "soler.temporal.params",
            std::mem::size_of::<TemporalParams>() as u64,
        );
        let t = targets(device, size);
        let none = wgpu::TextureUsages::empty();
        let no_specular = crate::passes::create_target(device, "soler.temporal.no_specular", 1, 1, LIGHT_FORMAT, none);
        Self {
            no_specular,
            size,
            filtered: t.filtered,
            history: t.history,
            normals: t.normals,
            spec_history: t.spec_history,
            current: 0,
            warped: t.warped,
            rejection: t.rejection,
            a: t.a,
            valid: false,
            layout,
            pipeline,
            params,
        }
    }

    /// Resizes to the G-buffer; true when the textures were replaced (the history is lost).
    pub fn ensure(&mut self, ctx: &GpuContext, size: (u32, u32)) -> bool {
        if size == self.size {
            return false;
        }
        let t = targets(&ctx.device, size);
        (self.filtered, self.history, self.normals) = (t.filtered, t.history, t.normals);
        self.spec_history = t.spec_history;
        (self.warped, self.rejection, self.a) = (t.warped, t.rejection, t.a);
        self.size = size;
        self.valid = false;
        true
    }

    /// Forgets the history.
    pub fn reset(&mut self) {
        self.valid = false;
    }

    pub fn register(&self, reg: &mut BufferRegistry) {
        let entries: [(&str, BufferKind, &str, &wgpu::Texture); 6] = [
            (
                "soler.temporal.specular_history",
                BufferKind::Hdr,
                "Soler Eq. 6's history of the glossy light for the next frame (irradiance blend, soler.temporal_quantity): F_S or S",
                &self.spec_history[self.current],
            ),
            (
                "soler.temporal",
                BufferKind::Hdr,
                "Soler temporal filtering (004 Eq. 6): F_i = a·W(history) + (1 − a)·I_i, what compose adds",
                &self.filtered,
            ),
            (
                "soler.temporal.warped",
                BufferKind::Hdr,
                "Soler Eq. 6's W(history): the history at the pixel's previous position (movement buffer), black where none",
                &self.warped,
            ),
            (
                "soler.temporal.rejection",
                BufferKind::Data,
                "Soler Eq. 6's rejection mask: r depth disagrees (τ_z), g normal disagrees (τ_n), b no history (off screen, background, first frame)",
                &self.rejection,
            ),
            (
                "soler.temporal.a",
                BufferKind::Data,
                "Soler Eq. 6's effective a: a adapted to motion and glossiness, 0 where the history is rejected",
                &self.a,
            ),
            (
                "soler.temporal.history",
                BufferKind::Hdr,
                "Soler Eq. 6's history for the next frame: F_i or I_i (soler.temporal_history), view depth in a",
                &self.history[self.current],
            ),
        ];
        for (name, kind, doc, t) in entries {
            reg.register(name, kind, doc, t);
        }
    }

    /// Blends `current` (I_i, and the glossy light added into it) with the warped history
    /// into `soler.temporal`.
    pub fn run(
        &mut self,
        r: PassRec<'_, '_>,
        s: &SolerSettings,
        camera: &wgpu::Buffer,
        (current, specular): (&wgpu::TextureView, Option<&wgpu::TextureView>),
        g: &GBufferViews,
    ) {
        let PassRec { ctx, enc: encoder, slot } = r;
        let params = TemporalParams::of(s, self.valid, specular.is_some());
        ctx.queue.upload(&self.params, 0, bytemuck::bytes_of(&params));
        let no_specular = crate::passes::view(&self.no_specular, "soler.temporal.no_specular");
        let v = |t: &wgpu::Texture| crate::passes::view(t, "soler.temporal.view");
        let (read, write) = (self.current, 1 - self.current);
        let (prev_n, hist_prev, filtered, hist, warped, rejection, a, normal_out) = (
            v(&self.normals[read]),
            v(&self.history[read]),
            v(&self.filtered),
            v(&self.history[write]),
            v(&self.warped),
            v(&self.rejection),
            v(&self.a),
            v(&self.normals[write]),
        );
        let tv = wgpu::BindingResource::TextureView;
        let mut resources = vec![self.params.as_entire_binding(), camera.as_entire_binding()];
        let views = [current, &g.position, &g.packed_normal, &g.motion, &g.material, &prev_n, &hist_prev];
        resources.extend(views.map(tv));
        resources.extend([&filtered, &hist, &warped, &rejection, &a, &normal_out].map(tv));
        let (spec_prev, spec_out) = (v(&self.spec_history[read]), v(&self.spec_history[write]));
        resources.extend([&g.albedo, specular.unwrap_or(&no_specular), &spec_prev, &spec_out].map(tv));
        let group = TEMPORAL_INPUTS_BINDINGS.group(&ctx.device, &self.layout, resources);
        let stamps = slot.and_then(|s| s.compute(true, true));
        crate::passes::dispatch_2d(encoder, "soler.temporal", &self.pipeline, &group, &[], stamps, self.size);
        self.current = write;
        self.valid = true;
    }
}
