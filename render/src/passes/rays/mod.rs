//! Rays on the GPU (issue #56 point 1; docs/architecture.md "Rays on the GPU"): the scene's
//! two-level hierarchy ([`crate::scene::two_level`]) in storage buffers, bound as group 1 of
//! any kernel that imports `shaders/rays/scene.wgsl`, and [`RayCastPass`], a batch of rays
//! cast through it (the tests against the path tracer's traversal, `gi-lab bench --suite
//! rays`). The GPU path tracer and the DDGI probe update (issue #56 points 2 and 3) trace
//! with the same module.

use crate::counters::prelude::*;

pub mod pathtrace;
pub mod shade;

use glam::{Vec3, Vec4};

use crate::gpu::GpuContext;
use crate::gpu::bindings::{Bindings, Kind, binding};
use crate::scene::two_level::{Query, TwoLevel};
use crate::scene::{Scene, SceneState};

const CS: wgpu::ShaderStages = wgpu::ShaderStages::COMPUTE;
const READ: Kind = Kind::Storage { read_only: true };

/// The walk's stack (`RAY_STACK` in `shaders/rays/scene.wgsl`): a tree deeper than this
/// less one is refused at upload.
pub const RAY_STACK: u32 = 64;

/// The scene's group (`rays/scene.wgsl`, group 1), as the batch caster binds it.
pub const RAY_SCENE_BINDINGS: Bindings = Bindings {
    label: "rays.scene",
    shader: "rays/cast.wgsl",
    group: 1,
    entry: None,
    visibility: CS,
    list: &[
        binding(0, "ray_scene", Kind::Uniform),
        binding(1, "ray_nodes", READ),
        binding(2, "ray_tris", READ),
        binding(3, "ray_vertices", READ),
        binding(4, "ray_indices", READ),
        binding(5, "ray_instances", READ),
        binding(6, "ray_materials", READ),
        binding(7, "ray_textures", READ),
        binding(8, "ray_texels", READ),
    ],
};

/// WGSL twin: `RaySceneInfo` in `shaders/rays/scene.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct RaySceneInfo {
    pub tlas_root: u32,
    pub tlas_nodes: u32,
    pub instances: u32,
    pub materials: u32,
}

/// The scene's hierarchy, materials and textures on the GPU.
pub struct RayScene {
    /// The CPU copy (the top level is rebuilt there and its nodes uploaded).
    pub cpu: TwoLevel,
    info: wgpu::Buffer,
    nodes: wgpu::Buffer,
    instances: wgpu::Buffer,
    /// The other buffers, kept alive with the group.
    _rest: Vec<wgpu::Buffer>,
    pub layout: wgpu::BindGroupLayout,
    pub group: wgpu::BindGroup,
    /// Bytes on the GPU.
    pub bytes: u64,
}

/// A storage buffer holding `data` (at least `min` zero bytes: a binding of zero bytes, or
/// one shorter than the array's element, is a validation error).
pub(crate) fn storage(ctx: &GpuContext, label: &str, data: &[u8], min: usize) -> wgpu::Buffer {
    let mut bytes = data.to_vec();
    if bytes.len() < min {
        bytes.resize(min, 0);
    }
    ctx.device.counted_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents: &bytes,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
    })
}

impl RayScene {
    /// Builds the hierarchy of `scene` at `state` and uploads it; a clear message when it does
    /// not fit the device (a buffer past `max_storage_buffer_binding_size`, a tree deeper
    /// than the walk's stack).
    pub fn new(ctx: &GpuContext, scene: &Scene, state: &SceneState) -> Result<Self, String> {
        let cpu = TwoLevel::new(scene, state);
        if cpu.depth >= RAY_STACK {
            return Err(format!(
                "the scene's ray hierarchy is {} levels deep, the GPU walk holds {}",
                cpu.depth,
                RAY_STACK - 1
            ));
        }
        let limit = ctx.device.limits().max_storage_buffer_binding_size;
        let parts: [(&str, &[u8], usize); 8] = [
            ("rays.nodes", bytemuck::cast_slice(&cpu.nodes), 32),
            ("rays.tris", bytemuck::cast_slice(&cpu.tris), 48),
            ("rays.vertices", bytemuck::cast_slice(&cpu.vertices), 48),
            ("rays.indices", bytemuck::cast_slice(&cpu.indices), 12),
            ("rays.instances", bytemuck::cast_slice(&cpu.instances), 208),
            ("rays.materials", bytemuck::cast_slice(&cpu.materials), 64),
            ("rays.textures", bytemuck::cast_slice(&cpu.texture_table), 16),
            ("rays.texels", bytemuck::cast_slice(&cpu.texels), 4),
        ];
        for (label, data, _) in &parts {
            if data.len() as u64 > limit {
                return Err(format!(
                    "{label}: {:.1} MiB is more than this device binds in one storage buffer ({:.1} MiB): \
                     the scene is too large for the GPU ray caster here",
                    data.len() as f64 / 1048576.0,
                    limit as f64 / 1048576.0
                ));
            }
        }
        let buffers: Vec<wgpu::Buffer> = parts.iter().map(|(l, d, m)| storage(ctx, l, d, *m)).collect();
        let info = ctx.device.counted_buffer(&wgpu::BufferDescriptor {
            label: Some("rays.scene.info"),
            size: std::mem::size_of::<RaySceneInfo>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let layout = RAY_SCENE_BINDINGS.layout(&ctx.device);
        let group = RAY_SCENE_BINDINGS.group(
            &ctx.device,
            &layout,
            std::iter::once(info.as_entire_binding()).chain(buffers.iter().map(|b| b.as_entire_binding())),
        );
        let bytes = buffers.iter().map(|b| b.size()).sum::<u64>() + info.size();
        let mut rest = buffers;
        let instances = rest.remove(4);
        let nodes = rest.remove(0);
        let s = Self { cpu, info, nodes, instances, _rest: rest, layout, group, bytes };
        s.write_info(ctx);
        Ok(s)
    }

    fn write_info(&self, ctx: &GpuContext) {
        let info = RaySceneInfo {
            tlas_root: self.cpu.tlas_base,
            tlas_nodes: self.cpu.tlas_nodes,
            instances: self.cpu.instances.len() as u32,
            materials: self.cpu.materials.len() as u32,
        };
        ctx.queue.upload(&self.info, 0, bytemuck::bytes_of(&info));
    }

    /// The instances of `state` (the same draws, moved) and the top level over them,
    /// rebuilt on the CPU and uploaded (the bottom levels stay).
    pub fn update(&mut self, ctx: &GpuContext, scene: &Scene, state: &SceneState) {
        self.cpu.set_instances(scene, state);
        let base = self.cpu.tlas_base as u64 * std::mem::size_of::<crate::scene::sah::BvhNode>() as u64;
        ctx.queue.upload(&self.nodes, base, bytemuck::cast_slice(self.cpu.tlas()));
        if !self.cpu.instances.is_empty() {
            ctx.queue.upload(&self.instances, 0, bytemuck::cast_slice(&self.cpu.instances));
        }
        self.write_info(ctx);
    }
}

/// One ray of a batch; WGSL twin: `CastRay` in `shaders/rays/cast.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct CastRay {
    /// Origin (xyz) and tmin (w).
    pub origin: Vec4,
    /// Direction (xyz) and tmax (w).
    pub dir: Vec4,
}

impl CastRay {
    pub fn new(o: Vec3, d: Vec3, tmin: f32, tmax: f32) -> Self {
        Self { origin: o.extend(tmin), dir: d.extend(tmax) }
    }
}

/// A ray's hit; WGSL twin: `CastHit`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct CastHit {
    /// Position (xyz) and t (w).
    pub p: Vec4,
    /// Normal facing the ray (xyz), material (w, the bits of a u32).
    pub n: Vec4,
    /// Barycentrics (xy), texture coordinates (zw).
    pub bary_uv: Vec4,
    /// Instance, triangle, front face (1), hit (1).
    pub ids: [u32; 4],
}

