// Temporal filtering of the screen-space indirect light (Soler et al. 004 §4, Eq. 6):
// F_i = a·W(H) + (1 − a)·I_i. W warps the history H to the current pixel p through the
// movement buffer (camera and object motion): the pixel was at q = p + m(p) in the previous
// frame (nearest texel). The history is rejected (a = 0) where q is off screen or was
// background, where the depth stored at q differs from the point's depth in the previous
// frame by more than τ_z of it, or where n · n_prev(q) < τ_n. That depth is the movement
// buffer's z, with the previous camera and the previous object transform (⚠[soler.temporal-object-motion]:
// W "accounts for both the camera and the moving object"; projecting the current position with
// the previous camera alone rejected every moving object's history).
// a adapts to motion, a · m½ / (m½ + |m|), and to glossiness, ÷ (1 + k_g · SI · √SP).
// H is F_{i−1} or I_{i−1} (a setting: the paper prints I_{i−1}). What is blended (reject.w,
// ⚠[soler.temporal-order]): the radiance as it comes, or, as Fig. 4 orders it, the irradiance
// before the albedo multiply: I_i is demodulated, E_i = (I_i − S_i) / (c·DI/π) per channel
// (S_i the glossy light added into it, 0 where the albedo is), the blend runs on E and the
// history keeps E; the glossy light has its own history, blended by the same a (adapted to
// the glossiness, as the text adapts it against ghosting on shiny surfaces), and F = c·DI/π ·
// F_E + F_S. Outputs: F (`soler.temporal`),
// the next history (rgb, depth in a), W(H) (a: 1 where q holds a surface), the rejection mask
// (r depth, g normal, b no history) and the effective a. CPU twin: cpu::soler_temporal::blend.
#import common/camera.wgsl
#import common/reproject.wgsl
#import common/normal.wgsl

// Rust twin: passes::soler::temporal::TemporalParams.
struct TemporalParams {
    // x: a, y: m½ (px/frame), z: k_g, w: 1 when the history holds a frame
    blend: vec4<f32>,
    // x: τ_z, y: τ_n, z: 1 when the history keeps I_{i−1} (else F_{i−1}); w: what is blended:
    // 0 the radiance, 1 the irradiance, 2 the irradiance less the glossy light `specular`
    reject: vec4<f32>,
}

@group(0) @binding(0) var<uniform> params: TemporalParams;
@group(0) @binding(1) var<uniform> camera: Camera;
@group(0) @binding(2) var current: texture_2d<f32>;
@group(0) @binding(3) var g_position: texture_2d<f32>;
// The camera G-buffer's packed normals (common/normal.wgsl, issue #53).
@group(0) @binding(4) var g_normal: texture_2d<u32>;
@group(0) @binding(5) var g_motion: texture_2d<f32>;
@group(0) @binding(6) var g_material: texture_2d<f32>;
@group(0) @binding(7) var prev_normal: texture_2d<f32>;
@group(0) @binding(8) var history_prev: texture_2d<f32>;
// F and W as half floats, the history (depth in a) as floats, the rejection flags as bytes
// (passes::soler::temporal::{LIGHT_FORMAT, MASK_FORMAT}).
@group(0) @binding(9) var out_filtered: texture_storage_2d<rgba16float, write>;
@group(0) @binding(10) var out_history: texture_storage_2d<rgba32float, write>;
@group(0) @binding(11) var out_warped: texture_storage_2d<rgba16float, write>;
@group(0) @binding(12) var out_mask: texture_storage_2d<rgba8unorm, write>;
@group(0) @binding(13) var out_a: texture_storage_2d<r32float, write>;
// This frame's normals, next frame's prev_normal (ping-pong: no copy, issue #38).
@group(0) @binding(14) var out_normal: texture_storage_2d<rgba16float, write>;
@group(0) @binding(15) var g_albedo: texture_2d<f32>;
// The glossy light added into `current` (reject.w = 2).
@group(0) @binding(16) var specular: texture_2d<f32>;
// The glossy light's history (F_S or S as the history keeps F or I), read at the warped texel
// and written for the next frame (ping-pong, like out_history).
@group(0) @binding(17) var spec_history_prev: texture_2d<f32>;
@group(0) @binding(18) var out_spec_history: texture_storage_2d<rgba16float, write>;

