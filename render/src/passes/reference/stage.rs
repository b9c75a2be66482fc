//! Stages 3, 4, 6 and 7 with the VPL source "uniform batches" (the exact-VPL reference,
//! Knecht 002 §5.2): one batch of uniformly sampled VPLs from one light view per frame, their
//! exact cube-face visibility (or none), and the full-BRDF gather at every pixel folded into
//! the running average (`reference/gather.wgsl` weights batch k by 1/(k+1): the gather and the
//! temporal choice "running average" are one shader). Once `total_vpls` are in, the average
//! is kept as it is; anything the image depends on restarts it.
//!
//! With emissive surfaces as lights (issue #18), `reference.emitter_points` points of the
//! emitters' stratified set join the cycle as lights of their own (`LIGHT_EMITTER`: a point
//! of flux Φ_j emits the radiant intensity Φ_j/π · max(n · ω, 0)) with five 90° views around
//! their normal, so the reference's first bounce includes the emitters' light, sampled from
//! light G-buffers rendered at those points (exact visibility, as for the punctual lights).

use glam::{Mat4, Vec3, Vec4};

use crate::gpu::GpuContext;
use crate::maths::halton;
use crate::passes::reference::vpl::{BatchView, VplSamplePass};
use crate::passes::reference::vpl_gather::{GatherParams, VplGatherPass};
use crate::passes::reference::vpl_visibility::VplVisibilityPass;
use crate::passes::shadow::{GpuLight, LightView};
use crate::passes::stages::{FrameInputs, Visibility, VplSet, vpl_clip};
use crate::scene::emitters::Emitters;
use crate::scene::upload::GpuScene;
use crate::settings::pipeline::VplVisibility;
use crate::timing::GpuTimer;
use crate::timing::PassRec;

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
            gather: VplGatherPass::new(ctx, width, height),
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

    /// Whether the running average has every batch `reference.total_vpls` asks for (it then
    /// gathers no more until something changes or the history is reset).
    pub fn complete(&self, rs: &crate::passes::reference::vpl::ReferenceSettings) -> bool {
        self.batches > 0 && self.batches >= rs.total_vpls.div_ceil(rs.vpls_per_frame.max(1))
    }

    /// The running average (`indirect.accum`).
    pub fn average(&self) -> wgpu::TextureView {
        crate::passes::view(&self.gather.accum, "indirect.accum")
    }

    /// Stage 3: the next batch, or None when the average is complete (or there is no light).
    /// `emitters`: this frame's emissive triangles when they are lights.
    pub fn vpls(
        &mut self,
        f: &FrameInputs,
        enc: &mut wgpu::CommandEncoder,
        timer: &mut GpuTimer,
        view_proj: Mat4,
        emitters: Option<&Emitters>,
    ) -> Option<VplSet> {
        let (ctx, rs) = (f.ctx, &f.settings.reference);
        let n = rs.vpls_per_frame;
        // The lights' views and the emitter points' views, taken in turn; each batch stands
        // for all V of them.
        let mut lights = f.lights.clone();
        let mut views: Vec<BatchView> =
            f.views.iter().map(|&(light_index, view)| BatchView { light_index, view }).collect();
        if let Some(e) = emitters {
            emitter_lights(e, rs.emitter_points, f.center, f.vpl_radius(), &mut lights, &mut views);
        }
        // Restart when anything the image depends on changed.
        // The sky's rotating directions are not a change: each batch takes this frame's set, so
        // that the average converges to the true sky (`sky.rotate_each_frame`, issue #51).
        let mut fingerprint: Vec<f32> = view_proj.to_cols_array().to_vec();
        fingerprint.extend(f.steady_light_key());
        fingerprint.extend(lights[f.lights.len()..].iter().flat_map(|l| bytemuck::cast::<_, [f32; 20]>(*l)));
        fingerprint.extend(f.state.draws.iter().flat_map(|d| d.world.to_cols_array()));
        if fingerprint != self.fingerprint {
            self.fingerprint = fingerprint;
            self.batches = 0;
        }
        if self.batches >= rs.total_vpls.div_ceil(n) || views.is_empty() {
            return None;
        }
        let v_count = views.len() as u32;
        let batch = views[(self.batches % v_count) as usize];
        let k = self.batches;
        let jitter = (halton(k / v_count + 1, 2) - 0.5, halton(k / v_count + 1, 3) - 0.5);
        let size = rs.light_gbuffer_size as f32;
        // The direct light's intensity scale applies to the punctual lights, not the emitters
        // (as in stage 2).
        let punctual = (batch.light_index as usize) < f.lights.len();
        let intensity = if punctual { f.settings.direct.intensity_scale } else { 1.0 };
        let flux_scale = size * size * v_count as f32 / n as f32 * intensity;
        let (gpu_scene, state) = (f.gpu_scene, f.state);
        let sample = &mut self.sample;
        timer.scope(ctx, enc, "vpl.light_gbuffer", |e, slot| {
            sample.render_view(PassRec { ctx, enc: e, slot }, gpu_scene, state, &batch.view, jitter)
        });
        timer.scope(ctx, enc, "vpl.sample", |e, slot| {
            sample.sample(PassRec { ctx, enc: e, slot }, &lights, batch, n, flux_scale, [rs.seed, k, k / v_count])
        });
        Some(VplSet {
            list: self.sample.vpls.clone(),
            count: n,
            min_distance: rs.min_distance_m,
            near_cut: f.near_field_cut(),
            sources: Vec::new(),
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
        self.visibility.exact_visibility(f, enc, timer, vpls, (self.clip(f), true))
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
                f.settings.vpl.diffuse_only_receiver() as u32 as f32,
            ),
            near: Vec4::new(vpls.near_cut * vpls.near_cut, 0.0, 0.0, 0.0),
        };
        let (gather, atlas) = (&self.gather, &self.visibility.atlas_view);
        timer.scope(ctx, enc, "indirect.gather", |e, slot| {
            gather.run(PassRec { ctx, enc: e, slot }, f.camera_buffer, f.gbuffer, &vpls.list, atlas, params)
        });
        self.batches += 1;
        self.average()
    }
}

