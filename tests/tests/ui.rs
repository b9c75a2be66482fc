//! The lab window with egui_kittest (no display needed): it renders the default scene on
//! the harness's wgpu device; every setting has a widget that drives the renderer; the
//! buffer viewer lists and shows every buffer; the probe shows the buffers' values; presets
//! save, open and report problems through the UI.

use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use gi_lab::ui::app::GiLabApp;
use gi_render::LabSettings;
use gi_render::settings::{FieldKind, Value};

use gi_lab_tests::ui_harness::{
    args_in, arrived, cheap_frames, harness, harness_in, harness_with, pause, run_until, show_in_viewer, temp_dir,
};

#[test]
fn app_renders_into_a_viewport_the_panels_do_not_cover() {
    let (mut h, _dir) = harness("layout");
    h.run_steps(3);
    assert!(h.state().is_rendering());
    h.get_by_label("2 · Direct light");
    h.get_by_label("7 · Tone mapping");
    for tab in ["Viewport", "Settings", "Scene & timeline", "Presets", "GPU timings", "Probes"] {
        h.get_by_label(tab);
    }
    let st = &h.state().state;
    let (vw, vh) = st.viewport_px;
    assert!(vw > 300 && vh > 300, "the viewport is {vw}×{vh}");
    let r = h.state().renderer().expect("renderer");
    let (w, h_px) = r.size();
    let scale = st.session.render_scale;
    assert_eq!((w, h_px), ((vw as f32 * scale).round() as u32, (vh as f32 * scale).round() as u32));
    assert!(r.clock.frame >= 3, "frames rendered: {}", r.clock.frame);
    let names: Vec<_> = r.timings().iter().map(|t| t.name.clone()).collect();
    // The default technique: instant radiosity with ISMs and temporal coherence (Knecht).
    assert_eq!(names, gi_lab_tests::DEFAULT_PASSES);
    for n in &names {
        let out = gi_render::renderer::scope_output(n).unwrap_or_else(|| panic!("pass {n} has no output buffer"));
        assert!(r.buffers().get(out).is_ok(), "{n} → {out} is not registered");
    }
}

#[test]
fn pause_and_step_drive_the_clock() {
    let (mut h, _dir) = harness("clock");
    h.run_steps(2);
    h.get_by_label("Scene & timeline").click();
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
    let (mut h, _dir) = harness("scene");
    h.run_steps(2);
    let before = h.state().renderer().expect("renderer").scene().triangle_count();
    let err = h.state_mut().open_scene("/nonexistent/scene.gltf", 1.0).expect_err("a missing file is refused");
    assert!(err.contains("nonexistent"), "{err}");
    h.run_steps(2);
    assert_eq!(h.state().renderer().expect("renderer").scene().triangle_count(), before);
    let path = gi_lab_tests::real_scene("cornell-box/CornellBox-Original.gltf");
    let ok = h.state_mut().open_scene(&path.to_string_lossy(), 1.0);
    assert!(ok.is_ok(), "{ok:?}");
    h.run_steps(2);
    let r = h.state().renderer().expect("renderer");
    assert_eq!(r.scene().triangle_count(), 32);
    assert!(r.clock.frame >= 2, "the new scene renders");
    // It has no punctual light: the status bar says that its emissive quad lights it (issue
    // #18).
    let status = h.state().state.status.as_ref().map(|s| s.0.clone()).unwrap_or_default();
    assert!(status.starts_with("the scene is lit by its emissive surfaces"), "status: {status}");
}

