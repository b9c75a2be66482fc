//! The renderer: scene, settings, camera, clock, and the passes each stage's choice needs
//! (created when a choice selects them, dropped when none does). `frame.rs` renders a frame
//! with them; `checks` refuses what the device cannot hold; `access` reads results back.

use crate::counters::prelude::*;

mod access;
mod direct_stage;
pub(crate) mod explain;
mod soler_samples;
pub use soler_samples::{SolerReceiver, SolerSample};
pub mod checks;

use glam::Mat4;

pub use access::{default_camera, pass_of_shader, scene_view, scope_output};
pub use checks::RenderError;
use checks::{check_ism_atlas, check_scene, check_size, check_split, check_vpl_atlas};

use crate::buffers::{BufferRegistry, ImageF32};
use crate::camera::Camera;
pub(crate) use crate::chain::StagePasses;
use crate::chain::StepList;
use crate::clock::Clock;
use crate::gpu::GpuContext;
use crate::lab_settings::LabSettings;
use crate::passes::CameraUniform;
use crate::passes::compose::ComposePass;
use crate::passes::direct::DirectPass;
use crate::passes::gbuffer::GBufferPass;
use crate::passes::shadow::{ShadowPass, light_views};
use crate::scene::upload::GpuScene;
use crate::scene::{Aabb, Scene};
use crate::timing::GpuTimer;

/// A pixel and the Soler samples behind it (the overlay's last complete answer).
pub(crate) type SolerAnswer = ((u32, u32), Vec<SolerReceiver>);

/// What the previous frame used, for the movement buffer (Knecht 002 §3.5.1).
pub(crate) struct PrevFrame {
    pub view_proj: Mat4,
    pub models: Vec<Mat4>,
}

