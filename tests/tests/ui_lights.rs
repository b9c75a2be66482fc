//! Light editing in the lab (issue #18 point 4): in the Scene panel a light is added where
//! the camera looks, moved by its position field, removed, and the scene's own lights come
//! back with "reset lights"; saved beside a scene file, the lights come back when it opens.

use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use gi_lab::ui::app::GiLabApp;
use gi_lab_tests::ui_harness::{harness, pause};

/// The lab in a harness at a tenth of its viewport's size: these tests ask what the Scene
/// panel does to the scene and compare stage 2's mean light before and after, which needs no
/// more pixels (issue #52: the suite's time).
fn small_harness(name: &str) -> (Harness<'static, GiLabApp>, std::path::PathBuf) {
    let (mut h, dir) = harness(name);
    h.state_mut().state.session.render_scale = 0.1;
    (h, dir)
}

/// Stage 2's direct light (deterministic: the indirect light's VPLs change every frame).
fn mean_luminance(h: &Harness<'static, GiLabApp>) -> f64 {
    let img = h.state().renderer().expect("renderer").readback("direct.radiance").expect("direct.radiance");
    img.data.iter().map(|p| (0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]) as f64).sum::<f64>() / img.data.len() as f64
}

fn lights(h: &Harness<'static, GiLabApp>) -> usize {
    h.state().renderer().expect("renderer").scene().evaluate(0.0).lights.len()
}

/// The height of the last light node (the one added last).
fn last_light_y(h: &Harness<'static, GiLabApp>) -> f32 {
    let scene = h.state().renderer().expect("renderer").scene();
    scene.nodes.iter().rev().find(|n| n.light.is_some()).expect("a light node").transform.translation.y
}

#[test]
fn a_light_is_added_moved_removed_and_reset_in_the_scene_panel() {
    let (mut h, dir) = small_harness("lights");
    pause(&mut h);
    h.get_by_label("Scene & timeline").click();
    h.run_steps(3);
    let (n0, lum0) = (lights(&h), mean_luminance(&h));
    h.get_by_label("point").click();
    h.run_steps(3);
    let lum1 = mean_luminance(&h);
    assert_eq!(lights(&h), n0 + 1, "a point light was added");
    assert!(lum1 > lum0 * 1.05, "the added light brightens the image: {lum0} -> {lum1}");
    // Move it: its header, then its y field (typed), lower toward the floor.
    h.get_by_label_contains(&format!("Light {n0}:")).click();
    h.run_steps(2);
    let y = last_light_y(&h);
    h.get_by_label(&format!("light {n0} y")).set_value_accesskit((y * 0.5) as f64);
    h.run_steps(3);
    let moved = last_light_y(&h);
    assert!((moved - y * 0.5).abs() < 1e-2 * y.abs().max(1.0), "the light moved to {moved} (wanted {})", y * 0.5);
    let lum2 = mean_luminance(&h);
    assert!((lum2 - lum1).abs() > 1e-3 * lum1, "moving the light changes the image: {lum1} -> {lum2}");
    h.get_by_label(&format!("remove light {n0}")).click();
    h.run_steps(3);
    assert_eq!(lights(&h), n0);
    // Remove the scene's own light too, then "reset lights" brings it back.
    h.get_by_label("remove light 0").click();
    h.run_steps(3);
    assert_eq!(lights(&h), n0 - 1);
    h.get_by_label("reset lights").click();
    h.run_steps(3);
    assert_eq!(lights(&h), n0);
    let lum3 = mean_luminance(&h);
    assert!((lum3 - lum0).abs() <= 1e-3 * lum0, "reset gives the first image back: {lum0} vs {lum3}");
    let _ = std::fs::remove_dir_all(dir);
}

/// Lights saved beside a scene file come back when it is opened again (the glTF unchanged).
#[test]
fn lights_saved_beside_the_scene_come_back_when_it_opens() {
    let (mut h, dir) = small_harness("lights_file");
    pause(&mut h);
    let glb = dir.join("box.glb");
    gi_render::scene::cornell::write_glb(&glb).expect("writes the default scene");
    let before = std::fs::read(&glb).expect("glb");
    h.state_mut().open_scene(&glb.to_string_lossy(), 1.0).expect("opens");
    h.get_by_label("Scene & timeline").click();
    h.run_steps(3);
    let n0 = lights(&h);
    h.get_by_label("spot").click();
    h.run_steps(2);
    h.get_by_label("save lights beside the scene").click();
    h.run_steps(2);
    let file = dir.join("box.glb.lights.ron");
    assert!(file.is_file(), "{} was written", file.display());
    assert_eq!(std::fs::read(&glb).expect("glb"), before, "the glTF is not rewritten");
    h.state_mut().open_scene(&glb.to_string_lossy(), 1.0).expect("opens again");
    h.run_steps(2);
    assert_eq!(lights(&h), n0 + 1, "the saved lights came back");
    let r = h.state().renderer().expect("renderer");
    assert!(r.scene().warnings.iter().any(|w| w.contains("lights from")), "{:?}", r.scene().warnings);
    let _ = std::fs::remove_dir_all(dir);
}

