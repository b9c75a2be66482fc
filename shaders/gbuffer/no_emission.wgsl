// Stage 1: `gbuffer.emission` of a scene where no material emits nor has an occlusion texture
// (issue #53, docs/architecture.md "The camera G-buffer's position"): the G-buffer leaves that
// target out, and this fills it when it is read with what the raster would have written:
// rgb 0 (no emitted radiance), a 1 (no occlusion texture) where geometry covers the pixel, 0
// elsewhere (the clear).

@group(0) @binding(0) var linear_depth: texture_2d<f32>;
@group(0) @binding(1) var out_emission: texture_storage_2d<rgba16float, write>;

@compute @workgroup_size(8, 8, 1)
fn cs_no_emission(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = textureDimensions(linear_depth);
    if (gid.x >= size.x || gid.y >= size.y) {
        return;
    }
    let p = vec2<i32>(gid.xy);
    let covered = textureLoad(linear_depth, p, 0).x > 0.0;
    textureStore(out_emission, p, vec4<f32>(0.0, 0.0, 0.0, select(0.0, 1.0, covered)));
}
