//! The passes, one file each (docs/principles.md principle 1), in one folder per paper beside its
//! shader folders. A pass owns its pipelines, its settings and its textures, registers every
//! texture it writes in the buffer registry, and exposes `run(..)`. `frame.rs` runs the pass
//! each stage's choice names (see `docs/architecture.md`).
//!
//! | folder | paper | stage choices | shaders |
//! |---|---|---|---|
//! | `gbuffer`, `shadow`, `direct`, `compose`, `view` | all | stages 1, 2, 7's compose, the viewer | `gbuffer/`, `shadow/`, `direct/`, `compose/`, `view/` |
//! | `knecht/` | Knecht 002 | VPL source importance warping, visibility imperfect, shading points every pixel / interleaved tiles, VPL gather, geometry-aware filter, confidence merge | `knecht/` (`vpl/{importance,reduce,warp,bounce,irsm}`, `ism/`, `interleave/`, `temporal/`) |
//! | `hcb/` | Nguyen et al. 000 | shading points HCB samples, coherence splatting, HCB sample cache | `hcb/` |
//! | `reference/` | Knecht 002 §5.2 (the baseline) | VPL source uniform batches, visibility exact, running average | `reference/` (`{sample,shadow,gather,explain}`) |
//! | `soler/` | Soler et al. 004 | shading points mip levels, screen-space ring gather, joint bilateral upsampling | `soler/` |
//! | `ddgi/` | Majercik et al. 2019, 2021 (issue #56) | gather `Probes` | `ddgi/` |
//! | `rays/` | issue #56 (no paper: the tools under the GPU truth and DDGI) | rays through a two-level BVH in compute | `rays/` |

use crate::counters::prelude::*;

pub use crate::gpu::compute_pipeline;

pub mod bins;
pub mod compose;
pub mod ddgi;
pub mod direct;
pub mod direct_history;
pub mod emitters;
pub mod gautron;
pub mod gbuffer;
pub mod gbuffer_position;
pub mod hcb;
pub mod knecht;
pub mod on_read;
pub mod rays;
pub mod reference;
pub mod shadow;
pub mod sky;
pub mod soler;
pub mod stages;
pub mod view;

use glam::{Mat4, Vec4};

/// Camera uniform; WGSL twin: `shaders/common/camera.wgsl` `Camera` (size checked by a test).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct CameraUniform {
    pub view_proj: Mat4,
    pub prev_view_proj: Mat4,
    pub inv_view_proj: Mat4,
    pub view: Mat4,
    pub position: Vec4,
    pub viewport: Vec4,
    pub params: Vec4,
    /// x: mip level of the base colour texture in the G-buffer (< 0: chosen by the
    /// hardware); the light G-buffer blurs the colour of its VPLs with it (Knecht 002 §4.3).
    pub lod: Vec4,
}

pub use crate::scene::upload::InstanceUniform;

/// An unmapped buffer of `size` bytes.
pub fn buffer(device: &wgpu::Device, label: &str, size: u64, usage: wgpu::BufferUsages) -> wgpu::Buffer {
    device.counted_buffer(&wgpu::BufferDescriptor { label: Some(label), size, usage, mapped_at_creation: false })
}

/// A uniform buffer of `size` bytes written with `queue.write_buffer`.
pub fn uniform_buffer(device: &wgpu::Device, label: &str, size: u64) -> wgpu::Buffer {
    buffer(device, label, size, wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST)
}

/// Uniforms for dynamic offsets: `items` laid out every `stride` bytes in a buffer of
/// `slots` × `stride` bytes (the rest zero).
pub fn strided_bytes<T: bytemuck::Pod>(stride: u64, slots: usize, items: &[T]) -> Vec<u8> {
    let mut data = vec![0u8; stride as usize * slots.max(items.len())];
    for (k, item) in items.iter().enumerate() {
        let o = k * stride as usize;
        data[o..o + std::mem::size_of::<T>()].copy_from_slice(bytemuck::bytes_of(item));
    }
    data
}

/// Size of the screen-space compute tiles (`TILE` in `shaders/common/fullscreen.wgsl`).
pub const TILE: u32 = 8;

