//! The comparison grid in the viewport (View → Compare grid, issue #40 point 1): a toolbar
//! (add a preset or the frozen settings, the truth and its bounces, the memory budget), then
//! the cells side by side: the live settings, the added cells and the truth, each with its
//! image, FLIP map or any buffer, and a caption with its technique, mean FLIP against the
//! truth, frame time, GPU memory and the settings it differs in. Dragging or scrolling in any
//! cell moves the one camera all cells share.

use crate::ui::ERROR;
use crate::ui::grid::{CellSource, CellView, Grid, Shown, Truth, Which};
use crate::ui::state::State;

const CAPTION: f32 = 62.0;

fn toolbar(st: &mut State, ui: &mut egui::Ui) {
    let presets = super::presets::preset_files(&st.args.presets_dir);
    let Ok(l) = &st.lab else { return };
    let Some(g) = &mut st.grid else { return };
    let mut close = false;
    ui.horizontal_wrapped(|ui| {
        ui.strong("Compare grid");
        let full = g.cells.len() >= crate::ui::grid::MAX_CELLS;
        ui.add_enabled_ui(!full, |ui| {
            ui.menu_button("Add cell", |ui| {
                if ui.button("the current settings (frozen)").clicked() {
                    let _ = g.add(&l.renderer, &l.settings, CellSource::Frozen);
                    ui.close();
                }
                ui.separator();
                if presets.is_empty() {
                    ui.label(format!("no presets in {}", st.args.presets_dir.display()));
                }
                for p in &presets {
                    let name = p.file_name().map(|n| n.to_string_lossy().to_string()).unwrap_or_default();
                    if ui.button(&name).clicked() {
                        let _ = g.add(&l.renderer, &l.settings, CellSource::Preset(p.clone()));
                        ui.close();
                    }
                }
            })
            .response
            .on_hover_text("a preset or the live settings frozen, rendered beside the live settings");
        });
        let mut truth = g.truth.is_some();
        let ctx = &l.renderer.ctx;
        let tracer = gi_render::passes::rays::pathtrace::TruthTracer::for_adapter(ctx);
        let hover = format!("{}, refining in the background", tracer.describe(ctx));
        if ui.checkbox(&mut truth, "truth").on_hover_text(hover).changed() {
            let gpu = (tracer == gi_render::passes::rays::pathtrace::TruthTracer::Gpu).then(|| ctx.clone());
            g.truth = truth.then(|| Truth::start(1, gpu));
        }
        if let Some(t) = &mut g.truth {
            ui.add(egui::DragValue::new(&mut t.bounces).range(0..=8).prefix("bounces "));
            ui.label(format!("{} spp", t.spp));
        }
        let mib = g.memory_bytes() as f64 / (1024.0 * 1024.0);
        ui.label(format!("GPU memory of the cells {mib:.0} of"));
        ui.add(egui::DragValue::new(&mut g.memory_budget_mib).range(64..=1_048_576).suffix(" MiB")).on_hover_text(
            "the most GPU memory the added cells may take together; a cell that would pass it is refused",
        );
        if ui.button("Close grid").clicked() {
            close = true;
        }
    });
    if close {
        st.stop_grid();
    }
}

/// The texture of a cell's image, FLIP map or buffer.
fn cell_texture(
    ctx: &egui::Context,
    r: &gi_render::Renderer,
    shown: &mut Shown,
    key: &str,
    image: Option<egui::TextureId>,
) -> Result<egui::TextureId, String> {
    if let Some(img) = shown.pending_map.take() {
        match &mut shown.flip_map {
            Some(h) => h.set(img, egui::TextureOptions::NEAREST),
            None => shown.flip_map = Some(ctx.load_texture(format!("{key}.flip"), img, egui::TextureOptions::NEAREST)),
        }
    }
    match shown.view.clone().unwrap_or(CellView::Image) {
        CellView::Image => image.ok_or_else(|| "no image yet".to_string()),
        CellView::Flip => {
            shown.flip_map.as_ref().map(|h| h.id()).ok_or_else(|| "turn the truth on for FLIP maps".into())
        }
        CellView::Buffer(name) => {
            let kind = r.buffers().get(&name).map(|e| e.kind).map_err(|e| e.to_string())?;
            let what = gi_render::readback::Readback::Image { name: name.clone(), layer: 0, mip: 0 };
            if let Some(a) = r.read_later(&format!("{key}.buffer"), what, 0)
                && let Ok(gi_render::readback::Readout::Image(img)) = &a.data
                && a.frame != shown.buffer_frame
            {
                shown.buffer_frame = a.frame;
                let rgba = gi_render::image_io::to_rgba8(img, kind);
                let ci =
                    egui::ColorImage::from_rgba_unmultiplied([img.width as usize, img.height as usize], rgba.as_raw());
                match &mut shown.buffer {
                    Some(h) => h.set(ci, egui::TextureOptions::NEAREST),
                    None => {
                        shown.buffer = Some(ctx.load_texture(format!("{key}.buf"), ci, egui::TextureOptions::NEAREST))
                    }
                }
            }
            shown.buffer.as_ref().map(|h| h.id()).ok_or_else(|| format!("reading {name} …"))
        }
    }
}