const INV_PI: f32 = 0.318309886183791;

@compute @workgroup_size(8, 8, 1)
fn cs_temporal(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = textureDimensions(current);
    if (gid.x >= size.x || gid.y >= size.y) {
        return;
    }
    let p = vec2<i32>(gid.xy);
    let radiance = textureLoad(current, p, 0).rgb;
    // The albedo k = c·DI/π and the glossy light s that turn the blended quantity into
    // radiance: k·x + s (k = 1, s = 0 when the radiance itself is blended).
    var k = vec3<f32>(1.0);
    var s = vec3<f32>(0.0);
    if (params.reject.w > 0.5) {
        let alb = textureLoad(g_albedo, p, 0);
        k = alb.rgb * alb.a * INV_PI;
        if (params.reject.w > 1.5) {
            s = textureLoad(specular, p, 0).rgb;
        }
    }
    let i_new = select(vec3<f32>(0.0), max(radiance - s, vec3<f32>(0.0)) / k, k > vec3<f32>(0.0));
    let nrm = gbuffer_normal(textureLoad(g_normal, p, 0).x);
    let pos = textureLoad(g_position, p, 0);
    var a = 0.0;
    var warped = vec4<f32>(0.0);
    var warped_s = vec3<f32>(0.0);
    var mask = vec4<f32>(0.0, 0.0, 1.0, 1.0);
    if (params.blend.w > 0.5 && nrm.w > 0.5) {
        let motion = textureLoad(g_motion, p, 0).xy;
        let q = previous_texel(p, motion, size);
        if (q.x >= 0) {
            let pn = textureLoad(prev_normal, q, 0);
            let h = textureLoad(history_prev, q, 0);
            if (pn.w > 0.5 && h.a > 0.0) {
                warped = vec4<f32>(h.rgb, 1.0);
                warped_s = textureLoad(spec_history_prev, q, 0).rgb;
                mask.z = 0.0;
                let z_prev = textureLoad(g_motion, p, 0).z;
                if (abs(h.a - z_prev) > params.reject.x * max(z_prev, 1e-6)) {
                    mask.x = 1.0;
                }
                if (dot(nrm.xyz, pn.xyz) < params.reject.y) {
                    mask.y = 1.0;
                }
                if (mask.x < 0.5 && mask.y < 0.5) {
                    let mat = textureLoad(g_material, p, 0);
                    let speed = length(motion);
                    let half = params.blend.y;
                    a = params.blend.x * half / (half + speed)
                        / (1.0 + params.blend.z * max(mat.x, 0.0) * sqrt(max(mat.y, 0.0)));
                }
            }
        }
    }
    let f = a * warped.rgb + (1.0 - a) * i_new;
    let f_s = a * warped_s + (1.0 - a) * s;
    textureStore(out_filtered, gid.xy, vec4<f32>(k * f + f_s, 1.0));
    var keep_s = f_s;
    if (params.reject.z > 0.5) {
        keep_s = s;
    }
    textureStore(out_spec_history, gid.xy, vec4<f32>(keep_s, 1.0));
    var keep = f;
    if (params.reject.z > 0.5) {
        keep = i_new;
    }
    var depth = 0.0;
    if (nrm.w > 0.5) {
        depth = pos.w;
    }
    textureStore(out_history, gid.xy, vec4<f32>(keep, depth));
    textureStore(out_warped, gid.xy, warped);
    textureStore(out_mask, gid.xy, mask);
    textureStore(out_a, gid.xy, vec4<f32>(a, 0.0, 0.0, 0.0));
    textureStore(out_normal, gid.xy, nrm);
}
