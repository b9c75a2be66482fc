//! Lights in the viewport (issue #39 point 2): every punctual light drawn over the image —
//! an icon in its colour, a spot's outer and inner cones, a directional light's direction,
//! a point light's range when it has one — and the selected light's handles: three axis
//! arrows and a centre disc to move it (along a world axis, or in the view plane), and an
//! aim handle at the tip of its direction for spots and directional lights. A click on an
//! icon selects the light (the Scene panel opens its section); holding Ctrl snaps moves to
//! a grid of a tenth of a power of ten of the scene's size and aims to 15° of elevation and
//! azimuth. Each drag is one undo step (`crate::ui::state::history` waits for the release), and the
//! image follows live, with the temporal history restarted as for the Scene panel's fields.

use glam::{Mat4, Quat, Vec3};

use crate::ui::lab::Lab;

/// Pick radius of an icon or handle, points.
const PICK: f32 = 9.0;
/// Screen length of the axis arrows, points.
const AXIS: f32 = 70.0;

/// World ↔ viewport.
struct View {
    vp: Mat4,
    rect: egui::Rect,
    right: Vec3,
    up: Vec3,
}

impl View {
    fn screen(&self, p: Vec3) -> Option<egui::Pos2> {
        let clip = self.vp * p.extend(1.0);
        (clip.w > 1e-6).then(|| {
            let ndc = clip.truncate() / clip.w;
            self.rect.min
                + egui::vec2((ndc.x * 0.5 + 0.5) * self.rect.width(), (0.5 - ndc.y * 0.5) * self.rect.height())
        })
    }

    /// World units per point at p (in the view plane through p).
    fn world_per_point(&self, p: Vec3) -> f32 {
        match (self.screen(p), self.screen(p + self.right)) {
            (Some(a), Some(b)) if a.distance(b) > 1e-6 => 1.0 / a.distance(b),
            _ => 0.0,
        }
    }
}

/// One light as the viewport shows it.
struct Shown {
    node: usize,
    name: String,
    kind: gi_render::scene::LightKind,
    colour: egui::Color32,
    range: Option<f32>,
    position: Vec3,
    /// The direction it shines along (spot, directional): the node's −Z.
    direction: Vec3,
    /// The node's parent's world matrix (edits are made in the node's local frame).
    parent: Mat4,
}

fn shown_lights(l: &Lab) -> Vec<Shown> {
    let scene = l.renderer.scene();
    let state = scene.evaluate(l.renderer.clock.time_s());
    let mut parent = vec![None; scene.nodes.len()];
    for (i, n) in scene.nodes.iter().enumerate() {
        for &c in &n.children {
            if c < parent.len() {
                parent[c] = Some(i);
            }
        }
    }
    scene
        .nodes
        .iter()
        .enumerate()
        .filter_map(|(i, n)| {
            let light = scene.lights.get(n.light?)?;
            let world = *state.node_world.get(i)?;
            let (_, rotation, position) = world.to_scale_rotation_translation();
            let c = light.color / light.color.max_element().max(1e-6);
            Some(Shown {
                node: i,
                name: light.name.clone(),
                kind: light.kind,
                colour: egui::Color32::from(egui::Rgba::from_rgb(c.x, c.y, c.z)),
                range: light.range,
                position,
                direction: (rotation * Vec3::NEG_Z).normalize_or(Vec3::NEG_Z),
                parent: parent[i].and_then(|p| state.node_world.get(p).copied()).unwrap_or(Mat4::IDENTITY),
            })
        })
        .collect()
}

/// What a handle does when dragged.
#[derive(Clone, Copy, PartialEq, Debug)]
enum Handle {
    /// Along a world axis.
    Axis(Vec3),
    /// In the view plane.
    Plane,
    /// The direction's tip.
    Aim,
}

/// The state at the start of a drag (kept in egui's memory under the handle's id).
#[derive(Clone, Copy)]
struct DragStart {
    position: Vec3,
    direction: Vec3,
}

