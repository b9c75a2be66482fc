//! Visibility of Soler et al.'s gather (004 §4 "Visibility", after Eisemann & Décoret's solid
//! voxelization): the scene drawn from the camera into a grid of one column of `voxel_slices`
//! bits per pixel of the screen, as 004 §4 does, or per texel of the first gathered level
//! (`soler.voxel_resolution`; ⚠[soler.voxel-grid] the depth range the slices divide, the
//! scene's bounding sphere along the view axis, is ours), every fragment toggling its column
//! from its slice to the back
//! (`shaders/soler/voxelize.wgsl`, atomicXor from the fragment stage: WebGPU has no logic-op
//! blending), a surface that faces the viewer toggling at its depth moved back by its slope
//! across the texel (`voxel_slope_bias`); each coarser level's grid is the AND of the four
//! columns below (`voxel_down.wgsl`), from the screen's grid down to the gathered levels'
//! (those below the first gathered level are not marched); the gather marches each sample's path through its
//! level's grid (`gather.wgsl`). CPU twin: `cpu::soler::{voxelize_column, and_down,
//! march_visible}`. The viewer's image of each grid is `soler.voxels.k` (`voxel_view.wgsl`).
//!
//! Solid voxelization needs closed meshes; [`open_meshes`] names those that are not (a room
//! of single walls seen from inside is one: the half-space behind each wall counts as solid,
//! which leaves the room's inside right).

use crate::counters::prelude::*;
use crate::gpu::bindings::{Bindings, Kind, binding};

use super::STRIDE;
use crate::buffers::{BufferKind, BufferRegistry};
use crate::gpu::GpuContext;
use crate::scene::upload::GpuScene;
use crate::scene::{Scene, SceneState};
use crate::timing::PassRec;

/// Bind group `soler.voxel_down.inputs` of `shaders/soler/voxel_down.wgsl` (group 0): one
/// coarser level of the voxel grid from the finer one.
pub const DOWN_INPUTS_BINDINGS: Bindings = Bindings {
    label: "soler.voxel_down.inputs",
    shader: "soler/voxel_down.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "params", Kind::UniformDynamic),
        binding(1, "fine", Kind::Storage { read_only: true }),
        binding(2, "coarse", Kind::Storage { read_only: false }),
    ],
};

/// Bind group `soler.voxel_view.inputs` of `shaders/soler/voxel_view.wgsl` (group 0): a level
/// of the grid drawn for the viewer.
pub const VIEW_INPUTS_BINDINGS: Bindings = Bindings {
    label: "soler.voxel_view.inputs",
    shader: "soler/voxel_view.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "params", Kind::UniformDynamic),
        binding(1, "grid", Kind::Storage { read_only: true }),
        binding(2, "out_view", Kind::StorageTexture(wgpu::TextureFormat::Rgba32Float)),
    ],
};

/// The voxelisation's grid group (group 3 of `shaders/soler/voxelize.wgsl`): the level's
/// parameters and its occupancy bits.
pub const GRID_BINDINGS: Bindings = Bindings {
    label: "soler.voxelize.grid",
    shader: "soler/voxelize.wgsl",
    group: 3,
    entry: None,
    visibility: wgpu::ShaderStages::FRAGMENT,
    list: &[binding(0, "params", Kind::UniformDynamic), binding(1, "grid", Kind::Storage { read_only: false })],
};
/// Rust twin of `VoxelParams` in `shaders/soler/voxel_common.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct VoxelParams {
    /// The grid's W, H (columns), 32-bit words per column, slices; W = 0: no visibility.
    pub grid: [u32; 4],
    /// z₀, z₁ (view depths of the grid's front and back), G-buffer pixels per texel (2^k),
    /// the viewer's slice (< 0: the filled fraction).
    pub depth: [f32; 4],
    /// The toggles' slope bias b, its cap (slices); unused, unused.
    pub toggle: [f32; 4],
}

/// One gathered level's grid.
pub struct VoxelGrid {
    pub level: u32,
    pub width: u32,
    pub height: u32,
    /// `width × height × words` u32, row-major columns.
    pub buffer: wgpu::Buffer,
    /// `soler.voxels.k`: r the viewer's slice (or the filled fraction), g 1 where the column
    /// ends inside a solid.
    pub view: wgpu::Texture,
}

