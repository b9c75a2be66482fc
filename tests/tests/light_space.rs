//! Issue #53: the light-space passes (shadow maps, light G-buffers with their importance, a
//! fixed VPL set with its ISMs or exact maps) run only when something they depend on changed,
//! and keeping them changes no pixel.

use gi_lab_tests::*;
use gi_render::Renderer;
use gi_render::settings::pipeline::{Technique, VplVisibility};

/// The passes a still frame keeps with a fixed VPL set.
const KEPT: [&str; 6] =
    ["direct.shadow", "vpl.light_gbuffer", "vpl.importance", "vpl.sample", "ism.splat", "ism.pull_push"];

fn renderer(visibility: VplVisibility, keep: bool) -> Renderer {
    let mut r = paused_renderer(48, Technique::Knecht, |s| {
        s.vpl.new_set_each_frame = false;
        s.pipeline.vpl_visibility = visibility;
    });
    r.keep_light_space = keep;
    r
}

/// The passes of one frame and the light-space counts it added (runs, kept).
fn frame(r: &mut Renderer) -> (Vec<String>, (u64, u64)) {
    let before = gi_render::counters::now();
    let names = r.render_frame().into_iter().map(|t| t.name).collect();
    let d = gi_render::counters::now() - before;
    (names, (d.light_space_runs, d.light_space_skips))
}

fn bits(i: &gi_render::ImageF32) -> Vec<u32> {
    i.data.iter().flatten().map(|x| x.to_bits()).collect()
}

#[test]
fn a_still_frame_keeps_the_light_space_passes_and_changes_no_pixel() {
    for visibility in [VplVisibility::Imperfect, VplVisibility::Exact] {
        let mut kept = renderer(visibility, true);
        let (first, counts) = frame(&mut kept);
        assert_eq!(counts, (3, 0), "{visibility:?}: the first frame makes the maps, the light views and the set");
        assert!(first.iter().any(|n| n == "direct.shadow"), "{visibility:?}: {first:?}");
        for _ in 0..4 {
            let (names, counts) = frame(&mut kept);
            assert_eq!(counts, (0, 3), "{visibility:?}: a still frame keeps all three");
            for pass in KEPT.iter().chain(&["vpl.shadow"]) {
                assert!(!names.iter().any(|n| n == pass), "{visibility:?}: {pass} ran in a still frame: {names:?}");
            }
        }
        let mut redone = renderer(visibility, false);
        for _ in 0..5 {
            let (names, counts) = frame(&mut redone);
            assert_eq!(counts, (3, 0), "{visibility:?}: keep_light_space off redoes them");
            assert!(names.iter().any(|n| n == "vpl.light_gbuffer"), "{visibility:?}: {names:?}");
        }
        let (a, b) = (read(&kept, "final.hdr"), read(&redone, "final.hdr"));
        assert!(a.data.iter().flatten().any(|x| *x > 0.0), "{visibility:?}: the image is black");
        assert!(bits(&a) == bits(&b), "{visibility:?}: keeping the light-space passes changed the image");
    }
}

#[test]
fn a_moved_light_or_object_or_a_setting_redoes_them() {
    let mut r = renderer(VplVisibility::Imperfect, true);
    frame(&mut r);
    assert_eq!(frame(&mut r).1, (0, 3));
    let scene = r.scene();
    let light = scene.nodes.iter().position(|n| n.light.is_some()).expect("the default box has a light");
    let object = scene.nodes.iter().position(|n| n.mesh.is_some()).expect("and objects");
    r.scene_mut().nodes[light].transform.translation.x += 0.05;
    let (names, counts) = frame(&mut r);
    assert_eq!(counts, (3, 0), "a moved light redoes all three");
    for pass in KEPT {
        assert!(names.iter().any(|n| n == pass), "{pass} missing after the light moved: {names:?}");
    }
    assert_eq!(frame(&mut r).1, (0, 3), "and the next still frame keeps them again");
    r.scene_mut().nodes[object].transform.translation.y += 0.01;
    assert_eq!(frame(&mut r).1, (3, 0), "a moved object redoes all three");
    frame(&mut r);
    let mut s = r.settings().clone();
    s.vpl.importance_bias *= 0.5;
    r.set_settings(s).expect("valid settings");
    assert_eq!(frame(&mut r).1, (2, 1), "a VPL setting redoes the light views and the set, not the shadow maps");
    let mut s = r.settings().clone();
    s.direct.pcf_radius += 1;
    r.set_settings(s).expect("valid settings");
    assert_eq!(frame(&mut r).1, (3, 0), "a setting of the direct light redoes all three");
    r.resize(40, 40).expect("resize");
    frame(&mut r);
    assert_eq!(frame(&mut r).1, (0, 3), "a resized window keeps them (they are in light space)");
}

#[test]
fn a_new_vpl_set_each_frame_is_made_every_frame_while_the_maps_are_kept() {
    let mut r = paused_renderer(48, Technique::Knecht, |s| s.vpl.new_set_each_frame = true);
    frame(&mut r);
    let (names, counts) = frame(&mut r);
    assert_eq!(counts, (1, 2), "the set is new, the shadow maps and the light views are kept");
    for pass in ["vpl.sample", "ism.splat", "ism.pull_push"] {
        assert!(names.iter().any(|n| n == pass), "{pass} missing: {names:?}");
    }
    for pass in ["direct.shadow", "vpl.light_gbuffer", "vpl.importance"] {
        assert!(!names.iter().any(|n| n == pass), "{pass} ran: {names:?}");
    }
}
