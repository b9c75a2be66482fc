//! Stages 5–7 with the shading points "HCB samples" (Nguyen et al. 000): the HCB build
//! (§3), the VPL gather at the samples (§4.1), coherence splatting and Eq. 11 (§4.2–4.3),
//! and — as stage 7's choice "HCB sample cache" — the cache of §5 (Fig. 5), whose work
//! surrounds the build: last frame's samples are validated, due ones re-gathered and splatted
//! before the build adds samples only where texels stay incomplete.

use crate::gpu::GpuContext;
use crate::lab_settings::LabSettings;
use crate::passes::hcb::cache::{CacheCounts, CacheFrame, HcbCachePass, cache_views};
use crate::passes::hcb::{GatherSet, GpuHcbSample, HcbFrame, HcbGatherPass, HcbPass, HcbSettings, HcbSplatPass};
use crate::passes::stages::{FrameInputs, Visibility, VplSet};
use crate::settings::pipeline::Temporal;
use crate::timing::GpuTimer;
use crate::timing::PassRec;

/// The HCB's passes: levels, masks and samples; gathering; splatting; the cache.
pub struct HcbStage {
    pub build: HcbPass,
    pub gather: HcbGatherPass,
    pub splat: HcbSplatPass,
    /// The sample cache (§5), created when it is stage 7's choice.
    pub cache: Option<HcbCachePass>,
    /// The settings the cached samples were identified with; the cache empties when they
    /// change.
    cached_with: Option<HcbSettings>,
}

/// Sample statistics of the HCB (see `Renderer::hcb_stats`).
#[derive(Clone, Debug, PartialEq)]
pub struct HcbStats {
    /// Every sample's G-buffer pixel (x, y) and level.
    pub samples: Vec<[u32; 3]>,
    pub samples_per_level: Vec<u32>,
    pub texels_per_level: Vec<u32>,
    /// Covered pixels that no sample's splat reached.
    pub uncovered: u32,
    /// The first `splat::UNCOVERED_LIST` of them, (x, y), in no particular order.
    pub uncovered_pixels: Vec<[u32; 2]>,
    /// The cache's counts of the frame (§5), None without the cache.
    pub cache: Option<CacheCounts>,
    /// The sample list itself (cached samples first, then the new ones).
    pub list: Vec<GpuHcbSample>,
    /// The d_max in use (scene units; the setting or the scene-relative default).
    pub d_max: f32,
}

impl HcbStats {
    pub fn samples(&self) -> u32 {
        self.samples_per_level.iter().sum()
    }

    /// Table 1 of Nguyen et al. in one line: the count, its share of `pixels`, per level
    /// (and the cache's counts).
    pub fn summary(&self, pixels: u32) -> String {
        let mut line = format!(
            "{} HCB samples ({:.2} % of the pixels), per level {:?}; {} covered pixels no sample reached",
            self.samples(),
            100.0 * self.samples() as f64 / pixels.max(1) as f64,
            self.samples_per_level,
            self.uncovered
        );
        if let Some(c) = &self.cache {
            line += &format!("; cache: {}", c.to_string().split_whitespace().collect::<Vec<_>>().join(" "));
        }
        line
    }
}

impl HcbStage {
    pub fn new(ctx: &GpuContext, s: &LabSettings, width: u32, height: u32) -> Self {
        Self {
            build: HcbPass::new(ctx, width, height, s.hcb.levels),
            gather: HcbGatherPass::new(ctx),
            splat: HcbSplatPass::new(ctx, width, height),
            cache: None,
            cached_with: None,
        }
    }

