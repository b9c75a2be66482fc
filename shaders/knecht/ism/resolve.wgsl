// Stage 4: the splatted distances (inverted f32 bits, 0 = empty) become the ISM atlas
// `ism.atlas` (distances in scene units, ISM_EMPTY in holes).
const ISM_EMPTY: f32 = 1.0e30;

// The call's first row (`ism.rs` `IsmPass::finish_maps`: only the rows of the maps splatted
// since the last resolve); the twin of pull_push.wgsl's LevelParams, of which it reads tile.y.
struct LevelParams {
    threshold: vec4<f32>,
    tile: vec4<u32>,
}

@group(0) @binding(0) var<storage, read> depth: array<u32>;
@group(0) @binding(1) var atlas: texture_storage_2d<r32float, write>;
@group(0) @binding(2) var<uniform> lp: LevelParams;

@compute @workgroup_size(8, 8, 1)
fn cs_resolve(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = textureDimensions(atlas);
    let g = vec2<u32>(gid.x, gid.y + lp.tile.y);
    if (g.x >= size.x || g.y >= size.y) {
        return;
    }
    let v = depth[g.y * size.x + g.x];
    var d = ISM_EMPTY;
    if (v != 0u) {
        d = bitcast<f32>(~v);
    }
    textureStore(atlas, g, vec4<f32>(d, 0.0, 0.0, 0.0));
}
