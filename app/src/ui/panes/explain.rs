//! The Explain pane and its viewport overlay (issue #42): the pinned pixel's contributors,
//! largest first, with their share, weights and rejections, the sums checked against the
//! buffers the frame wrote, and a CSV copy; over the image, each contributor as a dot sized by
//! its share with a line to the pixel, the rejected ones dimmed.

use gi_render::explain::{Contribution, Explanation};

use crate::ui::ERROR;
use crate::ui::explain::ExplainView;

/// Checks within this relative difference are shown as holding (two half-float steps: the
/// buffers the sums are checked against are half floats).
const CHECK_OK: f32 = 1e-3;

/// The pane reads and changes the explained pixel's view only.
pub(super) fn explain_ui(explain: &mut Option<ExplainView>, ui: &mut egui::Ui) {
    let Some(v) = explain else {
        ui.heading("Explain a pixel");
        ui.weak(
            "Right-click the viewport → Explain this pixel, or press X over it: this pane then lists \
             where the pixel's indirect light comes from (VPLs, the filter's window, the history), \
             largest first, with their weights and why the others give nothing.",
        );
        return;
    };
    let mut unpin = false;
    ui.horizontal(|ui| {
        ui.heading(format!("Explain pixel ({}, {})", v.pixel.0, v.pixel.1));
        if ui.button("Unpin").clicked() {
            unpin = true;
        }
        let csv = v.explanation().map(|e| e.to_csv());
        if ui.add_enabled(csv.is_some(), egui::Button::new("Copy CSV")).clicked()
            && let Some(csv) = csv
        {
            ui.ctx().copy_text(csv);
        }
        ui.checkbox(&mut v.show_rejected, "rejected too");
        ui.checkbox(&mut v.overlay, "overlay");
    });
    if unpin {
        *explain = None;
        return;
    }
    match &v.latest {
        None => {
            ui.weak("replaying the pixel's gather… (it arrives a frame or two late)");
        }
        Some(Err(e)) => {
            ui.colored_label(ERROR, e);
        }
        Some(Ok(_)) if v.explanation().is_none() => {
            ui.weak("replaying the new pixel's gather…");
        }
        Some(Ok(e)) => {
            let e = e.clone();
            summary(ui, &e);
            ui.separator();
            v.hovered = table(ui, &e, v.show_rejected);
        }
    }
}

/// The technique, the pixel's value against the contributions' sum, then the other checks
/// and the notes (folded while every check holds).
fn summary(ui: &mut egui::Ui, e: &Explanation) {
    ui.label(egui::RichText::new(&e.technique).small());
    let rgb = |c: glam::Vec3| format!("({:.4e}, {:.4e}, {:.4e})", c.x, c.y, c.z);
    let verdict = |ui: &mut egui::Ui, err: f32| {
        let (colour, word) =
            if err <= CHECK_OK { (egui::Color32::from_rgb(90, 200, 90), "✔") } else { (ERROR, "✘") };
        ui.colored_label(colour, format!("{word} Δ {err:.1e}"));
    };
    let total = e.total_check();
    ui.horizontal_wrapped(|ui| {
        verdict(ui, total.relative_error());
        ui.label(format!("Σ {} contributions = {}", e.contributions.len(), rgb(total.sum)));
        ui.label(format!("against {} = {}", e.buffer, rgb(e.value)));
    });
    let all_hold = e.checks.iter().all(|c| c.relative_error() <= CHECK_OK);
    egui::CollapsingHeader::new(format!(
        "{} more checks ({}) and notes",
        e.checks.len(),
        if all_hold { "all hold" } else { "one fails" }
    ))
    .id_salt("explain_checks")
    .default_open(!all_hold)
    .show(ui, |ui| {
        egui::Grid::new("explain_checks_grid").striped(true).num_columns(4).show(ui, |ui| {
            for c in &e.checks {
                verdict(ui, c.relative_error());
                ui.label(&c.what);
                ui.monospace(rgb(c.sum));
                ui.label(format!("{} = {}", c.buffer, rgb(c.value)));
                ui.end_row();
            }
        });
        for n in &e.notes {
            ui.weak(n);
        }
    });
}

