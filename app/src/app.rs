//! The GI Lab window (issue #4): docked panels (egui_tiles) around a viewport they never
//! cover — settings generated from `LabSettings`, scene and timeline, presets, GPU timings,
//! pixel probes and any number of buffer viewers — with a menu bar, a status bar, keyboard
//! shortcuts and a session that is restored on the next start. The renderer runs on
//! eframe's wgpu device; its images are shown as native egui textures.
//! Camera: drag to orbit, WASD/QE to fly, scroll to move forward/back; click to pin a probe.

use std::collections::{BTreeMap, VecDeque};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use gi_render::buffers::ProbeValue;
use gi_render::passes::view::ViewPipeline;
use gi_render::preset::{Export, ExportFormat, Loaded, Provenance};
use gi_render::timing::PassTiming;
use gi_render::{GpuContext, LabSettings, Renderer};

use crate::cli::AppArgs;
use crate::session::{self, Bookmark, LightEdit, Pane, PinnedProbe, Session};
use crate::viewer::{Viewer, ViewerState};

pub const ERROR: egui::Color32 = egui::Color32::from_rgb(255, 120, 80);

/// Opens the window and runs until it is closed.
pub fn run(args: AppArgs) -> Result<(), String> {
    let options = eframe::NativeOptions {
        viewport: egui::ViewportBuilder::default()
            .with_inner_size([1440.0, 900.0])
            .with_title("GI Lab")
            .with_drag_and_drop(true),
        renderer: eframe::Renderer::Wgpu,
        wgpu_options: wgpu_configuration(),
        ..Default::default()
    };
    eframe::run_native("GI Lab", options, Box::new(move |cc| Ok(Box::new(GiLabApp::new(cc, args)))))
        .map_err(|e| format!("could not open the window: {e}"))
}

/// eframe's wgpu setup with the device GI Lab needs (float32 blending/filtering,
/// timestamps, the adapter's limits). If the adapter lacks them, egui's defaults are
/// used so that the window can open and explain the problem.
pub fn wgpu_configuration() -> egui_wgpu::WgpuConfiguration {
    egui_wgpu::WgpuConfiguration { wgpu_setup: wgpu_setup(), ..Default::default() }
}

/// The wgpu setup of [`wgpu_configuration`] (also used by the UI tests' harness).
pub fn wgpu_setup() -> egui_wgpu::WgpuSetup {
    let mut setup = egui_wgpu::WgpuSetupCreateNew::without_display_handle();
    setup.native_adapter_selector = Some(Arc::new(|adapters, surface| {
        gi_render::gpu::best_adapter(adapters, surface).ok_or_else(|| gi_render::gpu::INSTALL_HINT.to_string())
    }));
    let fallback = setup.device_descriptor.clone();
    setup.device_descriptor = Arc::new(move |adapter| match gi_render::gpu::device_descriptor(adapter) {
        Ok(mut d) => {
            d.required_limits.max_texture_dimension_2d = d.required_limits.max_texture_dimension_2d.max(8192);
            d
        }
        Err(e) => {
            log::error!("{e}");
            fallback(adapter)
        }
    });
    egui_wgpu::WgpuSetup::CreateNew(setup)
}

/// The keyboard shortcuts (Help lists them).
pub const SHORTCUTS: &[(&str, &str)] = &[
    ("Space", "play / pause the animation"),
    ("Period (.)", "step one frame (paused)"),
    ("Ctrl+N", "new preset (defaults)"),
    ("Ctrl+O", "open a preset"),
    ("Ctrl+S", "save the preset"),
    ("Ctrl+Shift+S", "save the preset as…"),
    ("Ctrl+E", "export the preset as JSON"),
    ("Ctrl+Shift+O", "open a glTF scene"),
    ("Ctrl+B", "add a buffer viewer"),
    ("F12", "save the viewport as PNG and EXR"),
    ("Home", "reset the camera"),
    ("H", "restart temporal accumulation"),
    ("Escape", "unpin all probes"),
    ("Drag / WASD QE / scroll", "orbit / fly / move (viewport)"),
    ("Click", "pin a probe (viewport, viewers)"),
];

/// The renderer and what belongs to it (absent when the GPU or scene failed).
pub struct Lab {
    pub renderer: Renderer,
    /// The last uncaptured GPU error, if any.
    pub gpu_error: Arc<Mutex<Option<String>>>,
    pub render_state: egui_wgpu::RenderState,
    texture: Option<(egui::TextureId, (u32, u32))>,
    /// The texture egui's viewport texture points at.
    shown: Option<wgpu::Texture>,
    /// The live settings (the panels edit these).
    pub settings: LabSettings,
    pub settings_error: Option<String>,
    pub scene_error: Option<String>,
    pub frame_ms: f32,
    last_frame: Instant,
    pub scene_name: String,
    pub scene_path: Option<PathBuf>,
    pub unit_scale: f32,
}

