//! Stages 3–4 with the VPL source "importance warping" (Knecht 002 §3.3, §3.6.1, §4.3–4.4):
//! VPLs from the light G-buffers of every light view, their further bounces, and their
//! visibility by imperfect shadow maps (§2.6.5), exact cube-face maps or none.
//!
//! The further bounces need the ISMs of the bounce before them (§3.6.1: bounce b's ISMs are
//! splatted, then bounce b + 1's VPLs are chosen from the point cloud with them), so stage 3
//! splats the maps the bounces read and stage 4 splats what is left and pulls-pushes.

use crate::counters::prelude::*;
use crate::fingerprint::{Fingerprint, LastRun, Space};
use crate::gpu::GpuContext;
use crate::lab_settings::LabSettings;
use crate::maths::split_budget;
use crate::passes::knecht::irsm::{IrsmFrame, IrsmJob, IrsmPass};
use crate::passes::knecht::ism::{BounceShadowTest, IsmFrame, IsmJob, IsmPass, MAX_BOUNCES};
use crate::passes::knecht::vpl_bounce::{BounceFrame, BounceMethod, VplBouncePass};
use crate::passes::knecht::vpl_importance::{ViewJob, VplImportancePass, view_powers};
use crate::passes::reference::vpl_visibility::VplVisibilityPass;
use crate::passes::stages::{FrameInputs, Visibility, VplSet, vpl_clip};
use crate::scene::upload::GpuScene;
use crate::scene::{Scene, SceneState};
use crate::settings::pipeline::VplVisibility;
use crate::timing::GpuTimer;
use crate::timing::PassRec;

/// The passes of importance-warped VPLs and their visibility.
pub struct KnechtVpls {
    pub vpl: VplImportancePass,
    pub ism: IsmPass,
    pub bounce: VplBouncePass,
    /// The IRSM multi-bounce baseline, created when selected.
    pub irsm: Option<IrsmPass>,
    /// Exact visibility maps, created when selected.
    pub exact: Option<VplVisibilityPass>,
    /// Frames rendered (the Halton offset of a new VPL set per frame).
    pub frames: u32,
    /// This frame's ISM job (from stage 3 to stage 4).
    job: Option<IsmJob>,
    /// Maps of this frame's atlas already resolved and pull-pushed by the bounces' shadow
    /// tests (stage 4 does the rest).
    pulled_maps: u32,
    /// What the light G-buffers and importance pyramids were last made for, and the VPL set
    /// with its visibility: each is kept while its inputs stay the same (issue #53).
    light_views: LastRun,
    set: LastRun,
    /// Whether this frame made a new VPL set (stage 4 then redoes its visibility) and new
    /// light views.
    set_made: bool,
    views_made: bool,
}

