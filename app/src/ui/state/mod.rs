//! The window's state besides the tile tree, and its frame loop: rendering, probes, viewers,
//! shader hot reload, A/B, scene opening and dropped files.

use std::path::PathBuf;
use std::time::Instant;

use gi_render::passes::view::ViewPipeline;

use crate::args::AppArgs;
use crate::ui::lab::Lab;
use crate::ui::session::{Bookmark, Session};
use crate::ui::state::presets::PresetState;
use crate::ui::viewer::{Viewer, ViewerState};

pub mod capture;
pub mod history;
pub mod parts;
pub mod presets;

pub use parts::{Captures, Overlays, Probes, Requests, Timings, Viewers};

/// Everything but the tile tree (so that the tree's behaviour can borrow it).
pub struct State {
    pub args: AppArgs,
    pub config_dir: Option<PathBuf>,
    pub lab: Result<Lab, String>,
    pub session: Session,
    /// The buffer viewers.
    pub viewers: Viewers,
    /// The hovered and pinned pixel probes.
    pub probes: Probes,
    /// The timings pane's history.
    pub timings: Timings,
    /// What the View menu draws over the viewport.
    pub overlays: Overlays,
    /// What a menu or pane asked of the app (the layout is the app's).
    pub requests: Requests,
    /// Recordings and the window's screenshot.
    pub capture: Captures,
    pub preset: PresetState,
    /// Viewport size in physical pixels (the render size is this × the render scale).
    pub viewport_px: (u32, u32),
    /// Where the viewport was drawn last frame (points).
    pub viewport_rect: egui::Rect,
    /// Render at exactly this size whatever the viewport's (tests and scripted captures).
    pub render_size_override: Option<(u32, u32)>,
    pub status: Option<(String, Instant)>,
    pub frames: u64,
    pub bookmark_name: String,
    /// Path typed in the scene panel (when no file dialog is available).
    pub scene_path_text: String,
    /// The A/B comparison, when one runs.
    pub ab: Option<crate::ui::ab::Ab>,
    /// The comparison grid, when open (View → Compare grid; issue #40 point 1).
    pub grid: Option<crate::ui::grid::Grid>,
    pub hot: crate::ui::hot_reload::HotReload,
    pub(super) last_autosave: Instant,
    /// What the lab said when its GPU device was lost (it saved the session and restarts).
    pub device_lost: Option<String>,
    /// `GI_LAB_TEST_LOSE_DEVICE_AT=K`: the window destroys its device at frame K, as a driver
    /// reset would (for the test of the real restart, `app/tests/app_window.rs`).
    pub(super) lose_device_at: Option<u64>,
    pub(super) last_saved_session: String,
    /// The render scale's factor while the user drags (issue #39 point 3).
    pub adaptive: crate::ui::adaptive::AdaptiveScale,
    /// A gesture is under way this frame (a button held, a scroll, flying keys).
    pub interacting: bool,
    /// The settings panel's search text (issue #39 point 4).
    pub settings_search: String,
    /// Undo and redo (issue #39 point 1).
    pub history: crate::ui::state::history::History,
    /// The pinned pixel explained (issue #42), when one is.
    pub explain: Option<crate::ui::explain::ExplainView>,
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
            self.stop_grid();
            self.session.lights.clear();
            self.session.lights_complete = false;
            if let Some(p) = &path {
                Session::remember(&mut self.session.recent_scenes, p);
            }
            self.viewers.pass_view = None;
            // What the lab chose for the scene: its light (issue #18), the view and the unit
            // (issue #37).
            if let Some(note) = self.lab.as_ref().ok().and_then(|l| scene_note(l.renderer.scene())) {
                self.set_status(note);
            }
        }
        r
    }

    /// Moves the camera to the view the framing rule chooses (`Auto`: the scene's camera or
    /// the rule's choice; or inside / outside) and says which and why.
    pub fn frame_scene(&mut self, prefer: gi_render::scene::framing::ViewPreference) {
        let Ok(l) = &mut self.lab else { return };
        let (w, h) = l.renderer.size();
        let aspect = w as f32 / h.max(1) as f32;
        let view = match prefer {
            gi_render::scene::framing::ViewPreference::Auto => {
                gi_render::renderer::scene_view(l.renderer.scene(), l.renderer.bounds(), aspect)
            }
            p => gi_render::scene::framing::choose_view(l.renderer.scene(), aspect, p),
        };
        l.renderer.camera = view.camera;
        self.set_status(format!("view: {}", view.reason));
    }

    /// Asks for a glTF file with the platform's file dialog and opens it.
    pub fn open_scene_dialog(&mut self) {
        let picked =
            rfd::FileDialog::new().add_filter("glTF 2.0", &["gltf", "glb"]).set_title("Open scene").pick_file();
        if let Some(p) = picked {
            let scale = self.lab.as_ref().map(|l| l.unit_scale).unwrap_or(0.0);
            if let Err(e) = self.open_scene(Some(p), scale) {
                self.set_status(format!("scene not opened: {e}"));
            }
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
                    self.viewers.pipeline = None;
                    for v in self.viewers.open.values_mut() {
                        v.reset_gpu();
                    }
                    self.viewers.pass_view = None;
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
    pub(super) fn frame(&mut self) {
        self.hot_reload();
        self.poll_port_kit();
        let last_ms = self.lab.as_ref().map(|l| l.frame_ms).unwrap_or(0.0);
        let factor = if self.args.adaptive_scale && self.render_size_override.is_none() {
            self.adaptive.update(self.interacting, last_ms, self.session.target_fps, Instant::now())
        } else {
            1.0
        };
        let range = super::session::RENDER_SCALE_RANGE;
        let scale = self.session.render_scale.clamp(*range.start(), *range.end()) * factor;
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
            crate::ui::explain::before_frame(&mut self.explain, &mut l.renderer);
            let started = Instant::now();
            l.renderer.render_frame();
            crate::ui::explain::after_frame(&mut self.explain, &l.renderer);
            if let Some(g) = &mut self.grid {
                // The cells render in turn in what the frame budget leaves after the live frame.
                let fps = self.session.target_fps;
                let budget = if fps > 0.0 {
                    std::time::Duration::from_secs_f32(1.0 / fps).saturating_sub(started.elapsed())
                } else {
                    std::time::Duration::MAX
                };
                g.render(&l.renderer, &l.settings, budget);
            }
            let now = Instant::now();
            l.frame_ms = (now - l.last_frame).as_secs_f32() * 1e3;
            l.last_frame = now;
            self.timings.push(l.renderer.timings().to_vec(), self.session.history_frames);
        }
        // Probes: the hovered pixel and every pinned one, in one read-back.
        if let Some(e) = self.probes.update(&mut l.renderer, self.session.history_frames) {
            self.status = Some((e, Instant::now()));
        }
        let pipeline = self.viewers.pipeline.get_or_insert_with(|| ViewPipeline::new(&l.renderer.ctx)).clone();
        for id in &self.viewers.visible {
            if let Some(v) = self.viewers.open.get_mut(id) {
                v.update(&l.renderer, &pipeline, &l.render_state);
            }
        }
        // The viewport shows the hovered pass's output instead of the final image.
        if let Some(pass) = &self.timings.hovered_pass
            && let Some(buffer) = gi_render::renderer::scope_output(pass)
        {
            let v = self.viewers.pass_view.get_or_insert_with(|| Viewer::new(ViewerState::default()));
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
                    v.state.range_mode = crate::ui::viewer::RangeMode::Percentile;
                }
            }
            v.update(&l.renderer, &pipeline, &l.render_state);
        }
        self.record_step();
    }

    /// The viewport's texture this frame: the hovered pass's output or the final image.
    pub fn viewport_texture(&mut self) -> Option<(egui::TextureId, (u32, u32), Option<String>)> {
        let l = self.lab.as_mut().ok()?;
        if let (Some(pass), Some(v)) = (&self.timings.hovered_pass, &self.viewers.pass_view)
            && let Some(out) = v.output_texture()
        {
            let size = (out.width(), out.height());
            let id = l.show_texture(&out, false);
            return Some((id, size, Some(format!("{pass}: {}", v.state.buffer))));
        }
        let out = l.renderer.final_ldr().clone();
        let force = l.texture.is_some_and(|(_, s)| s == (0, 0))
            || self.viewers.pass_view.is_some() && self.timings.hovered_pass.is_none();
        if self.timings.hovered_pass.is_none() {
            self.viewers.pass_view = None;
        }
        let id = l.show_texture(&out, force);
        Some((id, (out.width(), out.height()), None))
    }

    /// Starts an A/B comparison of the live settings with `source`.
    pub fn start_ab(&mut self, source: crate::ui::ab::AbSource) {
        self.stop_ab();
        self.stop_grid();
        let Ok(l) = &self.lab else { return };
        match crate::ui::ab::Ab::start(&l.renderer, &l.settings, source) {
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
        let buffer =
            self.viewers.open.values().next().map(|v| v.state.buffer.clone()).unwrap_or_else(|| "final.hdr".into());
        if let Err(e) = self.probes.pin(pixel, buffer) {
            self.set_status(e);
        }
    }

    /// Explains `pixel` (frame pixels): pins it and shows the Explain pane.
    pub fn explain_pixel(&mut self, pixel: (u32, u32)) {
        let keep = self.explain.as_ref().map(|v| (v.show_rejected, v.overlay));
        let mut v = crate::ui::explain::ExplainView::new(pixel);
        if let Some((rejected, overlay)) = keep {
            (v.show_rejected, v.overlay) = (rejected, overlay);
        }
        self.explain = Some(v);
        self.requests.explain = true;
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

    pub(super) fn handle_dropped_files(&mut self, ctx: &egui::Context) {
        let dropped: Vec<PathBuf> = ctx.input(|i| {
            i.raw.dropped_files.iter().map(|f| f.path().to_path_buf()).filter(|p| !p.as_os_str().is_empty()).collect()
        });
        for p in dropped {
            let ext = p.extension().map(|e| e.to_string_lossy().to_ascii_lowercase()).unwrap_or_default();
            match ext.as_str() {
                "gltf" | "glb" => {
                    let scale = self.lab.as_ref().map(|l| l.unit_scale).unwrap_or(0.0);
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
}

/// The status line of a newly opened scene: the light the lab added (or the emitters that
/// light it), the view it opens on and why, and the unit read from its extent.
pub fn scene_note(scene: &gi_render::scene::Scene) -> Option<String> {
    let mut parts: Vec<String> = Vec::new();
    if let Some(n) = scene.default_light_note() {
        parts.push(n.to_string());
    }
    if let Some(v) = &scene.view {
        parts.push(format!("view: {}", v.reason));
    }
    if let Some((_, u)) = &scene.units {
        parts.push(u.clone());
    }
    (!parts.is_empty()).then(|| parts.join(" · "))
}