/// Every field of `LabSettings` (enumerated from the settings' own metadata) has a widget
/// named by its dotted path, and operating that widget changes the renderer's settings.
#[test]
fn every_setting_has_a_widget_that_changes_the_renderer() {
    let dir = temp_dir("fields");
    // Tall enough that the whole settings panel (every group, Soler's included) is on
    // screen: the reset buttons are clicked where they are drawn.
    let mut h = harness_in(&dir, egui::vec2(1400.0, 3600.0));
    // The tall viewport at 3 % of its size (about 30×110 pixels): this test renders ~600
    // frames and asks only whether each widget reaches the renderer.
    h.state_mut().state.session.render_scale = 0.03;
    h.run_steps(2);
    // And cheap frames: each widget must reach the renderer, whatever the sizes it starts at.
    cheap_frames(&mut h);
    // Choices that no other value of can be applied alone from the defaults (each refused
    // with its reason): the VPL source, since the default VPL gather needs importance-warped
    // VPLs and uniform batches need the reference's other stages; the shading points, since
    // every pixel needs no geometry-aware filter and HCB samples need coherence splatting
    // (the technique picker switches them together).
    let mut refused_alone = Vec::new();
    for (group, fields) in LabSettings::groups() {
        let first = format!("{group}.{}", fields[0].name);
        if h.query_by_label(&first).is_none() {
            // A section that starts collapsed (or folded with why it cannot act): open it.
            h.get_by_label_contains(&gi_lab::ui::settings_ui::section_title(group)).click();
            h.run_steps(2);
        }
        for m in fields {
            let path = format!("{group}.{}", m.name);
            let before = h.state().renderer().expect("renderer").settings().get(&path);
            assert!(before.is_some(), "{path}: no value");
            let node = h.query_by_label(&path);
            assert!(node.is_some(), "{path} has no widget in the settings panel");
            // Labels wrap in a narrow panel: the panel can be taller than the window.
            h.get_by_label(&path).scroll_to_me();
            h.run_steps(1);
            match m.kind {
                FieldKind::Bool => h.get_by_label(&path).click(),
                FieldKind::Choice(names) => {
                    // The first other choice the stage choices allow: a refused one (e.g. no
                    // VPL source while the VPL gather runs) must say why and change nothing.
                    let Some(Value::Choice(current)) = before.clone() else { panic!("{path}: not a choice") };
                    let mut applied = false;
                    for (k, _) in names.iter().enumerate().filter(|(_, n)| **n != current) {
                        h.get_by_label(&path).click();
                        h.run_steps(2);
                        h.get_by_label(m.labels[k]).click();
                        h.run_steps(2);
                        if h.state().renderer().expect("renderer").settings().get(&path) != before {
                            applied = true;
                            break;
                        }
                        let err = h.state().state.lab.as_ref().ok().and_then(|l| l.settings_error.clone());
                        assert!(err.is_some(), "{path} = {}: neither applied nor refused with a message", names[k]);
                    }
                    if !applied {
                        refused_alone.push(path);
                        continue;
                    }
                }
                FieldKind::F32 | FieldKind::U32 => {
                    // A valid value next to the current one, set through the widget's
                    // accessibility action (what a screen reader or a typed value does).
                    let x = match before.clone() {
                        Some(Value::F32(x)) => x as f64,
                        Some(Value::U32(x)) => x as f64,
                        _ => panic!("{path}: not a number"),
                    };
                    let pow2 = gi_render::lab_settings::POWER_OF_TWO_FIELDS.contains(&path.as_str());
                    let target = match m.kind {
                        // Power-of-two fields' sliders move the exponent: one doubling.
                        FieldKind::U32 if pow2 && 2.0 * x <= m.max => x.log2() + 1.0,
                        FieldKind::U32 if pow2 => x.log2() - 1.0,
                        FieldKind::U32 if x < m.max => x + 1.0,
                        FieldKind::U32 => x - 1.0,
                        _ if x < m.max => x + (m.max - x).min(1.0) * 0.5,
                        _ => x - (x - m.min).min(1.0) * 0.5,
                    };
                    h.get_by_label(&path).set_value_accesskit(target);
                }
            }
            h.run_steps(2);
            let after = h.state().renderer().expect("renderer").settings().get(&path);
            assert_ne!(after, before, "{path}: operating its widget did not change the renderer's settings");
            let err = h.state().state.lab.as_ref().ok().and_then(|l| l.settings_error.clone());
            assert!(err.is_none(), "{path}: {err:?}");
            // Back to the default with the field's reset button, so that one field's change
            // does not make another's refused (e.g. the technique).
            h.get_by_label(&format!("reset {path}")).click();
            h.run_steps(2);
            let reset = h.state().renderer().expect("renderer").settings().get(&path);
            assert_eq!(reset, LabSettings::default().get(&path), "{path}: reset restores the default");
            // A reset of one of the cheap frames' fields (the VPL count, the ISM's points…)
            // brings back its costly default for every later field: cheap again.
            if gi_lab_tests::ui_harness::CHEAP_FRAMES.iter().any(|a| a.split('=').next() == Some(path.as_str())) {
                cheap_frames(&mut h);
            }
        }
    }
    assert_eq!(
        refused_alone,
        ["pipeline.vpl_source", "pipeline.shading_points"],
        "choices whose every alternative is refused alone"
    );
}

#[test]
fn buffer_viewer_lists_every_buffer_and_shows_the_chosen_one() {
    let (mut h, _dir) = harness("viewer");
    // A fixed render size keeps the snapshot independent of the panel layout.
    h.state_mut().state.render_size_override = Some((320, 240));
    pause(&mut h);
    h.run_steps(3);
    let names = h.state().renderer().expect("renderer").buffers().names();
    assert!(names.len() >= 10, "{names:?}");
    // The viewer's picker (its text is the shown buffer) opens a tree of every name.
    h.get_by_label("viewer 1 buffer").click();
    h.run_steps(2);
    for n in &names {
        // (A pass of the same name may be listed in the GPU timings too.)
        assert!(h.query_all_by_label(n).next().is_some(), "buffer {n} is not listed in the viewer's picker");
    }
    h.get_by_label("direct.radiance").click();
    pause(&mut h);
    h.run_steps(4);
    let st = &h.state().state;
    let v = st.viewers.open.values().next().expect("a viewer");
    assert_eq!(v.state.buffer, "direct.radiance");
    assert!(v.error.is_none(), "{:?}", v.error);
    // What the viewer shows: its view output, read back, against a stored snapshot.
    let l = st.lab.as_ref().expect("lab");
    let out = v.output_texture().expect("the viewer rendered");
    let img = gi_render::buffers::read_texture(&l.renderer.ctx, "viewer", &out, 0, 0).expect("readback");
    let bytes: Vec<u8> = img.data.iter().flat_map(|p| p.map(|c| (c * 255.0).round().clamp(0.0, 255.0) as u8)).collect();
    let rgba = image::RgbaImage::from_raw(img.width, img.height, bytes).expect("image");
    egui_kittest::image_snapshot_options(
        &rgba,
        "viewer_direct_radiance",
        &egui_kittest::SnapshotOptions::new().threshold(2.0).max_failed_pixels(40),
    );
}

