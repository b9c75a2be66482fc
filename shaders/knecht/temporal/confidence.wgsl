// Stage 7, temporal coherence (Knecht 002 §3.5): the previous frame's indirect light, depth
// and normal are fetched through the movement buffer (§3.5.1: the previous position of pixel
// p is p + m_buf(p)); the confidence of Eq. 3.1–3.4 weighs them against this frame's light
// by the merge of Eq. 3.6, I = I_prev · confidence + (1 − confidence) · I_new. The thesis
// computes the confidence on the fly; we also store it (`temporal.confidence`). Pixels whose
// previous position is off screen or was background get confidence 0. The history keeps the
// merged light in rgb and the linear depth in a, as the thesis stores depth in the fourth
// channel of the old illumination. CPU twin: cpu::knecht::confidence (readings there).
//
// Demodulated (state.y = 1; issue #51, docs/readings.md knecht.demodulated-merge): the light
// is split as the demodulated filter split it, L = k·E + S with E the filter's mean irradiance
// (`indirect.filtered_irradiance`), k = c·DI/π this pixel's diffuse colour and S the specular
// light; E and S are merged apart and reflected with this pixel's own k, so that a history
// reprojected from a neighbouring texel brings its light but not its texture. The split
// history (a third ping-pong pair) keeps E and S as half floats, and the normal that the
// thesis' merge keeps in `normal_out` (issue #53, common/split_light.wgsl); Eq. 3.3 compares L
// with the history as this pixel reflects it, k·E_prev + S_prev. CPU twin:
// cpu::knecht::merge_demodulated.
#import common/fullscreen.wgsl
#import knecht/temporal/merge.wgsl

@group(0) @binding(0) var<uniform> params: ConfidenceParams;
@group(0) @binding(1) var current: texture_2d<f32>;
// The camera G-buffer's linear depth (issue #53).
@group(0) @binding(2) var g_position: texture_2d<f32>;
// The camera G-buffer's packed normal (common/normal.wgsl, issue #53).
@group(0) @binding(3) var g_normal: texture_2d<u32>;
@group(0) @binding(4) var g_motion: texture_2d<f32>;
@group(0) @binding(5) var prev_normal: texture_2d<f32>;
@group(0) @binding(6) var history_prev: texture_2d<f32>;
@group(0) @binding(7) var confidence_out: texture_storage_2d<r32float, write>;
// Half floats (passes::knecht::temporal::HISTORY_FORMAT).
@group(0) @binding(8) var history_out: texture_storage_2d<rgba16float, write>;
// This frame's normals, next frame's prev_normal (ping-pong: no copy, issue #38); not written
// by the demodulated merge, whose split history keeps the normal.
@group(0) @binding(9) var normal_out: texture_storage_2d<rgba16float, write>;
// The demodulated merge's inputs and split history (common/split_light.wgsl).
@group(0) @binding(10) var g_albedo: texture_2d<f32>;
@group(0) @binding(11) var irradiance: texture_2d<f32>;
@group(0) @binding(12) var split_prev: texture_2d<u32>;
@group(0) @binding(13) var split_out: texture_storage_2d<rgba32uint, write>;

@compute @workgroup_size(TILE, TILE, 1)
fn cs_confidence(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = textureDimensions(current);
    if (gid.x >= size.x || gid.y >= size.y) {
        return;
    }
    let p = vec2<i32>(gid.xy);
    var e_new = vec3<f32>(0.0);
    if (merges_demodulated()) {
        e_new = textureLoad(irradiance, p, 0).rgb;
    }
    merge_pixel(p, size, textureLoad(current, p, 0).rgb, e_new);
}

// `temporal.prev_normal` filled from the demodulated merge's split history when it is read
// (issue #53: that merge keeps the normal in the split's free word and writes no normals
// texture): the split history just written (bound as `split_prev`) into `normal_out`.
@compute @workgroup_size(TILE, TILE, 1)
fn cs_split_normal(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = textureDimensions(normal_out);
    if (gid.x >= size.x || gid.y >= size.y) {
        return;
    }
    let p = vec2<i32>(gid.xy);
    textureStore(normal_out, p, unpack_normal(textureLoad(split_prev, p, 0).w));
}
