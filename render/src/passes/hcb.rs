//! Stage 5 of the hierarchical coherence buffer (Nguyen et al., 000 §3): the HCB levels
//! (`hcb.level.k.position`: xyz + the sphere radius a^w; `hcb.level.k.normal`: xyz + the
//! group coherence n^w), the mask buffer (`hcb.mask.k`), the sample buffer (`hcb.samples`,
//! level + 1 at each sample's pixel) and the compact sample list. Shaders
//! `shaders/hcb/{base,build,samples}.wgsl`; CPU twin `cpu::hcb` (the paper's readings are
//! documented there).
//!
//! Not yet part of the frame: gathering at the samples, the coherence-weighted splatting and
//! the cache (issue #6) come next; this pass is built and tested on its own.

use bytemuck::Zeroable;
use glam::Vec4;

use super::bgl;
use crate::buffers::{BufferKind, BufferRegistry};
use crate::cpu::hcb::Thresholds;
use crate::gpu::GpuContext;
use crate::timing::Slot;
use crate::{settings_enum, settings_group};

settings_group! {
    /// The hierarchical coherence buffer (stages 5–6 of the HCB technique; Nguyen et al. 000
    /// §3–4): where indirect light is gathered and how it is splatted. The paper gives no
    /// values; the defaults were chosen on the default scene (see presets/nguyen-hcb.ron).
    pub struct HcbSettings: "hcb" {
        /// Largest normal divergence inside a coherent group (Eq. 2, combined by Eq. 6–7).
        theta_max_deg: f32 = 20.0,
        unit "°", symbol "θ_max", range 1.0..=89.0, cost "larger: fewer samples and blurrier light across bends", history false;
        /// Pose limit under backward lighting (Eq. 3): |âb·n_a| ≤ cos γ_max.
        gamma_max_deg: f32 = 70.0,
        unit "°", symbol "γ_max", range 1.0..=90.0, cost "smaller: fewer samples, light leaks across steps", history false;
        /// Largest radius of a coherent group (Eq. 1 on the accumulated distance, §3.5), in
        /// scene units; 0 picks it from the scene: 0.15 × its bounding radius (0.26 on the
        /// default Cornell box, 0.91 on the hotel room).
        d_max_m: f32 = 0.0,
        unit "m", symbol "d_max", range 0.0..=100.0, cost "larger: fewer samples, coarser light", history false;
        /// HCB levels including the G-buffer's (1: every pixel is a sample, the per-pixel gather).
        levels: u32 = 7,
        unit "levels", symbol "", range 1..=12, cost "one pass per level; more levels, larger groups", history false;
        /// Cache the samples from frame to frame (§5): reuse the valid ones, add samples only
        /// where the cached ones leave texels incomplete, recompute a share per frame.
        cache: bool = false,
        unit "", symbol "", range 0..=1, cost "saves the gather at every sample that is reused", history false;
        /// A cached sample is invalid when the G-buffer point it lands on is farther than
        /// this (§5.1's distance threshold).
        cache_distance_m: f32 = 0.05,
        unit "m", symbol "", range 0.0001..=10.0, cost "larger: fewer samples renewed, light may stick to moved surfaces", history false;
        /// A cached sample is invalid when the G-buffer normal it lands on diverges by more
        /// than this (§5.1's normal threshold).
        cache_normal_deg: f32 = 25.0,
        unit "°", symbol "", range 1.0..=90.0, cost "larger: fewer samples renewed", history false;
        /// Side of the quad around each invalid sample inside which the valid (surplus)
        /// samples are removed too (§5.1, Fig. 6).
        surplus_quad_px: u32 = 24,
        unit "px", symbol "", range 1..=256, cost "larger: more samples renewed, fewer surplus ones kept", history false;
        /// A texel whose splatted weight Σw (Eq. 10) is below this is incomplete and gets
        /// new samples (§5.2).
        incomplete_weight: f32 = 0.1,
        unit "Σw", symbol "", range 0.0..=1.0, cost "larger: more new samples per frame", history false;
        /// Where new samples may lie (§5.2): on the incomplete texels only (Fig. 7c) or also
        /// around them (Fig. 7d).
        new_samples: NewSamples = NewSamples::AroundIncomplete,
        unit "", symbol "", range 0..=1, cost "around: a few larger samples, fewer seams", history false;
        /// Frames between two recomputations of a cached sample's light (§5.3: 4, a quarter
        /// of the samples per frame, by the randomized 4×4 index pattern of Fig. 8).
        recompute_period: u32 = 4,
        unit "frames", symbol "", range 1..=16, cost "smaller: more samples gathered per frame, light follows changes sooner", history false;
    }
}

settings_enum! {
    /// Where the caching HCB places new samples (Nguyen §5.2).
    pub enum NewSamples {
        /// Only on incomplete texels (Fig. 7c): a block keeps its centre texel's sign.
        OnIncomplete = "on incomplete texels (Fig. 7c)",
        /// Also around them (Fig. 7d): a block with any incomplete texel is incomplete.
        AroundIncomplete = "around incomplete texels (Fig. 7d)",
    }
    default AroundIncomplete
}

/// The scene-relative d_max: this fraction of the scene's bounding radius.
pub const D_MAX_PER_RADIUS: f32 = 0.15;

impl HcbSettings {
    /// d_max in scene units for a scene of bounding radius `scene_radius` (the setting, or
    /// the scene-relative default when it is 0).
    pub fn d_max(&self, scene_radius: f32) -> f32 {
        if self.d_max_m > 0.0 { self.d_max_m } else { D_MAX_PER_RADIUS * scene_radius }
    }

