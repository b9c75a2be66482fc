//! The whole frame, stage by stage, in the order of DESIGN.md's pipeline table.
//!
//! | stage | pass | here |
//! |---|---|---|
//! | 1. G-buffer | `passes::gbuffer` | position, normal, albedo, material, depth, movement buffer |
//! | 2. Direct light | `passes::shadow`, `passes::direct` | shadow maps, direct radiance |
//! | 3. VPLs | `passes::vpl` / `passes::vpl_importance` | exact-VPL reference: light G-buffer of one light view per frame, uniform sampling; instant radiosity: light G-buffers of every view, importance (Eq. 4.3), hierarchical warping |
//! | 4. VPL visibility | `passes::vpl_visibility` / `passes::ism` | exact cube-face depth maps per VPL; imperfect shadow maps with pull-push |
//! | 5. Shading points | `passes::interleave` | every pixel (reference); interleaved n×n tiles (instant radiosity; HCB samples: #6) |
//! | 6. Gather | `passes::vpl_gather` / `passes::interleave` | reference: full-BRDF gather averaged over frames; instant radiosity: tiled gather, merge, geometry-aware filter |
//! | 7. Temporal + compose | `passes::temporal`, `passes::compose` | confidence merge (Eq. 3.6); final.hdr, log-average luminance, Reinhard tone mapping to final.ldr |

use glam::{Mat4, Vec4};

use crate::buffers::{BufferError, BufferRegistry, ImageF32};
use crate::camera::Camera;
use crate::clock::Clock;
use crate::gpu::GpuContext;
use crate::lab_settings::IndirectTechnique;
use crate::passes::compose::ComposePass;
use crate::passes::direct::DirectPass;
use crate::passes::gbuffer::GBufferPass;
use crate::passes::hcb::{GatherSet, HcbFrame, HcbGatherPass, HcbPass, HcbSettings, HcbSplatPass};
use crate::passes::hcb_cache::{CacheCounts, CacheFrame, HcbCachePass};
use crate::passes::interleave::{GatherVisibility, InterleavePass};
use crate::passes::irsm::{IrsmFrame, IrsmPass};
use crate::passes::ism::{IsmFrame, IsmLayout, IsmPass, MAX_BOUNCES, VplVisibility};
use crate::passes::shadow::{ShadowPass, gpu_light, light_views, setup_lights};
use crate::passes::temporal::TemporalPass;
use crate::passes::vpl::{BatchView, VplSamplePass, halton};
use crate::passes::vpl_bounce::{BounceFrame, BounceMethod, VplBouncePass};
use crate::passes::vpl_gather::{GatherParams, VplGatherPass};
use crate::passes::vpl_importance::{ViewJob, VplImportancePass, view_powers};
use crate::passes::vpl_visibility::{AtlasLayout, VisibilityParams, VplVisibilityPass};
use crate::passes::{CameraUniform, bgl};
use crate::scene::upload::GpuScene;
use crate::scene::{Aabb, Scene};
use crate::settings::{FieldError, LabSettings};
use crate::timing::{GpuTimer, PassTiming};

#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    #[error("cannot render at {width}×{height}: both sides must be at least 1 pixel")]
    ZeroSize { width: u32, height: u32 },
    #[error("cannot render at {width}×{height}: the device allows at most {max}×{max}")]
    TooLarge { width: u32, height: u32, max: u32 },
    #[error("invalid settings:\n{}", .0.iter().map(|e| format!("  - {e}")).collect::<Vec<_>>().join("\n"))]
    Settings(Vec<FieldError>),
    #[error(
        "a shadow map of {size}×{size} with {layers} layers exceeds this device (max {max_dim}² texels, {max_layers} layers); the largest valid size is {largest}"
    )]
    ShadowMapTooLarge { size: u32, layers: u32, max_dim: u32, max_layers: u32, largest: u32 },
    #[error(
        "the exact-VPL visibility atlas for {vpls} VPLs per frame (all bounces) with {size}² faces needs {width}×{height} texels; this device allows {max_dim}²: at {size}² at most {largest} VPLs per frame fit"
    )]
    VplAtlasTooLarge { vpls: u32, size: u32, width: u64, height: u64, max_dim: u32, largest: u32 },
    #[error(
        "the imperfect shadow map atlas for {vpls} VPLs × {bounces} bounce(s) of {size}² needs {width}×{height} texels ({bytes} bytes to splat into); this device allows {max_dim}² texels and {max_buffer} bytes: at {size}² and {bounces} bounce(s) at most {largest_vpls} VPLs fit{}",
        match .largest_size { Some(s) => format!(", and {vpls} VPLs fit at map size {s}²"), None => String::new() }
    )]
    IsmAtlasTooLarge {
        vpls: u32,
        bounces: u32,
        size: u32,
        width: u64,
        height: u64,
        bytes: u64,
        max_dim: u32,
        max_buffer: u64,
        largest_vpls: u32,
        largest_size: Option<u32>,
    },
    #[error(
        "the IRSM atlas for {vpls} VPLs of {size}² needs {width}×{height} texels; this device allows {max_dim}² texels and {max_buffer} bytes per buffer: at {size}² at most {largest_vpls} VPLs fit"
    )]
    IrsmAtlasTooLarge {
        vpls: u32,
        size: u32,
        width: u64,
        height: u64,
        max_dim: u32,
        max_buffer: u64,
        largest_vpls: u32,
    },
}

/// The passes of instant radiosity (Knecht 002), created when the technique is selected.
struct Knecht {
    vpl: VplImportancePass,
    ism: IsmPass,
    bounce: VplBouncePass,
    /// The IRSM multi-bounce baseline, created when selected.
    irsm: Option<IrsmPass>,
    /// The hierarchical coherence buffer's passes (Nguyen), created when it is the technique.
    hcb: Option<HcbParts>,
    exact: Option<VplVisibilityPass>,
    interleave: InterleavePass,
    temporal: TemporalPass,
    /// Frames rendered (the Halton offset of a new VPL set per frame).
    frames: u32,
}

/// Sample statistics of the HCB (see [`Renderer::hcb_stats`]).
#[derive(Clone, Debug, PartialEq)]
pub struct HcbStats {
    /// Every sample's G-buffer pixel (x, y) and level.
    pub samples: Vec<[u32; 3]>,
    pub samples_per_level: Vec<u32>,
    pub texels_per_level: Vec<u32>,
    /// Covered pixels that no sample's splat reached.
    pub uncovered: u32,
    /// The cache's counts of the frame (§5), None without the cache.
    pub cache: Option<CacheCounts>,
    /// The sample list itself (cached samples first, then the new ones).
    pub list: Vec<crate::passes::hcb::GpuHcbSample>,
    /// The d_max in use (scene units; the setting or the scene-relative default).
    pub d_max: f32,
}

impl HcbStats {
    pub fn samples(&self) -> u32 {
        self.samples_per_level.iter().sum()
    }

    /// Table 1 of Nguyen et al. in one line: the count, its share of `pixels`, per level
    /// (and the cache's counts).
    pub fn summary(&self, pixels: u32) -> String {
        let mut line = format!(
            "{} HCB samples ({:.2} % of the pixels), per level {:?}; {} covered pixels no sample reached",
            self.samples(),
            100.0 * self.samples() as f64 / pixels.max(1) as f64,
            self.samples_per_level,
            self.uncovered
        );
        if let Some(c) = &self.cache {
            line += &format!("; cache: {}", c.to_string().split_whitespace().collect::<Vec<_>>().join(" "));
        }
        line
    }
}

