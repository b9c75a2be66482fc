//! The viewport pane: the rendered image, camera navigation, probes and the VPL, HCB and A/B
//! overlays.

use super::caption;
use crate::ui::ERROR;
use crate::ui::state::State;

pub(super) fn viewport_ui(st: &mut State, ui: &mut egui::Ui) {
    let rect = ui.available_rect_before_wrap();
    if st.grid.is_some() {
        super::grid::grid_ui(st, ui, rect);
        return;
    }
    st.viewport_rect = rect;
    let ppp = ui.ctx().pixels_per_point();
    st.viewport_px = ((rect.width() * ppp).round().max(0.0) as u32, (rect.height() * ppp).round().max(0.0) as u32);
    let Some((id, (w, h), label)) = st.viewport_texture() else { return };
    let response = ui.allocate_rect(rect, egui::Sense::click_and_drag());
    ui.painter().image(
        id,
        rect,
        egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0)),
        egui::Color32::WHITE,
    );
    ab_overlay(st, ui, rect);
    if st.overlays.vpls {
        vpl_overlay(st, ui, rect);
    }
    if st.overlays.hcb_samples {
        hcb_overlay(st, ui, rect);
    }
    if st.overlays.soler_samples {
        soler_overlay(st, ui, rect);
    }
    if st.overlays.gautron_records {
        records_overlay(st, ui, rect);
    }
    if st.overlays.ddgi_probes {
        super::ddgi_overlay::probes_overlay(st, ui, rect);
    }
    if let (Some(v), Ok(l)) = (&st.explain, &st.lab)
        && v.overlay
    {
        super::explain::explain_overlay(v, ui, rect, (w, h), l.renderer.view_proj(), l.renderer.camera.right());
    }
    // The lights and their handles, on top of the image's response (they take its clicks
    // and drags where they are).
    if st.overlays.lights
        && let Ok(l) = &mut st.lab
    {
        super::light_gizmo::light_gizmos(l, ui, rect);
    }
    if !st.hot.errors.is_empty() {
        // The compile error stays on screen until the file is fixed.
        let text: Vec<String> = st.hot.errors.iter().map(|(f, e)| format!("{f}: {e}")).collect();
        let area = egui::Rect::from_min_max(
            rect.left_top() + egui::vec2(8.0, 8.0),
            rect.right_bottom() - egui::vec2(8.0, 40.0),
        );
        ui.scope_builder(egui::UiBuilder::new().max_rect(area), |ui| {
            egui::Frame::new().fill(egui::Color32::from_black_alpha(200)).inner_margin(8.0).show(ui, |ui| {
                ui.colored_label(ERROR, "Shader error — the last good pipelines keep running:");
                for t in &text {
                    ui.label(egui::RichText::new(t).monospace().color(egui::Color32::WHITE));
                }
            });
        });
    }
    if let Some(text) = label {
        ui.painter().text(
            rect.left_top() + egui::vec2(8.0, 8.0),
            egui::Align2::LEFT_TOP,
            format!("showing {text}"),
            egui::FontId::proportional(14.0),
            egui::Color32::YELLOW,
        );
    }
    // The hovered pixel of the render (for the probe); a click pins it.
    if let Some(p) = response.hover_pos() {
        let uv = (p - rect.min) / rect.size();
        st.probes.hover = Some((
            (uv.x * w as f32).clamp(0.0, w as f32 - 1.0) as u32,
            (uv.y * h as f32).clamp(0.0, h as f32 - 1.0) as u32,
        ));
    }
    // With the DDGI overlay on, a click on a probe's dot selects it (its rays are drawn).
    let picked = response
        .interact_pointer_pos()
        .filter(|_| response.clicked() && st.overlays.ddgi_probes)
        .and_then(|at| super::ddgi_overlay::pick(st, rect, at));
    if picked.is_some() {
        st.overlays.ddgi_selected = picked;
    } else if response.clicked()
        && let Some(p) = st.probes.hover
    {
        st.pin_probe(p);
    }
    // Explain a pixel (issue #42): the context menu, or X over the image.
    if response.secondary_clicked() {
        st.probes.context_pixel = st.probes.hover;
    }
    response.context_menu(|ui| {
        let Some(p) = st.probes.context_pixel else {
            ui.weak("no pixel under the pointer");
            return;
        };
        if ui.button(format!("Explain this pixel ({}, {})", p.0, p.1)).clicked() {
            st.explain_pixel(p);
            ui.close();
        }
        if ui.button("Pin a probe here").clicked() {
            st.pin_probe(p);
            ui.close();
        }
        if st.explain.is_some() && ui.button("Stop explaining").clicked() {
            st.explain = None;
            ui.close();
        }
    });
    if response.hovered()
        && !ui.ctx().egui_wants_keyboard_input()
        && ui.input_mut(|i| i.consume_key(egui::Modifiers::NONE, egui::Key::X))
        && let Some(p) = st.probes.hover
    {
        st.explain_pixel(p);
    }
    // Pinned probes as numbered rings.
    for (k, p) in st.probes.pinned.iter().enumerate() {
        let pos = rect.min
            + egui::vec2((p.pixel.0 as f32 + 0.5) / w as f32, (p.pixel.1 as f32 + 0.5) / h as f32) * rect.size();
        ui.painter().circle_stroke(pos, 6.0, egui::Stroke::new(2.0, egui::Color32::YELLOW));
        ui.painter().text(
            pos + egui::vec2(8.0, -8.0),
            egui::Align2::LEFT_BOTTOM,
            format!("{}", k + 1),
            egui::FontId::monospace(12.0),
            egui::Color32::YELLOW,
        );
    }
    if let Ok(l) = &mut st.lab {
        super::navigate(l, ui, &response);
    }
}

