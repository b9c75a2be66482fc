//! The settings of Soler et al.'s multi-resolution screen-space indirect illumination (004):
//! the mip levels, sample radius, voting filter, bilateral upsampling and voxel visibility.
//! The passes are in `passes/soler/`, the CPU twin in `cpu::soler`.

use crate::{settings_enum, settings_group};

/// Most levels a frame gathers (the settings' range).
pub const MAX_GATHERED: usize = 8;

settings_enum! {
    /// The resolution the first gathered level has (004 §4, Fig. 10).
    pub enum StartResolution {
        /// The G-buffer's resolution.
        Full = "full",
        /// Half the G-buffer's width and height (one vote down).
        Half = "half",
        /// A quarter (two votes down).
        Quarter = "quarter",
    }
    default Quarter
}

impl StartResolution {
    /// The pyramid level of the first gathered level (0: the G-buffer).
    pub fn level(self) -> u32 {
        match self {
            Self::Full => 0,
            Self::Half => 1,
            Self::Quarter => 2,
        }
    }
}

settings_enum! {
    /// The geometry term of each screen-space sample (004 §3).
    pub enum FormFactor {
        /// Eq. 1's cosθ cosθ' ds / r²: unbounded as r → 0 (noise near contacts, Fig. 2).
        PointToPoint = "point to point (Eq. 1)",
        /// Eq. 4's point-to-disc form factor R² cosθ / (r² + R²), R² = cosθ' ds / π, times
        /// π (our reading: Eq. 4 is a form factor, 1/π of Eq. 1's kernel for r ≫ R).
        PointToDisc = "point to disc (Eq. 4)",
    }
    default PointToDisc
}

settings_enum! {
    /// What Eq. 6's history W(·) warps (004 §4 "Temporal filtering"; the paper writes I_{i−1},
    /// the previous frame's unfiltered light, but "blending … with that of the previous frame"
    /// reads either way).
    pub enum TemporalHistory {
        /// F_{i−1}, the previous filtered result: an exponential moving average over frames
        /// (variance × (1 − a)/(1 + a) for a still pixel).
        Filtered = "F(i−1): the previous result",
        /// I_{i−1}, the previous frame's own gather, as Eq. 6 prints it: two frames averaged
        /// (variance × a² + (1 − a)²).
        Raw = "I(i−1): the previous gather (Eq. 6 as printed)",
    }
    default Filtered
}

settings_enum! {
    /// Where the voxel grid is built (004 §4 "Visibility": "we voxelize the scene at the
    /// resolution of the screen … the mipmapped voxel buffers are computed by AND-ing").
    pub enum VoxelResolution {
        /// At the G-buffer's resolution, ANDed down level by level to the gathered ones: a
        /// coarse voxel is solid where all the screen's voxels below it are (the text).
        Screen = "the screen's, ANDed down (004 §4)",
        /// At the first gathered level's resolution (a coarse texel records only the surfaces
        /// that cross its centre's ray: cheaper, and not conservative).
        FirstLevel = "the first gathered level's",
    }
    default Screen
}

settings_enum! {
    /// The radiance the first bounce's senders emit (004 §5.3: "as we're using a simple
    /// G-Buffer to represent the input illumination … we are limited to a diffuse
    /// approximation of this light").
    pub enum Sender {
        /// The direct light's diffuse part c·DI/π · E (`direct.diffuse`): every sender emits
        /// alike in all directions, as the text's G-buffer of direct illumination assumes and
        /// as the later bounces already do.
        Diffuse = "diffuse (c·DI/π·E, §5.3)",
        /// The direct light toward the camera through the whole BRDF (`direct.radiance`): a
        /// highlight seen by the camera is re-emitted to every receiver.
        ViewDependent = "view-dependent (toward the camera)",
    }
    default Diffuse
}

settings_enum! {
    /// What Eq. 6 blends (004 §4 "Temporal filtering" and Fig. 4: "the newly computed values
    /// are averaged with the values of the previous frame … The obtained illumination is
    /// multiplied by the albedo buffer").
    pub enum TemporalQuantity {
        /// The gathered irradiance, before the albedo multiply (Fig. 4): the history is
        /// demodulated by the albedo c·DI/π of its own pixel and modulated by the current
        /// pixel's, so textures do not smear; the glossy light is blended apart, with its own
        /// history and the same a (adapted to glossiness, 004 §4).
        Irradiance = "irradiance, before the albedo (Fig. 4)",
        /// The reflected radiance after the albedo multiply and the glossy light (GI Lab
        /// before issue #41): textures and highlights are blended with the warped history.
        Radiance = "radiance, after the albedo and glossy light",
    }
    default Irradiance
}

