//! The menu bar, the status bar, the keyboard shortcuts and their help window.

use gi_render::preset::ExportFormat;

use crate::ui::ERROR;
use crate::ui::state::State;

/// The keyboard shortcuts (Help lists them).
pub const SHORTCUTS: &[(&str, &str)] = &[
    ("Space", "play / pause the animation"),
    ("Period (.)", "step one frame (paused)"),
    ("Ctrl+Z", "undo the last edit"),
    ("Ctrl+Shift+Z / Ctrl+Y", "redo"),
    ("Ctrl+N", "new preset (defaults)"),
    ("Ctrl+O", "open a preset"),
    ("Ctrl+S", "save the preset"),
    ("Ctrl+Shift+S", "save the preset as…"),
    ("Ctrl+E", "export the preset as JSON"),
    ("Ctrl+Shift+O", "open a glTF scene"),
    ("Ctrl+B", "add a buffer viewer"),
    ("F12", "save the viewport as PNG and EXR"),
    ("Home", "reset the camera"),
    ("F", "frame the scene (the view it opens on: inside its largest room, or around it)"),
    ("H", "restart temporal accumulation"),
    ("Escape", "unpin all probes, deselect the light"),
    ("Ctrl (while dragging a light)", "snap the move to the grid, the aim to 15°"),
    ("Drag / WASD QE / scroll", "orbit / fly / move (viewport)"),
    ("Click", "pin a probe (viewport, viewers)"),
    (
        "X / right-click → Explain",
        "explain the pixel under the pointer: where its indirect light comes from (viewport)",
    ),
];

