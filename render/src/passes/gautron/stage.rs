//! Gautron et al.'s stages for the frame (003): shading points "irradiance records" (the
//! creation rounds), gather "hemisphere rasterization", reconstruction "weight splatting",
//! temporal "record cache". One frame: splat the cached records; K times: find the
//! under-covered pixels (one per creation tile), make up to the round's budget of records
//! there, render and reduce their hemispheres, splat them; resolve. The order the records are
//! made or splatted in does not change the image ("Algorithm: Summary": no order
//! constraint): the blending adds, and the creation lists its candidates in tile order.

use crate::counters::prelude::*;

use std::hash::{Hash, Hasher};

/// GI Lab's mix with Nguyen et al.: the hemispheres at the HCB's samples.
mod at_hcb;

use super::at_samples::AtSamplesPass;
use super::hemisphere::{HemispherePass, RoundArgs};
use super::splat::SplatPass;
use super::vpl_records::VplRecordPass;
use super::{
    CacheState, GautronParams, GautronSettings, GpuRecord, HemisphereCamera, Invalidation, RECORD_BYTES, ReusePolicy,
    atlas_grid,
};
use crate::buffers::{BufferKind, BufferRegistry, read_storage};
use crate::gpu::GpuContext;
use crate::gpu::bindings::{Bindings, Kind, binding};
use crate::passes::stages::{FrameInputs, Visibility, VplSet};
use crate::passes::{buffer, create_target, view};
use crate::settings::pipeline::Temporal;
use crate::timing::GpuTimer;
use crate::timing::PassRec;

/// Bind group `gautron.create.gbuffer` of `shaders/gautron/create.wgsl` (group 1): the G-buffer
/// and splatted coverage the creation tests, and its candidates' mask.
pub const CREATE_GBUFFER_BINDINGS: Bindings = Bindings {
    label: "gautron.create.gbuffer",
    shader: "gautron/create.wgsl",
    group: 1,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "g_position", Kind::Texture { filterable: false }),
        binding(1, "g_normal", Kind::Texture { filterable: false }),
        binding(2, "accum", Kind::Texture { filterable: false }),
        binding(3, "candidate_mask", Kind::StorageTexture(wgpu::TextureFormat::R32Float)),
    ],
};

/// Bind group `gautron.create` of `shaders/gautron/create.wgsl` (group 0).
pub const CREATE_BINDINGS: Bindings = Bindings {
    label: "gautron.create",
    shader: "gautron/create.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "params", Kind::Uniform),
        binding(1, "round", Kind::UniformDynamic),
        binding(2, "camera", Kind::Uniform),
        binding(3, "state", Kind::Storage { read_only: false }),
        binding(4, "candidates", Kind::Storage { read_only: false }),
        binding(5, "slots", Kind::Storage { read_only: false }),
        binding(6, "records", Kind::Storage { read_only: false }),
        binding(7, "cameras", Kind::Storage { read_only: false }),
        binding(8, "viewers", Kind::Storage { read_only: false }),
        binding(9, "raster_args", Kind::Storage { read_only: false }),
        binding(10, "splat_args", Kind::Storage { read_only: false }),
        binding(11, "maintain", Kind::Uniform),
        binding(12, "moved", Kind::Storage { read_only: true }),
    ],
};

/// Bytes between the rounds' uniforms (dynamic offsets).
const ROUND_STRIDE: u64 = 256;
/// Most creation rounds per frame (`gautron.rounds`' range).
const MAX_ROUNDS: u64 = 32;
/// Most scene draws that may move in one frame with the cache kept (each is tested against
/// every record); more empty the cache.
pub const MAX_MOVED: usize = 64;

/// What changed since the last frame (WGSL twin: `MaintainParams` in create.wgsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct MaintainParams {
    /// x: drop off-screen records, y: moved objects, z: every record invalid, w: refresh.
    flags: [u32; 4],
    /// The moved draws, bit (draw mod 128).
    mask: [u32; 4],
}