impl Lab {
    fn new(
        cc: &eframe::CreationContext<'_>,
        scene: &crate::cli::SceneArgs,
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
        let loaded = crate::cli::load_scene(scene).map_err(|e| e.message)?;
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
        })
    }

    /// Replaces the scene (None: the embedded default) keeping device, settings and size.
    /// On failure the current scene stays and the error is returned for display.
    pub fn open_scene(&mut self, path: Option<PathBuf>, unit_scale: f32) -> Result<(), String> {
        let args = crate::cli::SceneArgs { scene: path.clone(), unit_scale, ..Default::default() };
        let scene = crate::cli::load_scene(&args).map_err(|e| e.message)?;
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
        // The new renderer has new textures: make the next frame re-point egui's texture.
        self.texture = self.texture.map(|(id, _)| (id, (0, 0)));
        Ok(())
    }

    /// Applies the live settings; a refused change keeps the renderer's last valid settings
    /// and says why.
    pub fn apply_settings(&mut self) {
        if self.settings == *self.renderer.settings() {
            return;
        }
        match self.renderer.set_settings(self.settings.clone()) {
            Ok(_) => self.settings_error = None,
            Err(e) => {
                self.settings_error = Some(format!("refused: {e}"));
                self.settings = self.renderer.settings().clone();
            }
        }
    }

    /// Points egui's texture at `texture` (through an sRGB view), re-registering only
    /// when the texture changed size or identity.
    fn show_texture(&mut self, texture: &wgpu::Texture, force: bool) -> egui::TextureId {
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

/// A preset load that has problems, waiting for the user's decision.
pub struct PendingLoad {
    pub path: Option<PathBuf>,
    pub loaded: Loaded,
}

/// The preset the live settings are compared with.
pub struct PresetState {
    /// File of the loaded preset (None: a new, unsaved preset).
    pub path: Option<PathBuf>,
    /// Its settings as loaded or last saved (the "differs from preset" markers).
    pub baseline: LabSettings,
    pub pending: Option<PendingLoad>,
    /// Name typed in the presets panel's "Save as" field.
    pub save_as_name: String,
    /// The diff view compares with the default (None) or this preset file.
    pub diff_with: Option<PathBuf>,
    /// The compared file's settings, with the path and modification time they were read at.
    pub diff_cache: Option<(PathBuf, Option<std::time::SystemTime>, Result<LabSettings, String>)>,
}

/// A recording of N frames to a folder (File → Record).
pub struct Recording {
    pub dir: PathBuf,
    pub remaining: u32,
    pub index: u32,
}

/// Everything but the tile tree (so that the tree's behaviour can borrow it).
pub struct State {
    pub args: AppArgs,
    pub config_dir: Option<PathBuf>,
    pub lab: Result<Lab, String>,
    pub session: Session,
    pub viewers: BTreeMap<u32, Viewer>,
    view_pipeline: Option<Arc<ViewPipeline>>,
    /// A viewer used by the viewport to show a hovered pass's output.
    pass_view: Option<Viewer>,
    pub preset: PresetState,
    /// The hovered frame pixel (viewport or a viewer) and every buffer's value there.
    pub hover: Option<(u32, u32)>,
    pub hover_values: Vec<ProbeValue>,
    pub pinned: Vec<PinnedProbe>,
    /// Per pinned probe: the chosen buffer's value over the last frames.
    pub probe_history: Vec<VecDeque<[f32; 4]>>,
    pub timing_history: VecDeque<Vec<PassTiming>>,
    /// The pass whose row the pointer is over in the timings panel.
    pub hovered_pass: Option<String>,
    /// Viewport size in physical pixels (the render size is this × the render scale).
    pub viewport_px: (u32, u32),
    /// Where the viewport was drawn last frame (points).
    pub viewport_rect: egui::Rect,
    /// Render at exactly this size whatever the viewport's (tests and scripted captures).
    pub render_size_override: Option<(u32, u32)>,
    pub status: Option<(String, Instant)>,
    pub frames: u64,
    pub recording: Option<Recording>,
    pub bookmark_name: String,
    /// Path typed in the scene panel (when no file dialog is available).
    pub scene_path_text: String,
    pub record_frames: u32,
    /// Panels the tree drew last frame (viewers not shown are not updated).
    pub visible_viewers: Vec<u32>,
    pub show_help: bool,
    /// View → VPL overlay: instant radiosity's VPLs (`vpl.list`) as dots over the viewport.
    pub show_vpls: bool,
    /// Draw the HCB's samples over the viewport (Nguyen et al.'s white dots).
    pub show_hcb_samples: bool,
    /// The A/B comparison, when one runs.
    pub ab: Option<crate::ab::Ab>,
    pub hot: crate::hot_reload::HotReload,
    pub request_new_viewer: bool,
    pub request_reset_layout: bool,
    screenshot: Arc<Mutex<Option<Arc<egui::ColorImage>>>>,
    screenshot_requested: bool,
    last_autosave: Instant,
    last_saved_session: String,
}

pub struct GiLabApp {
    pub tree: egui_tiles::Tree<Pane>,
    pub state: State,
}

impl GiLabApp {
    pub fn new(cc: &eframe::CreationContext<'_>, args: AppArgs) -> Self {
        let config_dir = session::config_dir(args.config_dir.as_deref());
        let (mut session, session_problem) = match (&config_dir, args.fresh) {
            (Some(dir), false) => Session::load(dir),
            _ => (Session::default(), None),
        };
        // Command-line choices win over the restored session.
        if args.scene.scene.is_some() {
            session.scene = args.scene.scene.clone();
            session.unit_scale = args.scene.unit_scale;
            session.lights.clear();
            session.camera = None;
        }
        let mut messages: Vec<String> = session_problem.into_iter().collect();
        let mut preset_path = session.preset_path.clone();
        let mut baseline = LabSettings::default();
        let mut settings = LabSettings::default();
        if let Some(p) = &args.scene.preset {
            preset_path = Some(p.clone());
        }
        if let Some(p) = &preset_path {
            match gi_render::preset::load_file(p) {
                Ok(l) => {
                    for pr in &l.problems {
                        messages.push(format!("{}: {pr}", p.display()));
                    }
                    baseline = l.settings.clone();
                    settings = l.settings;
                }
                Err(e) => {
                    messages.push(format!("{e}; starting from the defaults"));
                    preset_path = None;
                }
            }
        }
        // Unsaved edits of the last session come back on top of their preset.
        if args.scene.preset.is_none()
            && let Some(text) = &session.settings_ron
            && let Ok(l) = gi_render::preset::load_lenient(text, "session")
        {
            settings = l.settings;
        }
        for o in &args.scene.overrides {
            if let Err(e) = settings.apply_override(o) {
                messages.push(format!("--set {o}: {e}"));
            }
        }
        let scene_args = crate::cli::SceneArgs {
            scene: session.scene.clone(),
            unit_scale: session.unit_scale,
            preset: None,
            overrides: Vec::new(),
        };
        let mut lab = Lab::new(cc, &scene_args, settings.clone());
        if lab.is_err() && session.scene.is_some() && args.scene.scene.is_none() {
            // The remembered scene is gone: start on the default scene rather than not at all.
            let e = lab.as_ref().err().cloned().unwrap_or_default();
            messages.push(format!("the last session's scene could not be opened ({e}); the default scene is shown"));
            session.scene = None;
            session.lights.clear();
            session.camera = None;
            lab = Lab::new(cc, &crate::cli::SceneArgs::default(), settings.clone());
        }
        if let Err(e) = &lab {
            log::error!("{e}");
        }
        if let Ok(l) = &mut lab {
            restore_scene_state(l, &session);
        }
        let tree = session.layout.take().unwrap_or_else(session::default_layout);
        let mut viewers = BTreeMap::new();
        for (id, v) in session.viewers.drain(..) {
            viewers.insert(id, Viewer::new(v));
        }
        for id in viewer_ids(&tree) {
            viewers.entry(id).or_insert_with(|| Viewer::new(ViewerState::default()));
        }
        let pinned = std::mem::take(&mut session.probes);
        let history = pinned.iter().map(|_| VecDeque::new()).collect();
        let status = (!messages.is_empty()).then(|| (messages.join("\n"), Instant::now()));
        for m in &messages {
            log::warn!("{m}");
        }
        let mut hot = crate::hot_reload::HotReload::new(args.shaders_dir.clone());
        if args.hot_reload.unwrap_or(cfg!(debug_assertions))
            && let Err(e) = hot.set_enabled(true)
        {
            log::info!("shader hot reload off: {e}");
        }
        let state = State {
            hot,
            args,
            config_dir,
            lab,
            session,
            viewers,
            view_pipeline: None,
            pass_view: None,
            preset: PresetState {
                path: preset_path,
                baseline,
                pending: None,
                save_as_name: String::new(),
                diff_with: None,
                diff_cache: None,
            },
            hover: None,
            hover_values: Vec::new(),
            pinned,
            probe_history: history,
            timing_history: VecDeque::new(),
            hovered_pass: None,
            viewport_px: (640, 480),
            viewport_rect: egui::Rect::NOTHING,
            render_size_override: None,
            status,
            frames: 0,
            recording: None,
            bookmark_name: String::new(),
            scene_path_text: String::new(),
            record_frames: 60,
            visible_viewers: Vec::new(),
            show_help: false,
            show_vpls: false,
            show_hcb_samples: false,
            ab: None,
            request_new_viewer: false,
            request_reset_layout: false,
            screenshot: Arc::new(Mutex::new(None)),
            screenshot_requested: false,
            last_autosave: Instant::now(),
            last_saved_session: String::new(),
        };
        Self { tree, state }
    }

    /// Whether a renderer is running (false when the GPU or scene failed).
    pub fn is_rendering(&self) -> bool {
        self.state.lab.is_ok()
    }

    /// Why the renderer could not start, if it could not.
    pub fn error(&self) -> Option<&str> {
        self.state.lab.as_ref().err().map(|e| e.as_str())
    }

    /// Opens a scene as Scene → Open does; on failure the current scene stays, and the
    /// error is returned and shown.
    pub fn open_scene(&mut self, path: &str, unit_scale: f32) -> Result<(), String> {
        self.state.open_scene(Some(PathBuf::from(path)), unit_scale)
    }

    /// The running renderer, if any.
    pub fn renderer(&self) -> Option<&Renderer> {
        self.state.lab.as_ref().ok().map(|l| &l.renderer)
    }

    /// The live settings (what the panels show), if the renderer runs.
    pub fn settings(&self) -> Option<&LabSettings> {
        self.state.lab.as_ref().ok().map(|l| &l.settings)
    }

    /// Writes the session now (also done every few seconds and on exit).
    pub fn save_session(&mut self) -> Result<(), String> {
        let s = self.session_snapshot();
        let dir = self.state.config_dir.clone().ok_or("no config directory on this platform")?;
        s.save(&dir)?;
        self.state.last_saved_session = s.to_ron();
        Ok(())
    }

    fn session_snapshot(&self) -> Session {
        let st = &self.state;
        let mut s = st.session.clone();
        s.layout = Some(self.tree.clone());
        s.preset_path = st.preset.path.clone();
        s.viewers = st.viewers.iter().map(|(id, v)| (*id, v.state.clone())).collect();
        s.probes = st.pinned.clone();
        if let Ok(l) = &st.lab {
            s.settings_ron = Some(l.settings.to_ron());
            s.scene = l.scene_path.clone();
            s.unit_scale = l.unit_scale;
            s.camera = Some(l.renderer.camera);
            s.playing = l.renderer.clock.playing;
            s.speed = l.renderer.clock.speed;
            s.loop_s = l.renderer.clock.loop_s;
            s.time_s = l.renderer.clock.time_s() as f64;
            let scene = l.renderer.scene();
            s.lights = scene
                .nodes
                .iter()
                .enumerate()
                .filter_map(|(i, n)| {
                    let li = n.light?;
                    Some(LightEdit {
                        node: i,
                        translation: n.transform.translation.to_array(),
                        rotation: n.transform.rotation.to_array(),
                        intensity: scene.lights[li].intensity,
                    })
                })
                .collect();
        }
        s
    }

    fn autosave(&mut self) {
        if self.state.last_autosave.elapsed().as_secs_f32() < 2.0 || self.state.config_dir.is_none() {
            return;
        }
        self.state.last_autosave = Instant::now();
        let text = self.session_snapshot().to_ron();
        if text != self.state.last_saved_session
            && let Err(e) = self.save_session()
        {
            self.state.set_status(format!("session autosave failed: {e}"));
        }
    }

    fn screenshot_step(&mut self, ctx: &egui::Context) {
        let st = &mut self.state;
        let Some(path) = st.args.screenshot.clone() else { return };
        if !st.screenshot_requested && st.frames >= st.args.screenshot_frames {
            let slot = st.screenshot.clone();
            ctx.request_screenshot(move |img| {
                if let Ok(mut s) = slot.lock() {
                    *s = Some(img);
                }
            });
            st.screenshot_requested = true;
        }
        let taken = st.screenshot.lock().ok().and_then(|mut s| s.take());
        if let Some(img) = taken {
            save_color_image(&path, &img);
            ctx.send_viewport_cmd(egui::ViewportCommand::Close);
        }
    }

    /// Adds a buffer viewer panel next to the first viewer (or on the right).
    pub fn add_viewer(&mut self) {
        let id = self.state.viewers.keys().max().copied().unwrap_or(0) + 1;
        let mut v = Viewer::new(ViewerState::default());
        if let Ok(l) = &self.state.lab {
            v.show_buffer(&l.renderer, "gbuffer.motion");
        }
        self.state.viewers.insert(id, v);
        let pane = self.tree.tiles.insert_pane(Pane::Viewer(id));
        let parent = viewer_ids(&self.tree)
            .first()
            .and_then(|first| self.tree.tiles.find_pane(&Pane::Viewer(*first)))
            .and_then(|t| self.tree.tiles.parent_of(t))
            .or(self.tree.root());
        if let Some(parent) = parent
            && let Some(egui_tiles::Tile::Container(c)) = self.tree.tiles.get_mut(parent)
        {
            c.add_child(pane);
            if let egui_tiles::Container::Tabs(t) = c {
                t.set_active(pane);
            }
        }
    }
}

fn viewer_ids(tree: &egui_tiles::Tree<Pane>) -> Vec<u32> {
    let mut ids: Vec<u32> = tree
        .tiles
        .tiles()
        .filter_map(|t| match t {
            egui_tiles::Tile::Pane(Pane::Viewer(id)) => Some(*id),
            _ => None,
        })
        .collect();
    ids.sort();
    ids
}

/// Camera, light edits and timeline of the session, applied to a freshly created lab.
fn restore_scene_state(l: &mut Lab, s: &Session) {
    if let Some(c) = s.camera {
        l.renderer.camera = c;
    }
    let scene = l.renderer.scene_mut();
    for e in &s.lights {
        if let Some(n) = scene.nodes.get_mut(e.node)
            && let Some(li) = n.light
        {
            n.transform.translation = glam::Vec3::from_array(e.translation);
            n.transform.rotation = glam::Quat::from_array(e.rotation).normalize();
            if let Some(light) = scene.lights.get_mut(li) {
                light.intensity = e.intensity;
            }
        }
    }
    let c = &mut l.renderer.clock;
    c.playing = s.playing;
    c.speed = if s.speed > 0.0 { s.speed } else { 1.0 };
    c.loop_s = s.loop_s.max(0.0);
    c.seek(s.time_s);
    l.renderer.reset_history();
}

/// A file-name-safe UTC time stamp for captures (`2026-11-22T17-03-46Z`).
pub fn capture_stamp() -> String {
    gi_render::preset::utc_now().replace(':', "-")
}

fn save_color_image(path: &Path, img: &egui::ColorImage) {
    let [w, h] = img.size;
    let bytes: Vec<u8> = img.pixels.iter().flat_map(|c| c.to_array()).collect();
    match image::RgbaImage::from_raw(w as u32, h as u32, bytes) {
        Some(i) => match i.save(path) {
            Ok(()) => println!("wrote screenshot {}", path.display()),
            Err(e) => eprintln!("gi-lab: cannot write screenshot {}: {e}", path.display()),
        },
        None => eprintln!("gi-lab: screenshot has inconsistent size"),
    }
}

impl State {
    pub fn set_status(&mut self, message: impl Into<String>) {
        let m = message.into();
        log::info!("{m}");
        self.status = Some((m, Instant::now()));
    }

    pub fn open_scene(&mut self, path: Option<PathBuf>, unit_scale: f32) -> Result<(), String> {
        let lab = self.lab.as_mut().map_err(|e| e.clone())?;
        let r = lab.open_scene(path.clone(), unit_scale);
        lab.scene_error = r.clone().err();
        if r.is_ok() {
            // B renders the old scene: the comparison ends with it.
            self.stop_ab();
            self.session.lights.clear();
            if let Some(p) = &path {
                Session::remember(&mut self.session.recent_scenes, p);
            }
            self.pass_view = None;
        }
        r
    }

    /// Asks for a glTF file with the platform's file dialog and opens it.
    pub fn open_scene_dialog(&mut self) {
        let picked =
            rfd::FileDialog::new().add_filter("glTF 2.0", &["gltf", "glb"]).set_title("Open scene").pick_file();
        if let Some(p) = picked {
            let scale = self.lab.as_ref().map(|l| l.unit_scale).unwrap_or(1.0);
            if let Err(e) = self.open_scene(Some(p), scale) {
                self.set_status(format!("scene not opened: {e}"));
            }
        }
    }

    /// Whether the live settings differ from the loaded preset (the unsaved marker).
    pub fn unsaved(&self) -> bool {
        self.lab.as_ref().is_ok_and(|l| l.settings != self.preset.baseline)
    }

    /// The preset's label with the unsaved marker (the A side of an A/B comparison).
    pub fn preset_label_text(&self) -> String {
        format!("{}{}", self.preset_label(), if self.unsaved() { " (unsaved)" } else { "" })
    }

    pub fn preset_label(&self) -> String {
        self.preset
            .path
            .as_ref()
            .and_then(|p| p.file_name())
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| "new preset".into())
    }

    /// Opens a preset. A clean file applies at once; one with problems opens the problem
    /// dialog, and nothing changes until the user accepts the listed fixes.
    pub fn open_preset(&mut self, path: &Path) {
        match gi_render::preset::load_file(path) {
            Ok(loaded) => {
                Session::remember(&mut self.session.recent_presets, path);
                if loaded.problems.is_empty() {
                    for m in &loaded.migrations {
                        self.set_status(format!("{}: migrated, {m}", path.display()));
                    }
                    self.apply_preset(Some(path.to_path_buf()), loaded.settings);
                } else {
                    self.preset.pending = Some(PendingLoad { path: Some(path.to_path_buf()), loaded });
                }
            }
            Err(e) => {
                // Nothing usable: say so in the dialog, keep everything as it is.
                self.preset.pending = Some(PendingLoad {
                    path: None,
                    loaded: Loaded {
                        settings: LabSettings::default(),
                        problems: vec![gi_render::preset::Problem {
                            field: path.display().to_string(),
                            message: e.to_string(),
                        }],
                        migrations: Vec::new(),
                    },
                });
            }
        }
    }

    pub fn open_preset_dialog(&mut self) {
        if let Some(p) = rfd::FileDialog::new()
            .add_filter("GI Lab preset", &["ron"])
            .set_directory(&self.args.presets_dir)
            .set_title("Open preset")
            .pick_file()
        {
            self.open_preset(&p);
        }
    }

    fn apply_preset(&mut self, path: Option<PathBuf>, settings: LabSettings) {
        self.preset.path = path;
        self.preset.baseline = settings.clone();
        if let Ok(l) = &mut self.lab {
            l.settings = settings;
            l.apply_settings();
            // A refused preset (e.g. an atlas too large for this GPU) keeps the renderer's
            // settings; the baseline stays the file's so that the difference shows.
        }
    }

    /// File → New: the defaults, not yet saved anywhere.
    pub fn new_preset(&mut self) {
        self.apply_preset(None, LabSettings::default());
    }

    /// File → Revert: reload the preset file, dropping the live edits.
    pub fn revert_preset(&mut self) {
        match self.preset.path.clone() {
            Some(p) => self.open_preset(&p),
            None => self.new_preset(),
        }
    }

    /// Saves the live settings to `path` atomically (a backup of the replaced file is kept).
    pub fn save_preset_to(&mut self, path: &Path) -> Result<(), String> {
        let Ok(l) = &self.lab else { return Err("no renderer".into()) };
        let settings = l.settings.clone();
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        }
        settings.save(path).map_err(|e| e.to_string())?;
        self.preset.path = Some(path.to_path_buf());
        self.preset.baseline = settings;
        Session::remember(&mut self.session.recent_presets, path);
        self.set_status(format!("saved {}", path.display()));
        Ok(())
    }

    /// File → Save (Save As when the preset has no file yet).
    pub fn save_preset(&mut self) {
        match self.preset.path.clone() {
            Some(p) => {
                if let Err(e) = self.save_preset_to(&p) {
                    self.set_status(format!("save failed: {e}"));
                }
            }
            None => self.save_preset_as_dialog(),
        }
    }

    pub fn save_preset_as_dialog(&mut self) {
        if let Some(p) = rfd::FileDialog::new()
            .add_filter("GI Lab preset", &["ron"])
            .set_directory(&self.args.presets_dir)
            .set_file_name("preset.ron")
            .set_title("Save preset as")
            .save_file()
            && let Err(e) = self.save_preset_to(&p)
        {
            self.set_status(format!("save failed: {e}"));
        }
    }

    /// The engine export of the live settings with provenance.
    pub fn export(&self) -> Option<Export> {
        let l = self.lab.as_ref().ok()?;
        Some(Export::new(l.settings.clone(), Provenance::now(&l.scene_name, l.renderer.camera)))
    }

    pub fn export_to(&mut self, path: &Path, format: ExportFormat) -> Result<(), String> {
        let e = self.export().ok_or("no renderer")?;
        gi_render::preset::write_atomic(path, &e.to_text(format)).map_err(|e| format!("{}: {e}", path.display()))?;
        self.set_status(format!("exported {}", path.display()));
        Ok(())
    }

    pub fn export_dialog(&mut self, format: ExportFormat) {
        let stem = self.preset_label().trim_end_matches(".ron").to_string();
        if let Some(p) = rfd::FileDialog::new()
            .add_filter("GI Lab export", &[format.extension()])
            .set_file_name(format!("{stem}.{}", format.extension()))
            .set_title("Export preset for engines")
            .save_file()
            && let Err(e) = self.export_to(&p, format)
        {
            self.set_status(format!("export failed: {e}"));
        }
    }

    /// File → Import export: the settings of an engine export (JSON or RON).
    pub fn import_export(&mut self, path: &Path) -> Result<(), String> {
        let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
        let e = Export::parse(&text, &path.display().to_string()).map_err(|e| e.to_string())?;
        self.apply_preset(None, e.settings);
        self.set_status(format!(
            "imported {} (exported by GI Lab {} on {} for {})",
            path.display(),
            e.provenance.gi_lab_version,
            e.provenance.date,
            e.provenance.scene
        ));
        Ok(())
    }

    /// Saves the viewport's image (final.ldr as PNG, final.hdr as EXR) into `captures/`.
    pub fn capture_viewport(&mut self) {
        let Ok(l) = &self.lab else { return };
        let stamp = crate::app::capture_stamp();
        let dir = PathBuf::from("captures");
        let r = (|| -> Result<String, String> {
            std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
            let ldr = l.renderer.readback("final.ldr").map_err(|e| e.to_string())?;
            let hdr = l.renderer.readback("final.hdr").map_err(|e| e.to_string())?;
            let png = dir.join(format!("viewport-{stamp}.png"));
            let exr = dir.join(format!("viewport-{stamp}.exr"));
            gi_render::image_io::save_png(&png, &ldr, gi_render::BufferKind::Ldr).map_err(|e| e.to_string())?;
            gi_render::image_io::save_exr(&exr, &hdr).map_err(|e| e.to_string())?;
            Ok(format!("saved {} and {}", png.display(), exr.display()))
        })();
        self.set_status(r.unwrap_or_else(|e| format!("capture failed: {e}")));
    }

    /// File → Record: the next `frames` frames as numbered PNGs in a new folder.
    pub fn start_recording(&mut self, frames: u32) {
        let stamp = crate::app::capture_stamp();
        let dir = PathBuf::from("captures").join(format!("sequence-{stamp}"));
        match std::fs::create_dir_all(&dir) {
            Ok(()) => {
                self.set_status(format!("recording {frames} frames to {}", dir.display()));
                self.recording = Some(Recording { dir, remaining: frames, index: 0 });
            }
            Err(e) => self.set_status(format!("cannot record to {}: {e}", dir.display())),
        }
    }

    fn record_step(&mut self) {
        let (Some(rec), Ok(l)) = (&mut self.recording, &self.lab) else { return };
        let path = rec.dir.join(format!("frame-{:05}.png", rec.index));
        let r = l.renderer.readback("final.ldr").map_err(|e| e.to_string()).and_then(|img| {
            gi_render::image_io::save_png(&path, &img, gi_render::BufferKind::Ldr).map_err(|e| e.to_string())
        });
        rec.index += 1;
        rec.remaining = rec.remaining.saturating_sub(1);
        let done = rec.remaining == 0;
        let dir = rec.dir.clone();
        let count = rec.index;
        if let Err(e) = r {
            self.recording = None;
            self.set_status(format!("recording stopped: {e}"));
        } else if done {
            self.recording = None;
            self.set_status(format!("recorded {count} frames to {}", dir.display()));
        }
    }

    /// Installs changed shaders and rebuilds the passes (and viewers) that use them.
    fn hot_reload(&mut self) {
        let changes = self.hot.poll();
        if changes.entries.is_empty() {
            return;
        }
        let Ok(l) = &mut self.lab else { return };
        match l.renderer.reload_shaders(&changes.entries) {
            Ok(passes) => {
                let mut rebuilt: Vec<String> = passes.iter().map(|p| p.to_string()).collect();
                if changes.entries.iter().any(|e| e.starts_with("view/")) {
                    // The viewers' pipeline: new views from the new source.
                    self.view_pipeline = None;
                    for v in self.viewers.values_mut() {
                        v.reset_gpu();
                    }
                    self.pass_view = None;
                    rebuilt.push("buffer viewers".into());
                }
                let m = format!("reloaded {}, rebuilt {}", changes.files.join(", "), rebuilt.join(", "));
                self.hot.last_reload = Some(m.clone());
                self.set_status(m);
            }
            Err(e) => {
                // naga accepted it but the device did not: undo, keep the old pipelines.
                for f in &changes.files {
                    gi_render::shaders::clear_override(f);
                    self.hot.errors.insert(f.clone(), format!("pipeline creation failed: {e}"));
                }
            }
        }
    }

    /// Renders this frame, probes, and updates the viewers.
    fn frame(&mut self) {
        self.hot_reload();
        let scale = self.session.render_scale.clamp(0.1, 2.0);
        let (vw, vh) = self.viewport_px;
        let target = self
            .render_size_override
            .unwrap_or((((vw as f32) * scale).round() as u32, ((vh as f32) * scale).round() as u32));
        let Ok(l) = &mut self.lab else { return };
        if target.0 > 0 && target.1 > 0 {
            if let Err(e) = l.renderer.resize(target.0, target.1) {
                l.settings_error = Some(e.to_string());
            }
            if let Some(ab) = &mut self.ab {
                // B first: it takes A's clock before A's frame advances it.
                ab.render(&l.renderer);
            }
            l.renderer.render_frame();
            let now = Instant::now();
            l.frame_ms = (now - l.last_frame).as_secs_f32() * 1e3;
            l.last_frame = now;
            self.timing_history.push_back(l.renderer.timings().to_vec());
            while self.timing_history.len() > self.session.history_frames.max(2) {
                self.timing_history.pop_front();
            }
        }
        // Probes: the hovered pixel and every pinned one, in one readback.
        let mut points: Vec<(u32, u32)> = self.hover.into_iter().collect();
        points.extend(self.pinned.iter().map(|p| p.pixel));
        points.truncate(gi_render::passes::view::PROBE_MAX_POINTS);
        let (fw, fh) = l.renderer.size();
        let points: Vec<(u32, u32)> = points.into_iter().map(|(x, y)| (x.min(fw - 1), y.min(fh - 1))).collect();
        if !points.is_empty() {
            match l.renderer.probe(&points) {
                Ok(mut values) => {
                    if self.hover.is_some() {
                        self.hover_values = values.remove(0);
                    } else {
                        self.hover_values.clear();
                    }
                    self.probe_history.resize_with(self.pinned.len(), VecDeque::new);
                    for ((p, h), vals) in self.pinned.iter().zip(&mut self.probe_history).zip(values) {
                        let v = vals.iter().find(|v| v.name == p.buffer).map(|v| v.value).unwrap_or([f32::NAN; 4]);
                        h.push_back(v);
                        while h.len() > self.session.history_frames.max(2) {
                            h.pop_front();
                        }
                    }
                }
                Err(e) => self.status = Some((format!("probe: {e}"), Instant::now())),
            }
        } else {
            self.hover_values.clear();
        }
        let pipeline = self.view_pipeline.get_or_insert_with(|| ViewPipeline::new(&l.renderer.ctx)).clone();
        for id in &self.visible_viewers {
            if let Some(v) = self.viewers.get_mut(id) {
                v.update(&l.renderer, &pipeline, &l.render_state);
            }
        }
        // The viewport shows the hovered pass's output instead of the final image.
        if let Some(pass) = &self.hovered_pass
            && let Some(buffer) = gi_render::frame::scope_output(pass)
        {
            let v = self.pass_view.get_or_insert_with(|| Viewer::new(ViewerState::default()));
            if v.state.buffer != buffer {
                v.show_buffer(&l.renderer, buffer);
                if v.state.view.mode != gi_render::passes::view::ViewMode::Rgb
                    || matches!(
                        buffer,
                        "gbuffer.position"
                            | "vpl.light_gbuffer.position"
                            | "final.hdr"
                            | "direct.radiance"
                            | "indirect.raw"
                    )
                {
                    v.state.range_mode = crate::viewer::RangeMode::Percentile;
                }
            }
            v.update(&l.renderer, &pipeline, &l.render_state);
        }
        self.record_step();
    }

    /// The viewport's texture this frame: the hovered pass's output or the final image.
    pub fn viewport_texture(&mut self) -> Option<(egui::TextureId, (u32, u32), Option<String>)> {
        let l = self.lab.as_mut().ok()?;
        if let (Some(pass), Some(v)) = (&self.hovered_pass, &self.pass_view)
            && let Some(out) = v.output_texture()
        {
            let size = (out.width(), out.height());
            let id = l.show_texture(&out, false);
            return Some((id, size, Some(format!("{pass}: {}", v.state.buffer))));
        }
        let out = l.renderer.final_ldr().clone();
        let force =
            l.texture.is_some_and(|(_, s)| s == (0, 0)) || self.pass_view.is_some() && self.hovered_pass.is_none();
        if self.hovered_pass.is_none() {
            self.pass_view = None;
        }
        let id = l.show_texture(&out, force);
        Some((id, (out.width(), out.height()), None))
    }

    /// Starts an A/B comparison of the live settings with `source`.
    pub fn start_ab(&mut self, source: crate::ab::AbSource) {
        self.stop_ab();
        let Ok(l) = &self.lab else { return };
        match crate::ab::Ab::start(&l.renderer, &l.settings, source) {
            Ok(ab) => self.ab = Some(ab),
            Err(e) => self.set_status(format!("A/B not started: {e}")),
        }
    }

    pub fn stop_ab(&mut self) {
        if let (Some(mut ab), Ok(l)) = (self.ab.take(), &self.lab) {
            ab.release(&l.render_state);
        }
    }

    pub fn pin_probe(&mut self, pixel: (u32, u32)) {
        if self.pinned.len() + 1 >= gi_render::passes::view::PROBE_MAX_POINTS {
            self.set_status("too many pinned probes");
            return;
        }
        let buffer = self.viewers.values().next().map(|v| v.state.buffer.clone()).unwrap_or_else(|| "final.hdr".into());
        self.pinned.push(PinnedProbe { pixel, buffer, channel: 0 });
        self.probe_history.push(VecDeque::new());
    }

    pub fn add_bookmark(&mut self) {
        let Ok(l) = &self.lab else { return };
        let name = if self.bookmark_name.trim().is_empty() {
            format!("view {}", self.session.bookmarks.len() + 1)
        } else {
            self.bookmark_name.trim().to_string()
        };
        self.session.bookmarks.push(Bookmark { name, camera: l.renderer.camera });
        self.bookmark_name.clear();
    }

    fn handle_dropped_files(&mut self, ctx: &egui::Context) {
        let dropped: Vec<PathBuf> = ctx.input(|i| {
            i.raw.dropped_files.iter().map(|f| f.path().to_path_buf()).filter(|p| !p.as_os_str().is_empty()).collect()
        });
        for p in dropped {
            let ext = p.extension().map(|e| e.to_string_lossy().to_ascii_lowercase()).unwrap_or_default();
            match ext.as_str() {
                "gltf" | "glb" => {
                    let scale = self.lab.as_ref().map(|l| l.unit_scale).unwrap_or(1.0);
                    if let Err(e) = self.open_scene(Some(p.clone()), scale) {
                        self.set_status(format!("scene not opened: {e}"));
                    }
                }
                "ron" if !std::fs::read_to_string(&p).is_ok_and(|t| t.contains("gi-lab-preset")) => {
                    self.open_preset(&p)
                }
                "ron" | "json" => {
                    if let Err(e) = self.import_export(&p) {
                        self.set_status(format!("import failed: {e}"));
                    }
                }
                _ => self.set_status(format!("{}: drop a .gltf/.glb scene or a .ron/.json preset", p.display())),
            }
        }
    }

    fn shortcuts(&mut self, ctx: &egui::Context) {
        use egui::{Key, KeyboardShortcut, Modifiers};
        let typing = ctx.egui_wants_keyboard_input();
        let pressed = |m: Modifiers, k: Key| ctx.input_mut(|i| i.consume_shortcut(&KeyboardShortcut::new(m, k)));
        let ctrl_shift = Modifiers::COMMAND | Modifiers::SHIFT;
        if pressed(ctrl_shift, Key::S) {
            self.save_preset_as_dialog();
        } else if pressed(Modifiers::COMMAND, Key::S) {
            self.save_preset();
        }
        if pressed(ctrl_shift, Key::O) {
            self.open_scene_dialog();
        } else if pressed(Modifiers::COMMAND, Key::O) {
            self.open_preset_dialog();
        }
        if pressed(Modifiers::COMMAND, Key::N) {
            self.new_preset();
        }
        if pressed(Modifiers::COMMAND, Key::E) {
            self.export_dialog(ExportFormat::Json);
        }
        if pressed(Modifiers::COMMAND, Key::B) {
            self.request_new_viewer = true;
        }
        if pressed(Modifiers::NONE, Key::F12) {
            self.capture_viewport();
        }
        if typing {
            return;
        }
        let Ok(l) = &mut self.lab else { return };
        if pressed(Modifiers::NONE, Key::Space) {
            l.renderer.clock.playing = !l.renderer.clock.playing;
        }
        if pressed(Modifiers::NONE, Key::Period) && !l.renderer.clock.playing {
            l.renderer.clock.step();
        }
        if pressed(Modifiers::NONE, Key::Home) {
            let (w, h) = l.renderer.size();
            l.renderer.camera =
                gi_render::frame::default_camera(l.renderer.scene(), l.renderer.bounds(), w as f32 / h.max(1) as f32);
        }
        if pressed(Modifiers::NONE, Key::H) {
            l.renderer.reset_history();
        }
        if pressed(Modifiers::NONE, Key::Escape) {
            self.pinned.clear();
            self.probe_history.clear();
        }
    }

    fn menu_bar(&mut self, ui: &mut egui::Ui) {
        let ctx = ui.ctx().clone();
        egui::MenuBar::new().ui(ui, |ui| {
            ui.menu_button("File", |ui| {
                if ui.button("New preset").clicked() {
                    self.new_preset();
                }
                if ui.button("Open preset…").clicked() {
                    self.open_preset_dialog();
                }
                ui.menu_button("Recent presets", |ui| {
                    for p in self.session.recent_presets.clone() {
                        if ui.button(p.display().to_string()).clicked() {
                            self.open_preset(&p);
                        }
                    }
                });
                if ui.button("Save preset").clicked() {
                    self.save_preset();
                }
                if ui.button("Save preset as…").clicked() {
                    self.save_preset_as_dialog();
                }
                if ui.add_enabled(self.unsaved(), egui::Button::new("Revert")).clicked() {
                    self.revert_preset();
                }
                ui.separator();
                if ui.button("Export for engines (JSON)…").clicked() {
                    self.export_dialog(ExportFormat::Json);
                }
                if ui.button("Export for engines (RON)…").clicked() {
                    self.export_dialog(ExportFormat::Ron);
                }
                if ui.button("Import an export…").clicked()
                    && let Some(p) = rfd::FileDialog::new().add_filter("GI Lab export", &["json", "ron"]).pick_file()
                    && let Err(e) = self.import_export(&p)
                {
                    self.set_status(format!("import failed: {e}"));
                }
                ui.separator();
                if ui.button("Save viewport (PNG + EXR)").clicked() {
                    self.capture_viewport();
                }
                ui.horizontal(|ui| {
                    if ui.button("Record").clicked() {
                        self.start_recording(self.record_frames);
                    }
                    ui.add(egui::DragValue::new(&mut self.record_frames).range(1..=100_000).suffix(" frames"));
                });
                ui.separator();
                if ui.button("Quit").clicked() {
                    ctx.send_viewport_cmd(egui::ViewportCommand::Close);
                }
            });
            ui.menu_button("View", |ui| {
                if ui.button("Add buffer viewer").clicked() {
                    self.request_new_viewer = true;
                }
                if ui.button("Reset panel layout").clicked() {
                    self.request_reset_layout = true;
                }
                let mut hot = self.hot.enabled();
                if ui
                    .checkbox(&mut hot, "Shader hot reload")
                    .on_hover_text(format!(
                        "watch {} and rebuild the passes whose shaders change",
                        self.hot.dir().display()
                    ))
                    .changed()
                    && let Err(e) = self.hot.set_enabled(hot)
                {
                    self.set_status(e);
                }
                ui.checkbox(&mut self.show_vpls, "VPL overlay (vpl.list)").on_hover_text(
                    "instant radiosity's VPLs as dots over the viewport, coloured by their reflected flux \
                     (the brightest at full colour); reads the list back every frame",
                );
                ui.checkbox(&mut self.show_hcb_samples, "HCB samples overlay (Table 1)").on_hover_text(
                    "the hierarchical coherence buffer's samples as white dots, larger for higher levels, \
                     with the count per level, and the covered pixels no sample reached in magenta; \
                     reads the sample list back every frame",
                );
                ui.horizontal(|ui| {
                    ui.label("render scale");
                    ui.add(egui::Slider::new(&mut self.session.render_scale, 0.1..=2.0).step_by(0.05))
                        .on_hover_text("render resolution relative to the viewport's pixels");
                });
                ui.menu_button("A/B compare", |ui| {
                    if ui.button("with the exact-VPL reference").clicked() {
                        self.start_ab(crate::ab::AbSource::Reference);
                    }
                    if ui.button("with the current settings (frozen)").clicked() {
                        self.start_ab(crate::ab::AbSource::Frozen);
                    }
                    if ui.button("with a preset file…").clicked()
                        && let Some(p) = rfd::FileDialog::new()
                            .add_filter("GI Lab preset", &["ron"])
                            .set_directory(&self.args.presets_dir)
                            .pick_file()
                    {
                        self.start_ab(crate::ab::AbSource::Preset(p));
                    }
                    if ui.add_enabled(self.ab.is_some(), egui::Button::new("Stop")).clicked() {
                        self.stop_ab();
                    }
                });
                if let Ok(l) = &mut self.lab
                    && ui.button("Reset camera").clicked()
                {
                    let (w, h) = l.renderer.size();
                    l.renderer.camera = gi_render::frame::default_camera(
                        l.renderer.scene(),
                        l.renderer.bounds(),
                        w as f32 / h.max(1) as f32,
                    );
                }
            });
            ui.menu_button("Scene", |ui| {
                if ui.button("Open glTF…").clicked() {
                    self.open_scene_dialog();
                }
                ui.menu_button("Recent scenes", |ui| {
                    for p in self.session.recent_scenes.clone() {
                        if ui.button(p.display().to_string()).clicked() {
                            let scale = self.lab.as_ref().map(|l| l.unit_scale).unwrap_or(1.0);
                            if let Err(e) = self.open_scene(Some(p.clone()), scale) {
                                self.set_status(format!("scene not opened: {e}"));
                            }
                        }
                    }
                });
                if ui.button("Default scene").clicked()
                    && let Err(e) = self.open_scene(None, 1.0)
                {
                    self.set_status(format!("scene not opened: {e}"));
                }
                ui.menu_button("Camera bookmarks", |ui| {
                    let mut restore = None;
                    for b in &self.session.bookmarks {
                        if ui.button(&b.name).clicked() {
                            restore = Some(b.camera);
                        }
                    }
                    if let (Some(c), Ok(l)) = (restore, &mut self.lab) {
                        l.renderer.camera = c;
                    }
                    if ui.button("Bookmark this view").clicked() {
                        self.add_bookmark();
                    }
                });
            });
            ui.menu_button("Help", |ui| {
                if ui.button("Keyboard shortcuts").clicked() {
                    self.show_help = true;
                }
                ui.label(format!("GI Lab {}", env!("CARGO_PKG_VERSION")));
            });
        });
    }

    fn status_bar(&mut self, ui: &mut egui::Ui) {
        ui.horizontal(|ui| match &self.lab {
            Ok(l) => {
                let (w, h) = l.renderer.size();
                let gpu: f64 = l.renderer.timings().iter().map(|t| t.ms).sum();
                ui.label(l.renderer.ctx.adapter_summary());
                ui.separator();
                ui.label(format!(
                    "render {w}×{h} (viewport {}×{} × {:.2})",
                    self.viewport_px.0, self.viewport_px.1, self.session.render_scale
                ))
                .on_hover_text("View > render scale changes the render resolution");
                ui.separator();
                ui.label(format!("frame {:.1} ms · GPU {:.2} ms ({:?})", l.frame_ms, gpu, l.renderer.timing_source()));
                ui.separator();
                let unsaved = l.settings != self.preset.baseline;
                let label =
                    format!("preset: {}{}", self.preset_label(), if unsaved { " (unsaved changes)" } else { "" });
                if unsaved {
                    ui.colored_label(crate::settings_ui::CHANGED, label);
                } else {
                    ui.label(label);
                }
                if let Some(e) = l.gpu_error.lock().ok().and_then(|e| e.clone()) {
                    ui.separator();
                    ui.colored_label(ERROR, "GPU error").on_hover_text(e);
                }
                if !self.hot.errors.is_empty() {
                    ui.separator();
                    let all: Vec<String> = self.hot.errors.values().cloned().collect();
                    ui.colored_label(
                        ERROR,
                        format!("shader error in {}", self.hot.errors.keys().cloned().collect::<Vec<_>>().join(", ")),
                    )
                    .on_hover_text(all.join("\n\n"));
                }
                if let Some(r) = &self.recording {
                    ui.separator();
                    ui.colored_label(ERROR, format!("recording, {} frames left", r.remaining));
                }
                if let Some((m, at)) = &self.status
                    && at.elapsed().as_secs() < 20
                {
                    ui.separator();
                    ui.label(m.lines().next().unwrap_or("")).on_hover_text(m.as_str());
                }
            }
            Err(e) => {
                ui.colored_label(ERROR, "renderer unavailable");
                ui.label(e);
            }
        });
    }

    /// The dialog of a preset load with problems: every problem listed, the fixes named;
    /// nothing changes unless the user accepts.
    fn problem_dialog(&mut self, ctx: &egui::Context) {
        let Some(p) = &self.preset.pending else { return };
        let usable = p.path.is_some();
        let mut decision = None;
        egui::Modal::new(egui::Id::unique("preset_problems")).show(ctx, |ui| {
            ui.set_max_width(640.0);
            let title = match &p.path {
                Some(path) => format!("Preset {} has problems", path.display()),
                None => "The preset could not be loaded".to_string(),
            };
            ui.heading(title);
            ui.label(if usable {
                "GI Lab can load it with these fixes (nothing has changed yet):"
            } else {
                "Nothing was changed:"
            });
            egui::ScrollArea::vertical().max_height(360.0).show(ui, |ui| {
                for pr in &p.loaded.problems {
                    ui.horizontal_wrapped(|ui| {
                        ui.monospace(&pr.field);
                        ui.label(&pr.message);
                    });
                }
                for m in &p.loaded.migrations {
                    ui.label(format!("migration: {m}"));
                }
            });
            ui.separator();
            ui.horizontal(|ui| {
                if usable && ui.button("Load with these fixes").clicked() {
                    decision = Some(true);
                }
                if ui.button(if usable { "Cancel (keep current settings)" } else { "Close" }).clicked() {
                    decision = Some(false);
                }
            });
        });
        match decision {
            Some(true) => {
                if let Some(p) = self.preset.pending.take() {
                    self.apply_preset(p.path, p.loaded.settings);
                }
            }
            Some(false) => self.preset.pending = None,
            None => {}
        }
    }

    fn help_window(&mut self, ctx: &egui::Context) {
        let mut open = self.show_help;
        egui::Window::new("Keyboard shortcuts").open(&mut open).collapsible(false).show(ctx, |ui| {
            egui::Grid::new("shortcuts").striped(true).show(ui, |ui| {
                for (k, what) in SHORTCUTS {
                    ui.monospace(*k);
                    ui.label(*what);
                    ui.end_row();
                }
            });
        });
        self.show_help = open;
    }
}

