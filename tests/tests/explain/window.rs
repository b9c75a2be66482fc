//! Explain a pixel in the window (issue #42): X over the viewport, or right-click → Explain
//! this pixel, pins the pixel; the Explain pane lists its contributors with the sum checked,
//! and the overlay draws them over the image.

use egui_kittest::kittest::Queryable;
use gi_lab_tests::ui_harness::{harness, pause, run_until};

/// Pixels of the harness's image close to the overlay's marker colour (255, 80, 255) inside
/// `rect`.
fn marker_pixels(image: &image::RgbaImage, rect: egui::Rect) -> usize {
    let mut n = 0;
    for y in rect.min.y.max(0.0) as u32..(rect.max.y as u32).min(image.height()) {
        for x in rect.min.x.max(0.0) as u32..(rect.max.x as u32).min(image.width()) {
            let p = image.get_pixel(x, y).0;
            n += (p[0] > 230 && (60..110).contains(&p[1]) && p[2] > 230) as usize;
        }
    }
    n
}

#[test]
fn x_over_the_viewport_explains_the_pixel_in_the_pane_and_the_overlay() {
    let (mut h, dir) = harness("explain");
    pause(&mut h);
    h.run_steps(3);
    let vp = h.get_by_label("Viewport").rect();
    // The floor in front of the blocks.
    let pos = egui::pos2(vp.center().x + 60.0, vp.max.y + 430.0);
    h.hover_at(pos);
    h.run_steps(2);
    h.key_press(egui::Key::X);
    run_until(&mut h, 40, |a| a.state.explain.as_ref().is_some_and(|v| v.explanation().is_some()));
    let st = &h.state().state;
    let v = st.explain.as_ref().expect("X pins the hovered pixel");
    assert_eq!(Some(v.pixel), st.probes.hover, "the explained pixel is the hovered one");
    let e = v.explanation().expect("the explanation arrives");
    assert!(e.total_check().relative_error() < 1e-3, "{}", e.to_text(4));
    assert!(e.contributions.iter().any(|c| c.name.starts_with("VPL ") && c.rejected.is_none()));
    let pixel = v.pixel;
    // The pane shows it: its heading, the sum's verdict, the rows.
    h.get_by_label(&format!("Explain pixel ({}, {})", pixel.0, pixel.1));
    assert!(h.query_by_label_contains("✔ Δ").is_some(), "the pane shows the sum's check holding");
    assert!(h.query_all_by_label("history").next().is_some(), "the history's share is a row");
    assert!(h.query_by_label("Copy CSV").is_some());
    // The overlay: the marker at the pixel and the contributors; none with the overlay off.
    let rect = h.state().state.viewport_rect;
    let on = marker_pixels(&h.render().expect("renders"), rect);
    h.state_mut().state.explain.as_mut().expect("explaining").overlay = false;
    h.run_steps(2);
    let off = marker_pixels(&h.render().expect("renders"), rect);
    assert!(on >= 20 && off == 0, "marker pixels with the overlay on {on}, off {off}");
    // Unpin: the renderer stops replaying.
    h.get_by_label("Unpin").click();
    h.run_steps(3);
    assert!(h.state().state.explain.is_none());
    assert_eq!(h.state().renderer().expect("renderer").explain_pixel(), None);
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn the_viewport_context_menu_explains_the_pixel_under_the_pointer() {
    let (mut h, dir) = harness("explain_menu");
    pause(&mut h);
    h.run_steps(3);
    let vp = h.get_by_label("Viewport").rect();
    let pos = egui::pos2(vp.center().x + 120.0, vp.max.y + 300.0);
    h.hover_at(pos);
    h.run_steps(2);
    let hovered = h.state().state.probes.hover.expect("a hovered pixel");
    for pressed in [true, false] {
        h.event(egui::Event::PointerButton {
            pos,
            button: egui::PointerButton::Secondary,
            pressed,
            modifiers: Default::default(),
        });
    }
    h.run_steps(2);
    h.get_by_label(&format!("Explain this pixel ({}, {})", hovered.0, hovered.1)).click();
    h.run_steps(2);
    assert_eq!(h.state().state.explain.as_ref().map(|v| v.pixel), Some(hovered));
    run_until(&mut h, 40, |a| a.state.explain.as_ref().is_some_and(|v| v.explanation().is_some()));
    h.get_by_label(&format!("Explain pixel ({}, {})", hovered.0, hovered.1));
    let _ = std::fs::remove_dir_all(dir);
}