/// Draws the lights and their handles over the viewport and applies their drags. Must run
/// after the viewport's own response is made, so that the handles are on top of it. Returns
/// whether the pointer is on a light or handle (the viewport then neither orbits nor pins).
pub(super) fn light_gizmos(l: &mut Lab, ui: &mut egui::Ui, rect: egui::Rect) -> bool {
    let cam = l.renderer.camera;
    let right = cam.right();
    let view = View { vp: l.renderer.view_proj(), rect, right, up: right.cross(cam.forward()).normalize_or(Vec3::Y) };
    let radius = l.renderer.bounds().radius().max(1e-3);
    let lights = shown_lights(l);
    if l.selected_light.is_some_and(|n| !lights.iter().any(|s| s.node == n)) {
        l.selected_light = None;
    }
    let painter = ui.painter_at(rect);
    let snap = ui.input(|i| i.modifiers.command);
    let mut busy = false;
    let mut edit: Option<(usize, Vec3, Vec3, Mat4)> = None;
    for s in &lights {
        let Some(centre) = view.screen(s.position) else { continue };
        if !rect.expand(PICK).contains(centre) {
            continue;
        }
        let id = ui.scope_id().with(("light", s.node));
        let icon = ui.interact(
            egui::Rect::from_center_size(centre, egui::vec2(2.0 * PICK, 2.0 * PICK)),
            id,
            egui::Sense::click_and_drag(),
        );
        let icon = icon.on_hover_text(format!("{} (click to select; drag to move in the view plane)", s.name));
        busy |= icon.hovered() || icon.dragged();
        if icon.clicked() || icon.drag_started() {
            if l.selected_light != Some(s.node) {
                l.reveal_selected = true;
            }
            l.selected_light = Some(s.node);
        }
        let selected = l.selected_light == Some(s.node);
        draw_light(&painter, &view, s, centre, radius, selected);
        if !selected {
            continue;
        }
        let wpp = view.world_per_point(s.position);
        let mut handles = Vec::new();
        let directional = matches!(s.kind, gi_render::scene::LightKind::Directional);
        if !directional {
            handles.push((Handle::Plane, centre, icon.clone()));
            for (axis, colour) in [
                (Vec3::X, egui::Color32::from_rgb(235, 70, 70)),
                (Vec3::Y, egui::Color32::from_rgb(90, 220, 90)),
                (Vec3::Z, egui::Color32::from_rgb(80, 140, 255)),
            ] {
                let Some(end) = view.screen(s.position + axis * AXIS * wpp) else { continue };
                painter.line_segment([centre, end], egui::Stroke::new(2.5, colour));
                painter.circle_filled(end, 5.0, colour);
                let r = ui.interact(
                    egui::Rect::from_center_size(end, egui::vec2(2.0 * PICK, 2.0 * PICK)),
                    id.with(("axis", axis.to_array().map(f32::to_bits))),
                    egui::Sense::drag(),
                );
                handles.push((Handle::Axis(axis), end, r));
            }
        }
        if !matches!(s.kind, gi_render::scene::LightKind::Point)
            && let Some(tip) = view.screen(s.position + s.direction * 1.4 * AXIS * wpp)
        {
            painter.line_segment([centre, tip], egui::Stroke::new(2.0, egui::Color32::YELLOW));
            painter.circle_stroke(tip, 6.0, egui::Stroke::new(2.5, egui::Color32::YELLOW));
            let r = ui.interact(
                egui::Rect::from_center_size(tip, egui::vec2(2.0 * PICK, 2.0 * PICK)),
                id.with("aim"),
                egui::Sense::drag(),
            );
            handles.push((Handle::Aim, tip, r.on_hover_text("drag to aim (Ctrl: 15° steps)")));
        }
        for (handle, at, r) in handles {
            busy |= r.hovered() || r.dragged();
            let key = r.id.with("start");
            if r.drag_started() {
                ui.data_mut(|d| d.insert_temp(key, DragStart { position: s.position, direction: s.direction }));
            }
            if !r.dragged() {
                continue;
            }
            let Some(start) = ui.data(|d| d.get_temp::<DragStart>(key)) else { continue };
            let (Some(origin), Some(now)) = (ui.input(|i| i.pointer.press_origin()), r.interact_pointer_pos()) else {
                continue;
            };
            let moved = now - origin;
            let (mut position, mut direction) = (start.position, start.direction);
            match handle {
                Handle::Axis(axis) => {
                    let along = (at - centre).normalized();
                    let length = (at - centre).length().max(1e-3);
                    position = start.position + axis * (moved.dot(along) / length * AXIS * wpp);
                    if snap {
                        position = snap_position(position, start.position, axis, radius);
                    }
                }
                Handle::Plane => {
                    position = start.position + (view.right * moved.x - view.up * moved.y) * wpp;
                    if snap {
                        position = Vec3::from_array(position.to_array().map(|c| snapped(c, grid(radius))));
                    }
                }
                Handle::Aim => {
                    let tip = start.position + start.direction * 1.4 * AXIS * wpp;
                    let tip_wpp = view.world_per_point(tip);
                    let tip = tip + (view.right * moved.x - view.up * moved.y) * tip_wpp;
                    direction = (tip - start.position).normalize_or(start.direction);
                    if snap {
                        direction = snap_direction(direction);
                    }
                }
            }
            edit = Some((s.node, position, direction, s.parent));
        }
    }
    if let Some((node, position, direction, parent)) = edit {
        set_world(l, node, position, direction, parent);
    }
    busy
}

/// The snapping grid: a tenth of the power of ten below the scene's radius (0.1 m in a
/// room of a few metres).
fn grid(radius: f32) -> f32 {
    10f32.powf(radius.log10().floor()) * 0.1
}

fn snapped(x: f32, step: f32) -> f32 {
    (x / step).round() * step
}

/// `p` moved along `axis` from `start`, its coordinate on that axis on the grid.
fn snap_position(p: Vec3, start: Vec3, axis: Vec3, radius: f32) -> Vec3 {
    let along = p.dot(axis);
    start + axis * (snapped(along, grid(radius)) - start.dot(axis))
}

