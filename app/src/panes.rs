//! The lab's panels as egui_tiles panes: viewport, settings, scene and timeline, presets,
//! GPU timings, probes and buffer viewers. Panels can be dragged, tabbed and resized; the
//! layout is part of the session.

use std::path::PathBuf;

use egui_plot::{Legend, Line, Plot, PlotPoints};
use gi_render::LabSettings;

use crate::app::{ERROR, State};
use crate::session::Pane;

pub struct Behavior<'a> {
    pub state: &'a mut State,
    /// Viewer panes closed this frame (their GPU resources are released by the app).
    pub closed_viewers: Vec<u32>,
}

impl egui_tiles::Behavior<Pane> for Behavior<'_> {
    fn tab_title_for_pane(&mut self, pane: &Pane) -> egui::WidgetText {
        match pane {
            Pane::Viewport => "Viewport".into(),
            Pane::Settings => "Settings".into(),
            Pane::Scene => "Scene & timeline".into(),
            Pane::Presets => "Presets".into(),
            Pane::Timings => "GPU timings".into(),
            Pane::Probe => "Probes".into(),
            Pane::Viewer(id) => {
                let name = self.state.viewers.get(id).map(|v| v.state.buffer.as_str()).unwrap_or("?");
                format!("Viewer {id}: {name}").into()
            }
        }
    }

    fn pane_ui(&mut self, ui: &mut egui::Ui, _tile: egui_tiles::TileId, pane: &mut Pane) -> egui_tiles::UiResponse {
        let st = &mut *self.state;
        match pane {
            Pane::Viewport => viewport_ui(st, ui),
            Pane::Settings => scrolled(ui, "settings", |ui| settings_ui(st, ui)),
            Pane::Scene => scrolled(ui, "scene", |ui| scene_ui(st, ui)),
            Pane::Presets => scrolled(ui, "presets", |ui| presets_ui(st, ui)),
            Pane::Timings => timings_ui(st, ui),
            Pane::Probe => scrolled(ui, "probe", |ui| probe_ui(st, ui)),
            Pane::Viewer(id) => viewer_ui(st, ui, *id),
        }
        egui_tiles::UiResponse::None
    }

    fn is_tab_closable(&self, tiles: &egui_tiles::Tiles<Pane>, tile_id: egui_tiles::TileId) -> bool {
        matches!(tiles.get(tile_id), Some(egui_tiles::Tile::Pane(Pane::Viewer(_))))
    }

    fn on_tab_close(&mut self, tiles: &mut egui_tiles::Tiles<Pane>, tile_id: egui_tiles::TileId) -> bool {
        if let Some(egui_tiles::Tile::Pane(Pane::Viewer(id))) = tiles.get(tile_id) {
            self.closed_viewers.push(*id);
        }
        true
    }

    fn simplification_options(&self) -> egui_tiles::SimplificationOptions {
        egui_tiles::SimplificationOptions { all_panes_must_have_tabs: true, ..Default::default() }
    }
}

fn scrolled(ui: &mut egui::Ui, id: &str, f: impl FnOnce(&mut egui::Ui)) {
    egui::ScrollArea::vertical().id_salt(id).auto_shrink([false, false]).show(ui, |ui| {
        ui.add_space(4.0);
        f(ui)
    });
}

