//! Settings panels, generated from `LabSettings` (docs/principles.md principle 4): one collapsible
//! section per stage with a widget per field chosen from the field's metadata — slider or
//! drag value with unit and range, checkbox, combo — a tooltip (meaning, paper symbol,
//! unit, range, cost), a reset-to-default button and a marker on fields that differ from
//! the loaded preset. Ranges and labels come from `settings_group!`, never from here, so a
//! new field of any pass appears without UI code. Each widget's accessible name is the
//! field's dotted path (`direct.pcf_radius`), which the UI tests use to find it.

use egui::Ui;
use gi_render::LabSettings;
use gi_render::lab_settings::GroupVisitor;
use gi_render::settings::pipeline::{Technique as Choices, Temporal};
use gi_render::settings::{FieldKind, FieldMeta, SettingsGroup, Value};

/// Colour of the "differs from the preset" marker.
pub const CHANGED: egui::Color32 = egui::Color32::from_rgb(255, 176, 64);

/// The label of the field at `path`: its words and the paper's symbol ("splat radius d_max");
/// the unit is in the value box, the path in the tooltip.
pub fn label_of(path: &str) -> String {
    let (group, name) = path.split_once('.').unwrap_or(("", path));
    let meta = LabSettings::groups()
        .into_iter()
        .find(|(g, _)| *g == group)
        .and_then(|(_, fields)| fields.iter().find(|m| m.name == name));
    let words = crate::ui::labels::words(path).map(str::to_string).unwrap_or_else(|| name.replace('_', " "));
    match meta {
        Some(m) if !m.symbol.is_empty() => format!("{words} {}", m.symbol),
        _ => words,
    }
}

pub fn tooltip(m: &FieldMeta) -> String {
    let mut t = m.doc.split('\n').map(str::trim).collect::<Vec<_>>().join(" ").trim().to_string();
    if !m.symbol.is_empty() {
        t += &format!("\nPaper symbol: {}", m.symbol);
    }
    if !m.unit.is_empty() {
        t += &format!("\nUnit: {}", m.unit);
    }
    if matches!(m.kind, FieldKind::F32 | FieldKind::U32) {
        t += &format!("\nRange: {} … {}", m.min, m.max);
    }
    t += &format!("\nCost: {}", m.cost);
    if m.resets_history {
        t += "\nChanging it restarts temporal accumulation.";
    }
    t
}

/// Whether a slider over the field's range should be logarithmic (ranges over 2 decades).
fn logarithmic(m: &FieldMeta) -> bool {
    m.min > 0.0 && m.max / m.min > 100.0
}

fn unit_suffix(m: &FieldMeta) -> String {
    if m.unit.is_empty() { String::new() } else { format!(" {}", m.unit) }
}

/// Width of the value box a slider draws for `v` (its text and unit, with the box's margin).
fn value_box_width(ui: &Ui, m: &FieldMeta, v: &Value) -> f32 {
    let text = match v {
        Value::F32(x) => format!("{x:.3}{}", unit_suffix(m)),
        Value::U32(x) => format!("{x}{}", unit_suffix(m)),
        _ => return 0.0,
    };
    let font = egui::TextStyle::Button.resolve(ui.style());
    ui.painter().layout_no_wrap(text, font, egui::Color32::WHITE).size().x + 2.0 * ui.spacing().button_padding.x
}

