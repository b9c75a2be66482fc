//! The scene and timeline pane: scene file, lights, animation clock, camera bookmarks.

use crate::ui::ERROR;
use crate::ui::state::State;

pub(super) fn scene_ui(st: &mut State, ui: &mut egui::Ui) {
    let Ok(l) = &mut st.lab else { return };
    ui.heading("Scene");
    ui.label(&l.scene_name);
    ui.small(format!("{} triangles", l.renderer.scene().triangle_count()));
    for w in &l.renderer.scene().warnings {
        ui.small(format!("warning: {w}"));
    }
    if let Some(v) = &l.renderer.scene().view {
        ui.small(format!("view: {}", v.reason));
    }
    default_light_controls(l, ui);
    scene_cameras(l, ui);
    let open = l.renderer.voxel_visibility_open_meshes();
    if !open.is_empty() {
        let names: Vec<String> = open.iter().map(|(n, e)| format!("{n} ({e} open edges)")).collect();
        ui.small(format!(
            "warning: Soler's voxel visibility needs closed meshes; these are open, and the space behind them counts as solid: {}",
            names.join(", ")
        ))
        .on_hover_text("Solid voxelization (004 §4) fills a column from each surface crossing to the next by parity. A room of single walls seen from inside is fine (behind its walls is outside the room); an open mesh inside the room blocks light wrongly.");
    }
    let mut open_dialog = false;
    let mut open_default = false;
    ui.horizontal(|ui| {
        open_dialog = ui.button("Open glTF…").on_hover_text("or drop a .gltf / .glb file on the window").clicked();
        open_default = ui.button("Default scene").clicked();
        ui.label("unit scale");
        ui.add(
            egui::DragValue::new(&mut l.unit_scale)
                .range(0.0..=1e6)
                .speed(0.001)
                .custom_formatter(|v, _| if v == 0.0 { "auto".into() } else { format!("{v}") }),
        )
        .on_hover_text(
            "multiplies the scene's coordinates (0.001 for millimetres); auto (0) reads the unit from the scene's extent; applies on the next open",
        );
    });
    let mut open_typed = false;
    ui.horizontal(|ui| {
        let r = ui.add(
            egui::TextEdit::singleline(&mut st.scene_path_text)
                .hint_text("or type a .gltf / .glb path")
                .desired_width(220.0),
        );
        let enter = r.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter));
        open_typed = (ui.add_enabled(!st.scene_path_text.trim().is_empty(), egui::Button::new("Open")).clicked()
            || enter)
            && !st.scene_path_text.trim().is_empty();
    });
    if let Some(e) = &l.scene_error {
        ui.colored_label(ERROR, e);
    }
    let lights_message = super::lights::light_controls(l, ui);
    ui.separator();
    timeline(l, ui);
    ui.separator();
    ui.heading("Camera");
    if ui.button("Reset camera (Home)").clicked() {
        let (w, h) = l.renderer.size();
        l.renderer.camera =
            gi_render::renderer::default_camera(l.renderer.scene(), l.renderer.bounds(), w as f32 / h.max(1) as f32);
    }
    let c = l.renderer.camera;
    ui.small(format!(
        "position ({:.2}, {:.2}, {:.2}) · yaw {:.1}° · pitch {:.1}° · fov {:.1}°",
        c.position.x,
        c.position.y,
        c.position.z,
        c.yaw.to_degrees(),
        c.pitch.to_degrees(),
        c.yfov.to_degrees()
    ));
    ui.horizontal(|ui| {
        ui.add(egui::TextEdit::singleline(&mut st.bookmark_name).hint_text("bookmark name").desired_width(140.0));
        if ui.button("Bookmark").clicked() {
            st.add_bookmark();
        }
    });
    let mut restore = None;
    let mut delete = None;
    for (i, b) in st.session.bookmarks.iter_mut().enumerate() {
        ui.horizontal(|ui| {
            ui.add(egui::TextEdit::singleline(&mut b.name).desired_width(140.0));
            if ui.button("Go").clicked() {
                restore = Some(b.camera);
            }
            if ui.button("Delete").clicked() {
                delete = Some(i);
            }
        });
    }
    if let Some(i) = delete {
        st.session.bookmarks.remove(i);
    }
    if let (Some(c), Ok(l)) = (restore, &mut st.lab) {
        l.renderer.camera = c;
    }
    if open_dialog {
        st.open_scene_dialog();
    }
    if open_typed {
        let path = std::path::PathBuf::from(st.scene_path_text.trim());
        let scale = st.lab.as_ref().map(|l| l.unit_scale).unwrap_or(0.0);
        if let Err(e) = st.open_scene(Some(path), scale) {
            st.set_status(format!("scene not opened: {e}"));
        }
    }
    if let Some(m) = lights_message {
        st.set_status(m);
    }
    if open_default && let Err(e) = st.open_scene(None, 0.0) {
        st.set_status(format!("scene not opened: {e}"));
    }
}

