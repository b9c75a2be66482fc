//! Explain a pixel (issue #42) for Soler et al.'s screen-space gather (004 §4, Fig. 4, Eq. 6):
//! `shaders/soler/explain.wgsl` replays the joint bilateral upsampling's weights from the
//! pixel up the levels (the same `jbu_weights` the upsampling runs) and reads each reached
//! texel's own gathered irradiance (the ring samples' sum) and the light the voxel visibility
//! removed there; [`decode`] makes the contributions: per level and texel, w · E · c·DI/π,
//! scaled by Eq. 6's 1 − a, and the warped history's a · c·DI/π · W (or a · W when the
//! radiance is blended). The stage replays each bounce right after gathering it (the levels'
//! light is that bounce's until the next one), and with alternating bounces reads the bounces
//! it did not gather this frame from what it kept (the stage's `run`).

use crate::counters::prelude::*;

use glam::{Vec3, Vec4};

use crate::explain::{Check, Contribution, Explanation, Rejection, Replay};
use crate::gpu::GpuContext;
use crate::gpu::bindings::{Bindings, Kind, binding};

/// Bind group `explain.soler.inputs` of `shaders/soler/explain.wgsl` (group 0): a pixel's
/// replay of the gathers and the upsampling, bounce by bounce.
pub const SOLER_INPUTS_BINDINGS: Bindings = Bindings {
    label: "explain.soler.inputs",
    shader: "soler/explain.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "step", Kind::UniformDynamic),
        binding(1, "fine_position", Kind::Texture { filterable: false }),
        binding(2, "fine_normal", Kind::Texture { filterable: false }),
        binding(3, "fine_light", Kind::Texture { filterable: false }),
        binding(4, "fine_occlusion", Kind::Texture { filterable: false }),
        binding(5, "coarse_position", Kind::Texture { filterable: false }),
        binding(6, "coarse_normal", Kind::Texture { filterable: false }),
        binding(7, "indirect", Kind::Texture { filterable: false }),
        binding(8, "last", Kind::Texture { filterable: false }),
        binding(9, "warped", Kind::Texture { filterable: false }),
        binding(10, "blend_a", Kind::Texture { filterable: false }),
        binding(11, "g_albedo", Kind::Texture { filterable: false }),
        binding(12, "header", Kind::Storage { read_only: false }),
        binding(13, "entries", Kind::Storage { read_only: false }),
        binding(14, "fine_specular", Kind::Texture { filterable: false }),
        binding(15, "g_motion", Kind::Texture { filterable: false }),
        binding(16, "spec_history_prev", Kind::Texture { filterable: false }),
    ],
};

/// Bind group `explain.soler.ring.inputs` of `shaders/soler/explain_ring.wgsl` (group 0).
pub const SOLER_RING_INPUTS_BINDINGS: Bindings = Bindings {
    label: "explain.soler.ring.inputs",
    shader: "soler/explain_ring.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "params", Kind::UniformDynamic),
        binding(1, "level_position", Kind::Texture { filterable: false }),
        binding(2, "level_normal", Kind::Texture { filterable: false }),
        binding(3, "level_radiance", Kind::Texture { filterable: false }),
        binding(4, "grid", Kind::Storage { read_only: true }),
        binding(5, "level_material", Kind::Texture { filterable: false }),
        binding(6, "ring", Kind::UniformDynamic),
        binding(7, "header_words", Kind::Storage { read_only: true }),
        binding(8, "entries", Kind::Storage { read_only: true }),
        binding(9, "slots", Kind::Storage { read_only: false }),
    ],
};

/// Texels per level the replay follows (`MAX_PER_LEVEL` in the shader).
const MAX_PER_LEVEL: u64 = 64;
/// Levels at most per bounce.
const MAX_LEVELS: u64 = 16;
/// Bounces at most (`gather::MAX_BOUNCES`).
const MAX_BOUNCES: u64 = 4;
const ENTRIES_OFFSET: u64 = 512;
/// Uniform slots are 256 bytes apart (dynamic offsets).
const STRIDE: u64 = 256;