settings_group! {
    /// Soler et al.'s screen-space indirect illumination (004 §3–4): the mip levels, the ring
    /// of samples and the upsampling. Defaults: the paper's typical setting (4 levels,
    /// r = 40 px, 64 samples from a quarter resolution, Fig. 9's first column); it gives no σ.
    pub struct SolerSettings: "soler" {
        /// Mip levels gathered, from the start resolution down (004 §4; each adds a ring twice
        /// as far).
        levels: u32 = 4,
        unit "levels", symbol "L", range 1..=8, cost "one gather per level, each a quarter of the one before", history false;
        /// Ring radius r in texels of every level (004 §4, Fig. 3): level k covers r/2 … r of
        /// its own texels, 2^k·r/2 … 2^k·r of the start level's; the first level the disc.
        radius_px: f32 = 40.0,
        unit "px", symbol "r", range 1.0..=256.0, cost "free (the samples spread wider)", history false;
        /// Samples per texel and level, constant across levels (004 §4).
        samples: u32 = 64,
        unit "samples", symbol "N", range 1..=1024, cost "linear in N", history false;
        /// Resolution of the first gathered level (004 §4, Fig. 10).
        start_resolution: StartResolution = StartResolution::Quarter,
        unit "", symbol "", range 0..=2, cost "full: 4× half's gather, 16× quarter's", history false;
        /// σ₁ of Eq. 5's g₁ on the texel distance (the paper gives none).
        vote_sigma_pixel: f32 = 1.0,
        unit "px", symbol "σ₁", range 0.05..=10.0, cost "free", history false;
        /// σ₂ of Eq. 5's g₂ on 1 − n_i·n_j.
        vote_sigma_normal: f32 = 0.2,
        unit "", symbol "σ₂", range 0.001..=2.0, cost "free", history false;
        /// σ₃ of Eq. 5's g₃ on the relative depth difference (z_j − z_i)/z_i (our reading:
        /// the paper's z_j − z_i divided by z_i, independent of the scene's scale).
        vote_sigma_depth: f32 = 0.05,
        unit "× z", symbol "σ₃", range 0.0001..=10.0, cost "free", history false;
        /// ⚠[soler.vote-radiance-power] Radiance goes down the pyramid so that a coarse texel emits its block's power: the
        /// sub-pixels' radiance weighted by their Eq. 2 areas, over the winner's (on); off:
        /// the block's plain mean, and the coarse texel, whose Eq. 2 area is the winner's (the
        /// less grazing sub-pixel, as a rule), emits less than its block (measured on the
        /// default scene at 128²: Σ L·ds −10 % at half and −30 % at quarter resolution).
        vote_power: bool = true,
        unit "", symbol "", range 0..=1, cost "free", history false;
        /// ⚠[soler.vote-consistent] A sub-pixel's radiance enters its coarse texel weighted by
        /// w = g₂(1 − n_i·n_w), Eq. 5's normal kernel (σ₂) centred on the winner's normal n_w,
        /// over Σ w (on): the coarse texel stands for the winner's surface over the whole block
        /// and emits along its normal only the light of the sub-pixels that face as it does —
        /// the "small inconsistent regions" Eq. 5 discards for the normal and depth are
        /// discarded for the light too; off: every sub-pixel's light over the block's count, so
        /// that a sunlit seat inside a block won by the chair's unlit back lights the floor under
        /// the chair (issue #51: 300× the truth at quarter resolution; FLIP against the
        /// screen-visible truth 0.366 → 0.185, the default box's 0.178 → 0.191 at 128²).
        vote_consistent: bool = true,
        unit "", symbol "", range 0..=1, cost "free (one more gaussian per sub-pixel)", history false;
        /// The geometry term of each sample (004 §3, Eq. 1 or Eq. 4).
        form_factor: FormFactor = FormFactor::PointToDisc,
        unit "", symbol "", range 0..=1, cost "free", history false;
        /// The senders' radiance on the first bounce (⚠[soler.sender-diffuse] 004 §5.3's
        /// diffuse approximation by default; the view-dependent light as an option).
        sender: Sender = Sender::Diffuse,
        unit "", symbol "", range 0..=1, cost "diffuse: a second output of the direct light (8 bytes per pixel)", history false;
        /// Smallest cos β in Eq. 2's cos α / cos β (⚠[soler.min-cos-beta] our bound: a grazing texel would stand for
        /// an unbounded area).
        min_cos_beta: f32 = 0.1,
        unit "", symbol "cos β_min", range 0.001..=1.0, cost "free", history false;
        /// σ of the upsampling's depth weight on (z_c − z)/z (joint bilateral upsampling; the
        /// paper gives no weights).
        upsample_sigma_depth: f32 = 0.1,
        unit "× z", symbol "", range 0.0001..=10.0, cost "free", history false;
        /// σ of the upsampling's normal weight on 1 − n·n_c.
        upsample_sigma_normal: f32 = 0.2,
        unit "", symbol "", range 0.001..=2.0, cost "free", history false;
        /// Bounces of indirect light (004 §4 "Multi-bounce computation"): bounce n gathers
        /// bounce n − 1's light (c·DI/π · E at every pixel, mipmapped like the direct light);
        /// the indirect light is their sum.
        bounces: u32 = 1,
        unit "bounces", symbol "n", range 1..=4, cost "a pyramid, a gather per level and an upsampling per bounce (the voxel grid is shared)", history false;
        /// Visibility on every bounce; off: on the first only (004 §5.3: suppressing it after
        /// bounce 1 "results in acceptable artifacts" and saves most of the cost).
        visibility_all_bounces: bool = false,
        unit "", symbol "", range 0..=1, cost "with visibility: the march on every bounce", history false;
        /// One bounce per frame, in turn: frame f gathers bounce (f mod n) + 1 from the stored
        /// result of the bounce before it, and the newest result of every bounce is added
        /// (004 §5.3's odd/even frames for n = 2; relies on the light's temporal coherence).
        alternate_bounces: bool = false,
        unit "", symbol "", range 0..=1, cost "one bounce's gather per frame instead of n", history true;
        /// Glossy reflection of the gathered light on the last bounce before the camera
        /// (004 §4 "Screen-space importance sampling"): each sample also adds L·K·f_s(l, v),
        /// f_s the BRDF's specular lobe, into a second accumulator that is upsampled like the
        /// irradiance and added after the resolve; the light passed to further bounces stays
        /// diffuse (§5.3). Off: the receiver reflects diffusely only (Fig. 4).
        glossy_reflection: bool = true,
        unit "", symbol "f_s", range 0..=1, cost "a second upsampling chain and the lobe per sample", history false;
        /// Importance sampling of glossy receivers: the angle of each ring sample is drawn in
        /// proportion to f(θ) = α + exp(−s (θ_r − θ)² / 2π) around the projected mirror
        /// direction θ_r, each sample's area weighted by 1/pdf (unbiased with the
        /// point-to-point kernel; ⚠[soler.glossy-pdf-weight] biased low with the point-to-disc
        /// kernel where the disc reaches the receiver, −20 % at R = r: `cpu::soler_glossy`);
        /// off: uniform angles.
        glossy_sampling: bool = true,
        unit "", symbol "", range 0..=1, cost "an erf and an inverse erf per sample of a glossy receiver", history false;
        /// α of f(θ): the share of the samples kept away from the lobe (the paper: 0.1).
        glossy_alpha: f32 = 0.1,
        unit "", symbol "α", range 0.001..=10.0, cost "free", history false;
        /// ⚠[soler.glossy-variance] k in s = k·SP: s is "the exponent of the lobe" (the receiver's specular power SP),
        /// k = 1 the formula as printed; the gaussian's standard deviation √(π/s) goes as
        /// 1/√SP (our reading of the text's "variance … inversely proportional to the square
        /// root of the exponent"). Default 0.25: the lobe's screen-space spread is wider than
        /// its angle in space (measured: noise of the reflection ÷1.78 at SP 245 and ÷1.40 at
        /// SP 30 against uniform angles; k = 1 gave ÷1.11 and ÷1.19).
        glossy_sharpness: f32 = 0.25,
        unit "× SP", symbol "s", range 0.001..=100.0, cost "free", history false;
        /// ⚠[soler.glossy-min-power] Receivers with a specular power SP below this are sampled uniformly (their lobe is
        /// too wide to be worth concentrating the samples).
        glossy_min_power: f32 = 16.0,
        unit "SP", symbol "SP_min", range 0.0..=4096.0, cost "free", history false;
        /// a of Eq. 6, F_i = a·W(history) + (1 − a)·I_i: the warped history's weight where it
        /// is accepted and nothing moves (`pipeline.temporal = WarpedBlend`; ⚠[soler.temporal-a] the paper gives no
        /// value).
        temporal_a: f32 = 0.85,
        unit "", symbol "a", range 0.0..=0.99, cost "free (one pass at the G-buffer's resolution)", history false;
        /// ⚠[soler.temporal-motion] Adaptation of a to motion (004 §4: "adapting a to the moving speed"): a is scaled
        /// by m½ / (m½ + |m|), |m| the movement buffer's length, so it halves at m½ pixels
        /// per frame.
        temporal_motion_px: f32 = 4.0,
        unit "px/frame", symbol "m½", range 0.01..=1000.0, cost "free", history false;
        /// ⚠[soler.temporal-gloss] Adaptation of a to glossiness (004 §4 and §5.3: ghosting on shiny surfaces): a is
        /// divided by 1 + k_g · SI · √SP (the lobe's width goes as 1/√SP, Ramamoorthi's
        /// frequency estimate the paper cites); 0: no adaptation.
        temporal_gloss: f32 = 0.05,
        unit "", symbol "k_g", range 0.0..=10.0, cost "free", history false;
        /// ⚠[soler.temporal-reject] Rejection on depth: the history is dropped where the stored depth at the warped
        /// position differs from the point's depth in the previous camera by more than this
        /// fraction of it.
        reject_depth: f32 = 0.05,
        unit "× z", symbol "τ_z", range 0.0001..=10.0, cost "free", history false;
        /// Rejection on normals: the history is dropped where n · n_prev at the warped position
        /// is below this.
        reject_normal: f32 = 0.9,
        unit "cos", symbol "τ_n", range -1.0..=1.0, cost "free", history false;
        /// ⚠[soler.temporal-history] What the history holds: F_{i−1} (the filtered result) or I_{i−1} (Eq. 6 as printed).
        temporal_history: TemporalHistory = TemporalHistory::Filtered,
        unit "", symbol "", range 0..=1, cost "free", history true;
        /// What Eq. 6 blends (⚠[soler.temporal-order] Fig. 4's irradiance by default; the
        /// radiance after the albedo multiply as an option).
        temporal_quantity: TemporalQuantity = TemporalQuantity::Irradiance,
        unit "", symbol "", range 0..=1, cost "free", history true;
        /// Split distance of `pipeline.near_field`, in units of the scene's scale
        /// (`scale.reference`: the room the camera is in, else the bounding radius): the
        /// screen-space gather takes senders closer than it, the VPL gather the others.
        near_field_distance: f32 = 0.25,
        unit "× radius", symbol "d_near", range 0.001..=4.0, cost "free", history false;
        /// Visibility by solid voxelization (004 §4 "Visibility", Eisemann & Décoret): the
        /// scene's closed meshes are voxelized from the camera and each sample's path is
        /// marched through the grid of its level; off: every sample is visible (v_i = 1).
        visibility: bool = false,
        unit "", symbol "v_i", range 0..=1, cost "one voxelization of the scene, an AND per coarser level and a march of up to r steps per sample (the paper: 5.9×)", history false;
        /// Where the voxel grid is built (⚠[soler.voxel-grid] the screen's by default, as the
        /// text; the first gathered level's as an option).
        voxel_resolution: VoxelResolution = VoxelResolution::Screen,
        unit "", symbol "", range 0..=1, cost "screen: the voxelization at full resolution, 16 bytes per pixel, and an AND per level below the first gathered", history false;
        /// Depth slices of the voxel grid (004 §4: a grid "128 in depth and equal to the size
        /// of the screen in x and y").
        voxel_slices: u32 = 128,
        unit "slices", symbol "", range 32..=128, cost "memory: slices/8 bytes per texel of the first level", history false;
        /// Front of the grid's depth range, as a fraction of the scene's extent along the
        /// view axis (0: the nearest point of the scene's bounding sphere).
        voxel_depth_from: f32 = 0.0,
        unit "× extent", symbol "z₀", range 0.0..=1.0, cost "free (finer slices where the range is short)", history false;
        /// Back of the grid's depth range, as a fraction of the scene's extent along the view
        /// axis (1: the farthest point of its bounding sphere).
        voxel_depth_to: f32 = 1.0,
        unit "× extent", symbol "z₁", range 0.0..=1.0, cost "free", history false;
        /// ⚠[soler.voxel-slope-bias] Slope bias of the voxelization: a surface facing the viewer toggles its column at
        /// its depth moved back by b × its depth change across the texel (|∂z/∂x| + |∂z/∂y|;
        /// ½: the texel's farthest corner), so that a column turns solid only behind the whole
        /// texel's surface; 0: the paper's toggle at the texel centre's depth, which hides
        /// samples whose path passes a grazing surface's texel in front of the surface.
        voxel_slope_bias: f32 = 0.5,
        unit "× texel slope", symbol "b", range 0.0..=4.0, cost "free", history false;
        /// The slope bias's cap, in slices (an edge-on surface's slope is unbounded).
        voxel_slope_cap: f32 = 8.0,
        unit "slices", symbol "", range 0.0..=128.0, cost "free", history false;
        /// ⚠[soler.march-bias] Texels of the march skipped at both ends (the start/end bias: the receiver and the
        /// sender sit on the voxels of their own surfaces).
        march_bias_px: f32 = 1.5,
        unit "texels", symbol "", range 0.0..=16.0, cost "free", history false;
        /// The march tests the slice this many slices in front of its line (a surface's own
        /// voxels start at its slice).
        march_depth_bias: f32 = 1.0,
        unit "slices", symbol "", range 0.0..=16.0, cost "free", history false;
        /// The slice `soler.voxels.k` shows (−1: each column's filled fraction).
        voxel_view_slice: f32 = -1.0,
        unit "slice", symbol "", range -1.0..=127.0, cost "free (the viewer only)", history false;
    }
}

