//! Stage 4, imperfect shadow maps (Knecht 002 §2.6.5 after Ritschel et al. 2008): a point
//! cloud on the scene's triangles, splatted into one paraboloid map per VPL in one atlas
//! (`ism.atlas`), then pull-push fills the holes (`ism.atlas_pulled`, one mip per level).
//! Shaders: `shaders/knecht/ism/{splat,resolve,pull_push}.wgsl`, `shaders/common/ism.wgsl`; CPU
//! twins in `cpu::knecht`.
//!
//! Point cloud (§2.6.5, §5.1): triangles are chosen with probability ∝ area × the object's
//! sample weight (`Material::sample_weight`), a point inside by uniform barycentrics; random
//! or low-discrepancy (Halton; the thesis' future work asks for quasi-random placement).
//! Each point keeps its triangle and barycentrics ([`CloudPoint`]); the GPU gets its
//! object-space position and normal with the draw it belongs to, so that it follows the
//! object's animation (our scenes animate rigidly, where the two are the same).

use crate::counters::prelude::*;

use glam::Vec4;

use crate::buffers::{BufferKind, BufferRegistry};
use crate::gpu::GpuContext;
use crate::gpu::bindings::{Bindings, Kind, binding};
use crate::scene::{Scene, SceneState};
use crate::timing::PassRec;
use crate::timing::Slot;

pub use super::point_cloud::{CloudPoint, GpuPoint, GpuPointSurface, PointCloud, PointPlacement};
pub use crate::settings::knecht::{BounceShadowTest, IsmSettings, PushBehind, SplatDepth};

/// Bind group `ism.splat.inputs` of `shaders/knecht/ism/splat.wgsl` (group 0; the IRSM's splat
/// binds an equal group of its own, `irsm.splat.inputs`).
pub const SPLAT_INPUTS_BINDINGS: Bindings = Bindings {
    label: "ism.splat.inputs",
    shader: "knecht/ism/splat.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "sp", Kind::UniformDynamic),
        binding(1, "points", Kind::Storage { read_only: true }),
        binding(2, "instances", Kind::Storage { read_only: true }),
        binding(3, "vpls", Kind::Storage { read_only: true }),
        binding(4, "depth", Kind::Storage { read_only: false }),
        binding(5, "owner", Kind::Storage { read_only: false }),
    ],
};

/// Bind group `ism.pull.inputs` of `shaders/knecht/ism/pull_push.wgsl` (group 0 of
/// `cs_pull`): one level of the pull (Knecht 002 §3.3's pull-push).
pub const PULL_INPUTS_BINDINGS: Bindings = Bindings {
    label: "ism.pull.inputs",
    shader: "knecht/ism/pull_push.wgsl",
    group: 0,
    entry: Some("cs_pull"),
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "lp", Kind::UniformDynamic),
        binding(1, "src", Kind::Texture { filterable: false }),
        binding(2, "dst", Kind::StorageTexture(wgpu::TextureFormat::R32Float)),
    ],
};

/// Bind group `ism.push.inputs` of `shaders/knecht/ism/pull_push.wgsl` (group 0 of
/// `cs_push`): one level of the push, filling the finer level's holes in place.
pub const PUSH_INPUTS_BINDINGS: Bindings = Bindings {
    label: "ism.push.inputs",
    shader: "knecht/ism/pull_push.wgsl",
    group: 0,
    entry: Some("cs_push"),
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "lp", Kind::UniformDynamic),
        binding(1, "src", Kind::Texture { filterable: false }),
        binding(3, "fine", Kind::StorageTextureReadWrite(wgpu::TextureFormat::R32Float)),
    ],
};

/// Bind group `ism.resolve.inputs` of `shaders/knecht/ism/resolve.wgsl` (group 0 of
/// `cs_resolve`): the splatted distances resolved into one level (level 0 of the pulled atlas
/// without pull-push levels, `ism.atlas` when it is read).
pub const RESOLVE_INPUTS_BINDINGS: Bindings = Bindings {
    label: "ism.resolve.inputs",
    shader: "knecht/ism/resolve.wgsl",
    group: 0,
    entry: Some("cs_resolve"),
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "depth", Kind::Storage { read_only: true }),
        binding(1, "atlas", Kind::StorageTexture(wgpu::TextureFormat::R32Float)),
        binding(2, "lp", Kind::UniformDynamic),
    ],
};