/// The bind groups described once (`gpu::bindings`, issue #52 point 3), each checked against
/// its shader by `tests/tests/shaders.rs`: every bind group the renderer makes comes from one
/// of these (the same test finds a layout or an entry written by hand, or a description not
/// listed here).
pub const BINDINGS: &[&crate::gpu::bindings::Bindings] = &[
    &compose::COMPOSE_BINDINGS,
    &compose::TONEMAP_BINDINGS,
    &compose::LUMINANCE_BINDINGS,
    &knecht::interleave::FILTER_BINDINGS,
    &knecht::temporal::CONFIDENCE_BINDINGS,
    &knecht::temporal::FILTER_MERGE_BINDINGS,
    &knecht::temporal::SPLIT_NORMAL_BINDINGS,
    &knecht::vpl_bounce::BOUNCE_BINDINGS,
    &reference::vpl::SAMPLE_BINDINGS,
    &direct::DIRECT_GBUFFER_BINDINGS,
    &direct::DIRECT_ATLAS_BINDINGS,
    &direct::DIRECT_DIFFUSE_BINDINGS,
    &hcb::build::LEVEL_INPUTS_BINDINGS,
    &hcb::build::SAMPLES_INPUTS_BINDINGS,
    &hcb::cache::CACHE_INPUTS_BINDINGS,
    &hcb::cache::CACHE_ARGS_BINDINGS,
    &hcb::cache::CACHE_REMOVAL_INPUTS_BINDINGS,
    &knecht::ism::RESOLVE_INPUTS_BINDINGS,
    &knecht::ism::RESOLVE_PULL_INPUTS_BINDINGS,
    &knecht::ism::PULL_INPUTS_BINDINGS,
    &knecht::ism::PUSH_INPUTS_BINDINGS,
    &gbuffer::CAMERA_BINDINGS,
    &gbuffer_position::POSITION_BINDINGS,
    &gbuffer_position::NO_EMISSION_BINDINGS,
    &gbuffer_position::NORMAL_BINDINGS,
    &gbuffer_position::MATERIAL_BINDINGS,
    &crate::scene::upload::INSTANCES_BINDINGS,
    &crate::scene::upload::MATERIAL_BINDINGS,
    &soler::voxels::GRID_BINDINGS,
    &soler::temporal::TEMPORAL_INPUTS_BINDINGS,
    &soler::bounces::BOUNCES_INPUTS_BINDINGS,
    &knecht::ism::SPLAT_INPUTS_BINDINGS,
    &knecht::irsm::SAMPLE_INPUTS_BINDINGS,
    &bins::BINS_BINDINGS,
    &soler::pyramid::VOTE_INPUTS_BINDINGS,
    &soler::pyramid::VOTE_RADIANCE_INPUTS_BINDINGS,
    &soler::upsample::UPSAMPLE_INPUTS_BINDINGS,
    &soler::explain::SOLER_INPUTS_BINDINGS,
    &soler::voxels::DOWN_INPUTS_BINDINGS,
    &soler::voxels::VIEW_INPUTS_BINDINGS,
    &gautron::stage::CREATE_GBUFFER_BINDINGS,
    &knecht::explain::VPL_INPUTS_BINDINGS,
    &gautron::splat::SPLAT_BINDINGS,
    &gautron::splat::SPLAT_BLEND_BINDINGS,
    &hcb::splat::SPLAT_INPUTS_BINDINGS,
    &view::VIEW_INPUTS_BINDINGS,
    &hcb::splat::NORMALIZE_INPUTS_BINDINGS,
    &hcb::gather::GATHER_INPUTS_BINDINGS,
    &crate::buffers::PROBE_INPUTS_BINDINGS,
    &reference::vpl_visibility::SHADOW_INPUTS_BINDINGS,
    &shadow::DIRECT_SHADOW_VIEW_BINDINGS,
    &knecht::interleave::SPLIT_INPUTS_BINDINGS,
    &knecht::interleave::MERGE_INPUTS_BINDINGS,
    &reference::explain::REFERENCE_INPUTS_BINDINGS,
    &knecht::vpl_importance::IMPORTANCE_INPUTS_BINDINGS,
    &knecht::vpl_importance::IMPORTANCE_REDUCE_BINDINGS,
    &knecht::vpl_importance::WARP_INPUTS_BINDINGS,
    &direct::DIRECT_INPUTS_BINDINGS,
    &reference::vpl_gather::INDIRECT_GATHER_INPUTS_BINDINGS,
    &hcb::splat::SPLAT_BINNED_BINDINGS,
    &knecht::interleave::GATHER_INPUTS_BINDINGS,
    &hcb::explain::HCB_INPUTS_BINDINGS,
    &hcb::explain::HCB_ARGS_BINDINGS,
    &gautron::explain::GAUTRON_INPUTS_BINDINGS,
    &gautron::vpl_records::VPL_RECORDS_BINDINGS,
    &gautron::stage::CREATE_BINDINGS,
    &gautron::at_samples::AT_SAMPLES_BINDINGS,
    &gautron::hemisphere::HEMISPHERE_CAMERAS_BINDINGS,
    &gautron::hemisphere::REDUCE_BINDINGS,
    &gautron::splat::RESOLVE_BINDINGS,
    &soler::explain::SOLER_RING_INPUTS_BINDINGS,
    &soler::hcb_gather::HCB_GATHER_INPUTS_BINDINGS,
    &soler::hcb_gather::HCB_GATHER_ARGS_BINDINGS,
    &soler::gather::GATHER_INPUTS_BINDINGS,
    &soler::upsample::RESOLVE_INPUTS_BINDINGS,
    &direct_history::SKY_HISTORY_INPUTS_BINDINGS,
    &rays::RAY_SCENE_BINDINGS,
    &rays::CAST_BINDINGS,
    &rays::pathtrace::PATHTRACE_BINDINGS,
    &ddgi::blend::BLEND_BINDINGS,
    &ddgi::trace::TRACE_BINDINGS,
    &ddgi::apply::APPLY_BINDINGS,
    &ddgi::apply::VIEW_BINDINGS,
    &ddgi::explain::EXPLAIN_BINDINGS,
];