/// `vpl.list` over the viewport (Knecht §3.3): each VPL projected with the camera as a dot
/// coloured by the flux it reflects diffusely, Φ·c (so a VPL on the red wall is red),
/// normalised so that the brightest VPL has its full colour; VPLs behind the camera are left
/// out. A line names the count and the brightest flux.
fn vpl_overlay(st: &State, ui: &mut egui::Ui, rect: egui::Rect) {
    let Ok(l) = &st.lab else { return };
    let painter = ui.painter_at(rect);
    let note = |s: String| {
        painter.text(
            rect.left_bottom() + egui::vec2(8.0, -8.0),
            egui::Align2::LEFT_BOTTOM,
            s,
            egui::FontId::proportional(14.0),
            egui::Color32::WHITE,
        )
    };
    let Some(vpls) = l.renderer.vpl_list_later() else {
        note("VPL overlay: pick a VPL gather (instant radiosity or the exact-VPL reference) to see its VPLs".into());
        return;
    };
    let lum = |f: glam::Vec4| 0.2126 * f.x + 0.7152 * f.y + 0.0722 * f.z;
    let reflected = |v: &gi_render::passes::reference::vpl::GpuVpl| v.flux * v.albedo;
    let brightest = vpls.iter().map(|v| lum(reflected(v))).fold(0.0f32, f32::max).max(1e-12);
    let vp = l.renderer.view_proj();
    for v in &vpls {
        let clip = vp * v.position.truncate().extend(1.0);
        if clip.w <= 0.0 {
            continue;
        }
        let ndc = clip.truncate() / clip.w;
        let pos = rect.min + egui::vec2((ndc.x * 0.5 + 0.5) * rect.width(), (0.5 - ndc.y * 0.5) * rect.height());
        let c = (reflected(v).truncate() / brightest).clamp(glam::Vec3::ZERO, glam::Vec3::ONE);
        let colour = egui::Color32::from(egui::Rgba::from_rgb(c.x, c.y, c.z));
        painter.circle(pos, 3.0, colour, egui::Stroke::new(1.0, egui::Color32::BLACK));
    }
    note(format!("{} VPLs coloured by reflected flux Φ·c; brightest {brightest:.3e} W (full colour)", vpls.len()));
}

/// The HCB's samples over the viewport (Nguyen et al. Fig. 4b's white dots): each at its
/// G-buffer pixel, its radius growing with its level, and Table 1's counts on a line.
fn hcb_overlay(st: &State, ui: &mut egui::Ui, rect: egui::Rect) {
    let Ok(l) = &st.lab else { return };
    let painter = ui.painter_at(rect);
    // On a dark plate, so that it stays readable over the dots.
    let text = |s: String| caption(&painter, rect, s);
    let Some(stats) = l.renderer.hcb_stats_later() else {
        text("HCB samples: pick the hierarchical coherence buffer (Nguyen) to see its samples".into());
        return;
    };
    let (w, h) = l.renderer.size();
    let scale = egui::vec2(rect.width() / w.max(1) as f32, rect.height() / h.max(1) as f32);
    let at = |x: u32, y: u32| rect.min + egui::vec2((x as f32 + 0.5) * scale.x, (y as f32 + 0.5) * scale.y);
    for &[x, y, level] in &stats.samples {
        painter.circle_filled(at(x, y), 1.0 + 0.5 * level as f32, egui::Color32::WHITE);
    }
    // Covered pixels that no sample reached (hcb.irradiance's a = 0): magenta, never
    // silently black. Listed by the GPU (issue #38: no whole images read back).
    for &[x, y] in &stats.uncovered_pixels {
        painter.circle_filled(at(x, y), 2.0, egui::Color32::from_rgb(255, 0, 255));
    }
    text(stats.summary(w * h));
}

