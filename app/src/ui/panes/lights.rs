//! The Scene panel's lights (issue #18 point 4): add a point, spot or directional light where
//! the camera looks, duplicate or remove any light, edit its place (or direction), colour,
//! intensity and spot cones; the sky light (point 2); save them beside the scene or reset them
//! to the file's.

use crate::scene_lights::{self, NewLight};
use crate::ui::lab::Lab;

/// Draws the controls; returns a message for the status bar (saving, resetting).
pub(super) fn light_controls(l: &mut Lab, ui: &mut egui::Ui) -> Option<String> {
    let r = l.renderer.bounds().radius();
    let mut changed = false;
    let mut message = None;
    ui.horizontal(|ui| {
        ui.label("add light");
        for (kind, label) in
            [(NewLight::Point, "point"), (NewLight::Spot, "spot"), (NewLight::Directional, "directional")]
        {
            if ui.button(label).on_hover_text(format!("add a {label} light where the camera looks")).clicked() {
                let c = l.renderer.camera;
                scene_lights::add_light(l.renderer.scene_mut(), kind, c.position, c.forward(), r);
                changed = true;
            }
        }
    });
    let light_nodes: Vec<usize> =
        l.renderer.scene().nodes.iter().enumerate().filter(|(_, n)| n.light.is_some()).map(|(i, _)| i).collect();
    emitter_controls(l, ui);
    changed |= sky_controls(l, ui);
    if light_nodes.is_empty() && l.renderer.emitter_stats().is_none() && !l.renderer.scene().sky.is_lit() {
        ui.small("no lights: the image has no direct light (add one above)");
    }
    let mut remove = None;
    let mut duplicate = None;
    // The light selected in the viewport: its section opens (once) and scrolls into view; a
    // click on a section's header selects its light there.
    let (selected, reveal) = (l.selected_light, std::mem::take(&mut l.reveal_selected));
    let mut clicked = None;
    for (k, &ni) in light_nodes.iter().enumerate() {
        let scene = l.renderer.scene_mut();
        let Some(li) = scene.nodes[ni].light else { continue };
        let name = scene.lights[li].name.clone();
        let directional = matches!(scene.lights[li].kind, gi_render::scene::LightKind::Directional);
        let reveal_this = reveal && selected == Some(ni);
        let section = egui::CollapsingHeader::new(format!("Light {k}: {name}"))
            .id_salt(("light", ni))
            .default_open(k == 0)
            .open(reveal_this.then_some(true))
            .show(ui, |ui| {
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
                            let value = *c as f64;
                            let field = ui.add(
                                egui::DragValue::new(c).speed(r * 0.005).max_decimals(3).prefix(format!("{axis} ")),
                            );
                            // Named for assistive technology (and the UI tests): "light 1 y".
                            field.widget_info(|| {
                                let mut info = egui::WidgetInfo::drag_value(true, value);
                                info.label = Some(format!("light {k} {axis}"));
                                info
                            });
                            changed |= field.changed();
                        }
                    });
                }
                let light = &mut scene.lights[li];
                ui.horizontal(|ui| {
                    ui.label("intensity");
                    changed |= ui
                        .add(egui::Slider::new(&mut light.intensity, 0.0..=100_000.0).logarithmic(true))
                        .on_hover_text("candela (W/sr) for point and spot lights, lux (W/m²) for directional lights")
                        .changed();
                });
                ui.horizontal(|ui| {
                    ui.label("colour");
                    let mut c = light.color.to_array();
                    if ui.color_edit_button_rgb(&mut c).changed() {
                        light.color = glam::Vec3::from_array(c);
                        changed = true;
                    }
                });
                if let gi_render::scene::LightKind::Spot { inner_cone, outer_cone } = &mut light.kind {
                    ui.horizontal(|ui| {
                        let (mut inner, mut outer) = (inner_cone.to_degrees(), outer_cone.to_degrees());
                        ui.label("cone");
                        let a = ui.add(egui::DragValue::new(&mut inner).range(0.0..=90.0).suffix("° inner"));
                        let b = ui.add(egui::DragValue::new(&mut outer).range(0.1..=90.0).suffix("° outer"));
                        if a.changed() || b.changed() {
                            *outer_cone = outer.to_radians();
                            *inner_cone = inner.min(outer).to_radians();
                            changed = true;
                        }
                    });
                }
                ui.horizontal(|ui| {
                    if ui.button(format!("duplicate light {k}")).clicked() {
                        duplicate = Some(ni);
                    }
                    if ui.button(format!("remove light {k}")).clicked() {
                        remove = Some(ni);
                    }
                });
            });
        if reveal_this {
            section.header_response.scroll_to_me(Some(egui::Align::TOP));
        }
        if section.header_response.clicked() {
            clicked = Some(ni);
        }
    }
    if clicked.is_some() {
        l.selected_light = clicked;
    }
    if let Some(ni) = duplicate {
        scene_lights::duplicate_light(l.renderer.scene_mut(), ni, r);
        changed = true;
    }
    if let Some(ni) = remove {
        scene_lights::remove_light(l.renderer.scene_mut(), ni);
        changed = true;
    }
    ui.horizontal(|ui| {
        let path = l.scene_path.clone();
        let save = ui
            .add_enabled(path.is_some(), egui::Button::new("save lights beside the scene"))
            .on_hover_text("writes <scene file>.lights.ron next to the glTF (never the glTF itself); it is applied whenever that scene is opened");
        if save.clicked()
            && let Some(p) = &path
        {
            message = Some(match scene_lights::save_overrides(l.renderer.scene(), p) {
                Ok(f) => format!("lights saved to {}", f.display()),
                Err(e) => format!("lights not saved: {e}"),
            });
        }
        if ui.button("reset lights").on_hover_text("the lights as the scene file (and its saved lights) have them").clicked() {
            let args = crate::scene_args::SceneArgs { scene: path.clone(), unit_scale: l.unit_scale, ..Default::default() };
            match crate::scene_args::load_scene(&args) {
                Ok(fresh) => {
                    let scene = l.renderer.scene_mut();
                    scene.nodes = fresh.nodes;
                    scene.roots = fresh.roots;
                    scene.lights = fresh.lights;
                    changed = true;
                    message = Some("lights reset to the scene's".into());
                }
                Err(e) => message = Some(format!("lights not reset: {}", e.message)),
            }
        }
    });
    if changed {
        l.renderer.reset_history_but_records();
    }
    message
}

