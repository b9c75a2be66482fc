//! The GPU timings pane: per-pass times and their history.

use egui_plot::{Legend, Line, Plot, PlotPoints};

use crate::ui::lab::Lab;
use crate::ui::state::Timings;

/// The pane reads the lab's renderer and its own part of the state, nothing else.
pub(super) fn timings_ui(timings: &mut Timings, l: &Lab, ui: &mut egui::Ui) {
    let mut hovered = None;
    ui.horizontal_top(|ui| {
        ui.vertical(|ui| {
            ui.set_width(230.0);
            if l.renderer.timing_source() == gi_render::timing::TimingSource::GpuTimestamps
                && !gi_render::timing::GpuTimer::timestamps_reliable(&l.renderer.ctx)
            {
                ui.colored_label(ui.visuals().warn_fg_color, "software device: its timestamps land in later passes, so per-pass times are unreliable here; `gi-lab bench` times each pass by the wall clock")
                    .on_hover_text("lavapipe writes a timestamp where the pass is recorded, not where its work runs");
            }
            if l.renderer.timing_source() == gi_render::timing::TimingSource::Off {
                ui.colored_label(ui.visuals().warn_fg_color, "this device has no GPU timestamps: the window does not time passes, because timing without them means waiting for the GPU after every pass; `gi-lab bench` times each pass by the wall clock");
            }
            steps_ui(ui, &l.renderer);
            let kept = l.renderer.kept_passes();
            if !kept.is_empty() {
                let text = egui::RichText::new(format!("kept from an earlier frame: {}", kept.join(", "))).small();
                ui.add(egui::Label::new(text).wrap()).on_hover_text(
                    "nothing these passes read (camera, objects, lights, settings) changed since they last ran, so their outputs hold that result (issue #53; docs/architecture.md, 'Passes kept while nothing moves')",
                );
            }
            egui::Grid::new("timings").num_columns(2).striped(true).show(ui, |ui| {
                let mut total = 0.0;
                for t in l.renderer.timings() {
                    let r = ui.label(&t.name) | ui.monospace(format!("{:8.3} ms", t.ms));
                    if r.hovered() {
                        hovered = Some(t.name.clone());
                    }
                    ui.end_row();
                    total += t.ms;
                }
                ui.strong("total");
                ui.monospace(format!("{total:8.3} ms"));
                ui.end_row();
            });
            ui.small("hover a pass to see its output in the viewport");
        });
        let names: Vec<String> = l.renderer.timings().iter().map(|t| t.name.clone()).collect();
        Plot::new("timing_history").legend(Legend::default()).y_axis_label("ms").x_axis_label("frame").show(
            ui,
            |plot| {
                for name in names {
                    let points: PlotPoints = timings
                        .history
                        .iter()
                        .enumerate()
                        .filter_map(|(i, ts)| ts.iter().find(|t| t.name == name).map(|t| [i as f64, t.ms]))
                        .collect();
                    plot.line(Line::new(name.clone(), points));
                }
            },
        );
    });
    timings.hovered_pass = hovered;
}

/// Stages 3–7 of the frame as the list of steps the stage choices compose (`gi_render::chain`),
/// on one wrapped line above the passes, and the step that found no pass to run, if one did.
fn steps_ui(ui: &mut egui::Ui, r: &gi_render::Renderer) {
    let steps: Vec<String> = r.frame_steps().iter().map(|(stage, name)| format!("{stage} {name}")).collect();
    let text = if steps.is_empty() { "none: direct light only".to_string() } else { steps.join(" → ") };
    ui.add(egui::Label::new(egui::RichText::new(format!("steps: {text}")).small()).wrap()).on_hover_text(
        "stages 3–7 as the stage choices compose them (stage, step), in frame order; docs/architecture.md, 'The frame as a list'",
    );
    if let Some(step) = r.failed_step() {
        ui.colored_label(ui.visuals().error_fg_color, format!("{step} found no pass to run: no indirect light"));
    }
    ui.separator();
}
