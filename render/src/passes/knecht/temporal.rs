//! Stage 7, temporal coherence of instant radiosity (Knecht 002 §3.5): the previous frame's
//! indirect light, depth and normals, reprojected through the movement buffer, are blended
//! with this frame's by the confidence of Eq. 3.1–3.4 (`temporal.confidence`) and the merge
//! of Eq. 3.6 (`temporal.history`, rgb = light, a = depth). Shader:
//! `shaders/knecht/temporal/confidence.wgsl`; CPU twin: `cpu::knecht::confidence`.
//!
//! History and normals ping-pong between two textures each, with no copy (issue #38): the
//! pass reads last frame's pair and writes this frame's, the G-buffer normals included as it
//! reads them (the thesis double-buffers the normals in the G-buffer). The registry names
//! the pair just written (`temporal.history`, `temporal.prev_normal`).
//!
//! Demodulated (`demodulate`, issue #51, ⚠[knecht.demodulated-merge]): after the demodulated
//! filter (or the HCB's splat) the pass also keeps the light split into the irradiance E it
//! reflects (the filter's window mean, or `hcb.irradiance`) and the specular rest S, in a
//! third ping-pong pair made on first use (not a viewable buffer: two half-float triples
//! packed in `Rgba32Uint`); it merges them apart and reflects E with each pixel's own colour.
//! `temporal.history` still holds the merged light the compose adds.

use crate::counters::prelude::*;

use glam::Vec4;

use crate::buffers::{BufferKind, BufferRegistry};
use crate::gpu::GpuContext;
use crate::gpu::bindings::{Bindings, Kind, binding};
use crate::passes::gbuffer::{GBufferViews, NORMAL_FORMAT};
pub use crate::settings::knecht::{MergeOrder, TemporalSettings};
use crate::timing::PassRec;

/// Format of `temporal.history` (the merged light in rgb, the linear depth in a): half floats,
/// as the light passes store light (issue #53: half the traffic of `Rgba32Float`; the depth's
/// relative step of 2⁻¹¹ is far below what Eq. 3.2's position term reacts to).
pub const HISTORY_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

/// Format of the demodulated merge's split history: E and S as three half-float pairs.
pub const SPLIT_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Uint;

/// The confidence merge's bindings (`knecht/temporal/confidence.wgsl`, group 0).
pub const CONFIDENCE_BINDINGS: Bindings = Bindings {
    label: "temporal.confidence.inputs",
    shader: "knecht/temporal/confidence.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "params", Kind::Uniform),
        binding(1, "current", Kind::Texture { filterable: false }),
        binding(2, "g_position", Kind::Texture { filterable: false }),
        binding(3, "g_normal", Kind::UintTexture),
        binding(4, "g_motion", Kind::Texture { filterable: false }),
        binding(5, "prev_normal", Kind::Texture { filterable: false }),
        binding(6, "history_prev", Kind::Texture { filterable: false }),
        binding(7, "confidence_out", Kind::StorageTexture(wgpu::TextureFormat::R32Float)),
        binding(8, "history_out", Kind::StorageTexture(HISTORY_FORMAT)),
        binding(9, "normal_out", Kind::StorageTexture(NORMAL_FORMAT)),
        binding(10, "g_albedo", Kind::Texture { filterable: false }),
        binding(11, "irradiance", Kind::Texture { filterable: false }),
        binding(12, "split_prev", Kind::UintTexture),
        binding(13, "split_out", Kind::StorageTexture(SPLIT_FORMAT)),
    ],
};

/// The geometry-aware filter fused into the confidence merge
/// (`knecht/temporal/filter_merge.wgsl`, group 0, issue #53): the merge's bindings, with the
/// gathered light and its irradiance in place of the filtered ones, and the filter's uniform.
pub const FILTER_MERGE_BINDINGS: Bindings = Bindings {
    label: "temporal.filter_merge.inputs",
    shader: "knecht/temporal/filter_merge.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "params", Kind::Uniform),
        binding(1, "src", Kind::Texture { filterable: false }),
        binding(2, "g_position", Kind::Texture { filterable: false }),
        binding(3, "g_normal", Kind::UintTexture),
        binding(4, "g_motion", Kind::Texture { filterable: false }),
        binding(5, "prev_normal", Kind::Texture { filterable: false }),
        binding(6, "history_prev", Kind::Texture { filterable: false }),
        binding(7, "confidence_out", Kind::StorageTexture(wgpu::TextureFormat::R32Float)),
        binding(8, "history_out", Kind::StorageTexture(HISTORY_FORMAT)),
        binding(9, "normal_out", Kind::StorageTexture(NORMAL_FORMAT)),
        binding(10, "g_albedo", Kind::Texture { filterable: false }),
        binding(11, "irradiance", Kind::Texture { filterable: false }),
        binding(12, "split_prev", Kind::UintTexture),
        binding(13, "split_out", Kind::StorageTexture(SPLIT_FORMAT)),
        binding(14, "filter_params", Kind::Uniform),
    ],
};