/// The renderer: scene, settings, camera, clock, passes and their buffers.
pub struct Renderer {
    pub ctx: GpuContext,
    pub(crate) scene: Scene,
    pub(crate) gpu_scene: GpuScene,
    pub(crate) bounds: Aabb,
    pub(crate) settings: LabSettings,
    pub camera: Camera,
    pub clock: Clock,
    pub(crate) width: u32,
    pub(crate) height: u32,
    pub(crate) camera_buffer: wgpu::Buffer,
    pub(crate) camera_group: wgpu::BindGroup,
    pub(crate) gbuffer: GBufferPass,
    pub(crate) shadow: ShadowPass,
    pub(crate) direct: DirectPass,
    pub(crate) stages: StagePasses,
    /// Stages 3–7 as the list of steps of the stage choices (`chain`), built when they change.
    pub(crate) steps: StepList,
    pub(crate) compose: ComposePass,
    pub(crate) registry: BufferRegistry,
    pub(crate) timer: GpuTimer,
    pub(crate) prev: Option<PrevFrame>,
    /// `metrics.flip`: the FLIP error map of the last comparison with a reference.
    flip_map: Option<wgpu::Texture>,
    /// Interactive mode (the app): timings are collected without waiting for the GPU.
    pub(crate) interactive: bool,
    /// Whether the passes that depend only on the camera, the objects, the lights and the
    /// settings keep their last result while none of these changed (issue #53; on by
    /// default): the shadow maps, the light G-buffers with their importance, a fixed VPL set
    /// with its visibility, the camera's G-buffer and the direct light. Off redoes them every
    /// frame, as before: the same image, for comparisons and measurements.
    pub reuse_unchanged: bool,
    /// The passes the last frame kept from an earlier one ([`Self::kept_passes`]).
    pub(crate) kept: Vec<&'static str>,
    /// The scene's sky as directional lights (`passes::sky`), cached.
    pub(crate) sky_lights: crate::passes::sky::SkyLights,
    /// The direct light's average over still frames while the sky's directions rotate
    /// (issue #51), created the first time it is needed.
    pub(crate) direct_history: Option<crate::passes::direct_history::DirectHistory>,
    /// The sky drawn behind the scene by stage 7.
    pub(crate) sky_background: crate::passes::sky::SkyBackground,
    /// The pixel probe's depth reader, created on first use.
    pub(crate) depth_probe: std::sync::OnceLock<crate::buffers::DepthProbe>,
    /// The last camera that could render, used in place of one that cannot.
    pub(crate) last_good_camera: Camera,
    /// Why the camera was last replaced by `last_good_camera`, until a good one comes.
    pub(crate) camera_problem: Option<String>,
    /// Read-backs copied in the frame's encoder and read without waiting (the window's).
    pub(crate) readbacks: std::sync::Mutex<crate::readback::Readbacks>,
    /// The last frame's bytes per pass (`counters::traffic`).
    pub(crate) traffic: Vec<(String, u64)>,
    /// The Soler samples overlay's last complete answer (`soler_samples_later`).
    pub(crate) soler_overlay: std::sync::Mutex<Option<SolerAnswer>>,
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
        ctx.make_current();
        let errors = settings.validate();
        if !errors.is_empty() {
            return Err(RenderError::Settings(errors));
        }
        check_vpl_atlas(&ctx, &settings)?;
        check_ism_atlas(&ctx, &settings)?;
        check_split(&ctx, &settings, width, height)?;
        check_scene(&ctx, &scene)?;
        let mut scene = scene;
        let bounds = scene.bounds(0.0);
        let camera = default_camera(&scene, bounds, width as f32 / height as f32);
        let gpu_scene = GpuScene::new(&ctx, &scene);
        for w in &gpu_scene.warnings {
            log::warn!("{w}");
        }
        scene.warnings.extend(gpu_scene.warnings.iter().cloned());
        let gbuffer = GBufferPass::new(&ctx, &gpu_scene, width, height);
        let camera_buffer = ctx.device.counted_buffer(&wgpu::BufferDescriptor {
            label: Some("frame.camera"),
            size: std::mem::size_of::<CameraUniform>() as u64,
            // COPY_SRC: `gbuffer.position` keeps the camera its depth was drawn with.
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let camera_group = crate::passes::gbuffer::CAMERA_BINDINGS.group_labelled(
            &ctx.device,
            "frame.camera",
            &gbuffer.camera_layout,
            [camera_buffer.as_entire_binding()],
        );
        let shadow = ShadowPass::new(&ctx, &gpu_scene);
        let direct = DirectPass::new(&ctx, width, height);
        let compose = ComposePass::new(&ctx, width, height);
        let sky_background = crate::passes::sky::SkyBackground::new(&ctx.device);
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
            stages: StagePasses::default(),
            steps: StepList::default(),
            flip_map: None,
            interactive: false,
            reuse_unchanged: true,
            kept: Vec::new(),
            sky_lights: Default::default(),
            direct_history: None,
            sky_background,
            depth_probe: std::sync::OnceLock::new(),
            last_good_camera: camera,
            camera_problem: None,
            readbacks: Default::default(),
            traffic: Vec::new(),
            soler_overlay: Default::default(),
        };
        r.register_all();
        r.ensure_passes();
        Ok(r)
    }

