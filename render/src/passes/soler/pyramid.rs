//! Stage 5 "mip levels" (Soler et al. 004 §4, "Filtering of mipmap levels", Eq. 5): the
//! G-buffer's position, depth and normal and the direct light are mipmapped by voting among
//! the sub-pixels of each 2×2 block (`shaders/soler/vote.wgsl`; CPU twin
//! `cpu::soler_vote::vote_level`). Level 0 is the G-buffer itself.

use crate::buffers::{BufferKind, BufferRegistry};
use crate::counters::prelude::CountedQueue;
use crate::gpu::GpuContext;
use crate::gpu::bindings::{Bindings, Kind, binding};
use crate::timing::PassRec;
use crate::timing::Slot;

/// Bind group `soler.vote.inputs` of `shaders/soler/vote.wgsl` (group 0 of `cs_vote`): one
/// level of the pyramid's vote (Soler 004 §3.1).
pub const VOTE_INPUTS_BINDINGS: Bindings = Bindings {
    label: "soler.vote.inputs",
    shader: "soler/vote.wgsl",
    group: 0,
    entry: Some("cs_vote"),
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "params", Kind::Uniform),
        binding(1, "fine_position", Kind::Texture { filterable: false }),
        binding(2, "fine_normal", Kind::Texture { filterable: false }),
        binding(3, "fine_radiance", Kind::Texture { filterable: false }),
        binding(4, "out_position", Kind::StorageTexture(wgpu::TextureFormat::Rgba32Float)),
        binding(5, "out_normal", Kind::StorageTexture(wgpu::TextureFormat::Rgba32Float)),
        binding(6, "out_radiance", Kind::StorageTexture(wgpu::TextureFormat::Rgba32Float)),
        binding(7, "out_winner", Kind::StorageTexture(wgpu::TextureFormat::R32Float)),
        binding(8, "fine_material", Kind::Texture { filterable: false }),
        binding(9, "out_material", Kind::StorageTexture(wgpu::TextureFormat::Rgba32Float)),
    ],
};

/// Bind group `soler.vote_radiance.inputs` of `shaders/soler/vote.wgsl` (group 0 of
/// `cs_vote_radiance`): a later bounce's radiance through the frame's winners.
pub const VOTE_RADIANCE_INPUTS_BINDINGS: Bindings = Bindings {
    label: "soler.vote_radiance.inputs",
    shader: "soler/vote.wgsl",
    group: 0,
    entry: Some("cs_vote_radiance"),
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "params", Kind::Uniform),
        binding(1, "fine_position", Kind::Texture { filterable: false }),
        binding(2, "fine_normal", Kind::Texture { filterable: false }),
        binding(3, "fine_radiance", Kind::Texture { filterable: false }),
        binding(6, "out_radiance", Kind::StorageTexture(wgpu::TextureFormat::Rgba32Float)),
        binding(10, "in_winner", Kind::Texture { filterable: false }),
        binding(11, "coarse_position", Kind::Texture { filterable: false }),
        binding(12, "coarse_normal", Kind::Texture { filterable: false }),
    ],
};

/// Rust twin of `VoteParams` in `shaders/soler/vote.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct VoteParams {
    /// σ₁, σ₂, σ₃, and 1 with `vote_consistent` (the sub-pixels' radiance weighted by g₂
    /// on the winner's normal), else 0.
    pub sigma: [f32; 4],
    /// The eye, Eq. 2's least cos β (< 0: the block's plain mean, `vote_power` off).
    pub power: [f32; 4],
}

/// One mip level above the G-buffer.
pub struct PyramidLevel {
    pub width: u32,
    pub height: u32,
    /// xyz world position of the winner, w its view depth (0: background).
    pub position: wgpu::Texture,
    /// xyz the winner's normal, w 1 on a surface, 0 on the background.
    pub normal: wgpu::Texture,
    /// rgb the block's mean radiance (the previous bounce), weighted by Eq. 2's areas with
    /// `vote_power`.
    pub radiance: wgpu::Texture,
    /// The winning sub-pixel, x + 2y in the block (0–3), −1 on the background.
    pub winner: wgpu::Texture,
    /// The winner's material as in the G-buffer: SI (r), SP (g), metallic, roughness.
    pub material: wgpu::Texture,
}

