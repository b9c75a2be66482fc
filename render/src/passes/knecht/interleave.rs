//! Stages 5–6 of instant radiosity (Knecht 002 §3.4): interleaved sampling. The camera
//! G-buffer is split into n×n tiles (`interleave.split.*`), every VPL is assigned to one
//! tile and all VPLs are shaded in one dispatch (`indirect.accum`, split layout), the tiles
//! are merged back (`indirect.merged`, with the irradiance it came from beside it in
//! `indirect.irradiance`), and the geometry-aware n×n box filter smooths the tiles away
//! (`indirect.filtered`; by default demodulated: the irradiance is filtered and reflected
//! with each pixel's own colour, issue #51).
//! Shaders: `shaders/knecht/interleave/{split,gather,merge,filter}.wgsl`.
//!
//! The thesis draws one quad per VPL over its tile ("tiled mesh geometry", §3.4.2) so that
//! one draw call shades all VPLs; here one compute dispatch over the split G-buffer does
//! the same, each thread looping over its tile's VPLs.

use crate::counters::prelude::*;

use glam::Vec4;

use crate::buffers::{BufferKind, BufferRegistry};
use crate::gpu::GpuContext;
use crate::gpu::bindings::{Bindings, Kind, binding};
use crate::passes::gbuffer::{ALBEDO_FORMAT, GBufferViews, LINEAR_DEPTH_FORMAT, MATERIAL_FORMAT, NORMAL_FORMAT};
use crate::passes::reference::vpl_visibility::{GatherVisibility, no_visibility_atlases};
pub use crate::settings::knecht::InterleaveSettings;
use crate::timing::PassRec;

/// Bind group `interleave.gather.inputs` of `shaders/knecht/interleave/gather.wgsl` (group 0).
pub const GATHER_INPUTS_BINDINGS: Bindings = Bindings {
    label: "interleave.gather.inputs",
    shader: "knecht/interleave/gather.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "camera", Kind::Uniform),
        binding(1, "params", Kind::Uniform),
        binding(2, "vpls", Kind::Storage { read_only: true }),
        binding(3, "ism_atlas", Kind::Texture { filterable: false }),
        binding(4, "exact_atlas", Kind::Texture { filterable: false }),
        binding(5, "s_position", Kind::Texture { filterable: false }),
        // The camera's packed normals (fused), or a stand-in beside `s_normal_split`.
        binding(6, "s_normal", Kind::UintTexture),
        binding(7, "s_albedo", Kind::Texture { filterable: false }),
        binding(8, "s_material", Kind::Texture { filterable: false }),
        binding(9, "out_accum", Kind::StorageTexture(wgpu::TextureFormat::Rgba16Float)),
        binding(10, "tile_offsets", Kind::Storage { read_only: true }),
        binding(11, "out_irradiance", Kind::StorageTexture(wgpu::TextureFormat::Rgba16Float)),
        binding(12, "s_normal_split", Kind::Texture { filterable: false }),
    ],
};

/// Bind group `interleave.split.inputs` of `shaders/knecht/interleave/split.wgsl` (group 0).
pub const SPLIT_INPUTS_BINDINGS: Bindings = Bindings {
    label: "interleave.split.inputs",
    shader: "knecht/interleave/split.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "params", Kind::Uniform),
        binding(1, "g_position", Kind::Texture { filterable: false }),
        binding(2, "g_normal", Kind::UintTexture),
        binding(3, "g_albedo", Kind::Texture { filterable: false }),
        binding(4, "g_material", Kind::Texture { filterable: false }),
        binding(5, "s_position", Kind::StorageTexture(LINEAR_DEPTH_FORMAT)),
        binding(6, "s_normal", Kind::StorageTexture(NORMAL_FORMAT)),
        binding(7, "s_albedo", Kind::StorageTexture(ALBEDO_FORMAT)),
        binding(8, "s_material", Kind::StorageTexture(MATERIAL_FORMAT)),
    ],
};