#[test]
fn probe_shows_the_values_of_a_cpu_readback() {
    let (mut h, _dir) = harness("probe");
    pause(&mut h);
    // Direct light only: every frame is the same, so the probe's values, which arrive a frame
    // or two late without waiting (issue #38), equal a read-back of the frame now.
    if let Ok(l) = &mut h.state_mut().state.lab {
        gi_render::settings::pipeline::Technique::DirectOnly.apply(&mut l.settings);
        l.apply_settings();
    }
    h.run_steps(3);
    let vp = h.get_by_label("Viewport").rect();
    // Hover the middle of the viewport (below its tab bar).
    let pos = egui::pos2(vp.center().x + 20.0, vp.max.y + 250.0);
    h.hover_at(pos);
    h.run_steps(3);
    h.get_by_label("Probes").click();
    h.hover_at(pos);
    run_until(&mut h, 30, |a| !a.state.probes.values.is_empty());
    let st = &h.state().state;
    let l = st.lab.as_ref().expect("lab");
    assert!(!st.probes.values.is_empty(), "the probe read nothing at {pos:?}");
    let names = l.renderer.buffers().names();
    assert_eq!(st.probes.values.len(), names.len(), "every buffer is probed");
    for v in &st.probes.values {
        let img = l.renderer.readback(&v.name).expect("readback");
        let want = img.at(v.texel.0, v.texel.1);
        let same = v.value.iter().zip(want).all(|(a, b)| *a == b || (a.is_nan() && b.is_nan()));
        assert!(same, "{} at {:?}: probe {:?}, readback {want:?}", v.name, v.texel, v.value);
    }
    // The Probes panel prints them.
    let hdr = st.probes.values.iter().find(|v| v.name == "final.hdr").expect("final.hdr probed");
    let text = gi_lab::ui::panes::format_value(hdr.value);
    assert!(h.query_all_by_label(&text).next().is_some(), "the Probes panel does not show final.hdr = {text}");
    // A click pins a probe there.
    h.get_by_label("Viewport");
    h.drag_at(pos);
    h.drop_at(pos);
    h.run_steps(3);
    assert_eq!(h.state().state.probes.pinned.len(), 1, "a click in the viewport pins a probe");
}

#[test]
fn preset_save_and_open_round_trip_through_the_ui() {
    let (mut h, dir) = harness("presets");
    // The preset's round trip is asked, not the frames: small ones.
    h.state_mut().state.session.render_scale = 0.1;
    h.run_steps(2);
    // The tone mapping section is below the technique sections: scroll it into view.
    h.get_by_label("tonemap.auto_exposure").scroll_to_me();
    h.run_steps(2);
    h.get_by_label("tonemap.auto_exposure").click();
    h.get_by_label("direct.pcf_radius").increment_accesskit();
    h.run_steps(2);
    let edited = h.state().settings().expect("settings").clone();
    assert_ne!(edited, LabSettings::default());
    h.get_by_label("Presets").click();
    h.run_steps(2);
    h.get_by_label("preset name").click();
    h.run_steps(1);
    h.get_by_label("preset name").type_text("roundtrip");
    h.run_steps(2);
    let save = format!("Save to {}/", dir.join("presets").display());
    h.get_by_label(&save).click();
    h.run_steps(2);
    let file = dir.join("presets/roundtrip.ron");
    let saved = LabSettings::load(&file).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
    assert_eq!(saved, edited, "the file holds the live settings");
    assert!(!h.state().state.unsaved());
    // Change something, then open the saved preset from the browser.
    h.get_by_label("Settings").click();
    h.run_steps(2);
    // The tone mapping section is below the technique sections: scroll it into view.
    h.get_by_label("tonemap.auto_exposure").scroll_to_me();
    h.run_steps(2);
    h.get_by_label("tonemap.auto_exposure").click();
    h.run_steps(2);
    assert_ne!(h.state().settings(), Some(&edited), "the checkbox changed the settings");
    assert!(h.state().state.unsaved(), "an edit marks the preset unsaved");
    h.get_by_label("Presets").click();
    h.run_steps(2);
    h.get_by_label("roundtrip.ron").click();
    h.run_steps(2);
    assert_eq!(h.state().settings(), Some(&edited), "opening the preset restores it");
    assert_eq!(h.state().renderer().expect("renderer").settings(), &edited);
    // File → Export of the live settings says where they were tuned (issue #54 point 4).
    let file = dir.join("live.json");
    h.state_mut().state.export_to(&file, gi_render::preset::ExportFormat::Json).expect("exported");
    let text = std::fs::read_to_string(&file).expect("export written");
    let e = gi_render::preset::Export::parse(&text, "live.json").expect("the export loads");
    let r = h.state().renderer().expect("renderer");
    assert_eq!(e.provenance.resolution, [r.size().0, r.size().1], "the renderer's image");
    assert_eq!(e.provenance.bounds.as_ref().map(|b| b.radius), Some(r.bounds().radius()));
    assert_eq!(e.provenance.scale.as_ref().map(|s| s.length), Some(r.scale_radius()));
    // File → Export port kit… writes the kit of the live scene, settings and camera in the
    // background (issue #54), and refuses a folder that exists.
    let (size, camera) = (r.size(), r.camera);
    let kit = dir.join("kit");
    // (Without the expressions' probe captures: tests/tests/port_kit.rs tests those.)
    h.state_mut().state.export_port_kit_with(kit.clone(), false).expect("the kit starts");
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(300);
    while h.state().state.preset.port_kit_job.is_some() && std::time::Instant::now() < deadline {
        std::thread::sleep(std::time::Duration::from_millis(50));
        h.run_steps(1);
    }
    let status = h.state().state.status.as_ref().map(|s| s.0.clone()).unwrap_or_default();
    assert!(status.starts_with("port kit written"), "{status}");
    let m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(kit.join("manifest.json")).expect("manifest")).expect("json");
    assert_eq!((m["size"][0].as_u64(), m["size"][1].as_u64()), (Some(size.0 as u64), Some(size.1 as u64)));
    let text = std::fs::read_to_string(kit.join("preset.json")).expect("the kit's export");
    let e = gi_render::preset::Export::parse(&text, "preset.json").expect("the kit's export loads");
    assert_eq!((e.provenance.camera, e.settings), (camera, edited), "the live camera and settings");
    let again = h.state_mut().state.export_port_kit_to(kit.clone());
    assert!(again.is_err_and(|e| e.contains("exists")), "an existing folder is refused");
}

