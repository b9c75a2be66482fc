// HCB level 0 (Nguyen et al. §3.2, §3.5): the G-buffer's position and normal, with n^w = 1
// (0 for the background) and a^w = the pixel's world-space footprint, √ of its back-projected
// area: its width at the view depth over √|cos| of the angle to the eye (|cos| clamped below
// at `hcb.footprint_min_cos`).
// For the cache (§5.2) this is the supplementary G-buffer: all of the G-buffer, with n^w = +1
// on incomplete texels (splatted weight Σw below the threshold) and −1 on the others, and
// `hcb.incomplete` marks the former.
#import hcb/common.wgsl

@group(0) @binding(0) var<uniform> hp: HcbParams;
@group(0) @binding(1) var g_position: texture_2d<f32>;
@group(0) @binding(2) var g_normal: texture_2d<f32>;
@group(0) @binding(3) var out_position: texture_storage_2d<rgba32float, write>;
@group(0) @binding(4) var out_normal: texture_storage_2d<rgba32float, write>;
// the cached samples' splat (a = Σw) and `hcb.incomplete`; 1×1 dummies without the cache
@group(0) @binding(5) var weight_sum: texture_2d<f32>;
@group(0) @binding(6) var out_incomplete: texture_storage_2d<r32float, write>;

@compute @workgroup_size(8, 8, 1)
fn cs_base(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = textureDimensions(out_position);
    if (gid.x >= size.x || gid.y >= size.y) {
        return;
    }
    let p = textureLoad(g_position, gid.xy, 0);
    let n = textureLoad(g_normal, gid.xy, 0);
    let supplementary = hp.level.z == 1u;
    if (n.w < 0.5) {
        textureStore(out_position, gid.xy, vec4<f32>(0.0));
        textureStore(out_normal, gid.xy, vec4<f32>(0.0, 0.0, 1.0, 0.0));
        if (supplementary) {
            textureStore(out_incomplete, gid.xy, vec4<f32>(0.0));
        }
        return;
    }
    var coherence = 1.0;
    if (supplementary) {
        let incomplete = textureLoad(weight_sum, gid.xy, 0).a < hp.cache.x;
        coherence = select(-1.0, 1.0, incomplete);
        textureStore(out_incomplete, gid.xy, vec4<f32>(select(0.0, 1.0, incomplete), 0.0, 0.0, 0.0));
    }
    let nrm = normalize(n.xyz);
    let to_eye = normalize(hp.eye.xyz - p.xyz);
    let r = p.w * hp.thresholds.w / sqrt(max(abs(dot(nrm, to_eye)), hp.cache.z));
    textureStore(out_position, gid.xy, vec4<f32>(p.xyz, r));
    textureStore(out_normal, gid.xy, vec4<f32>(nrm, coherence));
}
