//! The GI Lab window: the renderer's image in the central viewport, settings panels per
//! pass on the left, a status bar with adapter, resolution and frame time. The renderer
//! runs on eframe's wgpu device and its `final.ldr` is shown as a native egui texture.
//! Camera: drag to orbit, WASD/QE to fly, scroll to move forward/back.

use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use std::time::Instant;

use gi_render::{GpuContext, LabSettings, Renderer};

use crate::cli::AppArgs;

/// Opens the window and runs until it is closed.
pub fn run(args: AppArgs) -> Result<(), String> {
    let options = eframe::NativeOptions {
        viewport: egui::ViewportBuilder::default().with_inner_size([1280.0, 800.0]).with_title("GI Lab"),
        renderer: eframe::Renderer::Wgpu,
        wgpu_options: wgpu_configuration(),
        ..Default::default()
    };
    eframe::run_native("GI Lab", options, Box::new(move |cc| Ok(Box::new(GiLabApp::new(cc, args)))))
        .map_err(|e| format!("could not open the window: {e}"))
}

/// eframe's wgpu setup with the device GI Lab needs (float32 blending/filtering,
/// timestamps, the adapter's limits). If the adapter lacks them, egui's defaults are
/// used so that the window can open and explain the problem.
pub fn wgpu_configuration() -> egui_wgpu::WgpuConfiguration {
    egui_wgpu::WgpuConfiguration { wgpu_setup: wgpu_setup(), ..Default::default() }
}

/// The wgpu setup of [`wgpu_configuration`] (also used by the UI tests' harness).
pub fn wgpu_setup() -> egui_wgpu::WgpuSetup {
    let mut setup = egui_wgpu::WgpuSetupCreateNew::without_display_handle();
    setup.native_adapter_selector = Some(Arc::new(|adapters, surface| {
        gi_render::gpu::best_adapter(adapters, surface).ok_or_else(|| gi_render::gpu::INSTALL_HINT.to_string())
    }));
    let fallback = setup.device_descriptor.clone();
    setup.device_descriptor = Arc::new(move |adapter| match gi_render::gpu::device_descriptor(adapter) {
        Ok(mut d) => {
            d.required_limits.max_texture_dimension_2d = d.required_limits.max_texture_dimension_2d.max(8192);
            d
        }
        Err(e) => {
            log::error!("{e}");
            fallback(adapter)
        }
    });
    egui_wgpu::WgpuSetup::CreateNew(setup)
}

/// The running lab: a renderer when it could be created, else the reason it could not.
pub struct GiLabApp {
    args: AppArgs,
    /// Path typed in Scene → Open.
    scene_path: String,
    unit_scale: f32,
    viewer: Result<Viewer, String>,
    frames: u64,
    screenshot: Arc<Mutex<Option<Arc<egui::ColorImage>>>>,
    screenshot_requested: bool,
}

struct Viewer {
    renderer: Renderer,
    /// The last uncaptured GPU error, if any.
    gpu_error: Arc<Mutex<Option<String>>>,
    render_state: egui_wgpu::RenderState,
    texture: Option<(egui::TextureId, (u32, u32))>,
    settings: LabSettings,
    preset_name: String,
    settings_error: Option<String>,
    scene_error: Option<String>,
    frame_ms: f32,
    last_frame: Instant,
    scene_name: String,
}

impl GiLabApp {
    pub fn new(cc: &eframe::CreationContext<'_>, args: AppArgs) -> Self {
        let viewer = Viewer::new(cc, &args);
        if let Err(e) = &viewer {
            log::error!("{e}");
        }
        let scene_path = args.scene.scene.as_ref().map(|p| p.display().to_string()).unwrap_or_default();
        let unit_scale = args.scene.unit_scale;
        Self {
            args,
            scene_path,
            unit_scale,
            viewer,
            frames: 0,
            screenshot: Arc::new(Mutex::new(None)),
            screenshot_requested: false,
        }
    }

    /// Whether a renderer is running (false when the GPU or scene failed).
    pub fn is_rendering(&self) -> bool {
        self.viewer.is_ok()
    }

    /// Why the renderer could not start, if it could not.
    pub fn error(&self) -> Option<&str> {
        self.viewer.as_ref().err().map(|e| e.as_str())
    }