fn timeline(l: &mut crate::ui::lab::Lab, ui: &mut egui::Ui) {
    ui.heading("Animation");
    let duration = l.renderer.scene().animation_duration() as f64;
    let clock = &mut l.renderer.clock;
    ui.horizontal(|ui| {
        let label = if clock.playing { "Pause" } else { "Play" };
        if ui.button(label).on_hover_text("Space").clicked() {
            clock.playing = !clock.playing;
        }
        if ui.add_enabled(!clock.playing, egui::Button::new("Step")).on_hover_text("Period (.)").clicked() {
            clock.step();
        }
        ui.monospace(format!("t = {:.3} s  frame {}", clock.time_s(), clock.anim_frame));
    });
    ui.horizontal(|ui| {
        ui.label("speed");
        let mut speed = clock.speed;
        if ui.add(egui::Slider::new(&mut speed, 0.05..=8.0).logarithmic(true).suffix("×")).changed() {
            clock.set_speed(speed);
        }
    });
    ui.horizontal(|ui| {
        let mut looping = clock.loop_s > 0.0;
        if ui.checkbox(&mut looping, "loop").changed() {
            clock.loop_s = if looping { if duration > 0.0 { duration } else { 10.0 } } else { 0.0 };
        }
        if looping {
            ui.add(egui::DragValue::new(&mut clock.loop_s).range(0.01..=3600.0).speed(0.05).suffix(" s"));
        }
    });
    let end = if clock.loop_s > 0.0 {
        clock.loop_s
    } else if duration > 0.0 {
        duration
    } else {
        10.0
    };
    let mut t = clock.time_s() as f64;
    let scrub = ui.add(egui::Slider::new(&mut t, 0.0..=end).text("time").suffix(" s"));
    if scrub.changed() {
        clock.seek(t);
    }
    if duration > 0.0 {
        ui.small(format!("the scene's animations last {duration:.2} s"));
    }
}

/// "Remove the default light": the light (and the sky) the lab added to a scene without any
/// (issue #37 point 3) go away in one click; the path tracer reads the same scene.
fn default_light_controls(l: &mut crate::ui::lab::Lab, ui: &mut egui::Ui) {
    let added: Vec<usize> = l
        .renderer
        .scene()
        .lights
        .iter()
        .enumerate()
        .filter(|(_, li)| gi_render::scene::default_light::is_default_light(&li.name))
        .map(|(i, _)| i)
        .collect();
    if added.is_empty() {
        return;
    }
    if ui
        .button("Remove the default light")
        .on_hover_text("the light (and, for an open scene, the sky) the lab added because the scene has none")
        .clicked()
    {
        l.renderer.scene_mut().remove_default_light();
        l.renderer.reset_history();
    }
}

/// The scene's glTF cameras: one button each (the scene opens on the first).
fn scene_cameras(l: &mut crate::ui::lab::Lab, ui: &mut egui::Ui) {
    let state = l.renderer.scene().evaluate(0.0);
    if state.cameras.len() < 2 {
        return;
    }
    let bounds = l.renderer.bounds();
    ui.horizontal_wrapped(|ui| {
        ui.label("cameras:");
        for c in &state.cameras {
            if ui.button(&c.camera.name).on_hover_text("look through this glTF camera").clicked() {
                l.renderer.camera = gi_render::camera::Camera::from_node(c.world, &c.camera, bounds);
            }
        }
    });
}
