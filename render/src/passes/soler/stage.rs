//! Stages 5–6 with Soler et al.'s choices (004 §4, Fig. 4): the mip levels by voting, the
//! ring gather on each gathered level, and the joint bilateral upsampling that combines them
//! into `soler.indirect`; with temporal filtering (Eq. 6) the result is `soler.temporal`.

use super::bounces::SolerBounces;
use super::gather::{GatherParams, LevelInputs, SolerGather};
use super::hcb_gather::SolerHcbGather;
use super::pyramid::{SolerPyramid, sizes};
use super::temporal::SolerTemporal;
use super::upsample::{SolerUpsample, Step};
use super::voxels::{SolerVoxels, VoxelParams};
use super::{FormFactor, SolerSettings};
use crate::buffers::BufferRegistry;
use crate::gpu::GpuContext;
use crate::passes::stages::FrameInputs;
use crate::timing::GpuTimer;
use crate::timing::PassRec;

pub struct SolerStage {
    pub pyramid: SolerPyramid,
    pub gather: SolerGather,
    pub upsample: SolerUpsample,
    pub voxels: SolerVoxels,
    /// Multi-bounce: every bounce's light and their sum.
    pub bounces: SolerBounces,
    /// The gather at the HCB's samples (the mix with Nguyen et al.).
    pub hcb_gather: SolerHcbGather,
    /// Eq. 6's temporal filtering, when stage 7 filters this stage's light
    /// (`PipelineSettings::soler_temporal`).
    pub temporal: Option<SolerTemporal>,
    /// The scene's meshes that are not closed, with their open edges (solid voxelization's
    /// visibility is wrong behind them; `voxels::open_meshes`).
    pub open_meshes: Vec<(String, usize)>,
    /// The replay of a pinned pixel (issue #42), bounce by bounce (created when one is).
    pub explain: Option<super::explain::SolerExplainPass>,
}

/// Level sizes 0 (the G-buffer) … top.
fn all_sizes(width: u32, height: u32, top: u32) -> Vec<(u32, u32)> {
    let mut v = vec![(width.max(1), height.max(1))];
    v.extend(sizes(width, height, top));
    v
}