/// The combo that picks what a cell shows.
fn view_combo(ui: &mut egui::Ui, name: &str, shown: &mut Shown, buffers: &[String]) {
    let current = match shown.view.clone().unwrap_or(CellView::Image) {
        CellView::Image => "image".to_string(),
        CellView::Flip => "FLIP map".to_string(),
        CellView::Buffer(b) => b,
    };
    let before = shown.view.clone();
    let combo = egui::ComboBox::from_id_salt(("grid.view", name))
        .selected_text(current)
        .width(110.0)
        .truncate()
        .show_ui(ui, |ui| {
            if ui.selectable_label(matches!(shown.view, None | Some(CellView::Image)), "image").clicked() {
                shown.view = Some(CellView::Image);
            }
            if ui.selectable_label(shown.view == Some(CellView::Flip), "FLIP map").clicked() {
                shown.view = Some(CellView::Flip);
            }
            for b in buffers {
                if ui.selectable_label(shown.view == Some(CellView::Buffer(b.clone())), b).clicked() {
                    shown.view = Some(CellView::Buffer(b.clone()));
                }
            }
        });
    // Its accessible name says whose view it picks (the window's tests find it by that).
    combo.response.widget_info(|| egui::WidgetInfo::labeled(egui::Role::ComboBox, true, format!("view of {name}")));
    if shown.view != before {
        shown.buffer = None;
        shown.buffer_frame = 0;
    }
}

fn flip_text(shown: &Shown, truth: bool) -> String {
    match (shown.flip, truth) {
        (Some(f), _) => format!("FLIP {f:.4} ({} spp)", shown.flip_spp),
        (None, true) => "FLIP …".into(),
        (None, false) => "FLIP: no truth".into(),
    }
}