    /// Resizes for the settings and creates or drops the cache; true when textures were
    /// replaced.
    pub fn ensure(&mut self, ctx: &GpuContext, s: &LabSettings, width: u32, height: u32) -> bool {
        let resized = self.build.ensure(ctx, width, height, s.hcb.levels) | self.splat.ensure(ctx, width, height);
        let mut fresh = resized;
        if s.pipeline.temporal == Temporal::HcbSampleCache {
            let created = self.cache.is_none();
            let cache = self.cache.get_or_insert_with(|| HcbCachePass::new(ctx, width, height));
            fresh |= cache.ensure(ctx, width, height) | created;
            if resized || self.cached_with.as_ref() != Some(&s.hcb) {
                // The list and the cache are swapped each frame: both start empty.
                self.cached_with = None;
            }
        } else if self.cache.take().is_some() {
            fresh = true;
        }
        fresh
    }

    /// Registers the latest splat sums (the ping-pong pair's; after each frame's splats).
    pub fn register_sums(&self, reg: &mut crate::buffers::BufferRegistry) {
        self.splat.register_sums(reg);
    }

    pub fn register(&self, reg: &mut crate::buffers::BufferRegistry) {
        self.build.register(reg);
        self.splat.register(reg);
        if let Some(c) = &self.cache {
            c.register(reg);
        }
    }

    /// The frame's constants of the HCB's passes (the splat's thresholds among them).
    pub(crate) fn frame(f: &FrameInputs) -> HcbFrame {
        let s = &f.settings.hcb;
        HcbFrame {
            thresholds: s.thresholds(f.scale),
            eye: f.camera.position,
            pixel_scale: 2.0 * (f.camera.yfov * 0.5).tan() / f.height.max(1) as f32,
            pattern: crate::maths::recompute_pattern(s.recompute_period),
            incomplete_weight: s.incomplete_weight,
            footprint_min_cos: s.footprint_min_cos,
            receiver: s.receiver,
        }
    }

    fn run_gather(
        &self,
        f: &FrameInputs,
        enc: &mut wgpu::CommandEncoder,
        timer: &mut GpuTimer,
        scope: &str,
        (vpls, vis): (&VplSet, &Visibility),
        set: GatherSet<'_>,
    ) {
        let ctx = f.ctx;
        timer.scope(ctx, enc, scope, |e, slot| {
            self.gather.run(PassRec { ctx, enc: e, slot }, &self.build, (vpls, vis), set)
        });
    }

    /// Stage 5: the samples of this frame. With the cache (stage 7's choice, §5, Fig. 5) the
    /// cached samples are validated, the due ones re-gathered with `light` and splatted
    /// first, and the build adds samples only where texels stay incomplete.
    pub fn select(
        &mut self,
        f: &FrameInputs,
        enc: &mut wgpu::CommandEncoder,
        timer: &mut GpuTimer,
        light: (&VplSet, &Visibility),
    ) {
        if self.update_cache(f, enc, timer)
            && let Some(queue) = self.recompute_queue()
        {
            self.run_gather(f, enc, timer, "hcb.cache.recompute", light, GatherSet::Recompute(queue));
        }
        self.build_after_cache(f, enc, timer);
    }

    /// §5.1's first half (Fig. 5): last frame's samples become the cache (emptied when the
    /// HCB's settings changed), validated in this view and appended to the emptied list.
    /// The caller lights the cached samples due for a new gather (§5.3,
    /// [`Self::recompute_queue`]) before [`Self::build_after_cache`]. False without the cache.
    pub fn update_cache(&mut self, f: &FrameInputs, enc: &mut wgpu::CommandEncoder, timer: &mut GpuTimer) -> bool {
        let Some(c) = self.cache.as_mut() else {
            return false;
        };
        c.swap(&mut self.build);
        if self.cached_with.as_ref() != Some(&f.settings.hcb) {
            c.reset(enc);
            self.cached_with = Some(f.settings.hcb.clone());
        }
        let Some(c) = self.cache.as_ref() else {
            return false;
        };
        let s = &f.settings.hcb;
        let cf = CacheFrame {
            max_distance: s.cache_distance_m,
            max_normal_deg: s.cache_normal_deg,
            quad_px: s.surplus_quad_px,
            period: s.recompute_period,
        };
        let (ctx, g, camera, build) = (f.ctx, f.gbuffer, f.camera_buffer, &self.build);
        timer.scope(ctx, enc, "hcb.cache.update", |e, slot| {
            c.update(PassRec { ctx, enc: e, slot }, camera, (&g.position, &g.normal), build, cf)
        });
        true
    }

