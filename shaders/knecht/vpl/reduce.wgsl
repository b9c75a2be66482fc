// Stage 3: one level of the importance pyramid (Knecht 002 §3.3): each texel the average of
// its 2×2 children in the finer level (CPU twin: cpu::knecht::Pyramid::new).

@group(0) @binding(0) var finer: texture_2d_array<f32>;
@group(0) @binding(1) var coarser: texture_storage_2d_array<r32float, write>;

@compute @workgroup_size(8, 8, 1)
fn cs_reduce(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = textureDimensions(coarser);
    if (gid.x >= size.x || gid.y >= size.y) {
        return;
    }
    let layer = i32(gid.z);
    let c = vec2<i32>(gid.xy) * 2;
    let a00 = textureLoad(finer, c, layer, 0).r;
    let a10 = textureLoad(finer, c + vec2<i32>(1, 0), layer, 0).r;
    let a01 = textureLoad(finer, c + vec2<i32>(0, 1), layer, 0).r;
    let a11 = textureLoad(finer, c + vec2<i32>(1, 1), layer, 0).r;
    textureStore(coarser, vec2<i32>(gid.xy), layer, vec4<f32>((a00 + a10 + a01 + a11) * 0.25, 0.0, 0.0, 0.0));
}