    pub fn thresholds(&self, scene_radius: f32) -> Thresholds {
        Thresholds {
            cos_theta_max: self.theta_max_deg.to_radians().cos(),
            cos_gamma_max: self.gamma_max_deg.to_radians().cos(),
            d_max: self.d_max(scene_radius),
            spread_incomplete: self.new_samples == NewSamples::AroundIncomplete,
        }
    }
}

/// Uniform of the HCB passes; WGSL twin: `HcbParams` in `shaders/hcb/common.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct HcbParams {
    /// cos θ_max, cos γ_max, d_max, pixel scale 2 tan(fov_y / 2) / height.
    pub thresholds: Vec4,
    /// Eye position.
    pub eye: Vec4,
    /// 1 for the top level, level index, 1 for the supplementary G-buffer of the cache
    /// (§5.2: the base gets ±1 from the splatted weight), 1 to spread the sign (Fig. 7d).
    pub level: [u32; 4],
    /// x: the incomplete weight threshold (§5.2), y: the recompute period (§5.3); z, w: 0.
    pub cache: Vec4,
    /// §5.3's 4×4 index pattern: the recompute phase of a new sample at texel (x, y) of its level
    /// is `pattern[y mod 4][x mod 4]`.
    pub pattern: [[u32; 4]; 4],
}

/// One sample of the compact list; WGSL twin: `HcbSample` in `shaders/hcb/common.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuHcbSample {
    /// World position, a^w.
    pub position: Vec4,
    /// Normal, n^w.
    pub normal: Vec4,
    /// Texel x, y at its level; bits 0–7 the level, 8–15 the recompute counter (§5.3), 16–23
    /// the cache status during its update; the G-buffer pixel x | y << 16.
    pub texel: [u32; 4],
    /// Gathered light (rgb); a: 1 once gathered, 0 until then (new, or due for recomputation).
    pub light: Vec4,
}

impl GpuHcbSample {
    pub fn level(&self) -> u32 {
        self.texel[2] & 0xff
    }

    /// §5.3's counter.
    pub fn counter(&self) -> u32 {
        (self.texel[2] >> 8) & 0xff
    }

    /// The G-buffer pixel it stands at (for a cached sample, where it was reprojected).
    pub fn pixel(&self) -> [u32; 2] {
        [self.texel[3] & 0xffff, self.texel[3] >> 16]
    }
}

const STRIDE: u64 = 256;
/// Most levels (the base and 11 above: a 4096² G-buffer reaches 2²).
pub const MAX_LEVELS: u32 = 12;

/// One level's textures.
pub struct HcbLevel {
    pub width: u32,
    pub height: u32,
    pub position: wgpu::Texture,
    pub normal: wgpu::Texture,
    /// Inside (1) or outside (0) the splats of the level above (all 0 at the top).
    pub mask: wgpu::Texture,
}

/// What the HCB of one frame is built with.
#[derive(Clone, Copy, Debug)]
pub struct HcbFrame {
    pub thresholds: Thresholds,
    pub eye: glam::Vec3,
    /// 2 tan(fov_y / 2) / height.
    pub pixel_scale: f32,
    /// §5.3's index pattern (the recompute phase of a new sample by its level texel).
    pub pattern: [[u32; 4]; 4],
    /// §5.2's incomplete weight threshold.
    pub incomplete_weight: f32,
}

impl HcbFrame {
    /// A frame with §5.3's default period and no incomplete threshold (the per-frame HCB).
    pub fn new(thresholds: Thresholds, eye: glam::Vec3, pixel_scale: f32) -> Self {
        Self { thresholds, eye, pixel_scale, pattern: crate::cpu::hcb::recompute_pattern(4), incomplete_weight: 0.0 }
    }

    fn params(&self, level: [u32; 4]) -> HcbParams {
        let t = self.thresholds;
        HcbParams {
            thresholds: Vec4::new(t.cos_theta_max, t.cos_gamma_max, t.d_max, self.pixel_scale),
            eye: self.eye.extend(1.0),
            level,
            cache: Vec4::new(self.incomplete_weight, 0.0, 0.0, 0.0),
            pattern: self.pattern,
        }
    }
}

/// The cache's textures the HCB build writes (§5.2): with them, level 0 is the supplementary
/// G-buffer (n^w = ±1 from `weight_sum`'s Σw), `incomplete` marks the incomplete texels and
/// new samples are marked in `cache` (2) and `recompute_group` (phase + 1).
pub struct CacheViews<'a> {
    pub weight_sum: &'a wgpu::TextureView,
    pub incomplete: &'a wgpu::TextureView,
    pub cache: &'a wgpu::TextureView,
    pub recompute_group: &'a wgpu::TextureView,
}

pub struct HcbPass {
    pub levels: Vec<HcbLevel>,
    /// `hcb.samples`: level + 1 at each sample's pixel, 0 elsewhere (G-buffer resolution).
    pub samples: wgpu::Texture,
    /// The number of samples (one u32).
    pub counter: wgpu::Buffer,
    /// The compact sample list ([`GpuHcbSample`]s).
    pub list: wgpu::Buffer,
    pub list_capacity: u32,
    io_layout: wgpu::BindGroupLayout,
    sample_layout: wgpu::BindGroupLayout,
    base_pipeline: wgpu::ComputePipeline,
    build_pipeline: wgpu::ComputePipeline,
    mask_pipeline: wgpu::ComputePipeline,
    clear_pipeline: wgpu::ComputePipeline,
    samples_pipeline: wgpu::ComputePipeline,
    params: wgpu::Buffer,
    dummy_storage: wgpu::Texture,
    dummy_sampled: wgpu::Texture,
    /// Stand-ins for the cache's textures without the cache (one each: two writable bindings
    /// of one texture in a dispatch would conflict).
    dummy_cache: [wgpu::Texture; 3],
    width: u32,
    height: u32,
}