/// Gautron's irradiance records over the viewport (003, "From Octree to Splatting"): each
/// record a dot at P_k coloured by E_k (normalised so that the brightest has its full
/// colour), with the circle its influence sphere of radius a·R_k projects to (the radius
/// measured along the camera's right vector at P_k's depth); stale records in orange.
fn records_overlay(st: &State, ui: &mut egui::Ui, rect: egui::Rect) {
    let Ok(l) = &st.lab else { return };
    let painter = ui.painter_at(rect);
    let text = |s: String| caption(&painter, rect, s);
    let r = &l.renderer;
    let records = r.gautron_state_later(true).and_then(|(_, records)| records);
    let Some(records) = records.filter(|_| {
        l.settings.pipeline.shading_points == gi_render::settings::pipeline::ShadingPoints::IrradianceRecords
    }) else {
        text("Gautron records: pick irradiance records (Gautron, or records lit by VPLs) to see them".into());
        return;
    };
    let a = l.settings.gautron.accuracy;
    let vp = r.view_proj();
    let right = r.camera.view().row(0).truncate();
    let screen = |p: glam::Vec3| {
        let clip = vp * p.extend(1.0);
        (clip.w > 0.0).then(|| {
            let ndc = clip.truncate() / clip.w;
            rect.min + egui::vec2((ndc.x * 0.5 + 0.5) * rect.width(), (0.5 - ndc.y * 0.5) * rect.height())
        })
    };
    let brightest = records.iter().map(|g| g.irradiance.truncate().max_element()).fold(0.0f32, f32::max).max(1e-12);
    let mut stale = 0;
    for g in &records {
        let p = g.position.truncate();
        let (Some(centre), Some(edge)) = (screen(p), screen(p + right * a * g.position.w)) else { continue };
        let is_stale = g.pixel.w == 2.0;
        stale += is_stale as usize;
        let outline = if is_stale { egui::Color32::from_rgb(255, 150, 0) } else { egui::Color32::from_white_alpha(60) };
        painter.circle_stroke(centre, centre.distance(edge), egui::Stroke::new(1.0, outline));
        let c = (g.irradiance.truncate() / brightest).clamp(glam::Vec3::ZERO, glam::Vec3::ONE);
        let colour = egui::Color32::from(egui::Rgba::from_rgb(c.x, c.y, c.z));
        painter.circle(centre, 2.5, colour, egui::Stroke::new(1.0, egui::Color32::BLACK));
    }
    text(format!(
        "{} irradiance records ({stale} stale, orange), dots coloured by E_k (brightest {brightest:.3e} W/m² at full colour), circles a·R_k with a = {a}",
        records.len()
    ));
}

/// Level colours of the Soler samples overlay (level k: `LEVEL_COLOURS[k % 6]`).
const LEVEL_COLOURS: [egui::Color32; 6] = [
    egui::Color32::from_rgb(255, 255, 255),
    egui::Color32::from_rgb(255, 220, 0),
    egui::Color32::from_rgb(0, 220, 255),
    egui::Color32::from_rgb(255, 80, 200),
    egui::Color32::from_rgb(120, 255, 80),
    egui::Color32::from_rgb(255, 140, 40),
];

/// Soler et al.'s Fig. 3 right over the viewport: the ring samples of the hovered pixel (or
/// the first pinned probe) at every gathered level, coloured by level, filled where the
/// sample can light the pixel, with each level's receiver texel outlined and a legend.
fn soler_overlay(st: &State, ui: &mut egui::Ui, rect: egui::Rect) {
    let Ok(l) = &st.lab else { return };
    let painter = ui.painter_at(rect);
    let text = |s: String| caption(&painter, rect, s);
    let Some(pixel) = st.probes.pinned.first().map(|p| p.pixel).or(st.probes.hover) else {
        text("Soler samples: hover the image (or pin a probe) to see the samples behind a pixel".into());
        return;
    };
    let receivers = match l.renderer.soler_samples_later(pixel) {
        Ok(Some(r)) => r,
        Ok(None) => return text("Soler samples: reading the pixel's levels…".into()),
        Err(e) => return text(format!("Soler samples: {e}")),
    };
    let (w, h) = l.renderer.size();
    let scale = egui::vec2(rect.width() / w.max(1) as f32, rect.height() / h.max(1) as f32);
    let at = |p: glam::Vec2| rect.min + egui::vec2(p.x * scale.x, p.y * scale.y);
    let mut legend = Vec::new();
    for r in &receivers {
        let colour = LEVEL_COLOURS[r.level as usize % LEVEL_COLOURS.len()];
        for smp in &r.samples {
            if smp.lit {
                painter.circle_filled(at(smp.pixel), 2.5, colour);
            } else {
                painter.circle_stroke(at(smp.pixel), 2.5, egui::Stroke::new(1.0, colour));
            }
        }
        let fp = egui::Rect::from_min_max(at(r.footprint.0), at(r.footprint.1));
        painter.rect_stroke(fp, 0.0, egui::Stroke::new(1.5, colour), egui::StrokeKind::Outside);
        let lit = r.samples.iter().filter(|s| s.lit).count();
        let gloss = if r.glossy { ", glossy lobe" } else { "" };
        legend.push(format!("level {}: {lit}/{} lit{gloss}", r.level, r.samples.len()));
    }
    let pos = rect.min + egui::vec2((pixel.0 as f32 + 0.5) * scale.x, (pixel.1 as f32 + 0.5) * scale.y);
    painter.circle_stroke(pos, 4.0, egui::Stroke::new(2.0, egui::Color32::RED));
    if legend.is_empty() {
        legend.push("the pixel is background at every level".into());
    }
    text(format!("Soler samples of pixel ({}, {}) — {}", pixel.0, pixel.1, legend.join(" · ")));
}

