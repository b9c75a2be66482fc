//! Stage 2, direct light from the scene's punctual lights with PCF shadow maps, and from its
//! emissive surfaces by their VPLs (`passes::emitters`).
//! Shader: `shaders/direct/direct.wgsl`; BRDF: `shaders/common/brdf.wgsl` (CPU twin
//! `cpu::brdf`). Radiance L = Σ f(l, v) · I · falloff / d² · max(0, n·l) · visibility
//! over point and spot lights (KHR_lights_punctual units), with f · E · max(0, n·l) ·
//! visibility for directional lights, plus Σ f(l, v) · E_k · V_k over the emitter VPLs (E_k
//! the irradiance of Knecht 002 Eq. 4.7 with d_min, V_k the visibility of
//! `emitters.visibility`). The surface's own emission L_e is not part of it: the compose adds
//! `gbuffer.emission` (so no gather takes an emitter for a sender besides its VPLs).

use crate::counters::prelude::*;

use glam::Vec4;

use super::gbuffer::GBufferViews;
use super::shadow::LightSetup;
use crate::buffers::{BufferKind, BufferRegistry};
use crate::gpu::GpuContext;
use crate::gpu::bindings::{Bindings, Kind, binding};
pub use crate::settings::direct::*;
use crate::timing::PassRec;

/// Bind group `direct.inputs` of `shaders/direct/direct.wgsl` (group 0).
pub const DIRECT_INPUTS_BINDINGS: Bindings = Bindings {
    label: "direct.inputs",
    shader: "direct/direct.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "camera", Kind::Uniform),
        binding(1, "params", Kind::Uniform),
        binding(2, "lights", Kind::Storage { read_only: true }),
        binding(3, "light_view_proj", Kind::Storage { read_only: true }),
        binding(4, "shadow_map", Kind::DepthArray),
        binding(5, "shadow_sampler", Kind::Sampler(wgpu::SamplerBindingType::Comparison)),
        binding(6, "emitter_vpls", Kind::Storage { read_only: true }),
        binding(7, "emitter_ism", Kind::Texture { filterable: false }),
        binding(8, "emitter_exact", Kind::Texture { filterable: false }),
    ],
};

/// Bind group `direct.atlas` of `shaders/direct/direct.wgsl` (group 2 of `cs_atlas`): the
/// atlas of record hemispheres Gautron's stage lights (`DirectAtlas::shade_atlas`).
pub const DIRECT_ATLAS_BINDINGS: Bindings = Bindings {
    label: "direct.atlas",
    shader: "direct/direct.wgsl",
    group: 2,
    entry: Some("cs_atlas"),
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[binding(0, "atlas", Kind::Uniform), binding(1, "viewers", Kind::Storage { read_only: true })],
};

/// Bind group `direct.diffuse` of `shaders/direct/direct.wgsl` (group 2 of
/// `cs_main_diffuse`): the diffuse part Soler et al.'s senders read.
pub const DIRECT_DIFFUSE_BINDINGS: Bindings = Bindings {
    label: "direct.diffuse",
    shader: "direct/direct.wgsl",
    group: 2,
    entry: Some("cs_main_diffuse"),
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[binding(2, "out_diffuse", Kind::StorageTexture(RADIANCE_FORMAT))],
};

/// Bind group `direct.gbuffer` of `shaders/direct/direct.wgsl` (group 1).
pub const DIRECT_GBUFFER_BINDINGS: Bindings = Bindings {
    label: "direct.gbuffer",
    shader: "direct/direct.wgsl",
    group: 1,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        // The camera G-buffer's linear depth (`cs_main`, `cs_main_diffuse`), or the atlas's
        // positions (`cs_atlas`).
        binding(0, "g_position", Kind::Texture { filterable: false }),
        binding(1, "g_normal", Kind::Texture { filterable: false }),
        binding(2, "g_albedo", Kind::Texture { filterable: false }),
        binding(3, "g_material", Kind::Texture { filterable: false }),
        binding(4, "out_radiance", Kind::StorageTexture(wgpu::TextureFormat::Rgba16Float)),
        // The camera G-buffer's packed normals (issue #53); `g_normal` is then a stand-in,
        // and this one beside the atlas's normals.
        binding(5, "g_normal_packed", Kind::UintTexture),
    ],
};

/// Uniform of the direct pass; WGSL twin: `Params` in `shaders/direct/direct.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct DirectParams {
    pub shadow: Vec4,
    pub light: Vec4,
    /// Emitter VPLs, visibility mode (0 none, 1 ISM, 2 exact), atlas columns, map size.
    pub emitter_counts: [u32; 4],
    /// The visibility's parameters (`GatherVisibility::parts`), d_min².
    pub emitter_vis: Vec4,
}