/// The HCB technique's passes: levels, masks and samples; gathering; splatting; the cache.
struct HcbParts {
    build: HcbPass,
    gather: HcbGatherPass,
    splat: HcbSplatPass,
    /// The sample cache (§5), created when `hcb.cache` is on.
    cache: Option<HcbCachePass>,
    /// The settings the cached samples were identified with; the cache empties when they
    /// change.
    cached_with: Option<HcbSettings>,
}

/// The exact-VPL reference's passes and its progress (created when first selected).
struct ExactVpl {
    sample: VplSamplePass,
    visibility: VplVisibilityPass,
    gather: VplGatherPass,
    /// Batches accumulated since the last reset.
    batches: u32,
    /// What the accumulated image depends on (camera, lights, transforms, size); a change
    /// restarts the accumulation.
    fingerprint: Vec<f32>,
}

/// What the previous frame used, for the movement buffer (Knecht 002 §3.5.1).
struct PrevFrame {
    view_proj: Mat4,
    models: Vec<Mat4>,
}

/// The renderer: scene, settings, camera, clock, passes and their buffers.
pub struct Renderer {
    pub ctx: GpuContext,
    scene: Scene,
    gpu_scene: GpuScene,
    bounds: Aabb,
    settings: LabSettings,
    pub camera: Camera,
    pub clock: Clock,
    width: u32,
    height: u32,
    camera_buffer: wgpu::Buffer,
    camera_group: wgpu::BindGroup,
    gbuffer: GBufferPass,
    shadow: ShadowPass,
    direct: DirectPass,
    compose: ComposePass,
    registry: BufferRegistry,
    timer: GpuTimer,
    prev: Option<PrevFrame>,
    exact_vpl: Option<ExactVpl>,
    knecht: Option<Knecht>,
    /// `metrics.flip`: the FLIP error map of the last comparison with a reference.
    flip_map: Option<wgpu::Texture>,
    /// Interactive mode (the app): timings are collected without waiting for the GPU.
    interactive: bool,
    /// The pixel probe's depth reader, created on first use.
    depth_probe: std::sync::OnceLock<crate::passes::view::DepthProbe>,
}

