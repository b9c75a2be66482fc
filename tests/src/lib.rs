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

/// The passes of a frame with the default settings (instant radiosity with ISMs and
/// temporal coherence, Knecht), in order.
pub const DEFAULT_PASSES: &[&str] = &[
    "gbuffer",
    "direct.shadow",
    "direct",
    "vpl.light_gbuffer",
    "vpl.importance",
    "vpl.sample",
    "ism.splat",
    "ism.pull_push",
    "interleave.split",
    "interleave.gather",
    "interleave.merge",
    "interleave.filter",
    "temporal",
    "compose",
    "compose.luminance",
    "compose.tonemap",
];

/// The passes of a frame of direct light only (`pipeline.gather = None`).
pub const DIRECT_PASSES: &[&str] =
    &["gbuffer", "direct.shadow", "direct", "compose", "compose.luminance", "compose.tonemap"];

/// The default renderer with direct light only (`pipeline.gather = None`): deterministic
/// from frame to frame, for tests of the direct light and the frame's machinery.
pub fn direct_only_renderer(w: u32, h: u32) -> Renderer {
    let mut s = LabSettings::default();
    s.pipeline.gather = gi_render::pipeline::Gather::None;
    let mut r = Renderer::new(gpu(), default_scene(), s, w, h).expect("renderer");
    r.clock.playing = false;
    r
}

/// The default scene at `w`×`h` with the `nguyen-hcb` preset's VPLs (the same set every
/// frame) and the choices `edit` makes, validated; animation paused.
pub fn nguyen_fixed_vpls_renderer(w: u32, h: u32, edit: impl FnOnce(&mut LabSettings)) -> Renderer {
    let loaded =
        gi_render::preset::load_lenient(include_str!("../../presets/nguyen-hcb.ron"), "nguyen-hcb").expect("loads");
    let mut s = loaded.settings;
    s.vpl.new_set_each_frame = false;
    edit(&mut s);
    assert!(s.validate().is_empty(), "{:?}", s.validate());
    let mut r = Renderer::new(gpu(), default_scene(), s, w, h).expect("renderer");
    r.clock.playing = false;
    r
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

/// A sampled, copyable 2D texture of `format` filled with `bytes` (tightly packed rows).
pub fn texture_from_bytes(
    ctx: &GpuContext,
    label: &str,
    format: wgpu::TextureFormat,
    (width, height): (u32, u32),
    bytes: &[u8],
) -> wgpu::Texture {
    let t = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });
    ctx.queue.write_texture(
        t.as_image_copy(),
        bytes,
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(bytes.len() as u32 / height),
            rows_per_image: None,
        },
        wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
    );
    t
}
