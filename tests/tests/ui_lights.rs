//! Light editing in the lab (issue #18 point 4): in the Scene panel a light is added where
//! the camera looks, moved by its position field, removed, and the scene's own lights come
//! back with "reset lights"; saved beside a scene file, the lights come back when it opens.

use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use gi_lab::ui::app::GiLabApp;
use gi_lab_tests::ui_harness::{harness, pause};

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
    let (mut h, dir) = harness("lights");
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
    let (mut h, dir) = harness("lights_file");
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