impl Renderer {
    /// Creates the renderer for `scene` at `width`×`height`; the camera is the scene's
    /// first camera, else one that frames its bounds.
    pub fn new(
        ctx: GpuContext,
        scene: Scene,
        settings: LabSettings,
        width: u32,
        height: u32,
    ) -> Result<Self, RenderError> {
        check_size(&ctx, width, height)?;
        let errors = settings.validate();
        if !errors.is_empty() {
            return Err(RenderError::Settings(errors));
        }
        check_vpl_atlas(&ctx, &settings)?;
        check_ism_atlas(&ctx, &settings)?;
        let bounds = scene.bounds(0.0);
        let camera = default_camera(&scene, bounds, width as f32 / height as f32);
        let gpu_scene = GpuScene::new(&ctx, &scene);
        let gbuffer = GBufferPass::new(&ctx, &gpu_scene, width, height);
        let camera_buffer = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("frame.camera"),
            size: std::mem::size_of::<CameraUniform>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let camera_group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("frame.camera"),
            layout: &gbuffer.camera_layout,
            entries: &[wgpu::BindGroupEntry { binding: 0, resource: camera_buffer.as_entire_binding() }],
        });
        let shadow = ShadowPass::new(&ctx, &gpu_scene);
        let direct = DirectPass::new(&ctx, bgl::uniform(0, wgpu::ShaderStages::COMPUTE), width, height);
        let compose = ComposePass::new(&ctx, width, height);
        let timer = GpuTimer::new(&ctx);
        let clock = Clock::new(settings.animation.time_step_s as f64);
        let mut r = Self {
            ctx,
            scene,
            gpu_scene,
            bounds,
            settings,
            camera,
            clock,
            width,
            height,
            camera_buffer,
            camera_group,
            gbuffer,
            shadow,
            direct,
            compose,
            registry: BufferRegistry::default(),
            timer,
            prev: None,
            exact_vpl: None,
            knecht: None,
            flip_map: None,
            interactive: false,
            depth_probe: std::sync::OnceLock::new(),
        };
        r.register_all();
        r.ensure_exact_vpl();
        r.ensure_knecht();
        Ok(r)
    }

    fn register_all(&mut self) {
        self.registry = BufferRegistry::default();
        self.gbuffer.register(&mut self.registry);
        self.shadow.register(&mut self.registry);
        self.direct.register(&mut self.registry);
        self.compose.register(&mut self.registry);
        if let Some(x) = &self.exact_vpl {
            x.sample.light_gbuffer.register(&mut self.registry);
            x.visibility.register(&mut self.registry);
            x.gather.register(&mut self.registry);
        }
        if let Some(k) = &self.knecht {
            k.vpl.register(&mut self.registry);
            if self.settings.ism.visibility == VplVisibility::Exact {
                if let Some(e) = &k.exact {
                    e.register(&mut self.registry);
                }
            } else if self.settings.ism.visibility == VplVisibility::Imperfect {
                k.ism.register(&mut self.registry);
            }
            if let Some(irsm) = &k.irsm {
                irsm.register(&mut self.registry);
            }
            if let Some(h) = &k.hcb {
                h.build.register(&mut self.registry);
                h.splat.register(&mut self.registry);
                if let Some(c) = &h.cache {
                    c.register(&mut self.registry);
                }
            } else {
                k.interleave.register(&mut self.registry);
                k.temporal.register(&mut self.registry);
            }
        }
        if let Some(t) = &self.flip_map {
            self.registry.register(
                "metrics.flip",
                crate::buffers::BufferKind::Data,
                "per-pixel FLIP error (r = g = b, 0 … 1) of final.ldr against the last reference compared",
                t,
            );
        }
    }

    /// Publishes a FLIP error map (as `metrics::flip` returns it) as the buffer
    /// `metrics.flip`, so that viewers, the probe and `readback` can show it.
    pub fn set_flip_map(&mut self, map: &ImageF32) {
        if map.width == 0 || map.height == 0 {
            return;
        }
        let fits = self.flip_map.as_ref().is_some_and(|t| (t.width(), t.height()) == (map.width, map.height));
        if !fits {
            self.flip_map = Some(crate::passes::create_target(
                &self.ctx.device,
                "metrics.flip",
                map.width,
                map.height,
                wgpu::TextureFormat::Rgba32Float,
                wgpu::TextureUsages::COPY_DST,
            ));
        }
        let Some(t) = &self.flip_map else { return };
        self.ctx.queue.write_texture(
            t.as_image_copy(),
            bytemuck::cast_slice(&map.data),
            wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(16 * map.width), rows_per_image: None },
            wgpu::Extent3d { width: map.width, height: map.height, depth_or_array_layers: 1 },
        );
        if !fits {
            self.register_all();
        }
    }

    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// Mutable scene access for interactive edits of lights and materials' parameters that
    /// live in node transforms and light records (geometry changes need a new renderer).
    pub fn scene_mut(&mut self) -> &mut Scene {
        &mut self.scene
    }

    pub fn bounds(&self) -> Aabb {
        self.bounds
    }

    pub fn settings(&self) -> &LabSettings {
        &self.settings
    }

    /// Replaces the settings after validating them; invalid settings change nothing.
    /// Returns whether temporal history was reset.
    pub fn set_settings(&mut self, settings: LabSettings) -> Result<bool, RenderError> {
        let errors = settings.validate();
        if !errors.is_empty() {
            return Err(RenderError::Settings(errors));
        }
        self.check_shadow_map(&settings)?;
        check_vpl_atlas(&self.ctx, &settings)?;
        check_ism_atlas(&self.ctx, &settings)?;
        let reset = self.settings.history_invalidated_by(&settings);
        let visibility_changed = self.settings.ism.visibility != settings.ism.visibility;
        self.clock.time_step_s = settings.animation.time_step_s as f64;
        self.settings = settings;
        if reset {
            self.reset_history();
        }
        self.ensure_exact_vpl();
        self.ensure_knecht();
        if visibility_changed {
            self.register_all();
        }
        Ok(reset)
    }

    /// Forgets everything temporal (the movement buffer's previous frame today; the
    /// temporal techniques' history later).
    pub fn reset_history(&mut self) {
        self.prev = None;
        if let Some(x) = &mut self.exact_vpl {
            x.batches = 0;
        }
        if let Some(k) = &mut self.knecht {
            k.temporal.reset();
        }
    }

    /// The exact-VPL reference's progress: (VPLs accumulated, VPLs at which it stops), when
    /// it is the indirect technique.
    pub fn reference_progress(&self) -> Option<(u32, u32)> {
        if self.settings.indirect.technique != IndirectTechnique::ExactVpl {
            return None;
        }
        let rs = &self.settings.reference;
        let done = self.exact_vpl.as_ref().map_or(0, |x| x.batches.saturating_mul(rs.vpls_per_frame));
        Some((done.min(rs.total_vpls), rs.total_vpls))
    }

    /// Resizes every screen-sized target. Zero or too large sizes are refused and change
    /// nothing.
    pub fn resize(&mut self, width: u32, height: u32) -> Result<(), RenderError> {
        check_size(&self.ctx, width, height)?;
        if (width, height) == (self.width, self.height) {
            return Ok(());
        }
        self.width = width;
        self.height = height;
        self.gbuffer.resize(&self.ctx, width, height);
        self.direct.resize(&self.ctx, width, height);
        self.compose.resize(&self.ctx, width, height);
        if let Some(x) = &mut self.exact_vpl {
            x.gather.resize(&self.ctx, width, height);
            x.batches = 0;
        }
        if let Some(k) = &mut self.knecht {
            k.interleave.ensure(&self.ctx, width, height, self.settings.interleave.n);
            k.temporal.resize(&self.ctx, width, height);
        }
        self.register_all();
        Ok(())
    }

    fn shadow_layers(&self) -> u32 {
        let state = self.scene.evaluate(self.clock.time_s());
        state
            .lights
            .iter()
            .map(|l| match l.light.kind {
                crate::scene::LightKind::Point => 6,
                _ => 1,
            })
            .sum()
    }

    fn check_shadow_map(&self, settings: &LabSettings) -> Result<(), RenderError> {
        let size = settings.direct.shadow_map_size;
        let layers = if settings.direct.shadows { self.shadow_layers().max(1) } else { 1 };
        let max_dim = self.ctx.limits.max_texture_dimension_2d;
        let max_layers = self.ctx.limits.max_texture_array_layers;
        if size > max_dim || layers > max_layers {
            return Err(RenderError::ShadowMapTooLarge { size, layers, max_dim, max_layers, largest: max_dim });
        }
        Ok(())
    }

    /// Interactive mode: `render_frame` does not wait for the GPU; its timings are those of
    /// the newest finished frame (one or two frames late). Off by default, where every
    /// frame's own timings are returned.
    pub fn set_interactive(&mut self, interactive: bool) {
        self.interactive = interactive;
    }

    /// Renders one frame and advances the clock. Returns the per-pass timings (this frame's,
    /// or in interactive mode the newest available).
    pub fn render_frame(&mut self) -> Vec<PassTiming> {
        let ctx = self.ctx.clone();
        let aspect = self.width as f32 / self.height as f32;

        // The scene at this instant.
        let state = self.scene.evaluate(self.clock.time_s());
        let view_proj = self.camera.view_proj(aspect);
        let prev_view_proj = self.prev.as_ref().map(|p| p.view_proj).unwrap_or(view_proj);
        let cam = CameraUniform {
            view_proj,
            prev_view_proj,
            inv_view_proj: view_proj.inverse(),
            view: self.camera.view(),
            position: self.camera.position.extend(1.0),
            viewport: Vec4::new(
                self.width as f32,
                self.height as f32,
                1.0 / self.width as f32,
                1.0 / self.height as f32,
            ),
            params: Vec4::new(self.camera.znear, self.camera.zfar, self.clock.frame as f32, self.clock.time_s()),
            lod: Vec4::new(-1.0, 0.0, 0.0, 0.0),
        };
        ctx.queue.write_buffer(&self.camera_buffer, 0, bytemuck::bytes_of(&cam));
        self.gpu_scene.update_instances(&ctx, &state, self.prev.as_ref().map(|p| p.models.as_slice()));

        let mut enc = ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("frame") });

        // Stage 1: G-buffer and movement buffer.
        let (gbuffer, camera_group, gpu_scene) = (&self.gbuffer, &self.camera_group, &self.gpu_scene);
        self.timer.scope(&ctx, &mut enc, "gbuffer", |e, slot| gbuffer.run(e, slot, camera_group, gpu_scene, &state));

        // Stage 2: shadow maps and direct light.
        let ds = self.settings.direct.clone();
        let lights = setup_lights(&state.lights, self.bounds, ds.shadow_map_size, ds.shadows);
        let size = ds.shadow_map_size.min(ctx.limits.max_texture_dimension_2d);
        let layers = (lights.views.len() as u32).clamp(1, ctx.limits.max_texture_array_layers);
        if self.shadow.ensure(&ctx, size, layers) {
            self.shadow.register(&mut self.registry);
        }
        let shadow = &self.shadow;
        self.timer.scope(&ctx, &mut enc, "direct.shadow", |e, slot| {
            shadow.run(&ctx, e, slot, gpu_scene, &state, &lights.views)
        });
        let (direct, camera_buffer, gviews) = (&mut self.direct, &self.camera_buffer, &self.gbuffer.targets.views);
        let shadow_view = &self.shadow.array_view;
        self.timer.scope(&ctx, &mut enc, "direct", |e, slot| {
            direct.run(&ctx, e, slot, &ds, camera_buffer, gviews, &lights, shadow_view)
        });

        // Stages 3–6: indirect light.
        let indirect = match self.settings.indirect.technique {
            IndirectTechnique::None => None,
            IndirectTechnique::ExactVpl => self.exact_vpl_frame(&mut enc, &state, view_proj),
            IndirectTechnique::InstantRadiosity | IndirectTechnique::Hcb => self.knecht_frame(&mut enc, &state),
        };

        // Stage 7: compose and tone map.
        let radiance_view = crate::passes::view(&self.direct.radiance, "direct.radiance");
        let (compose, ts) = (&self.compose, &self.settings.tonemap);
        self.timer.scope(&ctx, &mut enc, "compose", |e, slot| {
            compose.compose(&ctx, e, slot, &radiance_view, indirect.as_ref())
        });
        self.timer.scope(&ctx, &mut enc, "compose.luminance", |e, slot| compose.luminance(&ctx, e, slot, ts));
        self.timer.scope(&ctx, &mut enc, "compose.tonemap", |e, slot| compose.tonemap(&ctx, e, slot, ts));

        self.timer.resolve(&ctx, &mut enc);
        ctx.queue.submit([enc.finish()]);
        let timings = self.timer.collect(&ctx, !self.interactive).to_vec();

        self.prev = Some(PrevFrame { view_proj, models: state.draws.iter().map(|d| d.world).collect() });
        self.clock.tick();
        timings
    }

    /// Rebuilds the passes whose shaders are among `entries` (entry modules, as listed in
    /// `shaders::ENTRY_MODULES`) from the current shader sources — the shader hot reload.
    /// Only those passes are recreated; their history restarts. If any new pipeline fails
    /// to build, every old pass is kept and the error is returned. Returns the passes
    /// rebuilt.
    pub fn reload_shaders(&mut self, entries: &[&str]) -> Result<Vec<&'static str>, String> {
        let mut passes: Vec<&'static str> = entries.iter().filter_map(|e| pass_of_shader(e)).collect();
        if let Some(i) = passes.iter().position(|p| *p == "vpl_shadow") {
            passes.swap_remove(i);
            passes.extend(["exact_vpl", "instant_radiosity"]);
        }
        passes.sort();
        passes.dedup();
        // The exact-VPL passes exist only while that technique is on.
        passes.retain(|p| *p != "exact_vpl" || self.exact_vpl.is_some());
        passes.retain(|p| *p != "instant_radiosity" || self.knecht.is_some());
        if passes.is_empty() {
            return Ok(passes);
        }
        let ctx = self.ctx.clone();
        let (w, h) = (self.width, self.height);
        let scope = ctx.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let gbuffer = passes.contains(&"gbuffer").then(|| GBufferPass::new(&ctx, &self.gpu_scene, w, h));
        let shadow = passes.contains(&"direct.shadow").then(|| ShadowPass::new(&ctx, &self.gpu_scene));
        let direct = passes
            .contains(&"direct")
            .then(|| DirectPass::new(&ctx, bgl::uniform(0, wgpu::ShaderStages::COMPUTE), w, h));
        let compose = passes.contains(&"compose").then(|| ComposePass::new(&ctx, w, h));
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(e.to_string());
        }
        if let Some(g) = gbuffer {
            self.gbuffer = g;
            self.camera_group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("frame.camera"),
                layout: &self.gbuffer.camera_layout,
                entries: &[wgpu::BindGroupEntry { binding: 0, resource: self.camera_buffer.as_entire_binding() }],
            });
        }
        if let Some(p) = shadow {
            self.shadow = p;
        }
        if let Some(p) = direct {
            self.direct = p;
        }
        if let Some(p) = compose {
            self.compose = p;
        }
        if passes.contains(&"exact_vpl") {
            let old = self.exact_vpl.take();
            let scope = ctx.device.push_error_scope(wgpu::ErrorFilter::Validation);
            self.ensure_exact_vpl();
            if let Some(e) = pollster::block_on(scope.pop()) {
                self.exact_vpl = old;
                return Err(e.to_string());
            }
        }
        if passes.contains(&"instant_radiosity") {
            let old = self.knecht.take();
            let scope = ctx.device.push_error_scope(wgpu::ErrorFilter::Validation);
            self.ensure_knecht();
            if let Some(e) = pollster::block_on(scope.pop()) {
                self.knecht = old;
                return Err(e.to_string());
            }
        }
        self.register_all();
        self.reset_history();
        Ok(passes)
    }

    /// Creates or resizes the exact-VPL reference's passes for the current settings (when it is
    /// the indirect technique), so that its buffers are registered before the first frame.
    fn ensure_exact_vpl(&mut self) {
        if self.settings.indirect.technique != IndirectTechnique::ExactVpl {
            if self.exact_vpl.take().is_some() {
                self.register_all();
            }
            return;
        }
        let ctx = self.ctx.clone();
        let rs = self.settings.reference.clone();
        let n = rs.vpls_per_frame;
        let x = self.exact_vpl.get_or_insert_with(|| ExactVpl {
            sample: VplSamplePass::new(&ctx, &self.gpu_scene, rs.light_gbuffer_size, n),
            visibility: VplVisibilityPass::new(&ctx, &self.gpu_scene),
            gather: VplGatherPass::new(&ctx, bgl::uniform(0, wgpu::ShaderStages::COMPUTE), self.width, self.height),
            batches: 0,
            fingerprint: Vec::new(),
        });
        let mut fresh = x.sample.ensure(&ctx, rs.light_gbuffer_size, n);
        fresh |= x.visibility.ensure(&ctx, n, rs.shadow_map_size);
        if fresh || self.registry.get("indirect.accum").is_err() {
            self.register_all();
        }
    }

    /// The light views of `state`, each with its light's index.
    fn light_view_list(&self, state: &crate::scene::SceneState) -> Vec<(u32, crate::passes::shadow::LightView)> {
        state
            .lights
            .iter()
            .enumerate()
            .flat_map(|(i, wl)| light_views(wl, self.bounds).into_iter().map(move |v| (i as u32, v)))
            .collect()
    }

    /// Creates or resizes the passes of instant radiosity for the current settings (when it is
    /// the indirect technique); drops them otherwise.
    fn ensure_knecht(&mut self) {
        if !self.settings.indirect.technique.uses_vpls() {
            if self.knecht.take().is_some() {
                self.register_all();
            }
            return;
        }
        let ctx = self.ctx.clone();
        let s = self.settings.clone();
        let state = self.scene.evaluate(self.clock.time_s());
        let views = self.light_view_list(&state).len();
        let (w, h) = (self.width, self.height);
        let camera_entry = bgl::uniform(0, wgpu::ShaderStages::COMPUTE);
        let created = self.knecht.is_none();
        let k = self.knecht.get_or_insert_with(|| Knecht {
            vpl: VplImportancePass::new(&ctx, s.vpl.light_gbuffer_size),
            ism: IsmPass::new(&ctx),
            bounce: VplBouncePass::new(&ctx),
            irsm: None,
            hcb: None,
            exact: None,
            interleave: InterleavePass::new(&ctx, camera_entry, w, h, s.interleave.n),
            temporal: TemporalPass::new(&ctx, w, h),
            frames: 0,
        });
        let mut fresh = created;
        let total = s.vpl.count * s.vpl.bounces.clamp(1, MAX_BOUNCES);
        fresh |= k.vpl.ensure(&ctx, &self.gpu_scene, s.vpl.light_gbuffer_size, views, total);
        // The point cloud serves the ISMs and the bounces; the splatted maps the ISM
        // visibility and the bounces' visibility test.
        if s.ism.visibility == VplVisibility::Imperfect || s.vpl.bounces > 1 {
            let maps = if ism_splats(&s) { total } else { 1 };
            fresh |= k.ism.ensure(&ctx, &self.scene, &state, &s.ism, maps, false);
        }
        if s.vpl.bounces > 1 && s.vpl.bounce_method == BounceMethod::Irsm {
            let points = k.ism.cloud.gpu.len();
            let created = k.irsm.is_none();
            let irsm = k.irsm.get_or_insert_with(|| IrsmPass::new(&ctx));
            fresh |= irsm.ensure(&ctx, s.vpl.count, s.vpl.irsm_size, points) || created;
        } else if k.irsm.take().is_some() {
            fresh = true;
        }
        if s.ism.visibility == VplVisibility::Exact {
            let e = k.exact.get_or_insert_with(|| VplVisibilityPass::new(&ctx, &self.gpu_scene));
            fresh |= e.ensure(&ctx, total, s.ism.map_size);
        }
        if s.indirect.technique == IndirectTechnique::Hcb {
            let created = k.hcb.is_none();
            let parts = k.hcb.get_or_insert_with(|| HcbParts {
                build: HcbPass::new(&ctx, w, h, s.hcb.levels),
                gather: HcbGatherPass::new(&ctx),
                splat: HcbSplatPass::new(&ctx, bgl::uniform(0, wgpu::ShaderStages::VERTEX), w, h),
                cache: None,
                cached_with: None,
            });
            let resized = parts.build.ensure(&ctx, w, h, s.hcb.levels) | parts.splat.ensure(&ctx, w, h);
            fresh |= created | resized;
            if s.hcb.cache {
                let created = parts.cache.is_none();
                let cache = parts.cache.get_or_insert_with(|| HcbCachePass::new(&ctx, w, h));
                fresh |= cache.ensure(&ctx, w, h) | created;
                if resized || parts.cached_with.as_ref() != Some(&s.hcb) {
                    // The list and the cache are swapped each frame: both start empty.
                    parts.cached_with = None;
                }
            } else if parts.cache.take().is_some() {
                fresh = true;
            }
        } else if k.hcb.take().is_some() {
            fresh = true;
        }
        fresh |= k.interleave.ensure(&ctx, w, h, s.interleave.n);
        fresh |= k.temporal.resize(&ctx, w, h);
        if fresh {
            self.register_all();
        }
    }

    /// Stages 3–7 of instant radiosity (Knecht 002): VPLs by importance warping from every
    /// light view, their visibility (ISMs, exact maps or none), the interleaved gather and
    /// merge, the confidence merge with the previous frame and the geometry-aware filter.
    /// Returns the filtered indirect light.
    fn knecht_frame(
        &mut self,
        enc: &mut wgpu::CommandEncoder,
        state: &crate::scene::SceneState,
    ) -> Option<wgpu::TextureView> {
        self.ensure_knecht();
        let ctx = self.ctx.clone();
        let s = self.settings.clone();
        let views = self.light_view_list(state);
        let r = self.bounds.radius().max(1e-3);
        let powers = view_powers(&state.lights, r, s.vpl.split_by_power);
        let counts = crate::cpu::knecht::split_budget(&powers, s.vpl.count);
        let mut first = 0;
        let jobs: Vec<ViewJob> = views
            .iter()
            .zip(&counts)
            .map(|(&(light_index, view), &count)| {
                let job = ViewJob { light_index, view, first, count };
                first += count;
                job
            })
            .collect();
        let lights: Vec<_> = state.lights.iter().map(gpu_light).collect();
        let k = self.knecht.as_mut()?;
        if let Some(h) = k.hcb.as_mut()
            && let Some(c) = h.cache.as_mut()
        {
            c.swap(&mut h.build);
            if h.cached_with.as_ref() != Some(&s.hcb) {
                c.reset(enc);
                h.cached_with = Some(s.hcb.clone());
            }
        }
        let (gpu_scene, timer) = (&self.gpu_scene, &mut self.timer);
        let halton_first = 1 + if s.vpl.new_set_each_frame { k.frames.wrapping_mul(s.vpl.count) } else { 0 };
        if lights.is_empty() {
            // No light: no VPL slot is written, so the list is cleared.
            enc.clear_buffer(&k.vpl.vpls, 0, None);
        } else {
            k.vpl.albedo_mip = s.vpl.albedo_mip;
            k.vpl.run(&ctx, enc, timer, gpu_scene, state, &lights, &jobs, halton_first, s.direct.intensity_scale);
        }
        let bounces = s.vpl.bounces.clamp(1, MAX_BOUNCES);
        let n_vpls = s.vpl.count.min(k.vpl.capacity / bounces);
        let total = n_vpls * bounces;

        // Stage 4 and the further bounces (§3.6): bounce b's ISMs are splatted, then bounce
        // b + 1's VPLs are chosen from the cloud with them, and so on.
        let eye_offset = 0.005 * r;
        let splats = ism_splats(&s);
        let job = (splats || bounces > 1).then(|| {
            let f = IsmFrame { vpls: n_vpls, bounces, eye_offset, extent: 2.0 * r };
            k.ism.begin(&ctx, &gpu_scene.instances, &k.vpl.vpls, &s.ism, f)
        });
        if let Some(job) = &job {
            let ism = &k.ism;
            if splats {
                timer.scope(&ctx, enc, "ism.splat", |e, slot| ism.splat(e, slot, job, 0));
            }
            if bounces > 1 {
                let seed = if s.vpl.new_set_each_frame { k.frames } else { 0 };
                let make = match (s.vpl.bounce_method, k.irsm.as_ref()) {
                    (BounceMethod::Irsm, Some(irsm)) => {
                        let f =
                            IrsmFrame { vpls: n_vpls, bounces, eye_offset, min_distance: s.vpl.min_distance_m, seed };
                        Bounces::Irsm(irsm, irsm.begin(&ctx, ism, &s.ism, &gpu_scene.instances, &k.vpl.vpls, f))
                    }
                    _ => {
                        let f = BounceFrame {
                            vpls: n_vpls,
                            selection: s.vpl.bounce_selection,
                            visibility: splats,
                            eye_offset,
                            depth_bias: s.ism.depth_bias,
                            min_distance: s.vpl.min_distance_m,
                            seed,
                        };
                        Bounces::PointCloud(
                            &k.bounce,
                            k.bounce.begin(&ctx, ism, &gpu_scene.instances, &k.vpl.vpls, bounces, f),
                        )
                    }
                };
                let points = ism.cloud.gpu.len() as u32;
                for b in 1..bounces {
                    timer.scope(&ctx, enc, &format!("vpl.bounce.{b}"), |e, slot| match &make {
                        Bounces::PointCloud(pass, group) => pass.run(e, slot, group, b, n_vpls),
                        Bounces::Irsm(pass, job) => pass.run(e, slot, job, b, n_vpls, points),
                    });
                    // The last bounce's maps are needed only when the ISMs are the shading's
                    // visibility.
                    if splats && (b + 1 < bounces || s.ism.visibility == VplVisibility::Imperfect) {
                        timer.scope(&ctx, enc, &format!("ism.splat.{b}"), |e, slot| ism.splat(e, slot, job, b));
                    }
                }
            }
        }
        let ism_view = k.ism.shading_view();
        let exact_view;
        let vis = match s.ism.visibility {
            VplVisibility::None => GatherVisibility::None,
            VplVisibility::Imperfect => {
                let (ism, job) = (&k.ism, job.as_ref()?);
                timer.scope(&ctx, enc, "ism.pull_push", |e, slot| ism.finish(&ctx, e, slot, job, &s.ism, 2.0 * r));
                let l = k.ism.layout_info;
                GatherVisibility::Ism {
                    atlas: &ism_view,
                    cols: l.cols,
                    size: l.size,
                    eye_offset,
                    bias: s.ism.depth_bias,
                    normal_offset: s.ism.normal_offset,
                }
            }
            VplVisibility::Exact => {
                let e = k.exact.as_ref()?;
                let (near, far) = ((r * 1e-3).max(1e-5), 2.2 * r);
                let clip = glam::Vec4::new(near, far, 2.0 * near, 0.0);
                let vpls = &k.vpl.vpls;
                timer.scope(&ctx, enc, "vpl.shadow", |e2, slot| {
                    e.run(&ctx, e2, slot, gpu_scene, state, vpls, total, VisibilityParams { clip })
                });
                exact_view = e.atlas_view.clone();
                let l = e.layout_info;
                GatherVisibility::Exact { atlas: &exact_view, cols: l.cols, size: l.size, clip: clip.truncate() }
            }
        };

        // The HCB technique (Nguyen): stages 5–6 at the samples instead of every pixel.
        if let Some(h) = &k.hcb {
            let g = &self.gbuffer.targets.views;
            let f = HcbFrame {
                thresholds: s.hcb.thresholds(self.bounds.radius()),
                eye: self.camera.position,
                pixel_scale: 2.0 * (self.camera.yfov * 0.5).tan() / self.height.max(1) as f32,
                pattern: crate::cpu::hcb::recompute_pattern(s.hcb.recompute_period),
                incomplete_weight: s.hcb.incomplete_weight,
            };
            let (vpls, camera) = (&k.vpl.vpls, &self.camera_buffer);
            let g3 = (&g.position, &g.normal, &g.albedo);
            let samples = (&h.build.list, &h.build.counter);
            let gather = |timer: &mut crate::timing::GpuTimer,
                          enc: &mut wgpu::CommandEncoder,
                          scope: &str,
                          set: GatherSet<'_>| {
                timer.scope(&ctx, enc, scope, |e, slot| {
                    h.gather.run(&ctx, e, slot, &h.build, vpls, total, s.vpl.min_distance_m, vis, set)
                })
            };
            match &h.cache {
                None => {
                    timer.scope(&ctx, enc, "hcb.build", |e, slot| {
                        h.build.run(&ctx, e, slot, &g.position, &g.normal, f, None)
                    });
                    gather(timer, enc, "hcb.gather", GatherSet::All);
                    timer.scope(&ctx, enc, "hcb.splat", |e, slot| {
                        h.splat.run(&ctx, e, slot, camera, g3, samples, &h.gather.args, f)
                    });
                }
                Some(c) => {
                    // §5 (Fig. 5): update the cache, recompute the due samples' light, splat
                    // the cached samples, then new samples where texels stay incomplete.
                    let cf = CacheFrame {
                        max_distance: s.hcb.cache_distance_m,
                        max_normal_deg: s.hcb.cache_normal_deg,
                        quad_px: s.hcb.surplus_quad_px,
                        period: s.hcb.recompute_period,
                    };
                    timer.scope(&ctx, enc, "hcb.cache.update", |e, slot| {
                        c.update(&ctx, e, slot, camera, (&g.position, &g.normal), &h.build, cf)
                    });
                    gather(timer, enc, "hcb.cache.recompute", GatherSet::Recompute(&c.queue));
                    timer.scope(&ctx, enc, "hcb.cache.splat", |e, slot| {
                        h.splat.splat(&ctx, e, slot, camera, g3, samples, (&h.gather.args, 0), false, true, f)
                    });
                    let weight_sum = crate::passes::view(&h.splat.weight_sum, "hcb.weight_sum");
                    let views = c.views();
                    timer.scope(&ctx, enc, "hcb.build", |e, slot| {
                        let io = crate::passes::hcb_cache::cache_views(&weight_sum, &views);
                        h.build.run(&ctx, e, slot, &g.position, &g.normal, f, Some(io))
                    });
                    gather(timer, enc, "hcb.gather", GatherSet::New);
                    timer.scope(&ctx, enc, "hcb.splat", |e, slot| {
                        h.splat.splat(&ctx, e, slot, camera, g3, samples, (&h.gather.args, 32), true, false, f);
                        h.splat.normalize(&ctx, e, slot, g3);
                    });
                }
            }
            k.frames = k.frames.wrapping_add(1);
            return Some(crate::passes::view(&h.splat.indirect, "hcb.indirect"));
        }

        // Stages 5–6: interleaved gather and merge.
        let g = &self.gbuffer.targets.views;
        k.interleave.shade(&ctx, enc, timer, &self.camera_buffer, g, &k.vpl.vpls, total, s.vpl.min_distance_m, vis);

        // Stage 6's geometry-aware filter, then stage 7's confidence merge. The thesis merges
        // first and filters after (§4, steps 11–12); we keep DESIGN.md's stage order because
        // the confidence's illumination term (Eq. 3.3) then compares the filtered light, an
        // estimate from all N VPLs, with the history instead of one pixel's N/n² VPLs, whose
        // noise alone drove the confidence down and kept flicker high (measured in
        // tests/knecht_quality.rs).
        let merged = crate::passes::view(&k.interleave.merged, "indirect.merged");
        let depth_range = self.camera.zfar - self.camera.znear;
        let interleave = &k.interleave;
        timer.scope(&ctx, enc, "interleave.filter", |e, slot| {
            interleave.filter(&ctx, e, slot, &s.interleave, depth_range, &merged, g)
        });
        let filtered = crate::passes::view(&k.interleave.filtered, "indirect.filtered");
        let (temporal, normal) = (&mut k.temporal, &self.gbuffer.targets.normal);
        timer.scope(&ctx, enc, "temporal", |e, slot| {
            temporal.run(&ctx, e, slot, &s.temporal, depth_range, &filtered, g, normal)
        });
        k.frames = k.frames.wrapping_add(1);
        Some(crate::passes::view(&k.temporal.history, "temporal.history"))
    }

    /// Stages 3, 4 and 6 of the exact-VPL reference: one batch of VPLs from one light view,
    /// their exact visibility, and the gather folded into the running average. Returns the
    /// averaged indirect light (None only if the passes could not be created). Once
    /// `total_vpls` are in, the average is kept as it is.
    fn exact_vpl_frame(
        &mut self,
        enc: &mut wgpu::CommandEncoder,
        state: &crate::scene::SceneState,
        view_proj: Mat4,
    ) -> Option<wgpu::TextureView> {
        self.ensure_exact_vpl();
        let ctx = self.ctx.clone();
        let rs = self.settings.reference.clone();
        let n = rs.vpls_per_frame;
        let x = self.exact_vpl.as_mut()?;

        // Restart when anything the image depends on changed.
        let lights: Vec<_> = state.lights.iter().map(gpu_light).collect();
        let mut fingerprint: Vec<f32> = view_proj.to_cols_array().to_vec();
        fingerprint.extend(lights.iter().flat_map(|l| bytemuck::cast::<_, [f32; 20]>(*l)));
        fingerprint.extend(state.draws.iter().flat_map(|d| d.world.to_cols_array()));
        if fingerprint != x.fingerprint {
            x.fingerprint = fingerprint;
            x.batches = 0;
        }
        let accum = crate::passes::view(&x.gather.accum, "indirect.accum");
        let target = rs.total_vpls.div_ceil(n);
        if x.batches >= target || lights.is_empty() {
            return Some(accum);
        }

        // The views of all lights, taken in turn; each batch stands for all V of them.
        let views: Vec<BatchView> = state
            .lights
            .iter()
            .enumerate()
            .flat_map(|(i, wl)| light_views(wl, self.bounds).into_iter().map(move |v| (i, v)))
            .map(|(i, view)| BatchView { light_index: i as u32, view })
            .collect();
        let v_count = views.len() as u32;
        let batch = views[(x.batches % v_count) as usize];
        let k = x.batches;
        let jitter = (halton(k / v_count + 1, 2) - 0.5, halton(k / v_count + 1, 3) - 0.5);
        let size = rs.light_gbuffer_size as f32;
        let flux_scale = size * size * v_count as f32 / n as f32 * self.settings.direct.intensity_scale;
        let r = self.bounds.radius().max(1e-3);
        let (near, far) = ((r * 1e-3).max(1e-5), 2.2 * r);
        let clip = glam::Vec4::new(near, far, 2.0 * near, rs.min_distance_m);

        let (gpu_scene, timer) = (&self.gpu_scene, &mut self.timer);
        let sample = &mut x.sample;
        timer.scope(&ctx, enc, "vpl.light_gbuffer", |e, slot| {
            sample.render_view(&ctx, e, slot, gpu_scene, state, &batch.view, jitter)
        });
        timer.scope(&ctx, enc, "vpl.sample", |e, slot| {
            sample.sample(&ctx, e, slot, &lights, batch, n, flux_scale, [rs.seed, k])
        });
        let (visibility, vpl_list) = (&x.visibility, &x.sample.vpls);
        if rs.visibility {
            timer.scope(&ctx, enc, "vpl.shadow", |e, slot| {
                visibility.run(&ctx, e, slot, gpu_scene, state, vpl_list, n, VisibilityParams { clip })
            });
        }
        let l = visibility.layout_info;
        let params = GatherParams {
            batch: glam::Vec4::new(n as f32, l.cols as f32, l.size as f32, 1.0 / (k + 1) as f32),
            clip,
            bias: glam::Vec4::new(rs.depth_bias, rs.normal_offset, if rs.visibility { 1.0 } else { 0.0 }, 0.0),
        };
        let (gather, camera, gviews, atlas) =
            (&x.gather, &self.camera_buffer, &self.gbuffer.targets.views, &visibility.atlas_view);
        timer.scope(&ctx, enc, "indirect.gather", |e, slot| {
            gather.run(&ctx, e, slot, camera, gviews, vpl_list, atlas, params)
        });
        x.batches += 1;
        Some(accum)
    }

    /// Timings of the last frame.
    pub fn timings(&self) -> &[PassTiming] {
        self.timer.last()
    }

    pub fn timing_source(&self) -> crate::timing::TimingSource {
        self.timer.source()
    }

    /// Measures the passes with `source` from the next frame on (GPU timestamps fall back to
    /// the wall clock where the device has none).
    pub fn set_timing_source(&mut self, source: crate::timing::TimingSource) {
        self.timer = GpuTimer::with_source(&self.ctx, source);
    }

    pub fn buffers(&self) -> &BufferRegistry {
        &self.registry
    }

    /// Reads a registered buffer back (layer 0, level 0).
    /// The HCB's samples of the last frame (Nguyen §3.6, Table 1's statistics): the count
    /// per level, the texels per level and the covered pixels that no sample reached. None
    /// when the technique is not the HCB or no frame was rendered with it. Blocks until the
    /// data is on the CPU.
    pub fn hcb_stats(&self) -> Option<HcbStats> {
        let h = self.knecht.as_ref()?.hcb.as_ref()?;
        let count: Vec<u32> = bytemuck::pod_collect_to_vec(
            &crate::buffers::read_storage(&self.ctx, &h.build.counter, crate::passes::hcb::COUNTER_BYTES).ok()?,
        );
        let n = count[0].min(h.build.list_capacity) as u64;
        let size = std::mem::size_of::<crate::passes::hcb::GpuHcbSample>() as u64;
        let list: Vec<crate::passes::hcb::GpuHcbSample> = if n == 0 {
            Vec::new()
        } else {
            bytemuck::pod_collect_to_vec(&crate::buffers::read_storage(&self.ctx, &h.build.list, n * size).ok()?)
        };
        let mut per_level = vec![0u32; h.build.levels.len()];
        for smp in &list {
            if let Some(c) = per_level.get_mut(smp.level() as usize) {
                *c += 1;
            }
        }
        let uncovered: Vec<u32> =
            bytemuck::pod_collect_to_vec(&crate::buffers::read_storage(&self.ctx, &h.splat.uncovered, 16).ok()?);
        Some(HcbStats {
            samples: list
                .iter()
                .map(|s| {
                    let [x, y] = s.pixel();
                    [x, y, s.level()]
                })
                .collect(),
            samples_per_level: per_level,
            texels_per_level: h.build.levels.iter().map(|l| l.width * l.height).collect(),
            uncovered: uncovered[0],
            cache: h.cache.as_ref().map(|_| CacheCounts::from_words(&count)),
            list,
            d_max: self.settings.hcb.d_max(self.bounds.radius()),
        })
    }

    /// The VPLs of instant radiosity's last frame (`vpl.list`, Knecht §3.3): position and
    /// incident flux of every filled slot; None when the technique is not instant radiosity
    /// or no frame was rendered with it. Blocks until the list is on the CPU.
    pub fn vpl_list(&self) -> Option<Vec<crate::passes::vpl::GpuVpl>> {
        if !self.settings.indirect.technique.uses_vpls() {
            return None;
        }
        let k = self.knecht.as_ref()?;
        if k.frames == 0 {
            return None;
        }
        let count =
            (self.settings.vpl.count * self.settings.vpl.bounces.clamp(1, MAX_BOUNCES)).min(k.vpl.capacity) as u64;
        let size = std::mem::size_of::<crate::passes::vpl::GpuVpl>() as u64;
        let bytes = crate::buffers::read_storage(&self.ctx, &k.vpl.vpls, count * size).ok()?;
        Some(
            bytemuck::pod_collect_to_vec::<u8, crate::passes::vpl::GpuVpl>(&bytes)
                .into_iter()
                .filter(|v| v.position.w > 0.5)
                .collect(),
        )
    }

    pub fn readback(&self, name: &str) -> Result<ImageF32, BufferError> {
        self.registry.readback(&self.ctx, name, 0, 0)
    }

    /// The tone-mapped image (Rgba8Unorm with an Rgba8UnormSrgb view format).
    /// The raw value of every registered buffer at each pixel (see
    /// [`BufferRegistry::probe`]); blocks until the values are on the CPU.
    pub fn probe(&self, pixels: &[(u32, u32)]) -> Result<Vec<Vec<crate::buffers::ProbeValue>>, BufferError> {
        let probe = self.depth_probe.get_or_init(|| crate::passes::view::DepthProbe::new(&self.ctx));
        self.registry.probe(&self.ctx, probe, self.size(), pixels)
    }

    pub fn final_ldr(&self) -> &wgpu::Texture {
        &self.compose.ldr
    }

    /// The camera uniform's view-projection for the current size (for CPU references).
    pub fn view_proj(&self) -> Mat4 {
        self.camera.view_proj(self.width as f32 / self.height as f32)
    }
}