/// The A/B comparison drawn over the viewport: B right of a draggable divider, or the
/// difference / FLIP image, with the two sources named and a mode switch.
fn ab_overlay(st: &mut State, ui: &mut egui::Ui, rect: egui::Rect) {
    use crate::ui::ab::AbView;
    let a_label = st.preset_label_text();
    let (Some(ab), Ok(l)) = (&mut st.ab, &st.lab) else { return };
    let full = egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0));
    let painter = ui.painter_at(rect);
    match ab.view {
        AbView::Split => {
            let (id, _) = ab.texture_b(&l.render_state);
            let x = rect.min.x + ab.split * rect.width();
            let right = egui::Rect::from_min_max(egui::pos2(x, rect.min.y), rect.max);
            let uv = egui::Rect::from_min_max(egui::pos2(ab.split, 0.0), egui::pos2(1.0, 1.0));
            painter.image(id, right, uv, egui::Color32::WHITE);
            let handle = egui::Rect::from_center_size(egui::pos2(x, rect.center().y), egui::vec2(12.0, rect.height()));
            let r = ui.interact(handle, ui.scope_id().with("ab_divider"), egui::Sense::drag());
            if r.dragged() {
                ab.split = ((x + r.drag_delta().x - rect.min.x) / rect.width()).clamp(0.0, 1.0);
            }
            let stroke = if r.hovered() || r.dragged() { 3.0 } else { 1.5 };
            painter
                .line_segment([egui::pos2(x, rect.min.y), egui::pos2(x, rect.max.y)], (stroke, egui::Color32::WHITE));
            r.on_hover_cursor(egui::CursorIcon::ResizeHorizontal);
        }
        AbView::Difference | AbView::Flip => {
            if let Some(id) = ab.compared(ui.ctx(), &l.renderer) {
                painter.image(id, rect, full, egui::Color32::WHITE);
            }
        }
    }
    let text = |pos: egui::Pos2, align, s: String| {
        painter.text(pos, align, s, egui::FontId::proportional(14.0), egui::Color32::WHITE);
    };
    text(rect.left_top() + egui::vec2(8.0, 28.0), egui::Align2::LEFT_TOP, format!("A: {a_label}"));
    text(rect.right_top() + egui::vec2(-8.0, 8.0), egui::Align2::RIGHT_TOP, format!("B: {}", ab.source.label()));
    if let Some((flip, rmse)) = ab.metrics {
        text(
            rect.right_top() + egui::vec2(-8.0, 28.0),
            egui::Align2::RIGHT_TOP,
            format!("FLIP {flip:.4} · RMSE {rmse:.4}"),
        );
    }
    if let Some(e) = &ab.error {
        text(rect.left_bottom() + egui::vec2(8.0, -40.0), egui::Align2::LEFT_BOTTOM, e.clone());
    }
    let bar = egui::Rect::from_min_size(rect.left_bottom() + egui::vec2(8.0, -30.0), egui::vec2(420.0, 24.0));
    let mut stop = false;
    ui.scope_builder(egui::UiBuilder::new().max_rect(bar), |ui| {
        ui.horizontal(|ui| {
            ui.selectable_value(&mut ab.view, AbView::Split, "A|B split");
            ui.selectable_value(&mut ab.view, AbView::Difference, "|A-B|");
            ui.selectable_value(&mut ab.view, AbView::Flip, "FLIP");
            if ab.view == AbView::Difference {
                ui.add(egui::DragValue::new(&mut ab.gain).range(0.1..=1000.0).speed(0.1).prefix("gain ×"));
            }
            stop = ui.button("stop A/B").clicked();
        });
    });
    if stop {
        st.stop_ab();
    }
}