/// The widget of one value in `room` points; returns its response (changed when the value
/// changed). The slider's rail takes what the value box leaves, so that the value and its
/// unit are never cut; a choice's box fits the room and shortens its text with "…" (the
/// whole text in its list and tooltip).
fn value_widget(ui: &mut Ui, path: &str, m: &FieldMeta, v: &mut Value, room: f32) -> egui::Response {
    let rail = (room - value_box_width(ui, m, v) - ui.spacing().item_spacing.x - 4.0).clamp(24.0, 95.0);
    ui.spacing_mut().slider_width = rail;
    match v {
        Value::F32(x) => {
            ui.add(egui::Slider::new(x, m.min as f32..=m.max as f32).logarithmic(logarithmic(m)).suffix(unit_suffix(m)))
        }
        Value::U32(x) if gi_render::lab_settings::POWER_OF_TWO_FIELDS.contains(&path) => {
            // Powers of two only: the slider moves the exponent, one step is one doubling.
            let (lo, hi) = ((m.min as u32).max(1).next_power_of_two().ilog2(), (m.max as u32).max(1).ilog2());
            let mut e = (*x).max(1).next_power_of_two().ilog2().clamp(lo, hi);
            let r = ui.add(
                egui::Slider::new(&mut e, lo..=hi)
                    .step_by(1.0)
                    .drag_value_speed(1.0)
                    .custom_formatter(|v, _| format!("{}", 1u64 << (v as u32).min(31)))
                    .custom_parser(|t| t.trim().parse::<f64>().ok().filter(|v| *v >= 1.0).map(|v| v.log2().round()))
                    .suffix(unit_suffix(m)),
            );
            *x = 1 << e;
            r
        }
        Value::U32(x) if m.min == 0.0 && m.max > 1e6 => {
            ui.add(egui::DragValue::new(x).range(m.min as u32..=m.max as u32).suffix(unit_suffix(m)))
        }
        // One keyboard / accessibility step is one unit (a point along the rail would round
        // back to the same integer on short ranges).
        Value::U32(x) => ui.add(
            egui::Slider::new(x, m.min as u32..=m.max as u32)
                .logarithmic(logarithmic(m))
                .step_by(1.0)
                .drag_value_speed(1.0)
                .suffix(unit_suffix(m)),
        ),
        Value::Bool(b) => ui.checkbox(b, ""),
        Value::Choice(c) => {
            let FieldKind::Choice(names) = m.kind else { return ui.label("?") };
            let label_of = |n: &str| {
                names.iter().position(|x| *x == n).and_then(|i| m.labels.get(i)).copied().unwrap_or(n).to_string()
            };
            let mut changed = false;
            let mut r = egui::ComboBox::from_id_salt(path)
                .width((room - 8.0).max(60.0))
                .truncate()
                .selected_text(label_of(c))
                .show_ui(ui, |ui| {
                    // The list shows every choice whole (only the closed box shortens).
                    ui.style_mut().wrap_mode = Some(egui::TextWrapMode::Extend);
                    for n in names.iter() {
                        changed |= ui.selectable_value(c, *n, label_of(n)).changed();
                    }
                })
                .response;
            if changed {
                r.mark_changed();
            }
            r
        }
    }
}

/// A small filled dot (drawn, so it needs no glyph from the font).
fn dot(ui: &mut Ui, colour: Option<egui::Color32>, hover: &str) {
    let (rect, response) = ui.allocate_exact_size(egui::vec2(10.0, 10.0), egui::Sense::hover());
    if let Some(c) = colour {
        ui.painter().circle_filled(rect.center(), 3.5, c);
        response.on_hover_text(hover);
    }
}

/// One row of a settings grid. Returns whether the value changed.
/// `label_width`: the most the label takes (it wraps beyond); `row_width`: the whole row's.
#[allow(clippy::too_many_arguments)]
fn field_row(
    ui: &mut Ui,
    path: &str,
    m: &FieldMeta,
    value: &mut Value,
    default: &Value,
    preset: &Value,
    label_width: f32,
    row_width: f32,
) -> bool {
    let tip = format!("{path}\n{}", tooltip(m));
    let differs = value != preset;
    let label_start = ui.cursor().min.x;
    ui.horizontal(|ui| {
        ui.set_max_width(label_width);
        dot(
            ui,
            differs.then_some(CHANGED),
            &format!("differs from the loaded preset (preset: {preset}{})", unit_suffix(m)),
        );
        ui.add(egui::Label::new(label_of(path)).wrap()).on_hover_text(&tip);
    });
    let mut changed = false;
    ui.horizontal(|ui| {
        // The reset button comes first so that a narrow panel never hides it.
        let reset = ui
            .add_enabled(value != default, egui::Button::new("reset").small())
            .accessible_name(format!("reset {path}"))
            .on_hover_text(format!("reset to the default {default}{}", unit_suffix(m)))
            .on_disabled_hover_text("at its default");
        if reset.clicked() {
            *value = default.clone();
            changed = true;
        }
        // What is left of the row after the label column and the reset button.
        let room = row_width - (ui.cursor().min.x - label_start);
        changed |= value_widget(ui, path, m, value, room).accessible_name(path).on_hover_text(&tip).changed();
    });
    ui.end_row();
    changed
}

/// The generic panel of one settings group: every field of `S`, from its metadata.
pub fn group_ui<S: SettingsGroup>(ui: &mut Ui, s: &mut S, preset: &S) -> bool {
    group_ui_filtered(ui, s, preset, "")
}

/// The paper a group's settings come from (the search finds them by its author's name).
pub fn group_paper(group: &str) -> &'static str {
    match group {
        "vpl" | "ism" | "interleave" | "temporal" | "reference" => "Knecht",
        "hcb" => "Nguyen",
        "soler" => "Soler",
        "gautron" => "Gautron",
        "ddgi" => "Majercik",
        "tonemap" => "Reinhard",
        _ => "",
    }
}

