//! Settings panels: one function per pass (DESIGN.md principle 4). Each starts by
//! destructuring its `Settings` so that a new field breaks the build until it has a
//! widget; the widgets themselves are driven by the field's metadata (range, unit,
//! symbol, documentation), never by ranges repeated here.

use egui::Ui;
use gi_render::lab_settings::{IndirectSettings, IndirectTechnique};
use gi_render::passes::compose::TonemapSettings;
use gi_render::passes::direct::DirectSettings;
use gi_render::passes::vpl::ReferenceSettings;
use gi_render::settings::{FieldKind, FieldMeta, SettingsGroup};

fn meta<S: SettingsGroup>(name: &str) -> &'static FieldMeta {
    S::fields().iter().find(|m| m.name == name).unwrap_or_else(|| {
        panic!("{}.{name} has no metadata: the settings_group! declaration is out of sync", S::GROUP)
    })
}

fn tooltip(m: &FieldMeta) -> String {
    let mut t = m.doc.trim().to_string();
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
    t
}

fn label(ui: &mut Ui, m: &FieldMeta) {
    let text = if m.symbol.is_empty() {
        m.name.replace('_', " ")
    } else {
        format!("{} ({})", m.name.replace('_', " "), m.symbol)
    };
    ui.label(text).on_hover_text(tooltip(m));
}

/// One row of a settings grid: the label with its tooltip, the widget, and a reset
/// button enabled when the value differs from the default.
fn row<T: PartialEq + Copy>(
    ui: &mut Ui,
    m: &FieldMeta,
    value: &mut T,
    default: T,
    widget: impl FnOnce(&mut Ui, &mut T) -> egui::Response,
) -> bool {
    let mut changed = false;
    label(ui, m);
    ui.horizontal(|ui| {
        changed |= widget(ui, value).on_hover_text(tooltip(m)).changed();
        let reset = ui.add_enabled(*value != default, egui::Button::new("reset").small());
        if reset.on_hover_text("reset to default").clicked() {
            *value = default;
            changed = true;
        }
    });
    ui.end_row();
    changed
}

/// Whether a slider over the field's range should be logarithmic (ranges over 2 decades).
fn logarithmic(m: &FieldMeta) -> bool {
    m.min > 0.0 && m.max / m.min > 100.0
}

/// A slider for an f32 field with its range and unit.
pub fn f32_field(ui: &mut Ui, m: &FieldMeta, value: &mut f32, default: f32) -> bool {
    row(ui, m, value, default, |ui, v| {
        ui.add(
            egui::Slider::new(v, m.min as f32..=m.max as f32)
                .logarithmic(logarithmic(m))
                .suffix(format!(" {}", m.unit)),
        )
    })
}

/// A slider for a u32 field with its range and unit (a drag value for ranges too wide to
/// slide over, such as seeds).
pub fn u32_field(ui: &mut Ui, m: &FieldMeta, value: &mut u32, default: u32) -> bool {
    if m.min == 0.0 && m.max > 1e6 {
        return row(ui, m, value, default, |ui, v| {
            ui.add(egui::DragValue::new(v).range(m.min as u32..=m.max as u32).suffix(format!(" {}", m.unit)))
        });
    }
    row(ui, m, value, default, |ui, v| {
        ui.add(
            egui::Slider::new(v, m.min as u32..=m.max as u32)
                .logarithmic(logarithmic(m))
                .suffix(format!(" {}", m.unit)),
        )
    })
}

/// A checkbox for a bool field.
pub fn bool_field(ui: &mut Ui, m: &FieldMeta, value: &mut bool, default: bool) -> bool {
    row(ui, m, value, default, |ui, v| ui.checkbox(v, ""))
}

/// A combo box over the choices of an enum field; `labels` in the order of `values`.
pub fn choice_field<T: PartialEq + Copy>(
    ui: &mut Ui,
    m: &FieldMeta,
    value: &mut T,
    default: T,
    values: &[T],
    labels: &[&str],
) -> bool {
    row(ui, m, value, default, |ui, v| {
        let current = values.iter().position(|x| x == v).and_then(|i| labels.get(i)).copied().unwrap_or("?");
        let mut changed = false;
        let mut r = egui::ComboBox::from_id_salt(m.name)
            .selected_text(current)
            .show_ui(ui, |ui| {
                for (x, l) in values.iter().zip(labels) {
                    changed |= ui.selectable_value(v, *x, *l).changed();
                }
            })
            .response;
        if changed {
            r.mark_changed();
        }
        r
    })
}

