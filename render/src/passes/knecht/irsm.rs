//! The multi-bounce baseline of Knecht 002 §3.6 (Ritschel et al. 2008): imperfect reflective
//! shadow maps. Per bounce, every source VPL's IRSM is splatted from its N-th of the point
//! cloud (`shaders/knecht/ism/splat.wgsl` `cs_splat`, `cs_owner`), its texels weighted by the
//! illumination of the point that owns them, and the next bounce's N VPLs importance-sampled
//! from all IRSMs together (`shaders/knecht/vpl/irsm.wgsl`, documented there; CPU twin
//! `cpu::knecht::irsm_pick`). Table 5.3 of the thesis compares its time with §3.6.1's
//! ([`crate::passes::knecht::vpl_bounce`]); `gi-lab bench --suite knecht` reproduces it.

use crate::counters::prelude::*;
use crate::gpu::bindings::{Bindings, Kind, binding};

use glam::Vec4;

use crate::gpu::GpuContext;
use crate::passes::knecht::ism::{IsmLayout, IsmPass, MAX_BOUNCES, SplatParams};
use crate::passes::knecht::vpl_bounce::{BounceParams, bounce_seed};
use crate::timing::Slot;

const STRIDE: u64 = 256;

/// Bind group `irsm.sample.inputs` of `shaders/knecht/vpl/irsm.wgsl` (group 0).
pub const SAMPLE_INPUTS_BINDINGS: Bindings = Bindings {
    label: "irsm.sample.inputs",
    shader: "knecht/vpl/irsm.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "ip", Kind::UniformDynamic),
        binding(1, "points", Kind::Storage { read_only: true }),
        binding(2, "surfaces", Kind::Storage { read_only: true }),
        binding(3, "instances", Kind::Storage { read_only: true }),
        binding(4, "owner", Kind::Storage { read_only: true }),
        binding(5, "cdf", Kind::Storage { read_only: false }),
        binding(6, "totals", Kind::Storage { read_only: false }),
        binding(7, "coverage", Kind::Storage { read_only: false }),
        binding(8, "vpls", Kind::Storage { read_only: false }),
        binding(9, "illumination", Kind::StorageTexture(wgpu::TextureFormat::R32Float)),
    ],
};

/// What one frame's IRSM bounces need.
#[derive(Clone, Copy, Debug)]
pub struct IrsmFrame {
    /// VPLs per bounce N.
    pub vpls: u32,
    pub bounces: u32,
    pub eye_offset: f32,
    pub min_distance: f32,
    pub seed: u32,
}

/// The bind groups of one frame ([`IrsmPass::begin`]).
pub struct IrsmJob {
    splat: wgpu::BindGroup,
    sample: wgpu::BindGroup,
}

pub struct IrsmPass {
    key: (u32, u32, usize),
    pub layout_info: IsmLayout,
    /// Splatted distances (inverted f32 bits) of the N IRSMs.
    pub depth: wgpu::Buffer,
    /// Owner of each IRSM texel: point index + 1, 0 = none.
    pub owner: wgpu::Buffer,
    /// Per-IRSM inclusive prefix sums of the texel weights.
    pub cdf: wgpu::Buffer,
    /// IRSM totals, then their running sum.
    pub totals: wgpu::Buffer,
    /// Texels each point owns.
    pub coverage: wgpu::Buffer,
    /// `irsm.illumination`: each texel's weight C (the owner's contribution) in the last
    /// bounce's IRSMs (the illumination map of Knecht 002 Fig. 3.6).
    pub illumination: wgpu::Texture,
    splat_layout: wgpu::BindGroupLayout,
    sample_layout: wgpu::BindGroupLayout,
    splat_pipeline: wgpu::ComputePipeline,
    owner_pipeline: wgpu::ComputePipeline,
    cdf_pipeline: wgpu::ComputePipeline,
    sample_pipeline: wgpu::ComputePipeline,
    splat_params: wgpu::Buffer,
    params: wgpu::Buffer,
}

fn dynamic(buffer: &wgpu::Buffer, size: usize) -> wgpu::BindingResource<'_> {
    wgpu::BindingResource::Buffer(wgpu::BufferBinding {
        buffer,
        offset: 0,
        size: std::num::NonZeroU64::new(size as u64),
    })
}