/// The contributors' table; returns the name of the row under the pointer.
fn table(ui: &mut egui::Ui, e: &Explanation, rejected: bool) -> Option<String> {
    let rows: Vec<&Contribution> = e.contributions.iter().filter(|c| rejected || c.rejected.is_none()).collect();
    let hidden = e.contributions.len() - rows.len();
    if hidden > 0 {
        ui.weak(format!("{hidden} rejected contributors hidden (tick \"rejected too\")"));
    }
    let mut hovered = None;
    egui::ScrollArea::both().id_salt("explain_rows").auto_shrink([false, false]).show(ui, |ui| {
        egui::Grid::new("explain_table").striped(true).num_columns(6).show(ui, |ui| {
            for h in ["contributor", "source", "share", "value (rgb)", "weight", "why / fields"] {
                ui.strong(h);
            }
            ui.end_row();
            for c in rows {
                let dim = c.rejected.is_some();
                let text = |s: String| if dim { egui::RichText::new(s).weak() } else { egui::RichText::new(s) };
                let r = ui.label(text(c.name.clone()));
                ui.label(text(c.source.clone()));
                ui.monospace(format!("{:>6.2}%", 100.0 * e.share(c)));
                ui.monospace(format!("{:.3e} {:.3e} {:.3e}", c.value.x, c.value.y, c.value.z));
                ui.monospace(format!("{:.4}", c.weight));
                let mut why: Vec<String> = c.rejected.iter().map(|r| r.label().to_string()).collect();
                if let Some((x, y)) = c.via {
                    why.push(format!("via ({x}, {y})"));
                }
                why.extend(c.fields.iter().map(|(k, v)| format!("{k} {v:.3e}")));
                ui.label(text(why.join(", ")));
                ui.end_row();
                if r.hovered() {
                    hovered = Some(c.name.clone());
                }
            }
        });
    });
    hovered
}