pub(super) fn grid_ui(st: &mut State, ui: &mut egui::Ui, rect: egui::Rect) {
    toolbar(st, ui);
    let top = ui.min_rect().bottom() + 4.0;
    let area = egui::Rect::from_min_max(egui::pos2(rect.left(), top), rect.right_bottom());
    let Some(g) = &st.grid else { return };
    let n = 1 + g.cells.len() + usize::from(g.truth.is_some());
    let cols = (n as f32).sqrt().ceil().max(1.0) as usize;
    let rows = n.div_ceil(cols);
    let cell = egui::vec2(area.width() / cols as f32, area.height() / rows as f32);
    let image_size = egui::vec2((cell.x - 8.0).max(8.0), (cell.y - CAPTION - 8.0).max(8.0));
    let ppp = ui.ctx().pixels_per_point();
    // The live renderer (and with it every cell, which follows its size) renders at a cell's size.
    st.viewport_px = ((image_size.x * ppp).round() as u32, (image_size.y * ppp).round() as u32);
    st.viewport_rect = area;
    let live_image = st.viewport_texture().map(|(id, _, _)| id);
    let truth_on = st.grid.as_ref().is_some_and(|g| g.truth.is_some());
    let ctx = ui.ctx().clone();
    let Ok(l) = &mut st.lab else { return };
    let Some(g) = &mut st.grid else { return };
    let mut remove = None;
    let mut responses = Vec::new();
    for k in 0..n {
        let at = area.min + egui::vec2((k % cols) as f32 * cell.x + 4.0, (k / cols) as f32 * cell.y + 4.0);
        let img_rect = egui::Rect::from_min_size(at, image_size);
        let caption =
            egui::Rect::from_min_size(at + egui::vec2(0.0, image_size.y + 2.0), egui::vec2(image_size.x, CAPTION));
        let which = if k == 0 {
            Some(Which::Live)
        } else if k <= g.cells.len() {
            Some(Which::Cell(k - 1))
        } else {
            None
        };
        let texture = match which {
            Some(Which::Live) => cell_texture(&ctx, &l.renderer, &mut g.live, "grid.live", live_image),
            Some(Which::Cell(i)) => {
                let c = &mut g.cells[i];
                let image = Some(crate::ui::lab::native_texture(
                    &l.render_state,
                    &mut c.texture,
                    c.renderer.final_ldr(),
                    false,
                ));
                cell_texture(&ctx, &c.renderer, &mut c.shown, &format!("grid.cell{i}"), image)
            }
            None => truth_texture(&ctx, g.truth.as_mut()),
        };
        match texture {
            Ok(id) => {
                ui.painter().image(
                    id,
                    img_rect,
                    egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0)),
                    egui::Color32::WHITE,
                );
            }
            Err(why) => {
                ui.painter().rect_filled(img_rect, 0.0, egui::Color32::from_gray(24));
                ui.painter().text(
                    img_rect.center(),
                    egui::Align2::CENTER_CENTER,
                    why,
                    egui::FontId::proportional(13.0),
                    egui::Color32::LIGHT_GRAY,
                );
            }
        }
        let response = ui.interact(img_rect, ui.scope_id().with(("grid.cell", k)), egui::Sense::click_and_drag());
        responses.push(response);
        ui.scope_builder(egui::UiBuilder::new().max_rect(caption), |ui| {
            ui.set_clip_rect(caption.intersect(ui.clip_rect()));
            ui.spacing_mut().item_spacing.y = 1.0;
            match which {
                Some(Which::Live) => {
                    let buffers = sorted_names(&l.renderer);
                    ui.horizontal(|ui| {
                        view_combo(ui, "live", &mut g.live, &buffers);
                        ui.add(egui::Label::new(egui::RichText::new("live settings").strong()).truncate());
                    });
                    let technique = crate::ui::grid::technique_of(&l.settings);
                    let line =
                        format!("{technique} · {} · {:.1} ms", flip_text(&g.live, truth_on), frame_ms(&l.renderer));
                    ui.add(egui::Label::new(line).truncate());
                    ui.add(egui::Label::new("the settings the panels edit").truncate());
                }
                Some(Which::Cell(i)) => {
                    let c = &mut g.cells[i];
                    let buffers = sorted_names(&c.renderer);
                    ui.horizontal(|ui| {
                        view_combo(ui, &c.name, &mut c.shown, &buffers);
                        if ui.small_button("remove").on_hover_text(format!("remove {} from the grid", c.name)).clicked()
                        {
                            remove = Some(i);
                        }
                        ui.add(egui::Label::new(egui::RichText::new(&c.name).strong()).truncate());
                    });
                    let mem =
                        c.bytes.map_or("memory unknown".to_string(), |b| format!("{:.0} MiB", b as f64 / 1048576.0));
                    let line =
                        format!("{} · {} · {:.1} ms · {mem}", c.technique, flip_text(&c.shown, truth_on), c.frame_ms);
                    ui.add(egui::Label::new(line).truncate());
                    let differs = if c.differs.is_empty() {
                        "the same settings as the live ones".to_string()
                    } else {
                        let names: Vec<&str> = c.differs.iter().map(|d| d.split(" = ").next().unwrap_or(d)).collect();
                        format!("differs in {}: {}", c.differs.len(), names.join(", "))
                    };
                    match &c.error {
                        Some(e) => ui.colored_label(ERROR, e),
                        None => ui.add(egui::Label::new(differs).truncate()).on_hover_text(c.differs.join("\n")),
                    };
                }
                None => {
                    if let Some(t) = &g.truth {
                        ui.strong("truth");
                        let line = format!("{}, {} bounce(s), {} spp", t.tracer, t.bounces, t.spp);
                        ui.add(egui::Label::new(line).truncate());
                    }
                }
            }
        });
    }
    // The last refusal or error, over the grid's foot (not in the layout: a line coming and
    // going would resize every cell and restart their histories and the truth).
    if let Some(m) = &g.message {
        let foot = egui::Rect::from_min_max(egui::pos2(area.left() + 4.0, area.bottom() - 40.0), area.right_bottom());
        ui.painter().rect_filled(foot, 2.0, egui::Color32::from_black_alpha(220));
        ui.put(foot.shrink(4.0), egui::Label::new(egui::RichText::new(m).color(ERROR)).wrap());
    }
    if let Some(i) = remove {
        g.remove(i, &l.render_state);
    }
    for response in &responses {
        super::navigate(l, ui, response);
    }
}

fn sorted_names(r: &gi_render::Renderer) -> Vec<String> {
    let mut v = r.buffers().names();
    v.sort();
    v
}

/// The live renderer's last frame: its passes' GPU times summed (ms).
fn frame_ms(r: &gi_render::Renderer) -> f64 {
    r.timings().iter().map(|t| t.ms).sum()
}

fn truth_texture(ctx: &egui::Context, truth: Option<&mut Truth>) -> Result<egui::TextureId, String> {
    let t = truth.ok_or("no truth")?;
    let Some(img) = t.image.clone() else { return Err("tracing the truth …".into()) };
    if t.texture_spp != t.spp || t.texture.is_none() {
        t.texture_spp = t.spp;
        let rgba = gi_render::image_io::to_rgba8(&img, gi_render::buffers::BufferKind::Hdr);
        let ci = egui::ColorImage::from_rgba_unmultiplied([img.width as usize, img.height as usize], rgba.as_raw());
        match &mut t.texture {
            Some(h) => h.set(ci, egui::TextureOptions::NEAREST),
            None => t.texture = Some(ctx.load_texture("grid.truth", ci, egui::TextureOptions::NEAREST)),
        }
    }
    t.texture.as_ref().map(|h| h.id()).ok_or_else(|| "no truth".to_string())
}

impl State {
    /// Opens the comparison grid (and ends an A/B comparison, whose overlay it replaces).
    pub fn start_grid(&mut self) {
        self.stop_ab();
        if self.grid.is_none() {
            self.grid = Some(Grid::default());
        }
    }

    pub fn stop_grid(&mut self) {
        if let (Some(mut g), Ok(l)) = (self.grid.take(), &self.lab) {
            g.release(&l.render_state);
        }
    }
}