/// Bind group `ism.resolve_pull.inputs` of `shaders/knecht/ism/resolve.wgsl` (group 0 of
/// `cs_resolve_pull`): the splatted distances resolved into level 0 of the pulled atlas and
/// pulled into its level 1 in one pass (issue #53).
pub const RESOLVE_PULL_INPUTS_BINDINGS: Bindings = Bindings {
    label: "ism.resolve_pull.inputs",
    shader: "knecht/ism/resolve.wgsl",
    group: 0,
    entry: Some("cs_resolve_pull"),
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "depth", Kind::Storage { read_only: true }),
        binding(1, "atlas", Kind::StorageTexture(wgpu::TextureFormat::R32Float)),
        binding(2, "lp", Kind::UniformDynamic),
        binding(3, "level1", Kind::StorageTexture(wgpu::TextureFormat::R32Float)),
    ],
};

/// One [`LevelParams`] slot of `buffer`, bound with a dynamic offset (the pull-push's and the
/// resolve's uniform).
fn level_binding(buffer: &wgpu::Buffer) -> wgpu::BindingResource<'_> {
    wgpu::BindingResource::Buffer(wgpu::BufferBinding {
        buffer,
        offset: 0,
        size: std::num::NonZeroU64::new(std::mem::size_of::<LevelParams>() as u64),
    })
}

/// Bind groups of one frame's splats and resolve ([`IsmPass::begin`]).
pub struct IsmJob {
    splat: wgpu::BindGroup,
    /// `cs_resolve_pull`'s group when pull-push has levels, else `cs_resolve`'s into level 0.
    resolve: wgpu::BindGroup,
}

/// Bind group layout of `shaders/knecht/ism/splat.wgsl` (the ISMs' and the IRSM baseline's splats):
/// params (dynamic), points, instances, VPLs, distances, IRSM owners.
pub fn splat_layout(device: &wgpu::Device, label: &str) -> wgpu::BindGroupLayout {
    SPLAT_INPUTS_BINDINGS.layout_labelled(device, label)
}

/// Layout of the ISM atlas: `cols` × `rows` maps of `size`², map = VPL index.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct IsmLayout {
    pub size: u32,
    pub cols: u32,
    pub rows: u32,
}

impl IsmLayout {
    pub fn new(vpls: u32, size: u32) -> Self {
        let n = vpls.max(1);
        let cols = (n as f64).sqrt().ceil() as u32;
        Self { size, cols, rows: n.div_ceil(cols) }
    }
    pub fn width(&self) -> u64 {
        self.cols as u64 * self.size as u64
    }
    pub fn height(&self) -> u64 {
        self.rows as u64 * self.size as u64
    }
    /// Whether the atlas fits textures of `max_dim` texels a side and a splat buffer of
    /// `max_buffer` bytes (4 bytes per texel).
    pub fn fits(&self, max_dim: u32, max_buffer: u64) -> bool {
        self.width() <= max_dim as u64
            && self.height() <= max_dim as u64
            && self.width() * self.height() * 4 <= max_buffer
    }
    /// The most VPLs whose atlas of `size`² maps fits.
    pub fn largest_count(size: u32, max_dim: u32, max_buffer: u64) -> u32 {
        let (mut lo, mut hi) = (0u32, 1 << 20);
        while lo < hi {
            let mid = (lo + hi).div_ceil(2);
            if Self::new(mid, size).fits(max_dim, max_buffer) { lo = mid } else { hi = mid - 1 }
        }
        lo
    }
    /// The largest power-of-two map size (≥ 32) at which `vpls` maps fit, if any.
    pub fn largest_size(vpls: u32, max_dim: u32, max_buffer: u64) -> Option<u32> {
        (5..=12).rev().map(|k| 1u32 << k).find(|&s| Self::new(vpls, s).fits(max_dim, max_buffer))
    }
}