/// WGSL twin: `StepParams`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
struct StepParams {
    level: [u32; 4],
    sigma: [f32; 4],
}

/// Ring samples listed per texel (`MAX_RING` in `soler/explain_ring.wgsl`).
const MAX_RING: u64 = 256;

/// WGSL twin: `RingParams`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
struct RingParams {
    list: [u32; 4],
}

/// One ring sample; WGSL twin: `RingOut`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuRingTerm {
    pub sender: Vec4,
    pub light: Vec4,
    pub position: Vec4,
    pub spec: Vec4,
}

/// The ring of one list's heaviest texel; WGSL twin: `RingSlot`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuRingHead {
    pub texel: [u32; 4],
}

/// WGSL twin: `Entry`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuEntry {
    pub texel: [u32; 4],
    pub weight: Vec4,
    pub own: Vec4,
    pub occlusion: Vec4,
    pub position: Vec4,
    pub spec: Vec4,
}

/// WGSL twin: `Header`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuHeader {
    pub pixel: [u32; 4],
    pub counts: [u32; 64],
    pub indirect: Vec4,
    pub last: Vec4,
    pub history: Vec4,
    pub albedo: Vec4,
    pub spec_history: Vec4,
    pub kept: [Vec4; 4],
}

/// One level of the chain: its position and normal, and (gathered levels) its own light and
/// occlusion.
pub struct LevelViews {
    pub position: wgpu::TextureView,
    pub normal: wgpu::TextureView,
    pub own: Option<(wgpu::TextureView, wgpu::TextureView)>,
    /// Its own glossy light (gathered levels with the glossy reflection).
    pub spec: Option<wgpu::TextureView>,
}

/// What the replay reads of the frame.
pub struct SolerExplainInputs<'a> {
    pub pixel: (u32, u32),
    /// Levels 0 (the G-buffer) … top.
    pub levels: Vec<LevelViews>,
    pub sigma: [f32; 2],
    pub indirect: wgpu::TextureView,
    /// The stage's output, and Eq. 6's W and a when the temporal filter ran.
    pub last: wgpu::TextureView,
    pub temporal: Option<(wgpu::TextureView, wgpu::TextureView)>,
    pub albedo: &'a wgpu::TextureView,
    pub motion: &'a wgpu::TextureView,
    /// The glossy light's history Eq. 6 read (with the temporal filter).
    pub spec_history: Option<wgpu::TextureView>,
}

/// What decode needs of the run.
#[derive(Clone, Debug, PartialEq)]
pub struct SolerChain {
    pub pixel: (u32, u32),
    /// Bounces n, and those this frame gathered (the others are read from what was kept).
    pub bounces: u32,
    pub gathered_bounces: Vec<u32>,
    pub levels: u32,
    pub gathered: std::ops::Range<u32>,
    pub temporal: bool,
    /// Eq. 6 blends the irradiance (the history is multiplied by c·DI/π), not the radiance.
    pub irradiance_blend: bool,
    pub technique: String,
    pub samples: u32,
    /// The ring's radius r in level texels (`soler.radius_px`).
    pub radius: f32,
}

pub struct SolerExplainPass {
    layout: wgpu::BindGroupLayout,
    pixel_pipeline: wgpu::ComputePipeline,
    step_pipeline: wgpu::ComputePipeline,
    kept_pipeline: wgpu::ComputePipeline,
    ring_layout: wgpu::BindGroupLayout,
    ring_pipeline: wgpu::ComputePipeline,
    ring_params: wgpu::Buffer,
    /// Per list, the ring of its heaviest texel (`GpuRingHead` then `MAX_RING` terms).
    pub rings: wgpu::Buffer,
    params: wgpu::Buffer,
    pub out: wgpu::Buffer,
    dummy: wgpu::TextureView,
    pub info: Option<SolerChain>,
}