/// Bytes of the sample counter: total, cached (reused), recomputed, invalid, surplus,
/// dropped (outside the view), 2 spare — see [`CacheCounts`].
pub const COUNTER_BYTES: u64 = 32;

/// Sizes of levels 0 … `levels` − 1 of a `width` × `height` G-buffer (each ⌈half⌉ of the
/// one below).
pub fn level_sizes(width: u32, height: u32, levels: u32) -> Vec<(u32, u32)> {
    let mut out = vec![(width.max(1), height.max(1))];
    for _ in 1..levels.clamp(1, MAX_LEVELS) {
        let (w, h) = *out.last().expect("level 0");
        out.push((w.div_ceil(2), h.div_ceil(2)));
    }
    out
}

impl HcbPass {
    pub fn new(ctx: &GpuContext, width: u32, height: u32, levels: u32) -> Self {
        let device = &ctx.device;
        let cs = wgpu::ShaderStages::COMPUTE;
        let rgba = wgpu::TextureFormat::Rgba32Float;
        let r32 = wgpu::TextureFormat::R32Float;
        let io_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("hcb.level.inputs"),
            entries: &[
                bgl::uniform_dynamic(0, cs),
                bgl::texture(1, cs, false),
                bgl::texture(2, cs, false),
                bgl::storage_texture(3, rgba),
                bgl::storage_texture(4, rgba),
                bgl::texture(5, cs, false),
                bgl::storage_texture(6, r32),
            ],
        });
        let sample_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("hcb.samples.inputs"),
            entries: &[
                bgl::uniform_dynamic(0, cs),
                bgl::texture(1, cs, false),
                bgl::storage_texture(2, r32),
                bgl::texture(3, cs, false),
                bgl::storage_texture(4, r32),
                bgl::storage(5, cs, false),
                bgl::texture(6, cs, false),
                bgl::storage(7, cs, false),
                bgl::storage_texture(8, r32),
                bgl::storage_texture(9, r32),
            ],
        });
        let m_base = crate::shaders::create_module(device, "hcb/base.wgsl");
        let m_build = crate::shaders::create_module(device, "hcb/build.wgsl");
        let m_samples = crate::shaders::create_module(device, "hcb/samples.wgsl");
        let pipeline = |label, m, entry, layout| super::compute_pipeline(device, label, m, entry, &[layout]);
        let base_pipeline = pipeline("hcb.base", &m_base, "cs_base", &io_layout);
        let build_pipeline = pipeline("hcb.build", &m_build, "cs_build", &io_layout);
        let mask_pipeline = pipeline("hcb.mask", &m_samples, "cs_mask", &sample_layout);
        let clear_pipeline = pipeline("hcb.samples.clear", &m_samples, "cs_clear", &sample_layout);
        let samples_pipeline = pipeline("hcb.samples", &m_samples, "cs_samples", &sample_layout);
        let params = super::uniform_buffer(device, "hcb.params", STRIDE * (2 * MAX_LEVELS as u64 + 1));
        let storage = wgpu::TextureUsages::STORAGE_BINDING;
        let dummy_storage = super::create_target(device, "hcb.dummy_mask_out", 1, 1, r32, storage);
        let dummy_sampled = super::create_target(device, "hcb.dummy_mask_in", 1, 1, r32, storage);
        let dummy_cache = ["hcb.dummy_incomplete", "hcb.dummy_cache", "hcb.dummy_recompute_group"]
            .map(|label| super::create_target(device, label, 1, 1, r32, storage));
        let (levels_v, samples, list, list_capacity) = Self::targets(device, width, height, levels);
        let counter = super::buffer(
            device,
            "hcb.sample_count",
            COUNTER_BYTES,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
        );
        Self {
            levels: levels_v,
            samples,
            counter,
            list,
            list_capacity,
            io_layout,
            sample_layout,
            base_pipeline,
            build_pipeline,
            mask_pipeline,
            clear_pipeline,
            samples_pipeline,
            params,
            dummy_storage,
            dummy_sampled,
            dummy_cache,
            width,
            height,
        }
    }

    fn targets(
        device: &wgpu::Device,
        width: u32,
        height: u32,
        levels: u32,
    ) -> (Vec<HcbLevel>, wgpu::Texture, wgpu::Buffer, u32) {
        let storage = wgpu::TextureUsages::STORAGE_BINDING;
        let levels_v = level_sizes(width, height, levels)
            .into_iter()
            .enumerate()
            .map(|(k, (w, h))| HcbLevel {
                width: w,
                height: h,
                position: super::create_target(
                    device,
                    &format!("hcb.level.{k}.position"),
                    w,
                    h,
                    wgpu::TextureFormat::Rgba32Float,
                    storage,
                ),
                normal: super::create_target(
                    device,
                    &format!("hcb.level.{k}.normal"),
                    w,
                    h,
                    wgpu::TextureFormat::Rgba32Float,
                    storage,
                ),
                mask: super::create_target(
                    device,
                    &format!("hcb.mask.{k}"),
                    w,
                    h,
                    wgpu::TextureFormat::R32Float,
                    storage,
                ),
            })
            .collect();
        let samples = super::create_target(
            device,
            "hcb.samples",
            width.max(1),
            height.max(1),
            wgpu::TextureFormat::R32Float,
            storage,
        );
        // Every pixel could be a level-0 sample.
        let capacity = width.max(1) * height.max(1);
        let list = super::buffer(
            device,
            "hcb.sample_list",
            std::mem::size_of::<GpuHcbSample>() as u64 * capacity as u64,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
        );
        (levels_v, samples, list, capacity)
    }

    /// Resizes for a `width` × `height` G-buffer and `levels` levels. Returns whether the
    /// textures were recreated.
    pub fn ensure(&mut self, ctx: &GpuContext, width: u32, height: u32, levels: u32) -> bool {
        let want = level_sizes(width, height, levels);
        let have: Vec<(u32, u32)> = self.levels.iter().map(|l| (l.width, l.height)).collect();
        if want == have && (self.width, self.height) == (width, height) {
            return false;
        }
        (self.levels, self.samples, self.list, self.list_capacity) = Self::targets(&ctx.device, width, height, levels);
        (self.width, self.height) = (width, height);
        true
    }

    pub fn register(&self, reg: &mut BufferRegistry) {
        for (k, l) in self.levels.iter().enumerate() {
            reg.register(
                &format!("hcb.level.{k}.position"),
                BufferKind::Data,
                "HCB level (Nguyen §3.2, §3.5): world position of the block's centre texel; w: a^w, the radius of the sphere around every pixel the texel stands for",
                &l.position,
            );
            reg.register(
                &format!("hcb.level.{k}.normal"),
                BufferKind::Data,
                "HCB level (Nguyen §3.2–3.4): normal of the block's centre texel; w: n^w, the group coherence of Algorithm 1 (0: incoherent or background, 1 at level 0)",
                &l.normal,
            );
            reg.register(
                &format!("hcb.mask.{k}"),
                BufferKind::Data,
                "HCB mask buffer (Nguyen §3.6): 1 inside the 3×3 splat of a coherent texel of the level above, 0 outside",
                &l.mask,
            );
        }
        reg.register(
            "hcb.samples",
            BufferKind::Data,
            "HCB samples (Nguyen §3.6) at G-buffer resolution: level + 1 at the pixel of each sample, 0 elsewhere",
            &self.samples,
        );
    }

    /// The bind group of `shaders/hcb/samples.wgsl` (mask, clear and sample passes) over the
    /// parameter slots: `views` = level normal, mask out, mask in, `hcb.samples`, level
    /// position, `hcb.cache`, `hcb.recompute_group`.
    fn sample_group(&self, ctx: &GpuContext, views: [&wgpu::TextureView; 7]) -> wgpu::BindGroup {
        let tv = wgpu::BindingResource::TextureView;
        let uniform = wgpu::BindingResource::Buffer(wgpu::BufferBinding {
            buffer: &self.params,
            offset: 0,
            size: std::num::NonZeroU64::new(std::mem::size_of::<HcbParams>() as u64),
        });
        let [normal, mask_out, mask_in, samples, position, cache, group] = views;
        ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("hcb.samples.inputs"),
            layout: &self.sample_layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: uniform },
                wgpu::BindGroupEntry { binding: 1, resource: tv(normal) },
                wgpu::BindGroupEntry { binding: 2, resource: tv(mask_out) },
                wgpu::BindGroupEntry { binding: 3, resource: tv(mask_in) },
                wgpu::BindGroupEntry { binding: 4, resource: tv(samples) },
                wgpu::BindGroupEntry { binding: 5, resource: self.counter.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 6, resource: tv(position) },
                wgpu::BindGroupEntry { binding: 7, resource: self.list.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 8, resource: tv(cache) },
                wgpu::BindGroupEntry { binding: 9, resource: tv(group) },
            ],
        })
    }

    /// Clears `hcb.samples` and the cache's `recompute_group` before the cache pass marks the
    /// reused samples (§5.1) and [`Self::run`] the new ones.
    pub fn clear_marks(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        recompute_group: &wgpu::TextureView,
    ) {
        let slot = 2 * MAX_LEVELS as u64;
        let mut p = HcbParams::zeroed();
        p.level[2] = 1;
        ctx.queue.write_buffer(&self.params, slot * STRIDE, bytemuck::bytes_of(&p));
        let view = |t: &wgpu::Texture| super::view(t, "hcb.view");
        let (samples, mask_out, mask_in, level) =
            (view(&self.samples), view(&self.dummy_storage), view(&self.dummy_sampled), view(&self.levels[0].normal));
        let dummies = self.dummy_cache.each_ref().map(view);
        let group =
            self.sample_group(ctx, [&level, &mask_out, &mask_in, &samples, &mask_in, &dummies[1], recompute_group]);
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("hcb.samples.clear"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&self.clear_pipeline);
        pass.set_bind_group(0, &group, &[(slot * STRIDE) as u32]);
        pass.dispatch_workgroups(self.width.div_ceil(8), self.height.div_ceil(8), 1);
    }

    /// Builds every level from the G-buffer's position and normal, the masks and the samples.
    /// Without `cache` the sample counter and `hcb.samples` start empty; with it (§5.2) the
    /// base is the supplementary G-buffer and the new samples are appended to the cached
    /// ones the cache pass put in the list (and `hcb.samples`).
    #[allow(clippy::too_many_arguments)]
    pub fn run(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        slot: Option<Slot<'_>>,
        g_position: &wgpu::TextureView,
        g_normal: &wgpu::TextureView,
        f: HcbFrame,
        cache: Option<CacheViews<'_>>,
    ) {
        let n = self.levels.len() as u32;
        let cached = cache.is_some() as u32;
        let spread = f.thresholds.spread_incomplete as u32;
        let mut params: Vec<HcbParams> = (0..n).map(|k| f.params([(k + 1 == n) as u32, k, cached, spread])).collect();
        // The clear of hcb.samples (and the recompute groups) uses the last slot.
        params.push(f.params([0, 0, cached, spread]));
        ctx.queue.write_buffer(&self.params, 0, &super::strided_bytes(STRIDE, params.len(), &params));
        let uniform = wgpu::BindingResource::Buffer(wgpu::BufferBinding {
            buffer: &self.params,
            offset: 0,
            size: std::num::NonZeroU64::new(std::mem::size_of::<HcbParams>() as u64),
        });
        let view = |t: &wgpu::Texture| super::view(t, "hcb.view");
        fn tv(v: &wgpu::TextureView) -> wgpu::BindingResource<'_> {
            wgpu::BindingResource::TextureView(v)
        }
        let (samples_view, dummy_out, dummy_in) =
            (view(&self.samples), view(&self.dummy_storage), view(&self.dummy_sampled));
        let dummies = self.dummy_cache.each_ref().map(view);
        let (weight_sum, incomplete, cache_view, group_view) = match &cache {
            Some(c) => (c.weight_sum, c.incomplete, c.cache, c.recompute_group),
            None => (&dummy_in, &dummies[0], &dummies[1], &dummies[2]),
        };
        let io_group = |a: &wgpu::TextureView,
                        b: &wgpu::TextureView,
                        c: &wgpu::TextureView,
                        d: &wgpu::TextureView,
                        weights: &wgpu::TextureView,
                        marks: &wgpu::TextureView| {
            ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("hcb.level.inputs"),
                layout: &self.io_layout,
                entries: &[
                    wgpu::BindGroupEntry { binding: 0, resource: uniform.clone() },
                    wgpu::BindGroupEntry { binding: 1, resource: tv(a) },
                    wgpu::BindGroupEntry { binding: 2, resource: tv(b) },
                    wgpu::BindGroupEntry { binding: 3, resource: tv(c) },
                    wgpu::BindGroupEntry { binding: 4, resource: tv(d) },
                    wgpu::BindGroupEntry { binding: 5, resource: tv(weights) },
                    wgpu::BindGroupEntry { binding: 6, resource: tv(marks) },
                ],
            })
        };
        let views: Vec<(wgpu::TextureView, wgpu::TextureView, wgpu::TextureView)> =
            self.levels.iter().map(|l| (view(&l.position), view(&l.normal), view(&l.mask))).collect();
        let mut io_groups = vec![io_group(g_position, g_normal, &views[0].0, &views[0].1, weight_sum, incomplete)];
        for k in 1..n as usize {
            io_groups.push(io_group(
                &views[k - 1].0,
                &views[k - 1].1,
                &views[k].0,
                &views[k].1,
                &dummy_in,
                &dummies[0],
            ));
        }
        let sample_group = |position: &wgpu::TextureView,
                            normal: &wgpu::TextureView,
                            mask_out: &wgpu::TextureView,
                            mask_in: &wgpu::TextureView| {
            self.sample_group(ctx, [normal, mask_out, mask_in, &samples_view, position, cache_view, group_view])
        };
        // Mask k − 1 from level k's coherence; the top's mask stays all outside.
        let mask_groups: Vec<wgpu::BindGroup> =
            (1..n as usize).map(|k| sample_group(&views[k].0, &views[k].1, &views[k - 1].2, &dummy_in)).collect();
        let level_groups: Vec<wgpu::BindGroup> = (0..n as usize)
            .map(|k| {
                let mask_in = if k + 1 == n as usize { &dummy_in } else { &views[k].2 };
                sample_group(&views[k].0, &views[k].1, &dummy_out, mask_in)
            })
            .collect();
        if cache.is_none() {
            encoder.clear_buffer(&self.counter, 0, None);
        }
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("hcb"),
            timestamp_writes: slot.and_then(|s| s.compute(true, true)),
        });
        let groups = |w: u32, h: u32| (w.div_ceil(8), h.div_ceil(8));
        let offset = |k: usize| [(k as u64 * STRIDE) as u32];
        for (k, l) in self.levels.iter().enumerate() {
            pass.set_pipeline(if k == 0 { &self.base_pipeline } else { &self.build_pipeline });
            pass.set_bind_group(0, &io_groups[k], &offset(k));
            let (gx, gy) = groups(l.width, l.height);
            pass.dispatch_workgroups(gx, gy, 1);
        }
        pass.set_pipeline(&self.mask_pipeline);
        for k in (1..n as usize).rev() {
            pass.set_bind_group(0, &mask_groups[k - 1], &offset(k));
            let (gx, gy) = groups(self.levels[k - 1].width, self.levels[k - 1].height);
            pass.dispatch_workgroups(gx, gy, 1);
        }
        if cache.is_none() {
            pass.set_pipeline(&self.clear_pipeline);
            pass.set_bind_group(0, &level_groups[0], &offset(n as usize));
            let (gx, gy) = groups(self.width, self.height);
            pass.dispatch_workgroups(gx, gy, 1);
        }
        pass.set_pipeline(&self.samples_pipeline);
        for (k, l) in self.levels.iter().enumerate() {
            pass.set_bind_group(0, &level_groups[k], &offset(k));
            let (gx, gy) = groups(l.width, l.height);
            pass.dispatch_workgroups(gx, gy, 1);
        }
    }
}

