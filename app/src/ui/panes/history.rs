//! The History pane (issue #39 point 1): every edit of the session, oldest first, the
//! current one marked; a click goes back (or forward) to any step (`crate::ui::state::history`).

use crate::ui::state::history::History;

/// The pane reads the undo steps only; the step clicked (undo, redo or a row) is returned for
/// the state to go to.
pub(super) fn history_ui(history: &History, ui: &mut egui::Ui) -> Option<usize> {
    let (steps, cursor) = history.steps();
    if steps.is_empty() {
        ui.weak("no edits yet");
        return None;
    }
    let mut jump = None;
    ui.horizontal(|ui| {
        if ui.add_enabled(cursor > 0, egui::Button::new("undo")).on_hover_text("Ctrl+Z").clicked() {
            jump = Some(cursor - 1);
        }
        if ui
            .add_enabled(cursor + 1 < steps.len(), egui::Button::new("redo"))
            .on_hover_text("Ctrl+Shift+Z or Ctrl+Y")
            .clicked()
        {
            jump = Some(cursor + 1);
        }
        ui.weak(format!(
            "{} of {} steps (the last {} are kept)",
            cursor,
            steps.len() - 1,
            crate::ui::state::history::MAX_STEPS
        ));
    });
    if history.dropped() > 0 {
        ui.weak(format!("{} older steps were dropped", history.dropped()));
    }
    ui.separator();
    for (k, name) in steps.iter().enumerate() {
        let label = format!("{k:>3}  {name}");
        let text = if k > cursor { egui::RichText::new(label).weak() } else { egui::RichText::new(label) };
        let row = ui.selectable_label(k == cursor, text).on_hover_text(if k == cursor {
            "the current state".to_string()
        } else if k < cursor {
            "go back to the state after this edit".to_string()
        } else {
            "redo up to this edit".to_string()
        });
        if row.clicked() {
            jump = Some(k);
        }
    }
    jump
}
