//! Interactive while tuning (issue #39 point 3): a drag in the viewport lowers the render
//! scale while frames miss View → target frame rate, the status bar says so, and the full
//! scale comes back once the drag ends.

use egui_kittest::kittest::Queryable;
use gi_lab_tests::ui_harness::{args_in, harness_with, pause, temp_dir};

#[test]
fn a_drag_lowers_the_render_scale_and_its_end_restores_it() {
    let dir = temp_dir("adaptive");
    let mut args = args_in(&dir, true);
    args.adaptive_scale = true;
    let mut h = harness_with(args, egui::vec2(1400.0, 1000.0));
    pause(&mut h);
    // Every frame of the software renderer misses 200 fps: the scale must go down.
    h.state_mut().state.session.target_fps = 200.0;
    h.run_steps(3);
    let size =
        |h: &egui_kittest::Harness<'static, gi_lab::ui::app::GiLabApp>| h.state().renderer().expect("renderer").size();
    let full = size(&h);
    let centre = h.state().state.viewport_rect.center();
    h.drag_at(centre);
    h.run_steps(1);
    let mut smallest = full;
    for k in 1..=14 {
        h.event(egui::Event::PointerMoved(centre + egui::vec2(3.0 * k as f32, 0.0)));
        h.run_steps(1);
        let s = size(&h);
        if s.0 * s.1 < smallest.0 * smallest.1 {
            smallest = s;
        }
    }
    assert!(
        (smallest.0 as f32) < 0.8 * full.0 as f32 && (smallest.1 as f32) < 0.8 * full.1 as f32,
        "the drag lowered the render size: {full:?} -> {smallest:?}"
    );
    let factor = h.state().state.adaptive.factor;
    assert!(factor < 1.0);
    h.get_by_label_contains("while dragging");
    h.drop_at(centre + egui::vec2(42.0, 0.0));
    h.run_steps(1);
    std::thread::sleep(gi_lab::ui::adaptive::SETTLE + std::time::Duration::from_millis(100));
    h.run_steps(3);
    assert_eq!(size(&h), full, "the full scale is back once the drag ended");
    assert_eq!(h.state().state.adaptive.factor, 1.0);
    let _ = std::fs::remove_dir_all(dir);
}
