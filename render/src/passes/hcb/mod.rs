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

pub use crate::settings::hcb::*;
use crate::settings::splat::IrradianceReceiver;

pub mod build;
pub mod cache;
pub mod explain;
pub mod gather;
pub mod splat;
pub mod stage;

pub use build::{COUNTER_BYTES, CacheViews, HcbPass, level_sizes};
pub use gather::{GatherSet, HcbGatherParams, HcbGatherPass};
pub use splat::HcbSplatPass;

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

/// How many samples the HCB's lists (the frame's and the cache's) hold for a `width` ×
/// `height` G-buffer on `device`: every pixel could be a level-0 sample, but a list is one
/// storage binding, which the device bounds (`max_storage_buffer_binding_size`: 128 MiB on
/// lavapipe, 1.68 M samples of 80 bytes, where 1920×1080 has 2.07 M pixels; the list of every
/// pixel made the HCB presets panic at 1080p there). The shaders drop the samples past it
/// (`slot < arrayLength`) and the counters still count them; a frame has far fewer samples
/// than pixels (θmax and dmax merge most of them into coarser levels).
pub fn list_capacity(device: &wgpu::Device, width: u32, height: u32) -> u32 {
    let limits = device.limits();
    let bytes = limits.max_storage_buffer_binding_size.min(limits.max_buffer_size);
    let most = (bytes / std::mem::size_of::<GpuHcbSample>() as u64).min(u32::MAX as u64) as u32;
    (width.max(1) * height.max(1)).min(most).max(1)
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