/// The IRSM side actually used: a power of two in 16 … 128 (the CDF pass gives each of its
/// 256 threads size²/256 texels).
pub fn irsm_size(setting: u32) -> u32 {
    1 << setting.clamp(16, 128).ilog2()
}

impl IrsmPass {
    pub fn new(ctx: &GpuContext) -> Self {
        let device = &ctx.device;
        let splat_layout = crate::passes::knecht::ism::splat_layout(device, "irsm.splat.inputs");
        let sample_layout = SAMPLE_INPUTS_BINDINGS.layout(device);
        let m_splat = crate::shaders::create_module(device, "knecht/ism/splat.wgsl");
        let m_irsm = crate::shaders::create_module(device, "knecht/vpl/irsm.wgsl");
        let splat_pipeline =
            crate::passes::compute_pipeline(device, "irsm.splat", &m_splat, "cs_splat", &[&splat_layout]);
        let owner_pipeline =
            crate::passes::compute_pipeline(device, "irsm.owner", &m_splat, "cs_owner", &[&splat_layout]);
        let cdf_pipeline = crate::passes::compute_pipeline(device, "irsm.cdf", &m_irsm, "cs_cdf", &[&sample_layout]);
        let sample_pipeline =
            crate::passes::compute_pipeline(device, "irsm.sample", &m_irsm, "cs_sample", &[&sample_layout]);
        let uniform = |label| crate::passes::uniform_buffer(device, label, STRIDE * MAX_BOUNCES as u64);
        let layout_info = IsmLayout::new(1, 16);
        let (depth, owner, cdf, totals, coverage) = Self::buffers(device, layout_info, 1, 1);
        let illumination = Self::illumination_texture(device, layout_info);
        Self {
            illumination,
            key: (1, 16, 1),
            layout_info,
            depth,
            owner,
            cdf,
            totals,
            coverage,
            splat_layout,
            sample_layout,
            splat_pipeline,
            owner_pipeline,
            cdf_pipeline,
            sample_pipeline,
            splat_params: uniform("irsm.splat.params"),
            params: uniform("irsm.params"),
        }
    }

    fn buffers(
        device: &wgpu::Device,
        l: IsmLayout,
        vpls: u32,
        points: usize,
    ) -> (wgpu::Buffer, wgpu::Buffer, wgpu::Buffer, wgpu::Buffer, wgpu::Buffer) {
        let make = |label, bytes: u64| {
            crate::passes::buffer(
                device,
                label,
                bytes.max(4),
                wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
            )
        };
        let texels = l.width() * l.height();
        (
            make("irsm.depth", 4 * texels),
            make("irsm.owner", 4 * texels),
            make("irsm.cdf", 4 * texels),
            make("irsm.totals", 8 * vpls as u64),
            make("irsm.coverage", 4 * points as u64),
        )
    }

    fn illumination_texture(device: &wgpu::Device, l: IsmLayout) -> wgpu::Texture {
        crate::passes::create_target(
            device,
            "irsm.illumination",
            l.width() as u32,
            l.height() as u32,
            wgpu::TextureFormat::R32Float,
            wgpu::TextureUsages::STORAGE_BINDING,
        )
    }

    pub fn register(&self, reg: &mut crate::buffers::BufferRegistry) {
        reg.register(
            "irsm.illumination",
            crate::buffers::BufferKind::Data,
            "IRSM baseline (Ritschel et al., Knecht Fig. 3.6): one map per source VPL of the last bounce, each texel the light its nearest cloud point would send on (the weight new VPLs are importance-sampled by), 0 where no point lies",
            &self.illumination,
        );
    }

    /// Sizes the IRSMs for `vpls` source VPLs of `size`² (see [`irsm_size`]) and `points`
    /// cloud points (the caller checked that the atlas fits). Returns whether the
    /// illumination texture was recreated.
    pub fn ensure(&mut self, ctx: &GpuContext, vpls: u32, size: u32, points: usize) -> bool {
        let size = irsm_size(size);
        if self.key == (vpls, size, points) {
            return false;
        }
        self.layout_info = IsmLayout::new(vpls, size);
        (self.depth, self.owner, self.cdf, self.totals, self.coverage) =
            Self::buffers(&ctx.device, self.layout_info, vpls, points);
        self.illumination = Self::illumination_texture(&ctx.device, self.layout_info);
        self.key = (vpls, size, points);
        true
    }