impl SolerSettings {
    /// The pyramid levels the gather runs on: start … start + levels − 1.
    pub fn gathered_levels(&self) -> std::ops::Range<u32> {
        let s = self.start_resolution.level();
        s..s + self.levels.max(1)
    }

    /// The split distance of the near field in scene units (`near_field_distance` × the
    /// scene's scale `radius`, `scale::scale_radius`).
    pub fn near_field_split(&self, radius: f32) -> f32 {
        self.near_field_distance * radius
    }

    /// 32-bit words per column of the voxel grid.
    pub fn voxel_words(&self) -> u32 {
        self.voxel_slices.clamp(32, 128).div_ceil(32)
    }

    /// The gathered levels whose ring starts beyond the diagonal of a `size` image, where it
    /// samples nothing (issue #51 point 4: at 128² with r = 40 from a quarter resolution,
    /// levels 4 and 5; level 3's ring, 160 … 320 px, joins only far corners). The first level
    /// samples the whole disc and is never off.
    pub fn levels_off_image(&self, size: (u32, u32)) -> Vec<u32> {
        let diagonal = (size.0 as f32).hypot(size.1 as f32);
        self.gathered_levels().skip(1).filter(|&k| 0.5 * self.radius_px * (1u64 << k) as f32 >= diagonal).collect()
    }

    /// The reach of the coarsest ring in G-buffer pixels: r · 2^{start + levels − 1}.
    pub fn reach_px(&self) -> f32 {
        self.radius_px * (1u64 << (self.gathered_levels().end - 1)) as f32
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue #51 point 4: at 128² the paper's setting (r = 40 from a quarter resolution, 4
    /// levels) gathers on levels 2 and 3 (level 3 only between far corners); at 1280×720, the
    /// paper's size, every level acts.
    #[test]
    fn the_levels_whose_ring_starts_beyond_the_image_are_named() {
        let s = SolerSettings::default();
        assert_eq!(s.levels_off_image((128, 128)), vec![4, 5]);
        assert!(s.levels_off_image((1280, 720)).is_empty());
        // Level 3's inner ring is 160 px: off a 100 × 100 image (diagonal 141 px), on a
        // 120 × 120 one (170 px).
        assert_eq!(SolerSettings { levels: 2, ..s.clone() }.levels_off_image((100, 100)), vec![3]);
        assert!(SolerSettings { levels: 2, ..s }.levels_off_image((120, 120)).is_empty());
    }
}