impl SolerStage {
    /// The passes the explain replay reads.
    fn parts(&self) -> super::explain::StageParts<'_> {
        super::explain::StageParts {
            pyramid: &self.pyramid,
            gather: &self.gather,
            upsample: &self.upsample,
            temporal: self.temporal.as_ref(),
        }
    }

    pub fn new(ctx: &GpuContext, s: &SolerSettings, width: u32, height: u32, temporal: bool) -> Self {
        let top = s.gathered_levels().end - 1;
        let mut stage = Self {
            pyramid: SolerPyramid::new(ctx, width, height, top),
            gather: SolerGather::new(ctx),
            upsample: SolerUpsample::new(ctx, &all_sizes(width, height, top)[..top as usize]),
            voxels: SolerVoxels::new(ctx),
            bounces: SolerBounces::new(ctx),
            hcb_gather: SolerHcbGather::new(ctx),
            temporal: None,
            open_meshes: Vec::new(),
            explain: None,
        };
        stage.ensure(ctx, s, width, height, temporal);
        stage
    }

    /// Resizes for the settings and the G-buffer (`temporal`: whether Eq. 6 filters the
    /// result); true when textures were created, replaced or dropped.
    pub fn ensure(&mut self, ctx: &GpuContext, s: &SolerSettings, width: u32, height: u32, temporal: bool) -> bool {
        let top = s.gathered_levels().end - 1;
        let all = all_sizes(width, height, top);
        let gathered: Vec<(u32, (u32, u32))> = s.gathered_levels().map(|k| (k, all[k as usize])).collect();
        let a = self.pyramid.ensure(ctx, width, height, top);
        let b = self.gather.ensure(ctx, &gathered);
        let c = self.upsample.ensure(ctx, &all[..top as usize], all[0], s.glossy_reflection);
        // The voxel grids: from the screen's (004 §4) or the first gathered level's, up.
        let from = match s.voxel_resolution {
            super::VoxelResolution::Screen => 0,
            super::VoxelResolution::FirstLevel => s.gathered_levels().start,
        };
        let grid_levels: Vec<(u32, (u32, u32))> = (from..=top).map(|k| (k, all[k as usize])).collect();
        let first = (s.gathered_levels().start - from) as usize;
        let d = self.voxels.ensure(ctx, &grid_levels, first, s.voxel_words(), s.visibility)
            | self.bounces.ensure(ctx, s.bounces, all[0], s.glossy_reflection);
        let e = match (&mut self.temporal, temporal) {
            (Some(t), true) => t.ensure(ctx, all[0]),
            (None, true) => {
                self.temporal = Some(SolerTemporal::new(ctx, all[0]));
                true
            }
            (t, false) => t.take().is_some(),
        };
        a | b | c | d | e
    }

    pub fn register(&self, reg: &mut BufferRegistry) {
        self.pyramid.register(reg);
        self.gather.register(reg);
        self.upsample.register(reg);
        self.voxels.register(reg);
        self.bounces.register(reg);
        if let Some(t) = &self.temporal {
            t.register(reg);
        }
    }

    /// The glossy reflection at G-buffer resolution (`soler.specular.accum.0`, or the
    /// full-resolution level's own when it is the only one), None without it.
    pub fn specular_light(&self) -> Option<&wgpu::Texture> {
        match self.upsample.spec_accum.first() {
            Some(t) => Some(t),
            None if self.upsample.accum.is_empty() => self.gather.specular.first(),
            None => None,
        }
    }

    /// The glossy light added into `soler.indirect` (every bounce's with several), None
    /// without the glossy reflection: what Eq. 6's irradiance blend leaves out.
    pub fn indirect_specular(&self, s: &SolerSettings) -> Option<&wgpu::Texture> {
        match (s.glossy_reflection, self.bounces.light.is_empty()) {
            (false, _) => None,
            (true, true) => self.specular_light(),
            (true, false) => self.bounces.specular_sum.as_ref(),
        }
    }

    /// Forgets the temporal filter's history.
    pub fn reset(&mut self) {
        if let Some(t) = &mut self.temporal {
            t.reset();
        }
    }

    /// The bounces this frame gathers, 0-based (all, or one in turn when alternating).
    pub fn bounces_of_frame(s: &SolerSettings, frame: u32) -> Vec<u32> {
        let n = s.bounces.clamp(1, super::gather::MAX_BOUNCES as u32);
        if s.alternate_bounces && n > 1 { vec![frame % n] } else { (0..n).collect() }
    }

    /// The frame's indirect light (`soler.indirect`, or `soler.temporal` when filtered).
    pub fn run(&mut self, f: &FrameInputs, enc: &mut wgpu::CommandEncoder, timer: &mut GpuTimer) -> wgpu::TextureView {
        let s = &f.settings.soler;
        let ctx = f.ctx;
        let g = f.gbuffer;
        let top = s.gathered_levels().end - 1;
        let all = all_sizes(f.gbuffer_size.0, f.gbuffer_size.1, top);
        // Visibility (004 §4): the scene voxelized from the camera, one grid per level, shared
        // by the bounces.
        let voxel_params = self.voxelize(f, enc, timer);
        let bounces = Self::bounces_of_frame(s, f.frame);
        // Per bounce gathered, the grids its levels march (none after the first bounce unless
        // `visibility_all_bounces`).
        let grids: Vec<Vec<VoxelParams>> = bounces
            .iter()
            .map(|&b| if b == 0 || s.visibility_all_bounces { voxel_params.clone() } else { Vec::new() })
            .collect();
        let base = gather_base(f);
        let levels: Vec<(u32, (u32, u32))> = s.gathered_levels().map(|k| (k, all[k as usize])).collect();
        self.gather.write_params(ctx, &levels, base, &grids);
        let bounce_views: Vec<wgpu::TextureView> =
            self.bounces.light.iter().map(|t| crate::passes::view(t, "soler.bounce")).collect();
        // A pinned pixel's replay (issue #42): after each bounce, while its light is the levels'.
        let explain = f.explain_pixel.filter(|p| p.0 < f.gbuffer_size.0 && p.1 < f.gbuffer_size.1);
        let mut replay = explain.map(|px| {
            let mut ex = self.explain.take().unwrap_or_else(|| super::explain::SolerExplainPass::new(ctx));
            let levels = super::explain::inputs(self.parts(), f, px).levels;
            let sigma = [s.upsample_sigma_depth, s.upsample_sigma_normal];
            ex.begin(ctx, &levels, sigma, super::explain::chain(f, px, &bounces, self.temporal.is_some()));
            (px, ex)
        });
        for (j, &b) in bounces.iter().enumerate() {
            // Bounce b + 1 gathers the light of bounce b (the direct light for the first).
            let radiance = if b == 0 { f.sender_radiance() } else { &bounce_views[b as usize - 1] };
            let prefix = if b == 0 { "soler".to_string() } else { format!("soler.bounce{}", b + 1) };
            self.bounce(f, &mut crate::timing::Recorder { enc, timer }, &prefix, radiance, &grids[j], (j, &all));
            if let Some((px, ex)) = &replay {
                // Each gathered level as this bounce's gather read it (its ring replayed).
                let lv = self.level_views();
                let ins = self.level_inputs(f, radiance, &lv, &grids[j], &all);
                let gathered = (&ins[..], j as u32, &self.gather.params);
                ex.bounce(ctx, enc, &super::explain::inputs(self.parts(), f, *px), b, gathered);
            }
            self.bounces.keep(enc, &self.upsample.indirect, self.specular_light(), b as usize);
        }
        if !self.bounces.light.is_empty() {
            let (bounces, out) = (&self.bounces, &self.upsample.indirect);
            timer.scope(ctx, enc, "soler.bounces", |e, slot| bounces.sum(ctx, e, slot, out));
        }
        let indirect = crate::passes::view(&self.upsample.indirect, "soler.indirect");
        let specular = self.indirect_specular(s).map(|t| crate::passes::view(t, "soler.indirect.specular"));
        let out = match &mut self.temporal {
            Some(t) => {
                let (camera, spec) = (f.camera_buffer, specular.as_ref());
                timer.pass(ctx, enc, "soler.temporal", |r| t.run(r, s, camera, (&indirect, spec), g));
                crate::passes::view(&t.filtered, "soler.temporal")
            }
            None => indirect,
        };
        if let Some((px, ex)) = replay.take() {
            // The bounces this frame did not gather (alternating bounces) are what was kept.
            let view = |t: &wgpu::Texture| crate::passes::view(t, "soler.bounce");
            let kept: Vec<(u32, wgpu::TextureView, Option<wgpu::TextureView>)> = (0..self.bounces.light.len() as u32)
                .filter(|b| !bounces.contains(b))
                .map(|b| (b, view(&self.bounces.light[b as usize]), self.bounces.specular.get(b as usize).map(view)))
                .collect();
            ex.finish(ctx, enc, &super::explain::inputs(self.parts(), f, px), &kept);
            self.explain = Some(ex);
        }
        out
    }

    /// The voxel grids of the frame (004 §4 "Visibility"), built when visibility is on; their
    /// parameters per gathered level (empty when off).
    fn voxelize(&self, f: &FrameInputs, enc: &mut wgpu::CommandEncoder, timer: &mut GpuTimer) -> Vec<VoxelParams> {
        let s = &f.settings.soler;
        let z = super::voxels::depth_range(
            f.camera.position,
            f.camera.forward(),
            f.center,
            f.radius,
            f.camera.znear,
            s.voxel_depth_from,
            s.voxel_depth_to,
        );
        let voxel_params = self.voxels.params_of(
            z,
            s.voxel_slices.clamp(32, 128),
            s.voxel_view_slice,
            (s.voxel_slope_bias, s.voxel_slope_cap),
        );
        if !voxel_params.is_empty() {
            timer.scope(f.ctx, enc, "soler.voxels", |e, slot| {
                let (cam, scene, state) = (f.camera_buffer, f.gpu_scene, f.state);
                self.voxels.run(PassRec { ctx: f.ctx, enc: e, slot }, cam, scene, state, &voxel_params, f.gbuffer_size)
            });
        }
        // The gather marches the gathered levels' grids only.
        voxel_params.get(self.voxels.first_gathered..).unwrap_or_default().to_vec()
    }

    /// GI Lab's mix with Nguyen et al. (`shading_points = HcbSamples`): the pyramid of the
    /// direct light and the ring gather of every level at each sample of the HCB's `list`
    /// (`hcb_gather`), which also writes the HCB's indirect arguments `args` for the splat.
    pub fn gather_at_samples(
        &self,
        f: &FrameInputs,
        enc: &mut wgpu::CommandEncoder,
        timer: &mut GpuTimer,
        hcb: (&wgpu::Buffer, &wgpu::Buffer, &wgpu::Buffer),
    ) {
        let s = &f.settings.soler;
        let ctx = f.ctx;
        let top = s.gathered_levels().end - 1;
        let all = all_sizes(f.gbuffer_size.0, f.gbuffer_size.1, top);
        let voxel_params = self.voxelize(f, enc, timer);
        let levels: Vec<(u32, (u32, u32))> = s.gathered_levels().map(|k| (k, all[k as usize])).collect();
        self.gather.write_params(ctx, &levels, gather_base(f), std::slice::from_ref(&voxel_params));
        self.vote(f, enc, timer, "soler.pyramid", f.sender_radiance());
        let lv = self.level_views();
        let inputs = self.level_inputs(f, f.sender_radiance(), &lv, &voxel_params, &all);
        let params = &self.gather.params;
        timer.pass(ctx, enc, "soler.hcb_gather", |r| self.hcb_gather.run(r, params, &inputs, hcb));
    }

    /// Stage 5: the mip levels of the G-buffer and of `radiance` by voting (Eq. 5), timed as
    /// `scope`.
    fn vote(
        &self,
        f: &FrameInputs,
        enc: &mut wgpu::CommandEncoder,
        timer: &mut GpuTimer,
        scope: &str,
        radiance: &wgpu::TextureView,
    ) {
        if self.pyramid.levels.is_empty() {
            return;
        }
        let (s, g) = (&f.settings.soler, f.gbuffer);
        let consistent = if s.vote_consistent { 1.0 } else { 0.0 };
        let sigma = [s.vote_sigma_pixel, s.vote_sigma_normal, s.vote_sigma_depth, consistent];
        let eye = f.camera.position;
        let power = [eye.x, eye.y, eye.z, if s.vote_power { s.min_cos_beta } else { -1.0 }];
        timer.scope(f.ctx, enc, scope, |e, slot| {
            self.pyramid.run(
                PassRec { ctx: f.ctx, enc: e, slot },
                (sigma, power),
                &g.position,
                &g.normal,
                radiance,
                &g.material,
            )
        });
    }

    /// Views of pyramid levels 1 … top: position, normal, radiance, material.
    fn level_views(&self) -> Vec<[wgpu::TextureView; 4]> {
        let view = |t: &wgpu::Texture| crate::passes::view(t, "soler.level.view");
        self.pyramid
            .levels
            .iter()
            .map(|l| [view(&l.position), view(&l.normal), view(&l.radiance), view(&l.material)])
            .collect()
    }

    /// The gathered levels' inputs: level 0 is the G-buffer with `radiance`, level k ≥ 1 the
    /// pyramid's (`lv`, from [`Self::level_views`]); `grids` the voxel grids they march.
    fn level_inputs<'a>(
        &'a self,
        f: &'a FrameInputs,
        radiance: &'a wgpu::TextureView,
        lv: &'a [[wgpu::TextureView; 4]],
        grids: &[VoxelParams],
        all: &[(u32, u32)],
    ) -> Vec<LevelInputs<'a>> {
        let g = f.gbuffer;
        f.settings
            .soler
            .gathered_levels()
            .enumerate()
            .map(|(i, k)| {
                let [position, normal, radiance, material] = match k {
                    0 => [&g.position, &g.normal, radiance, &g.material],
                    _ => {
                        let v = &lv[k as usize - 1];
                        [&v[0], &v[1], &v[2], &v[3]]
                    }
                };
                let (grid, voxels) = match (self.voxels.gathered().get(i), grids.get(i)) {
                    (Some(g), Some(p)) => (&g.buffer, *p),
                    _ => (&self.voxels.empty, VoxelParams::default()),
                };
                LevelInputs { level: k, position, normal, radiance, material, size: all[k as usize], grid, voxels }
            })
            .collect()
    }

    /// One bounce: the pyramid of `radiance`, the gather of every level (timing scopes
    /// `{prefix}.gather.k`) and the upsampling into `soler.indirect`. `slot.0` is the bounce's
    /// index among the frame's gathers (its parameter slots), `slot.1` the level sizes.
    fn bounce(
        &self,
        f: &FrameInputs,
        r: &mut crate::timing::Recorder,
        prefix: &str,
        radiance: &wgpu::TextureView,
        grids: &[VoxelParams],
        (j, all): (usize, &[(u32, u32)]),
    ) {
        let (enc, timer) = (&mut *r.enc, &mut *r.timer);
        let s = &f.settings.soler;
        let ctx = f.ctx;
        let g = f.gbuffer;
        if j == 0 {
            self.vote(f, enc, timer, &format!("{prefix}.pyramid"), radiance);
        } else if !self.pyramid.levels.is_empty() {
            // 004 §5.3: the bounces share the mipmapping of the G-buffer; only their light
            // goes down the levels again, through the winners of the frame's first vote.
            timer.scope(ctx, enc, &format!("{prefix}.pyramid"), |e, slot| {
                self.pyramid.run_radiance(ctx, e, slot, (&g.position, &g.normal), radiance)
            });
        }
        let view = |t: &wgpu::Texture| crate::passes::view(t, "soler.level.view");
        let lv = self.level_views();
        let level_views = |k: u32| -> [&wgpu::TextureView; 4] {
            if k == 0 {
                [&g.position, &g.normal, radiance, &g.material]
            } else {
                let v = &lv[k as usize - 1];
                [&v[0], &v[1], &v[2], &v[3]]
            }
        };
        let inputs = self.level_inputs(f, radiance, &lv, grids, all);
        let n = inputs.len();
        for (i, l) in inputs.iter().enumerate() {
            timer.scope(ctx, enc, &format!("{prefix}.gather.{}", l.level), |e, slot| {
                self.gather.run_level(PassRec { ctx, enc: e, slot }, l, i, j * n + i)
            });
        }
        let top = s.gathered_levels().end - 1;
        let light: Vec<wgpu::TextureView> = self.gather.light.iter().map(|(_, t)| view(t)).collect();
        let accum: Vec<wgpu::TextureView> = self.upsample.accum.iter().map(view).collect();
        let spec: Vec<wgpu::TextureView> = self.gather.specular.iter().map(view).collect();
        let spec_accum: Vec<wgpu::TextureView> = self.upsample.spec_accum.iter().map(view).collect();
        let start = s.gathered_levels().start;
        let lvs: Vec<[&wgpu::TextureView; 4]> = (0..=top).map(level_views).collect();
        fn last<'v>(top: u32, own: &'v [wgpu::TextureView], acc: &'v [wgpu::TextureView]) -> &'v wgpu::TextureView {
            if top == 0 { &own[own.len() - 1] } else { &acc[0] }
        }
        let steps = chain(start, &lvs, &light, &accum);
        let glossy = s.glossy_reflection;
        let spec_steps = if glossy { chain(start, &lvs, &spec, &spec_accum) } else { Vec::new() };
        let sigma = [s.upsample_sigma_depth, s.upsample_sigma_normal];
        let add_specular = self.bounces.light.is_empty();
        timer.scope(ctx, enc, &format!("{prefix}.upsample"), |e, slot| {
            let spec_chain = glossy.then(|| (&spec_steps[..], last(top, &spec, &spec_accum)));
            self.upsample.run(
                PassRec { ctx, enc: e, slot },
                sigma,
                &steps,
                last(top, &light, &accum),
                &g.albedo,
                (spec_chain, add_specular),
            )
        });
    }
}

