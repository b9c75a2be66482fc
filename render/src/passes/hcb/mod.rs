//! Stage 5 of the hierarchical coherence buffer (Nguyen et al., 000 §3): the HCB levels
//! (`hcb.level.k.position`: xyz + the sphere radius a^w; `hcb.level.k.normal`: xyz + the
//! group coherence n^w), the mask buffer (`hcb.mask.k`), the sample buffer (`hcb.samples`,
//! level + 1 at each sample's pixel) and the compact sample list. Shaders
//! `shaders/hcb/{base,build,samples}.wgsl`; CPU twin `cpu::hcb` (the paper's readings are
//! documented there).
//!
//! The folder holds the HCB's passes: `build` (levels, masks, samples; stage 5), `gather`
//! (the VPLs at the samples; stage 6), `splat` (coherence-weighted splatting and Eq. 11;
//! stage 6's reconstruction), `cache` (the sample cache of §5; stage 7), `stage`, which
//! runs them for the frame, and `explain`, the replay of a pinned pixel's splat (issue #42).

use glam::Vec4;

use crate::cpu::hcb::Thresholds;
use crate::passes::bins::SplatMethod;
use crate::passes::receiver::IrradianceReceiver;
use crate::{settings_enum, settings_group};

pub mod build;
pub mod cache;
pub mod explain;
pub mod gather;
pub mod splat;
pub mod stage;

pub use build::{COUNTER_BYTES, CacheViews, HcbPass, level_sizes};
pub use gather::{GatherSet, HcbGatherParams, HcbGatherPass};
pub use splat::HcbSplatPass;

