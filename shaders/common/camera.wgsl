// Camera uniform shared by every screen-space pass (Rust: passes::CameraUniform).
struct Camera {
    view_proj: mat4x4<f32>,
    // Previous frame's view-projection: the movement buffer reprojects with it
    // (Knecht 002 §3.5.1, after Nehab et al. [NSI06]).
    prev_view_proj: mat4x4<f32>,
    inv_view_proj: mat4x4<f32>,
    view: mat4x4<f32>,
    // xyz: eye position in world space.
    position: vec4<f32>,
    // width, height, 1/width, 1/height in pixels.
    viewport: vec4<f32>,
    // near, far, frame index, time in seconds.
    params: vec4<f32>,
    // x: mip level of the base colour texture in the G-buffer (< 0: chosen by the hardware);
    // the light G-buffer blurs its VPLs' colour with it (Knecht 002 §4.3, render target 0).
    lod: vec4<f32>,
}

// Clip-space position to pixel coordinates (origin top left, pixel centres at +0.5).
fn clip_to_pixel(clip: vec4<f32>, viewport: vec4<f32>) -> vec2<f32> {
    let ndc = clip.xy / clip.w;
    return vec2<f32>((ndc.x * 0.5 + 0.5) * viewport.x, (0.5 - ndc.y * 0.5) * viewport.y);
}
