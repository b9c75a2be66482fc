//! Stage 6 "screen-space ring gather" (Soler et al. 004 §3–4, Eq. 1–4, Fig. 3): every texel
//! of each gathered mip level sums the radiance of N samples on a ring around it
//! (`shaders/soler/gather.wgsl`; CPU twin `cpu::soler::gather`). The result per level is
//! irradiance (`soler.level.k.indirect`).

use super::STRIDE;
use crate::buffers::{BufferKind, BufferRegistry};
use crate::counters::prelude::CountedQueue;
use crate::gpu::GpuContext;
use crate::gpu::bindings::{Bindings, Kind, binding};

/// Rust twin of `GatherParams` in `shaders/soler/gather.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GatherParams {
    /// Samples N, first gathered level (full disc) 1/0, level index, frame.
    pub counts: [u32; 4],
    /// r (level texels), point-to-disc 1 / point-to-point 0, min cos β, unused.
    pub shape: [f32; 4],
    /// The eye (xyz).
    pub eye: [f32; 4],
    /// tan(f_h/2), tan(f_v/2), the level's W and H.
    pub screen: [f32; 4],
    /// This level's voxel grid (`grid[0]` = 0: no visibility).
    pub voxels: super::voxels::VoxelParams,
    /// Texels skipped at both ends of the march, depth bias (slices), unused, unused.
    pub march: [f32; 4],
    /// α, k (s = k·SP), the least SP importance sampled, flags (1 glossy reflection, 2
    /// importance sampling) of the glossy reflection (`cpu::soler_glossy`).
    pub gloss: [f32; 4],
    /// The camera's right, up and forward axes (xyz).
    pub right: [f32; 4],
    pub up: [f32; 4],
    pub forward: [f32; 4],
}

use super::MAX_GATHERED;
use crate::timing::PassRec;

/// Bind group `soler.gather.inputs` of `shaders/soler/gather.wgsl` (group 0).
pub const GATHER_INPUTS_BINDINGS: Bindings = Bindings {
    label: "soler.gather.inputs",
    shader: "soler/gather.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "params", Kind::UniformDynamic),
        binding(1, "level_position", Kind::Texture { filterable: false }),
        binding(2, "level_normal", Kind::Texture { filterable: false }),
        binding(3, "level_radiance", Kind::Texture { filterable: false }),
        binding(4, "out_light", Kind::StorageTexture(wgpu::TextureFormat::Rgba32Float)),
        binding(5, "grid", Kind::Storage { read_only: true }),
        binding(6, "out_occlusion", Kind::StorageTexture(wgpu::TextureFormat::Rgba32Float)),
        binding(7, "level_material", Kind::Texture { filterable: false }),
        binding(8, "out_specular", Kind::StorageTexture(wgpu::TextureFormat::Rgba32Float)),
    ],
};

/// Most bounces (the settings' range).
pub const MAX_BOUNCES: usize = 4;

/// One gathered level's input: its position, normal and radiance views and size.
pub struct LevelInputs<'a> {
    pub level: u32,
    pub position: &'a wgpu::TextureView,
    pub normal: &'a wgpu::TextureView,
    pub radiance: &'a wgpu::TextureView,
    /// SI (r) and SP (g) of the level's texels.
    pub material: &'a wgpu::TextureView,
    pub size: (u32, u32),
    /// The level's voxel grid and its parameters (the empty buffer and zeros without
    /// visibility).
    pub grid: &'a wgpu::Buffer,
    pub voxels: super::voxels::VoxelParams,
}

pub struct SolerGather {
    /// `soler.level.k.indirect` of each gathered level k (first = the start level).
    pub light: Vec<(u32, wgpu::Texture)>,
    /// `soler.level.k.occlusion`: the light the visibility removed (rgb) and the visible
    /// fraction of the samples that carried light (a).
    pub occlusion: Vec<wgpu::Texture>,
    /// `soler.level.k.specular`: the light the receiver's specular lobe reflects toward the
    /// eye (004 §4 "Screen-space importance sampling"), black without glossy reflection.
    pub specular: Vec<wgpu::Texture>,
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::ComputePipeline,
    pub(super) params: wgpu::Buffer,
}

impl SolerGather {
    pub fn new(ctx: &GpuContext) -> Self {
        let device = &ctx.device;
        let layout = GATHER_INPUTS_BINDINGS.layout(device);
        let module = crate::shaders::create_module(device, "soler/gather.wgsl");
        let pipeline = crate::passes::compute_pipeline(device, "soler.gather", &module, "cs_gather", &[&layout]);
        let params =
            crate::passes::uniform_buffer(device, "soler.gather.params", STRIDE * (MAX_GATHERED * MAX_BOUNCES) as u64);
        Self { light: Vec::new(), occlusion: Vec::new(), specular: Vec::new(), layout, pipeline, params }
    }

