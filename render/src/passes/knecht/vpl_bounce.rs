//! Stage 3, further light bounces of instant radiosity (Knecht 002 §3.6.1): per VPL of a
//! bounce, one point of the point cloud among those assigned to it becomes a VPL of the next
//! bounce; `shaders/knecht/vpl/bounce.wgsl` (documented there), CPU twins
//! `cpu::knecht::{bounce_incident, select_bounce}`.
//!
//! The VPL list (`vpl.list`) holds the bounces one after another: bounce b in slots
//! b·N … b·N + N − 1 (bounce 0 from the light G-buffers), and the ISM atlas one map per slot,
//! so the gather shades all B·N VPLs (each bounce's set estimates that bounce's light, and
//! the bounces add up).

use crate::counters::prelude::*;

use glam::Vec4;

use crate::gpu::GpuContext;
use crate::gpu::bindings::{Bindings, Kind, binding};
use crate::passes::knecht::ism::{BounceShadowTest, IsmPass, MAX_BOUNCES};
pub use crate::settings::knecht::{BounceMethod, BounceSelection};
use crate::timing::Slot;

/// Uniform of one bounce; WGSL twin: `BounceParams` in `shaders/common/bounce.wgsl` (the
/// IRSM baseline, `passes::knecht::irsm`, uses it too: counts, the two first slots, d_min², seed).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct BounceParams {
    /// Points P, VPLs per bounce N, atlas columns, map (ISM or IRSM) size.
    pub counts: [u32; 4],
    /// First slot of the source bounce, first slot of the new one, selection (0 strongest,
    /// 1 proportional), shadow test: none (0), raw splats (1) or pulled maps (2).
    pub slots: [u32; 4],
    /// ISM eye offset, depth bias, d_min², receiver normal offset (texels; pulled maps).
    pub geom: Vec4,
    /// Random seed of this frame and bounce.
    pub seed: [u32; 4],
}

const STRIDE: u64 = 256;

/// The random seed of bounce `b` in the frame with seed `frame_seed`.
pub fn bounce_seed(frame_seed: u32, b: u32) -> u32 {
    crate::maths::pcg_hash(frame_seed.wrapping_mul(MAX_BOUNCES).wrapping_add(b))
}

/// What one frame's bounces need besides the ISM pass.
#[derive(Clone, Copy, Debug)]
pub struct BounceFrame {
    /// VPLs per bounce N.
    pub vpls: u32,
    pub selection: BounceSelection,
    /// How the samples are tested against the source VPL's ISM (None: no visibility).
    pub visibility: Option<BounceShadowTest>,
    pub eye_offset: f32,
    pub depth_bias: f32,
    /// Receiver normal offset in texels (the pulled-maps test, as the gather's).
    pub normal_offset: f32,
    pub min_distance: f32,
    /// Seed of the frame (each bounce derives its own).
    pub seed: u32,
}

const CS: wgpu::ShaderStages = wgpu::ShaderStages::COMPUTE;
const READ: Kind = Kind::Storage { read_only: true };

/// The bounce's inputs (`knecht/vpl/bounce.wgsl`, group 0): the bounce's uniform slot, the
/// point cloud, the instances, the raw splats, the VPL list it writes, the pulled atlas.
pub const BOUNCE_BINDINGS: Bindings = Bindings {
    label: "vpl.bounce.inputs",
    shader: "knecht/vpl/bounce.wgsl",
    group: 0,
    entry: None,
    visibility: CS,
    list: &[
        binding(0, "bp", Kind::UniformDynamic),
        binding(1, "points", READ),
        binding(2, "surfaces", READ),
        binding(3, "instances", READ),
        binding(4, "depth", READ),
        binding(5, "vpls", Kind::Storage { read_only: false }),
        binding(6, "pulled", Kind::Texture { filterable: false }),
    ],
};

pub struct VplBouncePass {
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::ComputePipeline,
    params: wgpu::Buffer,
}

impl VplBouncePass {
    pub fn new(ctx: &GpuContext) -> Self {
        let device = &ctx.device;
        let layout = BOUNCE_BINDINGS.layout(device);
        let module = crate::shaders::create_module(device, "knecht/vpl/bounce.wgsl");
        let pipeline = crate::passes::compute_pipeline(device, "vpl.bounce", &module, "cs_bounce", &[&layout]);
        let params = crate::passes::uniform_buffer(device, "vpl.bounce.params", STRIDE * MAX_BOUNCES as u64);
        Self { layout, pipeline, params }
    }

    /// Writes the uniforms of bounces 1 … `bounces` − 1 and returns the frame's bind group
    /// (the raw splats and the pulled atlas are both bound; the uniform picks).
    pub fn begin(
        &self,
        ctx: &GpuContext,
        ism: &IsmPass,
        instances: &wgpu::Buffer,
        vpls: &wgpu::Buffer,
        bounces: u32,
        f: BounceFrame,
    ) -> wgpu::BindGroup {
        let l = ism.layout_info;
        let params: Vec<BounceParams> = (1..bounces.clamp(1, MAX_BOUNCES))
            .map(|b| BounceParams {
                counts: [ism.cloud.gpu.len() as u32, f.vpls, l.cols, l.size],
                slots: [
                    (b - 1) * f.vpls,
                    b * f.vpls,
                    (f.selection == BounceSelection::Proportional) as u32,
                    match f.visibility {
                        None => 0,
                        Some(BounceShadowTest::RawSplats) => 1,
                        Some(BounceShadowTest::PulledMaps) => 2,
                    },
                ],
                geom: Vec4::new(f.eye_offset, f.depth_bias, f.min_distance * f.min_distance, f.normal_offset),
                seed: [bounce_seed(f.seed, b), 0, 0, 0],
            })
            .collect();
        let data = crate::passes::strided_bytes(STRIDE, MAX_BOUNCES as usize, &params);
        ctx.queue.upload(&self.params, 0, &data);
        let shading = ism.shading_view();
        BOUNCE_BINDINGS.group(
            &ctx.device,
            &self.layout,
            [
                wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                    buffer: &self.params,
                    offset: 0,
                    size: std::num::NonZeroU64::new(std::mem::size_of::<BounceParams>() as u64),
                }),
                ism.points.as_entire_binding(),
                ism.surfaces.as_entire_binding(),
                instances.as_entire_binding(),
                ism.depth.as_entire_binding(),
                vpls.as_entire_binding(),
                wgpu::BindingResource::TextureView(&shading),
            ],
        )
    }

    /// Creates bounce `bounce`'s N VPLs (slots b·N …) from bounce b − 1's, whose ISMs must
    /// have been splatted (when visibility is on) and, for the pulled-maps test, resolved
    /// and pulled-pushed (`IsmPass::finish`).
    pub fn run(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        slot: Option<Slot<'_>>,
        group: &wgpu::BindGroup,
        bounce: u32,
        vpls: u32,
    ) {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("vpl.bounce"),
            timestamp_writes: slot.and_then(|s| s.compute(true, true)),
        });
        pass.set_pipe(&self.pipeline);
        let b = bounce.clamp(1, MAX_BOUNCES - 1);
        pass.set_group(0, group, &[((b - 1) as u64 * STRIDE) as u32]);
        pass.dispatch(vpls, 1, 1);
    }
}