/// `temporal.prev_normal` decoded from the demodulated merge's split history when it is read
/// (`cs_split_normal` of `knecht/temporal/confidence.wgsl`, issue #53).
pub const SPLIT_NORMAL_BINDINGS: Bindings = Bindings {
    label: "temporal.prev_normal.inputs",
    shader: "knecht/temporal/confidence.wgsl",
    group: 0,
    entry: Some("cs_split_normal"),
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(9, "normal_out", Kind::StorageTexture(NORMAL_FORMAT)),
        binding(12, "split_prev", Kind::UintTexture),
    ],
};

/// The filter a merge runs first, fused (`TemporalPass::run_fused`, issue #53).
pub struct FusedFilter<'a> {
    /// Whether the merge keeps the filter's mean irradiance apart (as [`TemporalPass::run`]
    /// with `Some` irradiance).
    pub demodulate: bool,
    /// The filter's uniform (`interleave::FilterParams`, as `InterleavePass` wrote it).
    pub params: &'a wgpu::Buffer,
    /// The gathered light's irradiance, which a demodulated filter averages (None: the filter
    /// averages the light itself).
    pub irradiance: Option<&'a wgpu::TextureView>,
}

/// A 1×1 stand-in for the split history, bound by the explain replays when the merge did not
/// run demodulated.
pub fn no_split_view(device: &wgpu::Device, label: &str) -> wgpu::TextureView {
    let t = crate::passes::create_target(device, label, 1, 1, SPLIT_FORMAT, wgpu::TextureUsages::empty());
    crate::passes::view(&t, label)
}

/// Uniform of the confidence pass; WGSL twin: `ConfidenceParams`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ConfidenceParams {
    pub weights: Vec4,
    /// x: the history is valid, y: merge demodulated, z: what the pass stores (0 everything,
    /// 1 all but the confidence, 2 the confidence alone).
    pub state: [u32; 4],
    /// x: z_far − z_near.
    pub range: Vec4,
}

pub struct TemporalPass {
    width: u32,
    height: u32,
    pub confidence: wgpu::Texture,
    /// Ping-pong pairs (issue #38: no copies): `history[current]` is this frame's merged
    /// light and next frame's I_prev; `normals[current]` this frame's G-buffer normals, which
    /// the pass writes as it reads them, and next frame's n_prev.
    history: [wgpu::Texture; 2],
    normals: [wgpu::Texture; 2],
    current: usize,
    /// Whether the previous-frame textures hold a frame.
    valid: bool,
    /// The demodulated merge's split history (E and S as half floats, `Rgba32Uint`), made on
    /// its first use; `split[current]` is this frame's.
    split: Option<[wgpu::Texture; 2]>,
    /// Whether the last run wrote `split[current]` (merged demodulated), and whether it read
    /// `split[1 − current]` as its history.
    split_written: bool,
    split_read: bool,
    /// 1×1 stand-ins for the split pair when the merge is not demodulated.
    dummy_split: [wgpu::Texture; 2],
    /// 1×1 stand-ins for the normals pair when it is: the demodulated merge keeps the normal
    /// in the split history (issue #53).
    dummy_normals: [wgpu::Texture; 2],
    /// Fills `normals[current]` from `split[current]` when `temporal.prev_normal` is read
    /// after a demodulated merge.
    split_normal_layout: wgpu::BindGroupLayout,
    split_normal_pipeline: wgpu::ComputePipeline,
    split_normal: std::sync::Arc<crate::passes::on_read::OnRead>,
    /// Whether the next merges store `temporal.confidence` (the default); when not (issue
    /// #53: nothing reads it in the frame, 4 bytes a pixel), the merge binds a 1×1 stand-in
    /// and the confidence is computed again, alone, when it is read.
    pub store_confidence: bool,
    /// Whether a demodulated merge also decodes `temporal.prev_normal` in the frame (a
    /// read-back of this frame copies it); otherwise it is decoded when read.
    pub decode_normals: bool,
    dummy_confidence: wgpu::Texture,
    confidence_on_read: std::sync::Arc<crate::passes::on_read::OnRead>,
    /// The uniform of that later pass (`state.z` = 2).
    confidence_params: wgpu::Buffer,
    layout: wgpu::BindGroupLayout,
    /// The merge of the thesis, then the demodulated one.
    pipeline: [wgpu::ComputePipeline; 2],
    /// The same with the geometry-aware filter fused in front (issue #53).
    fused_layout: wgpu::BindGroupLayout,
    fused_pipeline: [wgpu::ComputePipeline; 2],
    params: wgpu::Buffer,
}