fn viewport_ui(st: &mut State, ui: &mut egui::Ui) {
    let rect = ui.available_rect_before_wrap();
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
    if st.show_vpls {
        vpl_overlay(st, ui, rect);
    }
    if st.show_hcb_samples {
        hcb_overlay(st, ui, rect);
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
        st.hover = Some((
            (uv.x * w as f32).clamp(0.0, w as f32 - 1.0) as u32,
            (uv.y * h as f32).clamp(0.0, h as f32 - 1.0) as u32,
        ));
    }
    if response.clicked()
        && let Some(p) = st.hover
    {
        st.pin_probe(p);
    }
    // Pinned probes as numbered rings.
    for (k, p) in st.pinned.iter().enumerate() {
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
        navigate(l, ui, &response);
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
    let Some(vpls) = l.renderer.vpl_list() else {
        note("VPL overlay: pick instant radiosity (Knecht) to see its VPLs".into());
        return;
    };
    let lum = |f: glam::Vec4| 0.2126 * f.x + 0.7152 * f.y + 0.0722 * f.z;
    let reflected = |v: &gi_render::passes::vpl::GpuVpl| v.flux * v.albedo;
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
    let text = |s: String| {
        let galley = painter.layout_no_wrap(s, egui::FontId::proportional(14.0), egui::Color32::WHITE);
        let pos = rect.left_top() + egui::vec2(8.0, 8.0);
        let plate = egui::Rect::from_min_size(pos, galley.size()).expand(4.0);
        painter.rect_filled(plate, 3.0, egui::Color32::from_black_alpha(200));
        painter.galley(pos, galley, egui::Color32::WHITE);
    };
    let Some(stats) = l.renderer.hcb_stats() else {
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
    // silently black.
    if stats.uncovered > 0
        && let (Ok(light), Ok(normal)) = (l.renderer.readback("hcb.irradiance"), l.renderer.readback("gbuffer.normal"))
    {
        for (i, (e, n)) in light.data.iter().zip(&normal.data).enumerate() {
            if e[3] == 0.0 && n[3] > 0.5 {
                let (x, y) = (i as u32 % light.width, i as u32 / light.width);
                painter.circle_filled(at(x, y), 2.0, egui::Color32::from_rgb(255, 0, 255));
            }
        }
    }
    text(stats.summary(w * h));
}

/// The A/B comparison drawn over the viewport: B right of a draggable divider, or the
/// difference / FLIP image, with the two sources named and a mode switch.
fn ab_overlay(st: &mut State, ui: &mut egui::Ui, rect: egui::Rect) {
    use crate::ab::AbView;
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

fn navigate(l: &mut crate::app::Lab, ui: &egui::Ui, response: &egui::Response) {
    let r = l.renderer.bounds().radius();
    let cam = &mut l.renderer.camera;
    if response.dragged_by(egui::PointerButton::Primary) {
        let d = response.drag_delta();
        cam.orbit(-d.x * 0.008, -d.y * 0.008);
    }
    if response.hovered() && !ui.ctx().egui_wants_keyboard_input() {
        let (scroll, dt, keys) = ui.input(|i| {
            let k = |key| if i.key_down(key) && i.modifiers.is_none() { 1.0 } else { 0.0 };
            (
                i.smooth_scroll_delta.y,
                i.stable_dt.min(0.1),
                glam::Vec3::new(
                    k(egui::Key::D) - k(egui::Key::A),
                    k(egui::Key::E) - k(egui::Key::Q),
                    k(egui::Key::W) - k(egui::Key::S),
                ),
            )
        });
        let speed = r * 0.8;
        if keys != glam::Vec3::ZERO {
            cam.fly(keys * speed * dt);
        }
        if scroll != 0.0 {
            let step = scroll * r * 0.002;
            cam.fly(glam::Vec3::new(0.0, 0.0, step));
            cam.orbit_distance = (cam.orbit_distance - step).max(r * 0.05);
        }
    }
}

fn settings_ui(st: &mut State, ui: &mut egui::Ui) {
    let Ok(l) = &mut st.lab else { return };
    let changed = crate::settings_ui::lab_settings_ui(ui, &mut l.settings, &st.preset.baseline);
    if changed {
        l.apply_settings();
    }
    if let Some((done, target)) = l.renderer.reference_progress() {
        ui.add(
            egui::ProgressBar::new(done as f32 / target.max(1) as f32)
                .text(format!("{done} / {target} VPLs accumulated")),
        );
        if l.renderer.clock.playing {
            ui.small("The accumulation restarts whenever the camera, a light or an animated object moves: pause the animation (Space) to let it converge.");
        }
    }
    if let Some(e) = &l.settings_error {
        ui.colored_label(ERROR, e);
    }
    if l.settings.indirect.technique == gi_render::lab_settings::IndirectTechnique::Hcb {
        ui.separator();
        egui::CollapsingHeader::new("HCB statistics (Nguyen Table 1)").id_salt("hcb_stats").default_open(true).show(
            ui,
            |ui| match l.renderer.hcb_stats() {
                Some(stats) => hcb_stats_ui(ui, &stats, l.renderer.size()),
                None => {
                    ui.small("no HCB frame rendered yet");
                }
            },
        );
    }
}

/// Table 1 of Nguyen et al. for the last frame: per level its resolution, the samples and
/// their share of the level's texels and of the G-buffer's pixels; the total; the covered
/// pixels no sample reached; with the cache (§5), the reused, new and recomputed samples.
pub fn hcb_stats_ui(ui: &mut egui::Ui, stats: &gi_render::frame::HcbStats, size: (u32, u32)) {
    let pixels = (size.0 * size.1).max(1) as f64;
    let (mut w, mut h) = size;
    egui::Grid::new("hcb_table_1").num_columns(4).striped(true).show(ui, |ui| {
        for head in ["level (resolution)", "samples", "% of level", "% of G-buffer"] {
            ui.strong(head);
        }
        ui.end_row();
        for (k, (&n, &t)) in stats.samples_per_level.iter().zip(&stats.texels_per_level).enumerate() {
            ui.label(format!("{k} ({w}×{h})"));
            ui.label(n.to_string());
            ui.label(format!("{:.2} %", 100.0 * n as f64 / t.max(1) as f64));
            ui.label(format!("{:.2} %", 100.0 * n as f64 / pixels));
            ui.end_row();
            (w, h) = (w.div_ceil(2), h.div_ceil(2));
        }
        ui.strong("total");
        ui.strong(stats.samples().to_string());
        ui.label("");
        ui.strong(format!("{:.2} %", 100.0 * stats.samples() as f64 / pixels));
        ui.end_row();
    });
    ui.small(format!(
        "the paper: 1.9–4.4 % of the G-buffer; {} covered pixels no sample reached; d_max in use {:.3} scene units",
        stats.uncovered, stats.d_max
    ));
    if let Some(c) = &stats.cache {
        egui::Grid::new("hcb_cache_counts").num_columns(2).show(ui, |ui| {
            for (label, n, tip) in [
                ("cached (reused)", c.cached, "samples of the last frame still valid here (§5.1)"),
                ("new", c.new_samples(), "identified on the incomplete texels this frame (§5.2)"),
                ("recomputed", c.recomputed, "cached samples whose light was gathered again (§5.3)"),
                ("removed: invalid", c.invalid, "the G-buffer moved or turned under them (§5.1)"),
                ("removed: surplus", c.surplus, "valid, but inside an invalid sample's quad (§5.1)"),
                ("left the view", c.dropped, "reprojected outside the image"),
            ] {
                ui.label(label).on_hover_text(tip);
                ui.label(n.to_string());
                ui.end_row();
            }
        });
    }
}

fn scene_ui(st: &mut State, ui: &mut egui::Ui) {
    let Ok(l) = &mut st.lab else { return };
    ui.heading("Scene");
    ui.label(&l.scene_name);
    ui.small(format!("{} triangles", l.renderer.scene().triangle_count()));
    for w in &l.renderer.scene().warnings {
        ui.small(format!("warning: {w}"));
    }
    let mut open_dialog = false;
    let mut open_default = false;
    ui.horizontal(|ui| {
        open_dialog = ui.button("Open glTF…").on_hover_text("or drop a .gltf / .glb file on the window").clicked();
        open_default = ui.button("Default scene").clicked();
        ui.label("unit scale");
        ui.add(egui::DragValue::new(&mut l.unit_scale).range(1e-6..=1e6).speed(0.001))
            .on_hover_text("multiplies the scene's coordinates (0.001 for millimetres); applies on the next open");
    });
    let mut open_typed = false;
    ui.horizontal(|ui| {
        let r = ui.add(
            egui::TextEdit::singleline(&mut st.scene_path_text)
                .hint_text("or type a .gltf / .glb path")
                .desired_width(220.0),
        );
        let enter = r.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter));
        open_typed = (ui.add_enabled(!st.scene_path_text.trim().is_empty(), egui::Button::new("Open")).clicked()
            || enter)
            && !st.scene_path_text.trim().is_empty();
    });
    if let Some(e) = &l.scene_error {
        ui.colored_label(ERROR, e);
    }
    light_controls(l, ui);
    ui.separator();
    timeline(l, ui);
    ui.separator();
    ui.heading("Camera");
    if ui.button("Reset camera (Home)").clicked() {
        let (w, h) = l.renderer.size();
        l.renderer.camera =
            gi_render::frame::default_camera(l.renderer.scene(), l.renderer.bounds(), w as f32 / h.max(1) as f32);
    }
    let c = l.renderer.camera;
    ui.small(format!(
        "position ({:.2}, {:.2}, {:.2}) · yaw {:.1}° · pitch {:.1}° · fov {:.1}°",
        c.position.x,
        c.position.y,
        c.position.z,
        c.yaw.to_degrees(),
        c.pitch.to_degrees(),
        c.yfov.to_degrees()
    ));
    ui.horizontal(|ui| {
        ui.add(egui::TextEdit::singleline(&mut st.bookmark_name).hint_text("bookmark name").desired_width(140.0));
        if ui.button("Bookmark").clicked() {
            st.add_bookmark();
        }
    });
    let mut restore = None;
    let mut delete = None;
    for (i, b) in st.session.bookmarks.iter_mut().enumerate() {
        ui.horizontal(|ui| {
            ui.add(egui::TextEdit::singleline(&mut b.name).desired_width(140.0));
            if ui.button("Go").clicked() {
                restore = Some(b.camera);
            }
            if ui.button("Delete").clicked() {
                delete = Some(i);
            }
        });
    }
    if let Some(i) = delete {
        st.session.bookmarks.remove(i);
    }
    if let (Some(c), Ok(l)) = (restore, &mut st.lab) {
        l.renderer.camera = c;
    }
    if open_dialog {
        st.open_scene_dialog();
    }
    if open_typed {
        let path = std::path::PathBuf::from(st.scene_path_text.trim());
        let scale = st.lab.as_ref().map(|l| l.unit_scale).unwrap_or(1.0);
        if let Err(e) = st.open_scene(Some(path), scale) {
            st.set_status(format!("scene not opened: {e}"));
        }
    }
    if open_default && let Err(e) = st.open_scene(None, 1.0) {
        st.set_status(format!("scene not opened: {e}"));
    }
}

fn light_controls(l: &mut crate::app::Lab, ui: &mut egui::Ui) {
    let light_nodes: Vec<usize> =
        l.renderer.scene().nodes.iter().enumerate().filter(|(_, n)| n.light.is_some()).map(|(i, _)| i).collect();
    let r = l.renderer.bounds().radius();
    let mut changed = false;
    for (k, &ni) in light_nodes.iter().enumerate() {
        let scene = l.renderer.scene_mut();
        let Some(li) = scene.nodes[ni].light else { continue };
        let name = scene.lights[li].name.clone();
        let directional = matches!(scene.lights[li].kind, gi_render::scene::LightKind::Directional);
        egui::CollapsingHeader::new(format!("Light {k}: {name}")).default_open(k == 0).show(ui, |ui| {
            let tr = &mut scene.nodes[ni].transform;
            if directional {
                // A directional light has no position: edit where it shines from.
                let dir = tr.rotation * glam::Vec3::NEG_Z;
                let mut elevation = (-dir.y).clamp(-1.0, 1.0).asin().to_degrees();
                let mut azimuth = (-dir.x).atan2(-dir.z).to_degrees();
                ui.horizontal(|ui| {
                    ui.label("elevation");
                    let a = ui.add(egui::DragValue::new(&mut elevation).range(-90.0..=90.0).suffix("°"));
                    ui.label("azimuth");
                    let b = ui.add(egui::DragValue::new(&mut azimuth).suffix("°"));
                    if a.changed() || b.changed() {
                        let (e, z) = (elevation.to_radians(), azimuth.to_radians());
                        let d = glam::Vec3::new(-z.sin() * e.cos(), -e.sin(), -z.cos() * e.cos());
                        tr.rotation = glam::Quat::from_rotation_arc(glam::Vec3::NEG_Z, d.normalize());
                        changed = true;
                    }
                });
            } else {
                let t = &mut tr.translation;
                ui.horizontal(|ui| {
                    ui.label("position");
                    for (c, axis) in [(&mut t.x, "x"), (&mut t.y, "y"), (&mut t.z, "z")] {
                        changed |= ui
                            .add(egui::DragValue::new(c).speed(r * 0.005).max_decimals(3).prefix(format!("{axis} ")))
                            .changed();
                    }
                });
            }
            let l = &mut scene.lights[li];
            ui.horizontal(|ui| {
                ui.label("intensity");
                changed |= ui
                    .add(egui::Slider::new(&mut l.intensity, 0.0..=100_000.0).logarithmic(true))
                    .on_hover_text("candela for point and spot lights, lux for directional lights")
                    .changed();
            });
        });
    }
    if changed {
        l.renderer.reset_history();
    }
}

fn timeline(l: &mut crate::app::Lab, ui: &mut egui::Ui) {
    ui.heading("Animation");
    let duration = l.renderer.scene().animation_duration() as f64;
    let clock = &mut l.renderer.clock;
    ui.horizontal(|ui| {
        let label = if clock.playing { "Pause" } else { "Play" };
        if ui.button(label).on_hover_text("Space").clicked() {
            clock.playing = !clock.playing;
        }
        if ui.add_enabled(!clock.playing, egui::Button::new("Step")).on_hover_text("Period (.)").clicked() {
            clock.step();
        }
        ui.monospace(format!("t = {:.3} s  frame {}", clock.time_s(), clock.anim_frame));
    });
    ui.horizontal(|ui| {
        ui.label("speed");
        let mut speed = clock.speed;
        if ui.add(egui::Slider::new(&mut speed, 0.05..=8.0).logarithmic(true).suffix("×")).changed() {
            clock.set_speed(speed);
        }
    });
    ui.horizontal(|ui| {
        let mut looping = clock.loop_s > 0.0;
        if ui.checkbox(&mut looping, "loop").changed() {
            clock.loop_s = if looping { if duration > 0.0 { duration } else { 10.0 } } else { 0.0 };
        }
        if looping {
            ui.add(egui::DragValue::new(&mut clock.loop_s).range(0.01..=3600.0).speed(0.05).suffix(" s"));
        }
    });
    let end = if clock.loop_s > 0.0 {
        clock.loop_s
    } else if duration > 0.0 {
        duration
    } else {
        10.0
    };
    let mut t = clock.time_s() as f64;
    let scrub = ui.add(egui::Slider::new(&mut t, 0.0..=end).text("time").suffix(" s"));
    if scrub.changed() {
        clock.seek(t);
    }
    if duration > 0.0 {
        ui.small(format!("the scene's animations last {duration:.2} s"));
    }
}

/// The folder of `presets_dir`'s .ron files, sorted.
fn preset_files(dir: &std::path::Path) -> Vec<PathBuf> {
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

fn presets_ui(st: &mut State, ui: &mut egui::Ui) {
    ui.heading("Preset");
    let unsaved = st.unsaved();
    ui.horizontal(|ui| {
        ui.label(match &st.preset.path {
            Some(p) => p.display().to_string(),
            None => "new preset (not saved yet)".into(),
        });
        if unsaved {
            ui.colored_label(crate::settings_ui::CHANGED, "unsaved changes");
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
            ui.colored_label(crate::settings_ui::CHANGED, a);
            ui.label(b);
            ui.end_row();
        }
    });
}

fn timings_ui(st: &mut State, ui: &mut egui::Ui) {
    let Ok(l) = &st.lab else { return };
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
                    let points: PlotPoints = st
                        .timing_history
                        .iter()
                        .enumerate()
                        .filter_map(|(i, ts)| ts.iter().find(|t| t.name == name).map(|t| [i as f64, t.ms]))
                        .collect();
                    plot.line(Line::new(name.clone(), points));
                }
            },
        );
    });
    st.hovered_pass = hovered;
}

