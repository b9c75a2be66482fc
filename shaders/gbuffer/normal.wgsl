// Stage 1, the camera G-buffer's normals unpacked (issue #53, docs/architecture.md "The camera
// G-buffer's normal"): the raster writes each normal as one word (common/normal.wgsl); the
// passes that have not moved to the word (and every viewer, probe and read-back of
// `gbuffer.normal`) read this texture, filled only in the frames where one of them needs it.
// xyz: the unit normal in half floats, w: 1 where geometry covers the pixel; 0 elsewhere, as
// the raster's clear left it. The passes that read the word shade with these same values
// (`gbuffer_normal`).
#import common/normal.wgsl

@group(0) @binding(0) var packed: texture_2d<u32>;
@group(0) @binding(1) var out_normal: texture_storage_2d<rgba16float, write>;

@compute @workgroup_size(8, 8, 1)
fn cs_normal(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = textureDimensions(packed);
    if (gid.x >= size.x || gid.y >= size.y) {
        return;
    }
    let p = vec2<i32>(gid.xy);
    textureStore(out_normal, p, gbuffer_normal(textureLoad(packed, p, 0).x));
}