impl SolerExplainPass {
    pub fn new(ctx: &GpuContext) -> Self {
        let device = &ctx.device;
        let layout = SOLER_INPUTS_BINDINGS.layout(device);
        let ring_layout = SOLER_RING_INPUTS_BINDINGS.layout(device);
        let ring_module = crate::shaders::create_module(device, "soler/explain_ring.wgsl");
        let ring_pipeline = crate::passes::compute_pipeline(
            device,
            "explain.soler.ring",
            &ring_module,
            "cs_explain_ring",
            &[&ring_layout],
        );
        let module = crate::shaders::create_module(device, "soler/explain.wgsl");
        let pipeline = |label, entry| crate::passes::compute_pipeline(device, label, &module, entry, &[&layout]);
        let dummy = crate::passes::view(
            &crate::passes::create_target(
                device,
                "explain.soler.none",
                1,
                1,
                wgpu::TextureFormat::Rgba32Float,
                wgpu::TextureUsages::empty(),
            ),
            "explain.soler.none",
        );
        Self {
            pixel_pipeline: pipeline("explain.soler.pixel", "cs_explain_pixel"),
            step_pipeline: pipeline("explain.soler.step", "cs_explain_step"),
            kept_pipeline: pipeline("explain.soler.kept", "cs_explain_kept"),
            ring_layout,
            ring_pipeline,
            ring_params: crate::passes::uniform_buffer(
                device,
                "explain.soler.ring.params",
                STRIDE * MAX_BOUNCES * MAX_LEVELS,
            ),
            rings: crate::passes::buffer(
                device,
                "explain.soler.rings",
                Self::ring_bytes(),
                wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            ),
            layout,
            params: crate::passes::uniform_buffer(
                device,
                "explain.soler.params",
                STRIDE * (MAX_BOUNCES * MAX_LEVELS + MAX_BOUNCES),
            ),
            out: device.counted_buffer(&wgpu::BufferDescriptor {
                label: Some("explain.soler.out"),
                size: Self::bytes_of(),
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            dummy,
            info: None,
        }
    }

    /// One list's ring slot, and all of them.
    fn ring_slot() -> u64 {
        (std::mem::size_of::<GpuRingHead>() + MAX_RING as usize * std::mem::size_of::<GpuRingTerm>()) as u64
    }

    fn ring_bytes() -> u64 {
        MAX_BOUNCES * MAX_LEVELS * Self::ring_slot()
    }

    fn bytes_of() -> u64 {
        ENTRIES_OFFSET + MAX_BOUNCES * MAX_LEVELS * MAX_PER_LEVEL * std::mem::size_of::<GpuEntry>() as u64
    }

    /// Starts the frame's replay: every bounce's list holds pixel p at level 0 with weight 1;
    /// the uniforms of every step (bounce b, level k: slot b·16 + k; the kept bounce b: slot
    /// 64 + b).
    pub fn begin(&mut self, ctx: &GpuContext, levels: &[LevelViews], sigma: [f32; 2], info: SolerChain) {
        let n = levels.len().min(MAX_LEVELS as usize);
        let mut header: GpuHeader = bytemuck::Zeroable::zeroed();
        header.pixel = [info.pixel.0, info.pixel.1, 0, 0];
        for b in 0..MAX_BOUNCES as usize {
            header.counts[b * MAX_LEVELS as usize] = 1;
            let first = GpuEntry {
                texel: [info.pixel.0, info.pixel.1, 0, 0],
                weight: Vec4::new(1.0, 0.0, 0.0, 0.0),
                own: Vec4::ZERO,
                occlusion: Vec4::ZERO,
                position: Vec4::ZERO,
                spec: Vec4::ZERO,
            };
            let at = ENTRIES_OFFSET + (b as u64 * MAX_LEVELS * MAX_PER_LEVEL) * std::mem::size_of::<GpuEntry>() as u64;
            ctx.queue.upload(&self.out, at, bytemuck::bytes_of(&first));
        }
        ctx.queue.upload(&self.out, 0, bytemuck::bytes_of(&header));
        let mut params: Vec<StepParams> = Vec::new();
        for b in 0..MAX_BOUNCES as u32 {
            params.extend((0..MAX_LEVELS as usize).map(|k| StepParams {
                level: [k as u32, levels.get(k).is_some_and(|l| l.own.is_some()) as u32, (k + 1 >= n) as u32, b],
                sigma: [sigma[0], sigma[1], 0.0, 0.0],
            }));
        }
        let spec = levels.iter().any(|l| l.spec.is_some()) as u32;
        params.extend((0..MAX_BOUNCES as u32).map(|b| StepParams { level: [0, spec, 1, b], sigma: [0.0; 4] }));
        ctx.queue.upload(&self.params, 0, &crate::passes::strided_bytes(STRIDE, params.len(), &params));
        let rings: Vec<RingParams> = (0..(MAX_BOUNCES * MAX_LEVELS) as u32)
            .map(|list| {
                let k = list % MAX_LEVELS as u32;
                RingParams { list: [list, info.gathered.contains(&k) as u32, 0, 0] }
            })
            .collect();
        ctx.queue.upload(&self.ring_params, 0, &crate::passes::strided_bytes(STRIDE, rings.len(), &rings));
        self.info = Some(info);
    }

    /// A bind group of the layout: level `l` and the one above it (`coarse`), `light` and
    /// `spec` as the level's own light, and the frame's buffers at the pixel.
    fn group(
        &self,
        ctx: &GpuContext,
        inp: &SolerExplainInputs,
        (l, coarse): (&LevelViews, &LevelViews),
        (light, occlusion, spec): (&wgpu::TextureView, &wgpu::TextureView, &wgpu::TextureView),
    ) -> wgpu::BindGroup {
        let (w, a) = inp.temporal.as_ref().map(|(w, a)| (w, a)).unwrap_or((&self.dummy, &self.dummy));
        let views = [
            &l.position,
            &l.normal,
            light,
            occlusion,
            &coarse.position,
            &coarse.normal,
            &inp.indirect,
            &inp.last,
            w,
            a,
            inp.albedo,
        ];
        let mut resources = vec![crate::passes::dynamic_slot(&self.params, std::mem::size_of::<StepParams>())];
        resources.extend(views.into_iter().map(wgpu::BindingResource::TextureView));
        resources.push(crate::passes::buffer_part(&self.out, 0, Some(std::mem::size_of::<GpuHeader>() as u64)));
        resources.push(crate::passes::buffer_part(&self.out, ENTRIES_OFFSET, None));
        let spec_history = inp.spec_history.as_ref().unwrap_or(&self.dummy);
        resources.extend([spec, inp.motion, spec_history].map(wgpu::BindingResource::TextureView));
        SOLER_INPUTS_BINDINGS.group(&ctx.device, &self.layout, resources)
    }

    /// One dispatch of `pipeline`, alone in its pass (each reads what the one before wrote).
    fn dispatch(enc: &mut wgpu::CommandEncoder, pipeline: &wgpu::ComputePipeline, group: &wgpu::BindGroup, slot: u64) {
        let mut pass = enc
            .begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("explain.soler"), timestamp_writes: None });
        pass.set_pipe(pipeline);
        pass.set_bind_group(0, group, &[(slot * STRIDE) as u32]);
        pass.dispatch(1, 1, 1);
    }