/// A 2D render/storage target with the usages every registered buffer needs (sampling,
/// copying out for readback).
pub fn create_target(
    device: &wgpu::Device,
    label: &str,
    width: u32,
    height: u32,
    format: wgpu::TextureFormat,
    extra_usage: wgpu::TextureUsages,
) -> wgpu::Texture {
    device.counted_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_SRC | extra_usage,
        view_formats: &[],
    })
}

/// A depth-only render pipeline over the scene's vertices (`vs_main` of `module`, no culling,
/// `Depth32Float` with a less-than test): the primary shadow maps and the exact VPL maps.
/// With `cutout`, the fragment stage `fs_cutout` discards what an alpha mask cuts out (the
/// layout then has the scene's material group at index 2).
pub fn depth_only_pipeline(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::PipelineLayout,
    module: &wgpu::ShaderModule,
    cutout: bool,
) -> wgpu::RenderPipeline {
    device.counted_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(label),
        layout: Some(layout),
        vertex: wgpu::VertexState {
            module,
            entry_point: Some("vs_main"),
            compilation_options: Default::default(),
            buffers: &[Some(crate::scene::upload::vertex_layout())],
        },
        primitive: wgpu::PrimitiveState { cull_mode: None, ..Default::default() },
        depth_stencil: Some(wgpu::DepthStencilState {
            format: wgpu::TextureFormat::Depth32Float,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::Less),
            stencil: Default::default(),
            bias: Default::default(),
        }),
        multisample: Default::default(),
        fragment: cutout.then(|| wgpu::FragmentState {
            module,
            entry_point: Some("fs_cutout"),
            compilation_options: Default::default(),
            targets: &[],
        }),
        multiview_mask: None,
        cache: None,
    })
}

/// Default view of a texture, labelled.
pub fn view(texture: &wgpu::Texture, label: &str) -> wgpu::TextureView {
    texture.counted_view(&wgpu::TextureViewDescriptor { label: Some(label), ..Default::default() })
}

/// The first `size` bytes of `buffer`, bound with a dynamic offset (one slot of
/// [`strided_bytes`]).
pub fn dynamic_slot(buffer: &wgpu::Buffer, size: usize) -> wgpu::BindingResource<'_> {
    wgpu::BindingResource::Buffer(wgpu::BufferBinding {
        buffer,
        offset: 0,
        size: std::num::NonZeroU64::new(size as u64),
    })
}

/// `size` bytes of `buffer` from `offset` (None: to its end), as one binding of a buffer
/// that holds several parts (the explain replays' headers and lists).
pub fn buffer_part(buffer: &wgpu::Buffer, offset: u64, size: Option<u64>) -> wgpu::BindingResource<'_> {
    wgpu::BindingResource::Buffer(wgpu::BufferBinding { buffer, offset, size: size.and_then(wgpu::BufferSize::new) })
}

/// One compute pass of `pipeline` over `group` (with `offsets`), 8×8 workgroups covering
/// `size` texels.
pub fn dispatch_2d(
    encoder: &mut wgpu::CommandEncoder,
    label: &str,
    pipeline: &wgpu::ComputePipeline,
    group: &wgpu::BindGroup,
    offsets: &[u32],
    timestamp_writes: Option<wgpu::ComputePassTimestampWrites<'_>>,
    size: (u32, u32),
) {
    let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some(label), timestamp_writes });
    pass.set_pipe(pipeline);
    pass.set_group(0, group, offsets);
    pass.dispatch(size.0.div_ceil(8), size.1.div_ceil(8), 1);
}
