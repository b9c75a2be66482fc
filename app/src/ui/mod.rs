//! The GI Lab window (issue #4): docked panels (egui_tiles) around a viewport they never
//! cover — settings generated from `LabSettings`, scene and timeline, presets, GPU timings,
//! pixel probes and any number of buffer viewers — with a menu bar, a status bar, keyboard
//! shortcuts and a session that is restored on the next start. The renderer runs on
//! eframe's wgpu device; its images are shown as native egui textures.
//! Camera: drag to orbit, WASD/QE to fly, scroll to move forward/back; click to pin a probe.

pub mod ab;
pub mod adaptive;
pub mod app;
pub mod capture;
pub mod explain;
pub mod grid;
pub mod hot_reload;
pub mod lab;
pub mod labels;
pub mod menus;
pub mod panes;
pub mod session;
pub mod settings_ui;
pub mod state;
pub mod viewer;

use std::sync::Arc;

use crate::args::AppArgs;
use app::GiLabApp;

/// The papers' symbols that the settings, tooltips and panes write (the glyph test draws
/// them with [`install_fonts`]' fonts).
pub const PAPER_SYMBOLS: &str = "∇ ∝ ‖ θ γ σ ρ ω Φ Ω π α β ε δ λ μ τ → ← ↔ ≤ ≥ ≈ ≠ ± × · ∑ ∫ √ ∞ ° ² ³ ⁻¹ ⁰¹²³⁴⁵⁶⁷⁸⁹ ₀₁₂₃₄₅₆₇₈₉ ₖ ₙ ᵢ ⱼ θ_max γ_max d_max";

/// egui's fonts, then DejaVu Sans (`assets/fonts/`, Bitstream Vera licence beside it) for
/// every glyph they lack: the Greek letters, operators, arrows and sub- and superscripts of
/// the papers' symbols ([`PAPER_SYMBOLS`]), so that labels can write ∇, ∝ or ‖ as the papers do.
pub fn install_fonts(ctx: &egui::Context) {
    let mut fonts = egui::FontDefinitions::default();
    fonts.font_data.insert(
        "dejavu-sans".into(),
        Arc::new(egui::FontData::from_static(include_bytes!("../../../assets/fonts/DejaVuSans.ttf"))),
    );
    for family in [egui::FontFamily::Proportional, egui::FontFamily::Monospace] {
        fonts.families.entry(family).or_default().push("dejavu-sans".into());
    }
    ctx.set_fonts(fonts);
}

pub const ERROR: egui::Color32 = egui::Color32::from_rgb(255, 120, 80);

/// Opens the window and runs until it is closed.
pub fn run(args: AppArgs) -> Result<(), String> {
    let options = eframe::NativeOptions {
        viewport: egui::ViewportBuilder::default()
            .with_inner_size([1440.0, 900.0])
            .with_title("GI Lab")
            .with_drag_and_drop(true),
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