/// Stage 6 of the HCB (Nguyen et al. §4.2–4.3): the samples' coherence-weighted splats
/// (`hcb.weight_sum`: rgb Σ w E, a Σ w) and their normalisation (Eq. 11, `hcb.irradiance`;
/// a = 0 where a covered pixel got no weight, counted in `uncovered`). Shaders
/// `shaders/hcb/{splat,normalize}.wgsl`.
pub struct HcbSplatPass {
    pub weight_sum: wgpu::Texture,
    pub irradiance: wgpu::Texture,
    /// `hcb.indirect`: the indirect light the compose adds, c·DI/π × the splatted irradiance.
    pub indirect: wgpu::Texture,
    /// Covered pixels that no sample reached (one u32).
    pub uncovered: wgpu::Buffer,
    splat_layout: wgpu::BindGroupLayout,
    normalize_layout: wgpu::BindGroupLayout,
    splat_pipeline: wgpu::RenderPipeline,
    normalize_pipeline: wgpu::ComputePipeline,
    /// The uniforms of the splat of every sample and of the new samples only (§5.2).
    params: [wgpu::Buffer; 2],
    width: u32,
    height: u32,
}

/// Format of `hcb.weight_sum` (additive blending of f32 needs FLOAT32_BLENDABLE, which the
/// renderer requires).
const ACCUM_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

