//! Stage 2, emissive surfaces as lights (issue #18 point 1): VPLs on the emitters.
//!
//! The scene's emissive triangles ([`crate::scene::emitters::Emitters`]) get `emitters.vpls`
//! VPLs, placed by power on a stratified Halton set (documented there). They are lights of
//! their own kind, used twice:
//!
//! 1. **Direct light of area emitters**: `passes::direct` adds, at every pixel (and at every
//!    texel of Gautron et al.'s record hemispheres), the light of every emitter VPL with the
//!    geometry term of Knecht 002 Eq. 4.7 (clamped at d_min = `emitters.min_distance` × the
//!    samples' spacing √(A/N_e): the singularity of a point sample next to its area) and the
//!    visibility `emitters.visibility` chooses: **imperfect shadow maps** of the emitter VPLs
//!    (Knecht 002 §2.6.5 after Ritschel et al. 2008, whose §6 lights area lights with the
//!    ISMs of VPLs placed on them; the `ism.*` settings), **exact** five-face maps
//!    (`passes::reference::vpl_visibility`), or none. Since `direct.radiance` then holds the
//!    emitters' light, every technique's first bounce sees it: Soler's screen-space gather reads
//!    it, Gautron's hemispheres are lit with it.
//! 2. **The first bounce of the VPL techniques**: stage 3 (importance warping) gives the
//!    emitters their share of `vpl.count` by power (as it splits the budget between light
//!    views), and [`EmitterPass::bounce_into`] makes that many VPLs on the surfaces the
//!    emitters light with Knecht's point-cloud bounce (002 §3.6.1, `knecht/vpl/bounce.wgsl`, tested
//!    against the ISMs of the emitter VPLs; ⚠[knecht.emitter-bounce] the sample chosen ∝ its
//!    contribution, §6.1 — the thesis' strongest sample would put every VPL next to the
//!    emitter). Its sources are the first k emitter VPLs with flux Φ/k: the Halton prefix, so
//!    their ISMs are maps 0 … k − 1 of the atlas.
//!
//! With emitters as lights the surface's own emission is no longer part of
//! `direct.radiance`; the compose adds it (`gbuffer.emission`), so no gather takes it for a
//! sender a second time. `emitters.enabled` off: emitters only glow.

use crate::counters::prelude::*;

use glam::Vec4;

use crate::buffers::{BufferKind, BufferRegistry};
use crate::gpu::GpuContext;
use crate::lab_settings::LabSettings;
use crate::passes::knecht::ism::{IsmFrame, IsmPass};
use crate::passes::knecht::stage::FirstBounceSource;
use crate::passes::knecht::vpl_bounce::{BounceFrame, VplBouncePass};
use crate::passes::reference::vpl::GpuVpl;
use crate::passes::reference::vpl_visibility::GatherVisibility;
use crate::passes::reference::vpl_visibility::{VisibilityParams, VplVisibilityPass};
use crate::passes::stages::FrameInputs;
use crate::scene::emitters::{EmitterVpl, Emitters};
use crate::scene::upload::GpuScene;
use crate::scene::{Scene, SceneState};
pub use crate::settings::emitters::*;
use crate::timing::PassRec;
use crate::timing::{GpuTimer, Recorder};

/// What `passes::direct` reads of the emitters: this frame's VPLs and their visibility.
#[derive(Clone)]
pub struct EmitterLight {
    pub list: wgpu::Buffer,
    pub count: u32,
    /// d_min of the geometry term (scene units).
    pub min_distance: f32,
    pub visibility: GatherVisibility,
}

/// What the lab shows of the emitters (the Scene panel).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EmitterStats {
    pub triangles: usize,
    /// Total power, luminance (W).
    pub power: f32,
    pub area: f32,
    /// VPLs on the emitters this frame (direct light).
    pub vpls: u32,
    /// Stage 3's VPLs that the emitters' first bounce got this frame (0 without VPL techniques).
    pub bounce_share: u32,
    /// Stage 3's whole VPL budget this frame.
    pub bounce_budget: u32,
}

