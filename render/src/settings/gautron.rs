//! The settings of Gautron, Křivánek et al.'s irradiance cache splatting (003; the text has
//! no section numbers, so the docs cite its slide headings). The passes are in
//! `passes/gautron/`, the CPU twin in `cpu::gautron`.

use super::splat::{IrradianceReceiver, SplatMethod};
use crate::{settings_enum, settings_group};

settings_enum! {
    /// The directions the 126.87° camera misses ("Simple plane sampling" quotes Larsen et
    /// al.'s 86 % of the incoming directions; the square pyramid sees 83.1 % of a uniform
    /// sky's irradiance, measured in tests/gautron_cpu.rs).
    pub enum BorderCompensation {
        /// No compensation: the irradiance misses the grazing band (16.9 % of a uniform
        /// sky's at 126.87°).
        Off = "off",
        /// The text's Ω_border = Ω_p + cos θ_border · δφ, reflected with the border pixel's own
        /// cos θ: the band's solid angle counted at the border's cosine (overestimates, since
        /// the band's cosines fall from cos θ_border to 0: a uniform sky's E is 1.18·π).
        Paper = "paper (Ω_p + cos θ_b δφ)",
        /// Our reading: the band θ_border … 90° over the pixel's δφ weighted by its own cosines,
        /// ∫ cos θ sin θ dθ δφ = cos² θ_border / 2 · δφ: exact for uniform incident radiance.
        CosineWeighted = "cosine-weighted (cos² θ_b / 2 · δφ)",
    }
    default CosineWeighted
}

settings_enum! {
    /// What becomes of the records between frames (stage 7, "Results": "the scene being
    /// static, the irradiance cache is reused across frames").
    pub enum ReusePolicy {
        /// Records persist while the scene, its lights and the record settings stay the
        /// same; off-screen records are kept (a camera that returns finds them).
        KeepAll = "keep all",
        /// As KeepAll, but records whose position leaves the view frustum are dropped (a
        /// bounded cache for long camera paths).
        DropOffscreen = "drop off-screen",
    }
    default KeepAll
}

settings_enum! {
    /// What the record cache does with the records a change invalidates (stage 7; the text
    /// only reuses records of static scenes, "Results"): records whose hemisphere saw a moved
    /// object (old or new place), and every record when a light or the direct light's
    /// settings change. Records lying on a moved object are always dropped.
    pub enum Invalidation {
        /// Invalid records are dropped: the creation makes new ones where the coverage falls
        /// short (black until then when the round budget runs out).
        Drop = "drop",
        /// Invalid records stay, marked stale, and are splatted with their old value until
        /// a round computes them again at the same place (after the new records, round
        /// robin): no holes, the change shows with a delay.
        Refresh = "refresh in place",
    }
    default Refresh
}

settings_enum! {
    /// The creation tiles of a frame's rounds (⚠[gautron.creation-per-tile]: "Algorithm" tests
    /// the pixels one by one and splats each new record before testing the next; the GPU takes
    /// one candidate per tile and round).
    pub enum CreationSchedule {
        /// Coarse to fine: round k of K uses tiles of `creation_tile_px` × 2^(K−1−k) pixels
        /// (at most 64), so the first rounds place sparse records whose splats cover the open
        /// areas, and the finer rounds add records only where those leave pixels uncovered:
        /// the spacing follows the local a·R_k, as the sequential scan's does (fewer records:
        /// 305 against 677 at 256²). Only the last round has the finest tiles, so while the
        /// scene animates the pixels that moved objects uncover wait longer for new records
        /// (`popping_while_the_scene_animates` in tests/gautron_cache.rs run with it: 692
        /// uncovered pixel-frames against 2 with one tile size).
        CoarseToFine = "coarse to fine",
        /// Every round uses `creation_tile_px`: one record per tile wherever a tile has an
        /// uncovered pixel, so the tile size, not a·R_k, sets the density.
        Fixed = "one tile size",
    }
    default Fixed
}

/// Largest creation tile side (the candidates' key packs the index in the tile in 12 bits).
pub const MAX_CREATION_TILE: u32 = 64;

