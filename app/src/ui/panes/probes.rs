//! The probes pane: the hovered pixel's buffers and the pinned probes' histories.

use egui_plot::{Line, Plot, PlotPoints};

use crate::ui::lab::Lab;
use crate::ui::state::Probes;

/// The pane reads the lab's buffer names and its own part of the state, nothing else.
pub(super) fn probe_ui(probes: &mut Probes, l: &Lab, ui: &mut egui::Ui) {
    let names = l.renderer.buffers().names();
    ui.horizontal(|ui| {
        ui.heading("Hovered pixel");
        match probes.hover {
            Some((x, y)) => ui.monospace(format!("({x}, {y})")),
            None => ui.weak("hover the viewport or a viewer"),
        };
    });
    if !probes.values.is_empty() {
        egui::Grid::new("hover_values").striped(true).num_columns(3).show(ui, |ui| {
            for v in &probes.values {
                ui.monospace(&v.name);
                ui.monospace(format!("({}, {})", v.texel.0, v.texel.1));
                ui.monospace(format_value(v.value));
                ui.end_row();
            }
        });
    }
    ui.separator();
    ui.heading("Pinned probes");
    if probes.pinned.is_empty() {
        ui.weak("click the viewport or a viewer to pin a probe; its value is plotted over the last frames");
    }
    let mut remove = None;
    for (k, p) in probes.pinned.iter_mut().enumerate() {
        ui.horizontal(|ui| {
            ui.strong(format!("{} at ({}, {})", k + 1, p.pixel.0, p.pixel.1));
            crate::ui::viewer::buffer_picker(ui, 1000 + k as u32, &names, &mut p.buffer);
            for (i, c) in ["R", "G", "B", "A"].iter().enumerate() {
                ui.selectable_value(&mut p.channel, i, *c);
            }
            if ui.button("remove").clicked() {
                remove = Some(k);
            }
        });
        if let Some(h) = probes.history.get(k) {
            if let Some(last) = h.back() {
                ui.monospace(format!("{} = {}", p.buffer, format_value(*last)));
            }
            let ch = p.channel.min(3);
            let points: PlotPoints = h
                .iter()
                .enumerate()
                .filter(|(_, v)| v[ch].is_finite())
                .map(|(i, v)| [i as f64, v[ch] as f64])
                .collect();
            Plot::new(("probe_plot", k)).height(120.0).x_axis_label("frame").show(ui, |plot| {
                plot.line(Line::new(format!("{} {}", p.buffer, ["r", "g", "b", "a"][ch]), points));
            });
        }
    }
    if let Some(k) = remove {
        probes.unpin(k);
    }
}

pub fn format_value(v: [f32; 4]) -> String {
    v.iter().map(|x| format!("{x:>10.5}")).collect::<Vec<_>>().join(" ")
}