/// Whether the field at `path` matches the settings search `query` (lower case): its path,
/// words, symbol, documentation, section or paper.
pub fn matches_search(path: &str, m: &FieldMeta, query: &str) -> bool {
    if query.is_empty() {
        return true;
    }
    let group = path.split_once('.').map(|(g, _)| g).unwrap_or("");
    [
        path.to_string(),
        label_of(path),
        m.symbol.to_string(),
        m.doc.to_string(),
        section_title(group),
        group_paper(group).to_string(),
    ]
    .iter()
    .any(|t| t.to_lowercase().contains(query))
}

/// [`group_ui`] showing only the fields that match `query` (lower case; empty: all).
pub fn group_ui_filtered<S: SettingsGroup>(ui: &mut Ui, s: &mut S, preset: &S, query: &str) -> bool {
    let d = S::default();
    let mut changed = false;
    // Less the scroll bar, which floats over the panel's right edge.
    let row_width = ui.available_width() - 2.0 * ui.spacing().scroll.bar_width - 4.0;
    let label_width = (0.42 * row_width).max(90.0);
    egui::Grid::new(("settings", S::GROUP)).num_columns(2).striped(true).show(ui, |ui| {
        for m in S::fields() {
            let path = format!("{}.{}", S::GROUP, m.name);
            if !matches_search(&path, m, query) {
                continue;
            }
            let (Some(mut v), Some(dv), Some(pv)) = (s.get(m.name), d.get(m.name), preset.get(m.name)) else {
                continue;
            };
            if field_row(ui, &path, m, &mut v, &dv, &pv, label_width, row_width) {
                // Widgets keep values in range; a failure here would be a metadata bug.
                if let Err(e) = s.set(m.name, &v) {
                    log::error!("{path}: {e}");
                }
                changed = true;
            }
        }
    });
    changed
}

/// Section titles of the groups, in pipeline order (the stage numbers of the pipeline table
/// of docs/principles.md).
pub fn section_title(group: &str) -> String {
    match group {
        "animation" => "Animation clock".into(),
        "direct" => "2 · Direct light".into(),
        "emitters" => "2 · Emissive surfaces as lights".into(),
        "sky" => "2 · Sky light".into(),
        "indirect" => "3–6 · Indirect light".into(),
        "pipeline" => "Stage choices (3–7)".into(),
        "scale" => "Scene scale (relative settings)".into(),
        "vpl" => "3 · VPLs (instant radiosity)".into(),
        "ism" => "4 · VPL visibility (imperfect shadow maps)".into(),
        "interleave" => "5–6 · Interleaved sampling and filter".into(),
        "temporal" => "7 · Temporal coherence".into(),
        "hcb" => "5–6 · Hierarchical coherence buffer (Nguyen)".into(),
        "reference" => "Exact-VPL reference (stages 3, 4, 6)".into(),
        "soler" => "5–6 · Screen-space mip levels (Soler)".into(),
        "gautron" => "5–7 · Irradiance cache splatting (Gautron)".into(),
        "ddgi" => "5–7 · DDGI probes (Majercik et al. 2019, 2021)".into(),
        "tonemap" => "7 · Tone mapping".into(),
        other => other.to_string(),
    }
}

/// A technique: a named set of stage choices (the pipeline table of docs/principles.md).
pub struct Technique {
    pub name: &'static str,
    pub source: &'static str,
    pub apply: fn(&mut LabSettings),
    pub is: fn(&LabSettings) -> bool,
}