    /// Bounce `b`, right after the stage gathered and upsampled it: its levels' texels, their
    /// weights and own light.
    pub fn bounce(
        &self,
        ctx: &GpuContext,
        enc: &mut wgpu::CommandEncoder,
        inp: &SolerExplainInputs,
        b: u32,
        (levels, j, gather_params): (&[super::gather::LevelInputs], u32, &wgpu::Buffer),
    ) {
        let n = inp.levels.len().min(MAX_LEVELS as usize);
        for k in 0..n {
            let l = &inp.levels[k];
            let coarse = inp.levels.get(k + 1).unwrap_or(l);
            let (own, occlusion) = l.own.as_ref().map(|(o, c)| (o, c)).unwrap_or((&self.dummy, &self.dummy));
            let spec = l.spec.as_ref().unwrap_or(&self.dummy);
            let group = self.group(ctx, inp, (l, coarse), (own, occlusion, spec));
            Self::dispatch(enc, &self.step_pipeline, &group, b as u64 * MAX_LEVELS + k as u64);
        }
        // The heaviest texel of each gathered level gathers its ring again, sample by sample.
        let part = |offset, size| crate::passes::buffer_part(&self.out, offset, size);
        // Level i of bounce gathered j read the gather's uniform slot j · n + i
        // (`SolerGather::write_params`); its list is b · 16 + its level.
        for (i, r) in levels.iter().enumerate() {
            let slot = j as u64 * levels.len() as u64 + i as u64;
            let list = b as u64 * MAX_LEVELS + r.level as u64;
            let tv = wgpu::BindingResource::TextureView;
            let resources = vec![
                crate::passes::dynamic_slot(gather_params, std::mem::size_of::<super::gather::GatherParams>()),
                tv(r.position),
                tv(r.normal),
                tv(r.radiance),
                r.grid.as_entire_binding(),
                tv(r.material),
                crate::passes::dynamic_slot(&self.ring_params, std::mem::size_of::<RingParams>()),
                part(0, Some(std::mem::size_of::<GpuHeader>() as u64)),
                part(ENTRIES_OFFSET, None),
                self.rings.as_entire_binding(),
            ];
            let group = SOLER_RING_INPUTS_BINDINGS.group(&ctx.device, &self.ring_layout, resources);
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("explain.soler.ring"),
                timestamp_writes: None,
            });
            pass.set_pipe(&self.ring_pipeline);
            pass.set_bind_group(0, &group, &[(slot * STRIDE) as u32, (list * STRIDE) as u32]);
            pass.dispatch(1, 1, 1);
        }
    }

    /// After the stage: the pixel's buffers, and the bounces it kept (`kept`: bounce, its light
    /// and glossy light) but did not gather this frame.
    pub fn finish(
        &self,
        ctx: &GpuContext,
        enc: &mut wgpu::CommandEncoder,
        inp: &SolerExplainInputs,
        kept: &[(u32, wgpu::TextureView, Option<wgpu::TextureView>)],
    ) {
        let Some(l) = inp.levels.first() else { return };
        let group = self.group(ctx, inp, (l, l), (&self.dummy, &self.dummy, &self.dummy));
        Self::dispatch(enc, &self.pixel_pipeline, &group, 0);
        for (b, light, spec) in kept {
            let group = self.group(ctx, inp, (l, l), (light, &self.dummy, spec.as_ref().unwrap_or(&self.dummy)));
            Self::dispatch(enc, &self.kept_pipeline, &group, MAX_BOUNCES * MAX_LEVELS + *b as u64);
        }
    }
}