/// Half floats (issue #38: half the traffic of `Rgba32Float`): radiance needs the range, not
/// the precision (11 bits of mantissa, relative error ≤ 4.9e-4, below FLIP's and the
/// display's resolution; the shipped presets' images stay within FLIP 0.01 of the
/// `Rgba32Float` ones: tests/preset_images.rs).
pub const RADIANCE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

pub struct DirectPass {
    /// `cs_main` with the emitters' loop, and without it (scenes without emitters).
    pipeline: [wgpu::ComputePipeline; 2],
    /// `cs_atlas`: the same light at an atlas of G-buffer tiles, each seen from its own
    /// viewer (Gautron et al.'s record hemispheres).
    atlas_pipeline: [wgpu::ComputePipeline; 2],
    layout2: wgpu::BindGroupLayout,
    /// The lights, shadow maps and parameters of the last `run`, for `shade_atlas`.
    group0: Option<wgpu::BindGroup>,
    layout0: wgpu::BindGroupLayout,
    layout1: wgpu::BindGroupLayout,
    params: wgpu::Buffer,
    lights: wgpu::Buffer,
    light_capacity: usize,
    matrices: wgpu::Buffer,
    matrix_capacity: usize,
    sampler: wgpu::Sampler,
    pub radiance: wgpu::Texture,
    radiance_view: wgpu::TextureView,
    /// `cs_main_diffuse`: the same light, and its diffuse part c·DI/π·E into `diffuse`.
    diffuse_pipeline: [wgpu::ComputePipeline; 2],
    diffuse_layout: wgpu::BindGroupLayout,
    /// `direct.diffuse`, while a stage asks for it (`ensure_diffuse`): Soler et al.'s senders
    /// under 004 §5.3's diffuse approximation (`soler.sender`).
    pub diffuse: Option<(wgpu::Texture, wgpu::TextureView)>,
    /// What the light was last computed for: kept while nothing moved (issue #53).
    pub last: crate::fingerprint::LastRun,
    /// Whether the last `run` had emitter VPLs (the atlas then runs the same variant).
    emitters: bool,
    /// Stand-ins for the emitter VPLs and their atlases when there are none.
    no_emitters: wgpu::Buffer,
    no_ism: wgpu::TextureView,
    no_exact: wgpu::TextureView,
    /// Stand-ins for the normals a G-buffer does not have: unpacked (the camera's are packed),
    /// packed (the atlas's are not; issue #53).
    no_normals: [wgpu::TextureView; 2],
}

/// What stage 2's direct light reads: the settings, the camera uniform, the G-buffer, the
/// lights with their shadow maps, and the emitters' VPLs with their visibility when the scene
/// has emitters (`passes::emitters`).
#[derive(Clone, Copy)]
pub struct DirectInputs<'a> {
    pub settings: &'a DirectSettings,
    pub camera: &'a wgpu::Buffer,
    pub gbuffer: &'a GBufferViews,
    pub lights: &'a LightSetup,
    pub shadow_map: &'a wgpu::TextureView,
    pub emitters: Option<&'a super::emitters::EmitterLight>,
}

