// Stage 7, tone mapping (Knecht 002 §4.6) with Reinhard's global operator
// (compose/reinhard.wgsl) into final.ldr, as a pass of its own. It runs only when the compose
// could not tone map (compose/compose.wgsl): on the first frame with automatic exposure,
// whose log-average L̄w is known only after the compose.
#import common/fullscreen.wgsl
#import compose/reinhard.wgsl

struct Params {
    // x: 2^EV, y: key a, z: L_white, w: automatic exposure (1) or manual (0)
    tone: vec4<f32>,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var hdr_in: texture_2d<f32>;
@group(0) @binding(2) var<storage, read> log_average: array<f32>;
@group(0) @binding(3) var out_ldr: texture_storage_2d<rgba8unorm, write>;

@compute @workgroup_size(TILE, TILE, 1)
fn cs_tonemap(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = textureDimensions(out_ldr);
    if (gid.x >= size.x || gid.y >= size.y) {
        return;
    }
    let px = vec2<i32>(gid.xy);
    let mapped = reinhard(textureLoad(hdr_in, px, 0).rgb, params.tone, log_average[0]);
    textureStore(out_ldr, px, vec4<f32>(mapped, 1.0));
}