impl HcbSplatPass {
    pub fn new(ctx: &GpuContext, camera_entry: wgpu::BindGroupLayoutEntry, width: u32, height: u32) -> Self {
        let device = &ctx.device;
        let (vs, fs, cs) = (wgpu::ShaderStages::VERTEX, wgpu::ShaderStages::FRAGMENT, wgpu::ShaderStages::COMPUTE);
        let camera_entry = wgpu::BindGroupLayoutEntry { visibility: vs | fs, ..camera_entry };
        let splat_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("hcb.splat.inputs"),
            entries: &[
                camera_entry,
                bgl::uniform(1, vs | fs),
                bgl::storage(2, vs | fs, true),
                bgl::texture(3, fs, false),
                bgl::texture(4, fs, false),
                bgl::storage(5, vs, true),
            ],
        });
        let normalize_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("hcb.normalize.inputs"),
            entries: &[
                bgl::texture(0, cs, false),
                bgl::texture(1, cs, false),
                bgl::storage_texture(2, wgpu::TextureFormat::Rgba32Float),
                bgl::storage(3, cs, false),
                bgl::texture(4, cs, false),
                bgl::storage_texture(5, wgpu::TextureFormat::Rgba32Float),
            ],
        });
        let m_splat = crate::shaders::create_module(device, "hcb/splat.wgsl");
        let m_norm = crate::shaders::create_module(device, "hcb/normalize.wgsl");
        let pl = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("hcb.splat.pipeline_layout"),
            bind_group_layouts: &[Some(&splat_layout)],
            immediate_size: 0,
        });
        let add = wgpu::BlendComponent {
            src_factor: wgpu::BlendFactor::One,
            dst_factor: wgpu::BlendFactor::One,
            operation: wgpu::BlendOperation::Add,
        };
        let splat_pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("hcb.splat"),
            layout: Some(&pl),
            vertex: wgpu::VertexState {
                module: &m_splat,
                entry_point: Some("vs_splat"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: Default::default(),
            depth_stencil: None,
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &m_splat,
                entry_point: Some("fs_splat"),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState {
                    format: ACCUM_FORMAT,
                    blend: Some(wgpu::BlendState { color: add, alpha: add }),
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            multiview_mask: None,
            cache: None,
        });
        let normalize_pipeline =
            super::compute_pipeline(device, "hcb.normalize", &m_norm, "cs_normalize", &[&normalize_layout]);
        let size = std::mem::size_of::<HcbParams>() as u64;
        let params = [
            super::uniform_buffer(device, "hcb.splat.params", size),
            super::uniform_buffer(device, "hcb.splat.new.params", size),
        ];
        let uncovered = super::buffer(
            device,
            "hcb.uncovered",
            16,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
        );
        let (weight_sum, irradiance, indirect) = Self::targets(device, width, height);
        Self {
            weight_sum,
            irradiance,
            indirect,
            uncovered,
            splat_layout,
            normalize_layout,
            splat_pipeline,
            normalize_pipeline,
            params,
            width,
            height,
        }
    }

    fn targets(device: &wgpu::Device, width: u32, height: u32) -> (wgpu::Texture, wgpu::Texture, wgpu::Texture) {
        let (w, h) = (width.max(1), height.max(1));
        let weight_sum =
            super::create_target(device, "hcb.weight_sum", w, h, ACCUM_FORMAT, wgpu::TextureUsages::RENDER_ATTACHMENT);
        let storage = wgpu::TextureUsages::STORAGE_BINDING;
        let irradiance =
            super::create_target(device, "hcb.irradiance", w, h, wgpu::TextureFormat::Rgba32Float, storage);
        let indirect = super::create_target(device, "hcb.indirect", w, h, wgpu::TextureFormat::Rgba32Float, storage);
        (weight_sum, irradiance, indirect)
    }

    /// Resizes the targets. Returns whether they were recreated.
    pub fn ensure(&mut self, ctx: &GpuContext, width: u32, height: u32) -> bool {
        if (self.width, self.height) == (width, height) {
            return false;
        }
        (self.weight_sum, self.irradiance, self.indirect) = Self::targets(&ctx.device, width, height);
        (self.width, self.height) = (width, height);
        true
    }

    pub fn register(&self, reg: &mut BufferRegistry) {
        reg.register(
            "hcb.weight_sum",
            BufferKind::Data,
            "HCB splatting (Nguyen §4.3): rgb Σ w·E and a Σ w over the samples coherent to each pixel (Eq. 10)",
            &self.weight_sum,
        );
        reg.register(
            "hcb.irradiance",
            BufferKind::Data,
            "HCB splatted light (Nguyen Eq. 11): Σ w·E / Σ w; a = 1 where a sample reached the pixel, 0 on covered pixels none reached",
            &self.irradiance,
        );
        reg.register(
            "hcb.indirect",
            BufferKind::Hdr,
            "HCB indirect light: each pixel's diffuse reflection c·DI/π of the splatted irradiance; a = 0 where no sample reached it",
            &self.indirect,
        );
    }

    /// Splats the samples of `list` (instance count from `draw_args`, a `DrawIndirectArgs`
    /// with 6 vertices) over the G-buffer and normalises.
    #[allow(clippy::too_many_arguments)]
    pub fn run(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        slot: Option<Slot<'_>>,
        camera: &wgpu::Buffer,
        g: (&wgpu::TextureView, &wgpu::TextureView, &wgpu::TextureView),
        samples: (&wgpu::Buffer, &wgpu::Buffer),
        draw_args: &wgpu::Buffer,
        f: HcbFrame,
    ) {
        self.splat(ctx, encoder, slot, camera, g, samples, (draw_args, 0), false, false, f);
        self.normalize(ctx, encoder, slot, g);
    }

    /// Adds the splats of the samples of `samples` = (list, counter) to `hcb.weight_sum`
    /// (instance count from `draw_args` = (buffer, offset of a `DrawIndirectArgs`)): all of
    /// them onto a cleared target, or with `new_only` the ones after the cached samples
    /// (counter word 1, §5.2) onto what the cached ones left. `slot`'s scope begins here and
    /// ends here with `ends_scope`, else with [`Self::normalize`].
    #[allow(clippy::too_many_arguments)]
    pub fn splat(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        slot: Option<Slot<'_>>,
        camera: &wgpu::Buffer,
        g: (&wgpu::TextureView, &wgpu::TextureView, &wgpu::TextureView),
        samples: (&wgpu::Buffer, &wgpu::Buffer),
        draw_args: (&wgpu::Buffer, u64),
        new_only: bool,
        ends_scope: bool,
        f: HcbFrame,
    ) {
        let params = &self.params[new_only as usize];
        ctx.queue.write_buffer(params, 0, bytemuck::bytes_of(&f.params([new_only as u32, 0, 0, 0])));
        let tv = wgpu::BindingResource::TextureView;
        let group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("hcb.splat.inputs"),
            layout: &self.splat_layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: camera.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: params.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 2, resource: samples.0.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 3, resource: tv(g.0) },
                wgpu::BindGroupEntry { binding: 4, resource: tv(g.1) },
                wgpu::BindGroupEntry { binding: 5, resource: samples.1.as_entire_binding() },
            ],
        });
        let accum = super::view(&self.weight_sum, "hcb.weight_sum");
        let load = if new_only { wgpu::LoadOp::Load } else { wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT) };
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("hcb.splat"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &accum,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations { load, store: wgpu::StoreOp::Store },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: slot.as_ref().and_then(|s| s.render(true, ends_scope)),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.splat_pipeline);
        pass.set_bind_group(0, &group, &[]);
        pass.draw_indirect(draw_args.0, draw_args.1);
    }

    /// Eq. 11 over `hcb.weight_sum`: `hcb.irradiance`, `hcb.indirect` and the uncovered count
    /// (ends `slot`'s scope).
    pub fn normalize(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        slot: Option<Slot<'_>>,
        g: (&wgpu::TextureView, &wgpu::TextureView, &wgpu::TextureView),
    ) {
        let tv = wgpu::BindingResource::TextureView;
        let accum = super::view(&self.weight_sum, "hcb.weight_sum");
        let out = super::view(&self.irradiance, "hcb.irradiance");
        let radiance = super::view(&self.indirect, "hcb.indirect");
        let ngroup = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("hcb.normalize.inputs"),
            layout: &self.normalize_layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: tv(&accum) },
                wgpu::BindGroupEntry { binding: 1, resource: tv(g.1) },
                wgpu::BindGroupEntry { binding: 2, resource: tv(&out) },
                wgpu::BindGroupEntry { binding: 3, resource: self.uncovered.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 4, resource: tv(g.2) },
                wgpu::BindGroupEntry { binding: 5, resource: tv(&radiance) },
            ],
        });
        encoder.clear_buffer(&self.uncovered, 0, None);
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("hcb.normalize"),
            timestamp_writes: slot.and_then(|s| s.compute(false, true)),
        });
        pass.set_pipeline(&self.normalize_pipeline);
        pass.set_bind_group(0, &ngroup, &[]);
        pass.dispatch_workgroups(self.width.div_ceil(8), self.height.div_ceil(8), 1);
    }
}

