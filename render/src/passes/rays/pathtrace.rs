//! Path-traced ground truth on the GPU (issue #56 point 2; docs/architecture.md "Rays on the
//! GPU"): the CPU path tracer's estimator ([`crate::cpu::pathtrace`]) over the GPU ray caster,
//! `shaders/rays/pathtrace.wgsl`. Same camera, lights, emitters, sky and materials; its own
//! random numbers, so the two agree in expectation (FLIP at equal spp, `tests/pathtrace/rays.rs`).
//! The CPU tracer stays the reference of the reference. [`Senders::ScreenVisible`] (the
//! screen-space gather's truth) is the CPU's alone.

use crate::counters::prelude::*;

use glam::{Mat4, Vec3, Vec4};

use super::{RayScene, storage};
use crate::buffers::ImageF32;
use crate::cpu::pathtrace::{PtImages, PtSettings, Senders};
use crate::gpu::GpuContext;
use crate::gpu::bindings::{Bindings, Kind, binding};
use crate::scene::emitters::Emitters;
use crate::scene::sky::SkySampler;
use crate::scene::two_level::NO_TEXTURE;
use crate::scene::{LightKind, Scene};

const READ: Kind = Kind::Storage { read_only: true };

/// The path tracer's inputs (`rays/pathtrace.wgsl`, group 0).
pub const PATHTRACE_BINDINGS: Bindings = Bindings {
    label: "rays.pathtrace.inputs",
    shader: "rays/pathtrace.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "pt", READ),
        binding(1, "pt_lights", READ),
        binding(2, "pt_emitters", READ),
        binding(3, "pt_sky_texels", READ),
        binding(4, "pt_sky_tables", READ),
        binding(5, "pt_sums", Kind::Storage { read_only: false }),
    ],
};

/// WGSL twin: `PtParams` in `shaders/rays/pathtrace.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
struct PtParams {
    inv_view_proj: Mat4,
    eye: Vec4,
    size: [u32; 4],
    config: [u32; 4],
    counts: [u32; 4],
    sky: Vec4,
    sky_more: Vec4,
    sky_total: Vec4,
}

/// WGSL twin: `PtLight` in `shaders/rays/lights.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct PtLight {
    pub position: Vec4,
    pub direction: Vec4,
    /// Colour (rgb) and intensity (w).
    pub color: Vec4,
    pub cone: Vec4,
}

/// WGSL twin: `PtEmitter` in `shaders/rays/lights.wgsl` (see there).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct PtEmitter {
    v0: Vec4,
    v1: Vec4,
    v2: Vec4,
    normal: Vec4,
    radiance: Vec4,
    factor: Vec4,
    uv01: Vec4,
    uv2_cut: Vec4,
    cut_uv01: Vec4,
    cut_uv2: Vec4,
    kept: Vec4,
}

const SKY_LIT: u32 = 1;
const SKY_BACKGROUND: u32 = 2;
const SKY_IMAGE: u32 = 4;

/// Samples per dispatch: a long dispatch can trip a desktop GPU's watchdog, so a pass is cut
/// into dispatches of this many samples per pixel.
const SPP_PER_DISPATCH: u32 = 4;

/// The scene prepared for path tracing on the GPU at one instant.
pub struct GpuPathTracer {
    rays: RayScene,
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::ComputePipeline,
    lights: Vec<PtLight>,
    emitters: Vec<PtEmitter>,
    sky: Option<crate::scene::sky::Sky>,
    sky_background: bool,
    eps: f32,
    /// The uploaded inputs (lights, emitters, sky texels, sky tables), rebuilt when they change.
    inputs: Option<[wgpu::Buffer; 4]>,
}

/// Each emitter's texture as an entry of the rays' texture table (the emitters hold clones
/// of the scene's textures: the same pixels, found by pointer).
fn texture_entry(rays: &RayScene, scene: &Scene, emitters: &Emitters, i: usize) -> u32 {
    let Some(t) = emitters.textures.get(i) else { return NO_TEXTURE };
    scene
        .textures
        .iter()
        .position(|s| std::sync::Arc::ptr_eq(&s.rgba8, &t.rgba8))
        .and_then(|k| rays.cpu.texture_entries.get(k).copied())
        .unwrap_or(NO_TEXTURE)
}

