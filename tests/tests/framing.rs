//! Issue #37 points 1–3: a scene without a glTF camera or lights opens framed and lit. Each
//! generated case (`scene::framing_cases`: a box room, two rooms joined by a door, a long
//! corridor, a closed sphere, an object with no floor, a floor plan without a ceiling, a room
//! with two cameras) is loaded as a glTF file in metres and in millimetres; its geometry
//! covers at least half of the frame and at least 60 % of the covered pixels are above black
//! after auto exposure; the window and the command line choose the same view.

use gi_lab_tests::gpu;
use gi_render::scene::framing::ViewKind;
use gi_render::scene::{LoadOptions, Scene, framing_cases, load_gltf_bytes};
use gi_render::{LabSettings, Renderer};

fn load(name: &str, unit: f32) -> Scene {
    let bytes = framing_cases::case_glb(name, unit).expect("a known case");
    load_gltf_bytes(&bytes, None, &LoadOptions::default()).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// The kind of view each case must open on.
fn expected_kind(name: &str) -> ViewKind {
    match name {
        "object" | "floor-plan" => ViewKind::Exterior,
        "two-cameras" => ViewKind::SceneCamera { index: 0, count: 2 },
        _ => ViewKind::Interior,
    }
}

/// Geometry coverage of the frame and the lit share of the covered pixels (final.ldr, a
/// channel above 12/255) after a few frames of the default technique.
fn coverage_and_lit(scene: Scene) -> (f64, f64) {
    let mut r = Renderer::new(gpu(), scene, LabSettings::default(), 80, 48).expect("renderer");
    r.clock.playing = false;
    for _ in 0..6 {
        r.render_frame();
    }
    let normal = r.readback("gbuffer.normal").expect("normals");
    let ldr = r.readback("final.ldr").expect("ldr");
    let covered: Vec<usize> = (0..normal.data.len()).filter(|&i| normal.data[i][3] > 0.5).collect();
    let lit = covered.iter().filter(|&&i| ldr.data[i][..3].iter().any(|c| *c > 12.0 / 255.0)).count();
    (covered.len() as f64 / normal.data.len() as f64, lit as f64 / covered.len().max(1) as f64)
}

#[test]
fn every_generated_case_opens_framed_and_lit_in_metres_and_millimetres() {
    let mut report = Vec::new();
    for name in framing_cases::CASES {
        for unit in [1.0, 1000.0] {
            let scene = load(name, unit);
            let view = scene.view.clone().expect("the loader chose a view");
            assert_eq!(view.kind, expected_kind(name), "{name} ×{unit}: {}", view.reason);
            assert!(!scene.lights.is_empty(), "{name} ×{unit}: no default light");
            if unit > 1.0 && name != "object" {
                // Millimetres are read from the extent and scaled to metres (an object 1.3 m
                // across, 1,300 units, reads as centimetres: the rule cannot tell).
                let (scale, note) = scene.units.clone().expect("the unit is read from the extent");
                assert_eq!(scale, 0.001, "{name}: {note}");
            }
            let (coverage, lit) = coverage_and_lit(scene);
            report.push(format!("{name} ×{unit}: coverage {coverage:.2}, lit {lit:.2} — {}", view.reason));
            assert!(coverage >= 0.5, "{name} ×{unit}: geometry covers {coverage:.2} of the frame ({})", view.reason);
            assert!(lit >= 0.6, "{name} ×{unit}: {lit:.2} of the covered pixels are lit ({})", view.reason);
        }
    }
    eprintln!("{}", report.join("\n"));
}

/// The same case in metres and in millimetres opens on the same view, in metres.
#[test]
fn millimetres_open_on_the_view_of_metres() {
    for name in ["box-room", "two-rooms", "corridor", "floor-plan", "two-cameras"] {
        let (m, mm) = (load(name, 1.0), load(name, 1000.0));
        let (a, b) = (m.view.expect("view").camera, mm.view.expect("view").camera);
        assert!(a.position.distance(b.position) < 1e-3, "{name}: {} against {}", a.position, b.position);
        assert!((a.yaw - b.yaw).abs() < 1e-3 && (a.pitch - b.pitch).abs() < 1e-3, "{name}");
        assert!((a.znear - b.znear).abs() < 1e-4, "{name}: near planes {} and {}", a.znear, b.znear);
    }
}

/// The interior view stands inside the room at eye height, looking along its longest free
/// direction; the light hangs under the ceiling.
#[test]
fn the_interior_view_stands_at_eye_height_in_the_largest_room() {
    let scene = load("two-rooms", 1.0);
    let view = scene.view.clone().expect("view");
    let room = view.room.expect("an interior view has a room");
    // Room A (x ∈ [0, 5]) is larger than room B (x ∈ [5, 8.5]); both are 2.7 m high.
    assert!((room.ceiling - room.floor - 2.7).abs() < 0.05, "{room:?}");
    assert!((view.camera.position.y - 1.6).abs() < 0.05, "eye height {}", view.camera.position.y);
    assert!(
        view.camera.position.x < 5.0,
        "the camera stands in room A: {} ({room:?}, {})",
        view.camera.position,
        view.reason
    );
    let light = scene.nodes.iter().find(|n| n.light.is_some()).expect("light").transform.translation;
    assert!(light.y > 2.0 && light.y < 2.7, "the light hangs under the ceiling: {light}");
    // The corridor: looking along it.
    let corridor = load("corridor", 1.0).view.expect("view");
    let f = corridor.camera.forward();
    assert!(f.x.abs() > 0.9, "the corridor runs along x; the camera looks along {f}");
}

/// An exterior view fits the geometry's projected extent: the object fills most of the
/// frame, and the lab adds a sun and a sky that the path tracer sees too.
#[test]
fn the_exterior_view_is_fitted_and_lit_by_sun_and_sky() {
    let scene = load("object", 1.0);
    assert!(scene.sky.is_lit(), "the neutral sky is on for an open scene");
    assert!(scene.lights.iter().any(|l| l.name == "default sun"));
    let (coverage, _) = coverage_and_lit(scene.clone());
    assert!(coverage >= 0.5, "the object fills {coverage:.2} of the frame");
    // Removing the default light takes the sun and the sky away.
    let mut s = scene;
    s.remove_default_light();
    assert!(s.lights.is_empty() && !s.sky.enabled && s.default_light_note().is_none());
}

/// The command line (`scene_args::load_scene`, unit scale 0 = read from the scene) and the
/// window (the lab opening the same file) choose the same camera, for every case (in
/// millimetres: the unit is read the same way too).
#[test]
fn window_and_command_line_choose_the_same_view() {
    let dir = gi_lab_tests::ui_harness::temp_dir("framing");
    for name in framing_cases::CASES {
        let path = dir.join(format!("{name}-mm.glb"));
        std::fs::write(&path, framing_cases::case_glb(name, 1000.0).expect("case")).expect("write");
        let args = gi_lab::scene_args::SceneArgs { scene: Some(path.clone()), ..Default::default() };
        let cli_scene = gi_lab::scene_args::load_scene(&args).expect("the CLI loads it");
        let mut h = gi_lab_tests::ui_harness::harness_in(&dir, egui::vec2(900.0, 700.0));
        // The view is chosen from the scene and the aspect, not from the pixels: small frames.
        h.state_mut().state.session.render_scale = 0.05;
        h.run_steps(2);
        h.state_mut().open_scene(&path.to_string_lossy(), 0.0).expect("the window opens it");
        h.run_steps(2);
        let r = h.state().renderer().expect("renderer");
        let (w, hh) = r.size();
        let cli = gi_render::renderer::default_camera(&cli_scene, cli_scene.bounds(0.0), w as f32 / hh as f32);
        let window = gi_render::renderer::default_camera(r.scene(), r.bounds(), w as f32 / hh as f32);
        assert!(cli.position.distance(window.position) < 1e-4, "{name}: {} against {}", cli.position, window.position);
        assert!((cli.yaw - window.yaw).abs() < 1e-4 && (cli.pitch - window.pitch).abs() < 1e-4, "{name}");
        assert!(
            r.camera.position.distance(window.position) < 1e-3,
            "{name}: the window opened on {}",
            r.camera.position
        );
        let status = h.state().state.status.as_ref().map(|s| s.0.clone()).unwrap_or_default();
        assert!(status.contains("view:") && status.contains("units:"), "{name}: status {status}");
    }
}

/// The Scene panel's "Remove the default light" (issue #37 point 3): one click takes away
/// the sun and the sky the lab added to an open scene, in the renderer the window draws.
#[test]
fn one_click_in_the_scene_panel_removes_the_default_light() {
    use egui_kittest::kittest::Queryable;
    let dir = gi_lab_tests::ui_harness::temp_dir("framing-remove-light");
    let path = dir.join("object-m.glb");
    std::fs::write(&path, framing_cases::case_glb("object", 1.0).expect("case")).expect("write");
    let mut h = gi_lab_tests::ui_harness::harness_in(&dir, egui::vec2(1200.0, 900.0));
    // What the click does to the scene is asked, not what the frames show: small frames.
    h.state_mut().state.session.render_scale = 0.05;
    h.run_steps(2);
    h.state_mut().open_scene(&path.to_string_lossy(), 0.0).expect("the window opens it");
    h.run_steps(2);
    {
        let scene = h.state().renderer().expect("renderer").scene();
        assert!(scene.lights.iter().any(|l| l.name == "default sun") && scene.sky.enabled);
    }
    h.get_by_label("Scene & timeline").click();
    h.run_steps(2);
    h.get_by_label("Remove the default light").click();
    h.run_steps(2);
    let scene = h.state().renderer().expect("renderer").scene();
    assert!(scene.lights.is_empty(), "{:?}", scene.lights);
    assert!(!scene.sky.enabled && scene.default_light_note().is_none());
    assert!(h.query_by_label("Remove the default light").is_none(), "the button goes with the light");
}

/// Issue #51 point 4: the scene-relative settings scale with the room the camera stands in.
/// In "two-rooms" the camera opens in room A, smaller than the model: the scale is half the
/// diagonal of its mean spans and height, and the HCB's d_max (`hcb.d_max_m` = 0) 0.1 of it; with
/// `scale.reference = Model`, or with the camera moved into room B (not the framed room), it
/// is the model's bounding radius again.
#[test]
fn scene_relative_settings_scale_with_the_room_the_camera_is_in() {
    use gi_render::scale::{ScaleReference, ScaleSource, room_box};
    let scene = load("two-rooms", 1.0);
    let room = scene.view.as_ref().and_then(|v| v.room).expect("an interior view has a room");
    let mut r = Renderer::new(gpu(), scene, LabSettings::default(), 64, 48).expect("renderer");
    r.clock.playing = false;
    let model = r.bounds().radius();
    let (scale, from) = r.scale();
    let in_room = room_box(&room).expect("the room's box");
    assert_eq!(from, ScaleSource::Room(in_room));
    let want = 0.5 * (room.size.length_squared() + (room.ceiling - room.floor).powi(2)).sqrt();
    assert!((scale - want).abs() < 1e-5 && scale < 0.9 * model, "room {scale} ({room:?}), model {model}");
    let mut s = r.settings().clone();
    gi_render::settings::pipeline::Technique::Nguyen.apply(&mut s);
    r.set_settings(s.clone()).expect("the HCB");
    r.render_frame();
    let d_max = r.hcb_stats().expect("HCB statistics").d_max;
    assert!((d_max - 0.1 * scale).abs() < 1e-5, "d_max {d_max} against 0.1 × the room's {scale}");
    s.scale.reference = ScaleReference::Model;
    r.set_settings(s.clone()).expect("the model's scale");
    assert_eq!(r.scale(), (model, ScaleSource::Model));
    r.render_frame();
    let d_max = r.hcb_stats().expect("HCB statistics").d_max;
    assert!((d_max - 0.1 * model).abs() < 1e-5, "d_max {d_max} against 0.1 × the model's {model}");
    // In room B, which the loader did not frame: the model's radius.
    s.scale.reference = ScaleReference::Room;
    r.set_settings(s).expect("the room's scale");
    r.camera.position.x = in_room.max.x + 0.5 * (r.bounds().max.x - in_room.max.x);
    assert_eq!(r.scale().1, ScaleSource::Model, "camera at {} outside {room:?}", r.camera.position);
}