/// The passes of the stage whose outputs the replay reads (issue #52: the explain replay
/// takes its inputs, not the stage).
#[derive(Clone, Copy)]
pub struct StageParts<'s> {
    pub pyramid: &'s super::pyramid::SolerPyramid,
    pub gather: &'s super::gather::SolerGather,
    pub upsample: &'s super::upsample::SolerUpsample,
    pub temporal: Option<&'s super::temporal::SolerTemporal>,
}

/// The replay's inputs from the stage's passes as they stand (after a bounce: the levels'
/// light is that bounce's).
pub fn inputs<'a>(
    stage: StageParts<'_>,
    f: &'a crate::passes::stages::FrameInputs,
    pixel: (u32, u32),
) -> SolerExplainInputs<'a> {
    let s = &f.settings.soler;
    let (start, top) = (s.gathered_levels().start, s.gathered_levels().end - 1);
    let v = |t: &wgpu::Texture| crate::passes::view(t, "explain.soler.level");
    let levels = (0..=top)
        .map(|k| {
            let (position, normal) = match k {
                0 => (f.gbuffer.position.clone(), f.gbuffer.normal.clone()),
                _ => match stage.pyramid.levels.get(k as usize - 1) {
                    Some(l) => (v(&l.position), v(&l.normal)),
                    None => (f.gbuffer.position.clone(), f.gbuffer.normal.clone()),
                },
            };
            let i = k.checked_sub(start).map(|i| i as usize);
            let own = i.and_then(|i| Some((v(&stage.gather.light.get(i)?.1), v(stage.gather.occlusion.get(i)?))));
            let spec = i.filter(|_| s.glossy_reflection).and_then(|i| Some(v(stage.gather.specular.get(i)?)));
            LevelViews { position, normal, own, spec }
        })
        .collect();
    let indirect = v(&stage.upsample.indirect);
    let (last, temporal, spec_history) = match stage.temporal {
        Some(t) => (v(&t.filtered), Some((v(&t.warped), v(&t.a))), Some(v(t.spec_history_prev()))),
        None => (indirect.clone(), None, None),
    };
    SolerExplainInputs {
        pixel,
        levels,
        sigma: [s.upsample_sigma_depth, s.upsample_sigma_normal],
        indirect,
        last,
        temporal,
        albedo: &f.gbuffer.albedo,
        motion: &f.gbuffer.motion,
        spec_history,
    }
}

