//! Buffer viewer panels (issue #4 item 3; RenderDoc's texture viewer): any registered
//! buffer picked from a tree of its dotted names, shown through the renderer's view pass
//! (`gi_render::passes::view`) — RGB, one channel or length through viridis / turbo /
//! inferno, a manual, min–max or percentile range, exposure and log scale, a NaN / Inf /
//! negative overlay, layer and level pickers — with nearest-neighbour zoom and pan.
//! Several viewers may be open at once; each owns its GPU view and egui texture.

use gi_render::readback::{Readback, Readout};
use std::time::{Duration, Instant};

use gi_render::buffers::ProbeValue;
use gi_render::passes::view::{BufferView, Colormap, ViewMode, ViewPipeline, ViewSettings};
use gi_render::{Renderer, image_io};
use serde::{Deserialize, Serialize};

/// How a viewer's value range is chosen.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum RangeMode {
    /// The range typed by the user.
    #[default]
    Manual,
    /// Minimum and maximum of the shown values (finite only).
    MinMax,
    /// The [p, 100 − p] percentiles of the shown values.
    Percentile,
}

/// What a viewer shows and how (saved with the session).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ViewerState {
    pub buffer: String,
    pub view: ViewSettings,
    pub range_mode: RangeMode,
    /// p of the percentile range, in percent.
    pub percentile: f32,
    /// Magnification relative to "fit in the panel".
    pub zoom: f32,
    /// The image point (in [0, 1]²) at the panel's centre.
    pub center: [f32; 2],
}

impl Default for ViewerState {
    fn default() -> Self {
        Self {
            buffer: "gbuffer.normal".into(),
            view: ViewSettings::for_kind(gi_render::BufferKind::Direction),
            range_mode: RangeMode::Manual,
            percentile: 1.0,
            zoom: 1.0,
            center: [0.5, 0.5],
        }
    }
}

/// What the user did in a viewer this frame.
#[derive(Default)]
pub struct ViewerEvents {
    /// The hovered texel as a pixel of the frame (for the probe).
    pub hovered_pixel: Option<(u32, u32)>,
    /// A click asks to pin a probe at this frame pixel.
    pub pin: Option<(u32, u32)>,
    /// A status or error message for the status line.
    pub message: Option<String>,
}

/// A viewer's runtime state next to its saved [`ViewerState`].
pub struct Viewer {
    pub state: ViewerState,
    gpu: Option<BufferView>,
    texture: Option<egui::TextureId>,
    slot: Option<(egui::TextureId, (u32, u32))>,
    pub error: Option<String>,
    last_auto: Option<Instant>,
    /// The frame of the last auto-range read-back taken in (it arrives late, without waiting).
    range_frame: Option<u64>,
    /// Buffer size of the last render (texels of the shown level).
    size: (u32, u32),
}

impl Viewer {
    pub fn new(state: ViewerState) -> Self {
        Self {
            state,
            gpu: None,
            texture: None,
            slot: None,
            error: None,
            last_auto: None,
            range_frame: None,
            size: (0, 0),
        }
    }

    /// Switches to another buffer with the first view that suits its kind.
    pub fn show_buffer(&mut self, renderer: &Renderer, name: &str) {
        self.state.buffer = name.to_string();
        if let Ok(e) = renderer.buffers().get(name) {
            self.state.view = ViewSettings::for_kind(e.kind);
        }
        self.state.range_mode =
            if matches!(self.state.view.mode, ViewMode::Rgb) { RangeMode::Manual } else { RangeMode::MinMax };
        self.last_auto = None;
    }