impl TemporalPass {
    pub fn new(ctx: &GpuContext, width: u32, height: u32) -> Self {
        let device = &ctx.device;
        let layout = CONFIDENCE_BINDINGS.layout(device);
        let module = crate::shaders::create_module(device, "knecht/temporal/confidence.wgsl");
        // The thesis' merge and the demodulated one, each without the other's branch
        // (`DEMODULATE`, issue #53).
        let pipeline = [0.0, 1.0].map(|demodulate| {
            let label = if demodulate > 0.0 { "temporal.confidence.demodulated" } else { "temporal.confidence" };
            let constants = [("DEMODULATE", demodulate)];
            crate::gpu::compute_pipeline_with(device, label, (&module, "cs_confidence", &constants), &[&layout])
        });
        let fused_layout = FILTER_MERGE_BINDINGS.layout(device);
        let fused_module = crate::shaders::create_module(device, "knecht/temporal/filter_merge.wgsl");
        let fused_pipeline = [0.0, 1.0].map(|demodulate| {
            let label = if demodulate > 0.0 { "temporal.filter_merge.demodulated" } else { "temporal.filter_merge" };
            let entry = (&fused_module, "cs_filter_merge", &[("DEMODULATE", demodulate)][..]);
            crate::gpu::compute_pipeline_with(device, label, entry, &[&fused_layout])
        });
        let split_normal_layout = SPLIT_NORMAL_BINDINGS.layout(device);
        let split_normal_pipeline = crate::passes::compute_pipeline(
            device,
            "temporal.prev_normal",
            &module,
            "cs_split_normal",
            &[&split_normal_layout],
        );
        let split_normal = crate::passes::on_read::OnRead::new(ctx, "temporal.prev_normal", (width, height));
        let bytes = std::mem::size_of::<ConfidenceParams>() as u64;
        let params = crate::passes::uniform_buffer(device, "temporal.params", bytes);
        let confidence_params = crate::passes::uniform_buffer(device, "temporal.confidence.params", bytes);
        let (confidence, history, normals) = Self::targets(device, width, height);
        // 1×1 stand-ins for the confidence and the normals pair (one set of small targets).
        let (dummy_confidence, _, dummy_normals) = Self::targets(device, 1, 1);
        Self {
            width,
            height,
            confidence,
            history,
            normals,
            current: 0,
            valid: false,
            split: None,
            split_written: false,
            split_read: false,
            dummy_split: Self::split_pair(device, 1, 1, "temporal.history_split.unused"),
            dummy_normals,
            split_normal_layout,
            split_normal_pipeline,
            split_normal,
            store_confidence: true,
            decode_normals: false,
            dummy_confidence,
            confidence_on_read: crate::passes::on_read::OnRead::new(ctx, "temporal.confidence", (width, height)),
            confidence_params,
            layout,
            pipeline,
            fused_layout,
            fused_pipeline,
            params,
        }
    }

    fn split_pair(device: &wgpu::Device, w: u32, h: u32, label: &str) -> [wgpu::Texture; 2] {
        let st = wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::COPY_DST;
        let t = |i| crate::passes::create_target(device, &format!("{label}.{i}"), w, h, SPLIT_FORMAT, st);
        [t(0), t(1)]
    }

    #[allow(clippy::type_complexity)]
    fn targets(device: &wgpu::Device, w: u32, h: u32) -> (wgpu::Texture, [wgpu::Texture; 2], [wgpu::Texture; 2]) {
        let st = wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::COPY_DST;
        let t = |label, f| crate::passes::create_target(device, label, w, h, f, st);
        (
            t("temporal.confidence", wgpu::TextureFormat::R32Float),
            [t("temporal.history.0", HISTORY_FORMAT), t("temporal.history.1", HISTORY_FORMAT)],
            [t("temporal.prev_normal.0", NORMAL_FORMAT), t("temporal.prev_normal.1", NORMAL_FORMAT)],
        )
    }