/// Uniform of the gather at the samples; WGSL twin: `HcbGatherParams` in
/// `shaders/hcb/gather.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct HcbGatherParams {
    /// VPL count, visibility (0 none, 1 ISM, 2 exact), atlas columns, map size.
    pub counts: [u32; 4],
    /// The samples gathered ([`GatherSet`] as u32), 0, 0, 0.
    pub mode: [u32; 4],
    /// d_min², then as `interleave::GatherParams::shade`.
    pub shade: Vec4,
}

/// Which samples of the list a gather dispatch covers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GatherSet<'a> {
    /// Every sample (the per-frame HCB).
    All,
    /// The cached samples due for recomputation (§5.3): the list slots in the queue.
    Recompute(&'a wgpu::Buffer),
    /// The new samples after the cached ones (§5.2).
    New,
}

/// Stage 5 of the HCB technique (Nguyen et al. §4.1): the irradiance the VPLs send each
/// sample of the list (`shaders/hcb/gather.wgsl`), and the indirect arguments of this
/// dispatch and of the splat draws (`args`: 4 draw words for every sample, 3 dispatch words,
/// one spare, 4 draw words for the samples after the cached ones, §5.2).
pub struct HcbGatherPass {
    layout: wgpu::BindGroupLayout,
    args_pipeline: wgpu::ComputePipeline,
    gather_pipeline: wgpu::ComputePipeline,
    /// The uniforms of the gathers of every sample / the new samples, and of the recomputed
    /// ones (both run in a cached frame).
    params: [wgpu::Buffer; 2],
    pub args: wgpu::Buffer,
    /// Bound as the recompute queue when there is none.
    no_queue: wgpu::Buffer,
    /// Bound in `args`'s place for the gather, which reads `args` as its indirect arguments
    /// (a buffer cannot be both in one dispatch).
    no_args: wgpu::Buffer,
    no_ism: wgpu::TextureView,
    no_exact: wgpu::TextureView,
}