/// Refuses an exact-VPL atlas larger than the device allows, naming the largest batch that fits.
fn check_vpl_atlas(ctx: &GpuContext, settings: &LabSettings) -> Result<(), RenderError> {
    if settings.indirect.technique != IndirectTechnique::ExactVpl {
        return Ok(());
    }
    let rs = &settings.reference;
    let l = AtlasLayout::new(rs.vpls_per_frame, rs.shadow_map_size);
    let max_dim = ctx.limits.max_texture_dimension_2d;
    if l.fits(max_dim) {
        return Ok(());
    }
    Err(RenderError::VplAtlasTooLarge {
        vpls: rs.vpls_per_frame,
        size: rs.shadow_map_size,
        width: l.width(),
        height: l.height(),
        max_dim,
        largest: AtlasLayout::largest_batch(rs.shadow_map_size, max_dim),
    })
}

/// The pass that makes a frame's further bounces, with its bind groups.
enum Bounces<'a> {
    PointCloud(&'a VplBouncePass, wgpu::BindGroup),
    Irsm(&'a IrsmPass, crate::passes::irsm::IrsmJob),
}

/// Whether instant radiosity splats the point cloud into ISMs this frame: for the ISM
/// visibility, and for the further bounces' visibility test unless visibility is off.
fn ism_splats(s: &LabSettings) -> bool {
    match s.ism.visibility {
        VplVisibility::None => false,
        VplVisibility::Imperfect => true,
        VplVisibility::Exact => s.vpl.bounces > 1 && s.vpl.bounce_method == BounceMethod::PointCloud,
    }
}

/// Refuses an ISM (or exact-map) atlas of instant radiosity larger than the device allows,
/// naming the largest VPL count at this map size and the largest map size for this count.
fn check_ism_atlas(ctx: &GpuContext, settings: &LabSettings) -> Result<(), RenderError> {
    if !settings.indirect.technique.uses_vpls() {
        return Ok(());
    }
    let (vpls, size) = (settings.vpl.count, settings.ism.map_size);
    let bounces = settings.vpl.bounces.clamp(1, MAX_BOUNCES);
    let max_dim = ctx.limits.max_texture_dimension_2d;
    if ism_splats(settings) {
        let max_buffer = ctx.limits.max_storage_buffer_binding_size.min(ctx.limits.max_buffer_size);
        let l = IsmLayout::new(vpls * bounces, size);
        if !l.fits(max_dim, max_buffer) {
            return Err(RenderError::IsmAtlasTooLarge {
                vpls,
                bounces,
                size,
                width: l.width(),
                height: l.height(),
                bytes: l.width() * l.height() * 4,
                max_dim,
                max_buffer,
                largest_vpls: IsmLayout::largest_count(size, max_dim, max_buffer) / bounces,
                largest_size: IsmLayout::largest_size(vpls * bounces, max_dim, max_buffer),
            });
        }
    }
    if bounces > 1 && settings.vpl.bounce_method == BounceMethod::Irsm {
        let max_buffer = ctx.limits.max_storage_buffer_binding_size.min(ctx.limits.max_buffer_size);
        let size = crate::passes::irsm::irsm_size(settings.vpl.irsm_size);
        let l = IsmLayout::new(vpls, size);
        if !l.fits(max_dim, max_buffer) {
            return Err(RenderError::IrsmAtlasTooLarge {
                vpls,
                size,
                width: l.width(),
                height: l.height(),
                max_dim,
                max_buffer,
                largest_vpls: IsmLayout::largest_count(size, max_dim, max_buffer),
            });
        }
    }
    if settings.ism.visibility == VplVisibility::Exact {
        let l = AtlasLayout::new(vpls * bounces, size);
        if !l.fits(max_dim) {
            return Err(RenderError::VplAtlasTooLarge {
                vpls: vpls * bounces,
                size,
                width: l.width(),
                height: l.height(),
                max_dim,
                largest: AtlasLayout::largest_batch(size, max_dim),
            });
        }
    }
    Ok(())
}

fn check_size(ctx: &GpuContext, width: u32, height: u32) -> Result<(), RenderError> {
    if width == 0 || height == 0 {
        return Err(RenderError::ZeroSize { width, height });
    }
    let max = ctx.limits.max_texture_dimension_2d;
    if width > max || height > max {
        return Err(RenderError::TooLarge { width, height, max });
    }
    Ok(())
}

/// The scene's first camera, else one that frames the bounds.
/// The pass (as `Renderer::reload_shaders` names it) that an entry module's pipelines
/// belong to; None for shaders outside the frame (the viewer's).
pub fn pass_of_shader(entry: &str) -> Option<&'static str> {
    Some(match entry {
        "gbuffer/gbuffer.wgsl" => "gbuffer",
        "shadow/shadow.wgsl" => "direct.shadow",
        "direct/direct.wgsl" => "direct",
        "compose/compose.wgsl" | "compose/tonemap.wgsl" | "compose/luminance.wgsl" => "compose",
        "vpl/sample.wgsl" | "vpl/gather.wgsl" => "exact_vpl",
        // The exact cube-face maps serve both VPL techniques.
        "vpl/shadow.wgsl" => "vpl_shadow",
        "vpl/importance.wgsl"
        | "vpl/reduce.wgsl"
        | "vpl/warp.wgsl"
        | "vpl/bounce.wgsl"
        | "vpl/irsm.wgsl"
        | "ism/splat.wgsl"
        | "ism/resolve.wgsl"
        | "ism/pull_push.wgsl"
        | "interleave/split.wgsl"
        | "interleave/gather.wgsl"
        | "interleave/merge.wgsl"
        | "interleave/filter.wgsl"
        | "temporal/confidence.wgsl"
        | "hcb/base.wgsl"
        | "hcb/build.wgsl"
        | "hcb/samples.wgsl"
        | "hcb/gather.wgsl"
        | "hcb/splat.wgsl"
        | "hcb/normalize.wgsl"
        | "hcb/cache.wgsl"
        | "hcb/cache_removal.wgsl" => "instant_radiosity",
        _ => return None,
    })
}