    /// The split history this frame's demodulated merge read (E and S of last frame, packed as
    /// `shaders/knecht/temporal/confidence.wgsl` says), or None when this frame did not merge
    /// demodulated or last frame left no split history.
    pub fn split_prev(&self) -> Option<&wgpu::Texture> {
        let split = self.split.as_ref()?;
        self.split_read.then(|| &split[1 - self.current])
    }

    /// This frame's merged light (`temporal.history`).
    pub fn history(&self) -> &wgpu::Texture {
        &self.history[self.current]
    }

    /// The history this frame's merge read (last frame's `temporal.history`).
    pub fn history_prev(&self) -> &wgpu::Texture {
        &self.history[1 - self.current]
    }

    pub fn resize(&mut self, ctx: &GpuContext, width: u32, height: u32) -> bool {
        if (width, height) == (self.width, self.height) {
            return false;
        }
        (self.confidence, self.history, self.normals) = Self::targets(&ctx.device, width, height);
        (self.width, self.height) = (width, height);
        self.split_normal = crate::passes::on_read::OnRead::new(ctx, "temporal.prev_normal", (width, height));
        self.confidence_on_read = crate::passes::on_read::OnRead::new(ctx, "temporal.confidence", (width, height));
        self.split = None;
        self.valid = false;
        true
    }

    /// Forgets the previous frame.
    pub fn reset(&mut self) {
        self.valid = false;
    }

    pub fn register(&self, reg: &mut BufferRegistry) {
        reg.register_derived(
            "temporal.confidence",
            BufferKind::Data,
            "confidence in the previous frame's indirect light (Knecht Eq. 3.4), 0 … c_base; the thesis computes it on the fly",
            &self.confidence,
            self.confidence_on_read.clone(),
        );
        reg.register(
            "temporal.history",
            BufferKind::Hdr,
            "indirect light after the confidence merge (Eq. 3.6) in rgb, view depth in a: what compose adds, and next frame's I_prev",
            self.history(),
        );
        let (name, kind, normals) = ("temporal.prev_normal", BufferKind::Direction, &self.normals[self.current]);
        let what = "the last frame's G-buffer normals, next frame's n_prev (Eq. 3.2)";
        if self.split_written {
            // Kept in the split history by the demodulated merge: decoded when read.
            reg.register_derived(name, kind, what, normals, self.split_normal.clone());
        } else {
            reg.register(name, kind, what, normals);
        }
    }

    /// Merges `current` (this frame's indirect light) with the reprojected history; the
    /// result is `temporal.history`. `irradiance`: the irradiance `current` reflects (the
    /// demodulated filter's `indirect.filtered_irradiance`, the HCB's `hcb.irradiance`) to
    /// merge demodulated, None for the thesis' merge of the reflected light. A switch between
    /// the two forgets the history.
    pub fn run(
        &mut self,
        r: PassRec<'_, '_>,
        s: &TemporalSettings,
        depth_range: f32,
        current: &wgpu::TextureView,
        g: &GBufferViews,
        irradiance: Option<&wgpu::TextureView>,
    ) {
        self.merge(r, s, depth_range, current, g, (irradiance.is_some(), irradiance, None));
    }

    /// The geometry-aware filter of `gathered` and the merge of its result in one pass
    /// (`knecht/temporal/filter_merge.wgsl`, issue #53): what `InterleavePass::filter` then
    /// [`Self::run`] give, without `indirect.filtered` in between.
    pub fn run_fused(
        &mut self,
        r: PassRec<'_, '_>,
        s: &TemporalSettings,
        depth_range: f32,
        gathered: &wgpu::TextureView,
        g: &GBufferViews,
        filter: FusedFilter<'_>,
    ) {
        let how = (filter.demodulate, filter.irradiance, Some(filter.params));
        self.merge(r, s, depth_range, gathered, g, how);
    }