pub struct SolerPyramid {
    /// Levels 1, 2, … (index k − 1 for level k).
    pub levels: Vec<PyramidLevel>,
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::ComputePipeline,
    /// `cs_vote_radiance`: a later bounce's radiance down the winners of this frame's vote.
    radiance_layout: wgpu::BindGroupLayout,
    radiance_pipeline: wgpu::ComputePipeline,
    params: wgpu::Buffer,
}

/// Sizes of pyramid levels 1 … `top` over a `width` × `height` G-buffer (each ⌈half⌉).
pub fn sizes(width: u32, height: u32, top: u32) -> Vec<(u32, u32)> {
    let mut out = Vec::new();
    let (mut w, mut h) = (width.max(1), height.max(1));
    for _ in 0..top {
        (w, h) = (w.div_ceil(2), h.div_ceil(2));
        out.push((w, h));
    }
    out
}

impl SolerPyramid {
    pub fn new(ctx: &GpuContext, width: u32, height: u32, top: u32) -> Self {
        let device = &ctx.device;
        let layout = VOTE_INPUTS_BINDINGS.layout(device);
        let module = crate::shaders::create_module(device, "soler/vote.wgsl");
        let pipeline = crate::passes::compute_pipeline(device, "soler.vote", &module, "cs_vote", &[&layout]);
        let radiance_layout = VOTE_RADIANCE_INPUTS_BINDINGS.layout(device);
        let radiance_pipeline = crate::passes::compute_pipeline(
            device,
            "soler.vote_radiance",
            &module,
            "cs_vote_radiance",
            &[&radiance_layout],
        );
        let params =
            crate::passes::uniform_buffer(device, "soler.vote.params", std::mem::size_of::<VoteParams>() as u64);
        let levels = Self::targets(device, width, height, top);
        Self { levels, layout, pipeline, radiance_layout, radiance_pipeline, params }
    }

    fn targets(device: &wgpu::Device, width: u32, height: u32, top: u32) -> Vec<PyramidLevel> {
        let storage = wgpu::TextureUsages::STORAGE_BINDING;
        let rgba = wgpu::TextureFormat::Rgba32Float;
        sizes(width, height, top)
            .into_iter()
            .enumerate()
            .map(|(i, (w, h))| {
                let k = i + 1;
                let t = |name: &str, format| {
                    crate::passes::create_target(device, &format!("soler.level.{k}.{name}"), w, h, format, storage)
                };
                PyramidLevel {
                    width: w,
                    height: h,
                    position: t("position", rgba),
                    normal: t("normal", rgba),
                    radiance: t("radiance", rgba),
                    winner: t("winner", wgpu::TextureFormat::R32Float),
                    material: t("material", rgba),
                }
            })
            .collect()
    }

    /// Resizes for a `width` × `height` G-buffer and levels up to `top`; true when the
    /// textures were replaced.
    pub fn ensure(&mut self, ctx: &GpuContext, width: u32, height: u32, top: u32) -> bool {
        let have: Vec<(u32, u32)> = self.levels.iter().map(|l| (l.width, l.height)).collect();
        if have == sizes(width, height, top) {
            return false;
        }
        self.levels = Self::targets(&ctx.device, width, height, top);
        true
    }

    pub fn register(&self, reg: &mut BufferRegistry) {
        for (i, l) in self.levels.iter().enumerate() {
            let k = i + 1;
            reg.register(
                &format!("soler.level.{k}.position"),
                BufferKind::Data,
                "Soler mip level (004 §4, Eq. 5): world position of the voting winner; w its view depth (0: background)",
                &l.position,
            );
            reg.register(
                &format!("soler.level.{k}.normal"),
                BufferKind::Direction,
                "Soler mip level (004 §4, Eq. 5, Fig. 5): the voting winner's normal, never an average",
                &l.normal,
            );
            reg.register(
                &format!("soler.level.{k}.radiance"),
                BufferKind::Hdr,
                "Soler mip level (004 §4): radiance of the previous bounce (direct light), the 2×2 block's mean",
                &l.radiance,
            );
            reg.register(
                &format!("soler.level.{k}.winner"),
                BufferKind::Data,
                "Soler mip level (004 Eq. 5): the winning sub-pixel x + 2y of the 2×2 block (0–3), −1 on the background",
                &l.winner,
            );
            reg.register(
                &format!("soler.level.{k}.material"),
                BufferKind::Data,
                "Soler mip level (004 §4): the voting winner's material, SI (r) and SP (g) for the glossy reflection",
                &l.material,
            );
        }
    }

