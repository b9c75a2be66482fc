//! Explain a pixel (issue #42) for Soler et al.'s screen-space gather (004 §4, Fig. 4, Eq. 6):
//! `shaders/soler/explain.wgsl` replays the joint bilateral upsampling's weights from the
//! pixel up the levels (the same `jbu_weights` the upsampling runs) and reads each reached
//! texel's own gathered irradiance (the ring samples' sum) and the light the voxel visibility
//! removed there; [`decode`] makes the contributions: per level and texel, w · E · c·DI/π,
//! scaled by Eq. 6's 1 − a, and the warped history's a · c·DI/π · W (or a · W when the
//! radiance is blended). The stage replays each bounce right after gathering it (the levels'
//! light is that bounce's until the next one), and with alternating bounces reads the bounces
//! it did not gather this frame from what it kept (`SolerStage::run`).

use crate::counters::prelude::*;

use glam::{Vec3, Vec4};

use crate::explain::{Check, Contribution, Explanation, Replay};
use crate::gpu::GpuContext;
use crate::passes::bgl;

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
    params: wgpu::Buffer,
    pub out: wgpu::Buffer,
    dummy: wgpu::TextureView,
    pub info: Option<SolerChain>,
}

impl SolerExplainPass {
    pub fn new(ctx: &GpuContext) -> Self {
        let device = &ctx.device;
        let cs = wgpu::ShaderStages::COMPUTE;
        let mut entries = vec![bgl::uniform_dynamic(0, cs)];
        entries.extend((1..=11).map(|b| bgl::texture(b, cs, false)));
        entries.push(bgl::storage(12, cs, false));
        entries.push(bgl::storage(13, cs, false));
        entries.extend((14..=16).map(|b| bgl::texture(b, cs, false)));
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("explain.soler.inputs"),
            entries: &entries,
        });
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
            ctx.queue.write_buffer(&self.out, at, bytemuck::bytes_of(&first));
        }
        ctx.queue.write_buffer(&self.out, 0, bytemuck::bytes_of(&header));
        let mut params: Vec<StepParams> = Vec::new();
        for b in 0..MAX_BOUNCES as u32 {
            params.extend((0..MAX_LEVELS as usize).map(|k| StepParams {
                level: [k as u32, levels.get(k).is_some_and(|l| l.own.is_some()) as u32, (k + 1 >= n) as u32, b],
                sigma: [sigma[0], sigma[1], 0.0, 0.0],
            }));
        }
        let spec = levels.iter().any(|l| l.spec.is_some()) as u32;
        params.extend((0..MAX_BOUNCES as u32).map(|b| StepParams { level: [0, spec, 1, b], sigma: [0.0; 4] }));
        ctx.queue.write_buffer(&self.params, 0, &crate::passes::strided_bytes(STRIDE, params.len(), &params));
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
        resources.push(wgpu::BindingResource::Buffer(wgpu::BufferBinding {
            buffer: &self.out,
            offset: 0,
            size: wgpu::BufferSize::new(std::mem::size_of::<GpuHeader>() as u64),
        }));
        resources.push(wgpu::BindingResource::Buffer(wgpu::BufferBinding {
            buffer: &self.out,
            offset: ENTRIES_OFFSET,
            size: None,
        }));
        let spec_history = inp.spec_history.as_ref().unwrap_or(&self.dummy);
        resources.extend([spec, inp.motion, spec_history].map(wgpu::BindingResource::TextureView));
        crate::passes::bind_group(&ctx.device, "explain.soler.inputs", &self.layout, resources)
    }

    /// One dispatch of `pipeline`, alone in its pass (each reads what the one before wrote).
    fn dispatch(enc: &mut wgpu::CommandEncoder, pipeline: &wgpu::ComputePipeline, group: &wgpu::BindGroup, slot: u64) {
        let mut pass = enc
            .begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("explain.soler"), timestamp_writes: None });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, group, &[(slot * STRIDE) as u32]);
        pass.dispatch_workgroups(1, 1, 1);
    }

    /// Bounce `b`, right after the stage gathered and upsampled it: its levels' texels, their
    /// weights and own light.
    pub fn bounce(&self, ctx: &GpuContext, enc: &mut wgpu::CommandEncoder, inp: &SolerExplainInputs, b: u32) {
        let n = inp.levels.len().min(MAX_LEVELS as usize);
        for k in 0..n {
            let l = &inp.levels[k];
            let coarse = inp.levels.get(k + 1).unwrap_or(l);
            let (own, occlusion) = l.own.as_ref().map(|(o, c)| (o, c)).unwrap_or((&self.dummy, &self.dummy));
            let spec = l.spec.as_ref().unwrap_or(&self.dummy);
            let group = self.group(ctx, inp, (l, coarse), (own, occlusion, spec));
            Self::dispatch(enc, &self.step_pipeline, &group, b as u64 * MAX_LEVELS + k as u64);
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

/// The replay's inputs from the stage as it stands (after a bounce: the levels' light is that
/// bounce's).
pub fn inputs<'a>(
    stage: &super::stage::SolerStage,
    f: &'a crate::stages::FrameInputs,
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
    let (last, temporal, spec_history) = match &stage.temporal {
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
pub fn chain(f: &crate::stages::FrameInputs, pixel: (u32, u32), bounces: &[u32], temporal: bool) -> SolerChain {
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
            if f.settings.pipeline.gather == crate::pipeline::Gather::Vpl { "near field: " } else { "" },
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
        Some(vec![(self.out.clone(), Self::bytes_of())])
    }

    fn decode(&self, parts: &[Vec<u8>]) -> Option<Explanation> {
        decode(self.info.as_ref()?, parts.first()?)
    }
}

/// The pixel's explanation from the replay's output.
pub fn decode(info: &SolerChain, bytes: &[u8]) -> Option<Explanation> {
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
            for e in entries.get(base..base + n)? {
                let w = e.weight.x;
                let own = v3(e.own);
                let spec = v3(e.spec);
                gathered_sum += (own * k_p + spec) * w;
                if w <= 0.0 {
                    continue;
                }
                let bounce = if several { format!("bounce {} ", b + 1) } else { String::new() };
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
    let checks = vec![Check {
        what: if several {
            "Σ bounces and levels w · (E · c·DI/π + S)".into()
        } else {
            "Σ levels w · (E · c·DI/π + S)".into()
        },
        sum: gathered_sum,
        buffer: "soler.indirect".into(),
        value: v3(header.indirect),
    }];
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