    pub(crate) fn register_all(&mut self) {
        // Passes or targets changed: the views and bind groups cached for the old ones would
        // keep their memory for a few frames more (`counters::reuse`); leaving a stage choice
        // or resizing gives it back at once. The others are made again on next use.
        crate::counters::reuse::clear();
        self.registry = BufferRegistry::default();
        self.gbuffer.register(&mut self.registry);
        self.shadow.register(&mut self.registry);
        self.direct.register(&mut self.registry);
        self.compose.register(&mut self.registry);
        let x = &self.stages;
        if let Some(e) = &x.emitters {
            e.register(&mut self.registry, &self.settings);
        }
        if let Some(r) = &x.reference {
            r.register(&mut self.registry);
        }
        if let Some(k) = &x.knecht {
            k.register(&mut self.registry, &self.settings);
        }
        if let Some(i) = &x.interleave {
            i.register(&mut self.registry);
        }
        if let Some(h) = &x.hcb {
            h.register(&mut self.registry);
        }
        if let Some(t) = &x.temporal {
            t.register(&mut self.registry);
        }
        if let Some(t) = &x.soler {
            t.register(&mut self.registry);
        }
        if let Some(t) = &x.gautron {
            t.register(&mut self.registry);
        }
        if let Some(t) = &x.ddgi {
            t.register(&mut self.registry);
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

    /// Moves the renderer to a new device (after the old one was lost): the scene is
    /// uploaded again with its textures and every pass is rebuilt, keeping the settings,
    /// size, camera, clock, timing mode and interactive mode. Temporal history restarts. On
    /// failure the renderer is unchanged.
    pub fn move_to(&mut self, ctx: GpuContext) -> Result<(), RenderError> {
        let mut next = Renderer::new(ctx, self.scene.clone(), self.settings.clone(), self.width, self.height)?;
        next.camera = self.camera;
        next.last_good_camera = self.last_good_camera;
        next.clock = self.clock;
        next.set_interactive(self.interactive);
        next.set_timing_source(self.timing_source());
        *self = next;
        Ok(())
    }

    /// Why the camera set last could not render (the previous good camera was used), if so.
    pub fn camera_problem(&self) -> Option<&str> {
        self.camera_problem.as_deref()
    }

    /// Keeps the camera if it can render, else puts the last good one back and says why.
    pub(crate) fn check_camera(&mut self) {
        match self.camera.problem() {
            None => {
                self.last_good_camera = self.camera;
                self.camera_problem = None;
            }
            Some(why) => {
                if self.camera_problem.as_deref() != Some(why.as_str()) {
                    log::warn!("{why}; the previous camera is kept");
                }
                self.camera = self.last_good_camera;
                self.camera_problem = Some(why);
            }
        }
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
        check_split(&self.ctx, &settings, self.width, self.height)?;
        let reset = self.settings.history_invalidated_by(&settings);
        let choices_changed = self.settings.pipeline != settings.pipeline;
        self.clock.time_step_s = settings.animation.time_step_s as f64;
        self.settings = settings;
        if reset {
            self.reset_history_but_records();
        }
        self.ensure_passes();
        if choices_changed {
            self.register_all();
        }
        Ok(reset)
    }

    /// [`Self::set_settings`] for an interactive change: when the one field that changed is
    /// refused by a device limit that names the largest value fitting (an ISM atlas past the
    /// device's storage binding, `RenderError::largest_value`), that value is applied instead
    /// and the note returned says so with the limit's message. Any other refusal is returned
    /// as it is. The command line does not clamp (`--set` refuses), so that a script gets
    /// what it asked for or an error.
    pub fn set_settings_clamped(&mut self, settings: LabSettings) -> Result<Option<String>, RenderError> {
        let refused = match self.set_settings(settings.clone()) {
            Ok(_) => return Ok(None),
            Err(e) => e,
        };
        let changed: Vec<String> =
            LabSettings::all_paths().into_iter().filter(|path| self.settings.get(path) != settings.get(path)).collect();
        let [field] = changed.as_slice() else { return Err(refused) };
        let Some(value) = refused.largest_value(field, &settings) else { return Err(refused) };
        let mut clamped = settings;
        if clamped.set(field, &value).is_err() || self.set_settings(clamped).is_err() {
            return Err(refused);
        }
        Ok(Some(format!("{field} clamped to {value}: {refused}")))
    }

    /// Forgets everything temporal: the movement buffer's previous frame, the confidence
    /// merge's history, the reference's average, the exposure of the last frame and Gautron's record cache.
    pub fn reset_history(&mut self) {
        self.reset_history_but_records();
        if let Some(x) = &mut self.stages.gautron {
            x.reset();
        }
    }

    /// [`Self::reset_history`] but for Gautron's record cache, which finds by itself what a
    /// settings, light or object change invalidates (stage 7, `gautron.invalidation`): after
    /// a settings change or a light edit.
    pub fn reset_history_but_records(&mut self) {
        self.prev = None;
        // A reloaded shader or a reset asks for every pass anew.
        self.redo_kept_passes();
        self.compose.forget_exposure();
        if let Some(h) = &mut self.direct_history {
            h.reset();
        }
        if let Some(x) = &mut self.stages.reference {
            x.batches = 0;
        }
        if let Some(t) = &mut self.stages.temporal {
            t.reset();
        }
        if let Some(x) = &mut self.stages.soler {
            x.reset();
        }
    }

    /// The exact-VPL reference's progress: (VPLs accumulated, VPLs at which it stops), when
    /// it is the indirect light.
    pub fn reference_progress(&self) -> Option<(u32, u32)> {
        if !self.settings.pipeline.is_reference() {
            return None;
        }
        let rs = &self.settings.reference;
        let done = self.stages.reference.as_ref().map_or(0, |x| x.batches.saturating_mul(rs.vpls_per_frame));
        Some((done.min(rs.total_vpls), rs.total_vpls))
    }

    /// Resizes every screen-sized target. Zero or too large sizes are refused and change
    /// nothing.
    pub fn resize(&mut self, width: u32, height: u32) -> Result<(), RenderError> {
        check_size(&self.ctx, width, height)?;
        check_split(&self.ctx, &self.settings, width, height)?;
        if (width, height) == (self.width, self.height) {
            return Ok(());
        }
        // An exterior view nobody has moved yet is fitted again to the new shape (the window
        // makes its renderer before it knows the viewport's size).
        if let Some(v) = &self.scene.view
            && v.kind == crate::scene::framing::ViewKind::Exterior
        {
            let bounds = self.bounds();
            let old = v.for_aspect(self.width as f32 / self.height.max(1) as f32, bounds).camera;
            if old == self.camera {
                self.camera = v.for_aspect(width as f32 / height.max(1) as f32, bounds).camera;
            }
        }
        self.width = width;
        self.height = height;
        self.gbuffer.resize(&self.ctx, width, height);
        self.direct.resize(&self.ctx, width, height);
        self.compose.resize(&self.ctx, width, height);
        if let Some(x) = &mut self.stages.reference {
            x.gather.resize(&self.ctx, width, height);
            x.batches = 0;
        }
        self.ensure_passes();
        self.register_all();
        Ok(())
    }

    /// Shadow map layers the current settings need: the punctual lights' and the sky's.
    pub fn shadow_layer_count(&self) -> u32 {
        self.shadow_layers(&self.settings)
    }

    /// Shadow map layers of the punctual lights and the sky's directions.
    fn shadow_layers(&self, settings: &LabSettings) -> u32 {
        let state = self.scene.evaluate(self.clock.time_s());
        let sky = if self.scene.sky.is_lit() { settings.sky.directions } else { 0 };
        state
            .lights
            .iter()
            .map(|l| match l.light.kind {
                crate::scene::LightKind::Point => 6,
                _ => 1,
            })
            .sum::<u32>()
            + sky
    }

    fn check_shadow_map(&self, settings: &LabSettings) -> Result<(), RenderError> {
        let size = settings.direct.shadow_map_size;
        let layers = if settings.direct.shadows { self.shadow_layers(settings).max(1) } else { 1 };
        let max_dim = self.ctx.limits.max_texture_dimension_2d;
        let max_layers = self.ctx.limits.max_texture_array_layers;
        if size > max_dim || layers > max_layers {
            return Err(RenderError::ShadowMapTooLarge { size, layers, max_dim, max_layers, largest: max_dim });
        }
        Ok(())
    }

    /// The passes the last frame did not run because nothing they read had changed since
    /// they last ran (issue #53): their outputs hold that run's result. The window lists
    /// them under the timings.
    pub fn kept_passes(&self) -> &[&'static str] {
        &self.kept
    }

    /// Forgets what the kept passes (see [`Self::reuse_unchanged`]) were last made for: the
    /// next frame redoes them (after a shader reload, a history reset, or every frame when
    /// reuse is off).
    pub fn redo_kept_passes(&mut self) {
        self.shadow.last.invalidate();
        self.gbuffer.last.invalidate();
        self.direct.last.invalidate();
        if let Some(k) = self.stages.knecht.as_mut() {
            k.redo_light_space();
        }
        if let Some(e) = self.stages.emitters.as_mut() {
            e.redo_maps();
        }
    }

    /// Interactive mode: `render_frame` does not wait for the GPU; its timings are those of
    /// the newest finished frame (one or two frames late). Off by default, where every
    /// frame's own timings are returned.
    pub fn set_interactive(&mut self, interactive: bool) {
        self.interactive = interactive;
        self.timer.set_no_wait(interactive);
    }

    /// The scene at this instant, with the sky's directions among its lights (`passes::sky`).
    pub(crate) fn frame_state(&mut self) -> crate::scene::SceneState {
        let mut state = self.scene.evaluate(self.clock.time_s());
        let rotation = if self.settings.sky.rotate_each_frame { self.clock.frame as u32 } else { 0 };
        state.lights.extend_from_slice(self.sky_lights.get(&self.scene.sky, self.settings.sky.directions, rotation));
        state
    }

    /// Creates, resizes or drops the passes of stages 3–7 for the current stage choices, so
    /// that their buffers are registered before the first frame.
    pub(crate) fn ensure_passes(&mut self) {
        self.ensure_passes_for(None);
    }

    /// [`Self::ensure_passes`] with the scene at this instant when the caller has it (the
    /// frame: so that the scene is not evaluated twice per frame, issue #38).
    pub(crate) fn ensure_passes_for(&mut self, frame_state: Option<&crate::scene::SceneState>) {
        self.ctx.make_current();
        let ctx = self.ctx.clone();
        let s = self.settings.clone();
        // The scene at this instant, evaluated only when a pass sizes itself by it.
        let evaluated;
        let state = match frame_state {
            Some(state) => state,
            None => {
                let needed = (s.emitters.enabled && self.scene.has_emitters())
                    || s.pipeline.uses_knecht_vpls()
                    || s.pipeline.uses_ddgi();
                evaluated = if needed { self.frame_state() } else { Default::default() };
                &evaluated
            }
        };
        let needs = crate::chain::Needs {
            ctx: &ctx,
            scene: &self.scene,
            gpu_scene: &self.gpu_scene,
            state,
            settings: &s,
            size: (self.width, self.height),
            light_views: light_view_list(state, self.bounds).len(),
            bounds: self.bounds,
            room: match self.scale().1 {
                crate::scale::ScaleSource::Room(b) => Some(b),
                crate::scale::ScaleSource::Model => None,
            },
        };
        let mut fresh = self.stages.ensure(&needs);
        fresh |= self.direct.ensure_diffuse(&ctx, crate::chain::needs_direct_diffuse(&s));
        fresh |= self.gbuffer.ensure_motion_depth(&ctx, s.pipeline.soler_temporal());
        self.steps.update(&s);
        if fresh {
            self.register_all();
        }
    }
}

/// The light views of `state`, each with its light's index.
pub(crate) fn light_view_list(
    state: &crate::scene::SceneState,
    bounds: Aabb,
) -> Vec<(u32, crate::passes::shadow::LightView)> {
    state
        .lights
        .iter()
        .enumerate()
        .flat_map(|(i, wl)| light_views(wl, bounds).into_iter().map(move |v| (i as u32, v)))
        .collect()
}
