//! Dynamic diffuse global illumination on the GPU (issue #56 point 3; Majercik et al. 2019,
//! 2021; CPU twin `cpu::ddgi`; docs/architecture.md "Rays on the GPU"): the stage choice
//! `pipeline.gather = Probes`. Each frame the probes trace their rays through the GPU ray
//! caster and light the hits as the GPU truth does (`trace`), blend them into their
//! octahedral irradiance and distance tiles, classify and relocate themselves (`blend`), and
//! every pixel reads its cell's eight probes (`apply`); `stage` owns the grid and the buffers.

pub mod apply;
pub mod blend;
pub mod explain;
pub mod stage;
pub mod trace;

pub use crate::settings::ddgi::*;

use glam::{UVec3, Vec4};

use crate::cpu::ddgi::{DdgiParams, ProbeGrid};

/// WGSL twin: `DdgiGrid` in `shaders/ddgi/probes.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct DdgiGridParams {
    /// The first probe (xyz), the normal bias in world units (w).
    pub origin: Vec4,
    /// The spacing (xyz), the view bias in world units (w).
    pub spacing: Vec4,
    /// Probes along x, y, z; flags ([`CLASSIFY`], [`RELOCATE`], [`BOUNCES`], [`SKIP_INACTIVE`]).
    pub counts: [u32; 4],
    /// Irradiance interior texels and tiles a row, distance interior texels and tiles a row.
    pub atlas: [u32; 4],
    /// Classification's back-face share, relocation's least front-face distance (world), 1 for
    /// the glossy receiver.
    pub state: Vec4,
}

pub const CLASSIFY: u32 = 1;
pub const RELOCATE: u32 = 2;
pub const BOUNCES: u32 = 4;
/// Inactive probes cast `cpu::ddgi::INACTIVE_RAYS` rays and are not blended (with [`CLASSIFY`]).
pub const SKIP_INACTIVE: u32 = 8;

/// The twin's parameters of the settings (`cpu::ddgi::DdgiParams`).
pub fn twin_params(s: &DdgiSettings) -> DdgiParams {
    DdgiParams {
        hysteresis: s.hysteresis,
        distance_sharpness: s.distance_sharpness,
        max_distance: s.max_distance,
        normal_bias: s.normal_bias,
        view_bias: s.view_bias,
    }
}

impl DdgiGridParams {
    /// The grid's parameters for the shaders: `columns` the tiles a row of each atlas
    /// (`cpu::ddgi::Atlas::columns`).
    pub fn new(grid: &ProbeGrid, s: &DdgiSettings, columns: u32) -> Self {
        let scale = grid.spacing.min_element();
        let flags = (s.classification as u32 * CLASSIFY)
            | (s.relocation as u32 * RELOCATE)
            | (s.infinite_bounces as u32 * BOUNCES)
            | (s.skip_inactive as u32 * SKIP_INACTIVE);
        let (irr, dist) = (s.irradiance_texels.max(2), s.distance_texels.max(2));
        Self {
            origin: grid.origin.extend(s.normal_bias * scale),
            spacing: grid.spacing.extend(s.view_bias * scale),
            counts: [grid.counts.x, grid.counts.y, grid.counts.z, flags],
            atlas: [irr, columns, dist, columns],
            state: Vec4::new(s.backface_ratio, s.min_frontface * scale, s.receiver.flag(), 0.0),
        }
    }
}

/// The probe counts the settings ask for.
pub fn asked_counts(s: &DdgiSettings) -> UVec3 {
    UVec3::new(s.probes_x, s.probes_y, s.probes_z)
}

/// The most probes the device holds with `rays` rays each and the settings' tiles: the rays'
/// records and both atlases must each fit a storage buffer binding, and the trace's dispatch
/// (64 rays a workgroup) the workgroup limit.
pub fn max_probes(limits: &wgpu::Limits, s: &DdgiSettings) -> u32 {
    let binding = limits.max_storage_buffer_binding_size.min(limits.max_buffer_size);
    let rays = s.rays_per_probe.max(1) as u64;
    let tile = |n: u32| ((n.max(2) + 2) as u64).pow(2) * 16;
    let by_rays = binding / (rays * 16);
    let by_atlas = binding / tile(s.irradiance_texels.max(s.distance_texels)).max(1) / 2;
    let by_dispatch = limits.max_compute_workgroups_per_dimension as u64 * 64 / rays;
    by_rays.min(by_atlas).min(by_dispatch).min(u32::MAX as u64) as u32
}