fn probe_ui(st: &mut State, ui: &mut egui::Ui) {
    let Ok(l) = &st.lab else { return };
    let names = l.renderer.buffers().names();
    ui.horizontal(|ui| {
        ui.heading("Hovered pixel");
        match st.hover {
            Some((x, y)) => ui.monospace(format!("({x}, {y})")),
            None => ui.weak("hover the viewport or a viewer"),
        };
    });
    if !st.hover_values.is_empty() {
        egui::Grid::new("hover_values").striped(true).num_columns(3).show(ui, |ui| {
            for v in &st.hover_values {
                ui.monospace(&v.name);
                ui.monospace(format!("({}, {})", v.texel.0, v.texel.1));
                ui.monospace(format_value(v.value));
                ui.end_row();
            }
        });
    }
    ui.separator();
    ui.heading("Pinned probes");
    if st.pinned.is_empty() {
        ui.weak("click the viewport or a viewer to pin a probe; its value is plotted over the last frames");
    }
    let mut remove = None;
    for (k, p) in st.pinned.iter_mut().enumerate() {
        ui.horizontal(|ui| {
            ui.strong(format!("{} at ({}, {})", k + 1, p.pixel.0, p.pixel.1));
            crate::viewer::buffer_picker(ui, 1000 + k as u32, &names, &mut p.buffer);
            for (i, c) in ["R", "G", "B", "A"].iter().enumerate() {
                ui.selectable_value(&mut p.channel, i, *c);
            }
            if ui.button("remove").clicked() {
                remove = Some(k);
            }
        });
        if let Some(h) = st.probe_history.get(k) {
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
        st.pinned.remove(k);
        if k < st.probe_history.len() {
            st.probe_history.remove(k);
        }
    }
}

pub fn format_value(v: [f32; 4]) -> String {
    v.iter().map(|x| format!("{x:>10.5}")).collect::<Vec<_>>().join(" ")
}

fn viewer_ui(st: &mut State, ui: &mut egui::Ui, id: u32) {
    st.visible_viewers.push(id);
    let Ok(l) = &st.lab else { return };
    let Some(v) = st.viewers.get_mut(&id) else {
        ui.weak("this viewer was closed");
        return;
    };
    let events = v.ui(ui, &l.renderer, &st.hover_values, id);
    if let Some(p) = events.hovered_pixel {
        st.hover = Some(p);
    }
    if let Some(p) = events.pin {
        st.pin_probe(p);
    }
    if let Some(m) = events.message {
        st.set_status(m);
    }
}