/// The techniques of the picker: each is a named set of stage choices
/// (`gi_render::settings::pipeline::Technique`); after picking one, every stage can be changed alone.
pub const TECHNIQUES: &[Technique] = &[
    Technique {
        name: "Direct light only",
        source: "stages 1, 2, 7",
        apply: |s| Choices::DirectOnly.apply(s),
        is: |s| Choices::of(&s.pipeline) == Some(Choices::DirectOnly),
    },
    Technique {
        name: "Exact-VPL reference",
        source: "Knecht 002 §5.2: many VPLs, exact visibility, accumulated",
        apply: |s| Choices::ExactVpl.apply(s),
        is: |s| Choices::of(&s.pipeline) == Some(Choices::ExactVpl),
    },
    Technique {
        name: "Instant radiosity + ISM + temporal coherence (Knecht)",
        source: "Knecht 002 ch. 3–4: importance-warped VPLs, imperfect shadow maps, interleaved sampling, confidence merge",
        apply: |s| Choices::Knecht.apply(s),
        is: |s| Choices::of(&s.pipeline) == Some(Choices::Knecht),
    },
    Technique {
        name: "Hierarchical coherence buffer (Nguyen)",
        source: "Nguyen et al. 000 §3–4: VPLs gathered at HCB samples, coherence-weighted splatting",
        apply: |s| Choices::Nguyen.apply(s),
        is: |s| Choices::of(&s.pipeline) == Some(Choices::Nguyen),
    },
    Technique {
        name: "Hierarchical coherence buffer with the sample cache (Nguyen)",
        source: "Nguyen et al. 000 §5: samples reused from frame to frame, new ones only where texels stay incomplete, a quarter recomputed per frame",
        apply: |s| {
            Choices::NguyenCached.apply(s);
            // Cached samples gathered in different frames must see the same VPLs.
            s.vpl.new_set_each_frame = false;
        },
        is: |s| Choices::of(&s.pipeline) == Some(Choices::NguyenCached),
    },
    Technique {
        name: "Imperfect shadow maps without temporal coherence (Ritschel)",
        source: "Knecht 002 §5.2's baseline: Ritschel et al. 2008, a new image every frame",
        apply: |s| {
            Choices::Knecht.apply(s);
            s.pipeline.temporal = Temporal::None;
        },
        is: |s| {
            let mut ritschel = Choices::Knecht.choices(&s.pipeline);
            ritschel.temporal = Temporal::None;
            s.pipeline == ritschel
        },
    },
    Technique {
        name: "Screen-space mip levels (Soler)",
        source: "Soler et al. 004 §3–4: voted mip levels, ring gather with the point-to-disc form factor, joint bilateral upsampling, Eq. 6's temporal filter (visibility, bounces and the glossy reflection are settings)",
        apply: |s| Choices::Soler.apply(s),
        is: |s| Choices::of(&s.pipeline) == Some(Choices::Soler),
    },
    Technique {
        name: "Near field screen-space (Soler), far field VPLs (Knecht)",
        source: "GI Lab's mix: Soler et al. 004 for senders closer than soler.near_field_distance, Knecht 002's instant radiosity beyond it",
        apply: |s| Choices::SolerNearKnechtFar.apply(s),
        is: |s| Choices::of(&s.pipeline) == Some(Choices::SolerNearKnechtFar),
    },
    Technique {
        name: "Screen-space gather at HCB samples (Nguyen + Soler)",
        source: "GI Lab's mix: Soler et al. 004's rings of every level gathered at Nguyen et al. 000's HCB samples only, spread by coherence splatting",
        apply: |s| Choices::SolerAtHcbSamples.apply(s),
        is: |s| Choices::of(&s.pipeline) == Some(Choices::SolerAtHcbSamples),
    },
    Technique {
        name: "Irradiance cache splatting (Gautron)",
        source: "Gautron et al. 003: records where the coverage is insufficient, hemispheres rasterized and reduced to irradiance and gradients, Ward's weights splatted, the records kept across frames",
        apply: |s| Choices::Gautron.apply(s),
        is: |s| Choices::of(&s.pipeline) == Some(Choices::Gautron),
    },
    Technique {
        name: "Irradiance records lit by VPLs (Gautron + Knecht)",
        source: "GI Lab's mix: Gautron et al. 003's records, splatting and cache, each record lit by Knecht 002's VPLs and their visibility instead of a rasterized hemisphere",
        apply: |s| Choices::GautronVplRecords.apply(s),
        is: |s| Choices::of(&s.pipeline) == Some(Choices::GautronVplRecords),
    },
    Technique {
        name: "Hemispheres at HCB samples (Nguyen + Gautron)",
        source: "GI Lab's mix: Gautron et al. 003's rasterized hemisphere at each of Nguyen et al. 000's HCB samples, spread by coherence splatting",
        apply: |s| Choices::GautronAtHcbSamples.apply(s),
        is: |s| Choices::of(&s.pipeline) == Some(Choices::GautronAtHcbSamples),
    },
    Technique {
        name: "DDGI probes (Majercik et al.)",
        source: "Majercik et al. 2019, 2021: a probe grid tracing rays every frame through the GPU ray caster, octahedral irradiance and distance moments with hysteresis, Chebyshev visibility, classification and relocation, read at every pixel",
        apply: |s| Choices::Ddgi.apply(s),
        is: |s| Choices::of(&s.pipeline) == Some(Choices::Ddgi),
    },
];