    /// The list slots of the cached samples due for a new gather this frame (§5.3; their
    /// count is word 2 of the sample counter); None without the cache.
    pub fn recompute_queue(&self) -> Option<&wgpu::Buffer> {
        self.cache.as_ref().map(|c| &c.queue)
    }

    /// §5.1's second half and §5.2: the cached samples (their due ones lit again) splatted,
    /// and the build adding samples where their weights stay incomplete; without the cache,
    /// the build of every sample.
    pub fn build_after_cache(&self, f: &FrameInputs, enc: &mut wgpu::CommandEncoder, timer: &mut GpuTimer) {
        let ctx = f.ctx;
        let hf = Self::frame(f);
        let g = f.gbuffer;
        let Some(c) = &self.cache else {
            let build = &self.build;
            timer.pass(ctx, enc, "hcb.build", |r| build.run(r, &g.position, &g.normal, hf, None));
            return;
        };
        let s = &f.settings.hcb;
        let (camera, g3) = (f.camera_buffer, (&g.position, &g.normal, &g.albedo, &g.material));
        let samples = (&self.build.list, &self.build.counter);
        let (splat, args) = (&self.splat, &self.gather.args);
        timer.scope(ctx, enc, "hcb.cache.splat", |e, slot| {
            splat.splat(PassRec { ctx, enc: e, slot }, camera, g3, (samples, (args, 0)), (false, true), (hf, s.splat))
        });
        let weight_sum = self.splat.weight_sum_view();
        let views = c.views();
        let build = &self.build;
        timer.scope(ctx, enc, "hcb.build", |e, slot| {
            let io = cache_views(&weight_sum, &views);
            build.run(PassRec { ctx, enc: e, slot }, &g.position, &g.normal, hf, Some(io))
        });
    }

    /// Stage 6: the VPL gather at the (new) samples and the coherence-weighted splatting with
    /// Eq. 11's normalisation; returns `hcb.indirect`.
    pub fn gather_and_splat(
        &self,
        f: &FrameInputs,
        enc: &mut wgpu::CommandEncoder,
        timer: &mut GpuTimer,
        light: (&VplSet, &Visibility),
    ) -> wgpu::TextureView {
        let (ctx, g) = (f.ctx, f.gbuffer);
        let hf = Self::frame(f);
        let (camera, g3) = (f.camera_buffer, (&g.position, &g.normal, &g.albedo, &g.material));
        let samples = (&self.build.list, &self.build.counter);
        let set = if self.cache.is_some() { GatherSet::New } else { GatherSet::All };
        self.run_gather(f, enc, timer, "hcb.gather", light, set);
        let (splat, args, method) = (&self.splat, &self.gather.args, f.settings.hcb.splat);
        timer.scope(ctx, enc, "hcb.splat", |e, slot| {
            if self.cache.is_some() {
                splat.splat(
                    PassRec { ctx, enc: e, slot },
                    camera,
                    g3,
                    (samples, (args, 32)),
                    (true, false),
                    (hf, method),
                );
                splat.normalize(ctx, e, slot, g3);
            } else {
                splat.run(PassRec { ctx, enc: e, slot }, camera, g3, samples, args, (hf, method));
            }
        });
        crate::passes::view(&self.splat.indirect, "hcb.indirect")
    }

    /// Stage 5 without VPLs (the mix with Soler's screen-space gather, which refuses the
    /// cache): the levels, masks and samples of this frame.
    pub fn build_only(&self, f: &FrameInputs, enc: &mut wgpu::CommandEncoder, timer: &mut GpuTimer) {
        let (ctx, g, hf) = (f.ctx, f.gbuffer, Self::frame(f));
        let build = &self.build;
        timer.pass(ctx, enc, "hcb.build", |r| build.run(r, &g.position, &g.normal, hf, None));
    }