impl DirectPass {
    pub fn new(ctx: &GpuContext, width: u32, height: u32) -> Self {
        let device = &ctx.device;
        let module = crate::shaders::create_module(device, "direct/direct.wgsl");
        let layout0 = DIRECT_INPUTS_BINDINGS.layout(device);
        let layout1 = DIRECT_GBUFFER_BINDINGS.layout(device);
        // Each entry with and without the emitters' loop (`EMITTERS`, issue #53); the screen's
        // entries read the camera G-buffer's linear depth, the atlas its positions
        // (`LINEAR_DEPTH`, issue #53).
        let both = |label: &str, entry: &str, layouts: &[&wgpu::BindGroupLayout]| {
            let linear = if entry == "cs_atlas" { 0.0 } else { 1.0 };
            [true, false].map(|on| {
                let label = if on { label.to_string() } else { format!("{label}_no_emitters") };
                let constants = [("EMITTERS", if on { 1.0 } else { 0.0 }), ("LINEAR_DEPTH", linear)];
                crate::gpu::compute_pipeline_with(device, &label, (&module, entry, &constants), layouts)
            })
        };
        let pipeline = both("direct.pipeline", "cs_main", &[&layout0, &layout1]);
        let layout2 = DIRECT_ATLAS_BINDINGS.layout(device);
        let atlas_pipeline = both("direct.atlas_pipeline", "cs_atlas", &[&layout0, &layout1, &layout2]);
        let diffuse_layout = DIRECT_DIFFUSE_BINDINGS.layout(device);
        let diffuse_pipeline =
            both("direct.diffuse_pipeline", "cs_main_diffuse", &[&layout0, &layout1, &diffuse_layout]);
        let params = device.counted_buffer(&wgpu::BufferDescriptor {
            label: Some("direct.params"),
            size: std::mem::size_of::<DirectParams>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let storage = |label, size| {
            device.counted_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        let lights = storage("direct.lights", 8 * std::mem::size_of::<super::shadow::GpuLight>() as u64);
        let matrices = storage("direct.light_view_proj", 8 * 64);
        let sampler = device.counted_sampler(&wgpu::SamplerDescriptor {
            label: Some("direct.shadow_sampler"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            compare: Some(wgpu::CompareFunction::LessEqual),
            ..Default::default()
        });
        let (radiance, radiance_view) = Self::target(ctx, "direct.radiance", width, height);
        let no_emitters = storage("direct.no_emitters", std::mem::size_of::<super::reference::vpl::GpuVpl>() as u64);
        let (no_ism, no_exact) = super::reference::vpl_visibility::no_visibility_atlases(device, "direct.emitters");
        let no_normals = super::gbuffer::normal_stand_ins(device, "direct");
        Self {
            no_normals,
            no_emitters,
            last: Default::default(),
            emitters: true,
            no_ism,
            no_exact,
            pipeline,
            atlas_pipeline,
            layout2,
            group0: None,
            layout0,
            layout1,
            params,
            lights,
            light_capacity: 8,
            matrices,
            matrix_capacity: 8,
            sampler,
            radiance,
            radiance_view,
            diffuse_pipeline,
            diffuse_layout,
            diffuse: None,
        }
    }

    fn target(ctx: &GpuContext, name: &str, width: u32, height: u32) -> (wgpu::Texture, wgpu::TextureView) {
        let t = super::create_target(
            &ctx.device,
            name,
            width,
            height,
            RADIANCE_FORMAT,
            wgpu::TextureUsages::STORAGE_BINDING,
        );
        let v = super::view(&t, name);
        (t, v)
    }

    pub fn resize(&mut self, ctx: &GpuContext, width: u32, height: u32) {
        self.last.invalidate();
        (self.radiance, self.radiance_view) = Self::target(ctx, "direct.radiance", width, height);
        if self.diffuse.is_some() {
            self.diffuse = Some(Self::target(ctx, "direct.diffuse", width, height));
        }
    }

    /// Creates or drops `direct.diffuse` (`wanted`: a stage gathers diffuse senders); true
    /// when it was created or dropped (the buffer registry must be rebuilt).
    pub fn ensure_diffuse(&mut self, ctx: &GpuContext, wanted: bool) -> bool {
        match (&self.diffuse, wanted) {
            (None, true) => {
                self.diffuse = Some(Self::target(ctx, "direct.diffuse", self.radiance.width(), self.radiance.height()));
                true
            }
            (Some(_), false) => {
                self.diffuse = None;
                true
            }
            _ => false,
        }
    }

    pub fn register(&self, reg: &mut BufferRegistry) {
        reg.register(
            "direct.radiance",
            BufferKind::Hdr,
            "outgoing radiance from the punctual lights and the emitter VPLs (W/(m²·sr)); the surface's own emission is gbuffer.emission",
            &self.radiance,
        );
        if let Some((t, _)) = &self.diffuse {
            reg.register(
                "direct.diffuse",
                BufferKind::Hdr,
                "the direct light's diffuse part c·DI/π · E (W/(m²·sr)): the light Soler et al.'s senders emit under 004 §5.3's diffuse approximation (soler.sender)",
                t,
            );
        }
    }

    /// Stage 2's direct light at every pixel of `inputs.gbuffer` (`direct.radiance`).
    pub fn run(&mut self, r: PassRec<'_, '_>, inputs: &DirectInputs) {
        let PassRec { ctx, enc: encoder, slot } = r;
        let DirectInputs { settings, camera, gbuffer, lights, shadow_map, emitters } = *inputs;
        let device = &ctx.device;
        let none = super::reference::vpl_visibility::GatherVisibility::None;
        let vis = emitters.map_or(&none, |e| &e.visibility);
        let (mode, ism, exact, cols, size, vp) = vis.parts(&self.no_ism, &self.no_exact);
        let (count, dmin) = emitters.map_or((0, 0.0), |e| (e.count, e.min_distance));
        let p = DirectParams {
            emitter_counts: [count, mode, cols, size],
            emitter_vis: Vec4::new(vp.y, vp.z, vp.w, dmin * dmin),
            shadow: Vec4::new(
                settings.pcf_radius as f32,
                settings.shadow_map_size as f32,
                settings.depth_bias,
                settings.normal_offset,
            ),
            light: Vec4::new(settings.intensity_scale, settings.shadows as u32 as f32, 0.0, 0.0),
        };
        ctx.queue.upload(&self.params, 0, bytemuck::bytes_of(&p));
        let light_size = std::mem::size_of::<super::shadow::GpuLight>() as u64;
        if lights.lights.len() > self.light_capacity {
            self.light_capacity = lights.lights.len().next_power_of_two();
            self.lights = device.counted_buffer(&wgpu::BufferDescriptor {
                label: Some("direct.lights"),
                size: self.light_capacity as u64 * light_size,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
        }
        if lights.views.len() > self.matrix_capacity {
            self.matrix_capacity = lights.views.len().next_power_of_two();
            self.matrices = device.counted_buffer(&wgpu::BufferDescriptor {
                label: Some("direct.light_view_proj"),
                size: self.matrix_capacity as u64 * 64,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
        }
        ctx.queue.upload(&self.lights, 0, bytemuck::cast_slice(&lights.lights));
        if !lights.views.is_empty() {
            ctx.queue.upload(&self.matrices, 0, bytemuck::cast_slice(&lights.views));
        }
        let group0 = DIRECT_INPUTS_BINDINGS.group(
            device,
            &self.layout0,
            [
                camera.as_entire_binding(),
                self.params.as_entire_binding(),
                wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                    buffer: &self.lights,
                    offset: 0,
                    size: std::num::NonZeroU64::new(lights.lights.len() as u64 * light_size),
                }),
                self.matrices.as_entire_binding(),
                wgpu::BindingResource::TextureView(shadow_map),
                wgpu::BindingResource::Sampler(&self.sampler),
                emitters.map_or(&self.no_emitters, |e| &e.list).as_entire_binding(),
                wgpu::BindingResource::TextureView(ism),
                wgpu::BindingResource::TextureView(exact),
            ],
        );
        let tv = wgpu::BindingResource::TextureView;
        let group1 = DIRECT_GBUFFER_BINDINGS.group(
            device,
            &self.layout1,
            [
                tv(&gbuffer.linear_depth),
                tv(&self.no_normals[0]),
                tv(&gbuffer.albedo),
                tv(&gbuffer.material),
                tv(&self.radiance_view),
                tv(&gbuffer.packed_normal),
            ],
        );
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("direct.pass"),
            timestamp_writes: slot.and_then(|s| s.compute(true, true)),
        });
        let diffuse =
            self.diffuse.as_ref().map(|(_, v)| DIRECT_DIFFUSE_BINDINGS.group(device, &self.diffuse_layout, [tv(v)]));
        let k = emitters.is_none() as usize;
        pass.set_pipe(if diffuse.is_some() { &self.diffuse_pipeline[k] } else { &self.pipeline[k] });
        pass.set_group(0, &group0, &[]);
        pass.set_group(1, &group1, &[]);
        if let Some(g) = &diffuse {
            pass.set_group(2, g, &[]);
        }
        let (w, h) = (self.radiance.width(), self.radiance.height());
        pass.dispatch(w.div_ceil(super::TILE), h.div_ceil(super::TILE), 1);
        drop(pass);
        self.group0 = Some(group0);
        self.emitters = emitters.is_some();
    }
}

/// The direct light of this frame (the lights and shadow maps of the last [`DirectPass::run`])
/// at the hemispheres of Gautron et al.'s records (003, "Simple plane sampling").
impl super::stages::DirectAtlas for DirectPass {
    fn shade_atlas(
        &self,
        r: PassRec<'_, '_>,
        atlas: &GBufferViews,
        out: &wgpu::TextureView,
        size: (u32, u32),
        params: &wgpu::Buffer,
        viewers: &wgpu::Buffer,
        indirect: Option<(&wgpu::Buffer, u64)>,
    ) {
        let PassRec { ctx, enc: encoder, slot } = r;
        let Some(group0) = &self.group0 else { return };
        let device = &ctx.device;
        let tv = wgpu::BindingResource::TextureView;
        // The G-buffer group over the atlas's tiles (labelled `direct.gbuffer` like the frame's).
        let group1 = DIRECT_GBUFFER_BINDINGS.group(
            device,
            &self.layout1,
            [
                tv(&atlas.position),
                tv(&atlas.normal),
                tv(&atlas.albedo),
                tv(&atlas.material),
                tv(out),
                tv(&self.no_normals[1]),
            ],
        );
        let group2 = DIRECT_ATLAS_BINDINGS.group(
            device,
            &self.layout2,
            [params.as_entire_binding(), viewers.as_entire_binding()],
        );
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("direct.atlas_pass"),
            timestamp_writes: slot.and_then(|s| s.compute(true, true)),
        });
        pass.set_pipe(&self.atlas_pipeline[!self.emitters as usize]);
        pass.set_group(0, group0, &[]);
        pass.set_group(1, &group1, &[]);
        pass.set_group(2, &group2, &[]);
        match indirect {
            Some((args, offset)) => pass.dispatch_indirect(args, offset),
            None => pass.dispatch(size.0.div_ceil(super::TILE), size.1.div_ceil(super::TILE), 1),
        }
    }
}