/// The technique picker: sets the stage choices of one technique at once.
pub fn technique_picker(ui: &mut Ui, s: &mut LabSettings) -> bool {
    let current = TECHNIQUES.iter().find(|t| (t.is)(s)).map(|t| t.name).unwrap_or("custom combination");
    let mut changed = false;
    ui.horizontal(|ui| {
        ui.label("Technique");
        let room = ui.available_width() - 2.0 * ui.spacing().scroll.bar_width - 4.0;
        egui::ComboBox::from_id_salt("technique_picker")
            .width(room.max(80.0))
            .truncate()
            .selected_text(current)
            .show_ui(ui, |ui| {
                ui.style_mut().wrap_mode = Some(egui::TextWrapMode::Extend);
                for t in TECHNIQUES {
                    if ui.selectable_label((t.is)(s), t.name).on_hover_text(t.source).clicked() {
                        (t.apply)(s);
                        changed = true;
                    }
                }
            });
    });
    changed
}

/// What the panel knows beyond the settings: the search and the groups that cannot act on
/// this scene, with why.
#[derive(Default)]
pub struct PanelContext {
    /// The search box's text (any case; empty: every field).
    pub search: String,
    /// (group, why) of the groups that cannot act on this scene ("no emissive surfaces in
    /// this scene"): they fold into one line that says so.
    pub idle_groups: Vec<(&'static str, String)>,
}

/// The whole settings panel: technique picker, then one section per group. `preset` is
/// the loaded preset (for the markers). Returns whether anything changed.
pub fn lab_settings_ui(ui: &mut Ui, s: &mut LabSettings, preset: &LabSettings, cx: &PanelContext) -> bool {
    /// Visits the groups in use (`in_use`) or the others.
    struct Sections<'a> {
        ui: &'a mut Ui,
        changed: bool,
        pipeline: gi_render::settings::pipeline::PipelineSettings,
        in_use: bool,
        query: String,
        idle: &'a [(&'static str, String)],
    }
    impl GroupVisitor for Sections<'_> {
        fn visit<S: SettingsGroup>(&mut self, s: &mut S, preset: &S) {
            let group = S::GROUP;
            if !self.query.is_empty() {
                // Searching: every group with a matching field, open, whether in use or not.
                if !self.in_use
                    || !S::fields().iter().any(|m| matches_search(&format!("{group}.{}", m.name), m, &self.query))
                {
                    return;
                }
                let changed = &mut self.changed;
                egui::CollapsingHeader::new(section_title(group))
                    .id_salt(("search", group))
                    .open(Some(true))
                    .show(self.ui, |ui| *changed |= group_ui_filtered(ui, s, preset, &self.query));
                return;
            }
            if self.pipeline.group_in_use(group) != self.in_use {
                return;
            }
            let mut title = egui::RichText::new(section_title(group));
            if s != preset {
                title = title.color(CHANGED);
            }
            if let Some((_, why)) = self.idle.iter().find(|(g, _)| *g == group) {
                // Cannot act on this scene: one line that says why, folded (still editable).
                let changed = &mut self.changed;
                egui::CollapsingHeader::new(egui::RichText::new(format!("{} — {why}", section_title(group))).weak())
                    .id_salt(("idle", group))
                    .default_open(false)
                    .show(self.ui, |ui| *changed |= group_ui(ui, s, preset));
                return;
            }
            // Sections of stages no choice runs stay folded, their titles greyed.
            let open =
                self.in_use && !matches!(group, "animation" | "reference" | "vpl" | "ism" | "interleave" | "temporal");
            if !self.in_use {
                title = title.weak();
            }
            let changed = &mut self.changed;
            egui::CollapsingHeader::new(title).id_salt(group).default_open(open).show(self.ui, |ui| {
                *changed |= group_ui(ui, s, preset);
            });
        }
    }
    let changed = technique_picker(ui, s);
    ui.separator();
    // The stage choices and the settings that act on the image first; the settings of
    // stages no choice uses folded under "not in use".
    let pipeline = s.pipeline.clone();
    let query = cx.search.trim().to_lowercase();
    let idle = &cx.idle_groups;
    let mut v = Sections { ui, changed: false, pipeline: pipeline.clone(), in_use: true, query: query.clone(), idle };
    s.visit_groups(preset, &mut v);
    let mut changed = changed | v.changed;
    if !query.is_empty() {
        return changed;
    }
    egui::CollapsingHeader::new("Not in use (stages the current choices do not run)")
        .id_salt("not_in_use")
        .default_open(true)
        .show(ui, |ui| {
            let mut v = Sections { ui, changed: false, pipeline, in_use: false, query, idle };
            s.visit_groups(preset, &mut v);
            changed |= v.changed;
        });
    changed
}