/// The upsampling steps of one chain, coarse to fine: `lvs` the views of levels 0 … top,
/// `own` the gathered levels' light (from `start`), `acc` the chain's accumulators (the top
/// level's accumulated light is its own).
fn chain<'v>(
    start: u32,
    lvs: &[[&'v wgpu::TextureView; 4]],
    own: &'v [wgpu::TextureView],
    acc: &'v [wgpu::TextureView],
) -> Vec<Step<'v>> {
    let top = lvs.len() as u32 - 1;
    (0..top)
        .rev()
        .map(|k| {
            let [fp, fnorm, _, _] = lvs[k as usize];
            let [cp, cn, _, _] = lvs[k as usize + 1];
            let coarse = if k + 1 == top { &own[own.len() - 1] } else { &acc[k as usize + 1] };
            Step {
                fine: [fp, fnorm],
                fine_light: (k >= start).then(|| &own[(k - start) as usize]),
                coarse: [cp, cn, coarse],
            }
        })
        .collect()
}

/// The gather's parameters shared by every level and bounce of the frame (level, size and
/// grid are set per slot by `SolerGather::write_params`).
fn gather_base(f: &FrameInputs) -> GatherParams {
    let s = &f.settings.soler;
    let aspect = f.gbuffer_size.0 as f32 / f.gbuffer_size.1.max(1) as f32;
    let tan_v = (0.5 * f.camera.yfov).tan();
    GatherParams {
        counts: [s.samples, 0, 0, f.frame],
        shape: [
            s.radius_px,
            (s.form_factor == FormFactor::PointToDisc) as u32 as f32,
            s.min_cos_beta,
            f.near_field_cut() * f.near_field_cut(),
        ],
        eye: f.camera.position.extend(1.0).to_array(),
        screen: [aspect * tan_v, tan_v, 0.0, 0.0],
        voxels: VoxelParams::default(),
        march: [s.march_bias_px, s.march_depth_bias, 0.0, 0.0],
        gloss: [
            s.glossy_alpha,
            s.glossy_sharpness,
            s.glossy_min_power,
            (s.glossy_reflection as u32 + 2 * (s.glossy_reflection && s.glossy_sampling) as u32) as f32,
        ],
        right: f.camera.right().extend(0.0).to_array(),
        up: f.camera.right().cross(f.camera.forward()).extend(0.0).to_array(),
        forward: f.camera.forward().extend(0.0).to_array(),
    }
}