/// Bind group `interleave.merge.inputs` of `shaders/knecht/interleave/merge.wgsl` (group 0).
pub const MERGE_INPUTS_BINDINGS: Bindings = Bindings {
    label: "interleave.merge.inputs",
    shader: "knecht/interleave/merge.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "params", Kind::Uniform),
        binding(1, "split", Kind::Texture { filterable: false }),
        binding(2, "merged", Kind::StorageTexture(wgpu::TextureFormat::Rgba16Float)),
    ],
};

/// Format of the gathered and filtered light (`indirect.accum`, `indirect.merged`,
/// `indirect.filtered`): half floats, as `direct::RADIANCE_FORMAT` (issue #38; the kernel
/// tests allow one half step besides their own tolerance, since Vulkan lets a store round to
/// nearest or toward zero).
pub const LIGHT_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

/// Uniform of split and merge; WGSL twin: `SplitParams`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SplitParams {
    pub n: [u32; 4],
}

/// Uniform of the gather; WGSL twin: `GatherParams` in `shaders/knecht/interleave/gather.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GatherParams {
    pub split: [u32; 4],
    pub vis: [u32; 4],
    pub shade: Vec4,
    /// x: the near field's cut² (senders closer are skipped; 0: none), y–w: 0.
    pub near: Vec4,
}

/// Uniform of the filter; WGSL twin: `FilterParams`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct FilterParams {
    pub n: [u32; 4],
    pub thresholds: Vec4,
}

struct Split {
    position: wgpu::Texture,
    normal: wgpu::Texture,
    albedo: wgpu::Texture,
    material: wgpu::Texture,
    accum: wgpu::Texture,
    accum_irradiance: wgpu::Texture,
}

pub struct InterleavePass {
    n: u32,
    width: u32,
    height: u32,
    split: Option<Split>,
    pub merged: wgpu::Texture,
    /// The irradiance of `merged`'s light (Σ E_k·V_k·N/N_t), the demodulated filter's input.
    pub irradiance: wgpu::Texture,
    pub filtered: wgpu::Texture,
    /// The window's mean irradiance that `filtered` reflects (demodulated filter only): the
    /// demodulated confidence merge's E (`temporal.demodulate`).
    pub filtered_irradiance: wgpu::Texture,
    /// `interleave.split_passes`: the split textures exist only then.
    split_passes: bool,
    split_layout: wgpu::BindGroupLayout,
    gather_layout: wgpu::BindGroupLayout,
    merge_layout: wgpu::BindGroupLayout,
    filter_layout: wgpu::BindGroupLayout,
    split_pipeline: wgpu::ComputePipeline,
    /// By visibility mode (none, ISM, exact).
    gather_pipeline: [wgpu::ComputePipeline; 3],
    fused_pipeline: [wgpu::ComputePipeline; 3],
    merge_pipeline: wgpu::ComputePipeline,
    filter_pipeline: wgpu::ComputePipeline,
    split_params: wgpu::Buffer,
    gather_params: wgpu::Buffer,
    filter_params: wgpu::Buffer,
    dummy_ism: wgpu::TextureView,
    dummy_exact: wgpu::TextureView,
    /// 1×1 stand-ins for the gather's normals it does not read: the split's in the fused
    /// layout, the packed ones in the thesis' (issue #53).
    dummy_normals: [wgpu::TextureView; 2],
    /// This frame's slot→tile offsets (`cpu::knecht::tile_offsets`), one u32 per block.
    tile_offsets: wgpu::Buffer,
    /// Gathers run so far: the seed of the per-frame slot→tile map.
    pub frames: u32,
    /// The filter's own pass for a read of `indirect.filtered` after a frame that fused it
    /// into the merge (issue #53).
    on_read: std::sync::Arc<crate::passes::on_read::OnRead>,
}