pub struct EmitterPass {
    ism: IsmPass,
    exact: Option<VplVisibilityPass>,
    bounce: VplBouncePass,
    /// `emitters.vpls`: the emitter VPLs ([`GpuVpl`]).
    list: wgpu::Buffer,
    capacity: u32,
    /// Sources (slots 0 … k − 1) and results (k … 2k − 1) of the first bounce.
    bounce_list: wgpu::Buffer,
    bounce_capacity: u32,
    /// The emitters of this frame.
    pub emitters: Emitters,
    /// What `emitters` was collected from (see [`emitter_key`]): collected again only when
    /// it changes (a textured emitter's triangle means cost texture lookups).
    key: Vec<f32>,
    /// Whether the ISMs hold this frame's VPLs (splatted now, or kept: the bounce's shadow
    /// test reads them).
    splatted: bool,
    /// What the visibility maps were last made for: the emitter VPLs are the same every frame
    /// (sequence offset 0), so the maps are kept while the emitters, the objects and the
    /// settings are (issue #53).
    maps: crate::fingerprint::LastRun,
    /// Whether this frame kept them.
    pub maps_kept: bool,
    pub stats: EmitterStats,
}

/// The GPU record of an emitter VPL: a diffuse VPL of colour 1 (f = 1/π), its "incident"
/// direction along the normal.
pub fn gpu_vpl(v: &EmitterVpl) -> GpuVpl {
    GpuVpl {
        position: v.position.extend(1.0),
        normal: v.normal.extend(1.0),
        flux: v.flux.extend(0.0),
        incident: v.normal.extend(1.0),
        albedo: Vec4::new(1.0, 1.0, 1.0, 0.0),
    }
}

fn vpl_buffer(device: &wgpu::Device, label: &str, slots: u32) -> wgpu::Buffer {
    device.counted_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: slots.max(1) as u64 * std::mem::size_of::<GpuVpl>() as u64,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    })
}

impl EmitterPass {
    pub fn new(ctx: &GpuContext) -> Self {
        Self {
            ism: IsmPass::new(ctx),
            exact: None,
            bounce: VplBouncePass::new(ctx),
            list: vpl_buffer(&ctx.device, "emitters.vpls", 1),
            capacity: 1,
            bounce_list: vpl_buffer(&ctx.device, "emitters.bounce_vpls", 2),
            bounce_capacity: 1,
            emitters: Emitters::default(),
            key: Vec::new(),
            splatted: false,
            maps: Default::default(),
            maps_kept: false,
            stats: EmitterStats::default(),
        }
    }

    /// The number of emitter VPLs the settings ask for, within what the ISM atlas or the exact
    /// atlas can hold on this device (`LabSettings::validate` reports larger requests).
    fn count(ctx: &GpuContext, s: &LabSettings) -> u32 {
        let max_dim = ctx.limits.max_texture_dimension_2d;
        let max_buffer = ctx.limits.max_storage_buffer_binding_size;
        let mut n = s.emitters.vpls.max(1);
        n = n.min(crate::passes::knecht::ism::IsmLayout::largest_count(s.ism.map_size, max_dim, max_buffer).max(1));
        if s.emitters.visibility == EmitterVisibility::Exact {
            let largest = crate::passes::reference::vpl_visibility::AtlasLayout::largest_batch(s.ism.map_size, max_dim);
            n = n.min(largest.max(1));
        }
        n
    }

    /// Sizes the buffers and maps for the settings (the point cloud of `scene` is built when
    /// missing). Returns whether registered resources were replaced.
    pub fn ensure(
        &mut self,
        ctx: &GpuContext,
        scene: &Scene,
        state: &SceneState,
        gpu_scene: &GpuScene,
        s: &LabSettings,
    ) -> bool {
        let n = Self::count(ctx, s);
        let mut fresh = false;
        if n > self.capacity {
            self.list = vpl_buffer(&ctx.device, "emitters.vpls", n);
            self.capacity = n;
        }
        let budget = s.vpl.count.max(1);
        if budget > self.bounce_capacity {
            self.bounce_list = vpl_buffer(&ctx.device, "emitters.bounce_vpls", 2 * budget);
            self.bounce_capacity = budget;
        }
        fresh |= self.ism.ensure(ctx, scene, state, &s.ism, n, false);
        if s.emitters.visibility == EmitterVisibility::Exact {
            let e = self.exact.get_or_insert_with(|| VplVisibilityPass::new(ctx, gpu_scene));
            fresh |= e.ensure(ctx, n, s.ism.map_size);
        } else {
            fresh |= self.exact.take().is_some();
        }
        if fresh {
            self.maps.invalidate();
        }
        fresh
    }

    /// Forgets what the maps were made for: the next frame redoes them
    /// (`Renderer::redo_kept_passes`).
    pub fn redo_maps(&mut self) {
        self.maps.invalidate();
    }

