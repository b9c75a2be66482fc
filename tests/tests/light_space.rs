//! Issue #53: the light-space passes (shadow maps, light G-buffers with their importance, a
//! fixed VPL set with its ISMs or exact maps) and the camera's G-buffer and direct light run
//! only when something they depend on changed, and keeping them changes no pixel.

use gi_lab_tests::*;
use gi_render::Renderer;
use gi_render::settings::pipeline::{Technique, VplVisibility};

/// The passes a still frame keeps with a fixed VPL set: in light space …
const KEPT: [&str; 6] =
    ["direct.shadow", "vpl.light_gbuffer", "vpl.importance", "vpl.sample", "ism.splat", "ism.pull_push"];
/// … and in screen space.
const KEPT_SCREEN: [&str; 2] = ["gbuffer", "direct"];

fn renderer(visibility: VplVisibility, keep: bool) -> Renderer {
    let mut r = paused_renderer(48, Technique::Knecht, |s| {
        s.vpl.new_set_each_frame = false;
        s.pipeline.vpl_visibility = visibility;
    });
    r.reuse_unchanged = keep;
    r
}

/// The passes of one frame and the counts it added: light space (runs, kept), then the
/// G-buffer's and the direct light's.
fn frame(r: &mut Renderer) -> (Vec<String>, (u64, u64), (u64, u64)) {
    let before = gi_render::counters::now();
    let names = r.render_frame().into_iter().map(|t| t.name).collect();
    let d = gi_render::counters::now() - before;
    (names, (d.light_space_runs, d.light_space_skips), (d.screen_space_runs, d.screen_space_skips))
}

fn counts(r: &mut Renderer) -> ((u64, u64), (u64, u64)) {
    let (_, light, screen) = frame(r);
    (light, screen)
}

fn bits(i: &gi_render::ImageF32) -> Vec<u32> {
    i.data.iter().flatten().map(|x| x.to_bits()).collect()
}

