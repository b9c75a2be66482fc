//! A settings panel that shows what acts (issue #39 point 4): groups that cannot act on the
//! scene fold into one line that says why, labels are words with the paper's symbol, and the
//! search box filters the settings by name, symbol or paper. And shader hot reload (moved
//! here from ui.rs): a broken shader keeps the last good pipelines and shows the error.

use egui_kittest::kittest::Queryable;
use gi_lab::args::AppArgs;
use gi_lab_tests::ui_harness::{args_in, harness, harness_with, pause, temp_dir};

#[test]
fn idle_groups_fold_with_why_and_the_search_filters_by_name_symbol_and_paper() {
    let (mut h, dir) = harness("panel");
    pause(&mut h);
    h.run_steps(3);
    // The Cornell box has no emissive surfaces and no sky.
    assert!(!h.state().renderer().expect("renderer").scene().has_emitters());
    h.get_by_label("2 · Emissive surfaces as lights — none in this scene");
    h.get_by_label("2 · Sky light — off (Scene panel)");
    assert!(h.query_by_label("emitters.vpls").is_none(), "the folded group shows no widgets");
    // Labels are words with the paper's symbol; the path is the accessible name.
    h.get_by_label("shadow filter radius r");
    assert!(h.query_by_label("direct.pcf_radius").is_some());

    let search = |h: &mut egui_kittest::Harness<'static, gi_lab::ui::app::GiLabApp>, text: &str| {
        h.get_by_label("settings search").click();
        h.run_steps(1);
        h.state_mut().state.settings_search = text.to_string();
        h.run_steps(3);
    };
    // By symbol: the HCB's θ_max, although the HCB is not in use.
    search(&mut h, "θ_max");
    assert!(h.query_by_label("hcb.theta_max_deg").is_some(), "θ_max finds hcb.theta_max_deg");
    h.get_by_label("normal divergence θ_max");
    assert!(h.query_by_label("direct.pcf_radius").is_none(), "other fields are hidden");
    // By paper: every field of Nguyen et al.'s HCB.
    search(&mut h, "nguyen");
    for f in ["hcb.levels", "hcb.d_max_m", "hcb.recompute_period"] {
        assert!(h.query_by_label(f).is_some(), "'nguyen' finds {f}");
    }
    assert!(h.query_by_label("soler.levels").is_none());
    // By words.
    search(&mut h, "splat radius");
    h.get_by_label("splat radius d_max");
    // Cleared: the panel as before.
    search(&mut h, "");
    assert!(h.query_by_label("direct.pcf_radius").is_some());
    assert!(h.query_by_label("hcb.levels").is_none(), "the HCB's section stays folded when not searched");
    let _ = std::fs::remove_dir_all(dir);
}

/// Copies `shaders/` into `dir` (the hot reload test edits the copy).
fn copy_shaders(dir: &std::path::Path) {
    for (path, source) in gi_render::shaders::SOURCES {
        let p = dir.join(path);
        std::fs::create_dir_all(p.parent().expect("folder")).expect("mkdir");
        std::fs::write(p, source).expect("write shader");
    }
}

#[test]
fn shader_hot_reload_keeps_the_last_good_pipeline_and_shows_the_error() {
    let dir = temp_dir("hot");
    let shaders = dir.join("shaders");
    copy_shaders(&shaders);
    let args = AppArgs { shaders_dir: shaders.clone(), hot_reload: Some(true), ..args_in(&dir, true) };
    let mut h = harness_with(args, egui::vec2(1400.0, 1000.0));
    h.run_steps(2);
    assert!(h.state().state.hot.enabled(), "hot reload is on");
    let file = shaders.join("direct/direct.wgsl");
    let good = std::fs::read_to_string(&file).expect("read");
    std::fs::write(&file, format!("{good}\nfn broken( {{\n")).expect("write");
    let mut waited = 0;
    while h.state().state.hot.errors.is_empty() && waited < 100 {
        std::thread::sleep(std::time::Duration::from_millis(50));
        h.run_steps(1);
        waited += 1;
    }
    let err = h.state().state.hot.errors.get("direct/direct.wgsl").cloned().expect("the error is reported");
    assert!(err.contains("direct/direct.wgsl"), "{err}");
    let frames = h.state().renderer().expect("renderer").clock.frame;
    h.run_steps(3);
    assert!(
        h.state().renderer().expect("renderer").clock.frame >= frames + 3,
        "the last good pipelines keep rendering"
    );
    assert!(
        h.query_by_label("Shader error — the last good pipelines keep running:").is_some(),
        "the error is shown over the viewport"
    );
    // Fixed (with a harmless edit): the error goes and only the direct pass is rebuilt.
    std::fs::write(&file, format!("{good}\n// edited\n")).expect("write");
    let mut waited = 0;
    while !h.state().state.hot.errors.is_empty() && waited < 100 {
        std::thread::sleep(std::time::Duration::from_millis(50));
        h.run_steps(1);
        waited += 1;
    }
    assert!(h.state().state.hot.errors.is_empty(), "{:?}", h.state().state.hot.errors);
    let m = h.state().state.hot.last_reload.clone().expect("reloaded");
    assert!(m.ends_with("rebuilt direct"), "{m}");
}