impl CastHit {
    pub fn hit(&self) -> bool {
        self.ids[3] != 0
    }
    pub fn material(&self) -> u32 {
        self.n.w.to_bits()
    }
}

/// WGSL twin: `CastParams`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
struct CastParams {
    count: u32,
    query: u32,
    row: u32,
    _pad: u32,
}

/// The batch's group (`rays/cast.wgsl`, group 0).
pub const CAST_BINDINGS: Bindings = Bindings {
    label: "rays.cast.inputs",
    shader: "rays/cast.wgsl",
    group: 0,
    entry: None,
    visibility: CS,
    list: &[
        binding(0, "cast_params", READ),
        binding(1, "cast_rays", READ),
        binding(2, "cast_hits", Kind::Storage { read_only: false }),
    ],
};

/// Casts batches of rays through a [`RayScene`].
pub struct RayCastPass {
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::ComputePipeline,
}

impl RayCastPass {
    pub fn new(ctx: &GpuContext, scene: &RayScene) -> Self {
        let layout = CAST_BINDINGS.layout(&ctx.device);
        let module = crate::shaders::create_module(&ctx.device, "rays/cast.wgsl");
        let pipeline =
            crate::passes::compute_pipeline(&ctx.device, "rays.cast", &module, "cs_cast", &[&layout, &scene.layout]);
        Self { layout, pipeline }
    }

    /// The hits of `rays` for `query` (blocks until they are read back).
    pub fn cast(
        &self,
        ctx: &GpuContext,
        scene: &RayScene,
        rays: &[CastRay],
        query: Query,
    ) -> Result<Vec<CastHit>, String> {
        if rays.is_empty() {
            return Ok(Vec::new());
        }
        let groups = (rays.len() as u32).div_ceil(64);
        let x = groups.min(ctx.device.limits().max_compute_workgroups_per_dimension.max(1));
        let y = groups.div_ceil(x);
        let params = CastParams {
            count: rays.len() as u32,
            query: match query {
                Query::Closest => 0,
                Query::Camera => 1,
                Query::Any => 2,
            },
            row: x * 64,
            _pad: 0,
        };
        let params = storage(ctx, "rays.cast.params", bytemuck::bytes_of(&params), 16);
        let input = storage(ctx, "rays.cast.rays", bytemuck::cast_slice(rays), 32);
        let bytes = (rays.len() * std::mem::size_of::<CastHit>()) as u64;
        let hits = crate::passes::buffer(
            &ctx.device,
            "rays.cast.hits",
            bytes,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        );
        let group = CAST_BINDINGS.group(
            &ctx.device,
            &self.layout,
            [params.as_entire_binding(), input.as_entire_binding(), hits.as_entire_binding()],
        );
        let mut enc = ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("rays.cast") });
        {
            let mut pass = enc
                .begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("rays.cast"), timestamp_writes: None });
            pass.set_pipe(&self.pipeline);
            pass.set_group(0, &group, &[]);
            pass.set_group(1, &scene.group, &[]);
            pass.dispatch(x, y, 1);
        }
        ctx.submit([enc.finish()]);
        let data = crate::buffers::read_storage(ctx, &hits, bytes)?;
        Ok(bytemuck::pod_collect_to_vec(&data))
    }
}