settings_group! {
    /// The hierarchical coherence buffer (stages 5–6 of the HCB technique; Nguyen et al. 000
    /// §3–4): where indirect light is gathered and how it is splatted. ⚠[nguyen.thresholds] The
    /// paper gives no values; the defaults were chosen on the default scene (see
    /// presets/nguyen-hcb.ron).
    pub struct HcbSettings: "hcb" {
        /// Largest normal divergence inside a coherent group (Eq. 2, combined by Eq. 6–7).
        theta_max_deg: f32 = 20.0,
        unit "°", symbol "θ_max", range 1.0..=89.0, cost "larger: fewer samples and blurrier light across bends", history false;
        /// Pose limit under backward lighting (Eq. 3): |âb·n_a| ≤ cos γ_max.
        gamma_max_deg: f32 = 70.0,
        unit "°", symbol "γ_max", range 1.0..=90.0, cost "smaller: fewer samples, light leaks across steps", history false;
        /// Largest radius of a coherent group (Eq. 1 on the accumulated distance, §3.5), in
        /// scene units; ⚠[nguyen.d-max] 0 picks it from the scene: 0.1 × its scale
        /// (`scale.reference`: the room the camera is in, else the bounding radius; 0.17 on
        /// the default Cornell box, 0.47 in the hotel room, 0.61 with the model's radius).
        d_max_m: f32 = 0.0,
        unit "m", symbol "d_max", range 0.0..=100.0, cost "larger: fewer samples, coarser light", history false;
        /// HCB levels including the G-buffer's (1: every pixel is a sample, the per-pixel gather).
        levels: u32 = 7,
        unit "levels", symbol "", range 1..=12, cost "one pass per level; more levels, larger groups", history false;
        /// A cached sample is invalid when the G-buffer point it lands on is farther than
        /// this (§5.1's distance threshold; ⚠[nguyen.cache-thresholds] §5 gives no value for it,
        /// `cache_normal_deg`, `surplus_quad_px` or `incomplete_weight`).
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
        /// The smallest |cos| between a pixel's normal and the direction to the eye in its
        /// footprint a^w = depth · pixel size / √|cos| (§3.5's back-projected area;
        /// ⚠[nguyen.footprint-clamp] our clamp: the paper does not say how grazing pixels stay
        /// finite). Smaller: grazing pixels get larger footprints, so distance coherence
        /// (Eq. 1) holds across more of them.
        footprint_min_cos: f32 = 0.01,
        unit "", symbol "", range 0.0001..=1.0, cost "free", history false;
        /// How the splat sums the samples at the pixels (§4.3's additive blending of one quad
        /// per sample, or binned in compute: the same sums).
        splat: SplatMethod = SplatMethod::Auto,
        unit "", symbol "", range 0..=2, cost "blend: the quads' overdraw; binned: one pass over the screen per splat", history false;
        /// How each pixel reflects its splatted irradiance (Eq. 11): ⚠[nguyen.glossy-receiver]
        /// the paper's pixels reflect it diffusely, c·DI/π·E (§4.1), so glossy surfaces lose
        /// their indirect specular light; GI Lab's gather keeps the VPLs' mean incident
        /// direction beside each sample's irradiance, splats it with the same weights and lights
        /// the receiver's specular lobe from it (`cpu::brdf::receive_irradiance`).
        receiver: IrradianceReceiver = IrradianceReceiver::Glossy,
        unit "", symbol "f_x", range 0..=1, cost "a direction per sample and a second splat target (16 B a pixel)", history false;
    }
    legacy {
        /// Version 1: the sample cache on or off; now `pipeline.temporal = HcbSampleCache`.
        cache: bool;
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

/// The scene-relative d_max: this fraction of the scene's bounding radius. The paper gives
/// no value. 0.1 was measured on the default scene at 256² (`gi-lab bench --suite quality`,
/// the HCB against the per-pixel gather with the same 1024 VPLs): 0.15 gave FLIP 0.036 with
/// 7.3 % of the pixels as samples, 0.1 gives 0.022 with 10.0 % (4.1 % at 512², 1.8 % at
/// 1024², inside the paper's 1.9–4.4 % at its resolutions). Below 0.1 the share grows fast
/// (0.05: 50 % at 256²).
pub const D_MAX_PER_RADIUS: f32 = 0.1;

impl HcbSettings {
    /// d_max in scene units for a scene of scale `scene_radius` (`scale::scale_radius`; the setting, or
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
    /// x: the incomplete weight threshold (§5.2), y: 1 for the glossy receiver
    /// (`hcb.receiver`), z: the footprint's clamp of |cos|, w: 0.
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
    /// xyz: Σ lum(E_k) ω_k, the direction sum of the glossy receiver (issue #51); 0 when the
    /// gather keeps no direction.
    pub dir: Vec4,
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

pub(crate) const STRIDE: u64 = 256;
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
    /// The footprint's clamp of |cos| (`hcb.footprint_min_cos`).
    pub footprint_min_cos: f32,
    /// How Eq. 11's pixels reflect their irradiance (`hcb.receiver`).
    pub receiver: IrradianceReceiver,
}

impl HcbFrame {
    /// A frame with §5.3's default period and no incomplete threshold (the per-frame HCB).
    pub fn new(thresholds: Thresholds, eye: glam::Vec3, pixel_scale: f32) -> Self {
        Self {
            thresholds,
            eye,
            pixel_scale,
            pattern: crate::maths::recompute_pattern(4),
            incomplete_weight: 0.0,
            footprint_min_cos: HcbSettings::default().footprint_min_cos,
            receiver: IrradianceReceiver::Glossy,
        }
    }

    /// The passes' uniform for `level` (the splat's and, with [0; 4], the pixel's replay's:
    /// `explain::HcbExplainPass`).
    pub(crate) fn params(&self, level: [u32; 4]) -> HcbParams {
        let t = self.thresholds;
        HcbParams {
            thresholds: Vec4::new(t.cos_theta_max, t.cos_gamma_max, t.d_max, self.pixel_scale),
            eye: self.eye.extend(1.0),
            level,
            cache: Vec4::new(self.incomplete_weight, self.receiver.flag(), self.footprint_min_cos, 0.0),
            pattern: self.pattern,
        }
    }
}
