//! The lab in an egui_kittest harness, with its own session and presets folders (the UI
//! tests in tests/ui.rs and tests/ui_lights.rs).

use std::path::PathBuf;

use egui_kittest::Harness;
use gi_lab::args::AppArgs;
use gi_lab::ui::app::GiLabApp;

/// A fresh temporary folder for one test.
pub fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("gi-lab-ui-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("temp dir");
    d
}

/// Arguments that keep the app's session and presets in `dir` (never the user's).
pub fn args_in(dir: &std::path::Path, fresh: bool) -> AppArgs {
    let _ = std::fs::create_dir_all(dir.join("presets"));
    AppArgs {
        config_dir: Some(dir.join("config")),
        presets_dir: dir.join("presets"),
        fresh,
        // Fixed render sizes: the adaptive scale's own test turns it on.
        adaptive_scale: false,
        ..AppArgs::default()
    }
}

/// The app with `args` in a harness of `size` points.
pub fn harness_with(args: AppArgs, size: egui::Vec2) -> Harness<'static, GiLabApp> {
    Harness::builder()
        .with_size(size)
        .wgpu_setup(gi_lab::ui::wgpu_setup())
        .build_eframe(move |cc| GiLabApp::new(cc, args))
}

/// The app in a harness with its own config and presets folders.
pub fn harness_in(dir: &std::path::Path, size: egui::Vec2) -> Harness<'static, GiLabApp> {
    let h = harness_with(args_in(dir, true), size);
    if let Some(e) = h.state().error() {
        panic!(
            "the app could not start its renderer: {e}\n\
             Install Mesa's software Vulkan driver: `sudo apt-get install -y mesa-vulkan-drivers libvulkan1` \
             (or run `bash scripts/test.sh`)"
        );
    }
    h
}

pub fn harness(name: &str) -> (Harness<'static, GiLabApp>, PathBuf) {
    let dir = temp_dir(name);
    (harness_in(&dir, egui::vec2(1400.0, 1000.0)), dir)
}

/// Pauses the animation at t = 0 so that frames repeat exactly.
pub fn pause(h: &mut Harness<'static, GiLabApp>) {
    if let Ok(l) = &mut h.state_mut().state.lab {
        l.renderer.clock.playing = false;
        l.renderer.clock.seek(0.0);
    }
}

/// Shows buffer `name` in viewer 1 through its picker's filter field (opening the picker
/// when it is closed); the viewer must show it without error.
pub fn show_in_viewer(h: &mut Harness<'static, GiLabApp>, name: &str) {
    use egui_kittest::kittest::Queryable;
    if h.query_by_label("viewer 1 buffer filter").is_none() {
        h.get_by_label("viewer 1 buffer").click();
        h.run_steps(2);
    }
    h.get_by_label("viewer 1 buffer filter").click();
    h.run_steps(1);
    h.get_by_label("viewer 1 buffer filter").type_text(name);
    h.run_steps(2);
    h.get_by_label(name).click();
    h.run_steps(3);
    let v = h.state().state.viewers.open.values().next().expect("a viewer");
    assert_eq!(v.state.buffer, name);
    assert!(v.error.is_none(), "{name}: {:?}", v.error);
}

/// Runs frames until `done` holds (at most `max`, then one more): the window reads the GPU
/// without waiting (issue #38), so probes, statistics, overlays and A/B metrics arrive a
/// frame or a few later, more under load.
pub fn run_until(h: &mut Harness<'static, GiLabApp>, max: usize, done: impl Fn(&GiLabApp) -> bool) {
    for _ in 0..max {
        h.run_steps(1);
        if done(h.state()) {
            break;
        }
    }
    h.run_steps(1);
}

/// Whether the read-back `key` of the lab's renderer has arrived.
pub fn arrived(app: &GiLabApp, key: &str) -> bool {
    app.state.lab.as_ref().is_ok_and(|l| l.renderer.read_latest(key).is_some_and(|a| a.data.is_ok()))
}

/// The settings [`cheap_frames`] applies: the passes whose cost does not follow the image
/// (the ISM splat and pull-push, the light views, the shadow map) at their smallest useful
/// sizes. At render scale 0.1 they took about half of a default frame (`gi-lab bench --size
/// 140x360`: 114 → 49 ms on lavapipe, docs/runs/, the "Build and test time" runs).
pub const CHEAP_FRAMES: &[&str] =
    &["vpl.count=32", "ism.points=16384", "ism.map_size=32", "vpl.light_gbuffer_size=64", "direct.shadow_map_size=256"];

/// Makes the lab's frames cheap for the tests that ask what the window does, not what it
/// renders (the random walk, every widget reaching the renderer): [`CHEAP_FRAMES`] applied
/// to the live settings as if typed, before the test's first step.
pub fn cheap_frames(h: &mut Harness<'static, GiLabApp>) {
    let Ok(l) = &mut h.state_mut().state.lab else { panic!("no renderer") };
    for a in CHEAP_FRAMES {
        l.settings.apply_override(a).unwrap_or_else(|e| panic!("{a}: {e}"));
    }
    l.apply_settings();
    assert!(l.settings_error.is_none(), "cheap frames: {:?}", l.settings_error);
    h.run_steps(2);
}