/// A moved draw's world bounds last frame and now (WGSL twin: `MovedObject`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct MovedObject {
    old_min: [f32; 4],
    old_max: [f32; 4],
    new_min: [f32; 4],
    new_max: [f32; 4],
}

pub struct GautronStage {
    pub hemisphere: HemispherePass,
    pub splat: SplatPass,
    /// The records lit by VPLs instead of hemispheres (GI Lab's mix; made when first used).
    vpl_records: Option<VplRecordPass>,
    /// The hemispheres at the HCB's samples (GI Lab's mix; made when first used).
    at_samples: Option<AtSamplesPass>,
    /// The HCB's sample count of a recent frame, for the mix's chunks (read without waiting).
    sample_count: Option<crate::readback::LateCount>,
    candidates: wgpu::ComputePipeline,
    /// The candidates listed in tile order: per chunk of 256 tiles a count, the chunks'
    /// offsets, each chunk's candidates from its offset (`gautron/create.wgsl`).
    count: wgpu::ComputePipeline,
    compact: wgpu::ComputePipeline,
    scatter: wgpu::ComputePipeline,
    cameras_pipeline: wgpu::ComputePipeline,
    begin: wgpu::ComputePipeline,
    maintain: wgpu::ComputePipeline,
    clamp_cached: wgpu::ComputePipeline,
    clamp_new: wgpu::ComputePipeline,
    clamp_store: wgpu::ComputePipeline,
    maintain_params: wgpu::Buffer,
    moved: wgpu::Buffer,
    layout0: wgpu::BindGroupLayout,
    layout1: wgpu::BindGroupLayout,
    params: wgpu::Buffer,
    rounds: wgpu::Buffer,
    pub state: wgpu::Buffer,
    candidate_list: wgpu::Buffer,
    slots: wgpu::Buffer,
    pub records: wgpu::Buffer,
    /// The cache as each splat of the frame read it, while a pixel is explained (issue #42).
    pub snapshots: Option<super::explain::Snapshots>,
    cameras: wgpu::Buffer,
    viewers: wgpu::Buffer,
    atlas_params: wgpu::Buffer,
    raster_args: wgpu::Buffer,
    raster_draws: usize,
    splat_args: wgpu::Buffer,
    /// The round in which a record was made at each pixel this frame (`gautron.candidates`).
    pub candidate_mask: wgpu::Texture,
    /// What every cached record depends on (record settings, size), hashed: a change empties
    /// the cache.
    cache_key: Option<u64>,
    /// The lights and the direct light's settings, hashed: a change invalidates every record.
    lights_key: Option<u64>,
    /// Every scene draw's world matrix last frame (the moved objects).
    prev_worlds: Vec<glam::Mat4>,
    /// Local bounds of each (mesh, primitive), computed when it first moves.
    local_bounds: std::collections::HashMap<(usize, usize), crate::scene::Aabb>,
    /// (capacity, slots, tiles) the buffers were made for.
    sizes: (u32, u32, u32),
}