/// What decode needs of this frame's stage (`bounces`: the bounces it gathers).
pub fn chain(f: &crate::passes::stages::FrameInputs, pixel: (u32, u32), bounces: &[u32], temporal: bool) -> SolerChain {
    let s = &f.settings.soler;
    let n = s.bounces.clamp(1, MAX_BOUNCES as u32);
    SolerChain {
        pixel,
        bounces: n,
        gathered_bounces: bounces.to_vec(),
        levels: s.gathered_levels().end,
        gathered: s.gathered_levels(),
        temporal,
        irradiance_blend: s.temporal_quantity != super::TemporalQuantity::Radiance,
        technique: format!(
            "{}screen-space mip levels (Soler): levels {}…{} gathered with {} samples of r = {} texels, joint \
             bilateral upsampling{}{}",
            if f.settings.pipeline.gather == crate::settings::pipeline::Gather::Vpl { "near field: " } else { "" },
            s.gathered_levels().start,
            s.gathered_levels().end - 1,
            s.samples,
            s.radius_px,
            match (n, s.alternate_bounces) {
                (1, _) => String::new(),
                (n, false) => format!(", {n} bounces"),
                (n, true) => format!(", {n} bounces, one gathered per frame in turn"),
            },
            if temporal { ", Eq. 6's warped blend" } else { "" }
        ),
        samples: s.samples,
        radius: s.radius_px,
    }
}

impl Replay for SolerExplainPass {
    fn parts(&self) -> Option<Vec<(wgpu::Buffer, u64)>> {
        self.info.as_ref()?;
        Some(vec![(self.out.clone(), Self::bytes_of()), (self.rings.clone(), Self::ring_bytes())])
    }

    fn decode(&self, parts: &[Vec<u8>]) -> Option<Explanation> {
        let [out, rings] = parts else { return None };
        decode(self.info.as_ref()?, out, rings)
    }
}

