// Pixel probe of depth buffers: WebGPU cannot copy part of a depth texture, so the probe
// reads depth texels with textureLoad and writes them to a buffer (see `DepthProbe` in
// `render/src/passes/view.rs`). Other formats are probed by plain texel copies.

struct Jobs {
    // (count, first output index, layer, 1 = array texture)
    header: vec4<u32>,
    // (x, y, 0, 0) per probed texel
    texels: array<vec4<u32>, 64>,
};

@group(0) @binding(0) var<uniform> jobs: Jobs;
@group(0) @binding(1) var depth_2d: texture_depth_2d;
@group(0) @binding(2) var depth_array: texture_depth_2d_array;
@group(0) @binding(3) var<storage, read_write> values: array<f32>;

@compute @workgroup_size(64)
fn probe_depth(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= jobs.header.x {
        return;
    }
    let t = vec2<i32>(jobs.texels[id.x].xy);
    var d: f32;
    if jobs.header.w == 1u {
        d = textureLoad(depth_array, t, i32(jobs.header.z), 0);
    } else {
        d = textureLoad(depth_2d, t, 0);
    }
    values[jobs.header.y + id.x] = d;
}
