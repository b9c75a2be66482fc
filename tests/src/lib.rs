//! Shared helpers of GI Lab's integration tests.

use gi_render::scene::Scene;
use gi_render::{GpuContext, LabSettings, Renderer};

/// Opens the headless GPU context or fails the test with instructions; tests never skip
/// silently when no adapter exists.
pub fn gpu() -> GpuContext {
    match GpuContext::headless() {
        Ok(c) => c,
        Err(e) => panic!(
            "no GPU adapter for the tests: {e}\n\
             Install Mesa's software Vulkan driver (lavapipe): `sudo apt-get install -y mesa-vulkan-drivers libvulkan1` \
             and run with WGPU_BACKEND=vulkan, or run `bash scripts/test.sh`, which does both."
        ),
    }
}

/// The embedded default scene.
pub fn default_scene() -> Scene {
    gi_render::scene::cornell::default_scene().expect("the embedded default scene loads")
}

/// A renderer of the default scene at `w`×`h` with default settings, animation paused.
pub fn default_renderer(w: u32, h: u32) -> Renderer {
    let mut r = Renderer::new(gpu(), default_scene(), LabSettings::default(), w, h).expect("renderer");
    r.clock.playing = false;
    r
}

/// Path of a scene in `../shared/scenes/`, failing clearly when the folder is missing.
pub fn shared_scene(rel: &str) -> std::path::PathBuf {
    let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/scenes").join(rel);
    assert!(
        p.exists(),
        "shared scene {} is missing: the tests expect the workspace's sibling folder ../shared/scenes (see README)",
        p.display()
    );
    p
}

/// A path-traced reference stored in `tests/data/` (see `tests/references.rs`).
pub fn stored_reference(file: &str) -> gi_render::ImageF32 {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("data").join(file);
    gi_render::image_io::load_float_image(&path).unwrap_or_else(|e| panic!("tests/data/{file}: {e}"))
}