    /// Opens a scene as Scene → Open does; on failure the current scene stays, and the
    /// error is returned and shown in the Scene menu.
    pub fn open_scene(&mut self, path: &str, unit_scale: f32) -> Result<(), String> {
        let v = self.viewer.as_mut().map_err(|e| e.clone())?;
        let r = v.open_scene(Some(PathBuf::from(path)), unit_scale);
        v.scene_error = r.clone().err();
        r
    }

    /// The running renderer, if any.
    pub fn renderer(&self) -> Option<&Renderer> {
        self.viewer.as_ref().ok().map(|v| &v.renderer)
    }

    fn screenshot_step(&mut self, ctx: &egui::Context) {
        let Some(path) = self.args.screenshot.clone() else { return };
        if !self.screenshot_requested && self.frames >= self.args.screenshot_frames {
            let slot = self.screenshot.clone();
            ctx.request_screenshot(move |img| {
                if let Ok(mut s) = slot.lock() {
                    *s = Some(img);
                }
            });
            self.screenshot_requested = true;
        }
        let taken = self.screenshot.lock().ok().and_then(|mut s| s.take());
        if let Some(img) = taken {
            save_color_image(&path, &img);
            ctx.send_viewport_cmd(egui::ViewportCommand::Close);
        }
    }
}

fn save_color_image(path: &PathBuf, img: &egui::ColorImage) {
    let [w, h] = img.size;
    let bytes: Vec<u8> = img.pixels.iter().flat_map(|c| c.to_array()).collect();
    match image::RgbaImage::from_raw(w as u32, h as u32, bytes) {
        Some(i) => match i.save(path) {
            Ok(()) => println!("wrote screenshot {}", path.display()),
            Err(e) => eprintln!("gi-lab: cannot write screenshot {}: {e}", path.display()),
        },
        None => eprintln!("gi-lab: screenshot has inconsistent size"),
    }
}

