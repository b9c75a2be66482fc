//! The presets pane: the preset browser, save as, and the diff against another preset.

use std::path::PathBuf;

use gi_render::LabSettings;

use crate::ui::ERROR;
use crate::ui::state::State;

/// The folder of `presets_dir`'s .ron files, sorted.
pub(super) fn preset_files(dir: &std::path::Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .map(|rd| {
            rd.filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|x| x == "ron"))
                // Engine exports written next to the presets are not presets.
                .filter(|p| !p.to_string_lossy().ends_with(".export.ron"))
                .collect()
        })
        .unwrap_or_default();
    v.sort();
    v
}

pub(super) fn presets_ui(st: &mut State, ui: &mut egui::Ui) {
    ui.heading("Preset");
    let unsaved = st.unsaved();
    ui.horizontal(|ui| {
        ui.label(match &st.preset.path {
            Some(p) => p.display().to_string(),
            None => "new preset (not saved yet)".into(),
        });
        if unsaved {
            ui.colored_label(crate::ui::settings_ui::CHANGED, "unsaved changes");
        }
    });
    ui.horizontal_wrapped(|ui| {
        if ui.button("New").clicked() {
            st.new_preset();
        }
        if ui.button("Open…").clicked() {
            st.open_preset_dialog();
        }
        if ui.button("Save").clicked() {
            st.save_preset();
        }
        if ui.button("Save As…").clicked() {
            st.save_preset_as_dialog();
        }
        if ui.add_enabled(unsaved, egui::Button::new("Revert")).clicked() {
            st.revert_preset();
        }
    });
    let name = st.preset.save_as_name.trim().trim_end_matches(".ron").to_string();
    ui.horizontal(|ui| {
        ui.add(egui::TextEdit::singleline(&mut st.preset.save_as_name).hint_text("name").desired_width(160.0))
            .accessible_name("preset name");
        let valid = !name.is_empty() && !name.contains(['/', '\\']) && name != "." && name != "..";
        if ui.add_enabled(valid, egui::Button::new(format!("Save to {}/", st.args.presets_dir.display()))).clicked() {
            let path = st.args.presets_dir.join(format!("{name}.ron"));
            if let Err(e) = st.save_preset_to(&path) {
                st.set_status(format!("save failed: {e}"));
            }
        }
    });
    ui.horizontal(|ui| {
        if ui.button("Export JSON…").clicked() {
            st.export_dialog(gi_render::preset::ExportFormat::Json);
        }
        if ui.button("Export RON…").clicked() {
            st.export_dialog(gi_render::preset::ExportFormat::Ron);
        }
    });
    // Without a file dialog (or to skip it): the export lands next to the presets.
    let stem = if name.is_empty() { st.preset_label().trim_end_matches(".ron").to_string() } else { name.clone() };
    ui.horizontal(|ui| {
        for format in [gi_render::preset::ExportFormat::Json, gi_render::preset::ExportFormat::Ron] {
            let file = st.args.presets_dir.join(format!("{stem}.export.{}", format.extension()));
            if ui.button(format!("Export to {}", file.display())).clicked()
                && let Err(e) = st.export_to(&file, format)
            {
                st.set_status(format!("export failed: {e}"));
            }
        }
    });
    ui.separator();
    ui.heading(format!("Browser: {}", st.args.presets_dir.display()));
    let files = preset_files(&st.args.presets_dir);
    if files.is_empty() {
        ui.weak("no .ron files here");
    }
    let mut open = None;
    for f in &files {
        let name = f.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        let current = st.preset.path.as_ref() == Some(f);
        ui.horizontal(|ui| {
            if ui.selectable_label(current, &name).on_hover_text("open this preset").clicked() {
                open = Some(f.clone());
            }
            if ui.small_button("diff").on_hover_text("compare the live settings with this preset").clicked() {
                st.preset.diff_with = Some(f.clone());
            }
        });
    }
    if let Some(f) = open {
        st.open_preset(&f);
    }
    ui.separator();
    diff_ui(st, ui);
}

fn diff_ui(st: &mut State, ui: &mut egui::Ui) {
    let Ok(l) = &st.lab else { return };
    ui.horizontal(|ui| {
        ui.heading("Differences");
        ui.label("against");
        let label = st.preset.diff_with.as_ref().map(|p| p.display().to_string()).unwrap_or_else(|| "defaults".into());
        egui::ComboBox::from_id_salt("diff_with").selected_text(label).show_ui(ui, |ui| {
            ui.selectable_value(&mut st.preset.diff_with, None, "defaults");
            for f in preset_files(&st.args.presets_dir) {
                let name = f.display().to_string();
                ui.selectable_value(&mut st.preset.diff_with, Some(f), name);
            }
        });
    });
    // The compared file is read again only when it changed on disk (not every frame).
    let other = match &st.preset.diff_with {
        None => Ok(LabSettings::default()),
        Some(p) => {
            let stamp = std::fs::metadata(p).and_then(|m| m.modified()).ok();
            match &st.preset.diff_cache {
                Some((cp, cs, cached)) if cp == p && *cs == stamp => cached.clone(),
                _ => {
                    let loaded = gi_render::preset::load_file(p).map(|l| l.settings).map_err(|e| e.to_string());
                    st.preset.diff_cache = Some((p.clone(), stamp, loaded.clone()));
                    loaded
                }
            }
        }
    };
    let other = match other {
        Ok(o) => o,
        Err(e) => {
            ui.colored_label(ERROR, e);
            return;
        }
    };
    let rows: Vec<(String, String, String)> = LabSettings::all_paths()
        .into_iter()
        .filter_map(|p| {
            let (a, b) = (l.settings.get(&p)?, other.get(&p)?);
            (a != b).then(|| (p, a.to_string(), b.to_string()))
        })
        .collect();
    if rows.is_empty() {
        ui.weak("no differences");
        return;
    }
    egui::Grid::new("diff").striped(true).num_columns(3).show(ui, |ui| {
        ui.strong("setting");
        ui.strong("live");
        ui.strong("other");
        ui.end_row();
        for (p, a, b) in rows {
            ui.monospace(p);
            ui.colored_label(crate::ui::settings_ui::CHANGED, a);
            ui.label(b);
            ui.end_row();
        }
    });
}
