// Stage 7, tone mapping (Knecht 002 §4.6) with the global operator of Reinhard et al.
// [RSSF02] Eq. 2 and 4:
//   L = s · Lw with s = 2^EV (manual) or s = 2^EV · a / L̄w (automatic, key a),
//   Ld = L (1 + L / L²white) / (1 + L),
// applied to the colour by the ratio Ld / Lw, then sRGB-encoded into final.ldr.
#import common/fullscreen.wgsl

struct Params {
    // x: 2^EV, y: key a, z: L_white, w: automatic exposure (1) or manual (0)
    tone: vec4<f32>,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var hdr_in: texture_2d<f32>;
@group(0) @binding(2) var<storage, read> log_average: array<f32>;
@group(0) @binding(3) var out_ldr: texture_storage_2d<rgba8unorm, write>;
fn srgb_encode(c: vec3<f32>) -> vec3<f32> {
    let lo = c * 12.92;
    let hi = 1.055 * pow(c, vec3<f32>(1.0 / 2.4)) - 0.055;
    return select(hi, lo, c <= vec3<f32>(0.0031308));
}

@compute @workgroup_size(TILE, TILE, 1)
fn cs_tonemap(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = textureDimensions(out_ldr);
    if (gid.x >= size.x || gid.y >= size.y) {
        return;
    }
    let px = vec2<i32>(gid.xy);
    let c = max(textureLoad(hdr_in, px, 0).rgb, vec3<f32>(0.0));
    let lw = dot(c, vec3<f32>(0.2126, 0.7152, 0.0722));
    var s = params.tone.x;
    if (params.tone.w > 0.5) {
        s = s * params.tone.y / max(log_average[0], 1e-6);
    }
    let l = s * lw;
    let lwhite2 = params.tone.z * params.tone.z;
    let ld = l * (1.0 + l / lwhite2) / (1.0 + l);
    var mapped = vec3<f32>(0.0);
    if (lw > 0.0) {
        mapped = c * (ld / lw);
    }
    textureStore(out_ldr, px, vec4<f32>(srgb_encode(clamp(mapped, vec3<f32>(0.0), vec3<f32>(1.0))), 1.0));
}
