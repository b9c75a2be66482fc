//! Stage 3 of instant radiosity (Knecht 002 §3.3, §4.3–4.4): every view of every light
//! renders a light G-buffer (`vpl.light_gbuffer.*`; view k > 0 as `vpl.light_gbuffer.k.*`),
//! its texels get the importance of Eq. 4.3 (`vpl.importance`, one layer per view with its
//! mip pyramid), and one pass per view warps a Halton set down the pyramid (hierarchical
//! warping, Clarberg et al. 2005) and creates the VPLs (`vpl.list`).
//! Shaders: `shaders/knecht/vpl/{importance,reduce,warp}.wgsl`; CPU twins in `cpu::knecht`.
//!
//! The VPL budget N is split over the views by the lights' power ([`view_powers`]): the
//! thesis samples one spot light; point lights' cube maps were not importance-sampled there
//! (§4.4.3) — here every face is, and gets its share of the light's budget by solid angle.

use crate::counters::prelude::*;

use glam::Vec4;

use crate::buffers::{BufferKind, BufferRegistry};
use crate::gpu::GpuContext;
use crate::gpu::bindings::{Bindings, Kind, binding};
use crate::passes::CameraUniform;
use crate::passes::gbuffer::GBufferPass;
use crate::passes::reference::vpl::GpuVpl;
use crate::passes::shadow::{GpuLight, LightView};
use crate::scene::upload::GpuScene;
use crate::scene::{LightKind, SceneState, WorldLight};
pub use crate::settings::knecht::{ReceiverBrdf, VplSettings};

/// Bind group `vpl.importance.inputs` of `shaders/knecht/vpl/importance.wgsl` (group 0).
pub const IMPORTANCE_INPUTS_BINDINGS: Bindings = Bindings {
    label: "vpl.importance.inputs",
    shader: "knecht/vpl/importance.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "vp", Kind::StorageDynamic),
        binding(1, "lights", Kind::Storage { read_only: true }),
        binding(2, "lg_position", Kind::Texture { filterable: false }),
        binding(3, "lg_normal", Kind::Texture { filterable: false }),
        binding(4, "lg_albedo", Kind::Texture { filterable: false }),
        binding(5, "lg_material", Kind::Texture { filterable: false }),
        binding(6, "importance", Kind::StorageTextureArray(wgpu::TextureFormat::R32Float)),
    ],
};

/// Bind group `vpl.importance.reduce` of `shaders/knecht/vpl/reduce.wgsl` (group 0).
pub const IMPORTANCE_REDUCE_BINDINGS: Bindings = Bindings {
    label: "vpl.importance.reduce",
    shader: "knecht/vpl/reduce.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "finer", Kind::TextureArray { filterable: false }),
        binding(1, "coarser", Kind::StorageTextureArray(wgpu::TextureFormat::R32Float)),
    ],
};

/// Bind group `vpl.warp.inputs` of `shaders/knecht/vpl/warp.wgsl` (group 0).
pub const WARP_INPUTS_BINDINGS: Bindings = Bindings {
    label: "vpl.warp.inputs",
    shader: "knecht/vpl/warp.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "vp", Kind::StorageDynamic),
        binding(1, "lights", Kind::Storage { read_only: true }),
        binding(2, "lg_position", Kind::Texture { filterable: false }),
        binding(3, "lg_normal", Kind::Texture { filterable: false }),
        binding(4, "lg_albedo", Kind::Texture { filterable: false }),
        binding(5, "lg_material", Kind::Texture { filterable: false }),
        binding(6, "importance", Kind::TextureArray { filterable: false }),
        binding(7, "vpls", Kind::Storage { read_only: false }),
        binding(8, "warped", Kind::Storage { read_only: false }),
    ],
};

/// Uniform of one view's importance and warp passes; WGSL twin: `ViewParams` in
/// `shaders/knecht/vpl/importance.wgsl` and `shaders/knecht/vpl/warp.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ViewParams {
    pub eye: Vec4,
    pub forward: Vec4,
    /// First VPL slot, VPL count of the view, light index, importance layer.
    pub range: [u32; 4],
    /// Halton index of this frame's first sample.
    pub seq: [u32; 4],
    /// Flux scale, finest side, Eq. 4.3's constant b.
    pub scale: Vec4,
}

/// Dynamic-offset stride of the per-view uniforms.
const STRIDE: u64 = 256;
/// The VPL buffers' smallest capacity (VPLs).
const MIN_VPL_CAPACITY: u32 = 256;

