//! Gautron, Křivánek et al.'s irradiance cache splatting (003, SIGGRAPH 2008 course notes;
//! the text has no section numbers, so the docs cite its slide headings) as stage choices:
//! shading points "irradiance records" (created where the splatted coverage is insufficient,
//! "Irradiance Caching", "Algorithm"), the gather "hemisphere rasterization" ("From Ray
//! Tracing to Rasterization", "Simple plane sampling"), the reconstruction "weight splatting"
//! ("From Octree to Splatting": "Principle") and the temporal choice "record cache" (records
//! kept across frames, "Results"). Shaders `shaders/gautron/`; CPU twin `cpu::gautron` (the
//! readings of the inconsistent formulas are documented there).

use glam::{Mat4, Vec4};

pub use crate::passes::bins::SplatMethod;
pub use crate::settings::gautron::*;

pub mod at_samples;
pub mod explain;
pub mod hemisphere;
pub mod splat;
pub mod stage;
pub mod vpl_records;

/// One irradiance record on the GPU; WGSL twin: `Record` in `shaders/gautron/common.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuRecord {
    /// xyz: P_k, w: R_k after the clamps.
    pub position: Vec4,
    /// xyz: n_k, w: the harmonic mean distance H before the clamps.
    pub normal: Vec4,
    /// rgb: E_k, w: the frame it was made in.
    pub irradiance: Vec4,
    /// ∇_r E_k per colour channel (xyz).
    pub rot: [Vec4; 3],
    /// ∇_t E_k per colour channel (xyz).
    pub trans: [Vec4; 3],
    /// xy: the pixel it was made at, z: its linear view depth, w: 0 being computed, 1
    /// computed, 2 stale.
    pub pixel: Vec4,
    /// The scene draws its hemisphere saw: bit (draw mod 128) of the 128.
    pub seen: [u32; 4],
    /// xyz: Σ lum(L) cos θ Ω ω over the hemisphere (world space), the glossy receiver's
    /// direction sum (issue #51; `cpu::gautron::RecordTerms::dir`).
    pub dir: Vec4,
}

impl GpuRecord {
    /// Whether the record's hemisphere saw scene draw `draw` (or another of its bit).
    pub fn saw(&self, draw: usize) -> bool {
        self.seen[(draw % 128) / 32] & (1 << (draw % 32)) != 0
    }
}

/// Bytes per record on the GPU.
pub const RECORD_BYTES: u64 = std::mem::size_of::<GpuRecord>() as u64;

/// The cache's counters; WGSL twin: `CacheState`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct CacheState {
    /// Records in the cache.
    pub count: u32,
    /// First record of the last round's new ones.
    pub new_base: u32,
    /// New records of the last round.
    pub new_count: u32,
    /// Records made this frame.
    pub made: u32,
    /// Candidates the last round found (before the budget).
    pub candidates: u32,
    /// Stale records waiting to be computed again.
    pub stale: u32,
    /// Where the next search for stale records starts (round robin).
    pub cursor: u32,
    /// Stale records the last round computed again.
    pub refresh: u32,
    /// Records computed again this frame.
    pub refreshed: u32,
    pub pad: [u32; 3],
}

/// Uniform of every Gautron pass; WGSL twin: `GautronParams`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GautronParams {
    /// x: a, y: w_max, z: ∇r on, w: ∇t on.
    pub weight: Vec4,
    /// x: N, y: tiles per atlas row, z: tan(aperture / 2), w: near plane.
    pub hemisphere: Vec4,
    /// x: R_min, y: R_max (scene units); z: R_min, w: R_max (px).
    pub clamps: Vec4,
    /// x: creation tile, y: slots per round, z: capacity, w: far plane.
    pub creation: Vec4,
    /// x: frame, y: P00, z: P11, w: half the G-buffer's height.
    pub misc: Vec4,
    /// x: the "in front" test's tolerance × R_k (`f32::MAX`: no test); y, z, w: unused.
    pub rules: Vec4,
}

/// A record's hemisphere camera; WGSL twin: `HemisphereCamera` (create, hemisphere, reduce).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct HemisphereCamera {
    pub view_proj: Mat4,
    pub position: Vec4,
    pub t: Vec4,
    pub b: Vec4,
    pub n: Vec4,
    pub tile: Vec4,
}

/// Tiles per row of the hemisphere atlas for `slots` tiles (a square-ish grid).
pub fn atlas_grid(slots: u32) -> (u32, u32) {
    let per_row = (slots as f64).sqrt().ceil().max(1.0) as u32;
    (per_row, slots.div_ceil(per_row))
}
