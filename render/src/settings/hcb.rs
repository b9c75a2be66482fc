//! The settings of Nguyen et al.'s hierarchical coherence buffer (000): the thresholds of §3.1
//! (θmax, γmax, dmax), the levels, the samples and their cache (§5). The passes are in
//! `passes/hcb/`, the CPU twin in `cpu::hcb`.

use super::splat::{IrradianceReceiver, SplatMethod};
use crate::{settings_enum, settings_group};

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

/// The thresholds of §3.1.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Thresholds {
    /// cos θ_max (normal coherence, Eq. 2 and 6–7).
    pub cos_theta_max: f32,
    /// cos γ_max (pose coherence, Eq. 3).
    pub cos_gamma_max: f32,
    /// d_max in scene units (distance coherence, Eq. 1).
    pub d_max: f32,
    /// The caching HCB's sign rule (§5.2), where n^w carries +1 for incomplete texels and −1
    /// for complete ones: false keeps the centre texel's sign (Fig. 7c: new samples only on
    /// incomplete texels), true makes a block with any positive texel positive (Fig. 7d: new
    /// samples may lie outside them). Without signs (the per-frame HCB) both are the same.
    pub spread_incomplete: bool,
}