fn sky(h: &Harness<'static, GiLabApp>) -> gi_render::scene::sky::Sky {
    h.state().renderer().expect("renderer").scene().sky.clone()
}

/// The sky in the Scene panel (issue #18 point 2): off by default; turned on it lights the
/// default box through its open side; a file that is not an image gives an error that stays
/// on screen and changes nothing; an image loads and lights from where it is bright.
#[test]
fn the_sky_is_turned_on_in_the_scene_panel_and_a_bad_image_says_why() {
    let (mut h, dir) = small_harness("sky");
    pause(&mut h);
    // The same directions every frame, so that frames compare exactly (the rotation's
    // convergence is tests/sky.rs's).
    if let Ok(l) = &mut h.state_mut().state.lab {
        l.settings.sky.rotate_each_frame = false;
        l.apply_settings();
    }
    h.get_by_label("Scene & timeline").click();
    h.run_steps(3);
    assert!(!sky(&h).enabled, "off by default");
    let lum0 = mean_luminance(&h);
    h.get_by_label("Sky light").click();
    h.run_steps(2);
    h.get_by_label("sky lights the scene").click();
    h.run_steps(3);
    assert!(sky(&h).enabled && sky(&h).is_lit(), "{:?}", sky(&h));
    let lum1 = mean_luminance(&h);
    assert!(lum1 > lum0 * 1.02, "the sky lights the box: {lum0} -> {lum1}");
    assert!(h.query_by_label_contains("directional VPLs, each with a shadow map").is_some());

    let bad = dir.join("not-an-image.hdr");
    std::fs::write(&bad, b"hello").expect("write");
    h.get_by_label("sky image path").type_text(&bad.to_string_lossy());
    h.get_by_label("load").click();
    h.run_steps(3);
    h.run_steps(3);
    assert!(h.query_by_label_contains("sky image not loaded").is_some(), "the error stays on screen");
    assert!(sky(&h).image.is_none() && sky(&h).enabled, "a bad file changes nothing");
    assert!((mean_luminance(&h) - lum1).abs() <= 1e-6 * lum1);

    // A sky dark but for its upper half.
    let (w, hgt) = (16u32, 8u32);
    let data =
        (0..w * hgt).map(|i| if i / w < hgt / 2 { [2.0, 2.0, 2.0, 1.0] } else { [0.0, 0.0, 0.0, 1.0] }).collect();
    let exr = dir.join("upper.exr");
    gi_render::image_io::save_exr(&exr, &gi_render::ImageF32 { width: w, height: hgt, data }).expect("exr");
    h.get_by_label("sky image path").set_text_value_accesskit(&exr.to_string_lossy());
    h.run_steps(1);
    h.get_by_label("load").click();
    h.run_steps(3);
    let s = sky(&h);
    assert!(s.image.as_ref().is_some_and(|(p, m)| p == &exr && m.width == w), "the image is the sky");
    assert!(h.query_by_label_contains("sky image not loaded").is_none(), "the error is gone");
    let lum2 = mean_luminance(&h);
    assert!((lum2 - lum1).abs() > 1e-3 * lum1, "the image sky lights differently: {lum1} -> {lum2}");
    let _ = std::fs::remove_dir_all(dir);
}

/// The emitter lines of the Scene panel (issue #18 point 1): the real Cornell box lit by its
/// ceiling quad shows its emitters' triangles and power; turned off, the emitters only glow
/// and the box is dark.
#[test]
fn the_scene_panel_shows_the_emitters_and_turns_them_into_glow() {
    let (mut h, dir) = small_harness("emitters");
    pause(&mut h);
    let path = gi_lab_tests::real_scene("cornell-box/CornellBox-Original.gltf");
    h.state_mut().open_scene(&path.to_string_lossy(), 1.0).expect("opens");
    pause(&mut h);
    h.get_by_label("Scene & timeline").click();
    h.run_steps(3);
    assert!(h.query_by_label_contains("emitters: 2 triangles").is_some(), "the emitter line");
    assert!(mean_luminance(&h) > 0.0, "lit by the quad");
    h.get_by_label("emissive surfaces are lights").click();
    h.run_steps(3);
    assert!(h.query_by_label_contains("emitters only glow").is_some());
    assert_eq!(mean_luminance(&h), 0.0, "no light but the emitters'");
    assert!(!h.state().renderer().expect("renderer").settings().emitters.enabled);
    let _ = std::fs::remove_dir_all(dir);
}