impl Viewer {
    fn new(cc: &eframe::CreationContext<'_>, args: &AppArgs) -> Result<Self, String> {
        let rs = cc.wgpu_render_state.clone().ok_or("eframe did not start its wgpu renderer")?;
        // A GPU error caused by a setting (say, out of memory for a huge shadow map) must not
        // take the lab down with it: it is logged and shown in the status bar instead of
        // wgpu's default panic. Headless runs and tests keep the panic.
        let gpu_error = Arc::new(Mutex::new(None::<String>));
        let sink = gpu_error.clone();
        rs.device.on_uncaptured_error(Arc::new(move |e| {
            log::error!("GPU error: {e}");
            if let Ok(mut s) = sink.lock() {
                *s = Some(e.to_string());
            }
        }));
        let ctx =
            GpuContext::adopt(rs.device.clone(), rs.queue.clone(), rs.adapter.get_info()).map_err(|e| e.to_string())?;
        let scene = crate::cli::load_scene(&args.scene).map_err(|e| e.message)?;
        let settings = crate::cli::load_settings(&args.scene).map_err(|e| e.message)?;
        let scene_name =
            args.scene.scene.as_ref().map(|p| p.display().to_string()).unwrap_or_else(|| scene.name.clone());
        let mut renderer = Renderer::new(ctx, scene, settings.clone(), 640, 480).map_err(|e| e.to_string())?;
        renderer.set_interactive(true);
        let preset_name = args
            .scene
            .preset
            .as_ref()
            .and_then(|p| p.file_name())
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| "default".into());
        Ok(Self {
            renderer,
            gpu_error,
            render_state: rs,
            texture: None,
            settings,
            preset_name,
            settings_error: None,
            scene_error: None,
            frame_ms: 0.0,
            last_frame: Instant::now(),
            scene_name,
        })
    }

    /// Replaces the scene (None: the embedded default) keeping device, settings and size.
    /// On failure the current scene stays and the error is returned for display.
    fn open_scene(&mut self, path: Option<PathBuf>, unit_scale: f32) -> Result<(), String> {
        let args = crate::cli::SceneArgs { scene: path.clone(), unit_scale, ..Default::default() };
        let scene = crate::cli::load_scene(&args).map_err(|e| e.message)?;
        let (w, h) = self.renderer.size();
        let name = path.map(|p| p.display().to_string()).unwrap_or_else(|| scene.name.clone());
        let renderer =
            Renderer::new(self.renderer.ctx.clone(), scene, self.settings.clone(), w, h).map_err(|e| e.to_string())?;
        self.renderer = renderer;
        self.renderer.set_interactive(true);
        self.scene_name = name;
        // The new renderer has new textures: make the next frame re-point egui's texture.
        self.texture = self.texture.map(|(id, _)| (id, (0, 0)));
        Ok(())
    }

    /// Renders a frame at `size` pixels and makes the result available to egui.
    fn render(&mut self, size: (u32, u32)) -> Option<egui::TextureId> {
        if size.0 == 0 || size.1 == 0 {
            return self.texture.map(|t| t.0); // minimised or collapsed: keep the last image
        }
        if let Err(e) = self.renderer.resize(size.0, size.1) {
            self.settings_error = Some(e.to_string());
        }
        self.renderer.render_frame();
        let now = Instant::now();
        self.frame_ms = (now - self.last_frame).as_secs_f32() * 1e3;
        self.last_frame = now;
        let current = self.renderer.size();
        let view = self.renderer.final_ldr().create_view(&wgpu::TextureViewDescriptor {
            label: Some("app.final_ldr"),
            format: Some(wgpu::TextureFormat::Rgba8UnormSrgb),
            // The texture is also a storage target; this sRGB view is for sampling only.
            usage: Some(wgpu::TextureUsages::TEXTURE_BINDING),
            ..Default::default()
        });
        let mut egui_renderer = self.render_state.renderer.write();
        match self.texture {
            Some((id, s)) if s == current => Some(id),
            Some((id, _)) => {
                egui_renderer.update_egui_texture_from_wgpu_texture(
                    &self.render_state.device,
                    &view,
                    wgpu::FilterMode::Nearest,
                    id,
                );
                self.texture = Some((id, current));
                Some(id)
            }
            None => {
                let id =
                    egui_renderer.register_native_texture(&self.render_state.device, &view, wgpu::FilterMode::Nearest);
                self.texture = Some((id, current));
                Some(id)
            }
        }
    }

    fn side_panel(&mut self, ui: &mut egui::Ui) {
        ui.heading("Scene");
        ui.label(&self.scene_name);
        for w in &self.renderer.scene().warnings {
            ui.small(format!("warning: {w}"));
        }
        self.light_controls(ui);
        ui.separator();
        self.animation_controls(ui);
        ui.separator();
        ui.heading("Settings");
        let before = self.settings.clone();
        egui::CollapsingHeader::new("2 · Direct light").default_open(true).show(ui, |ui| {
            crate::settings_ui::direct_settings_ui(&mut self.settings.direct, ui);
        });
        egui::CollapsingHeader::new("3–6 · Indirect light").default_open(true).show(ui, |ui| {
            crate::settings_ui::indirect_settings_ui(&mut self.settings.indirect, ui);
            if let Some((done, target)) = self.renderer.reference_progress() {
                ui.add(
                    egui::ProgressBar::new(done as f32 / target.max(1) as f32)
                        .text(format!("{done} / {target} VPLs accumulated")),
                );
                if self.renderer.clock.playing {
                    ui.small("The accumulation restarts whenever the camera, a light or an animated object moves: pause the animation to let it converge.");
                }
            }
        });
        egui::CollapsingHeader::new("Exact-VPL reference").default_open(false).show(ui, |ui| {
            crate::settings_ui::reference_settings_ui(&mut self.settings.reference, ui);
        });
        egui::CollapsingHeader::new("7 · Tone mapping").default_open(true).show(ui, |ui| {
            crate::settings_ui::tonemap_settings_ui(&mut self.settings.tonemap, ui);
        });
        if self.settings != before {
            match self.renderer.set_settings(self.settings.clone()) {
                Ok(_) => self.settings_error = None,
                Err(e) => {
                    // Refused: keep the renderer's last valid settings and say why.
                    self.settings_error = Some(e.to_string());
                    self.settings = self.renderer.settings().clone();
                }
            }
        }
        if let Some(e) = &self.settings_error {
            ui.colored_label(egui::Color32::from_rgb(255, 120, 80), e);
        }
        ui.separator();
        ui.heading("GPU time");
        egui::Grid::new("timings").num_columns(2).striped(true).show(ui, |ui| {
            let mut total = 0.0;
            for t in self.renderer.timings() {
                ui.label(&t.name);
                ui.monospace(format!("{:8.3} ms", t.ms));
                ui.end_row();
                total += t.ms;
            }
            ui.strong("total");
            ui.monospace(format!("{total:8.3} ms"));
            ui.end_row();
        });
    }

    fn light_controls(&mut self, ui: &mut egui::Ui) {
        let light_nodes: Vec<usize> =
            self.renderer.scene().nodes.iter().enumerate().filter(|(_, n)| n.light.is_some()).map(|(i, _)| i).collect();
        let r = self.renderer.bounds().radius();
        let mut changed = false;
        for (k, &ni) in light_nodes.iter().enumerate() {
            let scene = self.renderer.scene_mut();
            let Some(li) = scene.nodes[ni].light else { continue };
            let name = scene.lights[li].name.clone();
            let directional = matches!(scene.lights[li].kind, gi_render::scene::LightKind::Directional);
            egui::CollapsingHeader::new(format!("Light {k}: {name}")).default_open(k == 0).show(ui, |ui| {
                let tr = &mut scene.nodes[ni].transform;
                if directional {
                    // A directional light has no position: edit where it shines from.
                    let dir = tr.rotation * glam::Vec3::NEG_Z;
                    let mut elevation = (-dir.y).clamp(-1.0, 1.0).asin().to_degrees();
                    let mut azimuth = (-dir.x).atan2(-dir.z).to_degrees();
                    ui.horizontal(|ui| {
                        ui.label("elevation");
                        let a = ui.add(egui::DragValue::new(&mut elevation).range(-90.0..=90.0).suffix("°"));
                        ui.label("azimuth");
                        let b = ui.add(egui::DragValue::new(&mut azimuth).suffix("°"));
                        if a.changed() || b.changed() {
                            let (e, z) = (elevation.to_radians(), azimuth.to_radians());
                            let d = glam::Vec3::new(-z.sin() * e.cos(), -e.sin(), -z.cos() * e.cos());
                            tr.rotation = glam::Quat::from_rotation_arc(glam::Vec3::NEG_Z, d.normalize());
                            changed = true;
                        }
                    });
                } else {
                    let t = &mut tr.translation;
                    ui.horizontal(|ui| {
                        ui.label("position");
                        for c in [&mut t.x, &mut t.y, &mut t.z] {
                            changed |= ui.add(egui::DragValue::new(c).speed(r * 0.005).max_decimals(3)).changed();
                        }
                    });
                }
                let l = &mut scene.lights[li];
                ui.horizontal(|ui| {
                    ui.label("intensity");
                    changed |= ui
                        .add(egui::Slider::new(&mut l.intensity, 0.0..=100_000.0).logarithmic(true))
                        .on_hover_text("candela for point and spot lights, lux for directional lights")
                        .changed();
                });
            });
        }
        if changed {
            self.renderer.reset_history();
        }
    }

    fn animation_controls(&mut self, ui: &mut egui::Ui) {
        ui.heading("Animation");
        let clock = &mut self.renderer.clock;
        ui.horizontal(|ui| {
            let label = if clock.playing { "Pause" } else { "Play" };
            if ui.button(label).clicked() {
                clock.playing = !clock.playing;
            }
            if ui.add_enabled(!clock.playing, egui::Button::new("Step")).clicked() {
                clock.step();
            }
            ui.monospace(format!("t = {:.3} s  frame {}", clock.time_s(), clock.anim_frame));
        });
    }

    fn navigate(&mut self, ui: &egui::Ui, response: &egui::Response) {
        let r = self.renderer.bounds().radius();
        let cam = &mut self.renderer.camera;
        if response.dragged_by(egui::PointerButton::Primary) {
            let d = response.drag_delta();
            cam.orbit(-d.x * 0.008, -d.y * 0.008);
        }
        if response.hovered() {
            let (scroll, dt, keys) = ui.input(|i| {
                let k = |key| if i.key_down(key) { 1.0 } else { 0.0 };
                (
                    i.smooth_scroll_delta.y,
                    i.stable_dt.min(0.1),
                    glam::Vec3::new(
                        k(egui::Key::D) - k(egui::Key::A),
                        k(egui::Key::E) - k(egui::Key::Q),
                        k(egui::Key::W) - k(egui::Key::S),
                    ),
                )
            });
            let speed = r * 0.8;
            if keys != glam::Vec3::ZERO {
                cam.fly(keys * speed * dt);
            }
            if scroll != 0.0 {
                let step = scroll * r * 0.002;
                cam.fly(glam::Vec3::new(0.0, 0.0, step));
                cam.orbit_distance = (cam.orbit_distance - step).max(r * 0.05);
            }
        }
    }
}