/// Uniform of the splat pass; WGSL twin: `SplatParams` in `shaders/knecht/ism/splat.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SplatParams {
    /// Points, VPLs of the bounce, atlas columns, map size.
    pub counts: [u32; 4],
    /// Eye offset, point radius r_s, largest splat half-size, splat scale.
    pub geom: Vec4,
    /// x: the bounce's first VPL slot, y: its first map (tile) in the atlas, z: splat depth
    /// (0 the point's distance, 1 its tangent plane).
    pub slots: [u32; 4],
}

/// Most light bounces (`vpl.bounces`); one splat uniform slot each.
pub const MAX_BOUNCES: u32 = 6;

/// Uniform of one pull-push level; WGSL twin: `LevelParams` in `shaders/knecht/ism/pull_push.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct LevelParams {
    pub threshold: Vec4,
    pub tile: [u32; 4],
}

const LEVEL_STRIDE: u64 = 256;
/// Uniform slots of one pull-push call: pull and push of up to 8 levels.
const LEVEL_SLOTS: u64 = 16;

/// What a frame's ISMs are made from.
#[derive(Clone, Copy, Debug)]
pub struct IsmFrame {
    /// VPLs of one bounce (N).
    pub vpls: u32,
    /// Light bounces B: the VPL list holds B sets of N, bounce b in slots b·N … b·N + N − 1,
    /// and the atlas one map per slot.
    pub bounces: u32,
    /// Eye offset along the VPL normal (scene units).
    pub eye_offset: f32,
    /// Scene extent (thresholds are fractions of it).
    pub extent: f32,
}

pub struct IsmPass {
    cloud_key: Option<(u32, PointPlacement)>,
    pub cloud: PointCloud,
    /// `ism.points`: the cloud's [`GpuPoint`]s.
    pub points: wgpu::Buffer,
    /// `ism.point_surfaces`: the cloud's [`GpuPointSurface`]s.
    pub surfaces: wgpu::Buffer,
    /// Splatted distances of the atlas (inverted f32 bits, 0 = empty), read by the bounce pass.
    pub depth: wgpu::Buffer,
    /// `ism.atlas`, the maps as splatted: resolved from `depth` only when read (issue #53;
    /// the frame resolves straight into level 0 of `pulled`).
    pub atlas: wgpu::Texture,
    pub pulled: wgpu::Texture,
    pub layout_info: IsmLayout,
    levels: u32,
    splat_layout: wgpu::BindGroupLayout,
    resolve_layout: wgpu::BindGroupLayout,
    resolve_pull_layout: wgpu::BindGroupLayout,
    pull_layout: wgpu::BindGroupLayout,
    push_layout: wgpu::BindGroupLayout,
    splat_pipeline: wgpu::ComputePipeline,
    resolve_pipeline: wgpu::ComputePipeline,
    resolve_pull_pipeline: wgpu::ComputePipeline,
    pull_pipeline: wgpu::ComputePipeline,
    push_pipeline: wgpu::ComputePipeline,
    splat_params: wgpu::Buffer,
    level_params: wgpu::Buffer,
    /// The splat shader's IRSM owner binding, unused by the ISMs.
    no_owner: wgpu::Buffer,
    /// `ism.atlas`'s resolve when it is read: the whole atlas from row 0 (a [`LevelParams`]
    /// of zeros), armed by every frame that splatted.
    atlas_rows: wgpu::Buffer,
    atlas_on_read: std::sync::Arc<crate::passes::on_read::OnRead>,
}