/// The pass that makes a frame's further bounces, with its bind groups.
enum Bounces<'a> {
    PointCloud(&'a VplBouncePass, wgpu::BindGroup),
    Irsm(&'a IrsmPass, IrsmJob),
}

/// The slots of each bounce: `vpl.count`, or fewer where the VPL list holds fewer.
fn first_bounce_slots(vpl: &VplImportancePass, s: &LabSettings) -> u32 {
    s.vpl.count.min(vpl.capacity / s.vpl.bounces.clamp(1, MAX_BOUNCES))
}

/// Whether the point cloud is splatted into ISMs this frame: for the ISM visibility, and for
/// the further bounces' visibility test unless visibility is off.
pub fn ism_splats(s: &LabSettings) -> bool {
    match s.pipeline.vpl_visibility {
        VplVisibility::None => false,
        VplVisibility::Imperfect => true,
        VplVisibility::Exact => s.vpl.bounces > 1 && s.vpl.bounce_method == BounceMethod::PointCloud,
    }
}

/// Another source of bounce-0 VPLs that shares stage 3's budget with the light views, by
/// power (`vpl.split_by_power`): the emissive surfaces (`passes::emitters`, which implements
/// it; Knecht's VPLs do not depend on it).
pub trait FirstBounceSource {
    /// How many VPLs it has this frame and their power; None when it has none.
    fn share(&self) -> Option<(u32, f32)>;
    /// Writes `k` (of a budget of `budget`) first-bounce VPLs to slots `first` … of `dest`;
    /// returns how many it wrote.
    fn bounce_into(
        &mut self,
        f: &FrameInputs,
        enc: &mut wgpu::CommandEncoder,
        timer: &mut GpuTimer,
        k_of_budget: (u32, u32),
        dest_from: (&wgpu::Buffer, u32),
    ) -> u32;
}

impl KnechtVpls {
    pub fn new(ctx: &GpuContext, s: &LabSettings) -> Self {
        Self {
            vpl: VplImportancePass::new(ctx, s.vpl.light_gbuffer_size),
            ism: IsmPass::new(ctx),
            bounce: VplBouncePass::new(ctx),
            irsm: None,
            exact: None,
            frames: 0,
            pulled_maps: 0,
            job: None,
            light_views: LastRun::default(),
            set: LastRun::default(),
            set_made: false,
            views_made: false,
        }
    }

    /// Creates or resizes what the settings need; true when buffers were replaced (the
    /// registry must be refreshed).
    pub fn ensure(
        &mut self,
        ctx: &GpuContext,
        scene: &Scene,
        state: &SceneState,
        gpu_scene: &GpuScene,
        s: &LabSettings,
        views: usize,
    ) -> bool {
        let total = s.vpl.count * s.vpl.bounces.clamp(1, MAX_BOUNCES);
        let mut fresh = self.vpl.ensure(ctx, gpu_scene, s.vpl.light_gbuffer_size, views, total);
        // The point cloud serves the ISMs and the bounces; the splatted maps the ISM
        // visibility and the bounces' visibility test.
        if s.pipeline.vpl_visibility == VplVisibility::Imperfect || s.vpl.bounces > 1 {
            let maps = if ism_splats(s) { total } else { 1 };
            fresh |= self.ism.ensure(ctx, scene, state, &s.ism, maps, false);
        }
        if s.vpl.bounces > 1 && s.vpl.bounce_method == BounceMethod::Irsm {
            let points = self.ism.cloud.gpu.len();
            let created = self.irsm.is_none();
            let irsm = self.irsm.get_or_insert_with(|| IrsmPass::new(ctx));
            fresh |= irsm.ensure(ctx, s.vpl.count, s.vpl.irsm_size, points) || created;
        } else if self.irsm.take().is_some() {
            fresh = true;
        }
        if s.pipeline.vpl_visibility == VplVisibility::Exact {
            let e = self.exact.get_or_insert_with(|| VplVisibilityPass::new(ctx, gpu_scene));
            fresh |= e.ensure(ctx, total, s.ism.map_size);
        } else if self.exact.take().is_some() {
            // The exact maps are not kept for a later switch back (issue #19's soak: an
            // atlas of ~11 MB stayed alive at the starting state after a visit to Exact).
            fresh = true;
        }
        if fresh {
            self.light_views.invalidate();
            self.set.invalidate();
        }
        fresh
    }

    /// The passes this frame kept from an earlier one (`Renderer::kept_passes`).
    pub fn kept(&self, s: &LabSettings) -> Vec<&'static str> {
        let mut v = Vec::new();
        if !self.views_made {
            v.extend(["vpl.light_gbuffer", "vpl.importance"]);
        }
        if !self.set_made {
            v.push("vpl.sample");
            match s.pipeline.vpl_visibility {
                VplVisibility::Exact => v.push("vpl.shadow"),
                VplVisibility::Imperfect => v.extend(["ism.splat", "ism.pull_push"]),
                VplVisibility::None => {}
            }
        }
        v
    }

    /// Forgets what the light views and the VPL set were made for: the next frame redoes them
    /// (`Renderer::redo_kept_passes`, `Renderer::reuse_unchanged` off).
    pub fn redo_light_space(&mut self) {
        self.light_views.invalidate();
        self.set.invalidate();
    }

    pub fn register(&self, reg: &mut crate::buffers::BufferRegistry, s: &LabSettings) {
        self.vpl.register(reg);
        match s.pipeline.vpl_visibility {
            VplVisibility::Exact => {
                if let Some(e) = &self.exact {
                    e.register(reg);
                }
            }
            VplVisibility::Imperfect => self.ism.register(reg),
            VplVisibility::None => {}
        }
        if let Some(irsm) = &self.irsm {
            irsm.register(reg);
        }
    }

    /// Stage 3: this frame's VPLs of every light view and bounce (with the ISMs the bounces
    /// need, §3.6.1). With emitters as lights (`passes::emitters`), bounce 0 also holds the
    /// emitters' first bounce: their share of the budget by power, after the light views'.
    pub fn vpls(
        &mut self,
        f: &FrameInputs,
        enc: &mut wgpu::CommandEncoder,
        timer: &mut GpuTimer,
        emitters: Option<&mut dyn FirstBounceSource>,
    ) -> VplSet {
        let (ctx, s) = (f.ctx, f.settings);
        let mut powers = view_powers(&f.state.lights, f.vpl_radius(), s.vpl.split_by_power);
        let emitters = emitters.filter(|e| e.share().is_some());
        if let Some((_, power)) = emitters.as_ref().and_then(|e| e.share()) {
            powers.push(if s.vpl.split_by_power { power } else { 1.0 });
        }
        let mut counts = split_budget(&powers, s.vpl.count);
        let emitter_share = if emitters.is_some() { counts.pop().unwrap_or(0) } else { 0 };
        let mut first = 0;
        let jobs: Vec<ViewJob> = f
            .views
            .iter()
            .zip(&counts)
            .map(|(&(light_index, view), &count)| {
                let job = ViewJob { light_index, view, first, count };
                first += count;
                job
            })
            .collect();
        // The slots' sources: bounce 0 by light view (then the emitters), one range per
        // further bounce.
        let light_name = |i: u32| f.state.lights.get(i as usize).map(|l| l.light.name.as_str()).unwrap_or("");
        let mut sources: Vec<(u32, u32, String)> = jobs
            .iter()
            .map(|j| (j.first, j.count, format!("light {} '{}', bounce 0", j.light_index, light_name(j.light_index))))
            .collect();
        let halton_first = 1 + if s.vpl.new_set_each_frame { self.frames.wrapping_mul(s.vpl.count) } else { 0 };
        let seed = if s.vpl.new_set_each_frame { self.frames } else { 0 };
        // The light G-buffers and their importance depend on the lights, their views, the
        // objects and the settings; the VPL set on those and its sequence offsets (new each
        // frame with `vpl.new_set_each_frame`). Each is redone only when they changed (issue
        // #53). The emitters' share follows from the same inputs (their VPLs and bounce use
        // sequence offset 0).
        let light_key = Fingerprint::new().debug(s).pod(&f.lights).debug(&f.views).draws(&f.state.draws).finish();
        let views_changed = self.light_views.needs_run(light_key, Space::Light);
        self.views_made = views_changed;
        let set_key = Fingerprint::new()
            .u64s(&[light_key, halton_first as u64, seed as u64, f.vpl_radius().to_bits() as u64])
            .finish();
        self.set_made = self.set.needs_run(set_key, Space::Light);
        if !self.set_made {
            self.frames = self.frames.wrapping_add(1);
            return self.vpl_set(s, f, sources, first_bounce_slots(&self.vpl, s));
        }
        if f.lights.is_empty() {
            // No light: no VPL slot is written, so the list is cleared.
            enc.counted_clear_buffer(&self.vpl.vpls, 0, None);
        } else {
            self.vpl.albedo_mip = s.vpl.albedo_mip;
            self.vpl.importance_bias = s.vpl.importance_bias;
            let (scene, state, lights) = (f.gpu_scene, f.state, &f.lights);
            self.vpl.write_params(ctx, lights, &jobs, halton_first, s.direct.intensity_scale);
            let r = &mut crate::timing::Recorder { enc, timer };
            self.vpl.run(ctx, r, (scene, state), &jobs, views_changed);
        }
        let bounces = s.vpl.bounces.clamp(1, MAX_BOUNCES);
        let n_vpls = first_bounce_slots(&self.vpl, s);
        if let Some(e) = emitters {
            let list = &self.vpl.vpls;
            let written = e.bounce_into(f, enc, timer, (emitter_share, s.vpl.count), (list, first));
            sources.push((first, written, "emitters, bounce 0".into()));
            // Slots the emitters could not fill (more than their VPLs) stay empty.
            let (used, size) = (first + written, std::mem::size_of::<crate::passes::reference::vpl::GpuVpl>() as u64);
            if used < n_vpls {
                enc.counted_clear_buffer(list, used as u64 * size, Some((n_vpls - used) as u64 * size));
            }
        }

        let eye_offset = Self::eye_offset(s, f.vpl_radius());
        let splats = ism_splats(s);
        self.pulled_maps = 0;
        let instances = &f.gpu_scene.instances;
        self.job = (splats || bounces > 1).then(|| {
            let frame = IsmFrame { vpls: n_vpls, bounces, eye_offset, extent: 2.0 * f.vpl_radius() };
            self.ism.begin(ctx, instances, &self.vpl.vpls, &s.ism, frame)
        });
        if let Some(job) = &self.job {
            let ism = &self.ism;
            if splats {
                timer.scope(ctx, enc, "ism.splat", |e, slot| ism.splat(e, slot, job, 0));
            }
            if bounces > 1 {
                let make = match (s.vpl.bounce_method, self.irsm.as_ref()) {
                    (BounceMethod::Irsm, Some(irsm)) => {
                        let fr =
                            IrsmFrame { vpls: n_vpls, bounces, eye_offset, min_distance: s.vpl.min_distance_m, seed };
                        Bounces::Irsm(irsm, irsm.begin(ctx, ism, &s.ism, instances, &self.vpl.vpls, fr))
                    }
                    _ => {
                        let fr = BounceFrame {
                            vpls: n_vpls,
                            selection: s.vpl.bounce_selection,
                            visibility: splats.then_some(s.ism.bounce_test),
                            eye_offset,
                            depth_bias: s.ism.depth_bias,
                            normal_offset: s.ism.normal_offset,
                            min_distance: s.vpl.min_distance_m,
                            seed,
                        };
                        let group = self.bounce.begin(ctx, ism, instances, &self.vpl.vpls, bounces, fr);
                        Bounces::PointCloud(&self.bounce, group)
                    }
                };
                let points = ism.cloud.gpu.len() as u32;
                let pulled = splats && s.ism.bounce_test == BounceShadowTest::PulledMaps;
                let extent = 2.0 * f.vpl_radius();
                for b in 1..bounces {
                    // The pulled maps of bounces 0 … b − 1 for bounce b's shadow test: those of
                    // bounces before b − 1 were pulled for bounce b − 1's, so only bounce
                    // b − 1's maps are resolved and pulled here (issue #38).
                    if pulled && matches!(make, Bounces::PointCloud(..)) {
                        let maps = (b - 1) * n_vpls..b * n_vpls;
                        timer.scope(ctx, enc, &format!("ism.pull_push.{b}"), |e, slot| {
                            ism.finish_maps(PassRec { ctx, enc: e, slot }, job, &s.ism, extent, maps, b)
                        });
                        self.pulled_maps = b * n_vpls;
                    }
                    timer.scope(ctx, enc, &format!("vpl.bounce.{b}"), |e, slot| match &make {
                        Bounces::PointCloud(pass, group) => pass.run(e, slot, group, b, n_vpls),
                        Bounces::Irsm(pass, job) => pass.run(e, slot, job, b, n_vpls, points),
                    });
                    // The last bounce's maps are needed only when the ISMs are the shading's
                    // visibility.
                    if splats && (b + 1 < bounces || s.pipeline.vpl_visibility == VplVisibility::Imperfect) {
                        timer.scope(ctx, enc, &format!("ism.splat.{b}"), |e, slot| ism.splat(e, slot, job, b));
                    }
                }
            }
        }
        self.frames = self.frames.wrapping_add(1);
        self.vpl_set(s, f, sources, n_vpls)
    }

    /// The frame's VPL set: `n_vpls` slots a bounce, bounce 0's `sources` and the further
    /// bounces'.
    fn vpl_set(&self, s: &LabSettings, f: &FrameInputs, mut sources: Vec<(u32, u32, String)>, n_vpls: u32) -> VplSet {
        let bounces = s.vpl.bounces.clamp(1, MAX_BOUNCES);
        sources.extend((1..bounces).map(|b| (b * n_vpls, n_vpls, format!("bounce {b}"))));
        VplSet {
            list: self.vpl.vpls.clone(),
            count: n_vpls * bounces,
            min_distance: s.vpl.min_distance_m,
            near_cut: f.near_field_cut(),
            sources,
        }
    }

    /// The ISM eye's lift above its VPL (`ism.eye_offset` × the scene radius).
    fn eye_offset(s: &LabSettings, radius: f32) -> f32 {
        s.ism.eye_offset * radius
    }

    /// Stage 4: the visibility of this frame's VPLs (None when the passes it needs are
    /// missing, which `ensure` prevents).
    pub fn visibility(
        &mut self,
        f: &FrameInputs,
        enc: &mut wgpu::CommandEncoder,
        timer: &mut GpuTimer,
        vpls: &VplSet,
    ) -> Option<Visibility> {
        let (ctx, s) = (f.ctx, f.settings);
        Some(match s.pipeline.vpl_visibility {
            VplVisibility::None => Visibility::None,
            VplVisibility::Imperfect => {
                let (ism, job) = (&self.ism, self.job.as_ref()?);
                let extent = 2.0 * f.vpl_radius();
                // The maps the bounces' shadow tests left (all of them without bounces).
                let maps = self.pulled_maps..vpls.count.max(self.pulled_maps);
                if self.set_made {
                    timer.scope(ctx, enc, "ism.pull_push", |e, slot| {
                        ism.finish_maps(PassRec { ctx, enc: e, slot }, job, &s.ism, extent, maps, 0)
                    });
                }
                let l = self.ism.layout_info;
                Visibility::Ism {
                    atlas: self.ism.shading_view(),
                    cols: l.cols,
                    size: l.size,
                    eye_offset: Self::eye_offset(s, f.vpl_radius()),
                    bias: s.ism.depth_bias,
                    normal_offset: s.ism.normal_offset,
                }
            }
            VplVisibility::Exact => {
                let clip = vpl_clip(f.vpl_radius(), 0.0);
                self.exact.as_ref()?.exact_visibility(f, enc, timer, vpls, (clip, self.set_made))
            }
        })
    }
}