impl eframe::App for GiLabApp {
    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        let ctx = ui.ctx().clone();
        egui::Panel::top("menu").show(ui, |ui| {
            egui::MenuBar::new().ui(ui, |ui| {
                ui.menu_button("File", |ui| {
                    if ui.button("Quit").clicked() {
                        ctx.send_viewport_cmd(egui::ViewportCommand::Close);
                    }
                });
                ui.menu_button("View", |ui| {
                    if let Ok(v) = &mut self.viewer
                        && ui.button("Reset camera").clicked()
                    {
                        let (w, h) = v.renderer.size();
                        v.renderer.camera = gi_render::frame::default_camera(
                            v.renderer.scene(),
                            v.renderer.bounds(),
                            w as f32 / h as f32,
                        );
                    }
                });
                ui.menu_button("Scene", |ui| {
                    let Ok(v) = &mut self.viewer else {
                        ui.label("no renderer");
                        return;
                    };
                    ui.label("glTF 2.0 file (.gltf / .glb):");
                    ui.text_edit_singleline(&mut self.scene_path);
                    ui.horizontal(|ui| {
                        ui.label("unit scale");
                        ui.add(egui::DragValue::new(&mut self.unit_scale).range(1e-6..=1e6).speed(0.001))
                            .on_hover_text("multiplies the scene's coordinates (0.001 for millimetres)");
                    });
                    ui.horizontal(|ui| {
                        let path = self.scene_path.trim();
                        if ui.add_enabled(!path.is_empty(), egui::Button::new("Open")).clicked() {
                            v.scene_error = v.open_scene(Some(PathBuf::from(path)), self.unit_scale).err();
                        }
                        if ui.button("Default scene").clicked() {
                            v.scene_error = v.open_scene(None, 1.0).err();
                        }
                    });
                    if let Some(e) = &v.scene_error {
                        ui.colored_label(egui::Color32::from_rgb(255, 120, 80), e);
                    }
                });
                ui.menu_button("Help", |ui| {
                    ui.label("Drag: orbit · WASD/QE: fly · scroll: forward/back");
                });
            });
        });
        egui::Panel::bottom("status").show(ui, |ui| {
            ui.horizontal(|ui| match &self.viewer {
                Ok(v) => {
                    let (w, h) = v.renderer.size();
                    let gpu: f64 = v.renderer.timings().iter().map(|t| t.ms).sum();
                    ui.label(v.renderer.ctx.adapter_summary());
                    ui.separator();
                    ui.label(format!("{w}×{h}"));
                    ui.separator();
                    ui.label(format!(
                        "frame {:.1} ms · GPU {:.2} ms ({:?})",
                        v.frame_ms,
                        gpu,
                        v.renderer.timing_source()
                    ));
                    ui.separator();
                    ui.label(format!("preset: {}", v.preset_name));
                    if let Some(e) = v.gpu_error.lock().ok().and_then(|e| e.clone()) {
                        ui.separator();
                        ui.colored_label(egui::Color32::from_rgb(255, 120, 80), "GPU error").on_hover_text(e);
                    }
                }
                Err(e) => {
                    ui.colored_label(egui::Color32::from_rgb(255, 120, 80), "renderer unavailable");
                    ui.label(e);
                }
            });
        });
        if let Ok(v) = &mut self.viewer {
            egui::Panel::left("settings").default_size(330.0).resizable(true).show(ui, |ui| {
                egui::ScrollArea::vertical().show(ui, |ui| v.side_panel(ui));
            });
        }
        egui::CentralPanel::no_frame().show(ui, |ui| match &mut self.viewer {
            Ok(v) => {
                let avail = ui.available_size();
                let ppp = ctx.pixels_per_point();
                let px = ((avail.x * ppp).round().max(0.0) as u32, (avail.y * ppp).round().max(0.0) as u32);
                if let Some(id) = v.render(px) {
                    let (w, h) = v.renderer.size();
                    let size = egui::vec2(w as f32 / ppp, h as f32 / ppp);
                    let response = ui.add(egui::Image::new((id, size)).sense(egui::Sense::click_and_drag()));
                    v.navigate(ui, &response);
                }
            }
            Err(e) => {
                ui.centered_and_justified(|ui| {
                    ui.colored_label(egui::Color32::from_rgb(255, 120, 80), format!("GI Lab cannot render:\n{e}"));
                });
            }
        });
        self.frames += 1;
        self.screenshot_step(&ctx);
        ctx.request_repaint();
    }
}
