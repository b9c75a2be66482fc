// Stage 7's confidence merge at one pixel (Knecht 002 §3.5), shared by the merge pass
// (knecht/temporal/confidence.wgsl) and the geometry-aware filter fused into it
// (knecht/temporal/filter_merge.wgsl, issue #53); what it computes and stores is described in
// confidence.wgsl. CPU twins: cpu::knecht::confidence, cpu::knecht::merge_demodulated.
//
// The including module declares `params` (ConfidenceParams), `g_position` (the camera
// G-buffer's linear depth, issue #53), `g_normal` (its packed normal), `g_motion`, `prev_normal`, `history_prev`,
// `confidence_out`, `history_out`, `normal_out`, `g_albedo`, `split_prev` and `split_out`.
#import common/reproject.wgsl
#import common/brdf.wgsl
#import common/split_light.wgsl

struct ConfidenceParams {
    // x: c_base, y: w_pos, z: w_normal, w: w_illumination
    weights: vec4<f32>,
    // x: 1 when the history is valid and temporal coherence is on; y: 1 to merge demodulated;
    // z: what the pass stores (issue #53): 0 everything, 1 everything but the confidence (no
    // one reads it this frame), 2 the confidence alone (its fill when it is read afterwards)
    state: vec4<u32>,
    // x: z_far − z_near of the camera (the thesis' linear depth unit, Eq. 4.2)
    range: vec4<f32>,
}

// The merge a pipeline is made for (0 the thesis', 1 demodulated; issue #53), so that it
// carries only its own branch; 2 (the default): `params.state.y` at run time.
override DEMODULATE: u32 = 2u;

fn merges_demodulated() -> bool {
    return select(params.state.y, DEMODULATE, DEMODULATE < 2u) == 1u;
}

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

// Merges pixel p's new light `i_new` (and, merging demodulated, the irradiance `e_in` it
// reflects) with the reprojected history and stores the confidence, the history, and the
// normal (in `normal_out`, or demodulated in the split history's free word, issue #53) and the
// split history of the pixel.
fn merge_pixel(p: vec2<i32>, size: vec2<u32>, i_new: vec3<f32>, e_in: vec3<f32>) {
    let nw = textureLoad(g_normal, p, 0).x;
    let nrm = gbuffer_normal(nw);
    // The history keeps the depth as a half float (issue #53): this frame's depth is compared
    // as the same half, so that a still pixel compares equal (Eq. 3.2's w_pos = 300 would turn
    // a half's rounding at 5 m into a confidence drop of several percent), and stored as that
    // half, exact, whatever rounding the device's store uses.
    let d = quantizeToF16(textureLoad(g_position, p, 0).x);
    var c = 0.0;
    var merged = i_new;
    let demodulate = merges_demodulated();
    var k = vec3<f32>(0.0);
    var e_new = vec3<f32>(0.0);
    if (demodulate) {
        let alb = textureLoad(g_albedo, p, 0);
        k = brdf_diffuse(alb.rgb, alb.a);
        e_new = e_in;
    }
    let s_new = i_new - k * e_new;
    var e_out = e_new;
    var s_out = s_new;
    if (params.state.x == 1u && nrm.w > 0.5) {
        let motion = textureLoad(g_motion, p, 0).xy;
        let q = previous_texel(p, motion, size);
        if (q.x >= 0) {
            let h = textureLoad(history_prev, q, 0);
            if (demodulate) {
                // n_prev from the split history's normal word (issue #53).
                let sp = textureLoad(split_prev, q, 0);
                let pn = unpack_normal(sp.w);
                if (pn.w > 0.5 && h.a > 0.0) {
                    let e_prev = unpack_irradiance(sp);
                    let s_prev = unpack_specular(sp);
                    c = confidence(motion, vec2<f32>(size), d, h.a, nrm.xyz, pn.xyz, i_new, k * e_prev + s_prev);
                    e_out = e_prev * c + (1.0 - c) * e_new;
                    s_out = s_prev * c + (1.0 - c) * s_new;
                    merged = k * e_out + s_out;
                }
            } else {
                let pn = textureLoad(prev_normal, q, 0);
                if (pn.w > 0.5 && h.a > 0.0) {
                    c = confidence(motion, vec2<f32>(size), d, h.a, nrm.xyz, pn.xyz, i_new, h.rgb);
                    merged = h.rgb * c + (1.0 - c) * i_new;
                }
            }
        }
    }
    if (params.state.z != 1u) {
        textureStore(confidence_out, p, vec4<f32>(c, 0.0, 0.0, 0.0));
    }
    if (params.state.z == 2u) {
        return;
    }
    if (!demodulate) {
        // Demodulated, the normal goes into the split history's free word instead.
        textureStore(normal_out, p, nrm);
    }
    var depth = 0.0;
    if (nrm.w > 0.5) {
        depth = d;
    }
    textureStore(history_out, p, vec4<f32>(merged, depth));
    if (demodulate) {
        textureStore(split_out, p, pack_split(e_out, s_out, nw));
    }
}
