//! Path-traced ground truth on the GPU (issue #56 point 2; docs/architecture.md "Rays on the
//! GPU"): the CPU path tracer's estimator ([`crate::cpu::pathtrace`]) over the GPU ray caster,
//! `shaders/rays/pathtrace.wgsl`. Same camera, lights, emitters, sky and materials; its own
//! random numbers, so the two agree in expectation (FLIP at equal spp, `tests/pathtrace/rays.rs`).
//! The CPU tracer stays the reference of the reference. [`Senders::ScreenVisible`] (the
//! screen-space gather's truth) is the CPU's alone.

use crate::counters::prelude::*;

use glam::{Mat4, Vec3, Vec4};

use super::shade::ShadeLights;
use super::{RayScene, storage};
use crate::buffers::ImageF32;
use crate::cpu::pathtrace::{PtImages, PtSettings, Senders};
use crate::gpu::GpuContext;
use crate::gpu::bindings::{Bindings, Kind, binding};
use crate::scene::Scene;

const READ: Kind = Kind::Storage { read_only: true };

/// The path tracer's inputs (`rays/pathtrace.wgsl`, group 0).
pub const PATHTRACE_BINDINGS: Bindings = Bindings {
    label: "rays.pathtrace.inputs",
    shader: "rays/pathtrace.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "pt_shade", READ),
        binding(1, "pt_lights", READ),
        binding(2, "pt_emitters", READ),
        binding(3, "pt_sky_texels", READ),
        binding(4, "pt_sky_tables", READ),
        binding(5, "pt", READ),
        binding(6, "pt_sums", Kind::Storage { read_only: false }),
    ],
};

/// WGSL twin: `PtParams` in `shaders/rays/pathtrace.wgsl` (the camera and the run; the
/// lights' parameters are `shade::PtShade`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
struct PtParams {
    inv_view_proj: Mat4,
    eye: Vec4,
    size: [u32; 4],
    config: [u32; 4],
}

/// Samples per dispatch: a long dispatch can trip a desktop GPU's watchdog, so a pass is cut
/// into dispatches of this many samples per pixel.
const SPP_PER_DISPATCH: u32 = 4;

/// The scene prepared for path tracing on the GPU at one instant.
pub struct GpuPathTracer {
    rays: RayScene,
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::ComputePipeline,
    /// The lights, emitters and sky (`rays/shade.wgsl`).
    shade: ShadeLights,
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
        let shade = ShadeLights::new(&rays, scene, time_s);
        Ok(Self { rays, layout, pipeline, shade })
    }

    /// The emitters as the lab's `emitters.*` settings say (`PathTracer::use_emitter_settings`).
    pub fn use_emitter_settings(&mut self, s: &crate::settings::emitters::EmitterSettings, scene: &Scene, time_s: f32) {
        self.shade.use_emitter_settings(&self.rays, s, scene, &scene.evaluate(time_s));
    }

    /// Whether camera rays that leave the scene see the sky (`PathTracer::set_sky_background`).
    pub fn set_sky_background(&mut self, on: bool) {
        self.shade.sky_background = on;
    }

    /// The ray caster's scene (its hierarchy and materials on the GPU).
    pub fn rays(&self) -> &RayScene {
        &self.rays
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
        let sky_flags = pt.shade.sky_flags();
        let eps = pt.shade.eps;
        let inputs = pt.shade.buffers(ctx);
        let params_buffer = storage(ctx, "rays.pathtrace.params", &[0u8; std::mem::size_of::<PtParams>()], 16);
        let group = PATHTRACE_BINDINGS.group(
            &ctx.device,
            &pt.layout,
            [
                inputs[0].as_entire_binding(),
                inputs[1].as_entire_binding(),
                inputs[2].as_entire_binding(),
                inputs[3].as_entire_binding(),
                inputs[4].as_entire_binding(),
                params_buffer.as_entire_binding(),
                self.sums.as_entire_binding(),
            ],
        );
        let mut done = 0;
        while done < settings.spp {
            let n = (settings.spp - done).min(SPP_PER_DISPATCH);
            let params = PtParams {
                inv_view_proj: view_proj.inverse(),
                eye: eye.extend(eps),
                size: [self.width, self.height, self.spp + done, n],
                config: [settings.bounces, (settings.seed ^ (settings.seed >> 32)) as u32, 0, sky_flags],
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
