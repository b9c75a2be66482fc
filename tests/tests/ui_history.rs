//! Undo and redo in the window (issue #39 point 1): a slider drag is one step, undo puts the
//! settings back bit for bit, a new edit clears redo, a preset load, a light and a bookmark
//! are undone in order, the History pane jumps to any step, and a preset save is not a step.

use egui::{Key, Modifiers};
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use gi_lab::ui::app::GiLabApp;
use gi_lab_tests::ui_harness::{harness, pause};
use gi_render::LabSettings;

/// The lab at 3 % of its render size: these tests ask what the history does, not what the
/// frame shows (the render scale is the session's, not a step).
fn small_harness(name: &str) -> (Harness<'static, GiLabApp>, std::path::PathBuf) {
    let (mut h, dir) = harness(name);
    h.state_mut().state.session.render_scale = 0.03;
    (h, dir)
}

fn settings(h: &Harness<'static, GiLabApp>) -> LabSettings {
    h.state().settings().expect("settings").clone()
}

fn steps(h: &Harness<'static, GiLabApp>) -> (Vec<String>, usize) {
    let (s, c) = h.state().state.history.steps();
    (s.into_iter().map(String::from).collect(), c)
}

fn lights(h: &Harness<'static, GiLabApp>) -> usize {
    h.state().renderer().expect("renderer").scene().nodes.iter().filter(|n| n.light.is_some()).count()
}

fn undo(h: &mut Harness<'static, GiLabApp>) {
    h.key_press_modifiers(Modifiers::COMMAND, Key::Z);
    h.run_steps(3);
}