/// The pixel's explanation from the replay's output.
pub fn decode(info: &SolerChain, bytes: &[u8], rings: &[u8]) -> Option<Explanation> {
    let header: GpuHeader = bytemuck::pod_read_unaligned(bytes.get(..std::mem::size_of::<GpuHeader>())?);
    if (header.pixel[0], header.pixel[1]) != info.pixel {
        return None;
    }
    let size = std::mem::size_of::<GpuEntry>();
    let entries: Vec<GpuEntry> = bytemuck::pod_collect_to_vec(
        bytes.get(ENTRIES_OFFSET as usize..)?.get(..(MAX_BOUNCES * MAX_LEVELS * MAX_PER_LEVEL) as usize * size)?,
    );
    let v3 = |v: Vec4| v.truncate();
    let k_p = v3(header.albedo);
    let a = if info.temporal { header.history.w } else { 0.0 };
    let mut contributions = Vec::new();
    let mut checks = Vec::new();
    let mut gathered_sum = Vec3::ZERO;
    let mut notes = Vec::new();
    let several = info.bounces > 1;
    for &b in &info.gathered_bounces {
        for k in 0..info.levels.min(MAX_LEVELS as u32) {
            let list = (b as u64 * MAX_LEVELS + k as u64) as usize;
            let n = header.counts[list] as usize;
            if n as u64 >= MAX_PER_LEVEL {
                notes.push(format!(
                    "level {k}: more than {MAX_PER_LEVEL} texels reach the pixel; the replay follows the first"
                ));
            }
            if !info.gathered.contains(&k) {
                continue;
            }
            let base = list * MAX_PER_LEVEL as usize;
            let bounce = if several { format!("bounce {} ", b + 1) } else { String::new() };
            let ring = ring_of(rings, list)?;
            for e in entries.get(base..base + n)? {
                let w = e.weight.x;
                let own = v3(e.own);
                let spec = v3(e.spec);
                gathered_sum += (own * k_p + spec) * w;
                if w <= 0.0 {
                    continue;
                }
                // The heaviest texel's ring, sample by sample, in place of its sum.
                if let Some((head, terms)) = &ring
                    && head.texel[2] == 1
                    && (head.texel[0], head.texel[1]) == (e.texel[0], e.texel[1])
                    && head.texel[3] as u64 <= MAX_RING
                {
                    let (rows, check) = ring_rows(&bounce, k, e, terms, (k_p, a, info.radius));
                    checks.push(check);
                    // A ring with no lit sample lists none: the texel's own row says so.
                    if !rows.is_empty() {
                        contributions.extend(rows);
                        continue;
                    }
                }
                contributions.push(Contribution {
                    name: format!("{bounce}level {k} ({}, {})", e.texel[0], e.texel[1]),
                    source: format!(
                        "ring gather of level {k} ({} samples){}",
                        info.samples,
                        match b {
                            0 => String::new(),
                            _ => format!(", of bounce {b}'s light"),
                        }
                    ),
                    position: Some(v3(e.position)),
                    value: (own * k_p + spec) * w * (1.0 - a),
                    weight: w * (1.0 - a),
                    rejected: None,
                    via: None,
                    fields: vec![
                        ("level", k as f32),
                        ("bounce", (b + 1) as f32),
                        ("w (upsampling)", w),
                        ("E (lum)", crate::explain::luminance(own)),
                        ("hidden by voxels (lum)", crate::explain::luminance(v3(e.occlusion))),
                        ("visible fraction", e.occlusion.w),
                        ("S glossy (lum)", crate::explain::luminance(spec)),
                        // The ring this texel gathered, in full-resolution pixels (r · 2^k).
                        ("ring radius (px)", info.radius * (1u32 << k.min(30)) as f32),
                    ],
                });
            }
        }
    }
    // The bounces this frame did not gather (alternating bounces): their kept light.
    for b in (0..info.bounces.min(MAX_BOUNCES as u32)).filter(|b| !info.gathered_bounces.contains(b)) {
        let kept = v3(header.kept[b as usize]);
        gathered_sum += kept;
        contributions.push(Contribution {
            name: format!("bounce {} (kept)", b + 1),
            source: "gathered in an earlier frame (alternating bounces, §5.3)".into(),
            position: None,
            value: kept * (1.0 - a),
            weight: 1.0 - a,
            rejected: None,
            via: None,
            fields: vec![("bounce", (b + 1) as f32)],
        });
    }
    if info.temporal {
        let history =
            v3(header.history) * if info.irradiance_blend { k_p } else { Vec3::ONE } + v3(header.spec_history);
        contributions.push(Contribution {
            name: "history".into(),
            source: "previous frame, warped (Eq. 6)".into(),
            position: None,
            value: history * a,
            weight: a,
            rejected: None,
            via: None,
            fields: vec![("a", a)],
        });
        notes.push(format!("Eq. 6: a = {a:.4} at the pixel (the history's share; this frame's levels weigh 1 − a)"));
    }
    notes.push("each level's E is the sum of its ring samples (soler.level.k.indirect); the light its voxel visibility removed is 'hidden by voxels'".into());
    checks.insert(
        0,
        Check {
            what: if several {
                "Σ bounces and levels w · (E · c·DI/π + S)".into()
            } else {
                "Σ levels w · (E · c·DI/π + S)".into()
            },
            sum: gathered_sum,
            buffer: "soler.indirect".into(),
            value: v3(header.indirect),
        },
    );
    let mut e = Explanation {
        pixel: info.pixel,
        technique: info.technique.clone(),
        contributions,
        buffer: if info.temporal { "soler.temporal".into() } else { "soler.indirect".into() },
        value: v3(header.last),
        checks,
        notes,
    };
    e.sort();
    Some(e)
}