settings_group! {
    /// Gautron et al.'s irradiance cache splatting (003): records, their hemispheres, the
    /// splatting of Ward's weights and the cache across frames.
    pub struct GautronSettings: "gautron" {
        /// Ward's accuracy a ("Irradiance Interpolation"): a record contributes where its
        /// weight w_k > 1/a, inside the sphere of radius a·R_k ("Principle"); new records are
        /// made where no record passes (the creation's "W < a" read as Σ w < 1/a).
        accuracy: f32 = 0.4,
        unit "", symbol "a", range 0.02..=2.0, cost "records grow as 1/a²", history true;
        /// Pixels per side of each record's hemisphere tile ("Simple plane sampling").
        hemisphere_resolution: u32 = 32,
        unit "px", symbol "N", range 4..=128, cost "raster and reduction grow as N² per record", history true;
        /// Full aperture of the hemisphere camera (Larsen et al.: 126.87°, tan = 2; the text
        /// quotes 86 % of the directions, the square sees 83.1 % of a uniform sky's irradiance).
        aperture_deg: f32 = 126.87,
        unit "°", symbol "", range 60.0..=170.0, cost "free (wider: coarser pixels)", history true;
        /// How the directions outside the aperture are compensated ("Simple plane sampling";
        /// ⚠[gautron.border-cosine]).
        border_compensation: BorderCompensation = BorderCompensation::CosineWeighted,
        unit "", symbol "", range 0..=2, cost "free", history true;
        /// Extrapolate with the rotational gradient of E_k (Ward and Heckbert 1992, as
        /// "Irradiance Interpolation" writes it: (n_k × n) · grad_r E_k).
        rotational_gradient: bool = true,
        unit "", symbol "", range 0..=1, cost "free", history false;
        /// Extrapolate with the translational gradient of E_k ((P − P_k) · grad_t E_k; from
        /// the hemisphere's texel edges, Ward and Heckbert 1992, Křivánek et al. 2005).
        translational_gradient: bool = true,
        unit "", symbol "", range 0..=1, cost "free", history false;
        /// New records per creation round (the per-round budget; one hemisphere tile each).
        records_per_round: u32 = 64,
        unit "records", symbol "", range 1..=1024, cost "one hemisphere raster each", history true;
        /// Creation rounds per frame: splat, find the under-covered pixels, create, repeat.
        rounds: u32 = 4,
        unit "rounds", symbol "K", range 1..=32, cost "one splat and one creation pass each", history true;
        /// Side of the tiles in which the creation picks one under-covered pixel per round
        /// (⚠[gautron.creation-per-tile]).
        creation_tile_px: u32 = 8,
        unit "px", symbol "", range 2..=64, cost "smaller: more candidates per round", history true;
        /// The tiles of the frame's rounds: coarse to fine, or one size.
        creation_schedule: CreationSchedule = CreationSchedule::Fixed,
        unit "", symbol "", range 0..=1, cost "coarse to fine: fewer records where they are large", history true;
        /// Records the cache can hold (creation stops when full).
        capacity: u32 = 16384,
        unit "records", symbol "", range 16..=65536, cost "memory 176 B per record", history true;
        /// Clamp R_k (⚠[gautron.r-clamps] not in 003, which uses R_k = H as computed; Tabellion
        /// and Lamorlette 2004, Křivánek et al. 2006): to `r_min_scene` … `r_max_scene` of the
        /// scene's radius, then to `r_min_px` … `r_max_px` on the screen at the record's depth.
        /// Off: R_k = H (a record that sees no surface covers every point its normal allows).
        r_clamps: bool = true,
        unit "", symbol "", range 0..=1, cost "free (off: records near corners shrink to points, over open space cover the screen)", history true;
        /// Lower clamp of R_k projected on the screen at the record's depth (not in 003).
        r_min_px: f32 = 20.0,
        unit "px", symbol "R_min", range 0.0..=1000.0, cost "free (larger: fewer records)", history true;
        /// Upper clamp of R_k projected on the screen at the record's depth (not in 003).
        r_max_px: f32 = 150.0,
        unit "px", symbol "R_max", range 1.0..=4000.0, cost "free (smaller: more records)", history true;
        /// Lower clamp of R_k in scene units, as a fraction of the scene's scale
        /// (`scale.reference`: the room the camera is in, else the bounding radius; not in 003).
        r_min_scene: f32 = 0.005,
        unit "× radius", symbol "", range 0.0..=10.0, cost "free", history true;
        /// Upper clamp of R_k in scene units, as a fraction of the scene's scale
        /// (`scale.reference`; not in 003).
        r_max_scene: f32 = 1.0,
        unit "× radius", symbol "", range 0.0001..=100.0, cost "free", history true;
        /// Neighbour clamping (⚠[gautron.neighbour-clamping] Křivánek et al. 2006; not in 003): each new record's R_k and
        /// its overlapping neighbours' are clamped to R_j + |P_k − P_j| (the harmonic mean
        /// distance's triangle inequality), so that records near geometry a neighbour saw
        /// do not spread over it. Applies to the records made from now on.
        neighbour_clamping: bool = true,
        unit "", symbol "", range 0..=1, cost "new records × cached records distance tests per round", history false;
        /// Ward's weight is unbounded at P = P_k: it is clamped to this before blending
        /// (⚠[gautron.weight-clamp] not in 003). It must exceed 1/a, or no record passes.
        weight_clamp: f32 = 100.0,
        unit "", symbol "w_max", range 1.0..=1.0e6, cost "free", history false;
        /// Ward's "in front" test (Ward 1988; not in 003, whose interpolation takes every record
        /// whose weight passes): a record lying in front of P, (P − P_k)·(n + n_k)/2 <
        /// −tol·R_k, does not contribute (its hemisphere saw P's surroundings from the other
        /// side of a fold).
        in_front_test: bool = true,
        unit "", symbol "", range 0..=1, cost "free", history false;
        /// The "in front" test's tolerance tol in units of R_k (⚠[gautron.in-front-tolerance]
        /// GI Lab's 0.05; Ward's test has 0: a record a hair in front of a flat receiver,
        /// through the hemisphere camera's near-plane offset, would then drop out).
        in_front_tolerance: f32 = 0.05,
        unit "× R_k", symbol "tol", range 0.0..=1.0, cost "free", history false;
        /// What becomes of the records between frames with stage 7's record cache (without
        /// it every frame starts from an empty cache: the cold-cache cost).
        reuse: ReusePolicy = ReusePolicy::KeepAll,
        unit "", symbol "", range 0..=1, cost "free", history true;
        /// What becomes of the records a moving object or a light change invalidates
        /// (⚠[gautron.invalidation]).
        invalidation: Invalidation = Invalidation::Refresh,
        unit "", symbol "", range 0..=1, cost "refresh: one hemisphere per stale record", history false;
        /// How the splat sums the records at the pixels.
        splat: SplatMethod = SplatMethod::Auto,
        unit "", symbol "", range 0..=2, cost "blend: the quads' overdraw; binned: one pass over the screen per splat", history false;
        /// How each pixel reflects the splatted irradiance: ⚠[gautron.glossy-receiver] the
        /// text reflects it diffusely (its records hold irradiance), so glossy surfaces lose
        /// their indirect specular light; GI Lab keeps each record's mean incident direction
        /// (Σ lum(L) cos θ Ω ω over its hemisphere, or over its VPLs), splats it with Ward's
        /// weights and lights the receiver's specular lobe from it
        /// (`cpu::brdf::receive_irradiance`).
        receiver: IrradianceReceiver = IrradianceReceiver::Glossy,
        unit "", symbol "f_x", range 0..=1, cost "3 more reduction terms per record, a third splat target (16 B a pixel)", history false;
    }
}

impl GautronSettings {
    /// The creation tile of round `k` of the frame's `gautron.rounds`.
    pub fn round_tile(&self, k: u32) -> u32 {
        let base = self.creation_tile_px.clamp(1, MAX_CREATION_TILE);
        let rounds = self.rounds.max(1);
        match self.creation_schedule {
            CreationSchedule::Fixed => base,
            CreationSchedule::CoarseToFine => {
                let up = rounds.saturating_sub(1).saturating_sub(k).min(6);
                (base << up).min(MAX_CREATION_TILE).max(base)
            }
        }
    }
}
