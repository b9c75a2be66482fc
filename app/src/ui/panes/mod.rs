//! The lab's panels as egui_tiles panes: viewport, settings, scene and timeline, presets,
//! GPU timings, probes and buffer viewers. Panels can be dragged, tabbed and resized; the
//! layout is part of the session.

mod ddgi_overlay;
mod explain;
mod grid;
mod history;
mod light_gizmo;
mod lights;
mod presets;
mod probes;
mod scene;
mod settings;
mod timings;
mod viewport;

use crate::ui::session::Pane;
use crate::ui::state::State;
use presets::presets_ui;
pub use probes::format_value;
use probes::probe_ui;
use scene::scene_ui;
use settings::settings_ui;
use timings::timings_ui;
use viewport::viewport_ui;

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
            Pane::History => "History".into(),
            Pane::Explain => "Explain".into(),
            Pane::Viewer(id) => {
                let name = self.state.viewers.open.get(id).map(|v| v.state.buffer.as_str()).unwrap_or("?");
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
            Pane::Timings => {
                if let Ok(l) = &st.lab {
                    timings_ui(&mut st.timings, l, ui);
                }
            }
            Pane::Probe => {
                if let Ok(l) = &st.lab {
                    scrolled(ui, "probe", |ui| probe_ui(&mut st.probes, l, ui));
                }
            }
            Pane::History => {
                let mut jump = None;
                scrolled(ui, "history", |ui| jump = history::history_ui(&st.history, ui));
                if let Some(k) = jump {
                    st.jump_to(k);
                }
            }
            Pane::Explain => explain::explain_ui(&mut st.explain, ui),
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

fn viewer_ui(st: &mut State, ui: &mut egui::Ui, id: u32) {
    st.viewers.visible.push(id);
    let Ok(l) = &st.lab else { return };
    let Some(v) = st.viewers.open.get_mut(&id) else {
        ui.weak("this viewer was closed");
        return;
    };
    let events = v.ui(ui, &l.renderer, &st.probes.values, id);
    if let Some(p) = events.hovered_pixel {
        st.probes.hover = Some(p);
    }
    if let Some(p) = events.pin {
        st.pin_probe(p);
    }
    if let Some(m) = events.message {
        st.set_status(m);
    }
}

/// Orbit, fly and dolly the camera of `l` by the viewport's (or a compare cell's) drags,
/// WASD/QE keys and scroll.
fn navigate(l: &mut crate::ui::lab::Lab, ui: &egui::Ui, response: &egui::Response) {
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

/// A line of text on a dark plate at the viewport's bottom left (the overlays' captions).
fn caption(painter: &egui::Painter, rect: egui::Rect, s: String) {
    let galley = painter.layout_no_wrap(s, egui::FontId::proportional(14.0), egui::Color32::WHITE);
    let pos = rect.left_bottom() + egui::vec2(8.0, -8.0 - galley.size().y);
    painter.rect_filled(
        egui::Rect::from_min_size(pos, galley.size()).expand(4.0),
        3.0,
        egui::Color32::from_black_alpha(200),
    );
    painter.galley(pos, galley, egui::Color32::WHITE);
}