impl IsmPass {
    pub fn new(ctx: &GpuContext) -> Self {
        let device = &ctx.device;
        let splat_layout = splat_layout(device, "ism.splat.inputs");
        let resolve_layout = RESOLVE_INPUTS_BINDINGS.layout(device);
        let resolve_pull_layout = RESOLVE_PULL_INPUTS_BINDINGS.layout(device);
        let pull_layout = PULL_INPUTS_BINDINGS.layout(device);
        let push_layout = PUSH_INPUTS_BINDINGS.layout(device);
        let m_splat = crate::shaders::create_module(device, "knecht/ism/splat.wgsl");
        let m_resolve = crate::shaders::create_module(device, "knecht/ism/resolve.wgsl");
        let m_pp = crate::shaders::create_module(device, "knecht/ism/pull_push.wgsl");
        let splat_pipeline =
            crate::passes::compute_pipeline(device, "ism.splat", &m_splat, "cs_splat", &[&splat_layout]);
        let resolve_pipeline =
            crate::passes::compute_pipeline(device, "ism.resolve", &m_resolve, "cs_resolve", &[&resolve_layout]);
        let resolve_pull_pipeline = crate::passes::compute_pipeline(
            device,
            "ism.resolve_pull",
            &m_resolve,
            "cs_resolve_pull",
            &[&resolve_pull_layout],
        );
        let pull_pipeline = crate::passes::compute_pipeline(device, "ism.pull", &m_pp, "cs_pull", &[&pull_layout]);
        let push_pipeline = crate::passes::compute_pipeline(device, "ism.push", &m_pp, "cs_push", &[&push_layout]);
        let splat_params = device.counted_buffer(&wgpu::BufferDescriptor {
            label: Some("ism.splat.params"),
            size: LEVEL_STRIDE * MAX_BOUNCES as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let level_params = device.counted_buffer(&wgpu::BufferDescriptor {
            label: Some("ism.pull_push.params"),
            size: LEVEL_STRIDE * LEVEL_SLOTS * (MAX_BOUNCES as u64 + 1),
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let no_owner = device.counted_buffer(&wgpu::BufferDescriptor {
            label: Some("ism.no_owner"),
            size: 4,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        let atlas_rows = device.counted_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("ism.atlas.on_read.rows"),
            contents: bytemuck::bytes_of(&LevelParams { threshold: Vec4::ZERO, tile: [0; 4] }),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let layout_info = IsmLayout::new(1, 32);
        let (depth, atlas, pulled) = Self::targets(device, layout_info, 0);
        let atlas_on_read = Self::atlas_on_read(ctx, layout_info);
        let (points, surfaces) = Self::point_buffers(device, &PointCloud::empty());
        Self {
            cloud_key: None,
            cloud: PointCloud::empty(),
            points,
            surfaces,
            depth,
            atlas,
            pulled,
            layout_info,
            levels: 0,
            splat_layout,
            resolve_layout,
            resolve_pull_layout,
            pull_layout,
            push_layout,
            splat_pipeline,
            resolve_pipeline,
            resolve_pull_pipeline,
            pull_pipeline,
            push_pipeline,
            splat_params,
            level_params,
            no_owner,
            atlas_rows,
            atlas_on_read,
        }
    }

    fn atlas_on_read(ctx: &GpuContext, l: IsmLayout) -> std::sync::Arc<crate::passes::on_read::OnRead> {
        crate::passes::on_read::OnRead::new(ctx, "ism.resolve", (l.width() as u32, l.height() as u32))
    }

    fn point_buffers(device: &wgpu::Device, cloud: &PointCloud) -> (wgpu::Buffer, wgpu::Buffer) {
        let zero = [GpuPoint { position: [0.0; 3], draw: 0, normal: [0.0; 3], material: 0 }];
        let points = device.counted_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("ism.points"),
            contents: bytemuck::cast_slice(if cloud.gpu.is_empty() { &zero } else { &cloud.gpu }),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let zero = [GpuPointSurface { albedo: [0.0; 4], material: [0.0; 4] }];
        let surfaces = device.counted_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("ism.point_surfaces"),
            contents: bytemuck::cast_slice(if cloud.surfaces.is_empty() { &zero } else { &cloud.surfaces }),
            usage: wgpu::BufferUsages::STORAGE,
        });
        (points, surfaces)
    }

    fn targets(device: &wgpu::Device, l: IsmLayout, levels: u32) -> (wgpu::Buffer, wgpu::Texture, wgpu::Texture) {
        let (w, h) = (l.width() as u32, l.height() as u32);
        let depth = device.counted_buffer(&wgpu::BufferDescriptor {
            label: Some("ism.splat_depth"),
            size: 4 * w as u64 * h as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let atlas = crate::passes::create_target(
            device,
            "ism.atlas",
            w,
            h,
            wgpu::TextureFormat::R32Float,
            wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::COPY_DST,
        );
        let pulled = device.counted_texture(&wgpu::TextureDescriptor {
            label: Some("ism.atlas_pulled"),
            size: wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
            mip_level_count: levels + 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::R32Float,
            usage: wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::STORAGE_BINDING
                | wgpu::TextureUsages::COPY_SRC
                | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        });
        (depth, atlas, pulled)
    }

    /// Builds the point cloud when its settings or the scene changed and sizes the atlas for
    /// `vpls` maps (all bounces; the caller checked that it fits). Returns whether textures
    /// were recreated.
    pub fn ensure(
        &mut self,
        ctx: &GpuContext,
        scene: &Scene,
        state: &SceneState,
        s: &IsmSettings,
        vpls: u32,
        rebuild_cloud: bool,
    ) -> bool {
        let key = (s.points, s.placement);
        if rebuild_cloud || self.cloud_key != Some(key) {
            self.cloud = PointCloud::build(scene, state, s.points, s.placement);
            (self.points, self.surfaces) = Self::point_buffers(&ctx.device, &self.cloud);
            self.cloud_key = Some(key);
        }
        let l = IsmLayout::new(vpls, s.map_size);
        let levels = s.pull_push_levels.min(s.map_size.ilog2());
        if l == self.layout_info && levels == self.levels {
            return false;
        }
        (self.depth, self.atlas, self.pulled) = Self::targets(&ctx.device, l, levels);
        self.atlas_on_read = Self::atlas_on_read(ctx, l);
        self.layout_info = l;
        self.levels = levels;
        true
    }

    pub fn register(&self, reg: &mut BufferRegistry) {
        reg.register_derived(
            "ism.atlas",
            BufferKind::Data,
            "imperfect shadow maps as splatted: one paraboloid map per VPL (map = VPL index), distance from the VPL in scene units, 1e30 in holes",
            &self.atlas,
            self.atlas_on_read.clone(),
        );
        reg.register(
            "ism.atlas_pulled",
            BufferKind::Data,
            "the ISM atlas after pull-push: mip 0 is what the shading reads, mip k the level-k result",
            &self.pulled,
        );
    }

    /// Radius r_s of a point's splat disc when each of `vpls` maps gets 1/`vpls` of the cloud:
    /// √(A / (π · points per map)).
    pub fn point_radius(&self, vpls: u32) -> f32 {
        let per_ism = (self.cloud.gpu.len() as f32 / vpls.max(1) as f32).max(1.0);
        (self.cloud.area / (std::f32::consts::PI * per_ism)).sqrt()
    }

    /// Writes the splat uniforms of every bounce of `f` and returns the bind groups of the
    /// frame's splats and resolve.
    pub fn begin(
        &self,
        ctx: &GpuContext,
        instances: &wgpu::Buffer,
        vpls: &wgpu::Buffer,
        s: &IsmSettings,
        f: IsmFrame,
    ) -> IsmJob {
        let l = self.layout_info;
        let n_points = self.cloud.gpu.len() as u32;
        let r_s = self.point_radius(f.vpls);
        let params: Vec<SplatParams> = (0..f.bounces.clamp(1, MAX_BOUNCES))
            .map(|b| SplatParams {
                counts: [n_points, f.vpls, l.cols, l.size],
                geom: Vec4::new(f.eye_offset, r_s, s.max_splat_radius as f32, s.splat_scale),
                slots: [b * f.vpls, b * f.vpls, (s.splat_depth == SplatDepth::TangentPlane) as u32, 0],
            })
            .collect();
        let data = crate::passes::strided_bytes(LEVEL_STRIDE, MAX_BOUNCES as usize, &params);
        ctx.queue.upload(&self.splat_params, 0, &data);
        let params = wgpu::BindingResource::Buffer(wgpu::BufferBinding {
            buffer: &self.splat_params,
            offset: 0,
            size: std::num::NonZeroU64::new(std::mem::size_of::<SplatParams>() as u64),
        });
        let splat = SPLAT_INPUTS_BINDINGS.group(
            &ctx.device,
            &self.splat_layout,
            [
                params,
                self.points.as_entire_binding(),
                instances.as_entire_binding(),
                vpls.as_entire_binding(),
                self.depth.as_entire_binding(),
                self.no_owner.as_entire_binding(),
            ],
        );
        let atlas_view = crate::passes::view(&self.atlas, "ism.atlas");
        // Read later, if at all: the whole atlas as splatted (the frame resolves into level 0
        // of the pulled atlas).
        let on_read = RESOLVE_INPUTS_BINDINGS.group(
            &ctx.device,
            &self.resolve_layout,
            [
                self.depth.as_entire_binding(),
                wgpu::BindingResource::TextureView(&atlas_view),
                level_binding(&self.atlas_rows),
            ],
        );
        self.atlas_on_read.arm_with(Some((&self.resolve_pipeline, on_read)), &[0]);
        IsmJob { splat, resolve: self.resolve_group(&ctx.device) }
    }

    /// The frame's resolve into level 0 of the pulled atlas (and its first pull into level 1
    /// when pull-push has levels); its rows and thresholds come from the call's uniform slot.
    fn resolve_group(&self, device: &wgpu::Device) -> wgpu::BindGroup {
        let rows = level_binding(&self.level_params);
        let level0 = self.level_view(0);
        if self.levels == 0 {
            return RESOLVE_INPUTS_BINDINGS.group(
                device,
                &self.resolve_layout,
                [self.depth.as_entire_binding(), wgpu::BindingResource::TextureView(&level0), rows],
            );
        }
        let level1 = self.level_view(1);
        RESOLVE_PULL_INPUTS_BINDINGS.group(
            device,
            &self.resolve_pull_layout,
            [
                self.depth.as_entire_binding(),
                wgpu::BindingResource::TextureView(&level0),
                rows,
                wgpu::BindingResource::TextureView(&level1),
            ],
        )
    }

    /// Splats the point cloud into the maps of bounce `bounce` (point j → slot b·N + j mod N);
    /// bounce 0 first clears the whole atlas.
    pub fn splat(&self, encoder: &mut wgpu::CommandEncoder, slot: Option<Slot<'_>>, job: &IsmJob, bounce: u32) {
        if bounce == 0 {
            encoder.counted_clear_buffer(&self.depth, 0, None);
        }
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("ism.splat"),
            timestamp_writes: slot.and_then(|s| s.compute(true, true)),
        });
        pass.set_pipe(&self.splat_pipeline);
        pass.set_group(0, &job.splat, &[(bounce.min(MAX_BOUNCES - 1) as u64 * LEVEL_STRIDE) as u32]);
        let groups = (self.cloud.gpu.len() as u32).div_ceil(64);
        pass.dispatch(groups.min(65535), groups.div_ceil(65535), 1);
    }

    /// Resolves the splatted distances into `ism.atlas` and runs pull-push, over the whole atlas.
    pub fn finish(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        slot: Option<Slot<'_>>,
        job: &IsmJob,
        s: &IsmSettings,
        extent: f32,
    ) {
        let all = self.layout_info.cols * self.layout_info.rows;
        self.finish_maps(PassRec { ctx, enc: encoder, slot }, job, s, extent, 0..all, 0);
    }

    /// [`Self::finish`] over the rows of the atlas that hold maps `maps` (issue #38: each extra
    /// bounce's shadow test needs the maps splatted since the last pull-push, not the whole
    /// atlas again). Maps are independent (pull and push stay inside a map), so a row done
    /// twice comes out the same. `call` (0 … MAX_BOUNCES) picks this call's uniform slots: every
    /// call of a frame needs its own, as all are written before the submission.
    pub fn finish_maps(
        &self,
        r: PassRec<'_, '_>,
        job: &IsmJob,
        s: &IsmSettings,
        extent: f32,
        maps: std::ops::Range<u32>,
        call: u32,
    ) {
        let PassRec { ctx, enc: encoder, slot } = r;
        let l = self.layout_info;
        let rows = (maps.start / l.cols).min(l.rows)..maps.end.div_ceil(l.cols).min(l.rows);
        if rows.is_empty() {
            return;
        }
        let call = call.min(MAX_BOUNCES);
        let (y0, y1) = (rows.start * l.size, rows.end * l.size);
        let w = l.width() as u32;
        self.write_levels(ctx, s, extent, y0, call);
        self.resolve_rows(encoder, &job.resolve, w, y0..y1, call);
        self.pull_push_rows(ctx, encoder, slot, y0..y1, call);
    }

    /// Resolves level-0 rows `rows` into level 0 of the pulled atlas and, with pull-push
    /// levels, pulls them into level 1 in the same pass (`cs_resolve_pull`, a texel of level 1
    /// an invocation, from the call's level-0 pull slot); without levels `cs_resolve` reads the
    /// level-0 push slot, whose `tile.y` is the first row.
    fn resolve_rows(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        group: &wgpu::BindGroup,
        w: u32,
        rows: std::ops::Range<u32>,
        call: u32,
    ) {
        let mut pass = encoder
            .begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("ism.resolve"), timestamp_writes: None });
        let span = rows.end - rows.start;
        if self.levels == 0 {
            pass.set_pipe(&self.resolve_pipeline);
            pass.set_group(0, group, &[Self::level_offset(call, 1)]);
            pass.dispatch(w.div_ceil(8), span.div_ceil(8), 1);
        } else {
            pass.set_pipe(&self.resolve_pull_pipeline);
            pass.set_group(0, group, &[Self::level_offset(call, 0)]);
            pass.dispatch((w / 2).div_ceil(8), (span / 2).div_ceil(8), 1);
        }
    }

    fn level_view(&self, level: u32) -> wgpu::TextureView {
        self.pulled.counted_view(&wgpu::TextureViewDescriptor {
            label: Some("ism.atlas_pulled.level"),
            base_mip_level: level,
            mip_level_count: Some(1),
            ..Default::default()
        })
    }

    /// Dynamic offset of uniform slot `k` of call `call`.
    fn level_offset(call: u32, k: u64) -> u32 {
        ((call as u64 * LEVEL_SLOTS + k) * LEVEL_STRIDE) as u32
    }

    /// Writes call `call`'s level uniforms: slot 2·level the pull threshold, slot 2·level + 1
    /// the push threshold and rule; `tile.y` the first texel row of the level the slot writes
    /// (level 0 row `y0` scaled down).
    fn write_levels(&self, ctx: &GpuContext, s: &IsmSettings, extent: f32, y0: u32, call: u32) {
        let l = self.layout_info;
        let mut data = vec![0u8; (LEVEL_STRIDE * LEVEL_SLOTS) as usize];
        let inside = (s.push_behind == PushBehind::InsideSurfaces) as u32 as f32;
        // Level 0's push slot exists even without levels: the resolve reads its row.
        for level in 0..self.levels.max(1) {
            let scale = (1u32 << level) as f32 * extent;
            for (k, t, rule, target) in [(0, s.pull_threshold, 0.0, level + 1), (1, s.push_threshold, inside, level)] {
                let p = LevelParams {
                    threshold: Vec4::new(t * scale, rule, 0.0, 0.0),
                    tile: [(l.size >> (level + 1)).max(1), y0 >> target, 0, 0],
                };
                let o = ((2 * level + k) as u64 * LEVEL_STRIDE) as usize;
                data[o..o + std::mem::size_of::<LevelParams>()].copy_from_slice(bytemuck::bytes_of(&p));
            }
        }
        ctx.queue.upload(&self.level_params, call as u64 * LEVEL_SLOTS * LEVEL_STRIDE, &data);
    }

    /// Resolves the splatted distances (`depth`) into level 0 of `ism.atlas_pulled` and runs
    /// pull-push on it (thresholds are fractions of `extent`), over the whole atlas.
    pub fn pull_push(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        slot: Option<Slot<'_>>,
        s: &IsmSettings,
        extent: f32,
    ) {
        let (w, h) = (self.layout_info.width() as u32, self.layout_info.height() as u32);
        self.write_levels(ctx, s, extent, 0, 0);
        self.resolve_rows(encoder, &self.resolve_group(&ctx.device), w, 0..h, 0);
        self.pull_push_rows(ctx, encoder, slot, 0..h, 0);
    }

    /// Pull-push over level-0 texel rows `rows` (whole maps), with call `call`'s uniforms.
    fn pull_push_rows(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        slot: Option<Slot<'_>>,
        rows: std::ops::Range<u32>,
        call: u32,
    ) {
        let l = self.layout_info;
        let w = l.width() as u32;
        let mut pulls = Vec::new();
        let mut pushes = Vec::new();
        let dynamic = level_binding(&self.level_params);
        for level in 0..self.levels {
            let (fine, coarse) = (self.level_view(level), self.level_view(level + 1));
            let tv = wgpu::BindingResource::TextureView;
            // Level 1 is pulled by the resolve (`resolve_rows`).
            if level > 0 {
                pulls.push(PULL_INPUTS_BINDINGS.group(
                    &ctx.device,
                    &self.pull_layout,
                    [dynamic.clone(), tv(&fine), tv(&coarse)],
                ));
            }
            pushes.push(PUSH_INPUTS_BINDINGS.group(
                &ctx.device,
                &self.push_layout,
                [dynamic.clone(), tv(&coarse), tv(&fine)],
            ));
        }
        // Mips 2…levels are first written (the pull, storage) and then read (the push,
        // sampled) inside the one pass below (mip 1 was written by the resolve's pass). wgpu 30 records a pass's *last* use of a
        // subresource the encoder has not seen yet as the encoder's start state (gfx-rs/wgpu
        // #10199, fix pending in #10212), so at submission it moved these mips to
        // SHADER_READ_ONLY while the first dispatch wrote them as storage (GENERAL): the
        // validation layers' InvalidImageLayout on `ism.atlas_pulled` (issue #52 point 6).
        // Telling the encoder their first use before the pass makes its start state right.
        if self.levels > 1 {
            encoder.transition_resources(
                std::iter::empty(),
                std::iter::once(wgpu::TextureTransition {
                    texture: &self.pulled,
                    selector: Some(wgpu::wgt::TextureSelector { mips: 2..self.levels + 1, layers: 0..1 }),
                    state: wgpu::TextureUses::STORAGE_WRITE_ONLY,
                }),
            );
        }
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("ism.pull_push"),
            timestamp_writes: slot.and_then(|s| s.compute(true, true)),
        });
        let span = |level: u32| ((rows.end >> level) - (rows.start >> level)).max(1);
        pass.set_pipe(&self.pull_pipeline);
        for (level, g) in (1..).zip(&pulls) {
            let cw = (w >> (level + 1)).max(1);
            pass.set_group(0, g, &[Self::level_offset(call, 2 * level as u64)]);
            pass.dispatch(cw.div_ceil(8), span(level + 1).div_ceil(8), 1);
        }
        // A 2×2 quad of the finer level an invocation (`cs_push`).
        pass.set_pipe(&self.push_pipeline);
        for (level, g) in pushes.iter().enumerate().rev() {
            let level = level as u32;
            let fw = (w >> level).max(1);
            pass.set_group(0, g, &[Self::level_offset(call, 2 * level as u64 + 1)]);
            pass.dispatch((fw / 2).div_ceil(8), (span(level) / 2).div_ceil(8), 1);
        }
    }

    /// The pull-pushed atlas the shading reads (level 0).
    pub fn shading_view(&self) -> wgpu::TextureView {
        self.level_view(0)
    }

    pub fn levels(&self) -> u32 {
        self.levels
    }
}