    /// The passes this frame kept from an earlier one (`Renderer::kept_passes`).
    pub fn kept(&self, s: &LabSettings) -> Vec<&'static str> {
        if !self.maps_kept {
            return Vec::new();
        }
        match s.emitters.visibility {
            EmitterVisibility::Imperfect => vec!["emitters.ism.splat", "emitters.ism.pull_push"],
            EmitterVisibility::Exact if s.pipeline.uses_knecht_vpls() => {
                vec!["emitters.ism.splat", "emitters.ism.pull_push", "emitters.shadow"]
            }
            EmitterVisibility::Exact => vec!["emitters.shadow"],
            EmitterVisibility::None => Vec::new(),
        }
    }

    pub fn register(&self, reg: &mut BufferRegistry, s: &LabSettings) {
        match s.emitters.visibility {
            EmitterVisibility::Imperfect => reg.register(
                "emitters.ism",
                BufferKind::Data,
                "imperfect shadow maps of the emitter VPLs after pull-push (map = emitter VPL index; distance in scene units)",
                &self.ism.pulled,
            ),
            EmitterVisibility::Exact => {
                if let Some(e) = &self.exact {
                    reg.register(
                        "emitters.shadow_atlas",
                        BufferKind::Depth,
                        "exact visibility of the emitter VPLs: five 90° cube faces on each one's normal, tile = VPL × 5 + face",
                        &e.atlas,
                    );
                }
            }
            EmitterVisibility::None => {}
        }
    }

    /// Stage 2: this frame's emitter VPLs and their visibility (None when the scene has no
    /// emitter), for the scene at this instant (`scene`, its `state` and its GPU copy) in a
    /// scene of bounding radius `radius`.
    pub fn run(
        &mut self,
        ctx: &GpuContext,
        r: &mut Recorder,
        (scene, state, gpu_scene): (&Scene, &SceneState, &GpuScene),
        s: &LabSettings,
        radius: f32,
    ) -> Option<EmitterLight> {
        let (enc, timer) = (&mut *r.enc, &mut *r.timer);
        let key = emitter_key(scene, state, s.emitters.two_sided);
        if key != self.key {
            self.emitters = Emitters::collect_sides(scene, state, s.emitters.two_sided);
            self.key = key;
        }
        self.maps_kept = false;
        self.stats = EmitterStats {
            triangles: self.emitters.triangles.len(),
            power: self.emitters.luminance_power(),
            area: self.emitters.area,
            ..Default::default()
        };
        if self.emitters.is_empty() {
            return None;
        }
        let n = Self::count(ctx, s).min(self.capacity);
        let vpls: Vec<GpuVpl> = self.emitters.vpls(n, 0).iter().map(gpu_vpl).collect();
        let n = vpls.len() as u32;
        ctx.queue.upload(&self.list, 0, bytemuck::cast_slice(&vpls));
        self.stats.vpls = n;
        let radius = radius.max(1e-3);
        let eye_offset = s.ism.eye_offset * radius;
        let maps_key = crate::fingerprint::Fingerprint::new()
            .pod(&self.key)
            .draws(&state.draws)
            .debug(s)
            .u64s(&[n as u64, radius.to_bits() as u64])
            .finish();
        self.maps_kept = !self.maps.needs_run(maps_key, crate::fingerprint::Space::Light);
        if !self.maps_kept {
            self.splatted = false;
        }
        let keep = self.maps_kept;
        let visibility = match s.emitters.visibility {
            EmitterVisibility::Imperfect => {
                if !keep {
                    self.splat(ctx, &mut Recorder { enc, timer }, gpu_scene, s, n, radius);
                }
                let l = self.ism.layout_info;
                GatherVisibility::Ism {
                    atlas: self.ism.shading_view(),
                    cols: l.cols,
                    size: l.size,
                    eye_offset,
                    bias: s.ism.depth_bias,
                    normal_offset: s.ism.normal_offset,
                }
            }
            EmitterVisibility::Exact => {
                // The first bounce's shadow test reads ISMs.
                if s.pipeline.uses_knecht_vpls() && !keep {
                    self.splat(ctx, &mut Recorder { enc, timer }, gpu_scene, s, n, radius);
                }
                let exact = self.exact.as_ref()?;
                let clip = crate::passes::stages::vpl_clip(radius, 0.0);
                let list = &self.list;
                if !keep {
                    timer.scope(ctx, enc, "emitters.shadow", |e, slot| {
                        exact.run(PassRec { ctx, enc: e, slot }, gpu_scene, state, list, n, VisibilityParams { clip })
                    });
                }
                let l = exact.layout_info;
                GatherVisibility::Exact {
                    atlas: exact.atlas_view.clone(),
                    cols: l.cols,
                    size: l.size,
                    clip: clip.truncate(),
                }
            }
            EmitterVisibility::None => GatherVisibility::None,
        };
        Some(EmitterLight {
            list: self.list.clone(),
            count: n,
            min_distance: s.emitters.min_distance * self.emitters.spacing(n),
            visibility,
        })
    }

    /// Splats the point cloud into the ISMs of the `n` emitter VPLs and pulls-pushes them.
    fn splat(
        &mut self,
        ctx: &GpuContext,
        r: &mut Recorder,
        gpu_scene: &GpuScene,
        s: &LabSettings,
        n: u32,
        radius: f32,
    ) {
        let (enc, timer) = (&mut *r.enc, &mut *r.timer);
        let eye_offset = s.ism.eye_offset * radius;
        let extent = 2.0 * radius;
        let frame = IsmFrame { vpls: n, bounces: 1, eye_offset, extent };
        let job = self.ism.begin(ctx, &gpu_scene.instances, &self.list, &s.ism, frame);
        let ism = &self.ism;
        timer.scope(ctx, enc, "emitters.ism.splat", |e, slot| ism.splat(e, slot, &job, 0));
        timer.scope(ctx, enc, "emitters.ism.pull_push", |e, slot| ism.finish(ctx, e, slot, &job, &s.ism, extent));
        self.splatted = true;
    }
}

