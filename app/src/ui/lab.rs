//! The renderer on eframe's device and the textures through which egui shows its images.

use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use std::time::Instant;

use gi_render::{GpuContext, LabSettings, Renderer};

/// The renderer and what belongs to it (absent when the GPU or scene failed).
pub struct Lab {
    pub renderer: Renderer,
    /// The last uncaptured GPU error, if any.
    pub gpu_error: Arc<Mutex<Option<String>>>,
    pub render_state: egui_wgpu::RenderState,
    pub(super) texture: Option<(egui::TextureId, (u32, u32))>,
    /// The texture egui's viewport texture points at.
    shown: Option<wgpu::Texture>,
    /// The live settings (the panels edit these).
    pub settings: LabSettings,
    pub settings_error: Option<String>,
    pub scene_error: Option<String>,
    pub frame_ms: f32,
    pub(super) last_frame: Instant,
    pub scene_name: String,
    pub scene_path: Option<PathBuf>,
    pub unit_scale: f32,
    /// The light (its node) selected in the viewport or the Scene panel (issue #39 point 2).
    pub selected_light: Option<usize>,
    /// The selection changed in the viewport: the Scene panel opens that light's section.
    pub reveal_selected: bool,
}

impl Lab {
    pub(super) fn new(
        cc: &eframe::CreationContext<'_>,
        scene: &crate::scene_args::SceneArgs,
        settings: LabSettings,
    ) -> Result<Self, String> {
        let rs = cc.wgpu_render_state.clone().ok_or("eframe did not start its wgpu renderer")?;
        // A GPU error caused by a setting (say, out of memory for a huge shadow map) must not
        // take the lab down with it: it is logged and shown in the status bar instead of
        // wgpu's default panic. Headless runs and tests keep the panic.
        let gpu_error = Arc::new(Mutex::new(None::<String>));
        let sink = gpu_error.clone();
        rs.device.on_uncaptured_error(Arc::new(move |e| {
            log::error!("GPU error: {e}");
            if let Ok(mut s) = sink.lock() {
                *s = Some(e.to_string());
            }
        }));
        let ctx =
            GpuContext::adopt(rs.device.clone(), rs.queue.clone(), rs.adapter.get_info()).map_err(|e| e.to_string())?;
        let loaded = crate::scene_args::load_scene(scene).map_err(|e| e.message)?;
        let scene_name = scene.scene.as_ref().map(|p| p.display().to_string()).unwrap_or_else(|| loaded.name.clone());
        let mut renderer = Renderer::new(ctx, loaded, settings.clone(), 320, 240).map_err(|e| e.to_string())?;
        renderer.set_interactive(true);
        Ok(Self {
            renderer,
            gpu_error,
            render_state: rs,
            texture: None,
            shown: None,
            settings,
            settings_error: None,
            scene_error: None,
            frame_ms: 0.0,
            last_frame: Instant::now(),
            scene_name,
            scene_path: scene.scene.clone(),
            unit_scale: scene.unit_scale,
            selected_light: None,
            reveal_selected: false,
        })
    }

    /// Replaces the scene (None: the embedded default) keeping device, settings and size.
    /// On failure the current scene stays and the error is returned for display.
    pub fn open_scene(&mut self, path: Option<PathBuf>, unit_scale: f32) -> Result<(), String> {
        let args = crate::scene_args::SceneArgs { scene: path.clone(), unit_scale, ..Default::default() };
        let scene = crate::scene_args::load_scene(&args).map_err(|e| e.message)?;
        let (w, h) = self.renderer.size();
        let name = path.as_ref().map(|p| p.display().to_string()).unwrap_or_else(|| scene.name.clone());
        let clock = self.renderer.clock;
        let renderer =
            Renderer::new(self.renderer.ctx.clone(), scene, self.settings.clone(), w, h).map_err(|e| e.to_string())?;
        self.renderer = renderer;
        self.renderer.set_interactive(true);
        self.renderer.clock.playing = clock.playing;
        self.renderer.clock.speed = clock.speed;
        self.renderer.clock.loop_s = clock.loop_s;
        self.scene_name = name;
        self.scene_path = path;
        self.unit_scale = unit_scale;
        self.selected_light = None;
        // The new renderer has new textures: make the next frame re-point egui's texture.
        self.texture = self.texture.map(|(id, _)| (id, (0, 0)));
        Ok(())
    }

    /// Applies the live settings; a refused change keeps the renderer's last valid settings
    /// and says why. A value past a device limit that names the largest fitting value (an
    /// ISM atlas larger than a storage binding) is clamped to it, with the limit's message.
    pub fn apply_settings(&mut self) {
        if self.settings == *self.renderer.settings() {
            return;
        }
        match self.renderer.set_settings_clamped(self.settings.clone()) {
            Ok(None) => self.settings_error = None,
            Ok(Some(note)) => {
                self.settings_error = Some(format!("clamped: {note}"));
                self.settings = self.renderer.settings().clone();
            }
            Err(e) => {
                self.settings_error = Some(format!("refused: {e}"));
                self.settings = self.renderer.settings().clone();
            }
        }
    }

    /// Points egui's texture at `texture` (through an sRGB view), re-registering only
    /// when the texture changed size or identity.
    pub(super) fn show_texture(&mut self, texture: &wgpu::Texture, force: bool) -> egui::TextureId {
        // Re-point only when another texture is shown (final image ↔ a pass's output).
        let other = self.shown.as_ref() != Some(texture);
        self.shown = Some(texture.clone());
        native_texture(&self.render_state, &mut self.texture, texture, force || other)
    }
}

/// Registers `texture` with egui through an sRGB view into `slot`, or re-points the slot's
/// id at it when its size changed or `force` is set; returns the id. Every image the lab
/// shows from the GPU (viewport, viewers, A/B) goes through here.
pub fn native_texture(
    rs: &egui_wgpu::RenderState,
    slot: &mut Option<(egui::TextureId, (u32, u32))>,
    texture: &wgpu::Texture,
    force: bool,
) -> egui::TextureId {
    let size = (texture.width(), texture.height());
    if let Some((id, s)) = *slot
        && s == size
        && !force
    {
        return id;
    }
    let view = texture.create_view(&wgpu::TextureViewDescriptor {
        label: Some("app.egui_texture"),
        format: Some(wgpu::TextureFormat::Rgba8UnormSrgb),
        usage: Some(wgpu::TextureUsages::TEXTURE_BINDING),
        ..Default::default()
    });
    let mut r = rs.renderer.write();
    let id = match *slot {
        Some((id, _)) => {
            r.update_egui_texture_from_wgpu_texture(&rs.device, &view, wgpu::FilterMode::Nearest, id);
            id
        }
        None => r.register_native_texture(&rs.device, &view, wgpu::FilterMode::Nearest),
    };
    *slot = Some((id, size));
    id
}