/// Emissive surfaces as lights: the toggle (`emitters.enabled`), their power and the VPLs
/// they get (issue #18 point 1).
fn emitter_controls(l: &mut Lab, ui: &mut egui::Ui) {
    if !l.renderer.scene().has_emitters() {
        return;
    }
    let mut on = l.settings.emitters.enabled;
    if ui
        .checkbox(&mut on, "emissive surfaces are lights")
        .on_hover_text("off: emissive surfaces only glow (emitters.enabled)")
        .changed()
    {
        l.settings.emitters.enabled = on;
        l.apply_settings();
    }
    match l.renderer.emitter_stats() {
        Some(e) => {
            ui.small(format!(
                "emitters: {} triangles, {:.3} W, {:.3} m²; {} VPLs for their direct light",
                e.triangles, e.power, e.area, e.vpls
            ));
            if e.bounce_budget > 0 {
                let share = 100.0 * e.bounce_share as f32 / e.bounce_budget as f32;
                ui.small(format!(
                    "first bounce: {} of stage 3's {} VPLs ({share:.0} %)",
                    e.bounce_share, e.bounce_budget
                ));
            }
        }
        None => {
            ui.small("emitters only glow");
        }
    }
}

/// The sky light (issue #18 point 2): on or off, a constant colour or an equirectangular
/// `.hdr` / `.exr` image, its radiance scale and rotation; the lab samples it in
/// `sky.directions` directional VPLs. Returns whether the sky changed.
fn sky_controls(l: &mut Lab, ui: &mut egui::Ui) -> bool {
    let mut changed = false;
    let directions = l.settings.sky.directions;
    egui::CollapsingHeader::new("Sky light").id_salt("sky").default_open(l.renderer.scene().sky.enabled).show(
        ui,
        |ui| {
            let sky = &mut l.renderer.scene_mut().sky;
            changed |= ui
                .checkbox(&mut sky.enabled, "sky lights the scene")
                .on_hover_text("a sky around the scene, for outdoor scenes; saved with the lights beside the scene")
                .changed();
            if sky.intensity == 0.0 && sky.color == glam::Vec3::ZERO && sky.enabled {
                sky.color = glam::Vec3::new(0.6, 0.75, 1.0);
                sky.intensity = 1.0;
                changed = true;
            }
            ui.horizontal(|ui| {
                ui.label("radiance");
                changed |= ui
                    .add(egui::DragValue::new(&mut sky.intensity).range(0.0..=1.0e5).speed(0.01).suffix(" W/(m²·sr)"))
                    .changed();
                if sky.image.is_none() {
                    let mut c = sky.color.to_array();
                    if ui.color_edit_button_rgb(&mut c).on_hover_text("the constant sky's linear colour").changed() {
                        sky.color = glam::Vec3::from(c);
                        changed = true;
                    }
                }
            });
            let id = ui.make_persistent_id("sky image path");
            let error_id = ui.make_persistent_id("sky image error");
            let mut text = ui.data_mut(|d| d.get_temp::<String>(id)).unwrap_or_default();
            // The last load's error stays until the next load (a click's frame is too short
            // to read it).
            let mut error = ui.data_mut(|d| d.get_temp::<String>(error_id));
            ui.horizontal(|ui| {
                ui.label("image");
                ui.add(
                    egui::TextEdit::singleline(&mut text)
                        .hint_text("equirectangular .hdr or .exr")
                        .desired_width(160.0),
                )
                .accessible_name("sky image path");
                if ui.button("load").clicked() {
                    match sky.load_image(std::path::Path::new(text.trim())) {
                        Ok(()) => {
                            changed = true;
                            error = None;
                        }
                        Err(e) => error = Some(e),
                    }
                }
                if sky.image.is_some() && ui.button("constant colour").clicked() {
                    sky.image = None;
                    changed = true;
                }
            });
            ui.data_mut(|d| {
                d.insert_temp(id, text);
                match &error {
                    Some(e) => {
                        d.insert_temp(error_id, e.clone());
                    }
                    None => d.remove::<String>(error_id),
                }
            });
            if let Some(e) = error {
                ui.colored_label(ui.visuals().error_fg_color, format!("sky image not loaded: {e}"));
            }
            if let Some((p, map)) = &sky.image {
                ui.small(format!("{} ({}×{})", p.display(), map.width, map.height));
                ui.horizontal(|ui| {
                    ui.label("rotation");
                    changed |=
                        ui.add(egui::DragValue::new(&mut sky.rotation_deg).range(-360.0..=360.0).suffix("°")).changed();
                });
            }
            if sky.enabled {
                ui.small(if sky.is_lit() {
                    format!("{directions} directional VPLs, each with a shadow map (sky.directions)")
                } else {
                    "the sky is dark: no light".to_string()
                });
            }
        },
    );
    changed
}