impl State {
    pub(super) fn shortcuts(&mut self, ctx: &egui::Context) {
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
            self.requests.new_viewer = true;
        }
        if pressed(Modifiers::NONE, Key::F12) {
            self.capture_viewport();
        }
        if typing {
            return;
        }
        // Text fields have their own undo: these act only when no field is focused.
        if pressed(ctrl_shift, Key::Z) || pressed(Modifiers::COMMAND, Key::Y) {
            self.redo();
        } else if pressed(Modifiers::COMMAND, Key::Z) {
            self.undo();
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
            l.renderer.camera = gi_render::renderer::default_camera(
                l.renderer.scene(),
                l.renderer.bounds(),
                w as f32 / h.max(1) as f32,
            );
        }
        if pressed(Modifiers::NONE, Key::H) {
            l.renderer.reset_history();
        }
        if pressed(Modifiers::NONE, Key::F) {
            self.frame_scene(gi_render::scene::framing::ViewPreference::Auto);
            return;
        }
        if pressed(Modifiers::NONE, Key::Escape) {
            self.probes.pinned.clear();
            self.probes.history.clear();
            if let Ok(l) = &mut self.lab {
                l.selected_light = None;
            }
        }
    }

    pub(super) fn menu_bar(&mut self, ui: &mut egui::Ui) {
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
                if ui
                    .add_enabled(self.preset.port_kit_job.is_none(), egui::Button::new("Export port kit…"))
                    .on_hover_text("A folder with the frame's passes, bindings and shaders (docs/port-kit.md)")
                    .clicked()
                {
                    self.export_port_kit_dialog();
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
                        self.start_recording(self.capture.record_frames);
                    }
                    ui.add(egui::DragValue::new(&mut self.capture.record_frames).range(1..=100_000).suffix(" frames"));
                });
                ui.separator();
                if ui.button("Quit").clicked() {
                    ctx.send_viewport_cmd(egui::ViewportCommand::Close);
                }
            });
            ui.menu_button("Edit", |ui| {
                let undo = self.history.undo_name().map(|n| format!("Undo {n}"));
                if ui
                    .add_enabled(undo.is_some(), egui::Button::new(undo.unwrap_or_else(|| "Undo".into())).shortcut_text("Ctrl+Z"))
                    .clicked()
                {
                    self.undo();
                }
                let redo = self.history.redo_name().map(|n| format!("Redo {n}"));
                if ui
                    .add_enabled(redo.is_some(), egui::Button::new(redo.unwrap_or_else(|| "Redo".into())).shortcut_text("Ctrl+Shift+Z"))
                    .clicked()
                {
                    self.redo();
                }
                ui.separator();
                if ui.button("History").on_hover_text("every edit of this session; click one to go back to it").clicked() {
                    self.requests.history = true;
                }
            });
            ui.menu_button("View", |ui| {
                if ui.button("Add buffer viewer").clicked() {
                    self.requests.new_viewer = true;
                }
                if ui.button("Reset panel layout").clicked() {
                    self.requests.reset_layout = true;
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
                ui.checkbox(&mut self.overlays.lights, "Lights in the viewport").on_hover_text(
                    "every light over the image (icon, spot cones, directions, ranges); click one to select it, \
                     drag its arrows to move it or its yellow handle to aim it (Ctrl: snap)",
                );
                ui.checkbox(&mut self.overlays.vpls, "VPL overlay (vpl.list)").on_hover_text(
                    "instant radiosity's VPLs as dots over the viewport, coloured by their reflected flux \
                     (the brightest at full colour); reads the list back every frame",
                );
                ui.checkbox(&mut self.overlays.hcb_samples, "HCB samples overlay (Table 1)").on_hover_text(
                    "the hierarchical coherence buffer's samples as white dots, larger for higher levels, \
                     with the count per level, and the covered pixels no sample reached in magenta; \
                     reads the sample list back every frame",
                );
                ui.checkbox(&mut self.overlays.soler_samples, "Soler samples overlay (Fig. 3 right)").on_hover_text(
                    "the screen-space gather's ring samples behind the pixel under the cursor (or the first \
                     pinned probe), one colour per mip level: filled where the sample can light the pixel, \
                     hollow where it cannot (background, facing away, beyond the near field's cut); the \
                     receiver texel of each level outlined; glossy receivers' samples follow their lobe",
                );
                ui.checkbox(&mut self.overlays.gautron_records, "Gautron records overlay").on_hover_text(
                    "the irradiance records as dots at P_k coloured by their irradiance E_k (the brightest \
                     at full colour), each with its influence circle of radius a·R_k; stale records \
                     (waiting to be computed again) outlined in orange; reads the records back every frame",
                );
                ui.checkbox(&mut self.overlays.ddgi_probes, "DDGI probes overlay").on_hover_text(
                    "DDGI's probes as dots at their relocated places (a line from the grid's place when \
                     moved), green while active, red when classified inactive (inside geometry or far from \
                     every surface, 2021 §5.2); click a dot to draw that probe's rays of the frame to their \
                     hits, coloured by the radiance they brought back; reads the probes back every frame",
                );
                ui.horizontal(|ui| {
                    ui.label("render scale");
                    ui.add(egui::Slider::new(&mut self.session.render_scale, super::session::RENDER_SCALE_RANGE).logarithmic(true))
                        .on_hover_text("render resolution relative to the viewport's physical pixels; a new session starts at 1 / the display's scale (one pixel per point)");
                });
                ui.horizontal(|ui| {
                    ui.label("target frame rate");
                    ui.add(egui::DragValue::new(&mut self.session.target_fps).range(0.0..=120.0).speed(0.5).suffix(" fps"))
                        .on_hover_text("while you drag or fly, the render scale is lowered until a frame takes at most 1 / this; it comes back a moment after you stop, so that the temporal passes converge at full scale; 0: off");
                });
                let grid_open = self.grid.is_some();
                if ui
                    .selectable_label(grid_open, "Compare grid")
                    .on_hover_text("the live settings beside presets, frozen settings and the path-traced truth, cell by cell")
                    .clicked()
                {
                    if grid_open {
                        self.stop_grid();
                    } else {
                        self.start_grid();
                    }
                    ui.close();
                }
                ui.menu_button("A/B compare", |ui| {
                    if ui.button("with the exact-VPL reference").clicked() {
                        self.start_ab(crate::ui::ab::AbSource::Reference);
                    }
                    if ui.button("with the current settings (frozen)").clicked() {
                        self.start_ab(crate::ui::ab::AbSource::Frozen);
                    }
                    if ui.button("with a preset file…").clicked()
                        && let Some(p) = rfd::FileDialog::new()
                            .add_filter("GI Lab preset", &["ron"])
                            .set_directory(&self.args.presets_dir)
                            .pick_file()
                    {
                        self.start_ab(crate::ui::ab::AbSource::Preset(p));
                    }
                    if ui.add_enabled(self.ab.is_some(), egui::Button::new("Stop")).clicked() {
                        self.stop_ab();
                    }
                });
                if let Ok(l) = &mut self.lab
                    && ui.button("Reset camera").clicked()
                {
                    let (w, h) = l.renderer.size();
                    l.renderer.camera = gi_render::renderer::default_camera(
                        l.renderer.scene(),
                        l.renderer.bounds(),
                        w as f32 / h.max(1) as f32,
                    );
                }
                use gi_render::scene::framing::ViewPreference;
                if ui
                    .button("Frame scene (F)")
                    .on_hover_text("the view the scene opens on, by the framing rule")
                    .clicked()
                {
                    self.frame_scene(ViewPreference::Auto);
                }
                if ui.button("View from inside").on_hover_text("stand in the largest room, at eye height").clicked() {
                    self.frame_scene(ViewPreference::Inside);
                }
                if ui
                    .button("View from outside")
                    .on_hover_text("a raised three-quarter view fitted to the geometry")
                    .clicked()
                {
                    self.frame_scene(ViewPreference::Outside);
                }
            });
            ui.menu_button("Scene", |ui| {
                if ui.button("Open glTF…").clicked() {
                    self.open_scene_dialog();
                }
                ui.menu_button("Recent scenes", |ui| {
                    for p in self.session.recent_scenes.clone() {
                        if ui.button(p.display().to_string()).clicked() {
                            let scale = self.lab.as_ref().map(|l| l.unit_scale).unwrap_or(0.0);
                            if let Err(e) = self.open_scene(Some(p.clone()), scale) {
                                self.set_status(format!("scene not opened: {e}"));
                            }
                        }
                    }
                });
                if ui.button("Default scene").clicked()
                    && let Err(e) = self.open_scene(None, 0.0)
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
                    self.requests.help = true;
                }
                ui.label(format!("GI Lab {}", env!("CARGO_PKG_VERSION")));
            });
        });
    }

    pub(super) fn status_bar(&mut self, ui: &mut egui::Ui) {
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
                if self.adaptive.factor < 1.0 {
                    ui.colored_label(egui::Color32::from_rgb(255, 200, 80), format!("× {:.2} while dragging", self.adaptive.factor))
                        .on_hover_text(format!(
                            "the render scale is lowered to keep {} fps while you drag (View > target frame rate); the full scale comes back when you stop",
                            self.session.target_fps
                        ));
                }
                ui.separator();
                ui.label(format!("frame {:.1} ms · GPU {:.2} ms ({:?})", l.frame_ms, gpu, l.renderer.timing_source()));
                ui.separator();
                let unsaved = l.settings != self.preset.baseline;
                let label =
                    format!("preset: {}{}", self.preset_label(), if unsaved { " (unsaved changes)" } else { "" });
                if unsaved {
                    ui.colored_label(crate::ui::settings_ui::CHANGED, label);
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
                if let Some(r) = &self.capture.recording {
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

    pub(super) fn help_window(&mut self, ctx: &egui::Context) {
        let mut open = self.requests.help;
        egui::Window::new("Keyboard shortcuts").open(&mut open).collapsible(false).show(ctx, |ui| {
            egui::Grid::new("shortcuts").striped(true).show(ui, |ui| {
                for (k, what) in SHORTCUTS {
                    ui.monospace(*k);
                    ui.label(*what);
                    ui.end_row();
                }
            });
        });
        self.requests.help = open;
    }
}
