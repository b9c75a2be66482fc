//! Soler et al.'s multi-resolution screen-space indirect illumination (004 §3–4) as stage
//! choices: shading points "mip levels" (the G-buffer mipmapped by the voting filter of Eq. 5,
//! `pyramid`), the gather "screen-space ring gather" (Eq. 1–4 on every texel of each level,
//! `gather`) and the reconstruction "joint bilateral upsampling" (the continuous combination
//! of all levels, `upsample`); `stage` runs them for the frame. Shaders `shaders/soler/`; CPU
//! twin `cpu::soler` (the readings of the garbled formulas are documented there).
//!
//! Visibility (`voxels`): the camera-space solid voxelization of 004 §4, marched per sample.
//! As `pipeline.near_field`, the gather is the near field of a VPL gather.
//!
//! Temporal filtering (Eq. 6, `temporal`) is stage 7's choice `WarpedBlend`.
//!
//! Multi-bounce (004 §4, §5.3): `bounces` runs the pyramid, the gather and the upsampling
//! once per bounce on the previous bounce's light (`soler.bounce.n`), or one bounce per frame
//! in turn (`alternate_bounces`); `bounces.wgsl` adds them into `soler.indirect`.
//!
//! Glossy reflection (004 §4 "Screen-space importance sampling"): the gather also sums each
//! sample's light through the receiver's specular lobe, glossy receivers draw the samples'
//! angles from the paper's importance function (`shaders/soler/glossy.wgsl`, CPU twin
//! `cpu::soler_glossy`), and the specular light goes up its own upsampling chain.
//!
//! The lab's sample overlay (Fig. 3 right) replays a pixel's rings: `Renderer::soler_samples`.
//!
//! The mix with Nguyen et al. (`hcb_gather`): the rings of every level gathered at the HCB's
//! samples, spread by its coherence splatting (`Technique::SolerAtHcbSamples`).

pub use crate::settings::soler::*;

pub mod bounces;
pub mod explain;
pub mod gather;
pub mod hcb_gather;
pub mod pyramid;
pub mod stage;
pub mod temporal;
pub mod upsample;
pub mod voxels;

/// Uniform slot stride for dynamic offsets (the device's minimum alignment).
pub const STRIDE: u64 = 256;
