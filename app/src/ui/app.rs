//! The eframe app: the tile tree and the state, created from the launch options and the
//! restored session; the session autosave; each frame's panels.

use std::collections::{BTreeMap, VecDeque};
use std::path::PathBuf;
use std::time::Instant;

use gi_render::{LabSettings, Renderer};

use crate::args::AppArgs;
use crate::ui::ERROR;
use crate::ui::lab::Lab;
use crate::ui::session::{self, Pane, Session};
use crate::ui::state::State;
use crate::ui::state::presets::PresetState;
use crate::ui::viewer::{Viewer, ViewerState};

/// The window's test hook that destroys its GPU device at a frame (see `State::lose_device_at`).
const LOSE_DEVICE_ENV: &str = "GI_LAB_TEST_LOSE_DEVICE_AT";

pub struct GiLabApp {
    pub tree: egui_tiles::Tree<Pane>,
    pub state: State,
}

impl GiLabApp {
    pub fn new(cc: &eframe::CreationContext<'_>, args: AppArgs) -> Self {
        let explain = args.explain;
        crate::ui::install_fonts(&cc.egui_ctx);
        let config_dir = session::config_dir(args.config_dir.as_deref());
        // Temporary files of saves that a kill interrupted (the saved files themselves are
        // whole: `files::write_atomic`).
        for dir in config_dir.iter().chain([&args.presets_dir]) {
            let n = gi_render::files::remove_stale_temps(dir);
            if n > 0 {
                log::info!("removed {n} temporary files of interrupted saves from {}", dir.display());
            }
        }
        let saved = matches!((&config_dir, args.fresh), (Some(dir), false) if Session::file(dir).exists());
        let (mut session, session_problem) = match (&config_dir, args.fresh) {
            (Some(dir), false) => Session::load(dir),
            _ => (Session::default(), None),
        };
        // The render scale counts physical pixels; a new session renders one pixel per point
        // (issue #38: a 2× display would otherwise render four times the pixels).
        if !saved {
            session.render_scale = session::default_render_scale() / cc.egui_ctx.pixels_per_point().max(0.5);
        }
        // Command-line choices win over the restored session.
        if args.scene.scene.is_some() {
            session.scene = args.scene.scene.clone();
            session.unit_scale = args.scene.unit_scale;
            session.lights.clear();
            session.lights_complete = false;
            session.camera = None;
        }
        let mut messages: Vec<String> = session_problem.into_iter().collect();
        if let Some(why) = &args.recovered {
            messages.push(format!(
                "GI Lab restarted because the GPU device was lost ({why}); your session (scene, settings, camera, timeline, lights, layout) was restored"
            ));
        }
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
        let scene_args = crate::scene_args::SceneArgs {
            scene: session.scene.clone(),
            unit_scale: session.unit_scale,
            preset: None,
            overrides: Vec::new(),
            sky: args.scene.sky.clone(),
            sky_intensity: args.scene.sky_intensity,
            sky_rotation: args.scene.sky_rotation,
        };
        let mut lab = Lab::new(cc, &scene_args, settings.clone());
        if lab.is_err() && session.scene.is_some() && args.scene.scene.is_none() {
            // The remembered scene is gone: start on the default scene rather than not at all.
            let e = lab.as_ref().err().cloned().unwrap_or_default();
            messages.push(format!("the last session's scene could not be opened ({e}); the default scene is shown"));
            session.scene = None;
            session.lights.clear();
            session.lights_complete = false;
            session.camera = None;
            lab = Lab::new(cc, &crate::scene_args::SceneArgs::default(), settings.clone());
        }
        if let Err(e) = &lab {
            log::error!("{e}");
        }
        if let Ok(l) = &mut lab {
            restore_scene_state(l, &session);
            // What the lab chose for the scene: its light (issue #18), the view and the unit
            // (issue #37).
            if let Some(note) = crate::ui::state::scene_note(l.renderer.scene()) {
                messages.push(note);
            }
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
        let mut hot = crate::ui::hot_reload::HotReload::new(args.shaders_dir.clone());
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
            viewers: crate::ui::state::Viewers { open: viewers, ..Default::default() },
            probes: crate::ui::state::Probes { pinned, history, ..Default::default() },
            timings: Default::default(),
            overlays: Default::default(),
            requests: crate::ui::state::Requests { explain: explain.is_some(), ..Default::default() },
            capture: Default::default(),
            preset: PresetState {
                path: preset_path,
                baseline,
                pending: None,
                save_as_name: String::new(),
                diff_with: None,
                diff_cache: None,
                port_kit_job: None,
            },
            viewport_px: (640, 480),
            viewport_rect: egui::Rect::NOTHING,
            render_size_override: None,
            status,
            frames: 0,
            bookmark_name: String::new(),
            scene_path_text: String::new(),
            ab: None,
            grid: None,
            last_autosave: Instant::now(),
            last_saved_session: String::new(),
            device_lost: None,
            lose_device_at: std::env::var(LOSE_DEVICE_ENV).ok().and_then(|v| v.parse().ok()),
            history: Default::default(),
            settings_search: String::new(),
            adaptive: Default::default(),
            interacting: false,
            explain: explain.map(crate::ui::explain::ExplainView::new),
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
        s.viewers = st.viewers.open.iter().map(|(id, v)| (*id, v.state.clone())).collect();
        s.probes = st.probes.pinned.clone();
        if let Ok(l) = &st.lab {
            s.settings_ron = Some(l.settings.to_ron());
            s.scene = l.scene_path.clone();
            s.unit_scale = l.unit_scale;
            s.camera = Some(l.renderer.camera);
            s.playing = l.renderer.clock.playing;
            s.speed = l.renderer.clock.speed;
            s.loop_s = l.renderer.clock.loop_s;
            s.time_s = l.renderer.clock.time_s() as f64;
            s.lights = crate::scene_lights::light_edits(l.renderer.scene());
            s.lights_complete = true;
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

    /// When the GPU device is lost (a driver reset), nothing on it can be used again, eframe's
    /// painter included: the lab saves the session at once, starts itself again with that
    /// session (a new window, device, renderer, scene upload and textures, with the same
    /// scene, settings, camera, timeline, lights and layout) and ends this process; the new
    /// window says why it restarted. With the restart off (the UI tests' harness, whose
    /// painter survives), it shows what happened instead. Returns whether the device is lost.
    fn handle_device_loss(&mut self) -> bool {
        if self.state.device_lost.is_some() {
            return true;
        }
        let Some(why) = self.state.lab.as_ref().ok().and_then(|l| l.renderer.ctx.lost_reason()) else {
            return false;
        };
        let saved = self.save_session();
        let mut msg = format!("the GPU device was lost ({why})");
        match &saved {
            Ok(()) => msg += "; the session was saved",
            Err(e) => msg += &format!("; the session could not be saved ({e})"),
        }
        if self.state.args.restart_on_device_loss {
            // The painter shares the lost device and panics on its next paint (egui-wgpu
            // 0.37 cannot recover), so this process ends here: a new one takes over with the
            // saved session, or the log says why none could.
            let restarted = match saved {
                Ok(()) => self.restart(&why),
                Err(_) => Err("there is no saved session to restart with".into()),
            };
            match restarted {
                Ok(()) => {
                    log::error!("{msg} and GI Lab is restarting with it");
                    std::process::exit(0);
                }
                Err(e) => {
                    log::error!("{msg}; restarting failed ({e}): start GI Lab again to continue");
                    std::process::exit(1);
                }
            }
        }
        log::error!("{msg}");
        self.state.set_status(msg.clone());
        self.state.device_lost = Some(msg);
        true
    }

    /// Starts a new lab process on the saved session (the scene, settings and camera come
    /// from it, not from this run's --scene, --preset or --set).
    fn restart(&self, why: &str) -> Result<(), String> {
        let exe = std::env::current_exe().map_err(|e| e.to_string())?;
        let a = &self.state.args;
        let mut cmd = std::process::Command::new(exe);
        if let Some(dir) = &self.state.config_dir {
            cmd.arg("--config-dir").arg(dir);
        }
        cmd.arg("--presets-dir").arg(&a.presets_dir).arg("--shaders-dir").arg(&a.shaders_dir);
        if let Some(h) = a.hot_reload {
            cmd.arg("--hot-reload").arg(h.to_string());
        }
        // A scripted screenshot run still gives its screenshot, from the new window.
        if let Some(shot) = &a.screenshot {
            cmd.arg("--screenshot").arg(shot).arg("--screenshot-frames").arg(a.screenshot_frames.to_string());
        }
        cmd.arg("--recovered").arg(why).env_remove(LOSE_DEVICE_ENV);
        cmd.spawn().map(|_| ()).map_err(|e| e.to_string())
    }

    /// Shows `pane` (History, Explain): its tab when it is in the layout, else a new tab
    /// beside the GPU timings (layouts saved before it existed have none).
    pub fn show_pane(&mut self, pane: Pane) {
        let tile = match self.tree.tiles.find_pane(&pane) {
            Some(t) => t,
            None => {
                let pane = self.tree.tiles.insert_pane(pane);
                let parent = self
                    .tree
                    .tiles
                    .find_pane(&Pane::Timings)
                    .and_then(|t| self.tree.tiles.parent_of(t))
                    .or(self.tree.root());
                if let Some(parent) = parent
                    && let Some(egui_tiles::Tile::Container(c)) = self.tree.tiles.get_mut(parent)
                {
                    c.add_child(pane);
                }
                pane
            }
        };
        self.tree.make_active(|id, _| id == tile);
    }

    /// Adds a buffer viewer panel next to the first viewer (or on the right).
    pub fn add_viewer(&mut self) {
        let id = self.state.viewers.open.keys().max().copied().unwrap_or(0) + 1;
        let mut v = Viewer::new(ViewerState::default());
        if let Ok(l) = &self.state.lab {
            v.show_buffer(&l.renderer, "gbuffer.motion");
        }
        self.state.viewers.open.insert(id, v);
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
    crate::scene_lights::apply_light_edits(l.renderer.scene_mut(), &s.lights, s.lights_complete);
    let c = &mut l.renderer.clock;
    c.playing = s.playing;
    c.speed = if s.speed > 0.0 { s.speed } else { 1.0 };
    c.loop_s = s.loop_s.max(0.0);
    c.seek(s.time_s);
    l.renderer.reset_history();
}

impl eframe::App for GiLabApp {
    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        let ctx = ui.ctx().clone();
        if self.state.lose_device_at == Some(self.state.frames)
            && let Ok(l) = &self.state.lab
        {
            l.renderer.ctx.device.destroy();
        }
        if self.handle_device_loss() {
            self.device_lost_panel(ui);
            return;
        }
        // A device can be lost in the middle of a frame (a driver reset is not announced):
        // wgpu then panics in calls that cannot fail otherwise (a buffer made with
        // `create_buffer_init`, a mapped range). Such a panic, with the device lost, is the
        // loss itself: the lab saves the session and restarts as above. Any other panic
        // goes on unwinding.
        let frame = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| self.frame_ui(ui, &ctx)));
        if let Err(panic) = frame {
            // A poll delivers a loss the device has not reported yet.
            if let Ok(l) = &self.state.lab {
                let _ = l.renderer.ctx.device.poll(wgpu::PollType::Poll);
            }
            if self.handle_device_loss() {
                self.device_lost_panel(ui);
                return;
            }
            std::panic::resume_unwind(panic);
        }
    }

    fn on_exit(&mut self) {
        if let Err(e) = self.save_session() {
            log::warn!("session not saved: {e}");
        }
    }
}

impl GiLabApp {
    /// What the window shows once the device is lost: the message, nothing that needs the GPU.
    fn device_lost_panel(&self, ui: &mut egui::Ui) {
        let msg = self.state.device_lost.clone().unwrap_or_default();
        egui::CentralPanel::default().show(ui, |ui| {
            ui.centered_and_justified(|ui| ui.colored_label(ERROR, msg));
        });
    }