#[test]
fn a_slider_drag_is_one_step_and_undo_restores_the_settings_bit_for_bit() {
    let (mut h, dir) = small_harness("history_drag");
    pause(&mut h);
    h.run_steps(3);
    let before = settings(&h);
    assert_eq!(steps(&h), (vec!["start".to_string()], 0), "the history starts with the opened state");
    // Drag the shadow bias slider over several frames, as a hand would.
    h.get_by_label("direct.depth_bias").scroll_to_me();
    h.run_steps(2);
    let r = h.get_by_label("direct.depth_bias").rect();
    let y = r.center().y;
    let (x0, x1) = (r.min.x + 0.3 * r.width(), r.min.x + 0.15 * r.width());
    h.drag_at(egui::pos2(x0, y));
    h.run_steps(1);
    let mut values = Vec::new();
    for k in 1..=6 {
        let x = x0 + (x1 - x0) * k as f32 / 6.0;
        h.event(egui::Event::PointerMoved(egui::pos2(x, y)));
        h.run_steps(1);
        values.push(settings(&h).direct.depth_bias);
    }
    h.drop_at(egui::pos2(x1, y));
    h.run_steps(3);
    let dragged = settings(&h);
    values.dedup();
    assert!(values.len() >= 3, "the drag changed the value over several frames: {values:?}");
    assert_ne!(dragged.direct.depth_bias, before.direct.depth_bias);
    let (names, cursor) = steps(&h);
    assert_eq!(names.len(), 2, "one drag, one step: {names:?}");
    assert_eq!(cursor, 1);
    assert!(names[1].starts_with("direct.depth_bias = "), "the step says what changed: {}", names[1]);
    assert_eq!(h.state().state.history.undo_name(), Some(names[1].as_str()));

    undo(&mut h);
    assert_eq!(settings(&h), before, "undo restores the settings bit for bit");
    assert_eq!(h.state().renderer().expect("renderer").settings(), &before, "and the renderer runs them");
    assert_eq!(steps(&h).1, 0);
    h.key_press_modifiers(Modifiers::COMMAND | Modifiers::SHIFT, Key::Z);
    h.run_steps(3);
    assert_eq!(settings(&h), dragged, "Ctrl+Shift+Z redoes the drag");
    undo(&mut h);
    h.key_press_modifiers(Modifiers::COMMAND, Key::Y);
    h.run_steps(3);
    assert_eq!(settings(&h), dragged, "Ctrl+Y redoes too");
    undo(&mut h);
    assert_eq!(h.state().state.history.redo_name(), Some(names[1].as_str()));

    // A new edit after an undo drops what could have been redone.
    h.get_by_label("direct.pcf_radius").scroll_to_me();
    h.run_steps(2);
    h.get_by_label("direct.pcf_radius").increment_accesskit();
    h.run_steps(3);
    let (names, cursor) = steps(&h);
    assert_eq!((names.len(), cursor), (2, 1), "{names:?}");
    assert!(names[1].starts_with("direct.pcf_radius"), "{names:?}");
    assert_eq!(h.state().state.history.redo_name(), None, "redo is cleared by a new edit");
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn a_preset_load_a_light_and_a_bookmark_are_undone_in_order_and_the_history_pane_jumps() {
    let (mut h, dir) = small_harness("history_kinds");
    pause(&mut h);
    h.run_steps(3);
    let start = settings(&h);
    let n0 = lights(&h);
    let preset = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../presets/nguyen-hcb.ron"));
    let from_file = gi_render::preset::load_file(preset).expect("shipped preset").settings;
    assert_ne!(from_file, start);
    h.state_mut().state.open_preset(preset);
    h.run_steps(3);
    assert_eq!(settings(&h), from_file);
    h.get_by_label("Scene & timeline").click();
    h.run_steps(2);
    h.get_by_label("point").click();
    h.run_steps(3);
    assert_eq!(lights(&h), n0 + 1);
    h.state_mut().state.bookmark_name = "corner".into();
    h.state_mut().state.add_bookmark();
    h.run_steps(3);
    let (names, cursor) = steps(&h);
    assert_eq!(cursor, 3, "{names:?}");
    assert_eq!(names[1], "open preset nguyen-hcb.ron");
    assert!(names[2].starts_with("add light point"), "{names:?}");
    assert_eq!(names[3], "add bookmark corner");

    // The Edit menu names what it undoes.
    h.get_by_label("Edit").click();
    h.run_steps(2);
    h.get_by_label_contains("Undo add bookmark corner").click();
    h.run_steps(3);
    assert!(h.state().state.session.bookmarks.is_empty(), "the bookmark is gone");
    assert_eq!(lights(&h), n0 + 1, "one step at a time");
    undo(&mut h);
    assert_eq!(lights(&h), n0, "the added light is gone");
    undo(&mut h);
    assert_eq!(settings(&h), start, "the preset load is undone bit for bit");
    assert_eq!(h.state().state.preset.path, None, "and the preset it came from is the one before");

    // The History pane lists every step and goes to any of them.
    h.get_by_label("History").click();
    h.run_steps(2);
    h.get_by_label_contains("add light point").click();
    h.run_steps(3);
    assert_eq!(steps(&h).1, 2);
    assert_eq!(settings(&h), from_file);
    assert_eq!(lights(&h), n0 + 1, "jumping forward redoes the light");
    assert!(h.state().state.session.bookmarks.is_empty(), "but not the bookmark after it");
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn a_preset_save_is_not_a_step_and_undo_keeps_the_file_saved() {
    let (mut h, dir) = small_harness("history_save");
    pause(&mut h);
    h.run_steps(3);
    let start = settings(&h);
    h.get_by_label("direct.pcf_radius").scroll_to_me();
    h.run_steps(2);
    h.get_by_label("direct.pcf_radius").increment_accesskit();
    h.run_steps(3);
    let edited = settings(&h);
    let file = dir.join("presets/saved.ron");
    h.state_mut().state.save_preset_to(&file).expect("saves");
    h.run_steps(3);
    assert_eq!(steps(&h).0.len(), 2, "the save added no step: {:?}", steps(&h).0);
    assert!(!h.state().state.unsaved());
    undo(&mut h);
    assert_eq!(settings(&h), start);
    assert!(h.state().state.unsaved(), "the file holds the edit, the live settings do not");
    h.key_press_modifiers(Modifiers::COMMAND, Key::Y);
    h.run_steps(3);
    assert_eq!(settings(&h), edited);
    assert!(!h.state().state.unsaved(), "redo gives the saved settings back");
    let _ = std::fs::remove_dir_all(dir);
}

/// The other kinds of edit, each undone to the state before it: a technique pick, a light
/// duplicated and one removed, the sky turned on, a revert of the preset, and a scene opened.
#[test]
fn every_kind_of_edit_is_undone() {
    let (mut h, dir) = small_harness("history_all");
    pause(&mut h);
    h.run_steps(3);
    let mut states = vec![(settings(&h), lights(&h))];
    let mut expect_step = |h: &mut Harness<'static, GiLabApp>, prefix: &str| {
        h.run_steps(3);
        let (names, cursor) = steps(h);
        assert!(names[cursor].starts_with(prefix), "the step is named '{prefix}…': {names:?}");
        states.push((settings(h), lights(h)));
    };
    // A technique.
    if let Ok(l) = &mut h.state_mut().state.lab {
        // What the technique picker does.
        gi_render::settings::pipeline::Technique::Nguyen.apply(&mut l.settings);
        l.apply_settings();
    }
    expect_step(&mut h, "pipeline.");
    // Lights: duplicate, then remove the first.
    h.get_by_label("Scene & timeline").click();
    h.run_steps(2);
    h.get_by_label("duplicate light 0").click();
    expect_step(&mut h, "add light");
    h.get_by_label("remove light 0").click();
    expect_step(&mut h, "remove light");
    // The sky.
    h.get_by_label("Sky light").click();
    h.run_steps(2);
    h.get_by_label("sky lights the scene").click();
    expect_step(&mut h, "edit the sky");
    assert!(h.state().renderer().expect("renderer").scene().sky.enabled);
    // A preset edited, then reverted.
    let preset = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../presets/soler-quarter-4-64.ron"));
    h.state_mut().state.open_preset(preset);
    expect_step(&mut h, "open preset");
    if let Ok(l) = &mut h.state_mut().state.lab {
        l.settings.soler.levels = 3;
        l.apply_settings();
    }
    expect_step(&mut h, "soler.levels");
    h.state_mut().state.revert_preset();
    expect_step(&mut h, "revert the preset");
    // A scene.
    let glb = dir.join("box.glb");
    gi_render::scene::cornell::write_glb(&glb).expect("writes the default scene");
    h.state_mut().open_scene(&glb.to_string_lossy(), 1.0).expect("opens");
    expect_step(&mut h, "open scene box.glb");

    // Undo each, newest first: each gives the state before it back.
    let n = states.len();
    for k in (0..n - 1).rev() {
        undo(&mut h);
        let (s, l) = (settings(&h), lights(&h));
        assert!(s == states[k].0, "undo to step {k}: the settings differ");
        assert_eq!(l, states[k].1, "undo to step {k}: the lights differ");
    }
    let r = h.state().renderer().expect("renderer");
    assert!(!r.scene().sky.enabled, "the sky is off again");
    assert_eq!(h.state().state.lab.as_ref().expect("lab").scene_path, None, "the default scene again");
    let _ = std::fs::remove_dir_all(dir);
}