/// The buffer that shows what a timing scope produced (the lab's "hover a pass to see its
/// output"). Every scope of `render_frame` is listed; a test checks it.
pub fn scope_output(scope: &str) -> Option<&'static str> {
    Some(match scope {
        "gbuffer" => "gbuffer.albedo",
        "direct.shadow" => "direct.shadow_map",
        "direct" => "direct.radiance",
        "compose" | "compose.luminance" => "final.hdr",
        "compose.tonemap" => "final.ldr",
        "vpl.light_gbuffer" => "vpl.light_gbuffer.albedo",
        "vpl.sample" => "vpl.light_gbuffer.position",
        "vpl.shadow" => "vpl.shadow_atlas",
        "indirect.gather" => "indirect.raw",
        "vpl.importance" => "vpl.importance",
        "ism.splat" => "ism.atlas",
        s if s.starts_with("ism.splat.") || s.starts_with("vpl.bounce.") => "ism.atlas",
        "ism.pull_push" => "ism.atlas_pulled",
        "interleave.split" => "interleave.split.albedo",
        "interleave.gather" => "indirect.accum",
        "interleave.merge" => "indirect.merged",
        "temporal" => "temporal.confidence",
        "interleave.filter" => "indirect.filtered",
        "hcb.build" => "hcb.samples",
        "hcb.gather" => "hcb.samples",
        "hcb.splat" => "hcb.indirect",
        "hcb.cache.update" => "hcb.cache",
        "hcb.cache.recompute" => "hcb.recompute_group",
        "hcb.cache.splat" => "hcb.weight_sum",
        _ => return None,
    })
}

pub fn default_camera(scene: &Scene, bounds: Aabb, aspect: f32) -> Camera {
    let state = scene.evaluate(0.0);
    match state.cameras.first() {
        Some(c) => Camera::from_node(c.world, &c.camera, bounds),
        None => Camera::frame_bounds(bounds, aspect),
    }
}
