// Stages 6–7 in one pass (issue #53): the geometry-aware filter of the gathered light
// (knecht/interleave/filter_window.wgsl, Knecht 002 §3.4.1) and the confidence merge of its
// result with the reprojected history (knecht/temporal/merge.wgsl, §3.5, Eq. 3.1–3.6), for the
// default order (filter, then merge). The filtered light and its mean irradiance stay in
// registers instead of going through `indirect.filtered` and `indirect.filtered_irradiance`
// (32 bytes a pixel written and read, and the G-buffer read twice); the pass of its own
// (knecht/interleave/filter.wgsl) fills those two when they are read. The merge's input differs
// from the two passes' by the half-float rounding of those two textures only. CPU twins:
// cpu::knecht::geometry_aware_filter, then cpu::knecht::confidence / merge_demodulated.
#import common/fullscreen.wgsl
#import knecht/interleave/filter_window.wgsl
#import knecht/temporal/merge.wgsl

@group(0) @binding(0) var<uniform> params: ConfidenceParams;
// The gathered light (`indirect.merged`), filtered here.
@group(0) @binding(1) var src: texture_2d<f32>;
// The camera G-buffer's linear depth (issue #53).
@group(0) @binding(2) var g_position: texture_2d<f32>;
// The camera G-buffer's packed normal (common/normal.wgsl, issue #53).
@group(0) @binding(3) var g_normal: texture_2d<u32>;
@group(0) @binding(4) var g_motion: texture_2d<f32>;
@group(0) @binding(5) var prev_normal: texture_2d<f32>;
@group(0) @binding(6) var history_prev: texture_2d<f32>;
@group(0) @binding(7) var confidence_out: texture_storage_2d<r32float, write>;
@group(0) @binding(8) var history_out: texture_storage_2d<rgba16float, write>;
@group(0) @binding(9) var normal_out: texture_storage_2d<rgba16float, write>;
@group(0) @binding(10) var g_albedo: texture_2d<f32>;
// The gathered light's irradiance (`indirect.irradiance`), filtered when demodulated.
@group(0) @binding(11) var irradiance: texture_2d<f32>;
@group(0) @binding(12) var split_prev: texture_2d<u32>;
@group(0) @binding(13) var split_out: texture_storage_2d<rgba32uint, write>;
@group(0) @binding(14) var<uniform> filter_params: FilterParams;

@compute @workgroup_size(TILE, TILE, 1)
fn cs_filter_merge(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = textureDimensions(src);
    if (gid.x >= size.x || gid.y >= size.y) {
        return;
    }
    let p = vec2<i32>(gid.xy);
    let f = filter_window(p, size, filter_params);
    merge_pixel(p, size, f.light, f.irradiance);
}