    /// One frame of the lab: its panels, viewers and renderer.
    fn frame_ui(&mut self, ui: &mut egui::Ui, ctx: &egui::Context) {
        self.state.handle_dropped_files(ctx);
        self.state.shortcuts(ctx);
        if std::mem::take(&mut self.state.requests.new_viewer) {
            self.add_viewer();
        }
        if std::mem::take(&mut self.state.requests.reset_layout) {
            self.tree = session::default_layout();
            for id in viewer_ids(&self.tree) {
                self.state.viewers.open.entry(id).or_insert_with(|| Viewer::new(ViewerState::default()));
            }
        }
        // (Outside `input`: it holds the context's lock.)
        let typing = ctx.egui_wants_keyboard_input();
        self.state.interacting = ctx.input(|i| {
            let flying = [egui::Key::W, egui::Key::A, egui::Key::S, egui::Key::D, egui::Key::Q, egui::Key::E]
                .iter()
                .any(|k| i.key_down(*k));
            i.pointer.any_down() || i.smooth_scroll_delta != egui::Vec2::ZERO || (flying && !typing)
        });
        self.state.frame();
        // The panels set the hovered pixel again while they are drawn.
        self.state.probes.hover = None;
        egui::Panel::top("menu").show(ui, |ui| self.state.menu_bar(ui));
        egui::Panel::bottom("status").show(ui, |ui| self.state.status_bar(ui));
        egui::CentralPanel::default().show(ui, |ui| {
            if let Err(e) = &self.state.lab {
                ui.centered_and_justified(|ui| {
                    ui.colored_label(ERROR, format!("GI Lab cannot render:\n{e}"));
                });
                return;
            }
            self.state.viewers.visible.clear();
            let mut behavior = crate::ui::panes::Behavior { state: &mut self.state, closed_viewers: Vec::new() };
            self.tree.ui(&mut behavior, ui);
            let closed = std::mem::take(&mut behavior.closed_viewers);
            for id in closed {
                if let (Some(mut v), Ok(l)) = (self.state.viewers.open.remove(&id), &self.state.lab) {
                    v.release(&l.render_state);
                }
            }
        });
        self.state.problem_dialog(ctx);
        self.state.help_window(ctx);
        self.state.frames += 1;
        // An edit becomes an undo step once its gesture ends (a drag released, a typed value
        // left): a slider drag is one step.
        let idle = !ctx.input(|i| i.pointer.any_down()) && !ctx.egui_wants_keyboard_input();
        self.state.record_history(idle);
        if std::mem::take(&mut self.state.requests.history) {
            self.show_pane(Pane::History);
        }
        if std::mem::take(&mut self.state.requests.explain) {
            self.show_pane(Pane::Explain);
        }
        self.screenshot_step(ctx);
        self.autosave();
        ctx.request_repaint();
    }
}

/// The `--screenshot` of the window (`crate::ui::capture::save_color_image` writes it).
impl GiLabApp {
    pub(super) fn screenshot_step(&mut self, ctx: &egui::Context) {
        let st = &mut self.state;
        let Some(path) = st.args.screenshot.clone() else { return };
        if !st.capture.screenshot_requested && st.frames >= st.args.screenshot_frames {
            let slot = st.capture.screenshot.clone();
            ctx.request_screenshot(move |img| {
                if let Ok(mut s) = slot.lock() {
                    *s = Some(img);
                }
            });
            st.capture.screenshot_requested = true;
        }
        let taken = st.capture.screenshot.lock().ok().and_then(|mut s| s.take());
        if let Some(img) = taken {
            match crate::ui::capture::save_color_image(&path, &img) {
                Ok(()) => println!("wrote screenshot {}", path.display()),
                Err(e) => eprintln!("gi-lab: {e}"),
            }
            ctx.send_viewport_cmd(egui::ViewportCommand::Close);
        }
    }
}