impl eframe::App for GiLabApp {
    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        let ctx = ui.ctx().clone();
        self.state.handle_dropped_files(&ctx);
        self.state.shortcuts(&ctx);
        if std::mem::take(&mut self.state.request_new_viewer) {
            self.add_viewer();
        }
        if std::mem::take(&mut self.state.request_reset_layout) {
            self.tree = session::default_layout();
            for id in viewer_ids(&self.tree) {
                self.state.viewers.entry(id).or_insert_with(|| Viewer::new(ViewerState::default()));
            }
        }
        self.state.frame();
        // The panels set the hovered pixel again while they are drawn.
        self.state.hover = None;
        egui::Panel::top("menu").show(ui, |ui| self.state.menu_bar(ui));
        egui::Panel::bottom("status").show(ui, |ui| self.state.status_bar(ui));
        egui::CentralPanel::default().show(ui, |ui| {
            if let Err(e) = &self.state.lab {
                ui.centered_and_justified(|ui| {
                    ui.colored_label(ERROR, format!("GI Lab cannot render:\n{e}"));
                });
                return;
            }
            self.state.visible_viewers.clear();
            let mut behavior = crate::panes::Behavior { state: &mut self.state, closed_viewers: Vec::new() };
            self.tree.ui(&mut behavior, ui);
            let closed = std::mem::take(&mut behavior.closed_viewers);
            for id in closed {
                if let (Some(mut v), Ok(l)) = (self.state.viewers.remove(&id), &self.state.lab) {
                    v.release(&l.render_state);
                }
            }
        });
        self.state.problem_dialog(&ctx);
        self.state.help_window(&ctx);
        self.state.frames += 1;
        self.screenshot_step(&ctx);
        self.autosave();
        ctx.request_repaint();
    }

    fn on_exit(&mut self) {
        if let Err(e) = self.save_session() {
            log::warn!("session not saved: {e}");
        }
    }
}