#[test]
fn a_bad_preset_lists_its_problems_and_changes_nothing_until_accepted() {
    let (mut h, dir) = harness("badpreset");
    // The preset's round trip is asked, not the frames: small ones.
    h.state_mut().state.session.render_scale = 0.1;
    h.run_steps(2);
    std::fs::write(
        dir.join("presets/bad.ron"),
        "(version: 1, direct: (pcf_radius: 40, shadowz: true), tonemap: (key: \"bright\", exposure_ev: 1.5))",
    )
    .expect("write");
    let before = h.state().settings().expect("settings").clone();
    h.get_by_label("Presets").click();
    h.run_steps(2);
    h.get_by_label("bad.ron").click();
    h.run_steps(2);
    for field in ["direct.pcf_radius", "direct.shadowz", "tonemap.key"] {
        assert!(h.query_by_label(field).is_some(), "the problem dialog does not list {field}");
    }
    assert_eq!(h.state().settings(), Some(&before), "nothing changes while the dialog is open");
    h.get_by_label("Cancel (keep current settings)").click();
    h.run_steps(2);
    assert_eq!(h.state().settings(), Some(&before), "cancel keeps the previous settings");
    h.get_by_label("bad.ron").click();
    h.run_steps(2);
    h.get_by_label("Load with these fixes").click();
    h.run_steps(2);
    let s = h.state().settings().expect("settings");
    assert_eq!(s.direct.pcf_radius, 4, "clamped");
    assert_eq!(s.tonemap.exposure_ev, 1.5, "valid values are kept");
    assert_eq!(s.tonemap.key, LabSettings::default().tonemap.key, "a wrong type falls back to the default");
}

#[test]
fn the_session_restores_layout_settings_viewers_and_probes() {
    let dir = temp_dir("session");
    let mut h = harness_with(args_in(&dir, true), egui::vec2(1400.0, 1000.0));
    h.run_steps(2);
    // The tone mapping section is below the technique sections: scroll it into view.
    h.get_by_label("tonemap.auto_exposure").scroll_to_me();
    h.run_steps(2);
    h.get_by_label("tonemap.auto_exposure").click();
    h.run_steps(2);
    h.state_mut().add_viewer();
    h.state_mut().state.pin_probe((10, 12));
    h.run_steps(2);
    let settings = h.state().settings().expect("settings").clone();
    let viewers: Vec<String> = h.state().state.viewers.open.values().map(|v| v.state.buffer.clone()).collect();
    h.state_mut().save_session().expect("session saved");
    drop(h);
    let mut h = harness_with(args_in(&dir, false), egui::vec2(1400.0, 1000.0));
    h.run_steps(2);
    assert_eq!(h.state().settings(), Some(&settings), "unsaved settings come back");
    let again: Vec<String> = h.state().state.viewers.open.values().map(|v| v.state.buffer.clone()).collect();
    assert_eq!(again, viewers, "the viewers come back");
    assert_eq!(h.state().state.probes.pinned.len(), 1, "the pinned probe comes back");
    assert!(h.state().state.unsaved(), "and they are still marked unsaved against the defaults");
}

#[test]
fn the_ab_split_renders_both_sides() {
    let (mut h, _dir) = harness("ab");
    pause(&mut h);
    h.run_steps(2);
    // B: the current (lit) settings, frozen. A: then switched to no light at all.
    h.state_mut().state.start_ab(gi_lab::ui::ab::AbSource::Frozen);
    if let Ok(l) = &mut h.state_mut().state.lab {
        l.settings.direct.intensity_scale = 0.0;
        l.apply_settings();
    }
    h.run_steps(4);
    let st = &h.state().state;
    let ab = st.ab.as_ref().expect("A/B runs");
    assert!(ab.b.clock.frame >= 3, "B renders: {} frames", ab.b.clock.frame);
    assert_eq!(ab.b.size(), st.lab.as_ref().expect("lab").renderer.size(), "B renders at A's size");
    let rect = st.viewport_rect;
    let image = h.render().expect("the harness renders");
    let ppp = 1.0;
    let mean = |x0: f32, x1: f32| {
        let (mut sum, mut n) = (0.0f64, 0u64);
        for y in (rect.min.y + 40.0) as u32..(rect.max.y - 40.0) as u32 {
            for x in (x0 * ppp) as u32..(x1 * ppp) as u32 {
                let p = image.get_pixel(x, y).0;
                sum += (p[0] as f64 + p[1] as f64 + p[2] as f64) / 3.0;
                n += 1;
            }
        }
        sum / n.max(1) as f64
    };
    let mid = rect.center().x;
    let (left, right) = (mean(rect.min.x + 10.0, mid - 10.0), mean(mid + 10.0, rect.max.x - 10.0));
    // Measured: the unlit A side is black (mean 0.1 of 255), the lit B side 17.4.
    assert!(left < 2.0 && right > 8.0, "A (unlit) left {left:.1} should be black, B (lit) right {right:.1} lit");
    // The FLIP view measures the two.
    h.state_mut().state.ab.as_mut().expect("ab").view = gi_lab::ui::ab::AbView::Flip;
    run_until(&mut h, 30, |a| a.state.ab.as_ref().is_some_and(|a| a.metrics.is_some()));
    let (flip, rmse) = h.state().state.ab.as_ref().and_then(|a| a.metrics).expect("FLIP and RMSE computed");
    assert!(flip > 0.1 && rmse > 0.0, "FLIP {flip}, RMSE {rmse}");
}

