//! The window's state besides the tile tree, and its frame loop: rendering, probes, viewers,
//! shader hot reload, A/B, scene opening and dropped files.

use std::collections::{BTreeMap, VecDeque};
use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use std::time::Instant;

use gi_render::buffers::ProbeValue;
use gi_render::passes::view::ViewPipeline;
use gi_render::readback::{Readback, Readout};
use gi_render::timing::PassTiming;

use crate::args::AppArgs;
use crate::ui::capture::Recording;
use crate::ui::lab::Lab;
use crate::ui::session::{Bookmark, PinnedProbe, Session};
use crate::ui::state::presets::PresetState;
use crate::ui::viewer::{Viewer, ViewerState};

pub mod capture;
pub mod history;
pub mod presets;

/// Everything but the tile tree (so that the tree's behaviour can borrow it).
pub struct State {
    pub args: AppArgs,
    pub config_dir: Option<PathBuf>,
    pub lab: Result<Lab, String>,
    pub session: Session,
    pub viewers: BTreeMap<u32, Viewer>,
    pub(super) view_pipeline: Option<Arc<ViewPipeline>>,
    /// A viewer used by the viewport to show a hovered pass's output.
    pub(super) pass_view: Option<Viewer>,
    pub preset: PresetState,
    /// The hovered frame pixel (viewport or a viewer) and every buffer's value there.
    pub hover: Option<(u32, u32)>,
    pub hover_values: Vec<ProbeValue>,
    pub pinned: Vec<PinnedProbe>,
    /// Per pinned probe: the chosen buffer's value over the last frames.
    pub probe_history: Vec<VecDeque<[f32; 4]>>,
    /// The frame of the last probe values taken in (they arrive without waiting, late).
    pub probe_frame: u64,
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
    /// View → Soler samples overlay: the ring samples of the hovered pixel per level (004
    /// Fig. 3 right).
    pub show_soler_samples: bool,
    /// View → Gautron records overlay: the irradiance records as dots coloured by E_k with
    /// their influence circles a·R_k (003, "From Octree to Splatting").
    pub show_gautron_records: bool,
    /// View → Lights in the viewport: every light drawn over the image, the selected one
    /// with its move and aim handles (issue #39 point 2).
    pub show_lights: bool,
    /// The A/B comparison, when one runs.
    pub ab: Option<crate::ui::ab::Ab>,
    /// The comparison grid, when open (View → Compare grid; issue #40 point 1).
    pub grid: Option<crate::ui::grid::Grid>,
    pub hot: crate::ui::hot_reload::HotReload,
    pub request_new_viewer: bool,
    pub request_reset_layout: bool,
    pub(super) screenshot: Arc<Mutex<Option<Arc<egui::ColorImage>>>>,
    pub(super) screenshot_requested: bool,
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
    /// Edit → History asked for the History pane (the app owns the layout).
    pub show_history_request: bool,
    /// The pinned pixel explained (issue #42), when one is.
    pub explain: Option<crate::ui::explain::ExplainView>,
    /// The pixel under the pointer when the viewport's context menu opened.
    pub context_pixel: Option<(u32, u32)>,
    /// An explain pin asked for the Explain pane.
    pub show_explain_request: bool,
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
            self.pass_view = None;
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
    pub(super) fn frame(&mut self) {
        self.hot_reload();
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
            self.timing_history.push_back(l.renderer.timings().to_vec());
            while self.timing_history.len() > self.session.history_frames.max(2) {
                self.timing_history.pop_front();
            }
        }
        // Probes: the hovered pixel and every pinned one, in one readback.
        let mut points: Vec<(u32, u32)> = self.hover.into_iter().collect();
        points.extend(self.pinned.iter().map(|p| p.pixel));
        points.truncate(gi_render::buffers::PROBE_MAX_POINTS);
        let (fw, fh) = l.renderer.size();
        let points: Vec<(u32, u32)> = points.into_iter().map(|(x, y)| (x.min(fw - 1), y.min(fh - 1))).collect();
        // Read without waiting (issue #38): the values arrive a frame or two late; the tag says
        // which points they are, so that a pin added or removed meanwhile is not misread.
        let tag = |hover: bool| probe_tag(hover, self.pinned.iter().map(|p| p.pixel));
        let arrived = if points.is_empty() {
            l.renderer.read_latest("probe")
        } else {
            l.renderer.read_later("probe", Readback::Probe(points), tag(self.hover.is_some()))
        };
        match arrived.as_deref().map(|a| (a.frame, a.tag, &a.data)) {
            Some((frame, t, Ok(Readout::Probe(values)))) if frame != self.probe_frame => {
                self.probe_frame = frame;
                let had_hover = t == tag(true);
                let pins_same = had_hover || t == tag(false);
                let mut values = values.iter();
                self.hover_values = match (had_hover, self.hover.is_some()) {
                    (true, true) => values.next().cloned().unwrap_or_default(),
                    (true, false) => {
                        values.next();
                        Vec::new()
                    }
                    _ => Vec::new(),
                };
                if pins_same {
                    self.probe_history.resize_with(self.pinned.len(), VecDeque::new);
                    for ((p, h), vals) in self.pinned.iter().zip(&mut self.probe_history).zip(values) {
                        let v = vals.iter().find(|v| v.name == p.buffer).map(|v| v.value).unwrap_or([f32::NAN; 4]);
                        h.push_back(v);
                        while h.len() > self.session.history_frames.max(2) {
                            h.pop_front();
                        }
                    }
                }
            }
            Some((frame, _, Err(e))) if frame != self.probe_frame => {
                self.probe_frame = frame;
                self.status = Some((format!("probe: {e}"), Instant::now()));
            }
            _ => {}
        }
        if self.hover.is_none() {
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
            && let Some(buffer) = gi_render::renderer::scope_output(pass)
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
        if self.pinned.len() + 1 >= gi_render::buffers::PROBE_MAX_POINTS {
            self.set_status("too many pinned probes");
            return;
        }
        let buffer = self.viewers.values().next().map(|v| v.state.buffer.clone()).unwrap_or_else(|| "final.hdr".into());
        self.pinned.push(PinnedProbe { pixel, buffer, channel: 0 });
        self.probe_history.push(VecDeque::new());
    }

    /// Explains `pixel` (frame pixels): pins it and shows the Explain pane.
    pub fn explain_pixel(&mut self, pixel: (u32, u32)) {
        let keep = self.explain.as_ref().map(|v| (v.show_rejected, v.overlay));
        let mut v = crate::ui::explain::ExplainView::new(pixel);
        if let Some((rejected, overlay)) = keep {
            (v.show_rejected, v.overlay) = (rejected, overlay);
        }
        self.explain = Some(v);
        self.show_explain_request = true;
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

/// Which points a probe read-back was asked for: whether the hovered pixel came first, and
/// the pinned pixels.
fn probe_tag(hover: bool, pins: impl Iterator<Item = (u32, u32)>) -> u64 {
    use std::hash::{Hash, Hasher};
    let mut h = std::collections::hash_map::DefaultHasher::new();
    hover.hash(&mut h);
    for p in pins {
        p.hash(&mut h);
    }
    h.finish()
}
