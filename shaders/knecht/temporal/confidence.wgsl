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
// history (a third ping-pong pair) keeps E and S as half floats; Eq. 3.3 compares L with the
// history as this pixel reflects it, k·E_prev + S_prev. CPU twin: cpu::knecht::merge_demodulated.
#import common/fullscreen.wgsl
#import common/reproject.wgsl
#import common/brdf.wgsl
#import common/split_light.wgsl

struct ConfidenceParams {
    // x: c_base, y: w_pos, z: w_normal, w: w_illumination
    weights: vec4<f32>,
    // x: 1 when the history is valid and temporal coherence is on; y: 1 to merge demodulated
    state: vec4<u32>,
    // x: z_far − z_near of the camera (the thesis' linear depth unit, Eq. 4.2)
    range: vec4<f32>,
}

// The merge a pipeline is made for (0 the thesis', 1 demodulated; issue #53), so that it
// carries only its own branch; 2 (the default): `params.state.y` at run time.
override DEMODULATE: u32 = 2u;

@group(0) @binding(0) var<uniform> params: ConfidenceParams;
@group(0) @binding(1) var current: texture_2d<f32>;
// The camera G-buffer's linear depth (issue #53).
@group(0) @binding(2) var g_position: texture_2d<f32>;
@group(0) @binding(3) var g_normal: texture_2d<f32>;
@group(0) @binding(4) var g_motion: texture_2d<f32>;
@group(0) @binding(5) var prev_normal: texture_2d<f32>;
@group(0) @binding(6) var history_prev: texture_2d<f32>;
@group(0) @binding(7) var confidence_out: texture_storage_2d<r32float, write>;
// Half floats (passes::knecht::temporal::HISTORY_FORMAT).
@group(0) @binding(8) var history_out: texture_storage_2d<rgba16float, write>;
// This frame's normals, next frame's prev_normal (ping-pong: no copy, issue #38).
@group(0) @binding(9) var normal_out: texture_storage_2d<rgba16float, write>;
// The demodulated merge's inputs and split history (common/split_light.wgsl).
@group(0) @binding(10) var g_albedo: texture_2d<f32>;
@group(0) @binding(11) var irradiance: texture_2d<f32>;
@group(0) @binding(12) var split_prev: texture_2d<u32>;
@group(0) @binding(13) var split_out: texture_storage_2d<rgba32uint, write>;

fn confidence(motion: vec2<f32>, size: vec2<f32>, d: f32, d_prev: f32, n: vec3<f32>, n_prev: vec3<f32>, i_new: vec3<f32>, i_prev: vec3<f32>) -> f32 {
    let w = params.weights;
    let rel_depth = (d - d_prev) / max(params.range.x, 1e-6);
    let d_pos = length(vec3<f32>(motion.x / size.x, motion.y / size.y, rel_depth)) * w.y;
    let d_normal = (1.0 - dot(n, n_prev)) * w.z;
    let scale = max(max(length(i_new), length(i_prev)), 1e-6);
    let diff = length(i_new - i_prev) / scale;
    let d_illum = clamp(diff * diff * diff, 0.0, 1.0) * w.w;
    return w.x * clamp(1.0 - max(d_pos, max(d_normal, d_illum)), 0.0, 1.0);
}

@compute @workgroup_size(TILE, TILE, 1)
fn cs_confidence(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = textureDimensions(current);
    if (gid.x >= size.x || gid.y >= size.y) {
        return;
    }
    let p = vec2<i32>(gid.xy);
    let i_new = textureLoad(current, p, 0).rgb;
    let nrm = textureLoad(g_normal, p, 0);
    // The history keeps the depth as a half float (issue #53): this frame's depth is compared
    // as the same half, so that a still pixel compares equal (Eq. 3.2's w_pos = 300 would turn
    // a half's rounding at 5 m into a confidence drop of several percent), and stored as that
    // half, exact, whatever rounding the device's store uses.
    let d = quantizeToF16(textureLoad(g_position, p, 0).x);
    var c = 0.0;
    var merged = i_new;
    let demodulate = select(params.state.y, DEMODULATE, DEMODULATE < 2u) == 1u;
    var k = vec3<f32>(0.0);
    var e_new = vec3<f32>(0.0);
    if (demodulate) {
        let alb = textureLoad(g_albedo, p, 0);
        k = brdf_diffuse(alb.rgb, alb.a);
        e_new = textureLoad(irradiance, p, 0).rgb;
    }
    let s_new = i_new - k * e_new;
    var e_out = e_new;
    var s_out = s_new;
    if (params.state.x == 1u && nrm.w > 0.5) {
        let motion = textureLoad(g_motion, p, 0).xy;
        let q = previous_texel(p, motion, size);
        if (q.x >= 0) {
            let pn = textureLoad(prev_normal, q, 0);
            let h = textureLoad(history_prev, q, 0);
            if (pn.w > 0.5 && h.a > 0.0) {
                if (demodulate) {
                    let sp = textureLoad(split_prev, q, 0);
                    let e_prev = unpack_irradiance(sp);
                    let s_prev = unpack_specular(sp);
                    c = confidence(motion, vec2<f32>(size), d, h.a, nrm.xyz, pn.xyz, i_new, k * e_prev + s_prev);
                    e_out = e_prev * c + (1.0 - c) * e_new;
                    s_out = s_prev * c + (1.0 - c) * s_new;
                    merged = k * e_out + s_out;
                } else {
                    c = confidence(motion, vec2<f32>(size), d, h.a, nrm.xyz, pn.xyz, i_new, h.rgb);
                    merged = h.rgb * c + (1.0 - c) * i_new;
                }
            }
        }
    }
    textureStore(confidence_out, p, vec4<f32>(c, 0.0, 0.0, 0.0));
    textureStore(normal_out, p, nrm);
    var depth = 0.0;
    if (nrm.w > 0.5) {
        depth = d;
    }
    textureStore(history_out, p, vec4<f32>(merged, depth));
    if (demodulate) {
        textureStore(split_out, p, pack_split(e_out, s_out));
    }
}