fn pack_emitters(rays: &RayScene, scene: &Scene, emitters: &Emitters) -> Vec<PtEmitter> {
    let n = emitters.triangles.len();
    // Running sums of the power shares, as `Emitters::pick` reads them.
    let cdf: Vec<f32> = (0..n).map(|i| emitters.cdf_at(i)).collect();
    emitters
        .triangles
        .iter()
        .enumerate()
        .map(|(i, t)| {
            let (tex, uv, factor) = match t.texture {
                Some((k, uv, factor)) => (texture_entry(rays, scene, emitters, k), uv, factor),
                None => (NO_TEXTURE, [glam::Vec2::ZERO; 3], Vec3::ZERO),
            };
            let (cut, cuv, cf, cc, kept) = match t.cutout {
                Some(c) => (texture_entry(rays, scene, emitters, c.texture), c.uv, c.factor, c.cutoff, c.kept),
                None => (NO_TEXTURE, [glam::Vec2::ZERO; 3], 0.0, 0.0, Vec3::ZERO),
            };
            PtEmitter {
                v0: t.v[0].extend(cdf[i]),
                v1: t.v[1].extend(t.area),
                v2: t.v[2].extend(t.sides as f32),
                normal: t.normal.extend(f32::from_bits(tex)),
                radiance: t.radiance.extend(0.0),
                factor: factor.extend(f32::from_bits(cut)),
                uv01: Vec4::new(uv[0].x, uv[0].y, uv[1].x, uv[1].y),
                uv2_cut: Vec4::new(uv[2].x, uv[2].y, cf, cc),
                cut_uv01: Vec4::new(cuv[0].x, cuv[0].y, cuv[1].x, cuv[1].y),
                cut_uv2: Vec4::new(cuv[2].x, cuv[2].y, 0.0, 0.0),
                kept: kept.extend(0.0),
            }
        })
        .collect()
}

impl GpuPathTracer {
    /// Prepares the scene as evaluated at `time_s` (emitters one-sided and lighting, the sky's
    /// background on: the CPU tracer's defaults); a clear message when the scene does not
    /// fit the device.
    pub fn new(ctx: &GpuContext, scene: &Scene, time_s: f32) -> Result<Self, String> {
        let state = scene.evaluate(time_s);
        let rays = RayScene::new(ctx, scene, &state)?;
        let layout = PATHTRACE_BINDINGS.layout(&ctx.device);
        let module = crate::shaders::create_module(&ctx.device, "rays/pathtrace.wgsl");
        let pipeline = crate::passes::compute_pipeline(
            &ctx.device,
            "rays.pathtrace",
            &module,
            "cs_pathtrace",
            &[&layout, &rays.layout],
        );
        let lights = state
            .lights
            .iter()
            .map(|wl| {
                let (kind, cone) = match wl.light.kind {
                    LightKind::Point => (0.0, Vec4::ZERO),
                    LightKind::Spot { inner_cone, outer_cone } => (1.0, Vec4::new(inner_cone, outer_cone, 0.0, 0.0)),
                    LightKind::Directional => (2.0, Vec4::ZERO),
                };
                PtLight {
                    position: wl.position.extend(kind),
                    direction: wl.direction.extend(wl.light.range.unwrap_or(0.0)),
                    color: wl.light.color.extend(wl.light.intensity),
                    cone,
                }
            })
            .collect();
        let emitters = pack_emitters(&rays, scene, &Emitters::collect(scene, &state));
        let eps = scene.bounds(time_s).radius().max(1e-3) * 1e-4;
        let sky = scene.sky.is_lit().then(|| scene.sky.clone());
        Ok(Self { rays, layout, pipeline, lights, emitters, sky, sky_background: true, eps, inputs: None })
    }

    /// The emitters as the lab's `emitters.*` settings say (`PathTracer::use_emitter_settings`).
    pub fn use_emitter_settings(&mut self, s: &crate::settings::emitters::EmitterSettings, scene: &Scene, time_s: f32) {
        let e = if s.enabled {
            Emitters::collect_sides(scene, &scene.evaluate(time_s), s.two_sided)
        } else {
            Emitters::default()
        };
        self.emitters = pack_emitters(&self.rays, scene, &e);
        self.inputs = None;
    }

    /// Whether camera rays that leave the scene see the sky (`PathTracer::set_sky_background`).
    pub fn set_sky_background(&mut self, on: bool) {
        self.sky_background = on;
    }

    /// The ray caster's scene (its hierarchy and materials on the GPU).
    pub fn rays(&self) -> &RayScene {
        &self.rays
    }