    /// Votes levels 1 … top from the G-buffer's `position`, `normal` and `material` and the
    /// `radiance` of the previous bounce, with the vote's `sigma` and `power` (`VoteParams`).
    pub fn run(
        &self,
        r: PassRec<'_, '_>,
        (sigma, power): ([f32; 4], [f32; 4]),
        position: &wgpu::TextureView,
        normal: &wgpu::TextureView,
        radiance: &wgpu::TextureView,
        material: &wgpu::TextureView,
    ) {
        let PassRec { ctx, enc: encoder, slot } = r;
        let p = VoteParams { sigma, power };
        ctx.queue.upload(&self.params, 0, bytemuck::bytes_of(&p));
        let view = |t: &wgpu::Texture| crate::passes::view(t, "soler.level.view");
        let views: Vec<[wgpu::TextureView; 5]> = self
            .levels
            .iter()
            .map(|l| [view(&l.position), view(&l.normal), view(&l.radiance), view(&l.winner), view(&l.material)])
            .collect();
        let n = self.levels.len();
        for (i, out) in views.iter().enumerate() {
            let (fp, fnorm, fr, fm) = if i == 0 {
                (position, normal, radiance, material)
            } else {
                (&views[i - 1][0], &views[i - 1][1], &views[i - 1][2], &views[i - 1][4])
            };
            let tv = wgpu::BindingResource::TextureView;
            let inputs = [fp, fnorm, fr, &out[0], &out[1], &out[2], &out[3], fm, &out[4]];
            let resources = std::iter::once(self.params.as_entire_binding()).chain(inputs.map(tv));
            let group = VOTE_INPUTS_BINDINGS.group(&ctx.device, &self.layout, resources);
            let l = &self.levels[i];
            let stamps = slot.as_ref().and_then(|s| s.compute(i == 0, i + 1 == n));
            crate::passes::dispatch_2d(encoder, "soler.vote", &self.pipeline, &group, &[], stamps, (l.width, l.height));
        }
    }

    /// Takes `radiance` (a later bounce's light) down levels 1 … top through the winners of
    /// the vote [`Self::run`] made this frame (004 §5.3: the bounces share the G-buffer's
    /// mipmapping); the levels' geometry stays as voted, and the vote's σ and power
    /// (`VoteParams`, the same for the whole frame) are reused.
    pub fn run_radiance(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        slot: Option<Slot<'_>>,
        (position, normal): (&wgpu::TextureView, &wgpu::TextureView),
        radiance: &wgpu::TextureView,
    ) {
        let view = |t: &wgpu::Texture| crate::passes::view(t, "soler.level.view");
        let views: Vec<[wgpu::TextureView; 4]> = self
            .levels
            .iter()
            .map(|l| [view(&l.position), view(&l.normal), view(&l.radiance), view(&l.winner)])
            .collect();
        let n = self.levels.len();
        let tv = wgpu::BindingResource::TextureView;
        for (i, out) in views.iter().enumerate() {
            let (fp, fnorm, fr) = if i == 0 {
                (position, normal, radiance)
            } else {
                (&views[i - 1][0], &views[i - 1][1], &views[i - 1][2])
            };
            // Bindings 0, 1–3, 6, 10–12 in the description's order.
            let group = VOTE_RADIANCE_INPUTS_BINDINGS.group(
                &ctx.device,
                &self.radiance_layout,
                [
                    self.params.as_entire_binding(),
                    tv(fp),
                    tv(fnorm),
                    tv(fr),
                    tv(&out[2]),
                    tv(&out[3]),
                    tv(&out[0]),
                    tv(&out[1]),
                ],
            );
            let l = &self.levels[i];
            let stamps = slot.as_ref().and_then(|s| s.compute(i == 0, i + 1 == n));
            crate::passes::dispatch_2d(
                encoder,
                "soler.vote_radiance",
                &self.radiance_pipeline,
                &group,
                &[],
                stamps,
                (l.width, l.height),
            );
        }
    }
}