/// The geometry-aware filter's bindings (`knecht/interleave/filter.wgsl`, group 0).
pub const FILTER_BINDINGS: Bindings = Bindings {
    label: "interleave.filter.inputs",
    shader: "knecht/interleave/filter.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "params", Kind::Uniform),
        binding(1, "src", Kind::Texture { filterable: false }),
        binding(2, "g_position", Kind::Texture { filterable: false }),
        binding(3, "g_normal", Kind::UintTexture),
        binding(4, "dst", Kind::StorageTexture(LIGHT_FORMAT)),
        binding(5, "irradiance", Kind::Texture { filterable: false }),
        binding(6, "g_albedo", Kind::Texture { filterable: false }),
        binding(7, "dst_irradiance", Kind::StorageTexture(LIGHT_FORMAT)),
    ],
};

/// What the gather at tiles or pixels reads (Knecht 002 §3.5): the camera, the G-buffer,
/// stage 3's VPLs and stage 4's visibility.
#[derive(Clone, Copy)]
pub struct ShadeInputs<'a> {
    pub camera: &'a wgpu::Buffer,
    pub g: &'a GBufferViews,
    /// `vpl.list` and how many of its slots to gather.
    pub vpls: &'a wgpu::Buffer,
    pub count: u32,
    /// The geometry term's distance clamp d_min (Eq. 4.7).
    pub min_distance: f32,
    /// Senders closer than this are the near field's (0: none).
    pub near_cut: f32,
    pub vis: &'a GatherVisibility,
    /// The receiver's BRDF: diffuse only (`vpl.receiver_brdf`).
    pub diffuse_only: bool,
}