impl HcbGatherPass {
    pub fn new(ctx: &GpuContext) -> Self {
        let device = &ctx.device;
        let cs = wgpu::ShaderStages::COMPUTE;
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("hcb.gather.inputs"),
            entries: &[
                bgl::uniform(0, cs),
                bgl::storage(1, cs, true),
                bgl::texture(2, cs, false),
                bgl::depth(3, cs),
                bgl::storage(4, cs, true),
                bgl::storage(5, cs, false),
                bgl::storage(6, cs, false),
                bgl::storage(7, cs, true),
            ],
        });
        let module = crate::shaders::create_module(device, "hcb/gather.wgsl");
        let args_pipeline = super::compute_pipeline(device, "hcb.gather.args", &module, "cs_args", &[&layout]);
        let gather_pipeline = super::compute_pipeline(device, "hcb.gather", &module, "cs_gather", &[&layout]);
        let size = std::mem::size_of::<HcbGatherParams>() as u64;
        let params = [
            super::uniform_buffer(device, "hcb.gather.params", size),
            super::uniform_buffer(device, "hcb.gather.recompute.params", size),
        ];
        let no_queue = super::buffer(device, "hcb.no_recompute_queue", 16, wgpu::BufferUsages::STORAGE);
        let args = super::buffer(
            device,
            "hcb.indirect_args",
            48,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::INDIRECT | wgpu::BufferUsages::COPY_SRC,
        );
        let no_args = super::buffer(device, "hcb.no_args", 48, wgpu::BufferUsages::STORAGE);
        let (no_ism, no_exact) = super::interleave::no_visibility_atlases(device, "hcb.gather");
        Self { layout, args_pipeline, gather_pipeline, params, args, no_args, no_queue, no_ism, no_exact }
    }

    /// Gathers at the samples `set` of `hcb`'s list from `vpl_count` VPLs with `vis`.
    #[allow(clippy::too_many_arguments)]
    pub fn run(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        slot: Option<Slot<'_>>,
        hcb: &HcbPass,
        vpls: &wgpu::Buffer,
        vpl_count: u32,
        d_min: f32,
        vis: super::interleave::GatherVisibility<'_>,
        set: GatherSet<'_>,
    ) {
        let (code, ism, exact, cols, size, shade) = vis.parts(&self.no_ism, &self.no_exact);
        let (mode, queue) = match set {
            GatherSet::All => (0, &self.no_queue),
            GatherSet::Recompute(q) => (1, q),
            GatherSet::New => (2, &self.no_queue),
        };
        let p = HcbGatherParams {
            counts: [vpl_count, code, cols, size],
            mode: [mode, 0, 0, 0],
            shade: Vec4::new(d_min * d_min, shade.y, shade.z, shade.w),
        };
        let params = &self.params[(mode == 1) as usize];
        ctx.queue.write_buffer(params, 0, bytemuck::bytes_of(&p));
        let tv = wgpu::BindingResource::TextureView;
        let group = |args: &wgpu::Buffer| {
            ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("hcb.gather.inputs"),
                layout: &self.layout,
                entries: &[
                    wgpu::BindGroupEntry { binding: 0, resource: params.as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 1, resource: vpls.as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 2, resource: tv(ism) },
                    wgpu::BindGroupEntry { binding: 3, resource: tv(exact) },
                    wgpu::BindGroupEntry { binding: 4, resource: hcb.counter.as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 5, resource: hcb.list.as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 6, resource: args.as_entire_binding() },
                    wgpu::BindGroupEntry { binding: 7, resource: queue.as_entire_binding() },
                ],
            })
        };
        let (args_group, gather_group) = (group(&self.args), group(&self.no_args));
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("hcb.gather"),
            timestamp_writes: slot.and_then(|s| s.compute(true, true)),
        });
        pass.set_bind_group(0, &args_group, &[]);
        pass.set_pipeline(&self.args_pipeline);
        pass.dispatch_workgroups(1, 1, 1);
        pass.set_bind_group(0, &gather_group, &[]);
        pass.set_pipeline(&self.gather_pipeline);
        pass.dispatch_workgroups_indirect(&self.args, 16);
    }
}
