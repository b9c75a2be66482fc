//! The Vulkan validation layers' messages (issue #52 point 6). wgpu turns the validation layer
//! on whenever it is installed and `WGPU_VALIDATION` is not `0` (debug builds), and logs every
//! message it reports through `log` (target `wgpu_hal::vulkan::instance`). [`install`] puts a
//! logger in place that keeps those messages, so that a test can take them after each piece of
//! work ([`take`]) and fail naming what caused them. Lavapipe forgives what a real driver may
//! not (a texture in the wrong layout), so this is how the tests see it.

use std::path::Path;
use std::sync::Mutex;

/// Messages of the validation layer, in the order they came, since the last [`take`].
static MESSAGES: Mutex<Vec<String>> = Mutex::new(Vec::new());
/// Whether the loader reported the validation layer as active.
static ACTIVE: Mutex<bool> = Mutex::new(false);

/// The messages every run may show, each with why it is not ours to fix. Matched against the
/// message's id (`[NAME (0x…)]`) and text.
pub const ALLOWED: &[(&str, &str)] = &[(
    "Invalid source language operand: 10",
    "Debian 12's layer (1.3.239) predates WGSL as a SPIR-V source language (naga writes \
     OpSource WGSL = 10); its spirv-val rejects the operand, not our code",
)];

/// Where Vulkan loaders look for explicit layers (the validation layer's manifest).
const LAYER_MANIFESTS: &[&str] = &[
    "/usr/share/vulkan/explicit_layer.d/VkLayer_khronos_validation.json",
    "/usr/local/share/vulkan/explicit_layer.d/VkLayer_khronos_validation.json",
    "/etc/vulkan/explicit_layer.d/VkLayer_khronos_validation.json",
];

/// Whether the Khronos validation layer's manifest is installed where the loader looks.
pub fn layer_installed() -> bool {
    LAYER_MANIFESTS.iter().any(|p| Path::new(p).exists())
}

struct Capture;

fn from_vulkan(target: &str) -> bool {
    target.starts_with("wgpu_hal::vulkan")
}

impl log::Log for Capture {
    fn enabled(&self, m: &log::Metadata) -> bool {
        from_vulkan(m.target()) && m.level() <= log::Level::Debug
    }

    fn log(&self, r: &log::Record) {
        if !self.enabled(r.metadata()) {
            return;
        }
        let text = r.args().to_string();
        if text.contains("VK_LAYER_KHRONOS_validation") {
            // The loader's own report (debug level) that it inserted the layer.
            *ACTIVE.lock().unwrap_or_else(|e| e.into_inner()) = true;
        }
        // The layer's reports: "VALIDATION [VUID-… (0x…)]", or "GENERAL [UNASSIGNED-…]".
        let report = r.level() <= log::Level::Warn && (text.contains("VALIDATION [") || text.contains("GENERAL ["));
        if report {
            eprintln!("vulkan validation: {text}");
            MESSAGES.lock().unwrap_or_else(|e| e.into_inner()).push(text);
        }
    }

    fn flush(&self) {}
}

static LOGGER: Capture = Capture;

/// Puts the capturing logger in place (once per process; later calls do nothing).
pub fn install() {
    if log::set_logger(&LOGGER).is_ok() {
        log::set_max_level(log::LevelFilter::Debug);
    }
}

/// Whether the loader has reported the validation layer active since [`install`].
pub fn active() -> bool {
    *ACTIVE.lock().unwrap_or_else(|e| e.into_inner())
}

/// The messages since the last call that [`ALLOWED`] does not excuse.
pub fn take() -> Vec<String> {
    let all = std::mem::take(&mut *MESSAGES.lock().unwrap_or_else(|e| e.into_inner()));
    all.into_iter().filter(|m| !ALLOWED.iter().any(|(pattern, _)| m.contains(pattern))).collect()
}