impl InterleavePass {
    pub fn new(ctx: &GpuContext, width: u32, height: u32, n: u32, split_passes: bool) -> Self {
        let device = &ctx.device;
        let split_layout = SPLIT_INPUTS_BINDINGS.layout(device);
        let gather_layout = GATHER_INPUTS_BINDINGS.layout(device);
        let merge_layout = MERGE_INPUTS_BINDINGS.layout(device);
        let filter_layout = FILTER_BINDINGS.layout(device);
        let module = |p| crate::shaders::create_module(device, p);
        let split_pipeline = crate::passes::compute_pipeline(
            device,
            "interleave.split",
            &module("knecht/interleave/split.wgsl"),
            "cs_split",
            &[&split_layout],
        );
        let gather_module = module("knecht/interleave/gather.wgsl");
        // One pipeline per visibility mode (none, ISM, exact: `VISIBILITY_MODE`, issue #53), so
        // that each carries only its own test.
        let by_mode = |label: &str, entry: &str| {
            [0u32, 1, 2].map(|mode| {
                let constants = [("VISIBILITY_MODE", mode as f64)];
                let label = format!("{label}.visibility_{mode}");
                crate::gpu::compute_pipeline_with(
                    device,
                    &label,
                    (&gather_module, entry, &constants),
                    &[&gather_layout],
                )
            })
        };
        let gather_pipeline = by_mode("interleave.gather", "cs_gather");
        let fused_pipeline = by_mode("interleave.gather_fused", "cs_gather_fused");
        let merge_pipeline = crate::passes::compute_pipeline(
            device,
            "interleave.merge",
            &module("knecht/interleave/merge.wgsl"),
            "cs_merge",
            &[&merge_layout],
        );
        let filter_pipeline = crate::passes::compute_pipeline(
            device,
            "interleave.filter",
            &module("knecht/interleave/filter.wgsl"),
            "cs_filter",
            &[&filter_layout],
        );
        let on_read = crate::passes::on_read::OnRead::new(ctx, "interleave.filter", (width, height));
        let uniform = |label, size| {
            device.counted_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        let split_params = uniform("interleave.split.params", std::mem::size_of::<SplitParams>() as u64);
        let gather_params = uniform("interleave.gather.params", std::mem::size_of::<GatherParams>() as u64);
        let filter_params = uniform("interleave.filter.params", std::mem::size_of::<FilterParams>() as u64);
        let (dummy_ism, dummy_exact) = no_visibility_atlases(device, "interleave");
        let dummy_normals = crate::passes::gbuffer::normal_stand_ins(device, "interleave");
        let (split, [merged, irradiance, filtered, filtered_irradiance]) =
            Self::targets(device, width, height, n, split_passes);
        Self {
            n,
            width,
            height,
            split,
            merged,
            irradiance,
            filtered,
            filtered_irradiance,
            split_passes,
            split_layout,
            gather_layout,
            merge_layout,
            filter_layout,
            split_pipeline,
            gather_pipeline,
            fused_pipeline,
            merge_pipeline,
            filter_pipeline,
            split_params,
            gather_params,
            filter_params,
            dummy_ism,
            dummy_exact,
            dummy_normals,
            tile_offsets: Self::offsets_buffer(device, 256),
            frames: 0,
            on_read,
        }
    }

    fn offsets_buffer(device: &wgpu::Device, blocks: u32) -> wgpu::Buffer {
        device.counted_buffer(&wgpu::BufferDescriptor {
            label: Some("interleave.tile_offsets"),
            size: blocks.max(1) as u64 * 4,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        })
    }

    /// Tiles per side (`interleave.n`) of the textures as they are.
    pub fn n(&self) -> u32 {
        self.n
    }

    /// The gather's uniform as the last `shade` wrote it (`GatherParams`).
    pub fn gather_params(&self) -> &wgpu::Buffer {
        &self.gather_params
    }

    /// The slot→tile offsets of the last `shade` (`cpu::knecht::tile_offsets`).
    pub fn tile_offsets(&self) -> &wgpu::Buffer {
        &self.tile_offsets
    }

    /// Tile size of an n×n split of `width`×`height`.
    pub fn tile(width: u32, height: u32, n: u32) -> (u32, u32) {
        (width.div_ceil(n.max(1)), height.div_ceil(n.max(1)))
    }

    fn targets(
        device: &wgpu::Device,
        width: u32,
        height: u32,
        n: u32,
        split_passes: bool,
    ) -> (Option<Split>, [wgpu::Texture; 4]) {
        let (tw, th) = Self::tile(width, height, n);
        let (sw, sh) = (tw * n.max(1), th * n.max(1));
        let st = wgpu::TextureUsages::STORAGE_BINDING;
        let t = |label, w, h, f| crate::passes::create_target(device, label, w, h, f, st);
        let split = split_passes.then(|| Split {
            position: t("interleave.split.position", sw, sh, LINEAR_DEPTH_FORMAT),
            normal: t("interleave.split.normal", sw, sh, NORMAL_FORMAT),
            albedo: t("interleave.split.albedo", sw, sh, ALBEDO_FORMAT),
            material: t("interleave.split.material", sw, sh, MATERIAL_FORMAT),
            accum: t("indirect.accum", sw, sh, LIGHT_FORMAT),
            accum_irradiance: t("indirect.accum_irradiance", sw, sh, LIGHT_FORMAT),
        });
        let merged = t("indirect.merged", width, height, LIGHT_FORMAT);
        let irradiance = t("indirect.irradiance", width, height, LIGHT_FORMAT);
        let filtered = t("indirect.filtered", width, height, LIGHT_FORMAT);
        let filtered_irradiance = t("indirect.filtered_irradiance", width, height, LIGHT_FORMAT);
        (split, [merged, irradiance, filtered, filtered_irradiance])
    }

    /// Resizes for `width`×`height` and n; returns whether textures were recreated.
    pub fn ensure(&mut self, ctx: &GpuContext, width: u32, height: u32, n: u32, split_passes: bool) -> bool {
        if (width, height, n, split_passes) == (self.width, self.height, self.n, self.split_passes) {
            return false;
        }
        (self.split, [self.merged, self.irradiance, self.filtered, self.filtered_irradiance]) =
            Self::targets(&ctx.device, width, height, n, split_passes);
        (self.width, self.height, self.n, self.split_passes) = (width, height, n, split_passes);
        self.on_read = crate::passes::on_read::OnRead::new(ctx, "interleave.filter", (width, height));
        true
    }

    pub fn register(&self, reg: &mut BufferRegistry) {
        let n = self.n;
        if let Some(s) = &self.split {
            Self::register_split(reg, s, n);
        }
        reg.register(
            "indirect.merged",
            BufferKind::Hdr,
            "the accumulation buffer merged back to image layout (each pixel lit by one tile's VPLs)",
            &self.merged,
        );
        reg.register(
            "indirect.irradiance",
            BufferKind::Hdr,
            "the irradiance of indirect.merged's light (Σ E·V·N/N_t, before each pixel's BRDF): what the demodulated filter averages",
            &self.irradiance,
        );
        reg.register_derived(
            "indirect.filtered",
            BufferKind::Hdr,
            "indirect light after the geometry-aware n×n filter (Knecht §3.4.1); the confidence merge follows (fused into it by default: then filled when read)",
            &self.filtered,
            self.on_read.clone(),
        );
        reg.register_derived(
            "indirect.filtered_irradiance",
            BufferKind::Hdr,
            "the demodulated filter's mean irradiance E (indirect.filtered = k·E + the mean specular light): what the demodulated confidence merge keeps (stale when the filter ran on L)",
            &self.filtered_irradiance,
            self.on_read.clone(),
        );
    }

    fn register_split(reg: &mut BufferRegistry, s: &Split, n: u32) {
        reg.register(
            "interleave.split.albedo",
            BufferKind::Albedo,
            &format!("the camera G-buffer's colour split into {n}×{n} tiles (Knecht §3.4.1, Fig. 3.2)"),
            &s.albedo,
        );
        reg.register("interleave.split.normal", BufferKind::Direction, "split G-buffer: normals", &s.normal);
        reg.register(
            "interleave.split.position",
            BufferKind::Data,
            "split G-buffer: linear depth (the gather rebuilds the point at the source pixel)",
            &s.position,
        );
        reg.register("interleave.split.material", BufferKind::Data, "split G-buffer: SI, SP", &s.material);
        reg.register(
            "indirect.accum",
            BufferKind::Hdr,
            "indirect light of each tile's VPLs in the split layout, scaled to all VPLs (Knecht Fig. 3.4)",
            &s.accum,
        );
        reg.register(
            "indirect.accum_irradiance",
            BufferKind::Hdr,
            "the irradiance of indirect.accum's light, in the split layout",
            &s.accum_irradiance,
        );
    }

    /// Splits the G-buffer, gathers `inputs.count` VPLs into the split accumulation buffer
    /// (tile t takes this frame's share, `maths::tile_offsets`) and merges it back into
    /// `indirect.merged`.
    pub fn shade(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        timer: &mut crate::timing::GpuTimer,
        inputs: &ShadeInputs,
    ) {
        let ShadeInputs { camera, g, vpls, count: vpl_count, min_distance: d_min, near_cut, vis, diffuse_only } =
            *inputs;
        let n = self.n.max(1);
        let (tw, th) = Self::tile(self.width, self.height, n);
        let sp = SplitParams { n: [n, tw, th, 0] };
        ctx.queue.upload(&self.split_params, 0, bytemuck::bytes_of(&sp));
        let (code, atlas_ism, atlas_exact, cols, size, shade) = vis.parts(&self.dummy_ism, &self.dummy_exact);
        let mode = (code as usize).min(2);
        let gp = GatherParams {
            split: [n, tw, th, vpl_count],
            vis: [code, cols, size, diffuse_only as u32],
            shade: Vec4::new(d_min * d_min, shade.y, shade.z, shade.w),
            near: Vec4::new(near_cut * near_cut, 0.0, 0.0, 0.0),
        };
        ctx.queue.upload(&self.gather_params, 0, bytemuck::bytes_of(&gp));
        let offsets = crate::maths::tile_offsets(vpl_count, n, self.frames);
        self.frames = self.frames.wrapping_add(1);
        if (offsets.len() as u64) * 4 > self.tile_offsets.size() {
            self.tile_offsets = Self::offsets_buffer(&ctx.device, offsets.len() as u32);
        }
        if !offsets.is_empty() {
            ctx.queue.upload(&self.tile_offsets, 0, bytemuck::cast_slice(&offsets));
        }
        let v = |t: &wgpu::Texture, l: &str| crate::passes::view(t, l);
        let merged_v = v(&self.merged, "indirect.merged");
        let irradiance_v = v(&self.irradiance, "indirect.irradiance");
        let tv = wgpu::BindingResource::TextureView;
        // The gather reads the split G-buffer (three passes) or the G-buffer itself at each
        // split pixel's source pixel (fused) and writes the split accumulation buffer or the
        // merged light.
        let gather_group = |p: [&wgpu::TextureView; 5], out: &wgpu::TextureView, irr: &wgpu::TextureView| {
            let tv = wgpu::BindingResource::TextureView;
            GATHER_INPUTS_BINDINGS.group(
                &ctx.device,
                &self.gather_layout,
                [
                    camera.as_entire_binding(),
                    self.gather_params.as_entire_binding(),
                    vpls.as_entire_binding(),
                    tv(atlas_ism),
                    tv(atlas_exact),
                    tv(p[0]),
                    tv(p[1]),
                    tv(p[2]),
                    tv(p[3]),
                    tv(out),
                    self.tile_offsets.as_entire_binding(),
                    tv(irr),
                    tv(p[4]),
                ],
            )
        };
        let (sw, sh) = (tw * n, th * n);
        let tile = crate::passes::TILE;
        let Some(s) = self.split.as_ref().filter(|_| self.split_passes) else {
            let no_split = &self.dummy_normals[0];
            let inputs = [&g.linear_depth, &g.packed_normal, &g.albedo, &g.material, no_split];
            let group = gather_group(inputs, &merged_v, &irradiance_v);
            timer.scope(ctx, encoder, "interleave.gather", |e, slot| {
                let mut pass = e.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("interleave.gather_fused"),
                    timestamp_writes: slot.and_then(|s| s.compute(true, true)),
                });
                pass.set_pipe(&self.fused_pipeline[mode]);
                pass.set_group(0, &group, &[]);
                pass.dispatch(sw.div_ceil(tile), sh.div_ceil(tile), 1);
            });
            return;
        };
        let (sp_v, sn_v, sa_v, sm_v, acc_v, acc_irr_v) = (
            v(&s.position, "interleave.split.position"),
            v(&s.normal, "interleave.split.normal"),
            v(&s.albedo, "interleave.split.albedo"),
            v(&s.material, "interleave.split.material"),
            v(&s.accum, "indirect.accum"),
            v(&s.accum_irradiance, "indirect.accum_irradiance"),
        );
        let split_group = SPLIT_INPUTS_BINDINGS.group(
            &ctx.device,
            &self.split_layout,
            [
                self.split_params.as_entire_binding(),
                tv(&g.linear_depth),
                tv(&g.packed_normal),
                tv(&g.albedo),
                tv(&g.material),
                tv(&sp_v),
                tv(&sn_v),
                tv(&sa_v),
                tv(&sm_v),
            ],
        );
        let gather_group = gather_group([&sp_v, &self.dummy_normals[1], &sa_v, &sm_v, &sn_v], &acc_v, &acc_irr_v);
        // The light and its irradiance are merged back alike.
        let merge_group = |src: &wgpu::TextureView, dst: &wgpu::TextureView| {
            let tv = wgpu::BindingResource::TextureView;
            MERGE_INPUTS_BINDINGS.group(
                &ctx.device,
                &self.merge_layout,
                [self.split_params.as_entire_binding(), tv(src), tv(dst)],
            )
        };
        let merge_groups = [merge_group(&acc_v, &merged_v), merge_group(&acc_irr_v, &irradiance_v)];
        timer.scope(ctx, encoder, "interleave.split", |e, slot| {
            let mut pass = e.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("interleave.split"),
                timestamp_writes: slot.and_then(|s| s.compute(true, true)),
            });
            pass.set_pipe(&self.split_pipeline);
            pass.set_group(0, &split_group, &[]);
            pass.dispatch(sw.div_ceil(tile), sh.div_ceil(tile), 1);
        });
        timer.scope(ctx, encoder, "interleave.gather", |e, slot| {
            let mut pass = e.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("interleave.gather"),
                timestamp_writes: slot.and_then(|s| s.compute(true, true)),
            });
            pass.set_pipe(&self.gather_pipeline[mode]);
            pass.set_group(0, &gather_group, &[]);
            pass.dispatch(sw.div_ceil(tile), sh.div_ceil(tile), 1);
        });
        timer.scope(ctx, encoder, "interleave.merge", |e, slot| {
            let mut pass = e.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("interleave.merge"),
                timestamp_writes: slot.and_then(|s| s.compute(true, true)),
            });
            pass.set_pipe(&self.merge_pipeline);
            for group in &merge_groups {
                pass.set_group(0, group, &[]);
                pass.dispatch(self.width.div_ceil(tile), self.height.div_ceil(tile), 1);
            }
        });
    }

    /// The geometry-aware filter of `src` into `indirect.filtered` (n = 1: a copy).
    /// `irradiance`: the irradiance of `src`'s light (this frame's `indirect.irradiance` when
    /// `src` is `indirect.merged`), which the filter averages apart and reflects with each
    /// pixel's colour (`interleave.demodulate`); None: the thesis' filter of `src` (also when
    /// `src` is a merged history, which holds no irradiance).
    pub fn filter(
        &self,
        r: PassRec<'_, '_>,
        s: &InterleaveSettings,
        depth_range: f32,
        src: &wgpu::TextureView,
        g: &GBufferViews,
        irradiance: Option<&wgpu::TextureView>,
    ) {
        let PassRec { ctx, enc: encoder, slot } = r;
        let group = self.filter_group(ctx, s, depth_range, src, g, irradiance);
        self.on_read.arm(None);
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("interleave.filter"),
            timestamp_writes: slot.and_then(|s| s.compute(true, true)),
        });
        pass.set_pipe(&self.filter_pipeline);
        pass.set_group(0, &group, &[]);
        pass.dispatch(self.width.div_ceil(crate::passes::TILE), self.height.div_ceil(crate::passes::TILE), 1);
    }

    /// The filter's uniform for a merge that runs it fused (`TemporalPass::run_fused`,
    /// issue #53), written for these inputs as [`Self::filter`] would; its outputs
    /// (`indirect.filtered`, `indirect.filtered_irradiance`) are filled from the same inputs
    /// when read.
    pub fn prepare_fused(
        &self,
        ctx: &GpuContext,
        s: &InterleaveSettings,
        depth_range: f32,
        src: &wgpu::TextureView,
        g: &GBufferViews,
        irradiance: Option<&wgpu::TextureView>,
    ) -> &wgpu::Buffer {
        let group = self.filter_group(ctx, s, depth_range, src, g, irradiance);
        self.on_read.arm(Some((&self.filter_pipeline, group)));
        &self.filter_params
    }

    /// Writes the filter's uniform and makes its bind group (see [`Self::filter`]).
    fn filter_group(
        &self,
        ctx: &GpuContext,
        s: &InterleaveSettings,
        depth_range: f32,
        src: &wgpu::TextureView,
        g: &GBufferViews,
        irradiance: Option<&wgpu::TextureView>,
    ) -> wgpu::BindGroup {
        let n = self.n.max(1);
        let fp = FilterParams {
            n: [n, irradiance.is_some() as u32, 0, 0],
            thresholds: Vec4::new(s.alpha * depth_range, s.beta, 0.0, 0.0),
        };
        ctx.queue.upload(&self.filter_params, 0, bytemuck::bytes_of(&fp));
        let dst = crate::passes::view(&self.filtered, "indirect.filtered");
        let dst_irradiance = crate::passes::view(&self.filtered_irradiance, "indirect.filtered_irradiance");
        // Without it the shader reads no irradiance: `src` stands in for the binding.
        let irradiance = irradiance.unwrap_or(src);
        let tv = wgpu::BindingResource::TextureView;
        let resources = [
            self.filter_params.as_entire_binding(),
            tv(src),
            tv(&g.linear_depth),
            tv(&g.packed_normal),
            tv(&dst),
            tv(irradiance),
            tv(&g.albedo),
            tv(&dst_irradiance),
        ];
        FILTER_BINDINGS.group(&ctx.device, &self.filter_layout, resources)
    }
}