    /// The buffers another gather fills at the samples: the list, its counter and the
    /// indirect arguments of the splat.
    pub fn sample_buffers(&self) -> (&wgpu::Buffer, &wgpu::Buffer, &wgpu::Buffer) {
        (&self.build.list, &self.build.counter, &self.gather.args)
    }

    /// Stage 6's coherence splatting (§4.2–4.3) of samples another gather lit; returns
    /// `hcb.indirect`.
    pub fn splat_only(
        &self,
        f: &FrameInputs,
        enc: &mut wgpu::CommandEncoder,
        timer: &mut GpuTimer,
    ) -> wgpu::TextureView {
        let (ctx, g, hf) = (f.ctx, f.gbuffer, Self::frame(f));
        let (camera, g3) = (f.camera_buffer, (&g.position, &g.normal, &g.albedo, &g.material));
        let samples = (&self.build.list, &self.build.counter);
        let (splat, args, method) = (&self.splat, &self.gather.args, f.settings.hcb.splat);
        timer.pass(ctx, enc, "hcb.splat", |r| splat.run(r, camera, g3, samples, args, (hf, method)));
        crate::passes::view(&self.splat.indirect, "hcb.indirect")
    }

    /// The statistics of the last frame (Table 1; blocks until the data is on the CPU).
    pub fn stats(&self, ctx: &GpuContext, d_max: f32) -> Option<HcbStats> {
        use crate::buffers::read_storage;
        let parts: Vec<Vec<u8>> =
            self.stats_sources().iter().map(|(b, n)| read_storage(ctx, b, *n).ok()).collect::<Option<_>>()?;
        self.stats_from(&parts, d_max)
    }

    /// The buffers (and bytes) the statistics are made of: the counters, the whole sample
    /// list and the uncovered-pixel count, for a read-back without waiting
    /// (`Renderer::hcb_stats_later`).
    pub fn stats_sources(&self) -> Vec<(wgpu::Buffer, u64)> {
        let size = std::mem::size_of::<GpuHcbSample>() as u64;
        vec![
            (self.build.counter.clone(), super::COUNTER_BYTES),
            (self.build.list.clone(), self.build.list_capacity as u64 * size),
            (self.splat.uncovered.clone(), super::splat::UNCOVERED_BYTES),
        ]
    }

    /// The statistics from the bytes of [`Self::stats_sources`].
    pub fn stats_from(&self, parts: &[Vec<u8>], d_max: f32) -> Option<HcbStats> {
        let [counter, list_bytes, uncovered] = parts else { return None };
        let count: Vec<u32> = bytemuck::pod_collect_to_vec(counter);
        let size = std::mem::size_of::<GpuHcbSample>();
        let n = (*count.first()?).min(self.build.list_capacity) as usize;
        let list: Vec<GpuHcbSample> = bytemuck::pod_collect_to_vec(list_bytes.get(..n * size)?);
        let mut per_level = vec![0u32; self.build.levels.len()];
        for smp in &list {
            if let Some(c) = per_level.get_mut(smp.level() as usize) {
                *c += 1;
            }
        }
        let uncovered: Vec<u32> = bytemuck::pod_collect_to_vec(uncovered);
        let listed = (*uncovered.first()?).min(super::splat::UNCOVERED_LIST) as usize;
        let uncovered_pixels = uncovered.get(4..4 + listed)?.iter().map(|p| [p & 0xffff, p >> 16]).collect();
        Some(HcbStats {
            samples: list
                .iter()
                .map(|s| {
                    let [x, y] = s.pixel();
                    [x, y, s.level()]
                })
                .collect(),
            samples_per_level: per_level,
            texels_per_level: self.build.levels.iter().map(|l| l.width * l.height).collect(),
            uncovered: *uncovered.first()?,
            uncovered_pixels,
            cache: self.cache.as_ref().map(|_| CacheCounts::from_words(&count)),
            list,
            d_max,
        })
    }
}
