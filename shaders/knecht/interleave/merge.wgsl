// Stage 6: the split accumulation buffer back to image layout (Knecht 002 §3.4.1, Fig. 3.4):
// pixel (x, y) is split pixel (x mod n)·tile + (x div n) (and likewise in y).
#import common/fullscreen.wgsl

struct SplitParams {
    // x: n, y: tile width, z: tile height
    n: vec4<u32>,
}

@group(0) @binding(0) var<uniform> params: SplitParams;
@group(0) @binding(1) var split: texture_2d<f32>;
@group(0) @binding(2) var merged: texture_storage_2d<rgba16float, write>;

@compute @workgroup_size(TILE, TILE, 1)
fn cs_merge(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = textureDimensions(merged);
    if (gid.x >= size.x || gid.y >= size.y) {
        return;
    }
    let n = params.n.x;
    let s = (gid.xy % vec2<u32>(n)) * params.n.yz + gid.xy / vec2<u32>(n);
    textureStore(merged, gid.xy, textureLoad(split, s, 0));
}