    fn inputs(&mut self, ctx: &GpuContext) -> &[wgpu::Buffer; 4] {
        if self.inputs.is_none() {
            let (texels, tables): (Vec<Vec4>, Vec<f32>) = match self.sky.as_ref().and_then(|s| s.image.as_ref()) {
                Some((_, m)) => {
                    let (rows, marginal, _) = m.tables();
                    (m.texels.iter().map(|t| t.extend(0.0)).collect(), rows.iter().chain(marginal).copied().collect())
                }
                None => (Vec::new(), Vec::new()),
            };
            self.inputs = Some([
                storage(ctx, "rays.pathtrace.lights", bytemuck::cast_slice(&self.lights), 64),
                storage(ctx, "rays.pathtrace.emitters", bytemuck::cast_slice(&self.emitters), 176),
                storage(ctx, "rays.pathtrace.sky_texels", bytemuck::cast_slice(&texels), 16),
                storage(ctx, "rays.pathtrace.sky_tables", bytemuck::cast_slice(&tables), 4),
            ]);
        }
        self.inputs.as_ref().expect("made above")
    }

    /// Renders `settings.spp` samples per pixel for a camera (view-projection and eye).
    pub fn render(
        &mut self,
        ctx: &GpuContext,
        view_proj: Mat4,
        eye: Vec3,
        (width, height): (u32, u32),
        settings: PtSettings,
    ) -> Result<PtImages, String> {
        let mut acc = GpuAccumulator::new(ctx, width, height)?;
        acc.add_pass(ctx, self, view_proj, eye, settings)?;
        acc.images(ctx)
    }
}

/// Progressive accumulation on the GPU: each pass adds samples (`cpu::pathtrace::Accumulator`).
pub struct GpuAccumulator {
    width: u32,
    height: u32,
    sums: wgpu::Buffer,
    spp: u32,
}

impl GpuAccumulator {
    /// A `width`×`height` image with no sample yet; a clear message when it is empty or its
    /// sums do not fit one storage buffer of the device.
    pub fn new(ctx: &GpuContext, width: u32, height: u32) -> Result<Self, String> {
        if width == 0 || height == 0 {
            return Err(format!("a {width}×{height} image has no pixel to trace"));
        }
        let bytes = width as u64 * height as u64 * 32;
        if bytes > ctx.device.limits().max_storage_buffer_binding_size {
            return Err(format!("{width}×{height} is too large for the GPU path tracer on this device"));
        }
        let sums = storage(ctx, "rays.pathtrace.sums", &vec![0u8; bytes as usize], 32);
        Ok(Self { width, height, sums, spp: 0 })
    }

    pub fn spp(&self) -> u32 {
        self.spp
    }

    /// Adds `settings.spp` samples per pixel (in dispatches of a few samples each).
    pub fn add_pass(
        &mut self,
        ctx: &GpuContext,
        pt: &mut GpuPathTracer,
        view_proj: Mat4,
        eye: Vec3,
        settings: PtSettings,
    ) -> Result<(), String> {
        if settings.senders == Senders::ScreenVisible {
            return Err("the GPU path tracer traces every sender; screen-visible senders are the CPU's".into());
        }
        let (sky_flags, sky_more, sky_total, sky_rot, sky_size) = match &pt.sky {
            None => (0, Vec4::ZERO, 0.0, 0.0, (0, 0)),
            Some(s) => {
                let background = if pt.sky_background { SKY_BACKGROUND } else { 0 };
                let constant = SkySampler::new(s).radiance(Vec3::Y);
                match &s.image {
                    Some((_, m)) => (
                        SKY_LIT | background | SKY_IMAGE,
                        constant.extend(s.intensity),
                        m.tables().2,
                        s.rotation_deg.to_radians(),
                        (m.width, m.height),
                    ),
                    None => (SKY_LIT | background, constant.extend(s.intensity), 0.0, 0.0, (0, 0)),
                }
            }
        };
        pt.inputs(ctx);
        let inputs = pt.inputs.as_ref().ok_or("the path tracer's inputs were not uploaded")?;
        let params_buffer = storage(ctx, "rays.pathtrace.params", &[0u8; std::mem::size_of::<PtParams>()], 16);
        let group = PATHTRACE_BINDINGS.group(
            &ctx.device,
            &pt.layout,
            [
                params_buffer.as_entire_binding(),
                inputs[0].as_entire_binding(),
                inputs[1].as_entire_binding(),
                inputs[2].as_entire_binding(),
                inputs[3].as_entire_binding(),
                self.sums.as_entire_binding(),
            ],
        );
        let mut done = 0;
        while done < settings.spp {
            let n = (settings.spp - done).min(SPP_PER_DISPATCH);
            let params = PtParams {
                inv_view_proj: view_proj.inverse(),
                eye: eye.extend(pt.eps),
                size: [self.width, self.height, self.spp + done, n],
                config: [settings.bounces, (settings.seed ^ (settings.seed >> 32)) as u32, 0, sky_flags],
                counts: [pt.lights.len() as u32, pt.emitters.len() as u32, sky_size.0, sky_size.1],
                sky: Vec4::new(0.0, 0.0, 0.0, sky_rot),
                sky_more,
                sky_total: Vec4::new(sky_total, 0.0, 0.0, 0.0),
            };
            ctx.queue.upload(&params_buffer, 0, bytemuck::bytes_of(&params));
            let mut enc =
                ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("rays.pathtrace") });
            {
                let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some("rays.pathtrace"),
                    timestamp_writes: None,
                });
                pass.set_pipe(&pt.pipeline);
                pass.set_group(0, &group, &[]);
                pass.set_group(1, &pt.rays.group, &[]);
                pass.dispatch(self.width.div_ceil(8), self.height.div_ceil(8), 1);
            }
            ctx.submit([enc.finish()]);
            ctx.wait()?;
            done += n;
        }
        self.spp += settings.spp;
        Ok(())
    }

    /// The images so far (averages over all samples).
    pub fn images(&self, ctx: &GpuContext) -> Result<PtImages, String> {
        let data = crate::buffers::read_storage(ctx, &self.sums, self.sums.size())?;
        let sums: &[[f32; 4]] = bytemuck::cast_slice(&data);
        let k = 1.0 / self.spp.max(1) as f32;
        let n = (self.width * self.height) as usize;
        let img = |f: &dyn Fn(usize) -> [f32; 3]| ImageF32 {
            width: self.width,
            height: self.height,
            data: (0..n).map(f).map(|c| [c[0] * k, c[1] * k, c[2] * k, 1.0]).collect(),
        };
        let at = |i: usize, j: usize| [sums[2 * i + j][0], sums[2 * i + j][1], sums[2 * i + j][2]];
        Ok(PtImages {
            direct: img(&|i| at(i, 0)),
            indirect: img(&|i| at(i, 1)),
            full: img(&|i| {
                let (a, b) = (at(i, 0), at(i, 1));
                [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
            }),
            spp: self.spp,
        })
    }
}

