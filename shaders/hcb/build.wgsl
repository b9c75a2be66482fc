// HCB level k from level k − 1: Algorithm 1 of Nguyen et al. (§3.4) with the distance
// accumulation of §3.5 over the 3×3 block centred at (2x, 2y). Neighbour c is coherent to
// the centre a when n_c^w · (n_a · n_c) ≥ cos θ_max (Eq. 6–7), the pose test of Eq. 3
// holds, and R'_c = ‖a − c‖ + R_c ≤ d_max (Eq. 1 on the accumulated distance). All eight
// coherent: n^w = min(n_a^w, n_c^w (n_a · n_c)), a^w = max(R_a, R'_c); else n^w = 0.
// A block reaching outside the level is incoherent. With the cache's signs (§5.2) |n^w|
// enters the test and the result keeps the centre's sign, or is positive when any texel of
// the block is (Fig. 7d, hp.level.w). CPU twin: cpu::hcb::build_texel.
#import hcb/common.wgsl

@group(0) @binding(0) var<uniform> hp: HcbParams;
@group(0) @binding(1) var prev_position: texture_2d<f32>;
@group(0) @binding(2) var prev_normal: texture_2d<f32>;
@group(0) @binding(3) var out_position: texture_storage_2d<rgba32float, write>;
@group(0) @binding(4) var out_normal: texture_storage_2d<rgba32float, write>;

// Eq. 3: with backward lighting (the two not facing each other), |âb · n_a| ≤ cos γ_max.
fn pose_coherent(a: vec3<f32>, na: vec3<f32>, b: vec3<f32>, nb: vec3<f32>) -> bool {
    let d = b - a;
    let len = length(d);
    if (len <= 0.0) {
        return true;
    }
    let ab = d / len;
    let backward = dot(ab, na) <= 0.0 || dot(-ab, nb) <= 0.0;
    return !backward || abs(dot(ab, na)) <= hp.thresholds.y;
}

@compute @workgroup_size(8, 8, 1)
fn cs_build(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = textureDimensions(out_position);
    if (gid.x >= size.x || gid.y >= size.y) {
        return;
    }
    let prev = vec2<i32>(textureDimensions(prev_position));
    let c = vec2<i32>(gid.xy) * 2;
    let a = textureLoad(prev_position, c, 0);
    let na = textureLoad(prev_normal, c, 0);
    var coherence = abs(na.w);
    var distance = a.w;
    var all = na.w != 0.0;
    var positive = na.w > 0.0;
    for (var j = -1; j <= 1 && all; j = j + 1) {
        for (var i = -1; i <= 1 && all; i = i + 1) {
            if (i == 0 && j == 0) {
                continue;
            }
            let t = c + vec2<i32>(i, j);
            if (t.x < 0 || t.y < 0 || t.x >= prev.x || t.y >= prev.y) {
                all = false;
                break;
            }
            let b = textureLoad(prev_position, t, 0);
            let nb = textureLoad(prev_normal, t, 0);
            let temp = abs(nb.w) * dot(na.xyz, nb.xyz);
            let reach = length(b.xyz - a.xyz) + b.w;
            if (nb.w != 0.0 && temp >= hp.thresholds.x && pose_coherent(a.xyz, na.xyz, b.xyz, nb.xyz) && reach <= hp.thresholds.z) {
                coherence = min(coherence, temp);
                distance = max(distance, reach);
                positive = positive || (hp.level.w == 1u && nb.w > 0.0);
            } else {
                all = false;
            }
        }
    }
    if (!all) {
        coherence = 0.0;
        distance = a.w;
    } else if (!positive) {
        coherence = -coherence;
    }
    textureStore(out_position, gid.xy, vec4<f32>(a.xyz, distance));
    textureStore(out_normal, gid.xy, vec4<f32>(na.xyz, coherence));
}
