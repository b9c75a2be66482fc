// The removal draw of Nguyen et al. §5.1 (see cache.wgsl): every invalid cached sample is a
// quad of `surplus_quad_px` pixels at depth 0.25 and every valid one a one-pixel quad at
// depth 0.75, both into `hcb.cache` (3: removed, 1: cached) with a less-than depth test, so
// that a removal quad clears the valid (surplus) samples under it in any draw order — the
// paper's "larger depth value for valid samples, smaller for invalid ones".
#import common/camera.wgsl
#import hcb/common.wgsl

@group(0) @binding(0) var<uniform> camera: Camera;
@group(0) @binding(1) var<uniform> cp: CacheParams;
@group(0) @binding(2) var<storage, read> prev: array<HcbSample>;

struct RemovalOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) @interpolate(flat) value: f32,
}

@vertex
fn vs_removal(@builtin(vertex_index) v: u32, @builtin(instance_index) i: u32) -> RemovalOut {
    var out: RemovalOut;
    let s = prev[i];
    let st = status(s);
    out.value = select(1.0, 3.0, st == INVALID);
    if (st == DROPPED) {
        out.clip = vec4<f32>(-2.0, -2.0, 0.5, 1.0);
        return out;
    }
    let half = select(0.5, 0.5 * cp.limits.z, st == INVALID);
    let pixel = vec2<f32>(unpack_pixel(s.texel.w)) + 0.5 + quad_corner(v) * half;
    let ndc = vec2<f32>(pixel.x * camera.viewport.z * 2.0 - 1.0, 1.0 - pixel.y * camera.viewport.w * 2.0);
    // Invalid samples nearer than valid ones: the depth test lets the quads clear them.
    out.clip = vec4<f32>(ndc, select(0.75, 0.25, st == INVALID), 1.0);
    return out;
}

@fragment
fn fs_removal(in: RemovalOut) -> @location(0) vec4<f32> {
    return vec4<f32>(in.value, 0.0, 0.0, 0.0);
}

