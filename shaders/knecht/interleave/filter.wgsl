// Stage 6: the geometry-aware n×n box filter (Knecht 002 §3.4.1 after Laine et al. 2007) as a
// pass of its own (knecht/interleave/filter_window.wgsl; the default list fuses it into the
// confidence merge, knecht/temporal/filter_merge.wgsl, issue #53). The mean irradiance goes to
// `indirect.filtered_irradiance` for the demodulated confidence merge
// (knecht/temporal/confidence.wgsl). CPU twin: cpu::knecht::geometry_aware_filter.
#import common/fullscreen.wgsl
#import knecht/interleave/filter_window.wgsl

@group(0) @binding(0) var<uniform> params: FilterParams;
@group(0) @binding(1) var src: texture_2d<f32>;
// The camera G-buffer's linear depth (issue #53).
@group(0) @binding(2) var g_position: texture_2d<f32>;
// The camera G-buffer's packed normal (common/normal.wgsl, issue #53).
@group(0) @binding(3) var g_normal: texture_2d<u32>;
@group(0) @binding(4) var dst: texture_storage_2d<rgba16float, write>;
@group(0) @binding(5) var irradiance: texture_2d<f32>;
@group(0) @binding(6) var g_albedo: texture_2d<f32>;
@group(0) @binding(7) var dst_irradiance: texture_storage_2d<rgba16float, write>;

@compute @workgroup_size(TILE, TILE, 1)
fn cs_filter(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = textureDimensions(dst);
    if (gid.x >= size.x || gid.y >= size.y) {
        return;
    }
    let p = vec2<i32>(gid.xy);
    let f = filter_window(p, size, params);
    textureStore(dst, p, vec4<f32>(f.light, 1.0));
    textureStore(dst_irradiance, p, vec4<f32>(f.irradiance, 1.0));
}