pub struct SolerVoxels {
    /// The grids from the voxelized level up: the screen's (level 0) or the first gathered
    /// level's, then one per level to the top.
    pub grids: Vec<VoxelGrid>,
    /// Index in `grids` of the first gathered level's grid.
    pub first_gathered: usize,
    pub words: u32,
    /// Bound in place of a grid when visibility is off.
    pub empty: wgpu::Buffer,
    /// The colour target the voxelization needs (nothing is written to it).
    target: Option<wgpu::Texture>,
    camera_layout: wgpu::BindGroupLayout,
    grid_layout: wgpu::BindGroupLayout,
    voxelize: wgpu::RenderPipeline,
    down_layout: wgpu::BindGroupLayout,
    down: wgpu::ComputePipeline,
    view_layout: wgpu::BindGroupLayout,
    view_pipeline: wgpu::ComputePipeline,
    params: wgpu::Buffer,
}

const TARGET_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R8Unorm;

impl SolerVoxels {
    pub fn new(ctx: &GpuContext) -> Self {
        let device = &ctx.device;
        // The camera and instance layouts equal the G-buffer's and the scene's (WebGPU: bind
        // groups of equal layouts are interchangeable).
        let camera_layout = crate::passes::gbuffer::CAMERA_BINDINGS.layout_labelled(device, "soler.voxelize.camera");
        let instance_layout =
            crate::scene::upload::INSTANCES_BINDINGS.layout_labelled(device, "soler.voxelize.instances");
        let grid_layout = GRID_BINDINGS.layout(device);
        let module = crate::shaders::create_module(device, "soler/voxelize.wgsl");
        // The scene's materials (group 2): alpha cutouts toggle nothing.
        let material_layout = crate::scene::upload::material_layout(device, "soler.voxelize.material");
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("soler.voxelize.layout"),
            bind_group_layouts: &[
                Some(&camera_layout),
                Some(&instance_layout),
                Some(&material_layout),
                Some(&grid_layout),
            ],
            immediate_size: 0,
        });
        let voxelize = device.counted_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("soler.voxelize"),
            layout: Some(&pipeline_layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_voxelize"),
                compilation_options: Default::default(),
                buffers: &[Some(crate::scene::upload::vertex_layout())],
            },
            // Every surface, front or back, toggles its column: no culling, no depth test.
            primitive: wgpu::PrimitiveState { topology: wgpu::PrimitiveTopology::TriangleList, ..Default::default() },
            depth_stencil: None,
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs_voxelize"),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState {
                    format: TARGET_FORMAT,
                    blend: None,
                    write_mask: wgpu::ColorWrites::empty(),
                })],
            }),
            multiview_mask: None,
            cache: None,
        });
        let down_layout = DOWN_INPUTS_BINDINGS.layout(device);
        let down_module = crate::shaders::create_module(device, "soler/voxel_down.wgsl");
        let down =
            crate::passes::compute_pipeline(device, "soler.voxel_down", &down_module, "cs_down", &[&down_layout]);
        let view_layout = VIEW_INPUTS_BINDINGS.layout(device);
        let view_module = crate::shaders::create_module(device, "soler/voxel_view.wgsl");
        let view_pipeline =
            crate::passes::compute_pipeline(device, "soler.voxel_view", &view_module, "cs_view", &[&view_layout]);
        let params = crate::passes::uniform_buffer(device, "soler.voxels.params", STRIDE * super::MAX_GATHERED as u64);
        let empty = crate::passes::buffer(device, "soler.voxels.empty", 16, wgpu::BufferUsages::STORAGE);
        Self {
            grids: Vec::new(),
            first_gathered: 0,
            words: 0,
            empty,
            target: None,
            camera_layout,
            grid_layout,
            voxelize,
            down_layout,
            down,
            view_layout,
            view_pipeline,
            params,
        }
    }

    /// Grids for `levels` (level, size: the voxelized level and every one above it to the
    /// top), `first_gathered` the index of the first gathered one among them, with `words` per
    /// column, or none when visibility is off; true when replaced.
    pub fn ensure(
        &mut self,
        ctx: &GpuContext,
        levels: &[(u32, (u32, u32))],
        first_gathered: usize,
        words: u32,
        on: bool,
    ) -> bool {
        let want: Vec<(u32, u32, u32)> =
            if on { levels.iter().map(|&(k, (w, h))| (k, w, h)).collect() } else { vec![] };
        let have: Vec<(u32, u32, u32)> = self.grids.iter().map(|g| (g.level, g.width, g.height)).collect();
        if have == want && (self.words == words || !on) {
            self.first_gathered = first_gathered;
            return false;
        }
        let device = &ctx.device;
        self.words = words;
        self.first_gathered = first_gathered;
        self.grids = want
            .iter()
            .map(|&(k, w, h)| {
                let size = (w as u64 * h as u64 * words as u64 * 4).max(16);
                let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC;
                VoxelGrid {
                    level: k,
                    width: w,
                    height: h,
                    buffer: crate::passes::buffer(device, &format!("soler.voxels.{k}.grid"), size, usage),
                    view: crate::passes::create_target(
                        device,
                        &format!("soler.voxels.{k}"),
                        w,
                        h,
                        wgpu::TextureFormat::Rgba32Float,
                        wgpu::TextureUsages::STORAGE_BINDING,
                    ),
                }
            })
            .collect();
        self.target = want.first().map(|&(_, w, h)| {
            crate::passes::create_target(
                device,
                "soler.voxelize.target",
                w,
                h,
                TARGET_FORMAT,
                wgpu::TextureUsages::RENDER_ATTACHMENT,
            )
        });
        true
    }

    /// The gathered levels' grids, the ones the gather marches.
    pub fn gathered(&self) -> &[VoxelGrid] {
        &self.grids[self.first_gathered.min(self.grids.len())..]
    }

    pub fn register(&self, reg: &mut BufferRegistry) {
        for g in &self.grids {
            reg.register(
                &format!("soler.voxels.{}", g.level),
                BufferKind::Data,
                "Soler visibility grid of one level (004 §4 \"Visibility\"): r the bit of slice soler.voxel_view_slice (−1: the column's filled fraction), g 1 where the column ends inside a solid (an open mesh, or a wall seen from inside)",
                &g.view,
            );
        }
    }

    /// The grid parameters of each gathered level: `z` the grid's depth range, `scale` the
    /// G-buffer pixels per texel of each level (2^k), `view_slice` the viewer's slice, `slope`
    /// the toggles' slope bias and its cap in slices.
    pub fn params_of(&self, z: (f32, f32), slices: u32, view_slice: f32, slope: (f32, f32)) -> Vec<VoxelParams> {
        self.grids
            .iter()
            .map(|g| VoxelParams {
                grid: [g.width, g.height, self.words, slices],
                depth: [z.0, z.1, (1u64 << g.level) as f32, view_slice],
                toggle: [slope.0, slope.1, 0.0, 0.0],
            })
            .collect()
    }

    /// Voxelizes the scene into the first grid, ANDs it down the others and writes the
    /// viewer's images. `gbuffer_size` is the G-buffer's (the viewport maps it onto the grid).
    pub fn run(
        &self,
        r: PassRec<'_, '_>,
        camera: &wgpu::Buffer,
        scene: &GpuScene,
        state: &SceneState,
        params: &[VoxelParams],
        gbuffer_size: (u32, u32),
    ) {
        let PassRec { ctx, enc: encoder, slot } = r;
        let (Some(first), Some(target)) = (self.grids.first(), &self.target) else { return };
        let device = &ctx.device;
        ctx.queue.upload(&self.params, 0, &crate::passes::strided_bytes(STRIDE, params.len(), params));
        let uniform = crate::passes::dynamic_slot(&self.params, std::mem::size_of::<VoxelParams>());
        for g in &self.grids {
            encoder.counted_clear_buffer(&g.buffer, 0, None);
        }
        let camera_group = crate::passes::gbuffer::CAMERA_BINDINGS.group_labelled(
            device,
            "soler.voxelize.camera",
            &self.camera_layout,
            [camera.as_entire_binding()],
        );
        let grid_group =
            GRID_BINDINGS.group(device, &self.grid_layout, [uniform.clone(), first.buffer.as_entire_binding()]);
        let target_view = crate::passes::view(target, "soler.voxelize.target");
        {
            let mut pass = encoder.begin_counted_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("soler.voxelize"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &target_view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                        store: wgpu::StoreOp::Discard,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: slot.as_ref().and_then(|s| s.render(true, false)),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            // The G-buffer's pixels onto the grid's texels: 1/2^k of its size.
            let scale = 1.0 / (1u64 << first.level) as f32;
            let (vw, vh) = (gbuffer_size.0 as f32 * scale, gbuffer_size.1 as f32 * scale);
            pass.set_viewport(0.0, 0.0, vw.min(first.width as f32), vh.min(first.height as f32), 0.0, 1.0);
            pass.set_pipe(&self.voxelize);
            pass.set_group(0, &camera_group, &[]);
            pass.set_group(1, &scene.instance_group, &[]);
            pass.set_group(3, &grid_group, &[0]);
            scene.draw(&mut pass, state, Some(2), None);
        }
        let n = self.grids.len();
        for (i, g) in self.grids.iter().enumerate() {
            let offset = [(i as u64 * STRIDE) as u32];
            if let Some(next) = self.grids.get(i + 1) {
                let group = DOWN_INPUTS_BINDINGS.group(
                    device,
                    &self.down_layout,
                    [uniform.clone(), g.buffer.as_entire_binding(), next.buffer.as_entire_binding()],
                );
                let size = (next.width, next.height);
                crate::passes::dispatch_2d(encoder, "soler.voxel_down", &self.down, &group, &offset, None, size);
            }
            let view = crate::passes::view(&g.view, "soler.voxels.view");
            let group = VIEW_INPUTS_BINDINGS.group(
                device,
                &self.view_layout,
                [uniform.clone(), g.buffer.as_entire_binding(), wgpu::BindingResource::TextureView(&view)],
            );
            let stamps = slot.as_ref().and_then(|s| s.compute(false, i + 1 == n));
            crate::passes::dispatch_2d(
                encoder,
                "soler.voxel_view",
                &self.view_pipeline,
                &group,
                &offset,
                stamps,
                (g.width, g.height),
            );
        }
    }
}