    /// Writes the uniforms of bounces 1 … B − 1 and returns the frame's bind groups.
    pub fn begin(
        &self,
        ctx: &GpuContext,
        ism: &IsmPass,
        s: &crate::passes::knecht::ism::IsmSettings,
        instances: &wgpu::Buffer,
        vpls: &wgpu::Buffer,
        f: IrsmFrame,
    ) -> IrsmJob {
        let l = self.layout_info;
        let n_points = ism.cloud.gpu.len() as u32;
        let bounces = 1..f.bounces.clamp(1, MAX_BOUNCES);
        let splat: Vec<SplatParams> = bounces
            .clone()
            .map(|b| SplatParams {
                counts: [n_points, f.vpls, l.cols, l.size],
                geom: Vec4::new(f.eye_offset, ism.point_radius(f.vpls), s.max_splat_radius as f32, s.splat_scale),
                slots: [(b - 1) * f.vpls, 0, 0, 0],
            })
            .collect();
        let irsm: Vec<BounceParams> = bounces
            .map(|b| BounceParams {
                counts: [n_points, f.vpls, l.cols, l.size],
                slots: [(b - 1) * f.vpls, b * f.vpls, 0, 0],
                geom: Vec4::new(0.0, 0.0, f.min_distance * f.min_distance, 0.0),
                seed: [bounce_seed(f.seed, b), 0, 0, 0],
            })
            .collect();
        let (splat, irsm) = (
            crate::passes::strided_bytes(STRIDE, MAX_BOUNCES as usize, &splat),
            crate::passes::strided_bytes(STRIDE, MAX_BOUNCES as usize, &irsm),
        );
        ctx.queue.upload(&self.splat_params, 0, &splat);
        ctx.queue.upload(&self.params, 0, &irsm);
        let splat = crate::passes::knecht::ism::SPLAT_INPUTS_BINDINGS.group_labelled(
            &ctx.device,
            "irsm.splat.inputs",
            &self.splat_layout,
            [
                dynamic(&self.splat_params, std::mem::size_of::<SplatParams>()),
                ism.points.as_entire_binding(),
                instances.as_entire_binding(),
                vpls.as_entire_binding(),
                self.depth.as_entire_binding(),
                self.owner.as_entire_binding(),
            ],
        );
        let illumination = crate::passes::view(&self.illumination, "irsm.illumination");
        let sample = SAMPLE_INPUTS_BINDINGS.group(
            &ctx.device,
            &self.sample_layout,
            [
                dynamic(&self.params, std::mem::size_of::<BounceParams>()),
                ism.points.as_entire_binding(),
                ism.surfaces.as_entire_binding(),
                instances.as_entire_binding(),
                self.owner.as_entire_binding(),
                self.cdf.as_entire_binding(),
                self.totals.as_entire_binding(),
                self.coverage.as_entire_binding(),
                vpls.as_entire_binding(),
                wgpu::BindingResource::TextureView(&illumination),
            ],
        );
        IrsmJob { splat, sample }
    }

    /// Creates bounce `bounce`'s N VPLs from bounce b − 1's through their IRSMs.
    pub fn run(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        slot: Option<Slot<'_>>,
        job: &IrsmJob,
        bounce: u32,
        vpls: u32,
        points: u32,
    ) {
        for b in [&self.depth, &self.owner, &self.coverage] {
            encoder.counted_clear_buffer(b, 0, None);
        }
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("irsm"),
            timestamp_writes: slot.and_then(|s| s.compute(true, true)),
        });
        let offset = [((bounce.clamp(1, MAX_BOUNCES - 1) - 1) as u64 * STRIDE) as u32];
        let groups = points.div_ceil(64);
        pass.set_group(0, &job.splat, &offset);
        pass.set_pipe(&self.splat_pipeline);
        pass.dispatch(groups.min(65535), groups.div_ceil(65535), 1);
        pass.set_pipe(&self.owner_pipeline);
        pass.dispatch(groups.min(65535), groups.div_ceil(65535), 1);
        pass.set_group(0, &job.sample, &offset);
        pass.set_pipe(&self.cdf_pipeline);
        pass.dispatch(vpls, 1, 1);
        pass.set_pipe(&self.sample_pipeline);
        pass.dispatch(1, 1, 1);
    }
}
