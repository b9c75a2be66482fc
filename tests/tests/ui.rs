//! The app's window with egui_kittest (no display needed): it renders the default scene on
//! the harness's wgpu device, the panels drive the renderer, and the play controls work.

use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use gi_lab::app::GiLabApp;
use gi_lab::cli::AppArgs;

fn harness() -> Harness<'static, GiLabApp> {
    let h = Harness::builder()
        .with_size(egui::vec2(1000.0, 700.0))
        .wgpu_setup(gi_lab::app::wgpu_setup())
        .build_eframe(|cc| GiLabApp::new(cc, AppArgs::default()));
    if let Some(e) = h.state().error() {
        panic!(
            "the app could not start its renderer: {e}\n\
             Install Mesa's software Vulkan driver: `sudo apt-get install -y mesa-vulkan-drivers libvulkan1` \
             (or run `bash scripts/test.sh`)"
        );
    }
    h
}

#[test]
fn app_renders_and_shows_a_section_per_stage() {
    let mut h = harness();
    h.run_steps(3);
    assert!(h.state().is_rendering());
    h.get_by_label("2 · Direct light");
    h.get_by_label("7 · Tone mapping");
    let r = h.state().renderer().expect("renderer");
    let (w, h_px) = r.size();
    assert!(w > 300 && h_px > 300, "the viewport is {w}×{h_px}: it should fill the central panel");
    assert!(r.clock.frame >= 3, "frames rendered: {}", r.clock.frame);
    let names: Vec<_> = r.timings().iter().map(|t| t.name.clone()).collect();
    assert_eq!(names, ["gbuffer", "direct.shadow", "direct", "compose", "compose.luminance", "compose.tonemap"]);
}

#[test]
fn pause_and_step_drive_the_clock() {
    let mut h = harness();
    h.run_steps(2);
    h.get_by_label("Pause").click();
    h.run_steps(2);
    let t0 = h.state().renderer().expect("renderer").clock.anim_frame;
    h.run_steps(3);
    assert_eq!(h.state().renderer().expect("renderer").clock.anim_frame, t0, "paused: animation time stands still");
    h.get_by_label("Step").click();
    h.run_steps(1);
    assert_eq!(h.state().renderer().expect("renderer").clock.anim_frame, t0 + 1, "Step advances one frame");
    h.get_by_label("Play").click();
    h.run_steps(3);
    assert!(h.state().renderer().expect("renderer").clock.anim_frame > t0 + 1, "playing again");
}

#[test]
fn opening_a_bad_scene_keeps_the_current_one_and_says_why() {
    let mut h = harness();
    h.run_steps(2);
    let before = h.state().renderer().expect("renderer").scene().triangle_count();
    let err = h.state_mut().open_scene("/nonexistent/scene.gltf", 1.0).expect_err("a missing file is refused");
    assert!(err.contains("nonexistent"), "{err}");
    h.run_steps(2);
    assert_eq!(h.state().renderer().expect("renderer").scene().triangle_count(), before);
    let path = gi_lab_tests::shared_scene("cornell-box/CornellBox-Original.gltf");
    let ok = h.state_mut().open_scene(&path.to_string_lossy(), 1.0);
    assert!(ok.is_ok(), "{ok:?}");
    h.run_steps(2);
    let r = h.state().renderer().expect("renderer");
    assert_eq!(r.scene().triangle_count(), 32);
    assert!(r.clock.frame >= 2, "the new scene renders");
}