/// Every text the panels can show from the settings' metadata (labels, tooltips with the
/// documentation, symbols, units, choice labels) and the shortcut list draws with the
/// app's fonts: the harness panics on a missing glyph, a real window would show a box.
#[test]
fn every_settings_text_has_glyphs() {
    let mut texts: Vec<String> = Vec::new();
    for (group, fields) in LabSettings::groups() {
        texts.push(gi_lab::ui::settings_ui::section_title(group));
        for m in fields {
            texts.push(gi_lab::ui::settings_ui::tooltip(m));
            texts.push(m.labels.join(" "));
        }
    }
    for (k, what) in gi_lab::ui::menus::SHORTCUTS {
        texts.push(format!("{k} {what}"));
    }
    // The papers' symbols, and the history's and labels' own texts.
    texts.push(gi_lab::ui::PAPER_SYMBOLS.to_string());
    for path in LabSettings::all_paths() {
        texts.push(gi_lab::ui::settings_ui::label_of(&path));
    }
    // The app's fonts first (they take effect from the next frame), then the texts.
    let installed = std::cell::Cell::new(false);
    let mut h = Harness::new_ui(move |ui| {
        if !installed.replace(true) {
            gi_lab::ui::install_fonts(ui.ctx());
            return;
        }
        for t in &texts {
            ui.label(t);
        }
    });
    h.run_steps(2);
}

#[test]
fn the_hcb_samples_overlay_draws_white_dots_and_table_1() {
    let (mut h, _dir) = harness("hcb_overlay");
    pause(&mut h);
    if let Ok(l) = &mut h.state_mut().state.lab {
        gi_render::settings::pipeline::Technique::Nguyen.apply(&mut l.settings);
        l.apply_settings();
    }
    h.run_steps(3);
    let white = |h: &mut Harness<'static, GiLabApp>| {
        let rect = h.state().state.viewport_rect;
        let image = h.render().expect("the harness renders");
        let mut n = 0;
        for y in (rect.min.y + 40.0) as u32..(rect.max.y - 10.0) as u32 {
            for x in (rect.min.x + 10.0) as u32..(rect.max.x - 10.0) as u32 {
                let p = image.get_pixel(x, y).0;
                if p[0] == 255 && p[1] == 255 && p[2] == 255 {
                    n += 1;
                }
            }
        }
        (n, image)
    };
    let (before, _) = white(&mut h);
    h.state_mut().state.overlays.hcb_samples = true;
    run_until(&mut h, 30, |a| arrived(a, "hcb.stats"));
    let (after, image) = white(&mut h);
    let _ = image.save(std::env::temp_dir().join("gi_lab_hcb_overlay.png"));
    let stats = h.state().state.lab.as_ref().ok().and_then(|l| l.renderer.hcb_stats()).expect("HCB statistics");
    assert!(stats.samples() > 100, "{}", stats.samples());
    // Dots cover at least a pixel each where samples do not overlap.
    assert!(
        after > before + stats.samples() as usize / 4,
        "white pixels {before} -> {after} for {} samples",
        stats.samples()
    );
}

#[test]
fn the_settings_pane_shows_table_1_and_the_cache_counts_for_the_hcb() {
    let dir = temp_dir("hcb_table_1");
    // Tall, so that the settings pane shows the statistics below the groups.
    let mut h = harness_in(&dir, egui::vec2(1400.0, 2600.0));
    pause(&mut h);
    if let Ok(l) = &mut h.state_mut().state.lab {
        gi_render::settings::pipeline::Technique::NguyenCached.apply(&mut l.settings);
        l.apply_settings();
    }
    h.run_steps(4);
    run_until(&mut h, 30, |a| arrived(a, "hcb.stats"));
    let _ = h.render().map(|i| i.save(std::env::temp_dir().join("gi_lab_hcb_table_1.png")));
    let stats = h.state().state.lab.as_ref().ok().and_then(|l| l.renderer.hcb_stats()).expect("HCB statistics");
    h.get_by_label("HCB statistics (Nguyen Table 1)");
    h.get_by_label("level (resolution)");
    // The total row carries the renderer's count; the cache's rows are there.
    let c = stats.cache.expect("cache counts");
    assert!(c.cached > 0, "{c:?}");
    let shown = |label: &str| h.query_all_by_label(label).count() > 0;
    for label in ["total", &stats.samples().to_string(), "cached (reused)", &c.cached.to_string(), "recomputed"] {
        assert!(shown(label), "'{label}' is shown");
    }
    // The technique picker names the cached HCB.
    let settings = h.state().state.lab.as_ref().map(|l| l.settings.clone()).expect("lab");
    let current = gi_lab::ui::settings_ui::TECHNIQUES.iter().find(|t| (t.is)(&settings)).map(|t| t.name);
    assert_eq!(current, Some("Hierarchical coherence buffer with the sample cache (Nguyen)"));
}