    /// Maps the buffer to colour on the GPU and keeps egui's texture pointing at the result.
    pub fn update(
        &mut self,
        renderer: &Renderer,
        pipeline: &std::sync::Arc<ViewPipeline>,
        render_state: &egui_wgpu::RenderState,
    ) {
        let Ok(entry) = renderer.buffers().get(&self.state.buffer) else {
            self.error = Some(format!("no buffer '{}' in this configuration", self.state.buffer));
            return;
        };
        let t = &entry.texture;
        self.state.view.layer = self.state.view.layer.min(t.depth_or_array_layers() - 1);
        self.state.view.level = self.state.view.level.min(t.mip_level_count() - 1);
        // Auto-range reduced on the GPU by the view pass (min, max and a histogram of the
        // values shown) and read back without waiting, 16 KB (issue #38): asked for every
        // 500 ms, applied when it arrives.
        let mut ask_range = false;
        if self.state.range_mode != RangeMode::Manual {
            let (layer, level) = (self.state.view.layer, self.state.view.level);
            let key = format!("viewer.range:{}@{layer}.{level}", entry.name);
            if let Some(a) = renderer.read_latest(&key)
                && self.range_frame != Some(a.frame)
            {
                self.range_frame = Some(a.frame);
                let p = if self.state.range_mode == RangeMode::MinMax { 0.0 } else { self.state.percentile.max(0.01) };
                match &a.data {
                    Ok(Readout::Bytes(parts)) => {
                        let words: Vec<u32> = parts
                            .first()
                            .map(|b| b.chunks_exact(4).map(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]])).collect())
                            .unwrap_or_default();
                        let ev = self.state.view.exposure_ev;
                        if let Some(r) = gi_render::cpu::view::range_from_stats(&words, ev, p) {
                            self.state.view.range = if r[1] > r[0] { r } else { [r[0], r[0] + 1e-6] };
                        }
                    }
                    Ok(_) => {}
                    Err(e) => self.error = Some(e.clone()),
                }
            }
            if self.last_auto.is_none_or(|at| at.elapsed() > Duration::from_millis(500)) {
                self.last_auto = Some(Instant::now());
                ask_range = true;
                if let Some(gpu) = &self.gpu {
                    let stats = (gpu.range_stats().clone(), gi_render::maths::colormap::RANGE_STATS_BYTES);
                    renderer.read_later(&key, Readback::Storage(vec![stats]), 0);
                }
            }
        }
        let gpu = self.gpu.get_or_insert_with(|| BufferView::new(&renderer.ctx, pipeline.clone()));
        match gpu.render(&renderer.ctx, entry, &self.state.view, ask_range) {
            Ok(recreated) => {
                self.error = None;
                let Some(out) = gpu.output() else { return };
                self.size = (out.width(), out.height());
                self.texture = Some(crate::ui::lab::native_texture(render_state, &mut self.slot, out, recreated));
            }
            Err(e) => self.error = Some(e.to_string()),
        }
    }

    /// The frame whose auto-range statistics the range was last set from (None before any
    /// arrived).
    pub fn auto_range_frame(&self) -> Option<u64> {
        self.range_frame
    }

    /// Drops the GPU view (after a shader reload it is rebuilt with the new pipeline).
    pub fn reset_gpu(&mut self) {
        self.gpu = None;
    }

    /// The view pass's output texture (for the viewport's pass preview).
    pub fn output_texture(&self) -> Option<wgpu::Texture> {
        self.gpu.as_ref().and_then(|g| g.output()).cloned()
    }

    /// Frees the egui texture (the viewer's panel was closed).
    pub fn release(&mut self, render_state: &egui_wgpu::RenderState) {
        self.texture = None;
        if let Some((id, _)) = self.slot.take() {
            render_state.renderer.write().free_texture(&id);
        }
    }

    /// The viewer's panel: controls, then the image. `hover` holds the probe's values of
    /// the hovered pixel (to print this buffer's value under the cursor).
    pub fn ui(&mut self, ui: &mut egui::Ui, renderer: &Renderer, hover: &[ProbeValue], id: u32) -> ViewerEvents {
        let mut events = ViewerEvents::default();
        let names = renderer.buffers().names();
        ui.horizontal_wrapped(|ui| {
            buffer_picker(ui, id, &names, &mut self.state.buffer).then(|| {
                let name = self.state.buffer.clone();
                self.show_buffer(renderer, &name);
            });
            self.controls(ui, renderer, id);
            if ui.button("Save PNG+EXR").on_hover_text("Save this view as PNG and the raw values as EXR").clicked() {
                events.message = Some(self.capture(renderer));
            }
        });
        if let Ok(e) = renderer.buffers().get(&self.state.buffer) {
            ui.small(format!("{} — {:?}, {:?}", e.description, e.texture.format(), e.kind));
        }
        if let Some(e) = &self.error {
            ui.colored_label(egui::Color32::from_rgb(255, 120, 80), e);
        }
        let (rect, response) = ui.allocate_exact_size(ui.available_size(), egui::Sense::click_and_drag());
        ui.painter().rect_filled(rect, 0.0, egui::Color32::from_gray(20));
        let (Some(tex), (bw, bh)) = (self.texture, self.size) else { return events };
        if bw == 0 || bh == 0 || rect.width() < 1.0 || rect.height() < 1.0 {
            return events;
        }
        let fit = (rect.width() / bw as f32).min(rect.height() / bh as f32);
        let scale = fit * self.state.zoom;
        let size = egui::vec2(bw as f32, bh as f32) * scale;
        let c = egui::vec2(self.state.center[0], self.state.center[1]);
        let origin = rect.center() - c * size;
        let image_rect = egui::Rect::from_min_size(origin, size);
        ui.painter_at(rect).image(
            tex,
            image_rect,
            egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0)),
            egui::Color32::WHITE,
        );
        // Zoom about the cursor, pan by dragging, double-click to fit.
        if let Some(p) = response.hover_pos() {
            let scroll = ui.input(|i| i.smooth_scroll_delta.y);
            if scroll != 0.0 {
                let uv = (p - origin) / size;
                self.state.zoom = (self.state.zoom * (scroll * 0.004).exp()).clamp(0.05, 512.0);
                let new_size = egui::vec2(bw as f32, bh as f32) * fit * self.state.zoom;
                let nc = uv - (p - rect.center()) / new_size;
                self.state.center = [nc.x, nc.y];
            }
            let t = (p - origin) / scale;
            if t.x >= 0.0 && t.y >= 0.0 && (t.x as u32) < bw && (t.y as u32) < bh {
                let (tx, ty) = (t.x as u32, t.y as u32);
                let (fw, fh) = renderer.size();
                // The probe reads level 0 of every buffer at the same relative position.
                let full = (bw << self.state.view.level, bh << self.state.view.level);
                let px = ((tx << self.state.view.level) as u64 * fw as u64 / full.0.max(1) as u64) as u32;
                let py = ((ty << self.state.view.level) as u64 * fh as u64 / full.1.max(1) as u64) as u32;
                events.hovered_pixel = Some((px.min(fw - 1), py.min(fh - 1)));
                if response.clicked() {
                    events.pin = events.hovered_pixel;
                }
                let value = hover.iter().find(|v| v.name == self.state.buffer);
                let text = match value {
                    Some(v) => format!(
                        "texel ({tx}, {ty})  value {}",
                        v.value.iter().map(|x| format!("{x:.5}")).collect::<Vec<_>>().join(", ")
                    ),
                    None => format!("texel ({tx}, {ty})"),
                };
                ui.painter().text(
                    rect.left_bottom() + egui::vec2(4.0, -4.0),
                    egui::Align2::LEFT_BOTTOM,
                    text,
                    egui::FontId::monospace(12.0),
                    egui::Color32::WHITE,
                );
            }
        }
        if response.dragged() {
            let d = response.drag_delta() / size;
            self.state.center[0] -= d.x;
            self.state.center[1] -= d.y;
        }
        if response.double_clicked() {
            self.state.zoom = 1.0;
            self.state.center = [0.5, 0.5];
        }
        events
    }

    fn controls(&mut self, ui: &mut egui::Ui, renderer: &Renderer, id: u32) {
        let v = &mut self.state.view;
        egui::ComboBox::from_id_salt(("viewer_mode", id)).selected_text(format!("{:?}", v.mode)).show_ui(ui, |ui| {
            for m in [ViewMode::Rgb, ViewMode::Channel, ViewMode::Length] {
                ui.selectable_value(&mut v.mode, m, format!("{m:?}"));
            }
        });
        if v.mode == ViewMode::Channel {
            for (i, c) in ["R", "G", "B", "A"].iter().enumerate() {
                ui.selectable_value(&mut v.channel, i as u32, *c);
            }
        }
        if v.mode != ViewMode::Rgb {
            egui::ComboBox::from_id_salt(("viewer_map", id)).selected_text(format!("{:?}", v.colormap)).show_ui(
                ui,
                |ui| {
                    for m in Colormap::ALL {
                        ui.selectable_value(&mut v.colormap, m, format!("{m:?}"));
                    }
                },
            );
        }
        let before = self.state.range_mode;
        egui::ComboBox::from_id_salt(("viewer_range", id))
            .selected_text(match self.state.range_mode {
                RangeMode::Manual => "range: manual",
                RangeMode::MinMax => "range: min–max",
                RangeMode::Percentile => "range: percentile",
            })
            .show_ui(ui, |ui| {
                ui.selectable_value(&mut self.state.range_mode, RangeMode::Manual, "manual");
                ui.selectable_value(&mut self.state.range_mode, RangeMode::MinMax, "auto min–max");
                ui.selectable_value(&mut self.state.range_mode, RangeMode::Percentile, "auto percentile");
            });
        if before != self.state.range_mode {
            self.last_auto = None;
        }
        let v = &mut self.state.view;
        if self.state.range_mode == RangeMode::Percentile {
            ui.add(
                egui::DragValue::new(&mut self.state.percentile)
                    .range(0.01..=49.0)
                    .speed(0.1)
                    .prefix("p ")
                    .suffix(" %"),
            );
        }
        let manual = self.state.range_mode == RangeMode::Manual;
        let speed = ((v.range[1] - v.range[0]).abs() * 0.005).max(1e-5);
        ui.add_enabled(manual, egui::DragValue::new(&mut v.range[0]).speed(speed).prefix("min "));
        ui.add_enabled(manual, egui::DragValue::new(&mut v.range[1]).speed(speed).prefix("max "));
        ui.add(egui::DragValue::new(&mut v.exposure_ev).range(-24.0..=24.0).speed(0.05).prefix("EV "))
            .on_hover_text("values are scaled by 2^EV before the range");
        ui.checkbox(&mut v.log, "log").on_hover_text("logarithmic range (values at or below min clamp to min)");
        if v.mode == ViewMode::Rgb {
            ui.checkbox(&mut v.srgb, "sRGB").on_hover_text("apply the sRGB transfer (linear colour data)");
        }
        ui.checkbox(&mut v.flag_nan_inf, "NaN/Inf").on_hover_text("NaN magenta, +-Inf green");
        ui.checkbox(&mut v.flag_negative, "neg").on_hover_text("negative values cyan");
        if let Ok(e) = renderer.buffers().get(&self.state.buffer) {
            let (layers, levels) = (e.texture.depth_or_array_layers(), e.texture.mip_level_count());
            if layers > 1 {
                ui.add(egui::DragValue::new(&mut v.layer).range(0..=layers - 1).prefix("layer "));
            }
            if levels > 1 {
                ui.add(egui::DragValue::new(&mut v.level).range(0..=levels - 1).prefix("level "));
            }
        }
        if ui.small_button("fit").on_hover_text("zoom to fit (double-click the image)").clicked() {
            self.state.zoom = 1.0;
            self.state.center = [0.5, 0.5];
        }
        if ui.small_button("1:1").on_hover_text("one texel per screen pixel").clicked() {
            let ppp = ui.ctx().pixels_per_point();
            let avail = ui.available_rect_before_wrap();
            let fit = (avail.width() / self.size.0.max(1) as f32).min(avail.height() / self.size.1.max(1) as f32);
            self.state.zoom = (1.0 / ppp) / fit.max(1e-6);
        }
    }

    /// Saves the view as PNG and the raw buffer as EXR into `captures/`.
    pub fn capture(&self, renderer: &Renderer) -> String {
        let dir = std::path::PathBuf::from("captures");
        let stamp = crate::ui::capture::capture_stamp();
        let base = dir.join(format!("{}-{stamp}", self.state.buffer));
        let result = (|| -> Result<String, String> {
            std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
            let raw = renderer
                .buffers()
                .readback(&renderer.ctx, &self.state.buffer, self.state.view.layer, self.state.view.level)
                .map_err(|e| e.to_string())?;
            let exr = base.with_extension("exr");
            image_io::save_exr(&exr, &raw).map_err(|e| e.to_string())?;
            let png = base.with_extension("png");
            if let Some(out) = self.gpu.as_ref().and_then(|g| g.output()) {
                let shown =
                    gi_render::buffers::read_texture(&renderer.ctx, "view", out, 0, 0).map_err(|e| e.to_string())?;
                image_io::save_png(&png, &shown, gi_render::BufferKind::Ldr).map_err(|e| e.to_string())?;
            }
            Ok(format!("saved {} and {}", png.display(), exr.display()))
        })();
        result.unwrap_or_else(|e| format!("capture failed: {e}"))
    }
}