/// A direction with its elevation and azimuth rounded to 15°.
fn snap_direction(d: Vec3) -> Vec3 {
    let step = 15f32.to_radians();
    let elevation = snapped((-d.y).clamp(-1.0, 1.0).asin(), step);
    let azimuth = snapped((-d.x).atan2(-d.z), step);
    Vec3::new(-azimuth.sin() * elevation.cos(), -elevation.sin(), -azimuth.cos() * elevation.cos())
}

/// Puts the light of `node` at world `position`, shining along world `direction`, through its
/// local transform (its parent's world matrix undone), and restarts the temporal history as
/// the Scene panel's fields do.
fn set_world(l: &mut Lab, node: usize, position: Vec3, direction: Vec3, parent: Mat4) {
    let inverse = parent.inverse();
    let (_, parent_rotation, _) = parent.to_scale_rotation_translation();
    let scene = l.renderer.scene_mut();
    let Some(n) = scene.nodes.get_mut(node) else { return };
    let translation = inverse.transform_point3(position);
    let rotation =
        parent_rotation.inverse() * Quat::from_rotation_arc(Vec3::NEG_Z, direction.normalize_or(Vec3::NEG_Z));
    if translation.is_finite() && rotation.is_finite() {
        n.transform.translation = translation;
        n.transform.rotation = rotation.normalize();
        l.renderer.reset_history_but_records();
    }
}

fn draw_light(painter: &egui::Painter, view: &View, s: &Shown, centre: egui::Pos2, radius: f32, selected: bool) {
    use gi_render::scene::LightKind;
    let line = egui::Stroke::new(1.5, s.colour.gamma_multiply(0.8));
    // The cone's drawn length: a fifth of the scene's radius (its light reaches farther).
    let length = 0.2 * radius;
    match s.kind {
        LightKind::Point => {
            if let Some(edge) = s.range.and_then(|r| view.screen(s.position + view.right * r)) {
                painter.circle_stroke(
                    centre,
                    centre.distance(edge),
                    egui::Stroke::new(1.0, s.colour.gamma_multiply(0.6)),
                );
            }
            for k in 0..8 {
                let a = k as f32 * std::f32::consts::FRAC_PI_4;
                let d = egui::vec2(a.cos(), a.sin());
                painter.line_segment([centre + d * 8.0, centre + d * 12.0], line);
            }
        }
        LightKind::Spot { inner_cone, outer_cone } => {
            let (t, b) = s.direction.any_orthonormal_pair();
            for (angle, stroke) in
                [(outer_cone, line), (inner_cone, egui::Stroke::new(1.0, s.colour.gamma_multiply(0.5)))]
            {
                let c = s.position + s.direction * length;
                let r = length * angle.tan().min(50.0);
                let ring: Vec<egui::Pos2> = (0..=24)
                    .filter_map(|k| {
                        let a = k as f32 / 24.0 * std::f32::consts::TAU;
                        view.screen(c + (t * a.cos() + b * a.sin()) * r)
                    })
                    .collect();
                if ring.len() == 25 {
                    painter.add(egui::Shape::line(ring.clone(), stroke));
                    for k in [0, 6, 12, 18] {
                        painter.line_segment([centre, ring[k]], stroke);
                    }
                }
            }
        }
        LightKind::Directional => {
            let wpp = view.world_per_point(s.position);
            if let Some(end) = view.screen(s.position + s.direction * 40.0 * wpp) {
                painter.arrow(centre, end - centre, line);
            }
        }
    }
    painter.circle(centre, 6.0, s.colour, egui::Stroke::new(1.5, egui::Color32::BLACK));
    if selected {
        painter.circle_stroke(centre, 9.5, egui::Stroke::new(2.0, egui::Color32::WHITE));
        painter.text(
            centre + egui::vec2(12.0, -12.0),
            egui::Align2::LEFT_BOTTOM,
            &s.name,
            egui::FontId::proportional(13.0),
            egui::Color32::WHITE,
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn snapping_rounds_to_the_grid_and_to_15_degrees() {
        assert!((grid(3.0) - 0.1).abs() < 1e-6, "{}", grid(3.0));
        assert!((grid(40.0) - 1.0).abs() < 1e-6);
        let p = snap_position(Vec3::new(0.33, 1.234, 2.0), Vec3::new(0.33, 1.0, 2.0), Vec3::Y, 3.0);
        assert!((p - Vec3::new(0.33, 1.2, 2.0)).length() < 1e-5, "{p}");
        let d = snap_direction(Vec3::new(0.1, -0.98, -0.2).normalize());
        let elevation = (-d.y).asin().to_degrees();
        let azimuth = (-d.x).atan2(-d.z).to_degrees();
        assert!((elevation / 15.0 - (elevation / 15.0).round()).abs() < 1e-3, "{elevation}");
        assert!((azimuth / 15.0 - (azimuth / 15.0).round()).abs() < 1e-3, "{azimuth}");
        assert!((d.length() - 1.0).abs() < 1e-5);
    }
}