    /// [`Self::run`] (`filter` None) or [`Self::run_fused`]; `how`: whether to merge
    /// demodulated, the irradiance texture the shader reads, the fused filter's uniform.
    fn merge(
        &mut self,
        r: PassRec<'_, '_>,
        s: &TemporalSettings,
        depth_range: f32,
        current: &wgpu::TextureView,
        g: &GBufferViews,
        (demodulate, irradiance, filter): (bool, Option<&wgpu::TextureView>, Option<&wgpu::Buffer>),
    ) {
        let PassRec { ctx, enc: encoder, slot } = r;
        if demodulate != self.split_written {
            // The other kind of history: this frame starts afresh.
            self.valid = false;
        }
        if demodulate && self.split.is_none() {
            self.split = Some(Self::split_pair(&ctx.device, self.width, self.height, "temporal.history_split"));
        }
        let stores = if self.store_confidence { 0 } else { 1 };
        let p = ConfidenceParams {
            weights: Vec4::new(s.c_base, s.w_pos, s.w_normal, s.w_illumination),
            state: [self.valid as u32, demodulate as u32, stores, 0],
            range: Vec4::new(depth_range, 0.0, 0.0, 0.0),
        };
        ctx.queue.upload(&self.params, 0, bytemuck::bytes_of(&p));
        let later = ConfidenceParams { state: [self.valid as u32, demodulate as u32, 2, 0], ..p };
        ctx.queue.upload(&self.confidence_params, 0, bytemuck::bytes_of(&later));
        let v = |t: &wgpu::Texture, l: &str| crate::passes::view(t, l);
        let (read, write) = (self.current, 1 - self.current);
        // Demodulated, the normals go into the split history's free word (issue #53).
        let normals = if demodulate { &self.dummy_normals } else { &self.normals };
        let (prev_n, hist_prev, conf, hist, normal_out) = (
            v(&normals[read], "temporal.prev_normal"),
            v(&self.history[read], "temporal.history_prev"),
            v(&self.confidence, "temporal.confidence"),
            v(&self.history[write], "temporal.history"),
            v(&normals[write], "temporal.normal_out"),
        );
        let split = match (&self.split, demodulate) {
            (Some(pair), true) => pair,
            _ => &self.dummy_split,
        };
        let (split_prev, split_out) =
            (v(&split[read], "temporal.history_split_prev"), v(&split[write], "temporal.history_split"));
        let tv = wgpu::BindingResource::TextureView;
        let stand_in = v(&self.dummy_confidence, "temporal.confidence.unused");
        // The merge's resources: for this frame's pass (`later` false), or for the pass that
        // computes the confidence alone when it is read.
        let resources = |later: bool| {
            let (params, conf) = match (later, self.store_confidence) {
                (true, _) => (&self.confidence_params, &conf),
                (false, store) => (&self.params, if store { &conf } else { &stand_in }),
            };
            [
                params.as_entire_binding(),
                tv(current),
                tv(&g.linear_depth),
                tv(&g.packed_normal),
                tv(&g.motion),
                tv(&prev_n),
                tv(&hist_prev),
                tv(conf),
                tv(&hist),
                tv(&normal_out),
                tv(&g.albedo),
                tv(irradiance.unwrap_or(current)),
                tv(&split_prev),
                tv(&split_out),
            ]
        };
        let group_of = |later| match filter {
            None => CONFIDENCE_BINDINGS.group(&ctx.device, &self.layout, resources(later)),
            Some(filter) => {
                let all = resources(later).into_iter().chain([filter.as_entire_binding()]);
                FILTER_MERGE_BINDINGS.group(&ctx.device, &self.fused_layout, all)
            }
        };
        let (pipeline, label) = match filter {
            None => (&self.pipeline[demodulate as usize], "temporal.confidence"),
            Some(_) => (&self.fused_pipeline[demodulate as usize], "temporal.filter_merge"),
        };
        let group = group_of(false);
        // Without the confidence, the same pass computes it alone when it is read.
        let later = (!self.store_confidence).then(|| (pipeline, group_of(true)));
        self.confidence_on_read.arm(later);
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(label),
                timestamp_writes: slot.and_then(|s| s.compute(true, true)),
            });
            pass.set_pipe(pipeline);
            pass.set_group(0, &group, &[]);
            pass.dispatch(self.width.div_ceil(crate::passes::TILE), self.height.div_ceil(crate::passes::TILE), 1);
        }
        let decoded = v(&self.normals[write], "temporal.prev_normal");
        let decode = demodulate.then(|| {
            let views = [&decoded, &split_out].map(wgpu::BindingResource::TextureView);
            SPLIT_NORMAL_BINDINGS.group(&ctx.device, &self.split_normal_layout, views)
        });
        match decode {
            Some(group) if self.decode_normals => {
                let size = (self.width, self.height);
                let pipeline = &self.split_normal_pipeline;
                crate::passes::dispatch_2d(encoder, "temporal.prev_normal", pipeline, &group, &[], None, size);
                self.split_normal.arm(None);
            }
            other => self.split_normal.arm(other.map(|group| (&self.split_normal_pipeline, group))),
        }
        self.current = write;
        self.split_read = demodulate && self.valid;
        self.split_written = demodulate;
        self.valid = true;
    }
}