/// A combo box listing every buffer as a tree of its dotted names, with a filter field at
/// the top (the list is long: Soler's levels alone add dozens); returns whether the selection
/// changed. Each entry's accessible name is the full dotted name.
pub fn buffer_picker(ui: &mut egui::Ui, id: u32, names: &[String], selected: &mut String) -> bool {
    let mut changed = false;
    let filter_id = egui::Id::unique(("buffer_picker_filter", id));
    // Typing in the filter must not close the list; picking an entry closes it and clears
    // the filter.
    let r = egui::ComboBox::from_id_salt(("buffer_picker", id))
        .selected_text(selected.as_str())
        .height(600.0)
        .close_behavior(egui::PopupCloseBehavior::CloseOnClickOutside)
        .show_ui(ui, |ui| {
            let mut filter: String = ui.data(|d| d.get_temp(filter_id)).unwrap_or_default();
            let edit = ui.add(egui::TextEdit::singleline(&mut filter).hint_text("filter, e.g. level.2"));
            let _ = edit.accessible_name(format!("viewer {id} buffer filter"));
            ui.data_mut(|d| d.insert_temp(filter_id, filter.clone()));
            let mut shown_groups: Vec<String> = Vec::new();
            for name in names.iter().filter(|n| n.contains(filter.trim())) {
                let parts: Vec<&str> = name.split('.').collect();
                // Headers for the groups of this name not shown yet (the tree's inner nodes).
                for depth in 1..parts.len() {
                    let group = parts[..depth].join(".");
                    if !shown_groups.contains(&group) {
                        ui.horizontal(|ui| {
                            ui.add_space(12.0 * (depth - 1) as f32);
                            ui.weak(format!("{}.", parts[depth - 1]));
                        });
                        shown_groups.push(group);
                    }
                }
                ui.horizontal(|ui| {
                    ui.add_space(12.0 * (parts.len() - 1) as f32);
                    let leaf = parts.last().copied().unwrap_or(name);
                    let r = ui.selectable_label(selected == name, leaf).accessible_name(name.as_str());
                    if r.clicked() {
                        *selected = name.clone();
                        changed = true;
                        ui.close();
                        ui.data_mut(|d| d.remove::<String>(filter_id));
                    }
                });
            }
        });
    let _ = r.response.accessible_name(format!("viewer {id} buffer"));
    changed
}