impl FirstBounceSource for EmitterPass {
    fn share(&self) -> Option<(u32, f32)> {
        (self.stats.vpls > 0).then_some((self.stats.vpls, self.stats.power))
    }

    /// Stage 3's share of the emitters: `k` VPLs of the first bounce off the surfaces the
    /// emitters light, written to slots `first` … `first + k − 1` of `dest` (see the module
    /// doc). `k` is at most this frame's emitter VPL count; returns how many were written.
    fn bounce_into(
        &mut self,
        f: &FrameInputs,
        enc: &mut wgpu::CommandEncoder,
        timer: &mut GpuTimer,
        (k, budget): (u32, u32),
        (dest, first): (&wgpu::Buffer, u32),
    ) -> u32 {
        let (ctx, gpu_scene, s, radius) = (f.ctx, f.gpu_scene, f.settings, f.vpl_radius());
        let k = k.min(self.stats.vpls).min(self.bounce_capacity);
        self.stats.bounce_budget = budget;
        if k == 0 {
            return 0;
        }
        let sources: Vec<GpuVpl> = self.emitters.vpls(k, 0).iter().map(gpu_vpl).collect();
        let k = sources.len() as u32;
        ctx.queue.upload(&self.bounce_list, 0, bytemuck::cast_slice(&sources));
        // The shadow test reads the emitter VPLs' ISMs when they were splatted this frame.
        let test = self.splatted.then_some(s.ism.bounce_test);
        let frame = BounceFrame {
            vpls: k,
            // Always ∝ contribution: the thesis' strongest sample is the nearest one, and from an
            // emitter under the ceiling that put every VPL on the top of the tallest object
            // (measured on the real Cornell box).
            selection: crate::passes::knecht::vpl_bounce::BounceSelection::Proportional,
            visibility: test,
            eye_offset: s.ism.eye_offset * radius,
            depth_bias: s.ism.depth_bias,
            normal_offset: s.ism.normal_offset,
            min_distance: s.vpl.min_distance_m,
            seed: 0,
        };
        let group = self.bounce.begin(ctx, &self.ism, &gpu_scene.instances, &self.bounce_list, 2, frame);
        let bounce = &self.bounce;
        timer.scope(ctx, enc, "emitters.bounce", |e, slot| bounce.run(e, slot, &group, 1, k));
        let size = std::mem::size_of::<GpuVpl>() as u64;
        enc.counted_copy_buffer(&self.bounce_list, k as u64 * size, dest, first as u64 * size, k as u64 * size);
        self.stats.bounce_share = k;
        k
    }
}

/// What the emitters of a frame depend on: the sides setting, and for every draw of an
/// emissive material its mesh, primitive, world matrix, emission and emissive texture.
fn emitter_key(scene: &Scene, state: &SceneState, two_sided: bool) -> Vec<f32> {
    let mut key = vec![two_sided as u32 as f32];
    for d in &state.draws {
        let material = scene.meshes.get(d.mesh).and_then(|m| m.primitives.get(d.primitive)).map(|p| p.material);
        let Some(m) = material.and_then(|i| scene.materials.get(i)) else { continue };
        if m.emissive.max_element() <= 0.0 {
            continue;
        }
        key.extend([d.mesh as f32, d.primitive as f32, m.emissive_texture.map_or(-1.0, |t| t as f32)]);
        key.extend(m.emissive.to_array());
        key.extend(d.world.to_cols_array());
    }
    key
}