/// List `list`'s ring slot: its head and its sample terms (None when the bytes are short).
fn ring_of(rings: &[u8], list: usize) -> Option<Option<(GpuRingHead, Vec<GpuRingTerm>)>> {
    let slot = SolerExplainPass::ring_slot() as usize;
    let bytes = rings.get(list * slot..(list + 1) * slot)?;
    let head: GpuRingHead = bytemuck::pod_read_unaligned(bytes.get(..16)?);
    if head.texel[2] != 1 {
        return Some(None);
    }
    let n = (head.texel[3] as usize).min(MAX_RING as usize);
    let size = std::mem::size_of::<GpuRingTerm>();
    let terms = bytemuck::pod_collect_to_vec(bytes.get(16..16 + n * size)?);
    Some(Some((head, terms)))
}

/// The rows of a texel's ring samples (the visible ones with their share, those the voxels
/// hid as occluded; samples that do not count, off the level or on a sender facing away, are
/// left out), and the check of their sum against the texel's own light.
fn ring_rows(
    bounce: &str,
    k: u32,
    e: &GpuEntry,
    terms: &[GpuRingTerm],
    (k_p, a, radius): (Vec3, f32, f32),
) -> (Vec<Contribution>, Check) {
    let (x, y) = (e.texel[0], e.texel[1]);
    let w = e.weight.x;
    let mut sum = Vec3::ZERO;
    let mut rows = Vec::new();
    let (mut lit, mut hidden) = (0u32, 0u32);
    for (i, t) in terms.iter().enumerate() {
        if t.sender.z < 0.5 {
            continue;
        }
        lit += 1;
        let visible = t.sender.w > 0.5;
        let light = t.light.truncate();
        let spec = t.spec.truncate();
        if visible {
            sum += light;
        } else {
            hidden += 1;
        }
        rows.push(Contribution {
            name: format!("{bounce}level {k} ({x}, {y}) #{i}"),
            source: format!("ring sample {i} of level {k} texel ({x}, {y}), from ({}, {})", t.sender.x, t.sender.y),
            position: Some(t.position.truncate()),
            value: if visible { (light * k_p + spec) * w * (1.0 - a) } else { Vec3::ZERO },
            weight: w * (1.0 - a),
            rejected: (!visible).then_some(Rejection::Occluded),
            via: None,
            fields: vec![
                ("level", k as f32),
                ("w (upsampling)", w),
                ("L·K (lum)", crate::explain::luminance(light)),
                ("S glossy (lum)", crate::explain::luminance(spec)),
                ("ring radius (px)", radius * (1u32 << k.min(30)) as f32),
            ],
        });
    }
    let check = Check {
        what: format!("Σ visible ring samples of level {k} ({x}, {y}) ({lit} lit, {hidden} hidden by voxels)"),
        sum,
        buffer: format!("soler.level.{k}.indirect"),
        value: e.own.truncate(),
    };
    (rows, check)
}
