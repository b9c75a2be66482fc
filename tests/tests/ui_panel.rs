//! A settings panel that shows what acts (issue #39 point 4): groups that cannot act on the
//! scene fold into one line that says why, labels are words with the paper's symbol, and the
//! search box filters the settings by name, symbol or paper.

use egui_kittest::kittest::Queryable;
use gi_lab_tests::ui_harness::{harness, pause};

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
