//! Lights in the viewport (issue #39 point 2): a click on a light's icon selects it (the
//! Scene panel follows), dragging its vertical arrow moves it and the image with it, dragging
//! its aim handle turns the spot, each drag is one undo step, and undo puts it back.

use egui::{Key, Modifiers};
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use gi_lab::ui::app::GiLabApp;
use gi_lab_tests::ui_harness::{harness, pause};
use glam::Vec3;

/// The default scene's spot light: its node, world position and direction.
fn spot(h: &Harness<'static, GiLabApp>) -> (usize, Vec3, Vec3) {
    let r = h.state().renderer().expect("renderer");
    let scene = r.scene();
    let state = scene.evaluate(r.clock.time_s());
    let (node, _) = scene.nodes.iter().enumerate().find(|(_, n)| n.light.is_some()).expect("the box has a light");
    let (_, rotation, position) = state.node_world[node].to_scale_rotation_translation();
    (node, position, rotation * Vec3::NEG_Z)
}

/// Where world point p is in the window, and the points per world unit there.
fn on_screen(h: &Harness<'static, GiLabApp>, p: Vec3) -> (egui::Pos2, f32) {
    let r = h.state().renderer().expect("renderer");
    let rect = h.state().state.viewport_rect;
    let vp = r.view_proj();
    let at = |q: Vec3| {
        let c = vp * q.extend(1.0);
        let ndc = c.truncate() / c.w;
        rect.min + egui::vec2((ndc.x * 0.5 + 0.5) * rect.width(), (0.5 - ndc.y * 0.5) * rect.height())
    };
    let (a, b) = (at(p), at(p + r.camera.right()));
    (a, a.distance(b))
}

fn direct_mean(h: &Harness<'static, GiLabApp>) -> f64 {
    let img = h.state().renderer().expect("renderer").readback("direct.radiance").expect("direct.radiance");
    img.data.iter().map(|p| (p[0] + p[1] + p[2]) as f64).sum::<f64>() / img.data.len() as f64
}

fn drag(h: &mut Harness<'static, GiLabApp>, from: egui::Pos2, by: egui::Vec2) {
    h.drag_at(from);
    h.run_steps(1);
    for k in 1..=5 {
        h.event(egui::Event::PointerMoved(from + by * (k as f32 / 5.0)));
        h.run_steps(1);
    }
    h.drop_at(from + by);
    h.run_steps(3);
}

#[test]
fn a_light_is_selected_moved_and_aimed_in_the_viewport_and_each_drag_is_undone() {
    let (mut h, dir) = harness("light_gizmo");
    pause(&mut h);
    h.get_by_label("Scene & timeline").click();
    h.run_steps(4);
    let (node, p0, d0) = spot(&h);
    let lum0 = direct_mean(&h);
    let (icon, _) = on_screen(&h, p0);
    // A click on its icon selects it.
    h.drag_at(icon);
    h.drop_at(icon);
    h.run_steps(3);
    let lab = h.state().state.lab.as_ref().expect("lab");
    assert_eq!(lab.selected_light, Some(node), "the click selected the light");
    assert_eq!(h.state().state.history.steps().0.len(), 1, "a selection is not an edit");

    // Its vertical (world Y) arrow, dragged 30 points down, lowers it.
    let (_, per_unit) = on_screen(&h, p0);
    let (y_end, _) = on_screen(&h, p0 + Vec3::Y * 70.0 / per_unit);
    drag(&mut h, y_end, egui::vec2(0.0, 30.0));
    let (_, p1, _) = spot(&h);
    assert!(p1.y < p0.y - 1e-3, "the light moved down: {p0} -> {p1}");
    assert!((p1.x - p0.x).abs() < 1e-5 && (p1.z - p0.z).abs() < 1e-5, "along Y only: {p0} -> {p1}");
    let lum1 = direct_mean(&h);
    assert!((lum1 - lum0).abs() > 1e-3 * lum0, "the image follows: {lum0} -> {lum1}");
    let (names, _) = h.state().state.history.steps();
    assert_eq!(names.len(), 2, "one drag, one step: {names:?}");
    assert!(names[1].starts_with("move light"), "{names:?}");

    // The aim handle at the tip of its direction, dragged sideways, turns it.
    let (at, per_unit) = on_screen(&h, p1);
    let (tip, _) = on_screen(&h, p1 + d0 * 1.4 * 70.0 / per_unit);
    assert!(tip.distance(at) > 5.0, "the spot's aim handle is visible");
    drag(&mut h, tip, egui::vec2(40.0, 0.0));
    let (_, p2, d2) = spot(&h);
    assert!((p2 - p1).length() < 1e-5, "aiming does not move it");
    assert!(d2.dot(d0) < 0.999, "the spot turned: {d0} -> {d2}");
    let (names, _) = h.state().state.history.steps();
    assert!(names.len() == 3 && names[2].starts_with("aim light"), "{names:?}");

    // Undo twice: back where it was, pointing where it pointed, the image as before.
    for _ in 0..2 {
        h.key_press_modifiers(Modifiers::COMMAND, Key::Z);
        h.run_steps(3);
    }
    let (_, p3, d3) = spot(&h);
    assert!((p3 - p0).length() < 1e-6 && (d3 - d0).length() < 1e-6, "undo puts it back: {p3} {d3}");
    let lum3 = direct_mean(&h);
    assert!((lum3 - lum0).abs() <= 1e-4 * lum0, "and the image: {lum0} vs {lum3}");
    if let Ok(path) = std::env::var("GI_LAB_SCREENSHOT") {
        h.run_steps(2);
        let image = h.render().expect("the harness renders");
        image.save(path).expect("screenshot");
    }
    let _ = std::fs::remove_dir_all(dir);
}
