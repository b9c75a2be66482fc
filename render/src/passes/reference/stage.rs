//! Stages 3, 4, 6 and 7 with the VPL source "uniform batches" (the exact-VPL reference,
//! Knecht 002 §5.2): one batch of uniformly sampled VPLs from one light view per frame, their
//! exact cube-face visibility (or none), and the full-BRDF gather at every pixel folded into
//! the running average (`vpl/gather.wgsl` weights batch k by 1/(k+1): the gather and the
//! temporal choice "running average" are one shader). Once `total_vpls` are in, the average
//! is kept as it is; anything the image depends on restarts it.

use glam::{Mat4, Vec4};

use crate::gpu::GpuContext;
use crate::passes::bgl;
use crate::passes::knecht::vpl_importance::ReceiverBrdf;
use crate::passes::reference::vpl::{BatchView, VplSamplePass, halton};
use crate::passes::reference::vpl_gather::{GatherParams, VplGatherPass};
use crate::passes::reference::vpl_visibility::VplVisibilityPass;
use crate::pipeline::VplVisibility;
use crate::scene::upload::GpuScene;
use crate::stages::{FrameInputs, Visibility, VplSet, vpl_clip};
use crate::timing::GpuTimer;

/// The exact-VPL reference's passes and its progress.
pub struct ReferenceVpls {
    pub sample: VplSamplePass,
    pub visibility: VplVisibilityPass,
    pub gather: VplGatherPass,
    /// Batches accumulated since the last reset.
    pub batches: u32,
    /// What the accumulated image depends on (camera, lights, transforms, size); a change
    /// restarts the accumulation.
    fingerprint: Vec<f32>,
}

impl ReferenceVpls {
    pub fn new(ctx: &GpuContext, gpu_scene: &GpuScene, s: &crate::LabSettings, width: u32, height: u32) -> Self {
        let rs = &s.reference;
        Self {
            sample: VplSamplePass::new(ctx, gpu_scene, rs.light_gbuffer_size, rs.vpls_per_frame),
            visibility: VplVisibilityPass::new(ctx, gpu_scene),
            gather: VplGatherPass::new(ctx, bgl::uniform(0, wgpu::ShaderStages::COMPUTE), width, height),
            batches: 0,
            fingerprint: Vec::new(),
        }
    }

    /// Resizes for the settings; true when buffers were replaced.
    pub fn ensure(&mut self, ctx: &GpuContext, s: &crate::LabSettings) -> bool {
        let rs = &s.reference;
        let fresh = self.sample.ensure(ctx, rs.light_gbuffer_size, rs.vpls_per_frame);
        fresh | self.visibility.ensure(ctx, rs.vpls_per_frame, rs.shadow_map_size)
    }

    pub fn register(&self, reg: &mut crate::buffers::BufferRegistry) {
        self.sample.light_gbuffer.register(reg);
        self.visibility.register(reg);
        self.gather.register(reg);
    }

    /// The running average (`indirect.accum`).
    pub fn average(&self) -> wgpu::TextureView {
        crate::passes::view(&self.gather.accum, "indirect.accum")
    }

    /// Stage 3: the next batch, or None when the average is complete (or there is no light).
    pub fn vpls(
        &mut self,
        f: &FrameInputs,
        enc: &mut wgpu::CommandEncoder,
        timer: &mut GpuTimer,
        view_proj: Mat4,
    ) -> Option<VplSet> {
        let (ctx, rs) = (f.ctx, &f.settings.reference);
        let n = rs.vpls_per_frame;
        // Restart when anything the image depends on changed.
        let mut fingerprint: Vec<f32> = view_proj.to_cols_array().to_vec();
        fingerprint.extend(f.lights.iter().flat_map(|l| bytemuck::cast::<_, [f32; 20]>(*l)));
        fingerprint.extend(f.state.draws.iter().flat_map(|d| d.world.to_cols_array()));
        if fingerprint != self.fingerprint {
            self.fingerprint = fingerprint;
            self.batches = 0;
        }
        if self.batches >= rs.total_vpls.div_ceil(n) || f.lights.is_empty() {
            return None;
        }
        // The views of all lights, taken in turn; each batch stands for all V of them.
        let views: Vec<BatchView> =
            f.views.iter().map(|&(light_index, view)| BatchView { light_index, view }).collect();
        let v_count = views.len() as u32;
        let batch = views[(self.batches % v_count) as usize];
        let k = self.batches;
        let jitter = (halton(k / v_count + 1, 2) - 0.5, halton(k / v_count + 1, 3) - 0.5);
        let size = rs.light_gbuffer_size as f32;
        let flux_scale = size * size * v_count as f32 / n as f32 * f.settings.direct.intensity_scale;
        let (gpu_scene, state) = (f.gpu_scene, f.state);
        let sample = &mut self.sample;
        timer.scope(ctx, enc, "vpl.light_gbuffer", |e, slot| {
            sample.render_view(ctx, e, slot, gpu_scene, state, &batch.view, jitter)
        });
        timer.scope(ctx, enc, "vpl.sample", |e, slot| {
            sample.sample(ctx, e, slot, &f.lights, batch, n, flux_scale, [rs.seed, k, k / v_count])
        });
        Some(VplSet {
            list: self.sample.vpls.clone(),
            count: n,
            min_distance: rs.min_distance_m,
            near_cut: f.near_field_cut(),
        })
    }

    fn clip(&self, f: &FrameInputs) -> Vec4 {
        vpl_clip(f.vpl_radius(), f.settings.reference.min_distance_m)
    }

    /// Stage 4: exact cube-face maps of the batch, or none.
    pub fn visibility(
        &mut self,
        f: &FrameInputs,
        enc: &mut wgpu::CommandEncoder,
        timer: &mut GpuTimer,
        vpls: &VplSet,
    ) -> Visibility {
        if f.settings.pipeline.vpl_visibility != VplVisibility::Exact {
            return Visibility::None;
        }
        self.visibility.exact_visibility(f, enc, timer, vpls, self.clip(f))
    }

    /// Stage 6 (and 7): the gather at every pixel (full BRDF, or diffuse only by
    /// `vpl.receiver_brdf`), folded into the running average.
    pub fn gather(
        &mut self,
        f: &FrameInputs,
        enc: &mut wgpu::CommandEncoder,
        timer: &mut GpuTimer,
        vpls: &VplSet,
        vis: &Visibility,
    ) -> wgpu::TextureView {
        let (ctx, rs) = (f.ctx, &f.settings.reference);
        let visible = matches!(vis, Visibility::Exact { .. });
        let l = self.visibility.layout_info;
        let k = self.batches;
        let params = GatherParams {
            batch: Vec4::new(vpls.count as f32, l.cols as f32, l.size as f32, 1.0 / (k + 1) as f32),
            clip: self.clip(f),
            bias: Vec4::new(
                rs.depth_bias,
                rs.normal_offset,
                if visible { 1.0 } else { 0.0 },
                (f.settings.vpl.receiver_brdf == ReceiverBrdf::DiffuseOnly) as u32 as f32,
            ),
            near: Vec4::new(vpls.near_cut * vpls.near_cut, 0.0, 0.0, 0.0),
        };
        let (gather, atlas) = (&self.gather, &self.visibility.atlas_view);
        timer.scope(ctx, enc, "indirect.gather", |e, slot| {
            gather.run(ctx, e, slot, f.camera_buffer, f.gbuffer, &vpls.list, atlas, params)
        });
        self.batches += 1;
        self.average()
    }
}
