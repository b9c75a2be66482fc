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

// The world-space point of pixel `p` (integer pixel, its centre) at linear view depth `depth`
// (the G-buffer's `gbuffer.linear_depth`, −z in view space, scene units; issue #53: the camera's
// G-buffer stores this one float instead of the position, and the passes rebuild the point).
// The ray through the pixel's centre meets the far plane at `far`; the point lies on it where
// its distance along the view axis is `depth` (Knecht 002 §4.2 stores the same linear depth,
// Eq. 4.2, beside the normal). CPU twin: `passes::gbuffer::world_from_linear_depth`.
fn world_from_linear_depth(cam: Camera, p: vec2<i32>, depth: f32) -> vec3<f32> {
    let uv = (vec2<f32>(p) + 0.5) * cam.viewport.zw;
    let ndc = vec4<f32>(uv.x * 2.0 - 1.0, 1.0 - uv.y * 2.0, 1.0, 1.0);
    let far = cam.inv_view_proj * ndc;
    let dir = far.xyz / far.w - cam.position.xyz;
    // The view axis in world space: −(third row of the view matrix's rotation).
    let forward = -vec3<f32>(cam.view[0].z, cam.view[1].z, cam.view[2].z);
    return cam.position.xyz + dir * (depth / dot(dir, forward));
}