/// Indirect light: the technique of stages 3–6.
pub fn indirect_settings_ui(s: &mut IndirectSettings, ui: &mut Ui) -> bool {
    let d = IndirectSettings::default();
    let IndirectSettings { technique } = s;
    type S = IndirectSettings;
    let mut c = false;
    egui::Grid::new("indirect_settings").num_columns(2).striped(true).show(ui, |ui| {
        let values = [IndirectTechnique::None, IndirectTechnique::ExactVpl];
        c |= choice_field(ui, meta::<S>("technique"), technique, d.technique, &values, IndirectTechnique::LABELS);
    });
    c
}

/// The exact-VPL reference (stages 3, 4 and 6 of the reference).
pub fn reference_settings_ui(s: &mut ReferenceSettings, ui: &mut Ui) -> bool {
    let d = ReferenceSettings::default();
    let ReferenceSettings {
        vpls_per_frame,
        total_vpls,
        light_gbuffer_size,
        shadow_map_size,
        visibility,
        min_distance_m,
        depth_bias,
        normal_offset,
        seed,
    } = s;
    type S = ReferenceSettings;
    let mut c = false;
    egui::Grid::new("reference_settings").num_columns(2).striped(true).show(ui, |ui| {
        c |= u32_field(ui, meta::<S>("vpls_per_frame"), vpls_per_frame, d.vpls_per_frame);
        c |= u32_field(ui, meta::<S>("total_vpls"), total_vpls, d.total_vpls);
        c |= u32_field(ui, meta::<S>("light_gbuffer_size"), light_gbuffer_size, d.light_gbuffer_size);
        c |= u32_field(ui, meta::<S>("shadow_map_size"), shadow_map_size, d.shadow_map_size);
        c |= bool_field(ui, meta::<S>("visibility"), visibility, d.visibility);
        c |= f32_field(ui, meta::<S>("min_distance_m"), min_distance_m, d.min_distance_m);
        c |= f32_field(ui, meta::<S>("depth_bias"), depth_bias, d.depth_bias);
        c |= f32_field(ui, meta::<S>("normal_offset"), normal_offset, d.normal_offset);
        c |= u32_field(ui, meta::<S>("seed"), seed, d.seed);
    });
    c
}

/// Direct light and shadow maps (stage 2).
pub fn direct_settings_ui(s: &mut DirectSettings, ui: &mut Ui) -> bool {
    let d = DirectSettings::default();
    let DirectSettings { intensity_scale, shadows, shadow_map_size, pcf_radius, depth_bias, normal_offset } = s;
    type S = DirectSettings;
    let mut c = false;
    egui::Grid::new("direct_settings").num_columns(2).striped(true).show(ui, |ui| {
        c |= f32_field(ui, meta::<S>("intensity_scale"), intensity_scale, d.intensity_scale);
        c |= bool_field(ui, meta::<S>("shadows"), shadows, d.shadows);
        c |= u32_field(ui, meta::<S>("shadow_map_size"), shadow_map_size, d.shadow_map_size);
        c |= u32_field(ui, meta::<S>("pcf_radius"), pcf_radius, d.pcf_radius);
        c |= f32_field(ui, meta::<S>("depth_bias"), depth_bias, d.depth_bias);
        c |= f32_field(ui, meta::<S>("normal_offset"), normal_offset, d.normal_offset);
    });
    c
}

/// Tone mapping (stage 7).
pub fn tonemap_settings_ui(s: &mut TonemapSettings, ui: &mut Ui) -> bool {
    let d = TonemapSettings::default();
    let TonemapSettings { exposure_ev, auto_exposure, key, white_point } = s;
    type S = TonemapSettings;
    let mut c = false;
    egui::Grid::new("tonemap_settings").num_columns(2).striped(true).show(ui, |ui| {
        c |= f32_field(ui, meta::<S>("exposure_ev"), exposure_ev, d.exposure_ev);
        c |= bool_field(ui, meta::<S>("auto_exposure"), auto_exposure, d.auto_exposure);
        c |= f32_field(ui, meta::<S>("key"), key, d.key);
        c |= f32_field(ui, meta::<S>("white_point"), white_point, d.white_point);
    });
    c
}