/// Soler et al. (issue #16) in the lab: with the technique picked, visibility and two
/// bounces, every Soler setting is in the settings pane, every Soler buffer (per level, the
/// voxel grids, the bounces, Eq. 6's) is in the viewer's picker and shows without error, and
/// the rings and reach per level are listed.
#[test]
fn soler_settings_buffers_and_reach_appear_in_the_lab() {
    let dir = temp_dir("soler");
    let mut h = harness_in(&dir, egui::vec2(1400.0, 2600.0));
    pause(&mut h);
    // The tall harness at a quarter of its side: the test asks what the lab lists and shows.
    h.state_mut().state.session.render_scale = 0.25;
    if let Ok(l) = &mut h.state_mut().state.lab {
        gi_render::settings::pipeline::Technique::Soler.apply(&mut l.settings);
        l.settings.soler.visibility = true;
        l.settings.soler.bounces = 2;
        l.apply_settings();
    }
    h.run_steps(4);
    let err = h.state().state.lab.as_ref().ok().and_then(|l| l.settings_error.clone());
    assert!(err.is_none(), "{err:?}");
    let settings = h.state().state.lab.as_ref().map(|l| l.settings.clone()).expect("lab");
    let current = gi_lab::ui::settings_ui::TECHNIQUES.iter().find(|t| (t.is)(&settings)).map(|t| t.name);
    assert!(current.is_some_and(|n| n.contains("Soler")), "{current:?}");
    let (_, fields) = LabSettings::groups().into_iter().find(|(g, _)| *g == "soler").expect("soler group");
    for m in fields {
        let path = format!("soler.{}", m.name);
        // (`soler.bounces` is also a pass in the GPU timings.)
        assert!(h.query_all_by_label(&path).next().is_some(), "{path} has no widget");
    }
    h.get_by_label("Soler rings and reach (Fig. 3)");
    // 4 levels from a quarter of the render size, r = 40: the reach is 40 · 2^5 px.
    let reach = format!("reach {:.0} px", settings.soler.reach_px());
    assert_eq!(settings.soler.reach_px(), 1280.0);
    assert!(h.query_all_by_label_contains(&reach).next().is_some(), "'{reach}' is shown");
    // Issue #51 point 4: the levels whose ring starts beyond the image's diagonal are marked.
    let size = h.state().renderer().expect("renderer").size();
    let off = settings.soler.levels_off_image(size).len();
    assert_eq!(h.query_all_by_label_contains("off the image").count(), off, "levels off a {size:?} image");
    // The scale of the scene-relative settings is said (the default box: no room).
    assert!(h.query_all_by_label_contains("scene scale").next().is_some(), "the scene's scale is shown");
    let names = h.state().renderer().expect("renderer").buffers().names();
    let soler: Vec<&String> = names.iter().filter(|n| n.starts_with("soler.")).collect();
    for want in [
        "soler.level.2.position",
        "soler.level.3.normal",
        "soler.level.4.radiance",
        "soler.level.5.winner",
        "soler.level.2.indirect",
        "soler.level.2.occlusion",
        "soler.accum.0",
        "soler.voxels.2",
        "soler.bounce.1",
        "soler.bounce.2",
        "soler.indirect",
        "soler.temporal",
        "soler.temporal.warped",
        "soler.temporal.rejection",
        "soler.temporal.a",
        "soler.level.2.material",
        "soler.level.2.specular",
        "soler.specular.accum.0",
        "soler.bounce.2.specular",
    ] {
        assert!(soler.iter().any(|n| *n == want), "{want} is not registered: {soler:?}");
    }
    h.get_by_label("viewer 1 buffer").click();
    h.run_steps(2);
    for n in &soler {
        assert!(h.query_all_by_label(n).next().is_some(), "buffer {n} is not listed in the viewer's picker");
    }
    // The list is long: the picker's filter field narrows it to the one wanted.
    for n in ["soler.voxels.2", "soler.temporal.rejection", "soler.bounce.2"] {
        show_in_viewer(&mut h, n);
    }
    let _ = h.render().map(|i| i.save(std::env::temp_dir().join("gi_lab_soler_viewer.png")));
}

/// Soler's Fig. 3 right in the lab: View → "Soler samples overlay" draws the ring samples
/// behind the pinned pixel, one colour per level, and names the levels' counts.
#[test]
fn the_soler_samples_overlay_draws_the_rings_behind_a_pixel() {
    let dir = temp_dir("soler_overlay");
    let mut h = harness_in(&dir, egui::vec2(1200.0, 800.0));
    pause(&mut h);
    if let Ok(l) = &mut h.state_mut().state.lab {
        gi_render::settings::pipeline::Technique::Soler.apply(&mut l.settings);
        l.settings.soler.radius_px = 12.0;
        l.apply_settings();
    }
    h.run_steps(4);
    let (w, hh) = h.state().renderer().expect("renderer").size();
    h.state_mut().state.pin_probe((w / 2, hh * 3 / 4));
    // Level 2's colour (the first gathered level from a quarter start).
    let cyan = |h: &mut Harness<'static, GiLabApp>| -> usize {
        let image = h.render().expect("the harness renders");
        // Anti-aliased dots blend with the image: near-cyan counts.
        image.pixels().filter(|p| p.0[0] < 80 && p.0[1] > 150 && p.0[2] > 190 && p.0[2] > p.0[1]).count()
    };
    let before = cyan(&mut h);
    h.state_mut().state.overlays.soler_samples = true;
    // The overlay reads the receivers, then their samples, each a frame or two late.
    run_until(&mut h, 40, |a| {
        a.state
            .lab
            .as_ref()
            .is_ok_and(|l| l.renderer.soler_samples_later(a.state.probes.pinned[0].pixel).is_ok_and(|r| r.is_some()))
    });
    let after = cyan(&mut h);
    let _ = h.render().map(|i| i.save(std::env::temp_dir().join("gi_lab_soler_overlay.png")));
    // (The legend is painted text, not a widget: the renderer's replay stands for it.)
    let pinned = h.state().state.probes.pinned[0].pixel;
    let rings = h.state().renderer().expect("renderer").soler_samples(pinned).expect("the samples");
    assert!(rings.iter().any(|r| r.level == 2 && !r.samples.is_empty()), "level 2's ring: {rings:?}");
    assert!(after > before + 20, "level 2's samples: {before} -> {after} cyan pixels");
}