/// The contributors over the viewport `rect` of a `size` render (`view_proj`: the camera's).
pub(super) fn explain_overlay(
    v: &ExplainView,
    ui: &mut egui::Ui,
    rect: egui::Rect,
    size: (u32, u32),
    view_proj: glam::Mat4,
    camera_right: glam::Vec3,
) {
    let painter = ui.painter_at(rect);
    let to_screen = |p: (u32, u32)| {
        rect.min + egui::vec2((p.0 as f32 + 0.5) / size.0 as f32, (p.1 as f32 + 0.5) / size.1 as f32) * rect.size()
    };
    let pixel = to_screen(v.pixel);
    let cross = egui::Stroke::new(2.0, egui::Color32::from_rgb(255, 80, 255));
    painter.line_segment([pixel - egui::vec2(9.0, 0.0), pixel + egui::vec2(9.0, 0.0)], cross);
    painter.line_segment([pixel - egui::vec2(0.0, 9.0), pixel + egui::vec2(0.0, 9.0)], cross);
    let Some(e) = v.explanation() else { return };
    let brightest = e.contributions.iter().map(|c| e.share(c)).fold(0.0f32, f32::max).max(1e-6);
    // Rejected first, so that the contributors are drawn over them.
    for c in e.contributions.iter().rev() {
        let Some(p) = c.position else { continue };
        let clip = view_proj * p.extend(1.0);
        if clip.w <= 0.0 {
            continue;
        }
        let ndc = clip.truncate() / clip.w;
        let pos = rect.min + egui::vec2((ndc.x * 0.5 + 0.5) * rect.width(), (0.5 - ndc.y * 0.5) * rect.height());
        let from = c.via.map(to_screen).unwrap_or(pixel);
        let hovered = v.hovered.as_deref() == Some(c.name.as_str());
        if c.rejected.is_some() {
            if v.show_rejected || hovered {
                let grey = egui::Color32::from_rgba_unmultiplied(150, 150, 150, 90);
                painter.line_segment([from, pos], egui::Stroke::new(0.5, grey));
                painter.circle_stroke(pos, 2.5, egui::Stroke::new(1.0, grey));
            }
            continue;
        }
        let s = (e.share(c) / brightest).clamp(0.0, 1.0);
        let colour = egui::Color32::from_rgb(255, (120.0 + 135.0 * s) as u8, 40);
        painter.line_segment([from, pos], egui::Stroke::new(0.5 + 1.5 * s, colour.gamma_multiply(0.6)));
        painter.circle(pos, 2.0 + 6.0 * s.sqrt(), colour, egui::Stroke::new(1.0, egui::Color32::BLACK));
        if hovered {
            painter.circle_stroke(pos, 12.0, egui::Stroke::new(2.0, egui::Color32::WHITE));
        }
        // A sample's splat quad (the HCB), as the splat draws it.
        let field = |name: &str| c.fields.iter().find(|(k, _)| *k == name).map(|(_, v)| *v);
        if let (Some(x0), Some(y0), Some(x1), Some(y1)) =
            (field("quad x0 (NDC)"), field("quad y0 (NDC)"), field("quad x1 (NDC)"), field("quad y1 (NDC)"))
        {
            let to =
                |x: f32, y: f32| rect.min + egui::vec2((x * 0.5 + 0.5) * rect.width(), (0.5 - y * 0.5) * rect.height());
            painter.rect_stroke(
                egui::Rect::from_two_pos(to(x0, y0), to(x1, y1)),
                0.0,
                egui::Stroke::new(1.0, colour.gamma_multiply(0.8)),
                egui::StrokeKind::Middle,
            );
        }
        // A record's sphere of influence a·R_k (Gautron), as the splat bounds it.
        if let Some((_, r)) = c.fields.iter().find(|(k, _)| *k == "a·R_k") {
            let edge = view_proj * (p + camera_right * *r).extend(1.0);
            if edge.w > 0.0 {
                let e = edge.truncate() / edge.w;
                let radius = ((e.x - ndc.x) * 0.5 * rect.width()).abs();
                painter.circle_stroke(pos, radius, egui::Stroke::new(1.0, colour.gamma_multiply(0.8)));
            }
        }
    }
    // Soler's rings: per level, the ring its heaviest texel gathered (r · 2^k pixels).
    let mut rings: Vec<(f32, &Contribution)> = Vec::new();
    // (A ring sample's position is its sender's: only the level texels' rows centre a ring.)
    for c in e.contributions.iter().filter(|c| c.rejected.is_none() && !c.name.contains('#')) {
        let Some((_, level)) = c.fields.iter().find(|(k, _)| *k == "level") else { continue };
        match rings.iter_mut().find(|(l, _)| l == level) {
            Some(r) if e.share(r.1) < e.share(c) => r.1 = c,
            Some(_) => {}
            None => rings.push((*level, c)),
        }
    }
    for (level, c) in rings {
        let (Some(p), Some((_, radius))) = (c.position, c.fields.iter().find(|(k, _)| *k == "ring radius (px)")) else {
            continue;
        };
        let clip = view_proj * p.extend(1.0);
        if clip.w <= 0.0 {
            continue;
        }
        let ndc = clip.truncate() / clip.w;
        let pos = rect.min + egui::vec2((ndc.x * 0.5 + 0.5) * rect.width(), (0.5 - ndc.y * 0.5) * rect.height());
        let colour = egui::Color32::from_rgb(80, 200 - (30.0 * level.min(5.0)) as u8, 255);
        painter.circle_stroke(pos, radius * rect.width() / size.0 as f32, egui::Stroke::new(1.0, colour));
        painter.text(
            pos + egui::vec2(0.0, -radius * rect.width() / size.0 as f32),
            egui::Align2::CENTER_BOTTOM,
            format!("level {level}"),
            egui::FontId::proportional(11.0),
            colour,
        );
    }
    // The filter's window: the pixels the VPLs came through.
    for c in &e.contributions {
        if let Some(q) = c.via {
            painter.rect_stroke(
                egui::Rect::from_center_size(to_screen(q), egui::vec2(4.0, 4.0)),
                0.0,
                egui::Stroke::new(1.0, egui::Color32::from_rgb(255, 80, 255)),
                egui::StrokeKind::Middle,
            );
        }
    }
    let accepted = e.contributions.iter().filter(|c| c.rejected.is_none()).count();
    painter.text(
        rect.left_bottom() + egui::vec2(8.0, -28.0),
        egui::Align2::LEFT_BOTTOM,
        format!(
            "explaining ({}, {}): {accepted} contributors (dots sized by share), {} rejected{}",
            v.pixel.0,
            v.pixel.1,
            e.contributions.len() - accepted,
            if v.show_rejected { " (grey)" } else { "" }
        ),
        egui::FontId::proportional(14.0),
        egui::Color32::WHITE,
    );
}
