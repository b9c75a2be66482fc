//! Presets in the window: open, save, revert, export and import, and the dialog of a preset
//! load with problems.

use std::path::{Path, PathBuf};

use gi_render::LabSettings;
use gi_render::preset::{Export, ExportFormat, Loaded, Provenance};

use crate::ui::session::Session;
use crate::ui::state::State;

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
    /// A port kit being written in the background (File → Export port kit…): its folder and
    /// the message it ends with.
    pub port_kit_job: Option<(PathBuf, std::sync::mpsc::Receiver<Result<String, String>>)>,
}

impl State {
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
        let old = self.preset.path.replace(path.to_path_buf());
        self.history.saved(old.as_deref(), path, &settings);
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
        let r = &l.renderer;
        let view = gi_render::export::ExportView::of_scene(
            &l.scene_name,
            r.scene(),
            r.bounds(),
            r.camera,
            r.size(),
            &l.settings,
        );
        Some(Export::new(l.settings.clone(), Provenance::now(&view)))
    }

    pub fn export_to(&mut self, path: &Path, format: ExportFormat) -> Result<(), String> {
        let e = self.export().ok_or("no renderer")?;
        gi_render::files::write_atomic(path, &e.to_text(format)).map_err(|e| format!("{}: {e}", path.display()))?;
        self.set_status(format!("exported {}", path.display()));
        Ok(())
    }

    /// File → Export port kit…: the kit of the live settings, scene and camera at the render
    /// size, written by a thread with its own device so that the window does not wait
    /// (docs/port-kit.md). A folder that exists is refused.
    pub fn export_port_kit_to(&mut self, dir: PathBuf) -> Result<(), String> {
        self.export_port_kit_with(dir, true)
    }

    /// [`Self::export_port_kit_to`], with or without the sizes' expressions (their probe
    /// captures take most of a kit's time on a software GPU; a test of the window's wiring
    /// leaves them out).
    pub fn export_port_kit_with(&mut self, dir: PathBuf, expressions: bool) -> Result<(), String> {
        use gi_render::export::port_kit::{self, KitRequest};
        if self.preset.port_kit_job.is_some() {
            return Err("a port kit is already being written".into());
        }
        if dir.exists() {
            return Err(format!("{} exists: choose a new folder for the kit", dir.display()));
        }
        let l = self.lab.as_ref().map_err(|e| e.clone())?;
        let r = &l.renderer;
        let (scene, settings, size, camera) = (r.scene().clone(), l.settings.clone(), r.size(), r.camera);
        let (scene_name, preset) = (l.scene_name.clone(), self.preset_label().trim_end_matches(".ron").to_string());
        let (tx, rx) = std::sync::mpsc::channel();
        let target = dir.clone();
        std::thread::Builder::new()
            .name("port-kit".into())
            .spawn(move || {
                let result = (|| {
                    let ctx = gi_render::GpuContext::headless().map_err(|e| e.to_string())?;
                    let req = KitRequest {
                        preset: &preset,
                        settings,
                        scene,
                        scene_name: &scene_name,
                        size,
                        frames: 4,
                        goldens: true,
                        camera: Some(camera),
                        expressions,
                        settings_probed: None,
                    };
                    let kit = port_kit::build(ctx, req)?;
                    port_kit::write(&kit, &target, false)?;
                    Ok(format!(
                        "port kit written to {}: {} passes, {} resources",
                        target.display(),
                        kit.manifest.passes.len(),
                        kit.manifest.resources.len()
                    ))
                })();
                let _ = tx.send(result);
            })
            .map_err(|e| format!("cannot start the port kit's thread: {e}"))?;
        self.preset.port_kit_job = Some((dir.clone(), rx));
        self.set_status(format!("writing the port kit to {} …", dir.display()));
        Ok(())
    }

    /// Says how the background port kit ended, once it has.
    pub fn poll_port_kit(&mut self) {
        let Some((dir, rx)) = &self.preset.port_kit_job else { return };
        let message = match rx.try_recv() {
            Ok(Ok(m)) => m,
            Ok(Err(e)) => format!("port kit {} failed: {e}", dir.display()),
            Err(std::sync::mpsc::TryRecvError::Empty) => return,
            Err(std::sync::mpsc::TryRecvError::Disconnected) => {
                format!("port kit {}: its thread stopped", dir.display())
            }
        };
        self.preset.port_kit_job = None;
        self.set_status(message);
    }

    pub fn export_port_kit_dialog(&mut self) {
        let stem = self.preset_label().trim_end_matches(".ron").to_string();
        if let Some(p) = rfd::FileDialog::new()
            .set_file_name(format!("{stem}-port-kit"))
            .set_title("Export port kit (a new folder)")
            .save_file()
            && let Err(e) = self.export_port_kit_to(p)
        {
            self.set_status(format!("port kit not written: {e}"));
        }
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

    /// The dialog of a preset load with problems: every problem listed, the fixes named;
    /// nothing changes unless the user accepts.
    pub(in crate::ui) fn problem_dialog(&mut self, ctx: &egui::Context) {
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
}
