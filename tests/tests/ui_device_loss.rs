//! Device loss in the window (issue #19 point 3). A lost device takes eframe's painter with
//! it, so the lab saves the session at once, says what happened and starts itself again on
//! that session; the new window has a new device, renderer, scene upload and textures with the
//! same settings, camera and timeline, and says why it restarted. Here the loss is forced with
//! `device.destroy()` and the restart (a new process in the app) is a new harness on the same
//! config folder with the arguments the lab passes it.

use egui_kittest::kittest::Queryable;
use gi_lab_tests::ui_harness::{args_in, harness_with, temp_dir};

#[test]
fn a_lost_device_saves_the_session_says_so_and_the_restart_restores_it() {
    let dir = temp_dir("device-loss");
    let mut args = args_in(&dir, true);
    args.restart_on_device_loss = false;
    let mut h = harness_with(args, egui::vec2(1200.0, 800.0));
    h.run_steps(3);
    let (camera, settings) = {
        let l = h.state_mut().state.lab.as_mut().expect("the lab renders");
        l.renderer.camera.yaw += 0.3;
        l.renderer.camera.position.y += 0.1;
        l.settings.direct.pcf_radius = 3;
        l.renderer.clock.playing = false;
        (l.renderer.camera, l.settings.clone())
    };
    h.run_steps(3);
    assert_eq!(h.state().state.device_lost, None);

    let ctx = h.state().renderer().expect("renderer").ctx.clone();
    ctx.device.destroy();
    ctx.wait_idle();
    h.run_steps(3);
    let said = h.state().state.device_lost.clone().expect("the lab noticed the loss");
    assert!(said.contains("the GPU device was lost") && said.contains("the session was saved"), "{said}");
    assert!(h.query_by_label_contains("the GPU device was lost").is_some(), "the status bar says so");
    let saved = std::fs::read_to_string(dir.join("config/session.ron")).expect("the session file exists");
    assert!(saved.contains("pcf_radius: 3"), "the live settings were saved:\n{saved}");

    // The restart: the lab's arguments on the same config folder, not fresh.
    let mut again = args_in(&dir, false);
    again.recovered = Some("Destroyed".into());
    let mut h2 = harness_with(again, egui::vec2(1200.0, 800.0));
    h2.run_steps(3);
    let l = h2.state().state.lab.as_ref().expect("the restarted lab renders");
    assert_eq!(l.settings, settings, "same settings");
    assert_eq!(l.renderer.camera, camera, "same camera");
    assert!(!l.renderer.clock.playing, "same timeline state");
    assert_eq!(l.renderer.ctx.lost_reason(), None, "a new device");
    assert!(h2.query_by_label_contains("restarted because the GPU device was lost").is_some(), "it says why");
}