/// The grid's depth range (z₀, z₁): the scene's bounding sphere (centre `center`, radius
/// `radius`) along the camera's view axis, cut to [`from`, `to`] of it and kept in front of
/// the near plane.
pub fn depth_range(
    eye: glam::Vec3,
    forward: glam::Vec3,
    center: glam::Vec3,
    radius: f32,
    znear: f32,
    from: f32,
    to: f32,
) -> (f32, f32) {
    let c = (center - eye).dot(forward.normalize_or_zero());
    let (near, far) = ((c - radius).max(znear), (c + radius).max(znear + 1e-3));
    let (a, b) = (from.min(to), from.max(to));
    let z0 = near + (far - near) * a;
    let z1 = (near + (far - near) * b).max(z0 + 1e-3);
    (z0, z1)
}

/// The meshes whose surface is not closed (an edge used by an odd number of triangles,
/// positions welded), with their count of open edges: solid voxelization counts the wrong side of them
/// as solid. Sorted by name.
pub fn open_meshes(scene: &Scene) -> Vec<(String, usize)> {
    use std::collections::HashMap;
    let mut out = Vec::new();
    for m in &scene.meshes {
        let size =
            m.primitives.iter().flat_map(|p| &p.vertices).flat_map(|v| v.position).fold(0.0f32, |a, c| a.max(c.abs()));
        let weld = (size * 1e-5).max(1e-12);
        let mut ids: HashMap<[i64; 3], u32> = HashMap::new();
        let mut edges: HashMap<(u32, u32), u32> = HashMap::new();
        for p in &m.primitives {
            let mut id = |i: u32| -> Option<u32> {
                let v = p.vertices.get(i as usize)?;
                // Positions closer than 1e-5 of the mesh's size are one (a sphere's seam and
                // poles are computed twice with different rounding).
                let key = v.position.map(|c| (c / weld).round() as i64);
                let n = ids.len() as u32;
                Some(*ids.entry(key).or_insert(n))
            };
            for t in p.indices.chunks_exact(3) {
                let (Some(a), Some(b), Some(c)) = (id(t[0]), id(t[1]), id(t[2])) else { continue };
                // Degenerate triangles (a sphere's poles) close nothing and open nothing.
                if a == b || b == c || c == a {
                    continue;
                }
                for (u, v) in [(a, b), (b, c), (c, a)] {
                    *edges.entry((u.min(v), u.max(v))).or_insert(0) += 1;
                }
            }
        }
        let open = edges.values().filter(|&&n| n % 2 == 1).count();
        if open > 0 {
            out.push((m.name.clone(), open));
        }
    }
    out.sort();
    out
}