/// One view of one light that receives `count` VPLs starting at slot `first`.
#[derive(Clone, Copy, Debug)]
pub struct ViewJob {
    pub light_index: u32,
    pub view: LightView,
    pub first: u32,
    pub count: u32,
}

/// The power each view stands for, for the VPL budget split: spot I·2π(1 − cos θ_outer),
/// point 4πI over six faces, directional E·πr² over the scene bounds (luminance of the
/// colour; the split only decides how many VPLs a view gets, each view's set is unbiased).
pub fn view_powers(lights: &[WorldLight], bounds_radius: f32, by_power: bool) -> Vec<f32> {
    let mut powers = Vec::new();
    for wl in lights {
        let l = &wl.light;
        let lum = (0.2126 * l.color.x + 0.7152 * l.color.y + 0.0722 * l.color.z) * l.intensity;
        let (views, total) = match l.kind {
            LightKind::Point => (6, 4.0 * std::f32::consts::PI * lum),
            LightKind::Spot { outer_cone, .. } => (1, std::f32::consts::TAU * (1.0 - outer_cone.cos()) * lum),
            LightKind::Directional => (1, std::f32::consts::PI * bounds_radius * bounds_radius * lum),
        };
        for _ in 0..views {
            powers.push(if by_power { total.max(0.0) / views as f32 } else { 1.0 / views as f32 });
        }
    }
    powers
}

/// A light view's G-buffer with its own camera uniform (all views render in one submit).
struct LightGBuffer {
    gbuffer: GBufferPass,
    camera: wgpu::Buffer,
    group: wgpu::BindGroup,
}

pub struct VplImportancePass {
    views: Vec<LightGBuffer>,
    size: u32,
    pub importance: wgpu::Texture,
    importance_layout: wgpu::BindGroupLayout,
    reduce_layout: wgpu::BindGroupLayout,
    warp_layout: wgpu::BindGroupLayout,
    importance_pipeline: wgpu::ComputePipeline,
    reduce_pipeline: wgpu::ComputePipeline,
    warp_pipeline: wgpu::ComputePipeline,
    params: wgpu::Buffer,
    params_capacity: usize,
    lights: wgpu::Buffer,
    light_capacity: usize,
    /// `vpl.list`: the VPLs of this frame.
    pub vpls: wgpu::Buffer,
    /// Warped sample of each slot: uv, pdf, texel index (−1: empty map).
    pub warped: wgpu::Buffer,
    pub capacity: u32,
    /// Mip level of the surface colour in the light G-buffers (`vpl.albedo_mip`).
    pub albedo_mip: f32,
    /// The constant b of Eq. 4.3's (b + SP') (`vpl.importance_bias`).
    pub importance_bias: f32,
}

impl VplImportancePass {
    pub fn new(ctx: &GpuContext, size: u32) -> Self {
        let device = &ctx.device;
        let importance_layout = IMPORTANCE_INPUTS_BINDINGS.layout(device);
        let reduce_layout = IMPORTANCE_REDUCE_BINDINGS.layout(device);
        let warp_layout = WARP_INPUTS_BINDINGS.layout(device);
        let m_imp = crate::shaders::create_module(device, "knecht/vpl/importance.wgsl");
        let m_red = crate::shaders::create_module(device, "knecht/vpl/reduce.wgsl");
        let m_warp = crate::shaders::create_module(device, "knecht/vpl/warp.wgsl");
        let importance_pipeline =
            crate::passes::compute_pipeline(device, "vpl.importance", &m_imp, "cs_importance", &[&importance_layout]);
        let reduce_pipeline =
            crate::passes::compute_pipeline(device, "vpl.importance.reduce", &m_red, "cs_reduce", &[&reduce_layout]);
        let warp_pipeline = crate::passes::compute_pipeline(device, "vpl.warp", &m_warp, "cs_warp", &[&warp_layout]);
        let (params, params_capacity) = Self::params_buffer(device, 6);
        let (lights, light_capacity) = Self::light_buffer(device, 4);
        let (vpls, warped) = Self::vpl_buffers(device, MIN_VPL_CAPACITY);
        let importance = Self::importance_texture(device, size, 1);
        Self {
            views: Vec::new(),
            size,
            importance,
            importance_layout,
            reduce_layout,
            warp_layout,
            importance_pipeline,
            reduce_pipeline,
            warp_pipeline,
            params,
            params_capacity,
            lights,
            light_capacity,
            vpls,
            warped,
            capacity: MIN_VPL_CAPACITY,
            albedo_mip: VplSettings::default().albedo_mip,
            importance_bias: VplSettings::default().importance_bias,
        }
    }