/// Gautron et al. (issue #17) in the lab: with the technique picked, every Gautron setting
/// has a widget, every Gautron buffer is in the viewer's picker and shows without error, the
/// settings pane lists the record cache's counts, and View → "Gautron records overlay"
/// draws the records with their influence circles.
#[test]
fn gautron_settings_buffers_cache_and_records_appear_in_the_lab() {
    let dir = temp_dir("gautron");
    let mut h = harness_in(&dir, egui::vec2(1400.0, 2600.0));
    pause(&mut h);
    // A tenth of the viewport's side: the tall harness would need thousands of records (at a
    // fifth, this test took 36 s alone; at a tenth 14, with about 190 records, the overlay
    // changing some 80,000 pixels).
    h.state_mut().state.session.render_scale = 0.1;
    if let Ok(l) = &mut h.state_mut().state.lab {
        gi_render::settings::pipeline::Technique::Gautron.apply(&mut l.settings);
        l.apply_settings();
    }
    h.run_steps(8);
    let settings = h.state().state.lab.as_ref().map(|l| l.settings.clone()).expect("lab");
    let current = gi_lab::ui::settings_ui::TECHNIQUES.iter().find(|t| (t.is)(&settings)).map(|t| t.name);
    assert_eq!(current, Some("Irradiance cache splatting (Gautron)"));
    let (_, fields) = LabSettings::groups().into_iter().find(|(g, _)| *g == "gautron").expect("gautron group");
    for m in fields {
        let path = format!("gautron.{}", m.name);
        assert!(h.query_all_by_label(&path).next().is_some(), "{path} has no widget");
    }
    // The cache's counts: the renderer's record count is shown.
    h.get_by_label("Gautron record cache");
    let r = h.state().renderer().expect("renderer");
    let st = r.gautron().and_then(|g| g.read_state(&r.ctx)).expect("cache state");
    assert!(st.count > 50, "{st:?}");
    let count = format!("{} of {}", st.count, settings.gautron.capacity);
    assert!(h.query_all_by_label_contains(&count).next().is_some(), "'{count}' is shown");
    let _ = h.render().map(|i| i.save(std::env::temp_dir().join("gi_lab_gautron_settings.png")));
    // Every buffer in the picker, each shown without error.
    let names = h.state().renderer().expect("renderer").buffers().names();
    let gautron: Vec<String> = names.iter().filter(|n| n.starts_with("gautron.")).cloned().collect();
    for want in [
        "gautron.hemisphere.radiance",
        "gautron.solid_angle",
        "gautron.accum",
        "gautron.irradiance.plain",
        "gautron.candidates",
    ] {
        assert!(gautron.iter().any(|n| n == want), "{want} is not registered: {gautron:?}");
    }
    for n in &gautron {
        show_in_viewer(&mut h, n);
    }
    // The records overlay changes the viewport where the records are.
    let viewport = viewport_pixels;
    let (before, _) = viewport(&mut h);
    h.state_mut().state.overlays.gautron_records = true;
    run_until(&mut h, 30, |a| arrived(a, "gautron.records"));
    let (after, image) = viewport(&mut h);
    let _ = image.save(std::env::temp_dir().join("gi_lab_gautron_records.png"));
    let changed =
        before.iter().zip(&after).filter(|(a, b)| a.iter().zip(b.iter()).any(|(x, y)| x.abs_diff(*y) > 40)).count();
    println!("{} records, the overlay changed {changed} pixels", st.count);
    assert!(changed > 4 * st.count as usize, "{changed} pixels changed for {} records", st.count);
}

/// Issue #19: a setting pushed past the ISM atlas's device limit is clamped to the largest
/// value that fits, and the settings panel says so (as a warning, the value being applied).
#[test]
fn a_value_past_the_atlas_limit_is_clamped_and_the_panel_says_so() {
    let (mut h, _dir) = harness("clamp");
    h.state_mut().state.session.render_scale = 0.1;
    if let Ok(l) = &mut h.state_mut().state.lab {
        l.settings.vpl.count = 4096;
        l.settings.ism.map_size = 32;
        l.settings.ism.points = 262144;
        l.apply_settings();
        assert!(l.settings_error.is_none(), "{:?}", l.settings_error);
        l.settings.ism.map_size = 512;
        l.apply_settings();
    }
    h.run_steps(2);
    let l = h.state().state.lab.as_ref().expect("lab");
    let size = l.renderer.settings().ism.map_size;
    assert!(size < 512 && l.settings.ism.map_size == size, "the panel and the renderer agree on {size}");
    let msg = l.settings_error.clone().unwrap_or_default();
    assert!(msg.starts_with(&format!("clamped: ism.map_size clamped to {size}")), "{msg}");
    h.get_by_label(&msg);
}

