// Stage 7, composition (Knecht 002 §4.6): final.hdr = emission + direct + indirect + near
// field (the surface's own emission L_e, `gbuffer.emission`, is kept out of direct.radiance so
// that no gather takes an emitter for a sender besides its VPLs; each
// indirect input is black when no stage provides it; the near field is `pipeline.near_field`'s
// screen-space gather of the senders closer than the split, the indirect input the VPLs'). Tone mapping: compose/tonemap.wgsl.
#import common/fullscreen.wgsl

@group(0) @binding(1) var direct: texture_2d<f32>;
@group(0) @binding(2) var indirect: texture_2d<f32>;
@group(0) @binding(3) var out_hdr: texture_storage_2d<rgba32float, write>;
@group(0) @binding(4) var near_field: texture_2d<f32>;
@group(0) @binding(5) var emission: texture_2d<f32>;

@compute @workgroup_size(TILE, TILE, 1)
fn cs_compose(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = textureDimensions(out_hdr);
    if (gid.x >= size.x || gid.y >= size.y) {
        return;
    }
    let px = vec2<i32>(gid.xy);
    let c = textureLoad(emission, px, 0).rgb + textureLoad(direct, px, 0).rgb + textureLoad(indirect, px, 0).rgb + textureLoad(near_field, px, 0).rgb;
    textureStore(out_hdr, px, vec4<f32>(c, 1.0));
}