impl GautronStage {
    /// What the explain replay reads of the stage.
    pub fn explain_parts(&self) -> super::explain::StageParts<'_> {
        super::explain::StageParts {
            params: self.params(),
            records: &self.records,
            state: &self.state,
            splat: &self.splat,
            snapshots: self.snapshots.as_ref(),
        }
    }

    /// The stage's uniform (`GautronParams`) as this frame wrote it.
    pub fn params(&self) -> &wgpu::Buffer {
        &self.params
    }

    pub fn new(
        ctx: &GpuContext,
        f_scene: &crate::scene::upload::GpuScene,
        s: &GautronSettings,
        w: u32,
        h: u32,
    ) -> Self {
        let device = &ctx.device;
        let layout0 = CREATE_BINDINGS.layout(device);
        let layout1 = CREATE_GBUFFER_BINDINGS.layout(device);
        let module = crate::shaders::create_module(device, "gautron/create.wgsl");
        let pipeline = |entry: &str| {
            crate::passes::compute_pipeline(device, &format!("gautron.{entry}"), &module, entry, &[&layout0, &layout1])
        };
        let storage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC;
        let indirect = storage | wgpu::BufferUsages::INDIRECT;
        let mut stage = Self {
            snapshots: None,
            hemisphere: HemispherePass::new(ctx, f_scene, s),
            splat: SplatPass::new(ctx, w, h),
            vpl_records: None,
            at_samples: None,
            sample_count: None,
            candidates: pipeline("cs_candidates"),
            count: pipeline("cs_count"),
            compact: pipeline("cs_compact"),
            scatter: pipeline("cs_scatter"),
            cameras_pipeline: pipeline("cs_cameras"),
            begin: pipeline("cs_begin"),
            maintain: pipeline("cs_maintain"),
            clamp_cached: pipeline("cs_clamp_cached"),
            clamp_new: pipeline("cs_clamp_new"),
            clamp_store: pipeline("cs_clamp_store"),
            maintain_params: crate::passes::uniform_buffer(
                device,
                "gautron.maintain",
                std::mem::size_of::<MaintainParams>() as u64,
            ),
            moved: buffer(
                device,
                "gautron.moved",
                (MAX_MOVED * std::mem::size_of::<MovedObject>()) as u64,
                wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            ),
            layout0,
            layout1,
            params: crate::passes::uniform_buffer(
                device,
                "gautron.params",
                std::mem::size_of::<GautronParams>() as u64,
            ),
            rounds: crate::passes::uniform_buffer(device, "gautron.rounds", ROUND_STRIDE * MAX_ROUNDS),
            state: buffer(device, "gautron.state", std::mem::size_of::<CacheState>() as u64, storage),
            candidate_list: buffer(device, "gautron.candidate_list", 4, storage),
            slots: buffer(device, "gautron.slots", 4, storage),
            records: buffer(device, "gautron.records", RECORD_BYTES, storage),
            cameras: buffer(device, "gautron.cameras", 144, storage),
            viewers: buffer(device, "gautron.viewers", 16, storage),
            atlas_params: crate::passes::uniform_buffer(device, "gautron.atlas_params", 16),
            raster_args: buffer(device, "gautron.raster_args", 20, indirect),
            raster_draws: 0,
            splat_args: buffer(device, "gautron.splat_args", 16, indirect),
            candidate_mask: mask(device, w, h),
            cache_key: None,
            lights_key: None,
            prev_worlds: Vec::new(),
            local_bounds: Default::default(),
            sizes: (0, 0, 0),
        };
        stage.ensure(ctx, s, w, h);
        stage
    }

    /// Resizes the targets and buffers for the settings and the G-buffer; true when any was
    /// remade (the cache is then emptied).
    pub fn ensure(&mut self, ctx: &GpuContext, s: &GautronSettings, w: u32, h: u32) -> bool {
        let device = &ctx.device;
        let mut fresh = self.hemisphere.ensure(ctx, s);
        if self.splat.resize(ctx, w, h) {
            self.candidate_mask = mask(device, w, h);
            fresh = true;
        }
        let tile = s.creation_tile_px.max(1);
        let tiles = w.div_ceil(tile) * h.div_ceil(tile);
        let sizes = (s.capacity.max(1), s.records_per_round.max(1), tiles);
        if sizes != self.sizes {
            self.sizes = sizes;
            let storage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC;
            let (capacity, slots, tiles) = (sizes.0 as u64, sizes.1 as u64, sizes.2 as u64);
            self.records = buffer(device, "gautron.records", capacity * RECORD_BYTES, storage);
            // The tiles' candidates, then per chunk of 256 tiles its count and its offset.
            let chunks = tiles.div_ceil(256);
            self.candidate_list = buffer(device, "gautron.candidate_list", (tiles + 2 * chunks) * 4, storage);
            self.slots = buffer(device, "gautron.slots", slots * 4, storage);
            self.cameras = buffer(device, "gautron.cameras", slots * 144, storage);
            self.viewers = buffer(device, "gautron.viewers", slots * 16, storage);
            self.splat.ensure_bins(ctx, sizes.0);
            fresh = true;
        }
        if fresh {
            self.cache_key = None;
            self.lights_key = None;
        }
        fresh
    }

    /// The pass that lights the records with VPLs (GI Lab's mix), once a frame has made it.
    pub fn vpl_records_mut(&mut self) -> Option<&mut VplRecordPass> {
        self.vpl_records.as_mut()
    }

    /// Registers the splat's latest sums (a ping-pong pair: after each frame).
    pub fn register_sums(&self, reg: &mut BufferRegistry) {
        self.splat.register_sums(reg);
    }

    pub fn register(&self, reg: &mut BufferRegistry) {
        self.hemisphere.register(reg);
        self.splat.register(reg);
        reg.register(
            "gautron.candidates",
            BufferKind::Data,
            "the creation round (1…K) in which a record was made at this pixel this frame; 0 elsewhere",
            &self.candidate_mask,
        );
    }

    /// Forgets the cached records (the next frame starts cold).
    pub fn reset(&mut self) {
        self.cache_key = None;
        self.lights_key = None;
    }

    /// Writes the frame's uniforms and the hemisphere raster's indirect draws; returns the
    /// round's slots.
    fn prepare(&mut self, f: &FrameInputs) -> u32 {
        let (ctx, s) = (f.ctx, &f.settings.gautron);
        self.ensure(ctx, s, f.gbuffer_size.0, f.gbuffer_size.1);
        let slots = s.records_per_round.max(1);
        let (per_row, _) = atlas_grid(slots);
        let aspect = f.gbuffer_size.0 as f32 / f.gbuffer_size.1.max(1) as f32;
        let proj = f.camera.projection(aspect);
        let r = f.radius.max(1e-6);
        let params = GautronParams {
            weight: glam::Vec4::new(
                s.accuracy,
                s.weight_clamp,
                s.rotational_gradient as u32 as f32,
                s.translational_gradient as u32 as f32,
            ),
            hemisphere: glam::Vec4::new(
                s.hemisphere_resolution as f32,
                per_row as f32,
                (s.aperture_deg.to_radians() * 0.5).tan(),
                r * 1e-4,
            ),
            clamps: match s.r_clamps {
                true => {
                    let scale = f.scale.max(1e-6);
                    glam::Vec4::new(s.r_min_scene * scale, s.r_max_scene * scale, s.r_min_px, s.r_max_px)
                }
                false => glam::Vec4::new(0.0, f32::MAX, 0.0, f32::MAX),
            },
            creation: glam::Vec4::new(s.creation_tile_px as f32, slots as f32, s.capacity as f32, 4.0 * r),
            misc: glam::Vec4::new(f.frame as f32, proj.x_axis.x, proj.y_axis.y, f.gbuffer_size.1 as f32 * 0.5),
            rules: glam::Vec4::new(
                if s.in_front_test { s.in_front_tolerance } else { f32::MAX },
                s.receiver.flag(),
                0.0,
                0.0,
            ),
        };
        ctx.queue.upload(&self.params, 0, bytemuck::bytes_of(&params));
        ctx.queue.upload(&self.atlas_params, 0, bytemuck::cast_slice(&[s.hemisphere_resolution, per_row, 0, 0]));
        let args = HemispherePass::draw_args(f.gpu_scene, f.state, slots);
        if args.len() * 4 > self.raster_args.size() as usize || args.is_empty() {
            let usage = wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_DST
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::INDIRECT;
            self.raster_args = buffer(&ctx.device, "gautron.raster_args", (args.len().max(5) * 4) as u64, usage);
        }
        self.raster_draws = args.len() / 5;
        if !args.is_empty() {
            ctx.queue.upload(&self.raster_args, 0, bytemuck::cast_slice(&args));
        }
        slots
    }

    /// Computes the round's slots' records (new ones and stale ones again): their hemispheres
    /// rasterized, lit by stage 2 and reduced ("Simple plane sampling"), or with `light` the
    /// VPL sums of GI Lab's mix with instant radiosity.
    fn compute_records(
        &self,
        f: &FrameInputs,
        e: &mut wgpu::CommandEncoder,
        slot: Option<crate::timing::Slot<'_>>,
        light: Option<(&VplSet, &Visibility)>,
        slots: u32,
        round: Option<RoundArgs<'_>>,
    ) {
        let ctx = f.ctx;
        if let (Some((vpls, vis)), Some(pass)) = (light, &self.vpl_records) {
            let buffers = (&self.params, &self.state, &self.cameras, &self.records);
            pass.run(PassRec { ctx, enc: e, slot }, buffers, (vpls, vis), f.radius, slots);
            return;
        }
        let hemisphere = &self.hemisphere;
        hemisphere.raster(
            PassRec { ctx, enc: e, slot },
            f.gpu_scene,
            f.state,
            (f.camera_buffer, &self.cameras),
            &self.params,
            (&self.raster_args, round),
        );
        f.direct.shade_atlas(
            PassRec { ctx, enc: e, slot: None },
            &hemisphere.atlas.views,
            hemisphere.radiance_view(),
            hemisphere.size,
            &self.atlas_params,
            &self.viewers,
            round.map(|RoundArgs(b)| (b, RoundArgs::SHADE)),
        );
        hemisphere.reduce(
            PassRec { ctx, enc: e, slot },
            &self.params,
            &self.state,
            &self.cameras,
            &self.records,
            (slots, round),
        );
    }

    /// Stages 5–7 for the frame: returns the reflected indirect light (`gautron.indirect`).
    /// `light`: the VPLs and their visibility when the records are lit by the VPL gather
    /// (GI Lab's mix, `pipeline.gather = Vpl`), None for the hemispheres.
    pub fn run(
        &mut self,
        f: &FrameInputs,
        enc: &mut wgpu::CommandEncoder,
        timer: &mut GpuTimer,
        light: Option<(&VplSet, &Visibility)>,
    ) -> wgpu::TextureView {
        let (ctx, s) = (f.ctx, &f.settings.gautron);
        if light.is_some() && self.vpl_records.is_none() {
            self.vpl_records = Some(VplRecordPass::new(ctx));
        }
        let slots = self.prepare(f);

        // The record cache (stage 7): records stay while what they depend on stays; a moved
        // object or a changed light invalidates the records it changes (cs_maintain).
        let maintain = self.changes(f);
        let keep = maintain.is_some();
        if !keep {
            ctx.queue.upload(&self.state, 0, bytemuck::bytes_of(&CacheState::default()));
        }
        let maintain = maintain.filter(|m| m.flags[0] + m.flags[1] + m.flags[2] > 0);
        if let Some(m) = &maintain {
            ctx.queue.upload(&self.maintain_params, 0, bytemuck::bytes_of(m));
        }
        let g0 = &self.create_group(f);
        // Each round's tiles (`GautronSettings::round_tile`), into the rounds' uniforms.
        let round_tiles: Vec<(u32, u32)> = (0..MAX_ROUNDS as u32)
            .map(|k| {
                let tile = s.round_tile(k);
                (f.gbuffer_size.0.div_ceil(tile), f.gbuffer_size.1.div_ceil(tile))
            })
            .collect();
        let rounds: Vec<[u32; 4]> = (0..MAX_ROUNDS as u32)
            .map(|k| [k, round_tiles[k as usize].0 * round_tiles[k as usize].1, s.round_tile(k), 0])
            .collect();
        ctx.queue.upload(&self.rounds, 0, &crate::passes::strided_bytes(ROUND_STRIDE, MAX_ROUNDS as usize, &rounds));
        let (splat, records, camera) = (&self.splat, &self.records, f.camera_buffer);
        // Every cached record, once (after the reuse policy and the invalidation).
        let (begin, cull) = (&self.begin, maintain.is_some().then_some(&self.maintain));
        timer.scope(ctx, enc, "gautron.splat", |e, slot| {
            {
                let mut pass = e.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("gautron.begin"),
                    timestamp_writes: None,
                });
                let g1 = &self.gbuffer_group(f);
                if let Some(cull) = cull {
                    pass.set_pipe(cull);
                    pass.set_group(0, g0, &[0]);
                    pass.set_group(1, g1, &[]);
                    pass.dispatch(1, 1, 1);
                }
                pass.set_pipe(begin);
                pass.set_group(0, g0, &[0]);
                pass.set_group(1, g1, &[]);
                pass.dispatch(1, 1, 1);
            }
            splat.splat(
                PassRec { ctx, enc: e, slot },
                (s.splat, true),
                [&self.params, camera, records],
                f.gbuffer,
                &self.splat_args,
            )
        });
        if let Some(snap) = &mut self.snapshots {
            snap.taken = 0;
            snap.take(enc, records, &self.state, 0);
        }
        for k in 0..s.rounds.min(MAX_ROUNDS as u32) {
            let offset = [(k as u64 * ROUND_STRIDE) as u32];
            let tiles = round_tiles[k as usize];
            // The coverage of the latest sums (the splat's ping-pong pair alternates).
            let g1 = &self.gbuffer_group(f);
            timer.scope(ctx, enc, "gautron.create", |e, slot| {
                let mut pass = e.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("gautron.create"),
                    timestamp_writes: slot.and_then(|s| s.compute(true, true)),
                });
                pass.set_group(0, g0, &offset);
                pass.set_group(1, g1, &[]);
                pass.set_pipe(&self.candidates);
                pass.dispatch(tiles.0, tiles.1, 1);
                let chunks = (tiles.0 * tiles.1).div_ceil(256);
                pass.set_pipe(&self.count);
                pass.dispatch(chunks, 1, 1);
                pass.set_pipe(&self.compact);
                pass.dispatch(1, 1, 1);
                pass.set_pipe(&self.scatter);
                pass.dispatch(chunks, 1, 1);
                pass.set_pipe(&self.cameras_pipeline);
                pass.dispatch(slots.div_ceil(64), 1, 1);
            });
            let name = if light.is_some() { "gautron.vpl_records" } else { "gautron.hemispheres" };
            timer.scope(ctx, enc, name, |e, slot| {
                self.compute_records(f, e, slot, light, slots, None);
                if s.neighbour_clamping {
                    let mut pass = e.begin_compute_pass(&wgpu::ComputePassDescriptor {
                        label: Some("gautron.neighbours"),
                        timestamp_writes: None,
                    });
                    pass.set_group(0, g0, &offset);
                    pass.set_group(1, g1, &[]);
                    pass.set_pipe(&self.clamp_cached);
                    pass.dispatch(s.capacity.max(1).div_ceil(64), 1, 1);
                    pass.set_pipe(&self.clamp_new);
                    pass.dispatch(slots.div_ceil(64), 1, 1);
                    pass.set_pipe(&self.clamp_store);
                    pass.dispatch(slots.div_ceil(64), 1, 1);
                }
            });
            timer.scope(ctx, enc, "gautron.splat", |e, slot| {
                splat.splat(
                    PassRec { ctx, enc: e, slot },
                    (s.splat, false),
                    [&self.params, camera, records],
                    f.gbuffer,
                    &self.splat_args,
                )
            });
            if let Some(snap) = &mut self.snapshots {
                snap.take(enc, records, &self.state, k + 1);
            }
        }
        timer.scope(ctx, enc, "gautron.resolve", |e, slot| {
            splat.resolve(ctx, e, slot, f.gbuffer, &self.params, f.camera_buffer)
        });
        splat.indirect_view()
    }

    /// The raster's indirect draws as bound by the compute passes that write them.
    fn raster_args_binding(&self) -> wgpu::BufferBinding<'_> {
        wgpu::BufferBinding {
            buffer: &self.raster_args,
            offset: 0,
            size: std::num::NonZeroU64::new((self.raster_draws.max(1) * 20) as u64),
        }
    }

    fn create_group(&self, f: &FrameInputs) -> wgpu::BindGroup {
        let device = &f.ctx.device;
        CREATE_BINDINGS.group(
            device,
            &self.layout0,
            [
                self.params.as_entire_binding(),
                crate::passes::dynamic_slot(&self.rounds, 16),
                f.camera_buffer.as_entire_binding(),
                self.state.as_entire_binding(),
                self.candidate_list.as_entire_binding(),
                self.slots.as_entire_binding(),
                self.records.as_entire_binding(),
                self.cameras.as_entire_binding(),
                self.viewers.as_entire_binding(),
                wgpu::BindingResource::Buffer(self.raster_args_binding()),
                self.splat_args.as_entire_binding(),
                self.maintain_params.as_entire_binding(),
                self.moved.as_entire_binding(),
            ],
        )
    }

    /// The creation's G-buffer group with the splat's latest sums (its coverage).
    fn gbuffer_group(&self, f: &FrameInputs) -> wgpu::BindGroup {
        let tv = wgpu::BindingResource::TextureView;
        let mask_view = view(&self.candidate_mask, "gautron.candidates");
        CREATE_GBUFFER_BINDINGS.group(
            &f.ctx.device,
            &self.layout1,
            [tv(&f.gbuffer.position), tv(&f.gbuffer.normal), tv(&self.splat.accum_view()), tv(&mask_view)],
        )
    }

    /// A hash of what every record depends on: the record settings that change a record
    /// (`history` fields) and the size.
    fn dependencies(&self, f: &FrameInputs) -> u64 {
        let mut h = std::collections::hash_map::DefaultHasher::new();
        let g = &f.settings.gautron;
        use crate::settings::SettingsGroup;
        for m in GautronSettings::fields().iter().filter(|m| m.resets_history) {
            format!("{:?}", g.get(m.name)).hash(&mut h);
        }
        f.gbuffer_size.hash(&mut h);
        // another gather (hemispheres or VPLs) makes other records
        format!("{:?}", f.settings.pipeline).hash(&mut h);
        h.finish()
    }

    /// A hash of the lights and the direct light's settings.
    fn lights(f: &FrameInputs) -> u64 {
        let mut h = std::collections::hash_map::DefaultHasher::new();
        // The sky's rotating directions are not a change (`sky.rotate_each_frame`).
        for x in f.steady_light_key() {
            x.to_bits().hash(&mut h);
        }
        format!("{:?}", f.settings.direct).hash(&mut h);
        // records lit by VPLs also depend on what makes the VPLs and their visibility
        if f.settings.pipeline.uses_vpls() {
            format!("{:?} {:?}", f.settings.vpl, f.settings.ism).hash(&mut h);
        }
        h.finish()
    }

    /// What changed since the last frame, and the moved objects uploaded: None empties the
    /// cache (no record cache, the record settings or the size changed, the draws were
    /// replaced, more than [`MAX_MOVED`] draws moved, or a light changed under the Drop
    /// policy); otherwise what `cs_maintain` must do (all zero flags: nothing).
    fn changes(&mut self, f: &FrameInputs) -> Option<MaintainParams> {
        let s = &f.settings.gautron;
        let key = self.dependencies(f);
        let lights = Self::lights(f);
        let worlds: Vec<glam::Mat4> = f.state.draws.iter().map(|d| d.world).collect();
        let previous = (self.cache_key.replace(key), self.lights_key.replace(lights));
        let prev_worlds = std::mem::replace(&mut self.prev_worlds, worlds);
        if f.settings.pipeline.temporal != Temporal::RecordCache
            || previous.0 != Some(key)
            || prev_worlds.len() != f.state.draws.len()
        {
            return None;
        }
        let refresh = s.invalidation == Invalidation::Refresh;
        let lights_changed = previous.1 != Some(lights);
        if lights_changed && !refresh {
            return None;
        }
        let mut m = MaintainParams::default();
        let mut moved = Vec::new();
        for (i, (d, old)) in f.state.draws.iter().zip(&prev_worlds).enumerate() {
            if d.world == *old {
                continue;
            }
            if moved.len() == MAX_MOVED {
                return None;
            }
            let local = *self
                .local_bounds
                .entry((d.mesh, d.primitive))
                .or_insert_with(|| f.scene.meshes[d.mesh].primitives[d.primitive].bounds());
            let (old, new) = (local.transformed(*old), local.transformed(d.world));
            let v4 = |v: glam::Vec3| v.extend(0.0).to_array();
            moved.push(MovedObject {
                old_min: v4(old.min),
                old_max: v4(old.max),
                new_min: v4(new.min),
                new_max: v4(new.max),
            });
            m.mask[(i % 128) / 32] |= 1 << (i % 32);
        }
        if !moved.is_empty() {
            f.ctx.queue.upload(&self.moved, 0, bytemuck::cast_slice(&moved));
        }
        m.flags =
            [(s.reuse == ReusePolicy::DropOffscreen) as u32, moved.len() as u32, lights_changed as u32, refresh as u32];
        Some(m)
    }

    /// The cache's counters (blocks; tests, the bench and the lab's status line).
    pub fn read_state(&self, ctx: &GpuContext) -> Option<CacheState> {
        let b = read_storage(ctx, &self.state, std::mem::size_of::<CacheState>() as u64).ok()?;
        Some(bytemuck::pod_read_unaligned(&b))
    }

    /// The buffers (and bytes) of the cache's counters and its whole record array, for a
    /// read-back without waiting (`Renderer::gautron_records_later`).
    pub fn state_sources(&self, with_records: bool) -> Vec<(wgpu::Buffer, u64)> {
        let mut v = vec![(self.state.clone(), std::mem::size_of::<CacheState>() as u64)];
        if with_records {
            v.push((self.records.clone(), self.records.size()));
        }
        v
    }

    /// The counters (and the first `count` records, when read) from [`Self::state_sources`]'s bytes.
    pub fn state_from(parts: &[Vec<u8>]) -> Option<(CacheState, Option<Vec<GpuRecord>>)> {
        let state: CacheState = bytemuck::pod_read_unaligned(parts.first()?.get(..std::mem::size_of::<CacheState>())?);
        let records = parts.get(1).map(|b| {
            let n = (state.count as usize * RECORD_BYTES as usize)
                .min(b.len() / RECORD_BYTES as usize * RECORD_BYTES as usize);
            bytemuck::pod_collect_to_vec(&b[..n])
        });
        Some((state, records))
    }

    /// The first `count` records (blocks).
    pub fn read_records(&self, ctx: &GpuContext, count: u32) -> Option<Vec<GpuRecord>> {
        let b = read_storage(ctx, &self.records, count as u64 * RECORD_BYTES).ok()?;
        Some(bytemuck::pod_collect_to_vec(&b))
    }

    /// The hemisphere cameras of the last round's slots (blocks; tests).
    pub fn read_cameras(&self, ctx: &GpuContext) -> Option<Vec<HemisphereCamera>> {
        let b = read_storage(ctx, &self.cameras, self.cameras.size()).ok()?;
        Some(bytemuck::pod_collect_to_vec(&b))
    }
}

fn mask(device: &wgpu::Device, w: u32, h: u32) -> wgpu::Texture {
    create_target(
        device,
        "gautron.candidates",
        w,
        h,
        wgpu::TextureFormat::R32Float,
        wgpu::TextureUsages::STORAGE_BINDING,
    )
}
