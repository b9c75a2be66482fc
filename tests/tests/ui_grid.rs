//! The comparison grid (issue #40 point 1) in the window: cells added from the presets
//! folder and the frozen settings and removed again, one camera for every cell, the truth
//! refining and each cell's FLIP against it, a FLIP map shown in a cell, and a cell refused
//! because it would pass the grid's memory budget.

use egui_kittest::kittest::Queryable;
use gi_lab::ui::grid::CellView;
use gi_lab_tests::ui_harness::{harness_in, pause, run_until, temp_dir};

type H = egui_kittest::Harness<'static, gi_lab::ui::app::GiLabApp>;

fn grid(h: &H) -> &gi_lab::ui::grid::Grid {
    h.state().state.grid.as_ref().expect("the grid is open")
}

fn add(h: &mut H, entry: &str) {
    h.get_by_label("Add cell").click();
    h.run_steps(2);
    h.get_by_label(entry).click();
    h.run_steps(2);
}

#[test]
fn cells_are_added_removed_share_the_camera_and_compare_with_the_truth() {
    let dir = temp_dir("grid");
    std::fs::create_dir_all(dir.join("presets")).expect("presets folder");
    for p in ["knecht-cornell-256.ron", "soler-quarter-4-64.ron", "nguyen-hcb.ron"] {
        let from = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../presets").join(p);
        std::fs::copy(from, dir.join("presets").join(p)).expect("copy preset");
    }
    let mut h = harness_in(&dir, egui::vec2(1400.0, 1000.0));
    pause(&mut h);
    h.run_steps(2);
    h.get_by_label("View").click();
    h.run_steps(2);
    h.get_by_label("Compare grid").click();
    h.run_steps(2);
    assert!(h.state().state.grid.is_some(), "View → Compare grid opens the grid");

    // Cells: two presets and the frozen settings, then one removed.
    add(&mut h, "knecht-cornell-256.ron");
    add(&mut h, "the current settings (frozen)");
    add(&mut h, "soler-quarter-4-64.ron");
    let names: Vec<String> = grid(&h).cells.iter().map(|c| c.name.clone()).collect();
    assert_eq!(names, ["knecht-cornell-256", "frozen settings", "soler-quarter-4-64"], "{:?}", grid(&h).message);
    for caption in [
        "instant radiosity (Knecht)",
        "screen-space mip levels (Soler)",
        "differs in",
        "the same settings as the live ones",
    ] {
        assert!(h.get_all_by_label_contains(caption).next().is_some(), "a caption says '{caption}'");
    }
    h.get_all_by_label("remove").nth(1).expect("the frozen cell's remove button").click();
    // The grid renders at least one cell a frame, in turn: under load (two test binaries on
    // two cores) one a frame, so four frames render each of the two cells at least once.
    h.run_steps(4);
    let names: Vec<String> = grid(&h).cells.iter().map(|c| c.name.clone()).collect();
    assert_eq!(names, ["knecht-cornell-256", "soler-quarter-4-64"]);
    let live_size = h.state().renderer().expect("renderer").size();
    for c in &grid(&h).cells {
        assert_eq!(c.renderer.size(), live_size, "a cell renders at the live renderer's size");
        assert!(c.frame_ms > 0.0, "{} has a frame time", c.name);
        assert!(c.bytes.is_some_and(|b| b > 0), "{}'s GPU memory is measured", c.name);
    }

    // One camera: a drag in the top-right cell orbits the camera every cell renders with.
    let before = h.state().renderer().expect("renderer").camera;
    let area = h.state().state.viewport_rect;
    let at = area.min + egui::vec2(area.width() * 0.75, area.height() * 0.2);
    h.drag_at(at);
    h.run_steps(1);
    for k in 1..=6 {
        h.event(egui::Event::PointerMoved(at + egui::vec2(8.0 * k as f32, 0.0)));
        h.run_steps(1);
    }
    h.drop_at(at + egui::vec2(48.0, 0.0));
    h.run_steps(4);
    let after = h.state().renderer().expect("renderer").camera;
    assert_ne!(format!("{before:?}"), format!("{after:?}"), "the drag in a cell moved the camera");
    for c in &grid(&h).cells {
        assert_eq!(format!("{:?}", c.renderer.camera), format!("{after:?}"), "{} follows the camera", c.name);
    }

    // The truth refines in the background; every cell gets its FLIP against it.
    h.get_by_label("truth").click();
    run_until(&mut h, 600, |app| {
        let g = app.state.grid.as_ref().expect("grid");
        g.truth.as_ref().is_some_and(|t| t.spp >= 2)
            && g.live.flip.is_some()
            && g.cells.iter().all(|c| c.shown.flip.is_some())
    });
    let g = grid(&h);
    for f in std::iter::once(g.live.flip).chain(g.cells.iter().map(|c| c.shown.flip)) {
        let f = f.expect("a FLIP");
        assert!(f > 0.0 && f < 1.0, "FLIP {f}");
    }
    assert!(h.get_all_by_label_contains("spp)").next().is_some(), "the captions give the truth's spp of their FLIP");
    // On lavapipe the truth is the CPU's, and its caption says so (issue #56).
    assert!(grid(&h).truth.as_ref().is_some_and(|t| t.tracer == "CPU path tracer"));
    assert!(
        h.get_all_by_label_contains("CPU path tracer, 1 bounce(s)").next().is_some(),
        "the truth's caption names its tracer"
    );

    // A FLIP map in the first added cell, through its view menu.
    h.get_by_label("view of knecht-cornell-256").click();
    h.run_steps(2);
    h.get_by_label("FLIP map").click();
    h.run_steps(3);
    assert_eq!(grid(&h).cells[0].shown.view, Some(CellView::Flip));
    assert!(grid(&h).cells[0].shown.flip_map.is_some(), "the FLIP map is a texture");

    // A cell that would pass the memory budget is refused, and says why: the budget is set
    // to what the two cells take plus one MiB.
    let used = grid(&h).memory_bytes() as f64 / 1048576.0;
    h.state_mut().state.grid.as_mut().expect("grid").memory_budget_mib = used.ceil() as u32 + 1;
    add(&mut h, "nguyen-hcb.ron");
    assert_eq!(grid(&h).cells.len(), 2, "the cell was refused");
    let msg = grid(&h).message.clone().expect("a message");
    assert!(msg.contains("nguyen-hcb not added") && msg.contains("MiB"), "{msg}");
    h.get_by_label_contains("not added");
    if let Ok(path) = std::env::var("GI_LAB_SCREENSHOT") {
        run_until(&mut h, 400, |app| {
            app.state.grid.as_ref().and_then(|g| g.truth.as_ref()).is_some_and(|t| t.spp >= 24)
        });
        h.run_steps(20);
        let image = h.render().expect("the harness renders");
        image.save(path).expect("screenshot");
    }
    // On a real GPU the truth is the GPU path tracer's, on the window's device: started here
    // with lavapipe's device, it refines and the cells compare with it the same way.
    let ctx = h.state().renderer().expect("renderer").ctx.clone();
    h.state_mut().state.grid.as_mut().expect("grid").truth = Some(gi_lab::ui::grid::Truth::start(1, Some(ctx)));
    run_until(&mut h, 600, |app| {
        let g = app.state.grid.as_ref().expect("grid");
        g.truth.as_ref().is_some_and(|t| t.spp >= 2 && t.image.is_some())
    });
    let t = grid(&h).truth.as_ref().expect("the truth");
    assert!(t.tracer.starts_with("GPU path tracer"), "{}", t.tracer);
    let img = t.image.as_ref().expect("an image");
    assert!(img.data.iter().any(|p| p[0] > 0.0), "the GPU truth lights the box");
    h.get_by_label("Close grid").click();
    h.run_steps(2);
    assert!(h.state().state.grid.is_none());
    let _ = std::fs::remove_dir_all(dir);
}