/// Appends `points` points of the emitters' stratified set (`Emitters::vpls`) to `lights` as
/// `LIGHT_EMITTER` lights (colour Φ_j/π: the radiant intensity along the normal) and their
/// five 90° views around the normal to `views` (the face behind the emitting side would see
/// nothing it lights). The eye sits 10⁻⁴ × the scene radius off the surface, in front.
fn emitter_lights(
    emitters: &Emitters,
    points: u32,
    center: Vec3,
    radius: f32,
    lights: &mut Vec<GpuLight>,
    views: &mut Vec<BatchView>,
) {
    let near = (radius * 0.002).max(1e-3);
    for p in emitters.vpls(points, 0) {
        let n = p.normal.normalize_or(Vec3::Y);
        let eye = p.position + n * (1e-4 * radius);
        let far = (eye.distance(center) + 1.05 * radius).max(2.0 * near);
        let proj = glam::camera::rh::proj::directx::perspective(std::f32::consts::FRAC_PI_2, 1.0, near, far);
        let light_index = lights.len() as u32;
        lights.push(GpuLight {
            position: eye.extend(3.0),
            direction: n.extend(0.0),
            color: (p.flux / std::f32::consts::PI).extend(0.0),
            cone: Vec4::new(-1.0, 1.0, 0.0, 0.0),
            shadow: Vec4::ZERO,
        });
        let (t, b) = n.any_orthonormal_pair();
        for (forward, up) in [(n, t), (t, n), (-t, n), (b, n), (-b, n)] {
            let view = LightView {
                view: glam::camera::rh::view::look_to_mat4(eye, forward, up),
                proj,
                eye,
                forward,
                pixel_extent: 2.0,
                orthographic: false,
            };
            views.push(BatchView { light_index, view });
        }
    }
}