    /// Textures for the gathered `levels`, each (level, size); true when replaced.
    pub fn ensure(&mut self, ctx: &GpuContext, levels: &[(u32, (u32, u32))]) -> bool {
        let have: Vec<(u32, (u32, u32))> = self.light.iter().map(|(k, t)| (*k, (t.width(), t.height()))).collect();
        if have == levels {
            return false;
        }
        let storage = wgpu::TextureUsages::STORAGE_BINDING;
        self.light = levels
            .iter()
            .map(|&(k, (w, h))| {
                let label = format!("soler.level.{k}.indirect");
                (k, crate::passes::create_target(&ctx.device, &label, w, h, wgpu::TextureFormat::Rgba32Float, storage))
            })
            .collect();
        let targets = |name: &str| -> Vec<wgpu::Texture> {
            levels
                .iter()
                .map(|&(k, (w, h))| {
                    let label = format!("soler.level.{k}.{name}");
                    crate::passes::create_target(&ctx.device, &label, w, h, wgpu::TextureFormat::Rgba32Float, storage)
                })
                .collect()
        };
        self.occlusion = targets("occlusion");
        self.specular = targets("specular");
        true
    }

    pub fn register(&self, reg: &mut BufferRegistry) {
        for (k, t) in &self.light {
            reg.register(
                &format!("soler.level.{k}.indirect"),
                BufferKind::Hdr,
                "Soler raw indirect of one mip level (004 Eq. 3–4): the irradiance its ring of samples gathers, before upsampling",
                t,
            );
        }
        for ((k, _), t) in self.light.iter().zip(&self.occlusion) {
            reg.register(
                &format!("soler.level.{k}.occlusion"),
                BufferKind::Hdr,
                "Soler visibility of one mip level (004 §4 \"Visibility\"): rgb the irradiance the voxel march removed (no-vis minus vis), a the visible fraction of the samples that carried light",
                t,
            );
        }
        for ((k, _), t) in self.light.iter().zip(&self.specular) {
            reg.register(
                &format!("soler.level.{k}.specular"),
                BufferKind::Hdr,
                "Soler glossy reflection of one mip level (004 §4 \"Screen-space importance sampling\"): Σ L_i K_i f_s(l_i, v), the light the receiver's specular lobe sends to the eye, before upsampling",
                t,
            );
        }
    }

    /// Writes the parameters of every gather of the frame: slot `b · levels + i` is level i
    /// (in the order of [`Self::light`]) of the b-th bounce gathered, `voxels[b][i]` its grid.
    /// `levels`: each gathered level and its size.
    pub fn write_params(
        &self,
        ctx: &GpuContext,
        levels: &[(u32, (u32, u32))],
        base: GatherParams,
        voxels: &[Vec<super::voxels::VoxelParams>],
    ) {
        let params: Vec<GatherParams> = voxels
            .iter()
            .flat_map(|per_level| {
                levels.iter().enumerate().map(move |(i, &(level, size))| {
                    let mut p = base;
                    p.counts[1] = (i == 0) as u32;
                    p.counts[2] = level;
                    p.screen[2] = size.0 as f32;
                    p.screen[3] = size.1 as f32;
                    p.voxels = per_level.get(i).copied().unwrap_or_default();
                    p
                })
            })
            .collect();
        ctx.queue.upload(&self.params, 0, &crate::passes::strided_bytes(STRIDE, params.len(), &params));
    }

    /// Gathers the level `l`, the i-th of [`Self::light`], with the parameters of `slot_index`
    /// ([`Self::write_params`]).
    pub fn run_level(&self, r: PassRec<'_, '_>, l: &LevelInputs<'_>, i: usize, slot_index: usize) {
        let PassRec { ctx, enc: encoder, slot } = r;
        let uniform = crate::passes::dynamic_slot(&self.params, std::mem::size_of::<GatherParams>());
        let (out, occ) = (&self.light[i].1, &self.occlusion[i]);
        let out_view = crate::passes::view(out, "soler.gather.out");
        let occ_view = crate::passes::view(occ, "soler.gather.occlusion");
        let spec_view = crate::passes::view(&self.specular[i], "soler.gather.specular");
        let tv = wgpu::BindingResource::TextureView;
        let views = [l.position, l.normal, l.radiance, &out_view];
        let mut resources: Vec<_> = std::iter::once(uniform).chain(views.map(tv)).collect();
        resources.push(l.grid.as_entire_binding());
        resources.push(tv(&occ_view));
        resources.push(tv(l.material));
        resources.push(tv(&spec_view));
        let group = GATHER_INPUTS_BINDINGS.group(&ctx.device, &self.layout, resources);
        let stamps = slot.as_ref().and_then(|s| s.compute(true, true));
        let offset = [(slot_index as u64 * STRIDE) as u32];
        crate::passes::dispatch_2d(encoder, "soler.gather", &self.pipeline, &group, &offset, stamps, l.size);
    }
}
