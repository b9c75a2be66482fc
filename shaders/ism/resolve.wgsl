// Stage 4: the splatted distances (inverted f32 bits, 0 = empty) become the ISM atlas
// `ism.atlas` (distances in scene units, ISM_EMPTY in holes).
const ISM_EMPTY: f32 = 1.0e30;

@group(0) @binding(0) var<storage, read> depth: array<u32>;
@group(0) @binding(1) var atlas: texture_storage_2d<r32float, write>;

@compute @workgroup_size(8, 8, 1)
fn cs_resolve(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = textureDimensions(atlas);
    if (gid.x >= size.x || gid.y >= size.y) {
        return;
    }
    let v = depth[gid.y * size.x + gid.x];
    var d = ISM_EMPTY;
    if (v != 0u) {
        d = bitcast<f32>(~v);
    }
    textureStore(atlas, gid.xy, vec4<f32>(d, 0.0, 0.0, 0.0));
}