/// DDGI (issue #56) in the lab: with the technique picked, every DDGI setting has a widget,
/// every DDGI buffer shows in the viewer, View → "DDGI probes overlay" draws the probes as
/// dots, and a click on one selects that probe and draws its rays of the frame.
#[test]
fn ddgi_settings_buffers_and_probe_overlay_appear_in_the_lab() {
    let dir = temp_dir("ddgi");
    let mut h = harness_in(&dir, egui::vec2(1400.0, 2000.0));
    pause(&mut h);
    h.state_mut().state.session.render_scale = 0.1;
    if let Ok(l) = &mut h.state_mut().state.lab {
        gi_render::settings::pipeline::Technique::Ddgi.apply(&mut l.settings);
        (l.settings.ddgi.probes_x, l.settings.ddgi.probes_y, l.settings.ddgi.probes_z) = (4, 3, 4);
        l.settings.ddgi.rays_per_probe = 32;
        l.apply_settings();
    }
    h.run_steps(4);
    let settings = h.state().state.lab.as_ref().map(|l| l.settings.clone()).expect("lab");
    let current = gi_lab::ui::settings_ui::TECHNIQUES.iter().find(|t| (t.is)(&settings)).map(|t| t.name);
    assert_eq!(current, Some("DDGI probes (Majercik et al.)"));
    let (_, fields) = LabSettings::groups().into_iter().find(|(g, _)| *g == "ddgi").expect("ddgi group");
    for m in fields {
        let path = format!("ddgi.{}", m.name);
        assert!(h.query_all_by_label(&path).next().is_some(), "{path} has no widget");
    }
    for n in
        ["ddgi.indirect", "ddgi.irradiance", "ddgi.atlas.irradiance", "ddgi.atlas.distance", "ddgi.rays", "ddgi.probes"]
    {
        show_in_viewer(&mut h, n);
    }
    let viewport = viewport_pixels;
    let changed = |a: &[[u8; 4]], b: &[[u8; 4]]| {
        a.iter().zip(b).filter(|(a, b)| a.iter().zip(b.iter()).any(|(x, y)| x.abs_diff(*y) > 40)).count()
    };
    let (plain, _) = viewport(&mut h);
    h.state_mut().state.overlays.ddgi_probes = true;
    run_until(&mut h, 30, |a| arrived(a, "ddgi.overlay"));
    let (dots, _) = viewport(&mut h);
    let overlay = h.state().renderer().and_then(|r| r.ddgi_overlay_later(false)).expect("the probes arrived");
    assert!(changed(&plain, &dots) > 10 * overlay.probes.len(), "the dots of {} probes", overlay.probes.len());
    // A probe on screen, away from the viewport's edges: click its dot.
    let rect = h.state().state.viewport_rect;
    let vp = h.state().renderer().expect("renderer").view_proj();
    let at = (0..overlay.probes.len())
        .filter_map(|i| {
            let clip = vp * overlay.position(i).extend(1.0);
            let ndc = clip.truncate() / clip.w;
            let pos = rect.min + egui::vec2((ndc.x * 0.5 + 0.5) * rect.width(), (0.5 - ndc.y * 0.5) * rect.height());
            (clip.w > 0.0 && rect.shrink(60.0).contains(pos)).then_some((i, pos))
        })
        .next();
    let (probe, pos) = at.expect("a probe in view");
    h.drag_at(pos);
    h.run_steps(1);
    h.drop_at(pos);
    h.run_steps(2);
    let selected = h.state().state.overlays.ddgi_selected.expect("the click selected a probe");
    let o = h.state().renderer().and_then(|r| r.ddgi_overlay_later(false)).expect("probes");
    let clip = vp * o.position(selected).extend(1.0);
    let ndc = clip.truncate() / clip.w;
    let got = rect.min + egui::vec2((ndc.x * 0.5 + 0.5) * rect.width(), (0.5 - ndc.y * 0.5) * rect.height());
    assert!(
        got.distance(pos) <= 8.0,
        "probe {selected} (clicked near probe {probe}) lies {} from the click",
        got.distance(pos)
    );
    assert!(h.state().state.probes.pinned.is_empty(), "the click selected a probe, it pinned no pixel");
    run_until(&mut h, 30, |a| arrived(a, "ddgi.overlay.rays"));
    let (rays, image) = viewport(&mut h);
    let _ = image.save(std::env::temp_dir().join("gi_lab_ddgi_overlay.png"));
    let lines = changed(&dots, &rays);
    println!("probe {selected}'s rays changed {lines} pixels");
    assert!(lines > 50, "the probe's rays are drawn: {lines} pixels changed");
}

/// The viewport's pixels (but for its caption rows and edges) as the harness renders them, and
/// the whole image.
fn viewport_pixels(h: &mut Harness<'static, GiLabApp>) -> (Vec<[u8; 4]>, image::RgbaImage) {
    let rect = h.state().state.viewport_rect;
    let image = h.render().expect("the harness renders");
    let mut pixels = Vec::new();
    for y in (rect.min.y + 40.0) as u32..(rect.max.y - 40.0) as u32 {
        for x in (rect.min.x + 10.0) as u32..(rect.max.x - 10.0) as u32 {
            pixels.push(image.get_pixel(x, y).0);
        }
    }
    (pixels, image)
}