#[test]
fn a_still_frame_keeps_the_light_space_passes_and_changes_no_pixel() {
    for visibility in [VplVisibility::Imperfect, VplVisibility::Exact] {
        let mut kept = renderer(visibility, true);
        let (first, light, screen) = frame(&mut kept);
        assert_eq!(light, (3, 0), "{visibility:?}: the first frame makes the maps, the light views and the set");
        assert_eq!(screen, (2, 0), "{visibility:?}: and the G-buffer and the direct light");
        assert!(first.iter().any(|n| n == "direct.shadow"), "{visibility:?}: {first:?}");
        // The second frame redraws the G-buffer: the first one's movement buffer had no
        // previous frame.
        frame(&mut kept);
        for _ in 0..4 {
            let (names, light, screen) = frame(&mut kept);
            assert_eq!((light, screen), ((0, 3), (0, 2)), "{visibility:?}: a still frame keeps all five");
            let visibility_passes: &[&str] =
                if visibility == VplVisibility::Exact { &["vpl.shadow"] } else { &["ism.splat", "ism.pull_push"] };
            let mut listed =
                vec!["gbuffer", "direct.shadow", "direct", "vpl.light_gbuffer", "vpl.importance", "vpl.sample"];
            listed.extend(visibility_passes);
            assert_eq!(kept.kept_passes(), listed, "{visibility:?}: the passes the window lists as kept");
            for pass in KEPT.iter().chain(&KEPT_SCREEN).chain(&["vpl.shadow"]) {
                assert!(!names.iter().any(|n| n == pass), "{visibility:?}: {pass} ran in a still frame: {names:?}");
            }
        }
        let mut redone = renderer(visibility, false);
        for _ in 0..6 {
            let (names, light, screen) = frame(&mut redone);
            assert_eq!((light, screen), ((3, 0), (2, 0)), "{visibility:?}: reuse_unchanged off redoes them");
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
    frame(&mut r);
    assert_eq!(counts(&mut r), ((0, 3), (0, 2)));
    let scene = r.scene();
    let light = scene.nodes.iter().position(|n| n.light.is_some()).expect("the default box has a light");
    let object = scene.nodes.iter().position(|n| n.mesh.is_some()).expect("and objects");
    r.scene_mut().nodes[light].transform.translation.x += 0.05;
    let (names, light, screen) = frame(&mut r);
    assert_eq!(light, (3, 0), "a moved light redoes the light space");
    assert_eq!(screen, (1, 1), "and the direct light, not the G-buffer");
    for pass in KEPT.iter().chain(&["direct"]) {
        assert!(names.iter().any(|n| n == pass), "{pass} missing after the light moved: {names:?}");
    }
    assert_eq!(r.kept_passes(), ["gbuffer"], "only the G-buffer was kept");
    assert_eq!(counts(&mut r), ((0, 3), (0, 2)), "the next still frame keeps them again");
    r.scene_mut().nodes[object].transform.translation.y += 0.01;
    assert_eq!(counts(&mut r), ((3, 0), (2, 0)), "a moved object redoes all five");
    // The movement buffer still holds the motion: the first still frame redraws it.
    assert_eq!(counts(&mut r), ((0, 3), (2, 0)), "the first still frame after a move redraws the G-buffer");
    assert_eq!(counts(&mut r), ((0, 3), (0, 2)));
    r.camera.position.x += 0.01;
    assert_eq!(counts(&mut r), ((0, 3), (2, 0)), "a moved camera redoes the screen, not the light space");
    frame(&mut r);
    let mut s = r.settings().clone();
    s.vpl.importance_bias *= 0.5;
    r.set_settings(s).expect("valid settings");
    let (light, screen) = counts(&mut r);
    assert_eq!(light, (2, 1), "a VPL setting redoes the light views and the set, not the shadow maps");
    assert_eq!(screen.1, 1, "and keeps the G-buffer: {screen:?}");
    let mut s = r.settings().clone();
    s.direct.pcf_radius += 1;
    r.set_settings(s).expect("valid settings");
    let (light, screen) = counts(&mut r);
    assert_eq!(light, (3, 0), "a setting of the direct light redoes the light space");
    assert!(screen.0 >= 1, "and the direct light: {screen:?}");
    frame(&mut r);
    assert_eq!(counts(&mut r), ((0, 3), (0, 2)));
    r.resize(40, 40).expect("resize");
    assert_eq!(counts(&mut r).1, (2, 0), "a resized window redoes the screen");
    frame(&mut r);
    assert_eq!(counts(&mut r), ((0, 3), (0, 2)), "the light space stayed");
}

#[test]
fn a_new_vpl_set_each_frame_is_made_every_frame_while_the_maps_are_kept() {
    let mut r = paused_renderer(48, Technique::Knecht, |s| s.vpl.new_set_each_frame = true);
    frame(&mut r);
    frame(&mut r);
    let (names, light, screen) = frame(&mut r);
    assert_eq!(light, (1, 2), "the set is new, the shadow maps and the light views are kept");
    assert_eq!(screen, (0, 2), "the G-buffer and the direct light are kept");
    for pass in ["vpl.sample", "ism.splat", "ism.pull_push"] {
        assert!(names.iter().any(|n| n == pass), "{pass} missing: {names:?}");
    }
    for pass in ["direct.shadow", "vpl.light_gbuffer", "vpl.importance"] {
        assert!(!names.iter().any(|n| n == pass), "{pass} ran: {names:?}");
    }
}

/// Every shipped preset, paused: the frames with the passes kept give the image of the frames
/// that redo every pass, and the third frame (the first it can) keeps at least the G-buffer
/// (the Gautron and Soler mixes keep the HCB's samples and the hemispheres at them as well).
/// Bit for bit, since both runs compute the same frames — except where a kept pass does not
/// give the same bits twice: the HCB's sample list is appended to atomically, so its order,
/// and the order in which the splat sums the samples lit at it, varies between builds (about
/// 10⁻⁵ relative). There a kept result is the second frame's, so it may differ from the
/// third by at most the redone frames' step from the second to the third and one more for
/// the variation between the two runs, and by one half-float step of `final.hdr` where the
/// sums' order flips its rounding (the sample cache's still view may keep its order from
/// frame to frame, so that the frames' own step is 0). The variation between runs is measured
/// too, by a second run that redoes every pass: under load the two runs' orders may differ
/// more than one run's frames do (a kept frame differed by two half steps where the frames'
/// own step was a quarter of one, once in a full suite).
#[test]
fn every_shipped_preset_renders_the_same_image_with_the_passes_kept() {
    for path in shipped_presets() {
        let name = path.file_stem().map(|s| s.to_string_lossy().to_string()).unwrap_or_default();
        let loaded = gi_render::preset::load_file(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
        // At most 64 VPLs (the stage choices are what is tested, not the budget), where the
        // preset stays valid so.
        let mut settings = loaded.settings.clone();
        settings.vpl.count = settings.vpl.count.min(64);
        if !settings.validate().is_empty() {
            settings = loaded.settings.clone();
        }
        let run = |reuse: bool| {
            let mut r = Renderer::new(gpu(), default_scene(), settings.clone(), 24, 24).expect("renderer");
            r.clock.playing = false;
            r.reuse_unchanged = reuse;
            let images: Vec<gi_render::ImageF32> = (0..3)
                .map(|_| {
                    r.render_frame();
                    read(&r, "final.hdr")
                })
                .collect();
            (images, r.kept_passes().to_vec())
        };
        let ((kept_images, kept), (redone_images, redone)) = (run(true), run(false));
        assert!(redone.is_empty(), "{name}: reuse off kept {redone:?}");
        assert!(kept.contains(&"gbuffer"), "{name}: the third still frame kept {kept:?}");
        if name.contains("at-hcb-samples") {
            assert!(kept.contains(&"hcb.build"), "{name}: the HCB's samples were redone: {kept:?}");
        }
        let max_diff = |a: &gi_render::ImageF32, b: &gi_render::ImageF32| {
            a.data.iter().flatten().zip(b.data.iter().flatten()).map(|(x, y)| (x - y).abs()).fold(0.0f32, f32::max)
        };
        let steps: Vec<f32> = redone_images[1..].windows(2).map(|w| max_diff(&w[0], &w[1])).collect();
        let (a, b) = (&kept_images[2], &redone_images[2]);
        // The HCB's samples are redone every frame where the cache keeps them (`nguyen-hcb-
        // cached`: `hcb.build` is not kept), and the list is appended to atomically all the
        // same: kept against redone differed there by one half step of `final.hdr` in one
        // value of 2,304, in one run of six (two of three on a loaded machine), once the ISM's
        // pull-push took less time (issue #53).
        let hcb_samples = settings.pipeline.shading_points == gi_render::settings::pipeline::ShadingPoints::HcbSamples;
        if !kept.contains(&"hcb.build") && !hcb_samples {
            assert!(bits(a) == bits(b), "{name}: keeping {kept:?} changed the image");
        } else {
            // The HCB's sample list is appended to atomically, so its order, and the order of
            // the splat's f32 sums, varies from frame to frame and from run to run: the kept
            // frame and the redone one may differ by the redone frames' own steps, and by one
            // step of `final.hdr`'s half floats wherever a sum's last f32 bits flip its
            // rounding (a still view's cached samples can keep their order for a few frames,
            // so the frames' own steps may be 0 while the two runs' orders differ).
            let again = run(false).0;
            let between_runs = max_diff(&redone_images[2], &again[2]);
            let bound = steps.iter().sum::<f32>() + steps.iter().copied().fold(0.0, f32::max) + between_runs;
            let excess = a
                .data
                .iter()
                .flatten()
                .zip(b.data.iter().flatten())
                .map(|(x, y)| (x - y).abs() - gi_render::buffers::half_step(x.abs().max(y.abs())))
                .fold(0.0f32, f32::max);
            let d = max_diff(a, b);
            println!(
                "{name}: redone frames step by {steps:?}, two redone runs differ by {between_runs}; kept against redone {d} ({excess} beyond a half step), bound {bound}"
            );
            assert!(
                excess <= bound,
                "{name}: keeping {kept:?} changed the image by {d}, {excess} beyond a half step and the frames' own {bound}"
            );
        }
    }
}

/// The shipped Cornell box lit by its emissive quad: the emitters' VPLs are the same every
/// frame, so a still frame keeps their maps, the direct light they give and, with a fixed set,
/// the VPLs they bounce — with the image of the frames that redo everything, bit for bit.
#[test]
fn an_emissive_scene_keeps_its_emitters_maps_and_changes_no_pixel() {
    let run = |reuse: bool| {
        let scene = asset_scene("scenes/cornell-box/CornellBox-Original.gltf");
        let mut r = scene_renderer(scene, 32, |s| s.vpl.new_set_each_frame = false);
        r.reuse_unchanged = reuse;
        for _ in 0..5 {
            r.render_frame();
        }
        (read(&r, "final.hdr"), r.kept_passes().to_vec())
    };
    let ((a, kept), (b, redone)) = (run(true), run(false));
    assert!(redone.is_empty(), "reuse off kept {redone:?}");
    for pass in ["emitters.ism.splat", "emitters.ism.pull_push", "direct", "vpl.sample", "ism.splat"] {
        assert!(kept.contains(&pass), "{pass} not kept: {kept:?}");
    }
    assert!(a.data.iter().flatten().any(|x| *x > 0.0), "the image is black");
    assert!(bits(&a) == bits(&b), "keeping {kept:?} changed the image");
}
