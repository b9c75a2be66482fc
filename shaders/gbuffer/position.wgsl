// Stage 1, the camera G-buffer's world positions rebuilt from its linear depth (issue #53,
// docs/architecture.md "The camera G-buffer's position"): the passes that have not moved to
// `gbuffer.linear_depth` (and every viewer, probe and read-back of `gbuffer.position`) read
// this texture, filled only in the frames where one of them needs it. xyz: the world point of
// the pixel's centre at its linear depth, w: the linear depth (Knecht 002 §4.2, Eq. 4.2);
// 0 where no geometry covers the pixel, as the raster's clear left it.
#import common/camera.wgsl

@group(0) @binding(0) var<uniform> camera: Camera;
@group(0) @binding(1) var linear_depth: texture_2d<f32>;
@group(0) @binding(2) var out_position: texture_storage_2d<rgba32float, write>;

@compute @workgroup_size(8, 8, 1)
fn cs_position(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = textureDimensions(linear_depth);
    if (gid.x >= size.x || gid.y >= size.y) {
        return;
    }
    let p = vec2<i32>(gid.xy);
    let d = textureLoad(linear_depth, p, 0).x;
    var out = vec4<f32>(0.0);
    if (d > 0.0) {
        out = vec4<f32>(world_from_linear_depth(camera, p, d), d);
    }
    textureStore(out_position, p, out);
}
