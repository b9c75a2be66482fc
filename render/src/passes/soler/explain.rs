//! Explain a pixel (issue #42) for Soler et al.'s screen-space gather (004 §4, Fig. 4, Eq. 6):
//! `shaders/soler/explain.wgsl` replays the joint bilateral upsampling's weights from the
//! pixel up the levels (the same `jbu_weights` the upsampling runs) and reads each reached
//! texel's own gathered irradiance (the ring samples' sum) and the light the voxel visibility
//! removed there; [`decode`] makes the contributions: per level and texel, w · E · c·DI/π,
//! scaled by Eq. 6's 1 − a, and the warped history's a · c·DI/π · W (or a · W when the
//! radiance is blended). Written for one bounce without the glossy reflection
//! (`Renderer::explain_unsupported` says so otherwise).

use crate::counters::prelude::*;

use glam::{Vec3, Vec4};

use crate::explain::{Check, Contribution, Explanation, Replay};
use crate::gpu::GpuContext;
use crate::passes::bgl;

/// Texels per level the replay follows (`MAX_PER_LEVEL` in the shader).
const MAX_PER_LEVEL: u64 = 64;
/// Levels at most (the header's counts).
const MAX_LEVELS: u64 = 16;
const ENTRIES_OFFSET: u64 = 256;
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
    pub counts: [u32; 16],
    pub indirect: Vec4,
    pub last: Vec4,
    pub history: Vec4,
    pub albedo: Vec4,
    pub spec_history: Vec4,
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
            layout,
            params: crate::passes::uniform_buffer(device, "explain.soler.params", STRIDE * MAX_LEVELS),
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
        ENTRIES_OFFSET + MAX_LEVELS * MAX_PER_LEVEL * std::mem::size_of::<GpuEntry>() as u64
    }

    /// Records the replay into `enc`, after the stage's passes.
    pub fn run(
        &mut self,
        ctx: &GpuContext,
        enc: &mut wgpu::CommandEncoder,
        inp: &SolerExplainInputs,
        info: SolerChain,
    ) {
        let n = inp.levels.len().min(MAX_LEVELS as usize);
        if n == 0 {
            return;
        }
        // The start: level 0's texel p with weight 1, every other level empty.
        let mut header: GpuHeader = bytemuck::Zeroable::zeroed();
        header.pixel = [inp.pixel.0, inp.pixel.1, 0, 0];
        header.counts[0] = 1;
        let first = GpuEntry {
            texel: [inp.pixel.0, inp.pixel.1, 0, 0],
            weight: Vec4::new(1.0, 0.0, 0.0, 0.0),
            own: Vec4::ZERO,
            occlusion: Vec4::ZERO,
            position: Vec4::ZERO,
            spec: Vec4::ZERO,
        };
        ctx.queue.write_buffer(&self.out, 0, bytemuck::bytes_of(&header));
        ctx.queue.write_buffer(&self.out, ENTRIES_OFFSET, bytemuck::bytes_of(&first));
        let params: Vec<StepParams> = (0..n)
            .map(|k| StepParams {
                level: [k as u32, inp.levels[k].own.is_some() as u32, (k + 1 == n) as u32, 0],
                sigma: [inp.sigma[0], inp.sigma[1], 0.0, 0.0],
            })
            .collect();
        ctx.queue.write_buffer(&self.params, 0, &crate::passes::strided_bytes(STRIDE, params.len(), &params));
        let (w, a) = inp.temporal.as_ref().map(|(w, a)| (w, a)).unwrap_or((&self.dummy, &self.dummy));
        for k in 0..n {
            let l = &inp.levels[k];
            let coarse = inp.levels.get(k + 1).unwrap_or(l);
            let (own, occlusion) = l.own.as_ref().map(|(o, c)| (o, c)).unwrap_or((&self.dummy, &self.dummy));
            let views = [
                &l.position,
                &l.normal,
                own,
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
            let spec = l.spec.as_ref().unwrap_or(&self.dummy);
            let spec_history = inp.spec_history.as_ref().unwrap_or(&self.dummy);
            resources.extend([spec, inp.motion, spec_history].map(wgpu::BindingResource::TextureView));
            let group = crate::passes::bind_group(&ctx.device, "explain.soler.inputs", &self.layout, resources);
            let offset = [(k as u64 * STRIDE) as u32];
            // One pass per dispatch: each reads what the one before wrote.
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("explain.soler"),
                timestamp_writes: None,
            });
            pass.set_bind_group(0, &group, &offset);
            if k == 0 {
                pass.set_pipeline(&self.pixel_pipeline);
                pass.dispatch_workgroups(1, 1, 1);
                drop(pass);
                pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("explain.soler"),
                    timestamp_writes: None,
                });
                pass.set_bind_group(0, &group, &offset);
            }
            pass.set_pipeline(&self.step_pipeline);
            pass.dispatch_workgroups(1, 1, 1);
        }
        self.info = Some(info);
    }
}

/// The replay's inputs from the stage as its last `run` left it (one bounce: the gathered
/// levels' light is the first bounce's).
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
        bytes.get(ENTRIES_OFFSET as usize..)?.get(..(MAX_LEVELS * MAX_PER_LEVEL) as usize * size)?,
    );
    let v3 = |v: Vec4| v.truncate();
    let k_p = v3(header.albedo);
    let a = if info.temporal { header.history.w } else { 0.0 };
    let mut contributions = Vec::new();
    let mut gathered_sum = Vec3::ZERO;
    let mut notes = Vec::new();
    for k in 0..info.levels.min(MAX_LEVELS as u32) {
        let n = header.counts[k as usize] as usize;
        if n as u64 >= MAX_PER_LEVEL {
            notes.push(format!(
                "level {k}: more than {MAX_PER_LEVEL} texels reach the pixel; the replay follows the first"
            ));
        }
        if !info.gathered.contains(&k) {
            continue;
        }
        let base = k as usize * MAX_PER_LEVEL as usize;
        for e in entries.get(base..base + n)? {
            let w = e.weight.x;
            let own = v3(e.own);
            let spec = v3(e.spec);
            gathered_sum += (own * k_p + spec) * w;
            if w <= 0.0 {
                continue;
            }
            contributions.push(Contribution {
                name: format!("level {k} ({}, {})", e.texel[0], e.texel[1]),
                source: format!("ring gather of level {k} ({} samples)", info.samples),
                position: Some(v3(e.position)),
                value: (own * k_p + spec) * w * (1.0 - a),
                weight: w * (1.0 - a),
                rejected: None,
                via: None,
                fields: vec![
                    ("level", k as f32),
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
        what: "Σ levels w · (E · c·DI/π + S)".into(),
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