/// Which path tracer renders a truth (issue #56 point 2): the GPU's on a real GPU, the CPU's
/// where the adapter is a software rasteriser (lavapipe runs the GPU tracer 10–30 times slower
/// than the CPU tracer runs on the same cores: docs/performance.md, "The GPU truth").
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TruthTracer {
    Cpu,
    Gpu,
}

impl TruthTracer {
    /// The tracer for the adapter of `ctx`.
    pub fn for_adapter(ctx: &GpuContext) -> Self {
        if ctx.adapter_info.device_type == wgpu::DeviceType::Cpu { Self::Cpu } else { Self::Gpu }
    }

    /// The tracer in words, with why it was chosen, for logs and the grid's truth cell.
    pub fn describe(self, ctx: &GpuContext) -> String {
        match self {
            Self::Gpu => format!("the GPU path tracer on {}", ctx.adapter_info.name),
            Self::Cpu if ctx.adapter_info.device_type == wgpu::DeviceType::Cpu => format!(
                "the CPU path tracer ({} is a software rasteriser, slower at tracing than the CPU)",
                ctx.adapter_info.name
            ),
            Self::Cpu => "the CPU path tracer".into(),
        }
    }
}

/// What a truth renders: the lighting settings the path tracers take besides the scene.
#[derive(Clone, Debug)]
pub struct TruthLighting {
    pub emitters: crate::settings::emitters::EmitterSettings,
    pub sky_background: bool,
}

/// A truth of `scene` at `time_s` by `tracer` seen by a camera (view-projection, eye, size in
/// pixels): the same images either way, up to noise.
pub fn render_truth(
    ctx: &GpuContext,
    tracer: TruthTracer,
    scene: &Scene,
    time_s: f32,
    lighting: &TruthLighting,
    (view_proj, eye, size): (Mat4, Vec3, (u32, u32)),
    settings: PtSettings,
) -> Result<PtImages, String> {
    match tracer {
        TruthTracer::Cpu => {
            let mut pt = crate::cpu::pathtrace::PathTracer::new(scene, time_s);
            pt.use_emitter_settings(&lighting.emitters, scene, time_s);
            pt.set_sky_background(lighting.sky_background);
            Ok(pt.render(view_proj, eye, size.0, size.1, settings))
        }
        TruthTracer::Gpu => {
            let mut pt = GpuPathTracer::new(ctx, scene, time_s)?;
            pt.use_emitter_settings(&lighting.emitters, scene, time_s);
            pt.set_sky_background(lighting.sky_background);
            pt.render(ctx, view_proj, eye, size, settings)
        }
    }
}