    fn params_buffer(device: &wgpu::Device, views: usize) -> (wgpu::Buffer, usize) {
        let b = device.counted_buffer(&wgpu::BufferDescriptor {
            label: Some("vpl.importance.params"),
            size: STRIDE * views as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        (b, views)
    }

    fn light_buffer(device: &wgpu::Device, n: usize) -> (wgpu::Buffer, usize) {
        let b = device.counted_buffer(&wgpu::BufferDescriptor {
            label: Some("vpl.importance.lights"),
            size: (std::mem::size_of::<GpuLight>() * n) as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        (b, n)
    }

    fn vpl_buffers(device: &wgpu::Device, n: u32) -> (wgpu::Buffer, wgpu::Buffer) {
        let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST;
        let vpls = device.counted_buffer(&wgpu::BufferDescriptor {
            label: Some("vpl.list"),
            size: std::mem::size_of::<GpuVpl>() as u64 * n as u64,
            usage,
            mapped_at_creation: false,
        });
        let warped = device.counted_buffer(&wgpu::BufferDescriptor {
            label: Some("vpl.warped"),
            size: 16 * n as u64,
            usage,
            mapped_at_creation: false,
        });
        (vpls, warped)
    }

    /// Levels of a `size`² pyramid down to 1×1.
    pub fn levels(size: u32) -> u32 {
        size.max(1).ilog2() + 1
    }

    fn importance_texture(device: &wgpu::Device, size: u32, layers: u32) -> wgpu::Texture {
        device.counted_texture(&wgpu::TextureDescriptor {
            label: Some("vpl.importance"),
            size: wgpu::Extent3d { width: size, height: size, depth_or_array_layers: layers },
            mip_level_count: Self::levels(size),
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::R32Float,
            usage: wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::STORAGE_BINDING
                | wgpu::TextureUsages::COPY_SRC
                | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        })
    }

    /// Sizes everything for `views` light views of `size`² and `capacity` VPLs. Returns
    /// whether textures were recreated (the registry must be refreshed).
    pub fn ensure(&mut self, ctx: &GpuContext, scene: &GpuScene, size: u32, views: usize, capacity: u32) -> bool {
        let device = &ctx.device;
        let mut fresh = false;
        // Grown on demand, and shrunk once they hold more than twice what is asked, so that
        // dragging `vpl.count` does not reallocate every step and a session that visited
        // 4096 VPLs does not keep their buffers at 128 (issue #19's memory checks).
        let wanted = capacity.max(MIN_VPL_CAPACITY);
        if capacity > self.capacity || self.capacity > wanted.saturating_mul(2) {
            (self.vpls, self.warped) = Self::vpl_buffers(device, wanted);
            self.capacity = wanted;
        }
        if views > self.params_capacity {
            (self.params, self.params_capacity) = Self::params_buffer(device, views);
        }
        if size != self.size {
            self.views.clear();
            self.size = size;
        }
        while self.views.len() < views {
            let k = self.views.len();
            let name = if k == 0 { "vpl.light_gbuffer".to_string() } else { format!("vpl.light_gbuffer.{k}") };
            let gbuffer = GBufferPass::light_view(ctx, scene, size, name.clone());
            let camera = device.counted_buffer(&wgpu::BufferDescriptor {
                label: Some(&format!("{name}.camera")),
                size: std::mem::size_of::<CameraUniform>() as u64,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            let group = crate::passes::gbuffer::CAMERA_BINDINGS.group_labelled(
                device,
                &format!("{name}.camera"),
                &gbuffer.camera_layout,
                [camera.as_entire_binding()],
            );
            self.views.push(LightGBuffer { gbuffer, camera, group });
            fresh = true;
        }
        if self.views.len() > views {
            self.views.truncate(views);
            fresh = true;
        }
        let layers = views.max(1) as u32;
        if self.importance.width() != size || self.importance.depth_or_array_layers() != layers {
            self.importance = Self::importance_texture(device, size, layers);
            fresh = true;
        }
        fresh
    }

    pub fn register(&self, reg: &mut BufferRegistry) {
        for v in &self.views {
            v.gbuffer.register(reg);
        }
        reg.register(
            "vpl.importance",
            BufferKind::Data,
            "importance of each light G-buffer texel (Knecht Eq. 4.3), one layer per light view; mip k is the pyramid level hierarchical warping descends",
            &self.importance,
        );
    }

    /// The light G-buffers and importance pyramids (when `views`: they are kept while nothing
    /// moved, issue #53) and the VPLs of `jobs` (one per light view), after
    /// [`Self::write_params`] for the same jobs.
    pub fn run(
        &mut self,
        ctx: &GpuContext,
        r: &mut crate::timing::Recorder,
        (scene, state): (&GpuScene, &SceneState),
        jobs: &[ViewJob],
        views: bool,
    ) {
        if jobs.is_empty() || jobs.len() > self.views.len() {
            return;
        }
        let (encoder, timer) = (&mut *r.enc, &mut *r.timer);
        if views {
            let views = &self.views;
            timer.scope(ctx, encoder, "vpl.light_gbuffer", |e, slot| {
                for (k, v) in views.iter().take(jobs.len()).enumerate() {
                    v.gbuffer.run_with(e, slot, (k == 0, k + 1 == jobs.len()), &v.group, scene, state);
                }
            });
            timer.scope(ctx, encoder, "vpl.importance", |e, slot| self.pyramid(ctx, e, slot, jobs.len(), true));
        }
        timer.scope(ctx, encoder, "vpl.sample", |e, slot| self.warp(ctx, e, slot, jobs));
    }

    /// Writes the per-view uniforms and light cameras of `jobs`.
    pub fn write_params(
        &mut self,
        ctx: &GpuContext,
        lights: &[GpuLight],
        jobs: &[ViewJob],
        halton_first: u32,
        flux_scale: f32,
    ) {
        // More views than the pass holds: nothing is written (`run` draws nothing then).
        if jobs.len() > self.views.len() {
            return;
        }
        let fs = self.size as f32;
        if lights.len() > self.light_capacity {
            (self.lights, self.light_capacity) = Self::light_buffer(&ctx.device, lights.len().next_power_of_two());
        }
        if !lights.is_empty() {
            ctx.queue.upload(&self.lights, 0, bytemuck::cast_slice(lights));
        }
        let mut params = vec![0u8; STRIDE as usize * jobs.len()];
        for (k, job) in jobs.iter().enumerate() {
            let v = &job.view;
            let p = ViewParams {
                eye: v.eye.extend(if v.orthographic { 1.0 } else { 0.0 }),
                forward: v.forward.extend(v.pixel_extent),
                range: [job.first, job.count, job.light_index, k as u32],
                seq: [halton_first.wrapping_add(job.first), 0, 0, 0],
                scale: Vec4::new(flux_scale, fs, self.importance_bias, 0.0),
            };
            params[k * STRIDE as usize..k * STRIDE as usize + std::mem::size_of::<ViewParams>()]
                .copy_from_slice(bytemuck::bytes_of(&p));
            if let Some(lg) = self.views.get(k) {
                let cam = CameraUniform {
                    view_proj: v.proj * v.view,
                    prev_view_proj: v.proj * v.view,
                    inv_view_proj: (v.proj * v.view).inverse(),
                    view: v.view,
                    position: v.eye.extend(1.0),
                    viewport: Vec4::new(fs, fs, 1.0 / fs, 1.0 / fs),
                    params: Vec4::ZERO,
                    lod: Vec4::new(self.albedo_mip, 0.0, 0.0, 0.0),
                };
                ctx.queue.upload(&lg.camera, 0, bytemuck::bytes_of(&cam));
            }
        }
        ctx.queue.upload(&self.params, 0, &params);
    }

    /// Bindings 0–5 shared by the importance and warp passes: the view uniform, the lights
    /// and the view's light G-buffer.
    fn view_resources<'a>(&'a self, t: &'a crate::passes::gbuffer::GBufferViews) -> [wgpu::BindingResource<'a>; 6] {
        let tv = wgpu::BindingResource::TextureView;
        [
            dynamic(&self.params),
            self.lights.as_entire_binding(),
            tv(&t.position),
            tv(&t.normal),
            tv(&t.albedo),
            tv(&t.material),
        ]
    }

    fn mip_view(&self, level: u32, label: &str) -> wgpu::TextureView {
        self.importance.counted_view(&wgpu::TextureViewDescriptor {
            label: Some(label),
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            base_mip_level: level,
            mip_level_count: Some(1),
            ..Default::default()
        })
    }

    /// Eq. 4.3 into level 0 of the first `views` layers (when `importance` is set; tests
    /// upload level 0 instead), then every coarser level of the pyramid.
    pub fn pyramid(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        slot: Option<crate::timing::Slot<'_>>,
        views: usize,
        importance: bool,
    ) {
        let size = self.size;
        let tv = wgpu::BindingResource::TextureView;
        let levels = Self::levels(size);
        let level0 = self.mip_view(0, "vpl.importance.level0");
        let imp_groups: Vec<wgpu::BindGroup> = self
            .views
            .iter()
            .take(if importance { views } else { 0 })
            .map(|v| {
                let t = &v.gbuffer.targets.views;
                IMPORTANCE_INPUTS_BINDINGS.group(
                    &ctx.device,
                    &self.importance_layout,
                    self.view_resources(t).into_iter().chain([tv(&level0)]),
                )
            })
            .collect();
        let reduce_groups: Vec<wgpu::BindGroup> = (1..levels)
            .map(|l| {
                let finer = self.mip_view(l - 1, "vpl.importance.finer");
                let coarser = self.mip_view(l, "vpl.importance.coarser");
                IMPORTANCE_REDUCE_BINDINGS.group(
                    &ctx.device,
                    &self.reduce_layout,
                    [wgpu::BindingResource::TextureView(&finer), wgpu::BindingResource::TextureView(&coarser)],
                )
            })
            .collect();
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("vpl.importance"),
            timestamp_writes: slot.and_then(|s| s.compute(true, true)),
        });
        pass.set_pipe(&self.importance_pipeline);
        for (k, g) in imp_groups.iter().enumerate() {
            pass.set_group(0, g, &[(k as u64 * STRIDE) as u32]);
            pass.dispatch(size.div_ceil(8), size.div_ceil(8), 1);
        }
        pass.set_pipe(&self.reduce_pipeline);
        for (l, g) in reduce_groups.iter().enumerate() {
            let s = (size >> (l + 1)).max(1);
            pass.set_group(0, g, &[]);
            pass.dispatch(s.div_ceil(8), s.div_ceil(8), views.max(1) as u32);
        }
    }

    /// Hierarchical warping and VPL creation for every job (the uniforms written by
    /// [`Self::write_params`]).
    pub fn warp(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        slot: Option<crate::timing::Slot<'_>>,
        jobs: &[ViewJob],
    ) {
        let tv = wgpu::BindingResource::TextureView;
        let full = self.importance.counted_view(&wgpu::TextureViewDescriptor {
            label: Some("vpl.importance.pyramid"),
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            ..Default::default()
        });
        let groups: Vec<wgpu::BindGroup> = self
            .views
            .iter()
            .take(jobs.len())
            .map(|v| {
                let t = &v.gbuffer.targets.views;
                WARP_INPUTS_BINDINGS.group(
                    &ctx.device,
                    &self.warp_layout,
                    self.view_resources(t).into_iter().chain([
                        tv(&full),
                        self.vpls.as_entire_binding(),
                        self.warped.as_entire_binding(),
                    ]),
                )
            })
            .collect();
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("vpl.warp"),
            timestamp_writes: slot.and_then(|s| s.compute(true, true)),
        });
        pass.set_pipe(&self.warp_pipeline);
        for (k, (g, job)) in groups.iter().zip(jobs).enumerate() {
            if job.count == 0 {
                continue;
            }
            pass.set_group(0, g, &[(k as u64 * STRIDE) as u32]);
            pass.dispatch(job.count.div_ceil(64), 1, 1);
        }
    }

    /// Writes an importance map into layer `layer` level 0 (tests feed synthetic maps).
    pub fn upload_importance(&self, ctx: &GpuContext, layer: u32, values: &[f32]) {
        ctx.queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: &self.importance,
                mip_level: 0,
                origin: wgpu::Origin3d { x: 0, y: 0, z: layer },
                aspect: wgpu::TextureAspect::All,
            },
            bytemuck::cast_slice(values),
            wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(4 * self.size), rows_per_image: None },
            wgpu::Extent3d { width: self.size, height: self.size, depth_or_array_layers: 1 },
        );
    }
}

/// The binding of one view's uniform (dynamic offset).
fn dynamic(buffer: &wgpu::Buffer) -> wgpu::BindingResource<'_> {
    wgpu::BindingResource::Buffer(wgpu::BufferBinding {
        buffer,
        offset: 0,
        size: std::num::NonZeroU64::new(std::mem::size_of::<ViewParams>() as u64),
    })
}
