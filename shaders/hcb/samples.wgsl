// HCB mask buffer and sample identification (Nguyen et al. §3.6). cs_mask: a texel of level
// k − 1 is 'inside' when a coherent texel of level k splats over it (its 3×3 block contains
// it); every coherent texel splats, so each texel looks up its at most 2×2 possible parents
// instead of a top-down scatter. cs_samples: the coherent texels of the top level and the
// coherent texels outside the splats at the others are the samples — appended to the compact
// list (for gathering) and marked in the sample buffer at G-buffer resolution (value =
// level + 1 at pixel (2^k x, 2^k y)). With the cache's signs (§5.2) 'coherent' is n^w > 0:
// only groups with incomplete texels splat and are samples. A new sample's recompute counter
// starts at the 4×4 index pattern's value at its texel (§5.3); with the cache it is marked
// new (2) in `hcb.cache` and its phase + 1 in `hcb.recompute_group`.
// CPU twins: cpu::hcb::{masks, samples, recompute_pattern}.
#import hcb/common.wgsl

@group(0) @binding(0) var<uniform> hp: HcbParams;
// level k's normals (coherence in w) for cs_mask; the level's own for cs_samples
@group(0) @binding(1) var level_normal: texture_2d<f32>;
// cs_mask: the mask of level k − 1 it writes; cs_samples: the level's mask
@group(0) @binding(2) var mask_out: texture_storage_2d<r32float, write>;
@group(0) @binding(3) var mask_in: texture_2d<f32>;
@group(0) @binding(4) var samples_out: texture_storage_2d<r32float, write>;
// the number of samples
@group(0) @binding(5) var<storage, read_write> counter: array<atomic<u32>>;
@group(0) @binding(6) var level_position: texture_2d<f32>;
@group(0) @binding(7) var<storage, read_write> list: array<HcbSample>;
// `hcb.cache` and `hcb.recompute_group` (1×1 dummies without the cache)
@group(0) @binding(8) var cache_out: texture_storage_2d<r32float, write>;
@group(0) @binding(9) var group_out: texture_storage_2d<r32float, write>;

@compute @workgroup_size(8, 8, 1)
fn cs_mask(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = textureDimensions(mask_out);
    if (gid.x >= size.x || gid.y >= size.y) {
        return;
    }
    let parents = vec2<i32>(textureDimensions(level_normal));
    let t = vec2<i32>(gid.xy);
    var inside = 0.0;
    for (var py = (t.y - 1) / 2; py <= (t.y + 1) / 2; py = py + 1) {
        for (var px = (t.x - 1) / 2; px <= (t.x + 1) / 2; px = px + 1) {
            let p = vec2<i32>(px, py);
            if (any(p < vec2<i32>(0)) || any(p >= parents) || any(abs(2 * p - t) > vec2<i32>(1))) {
                continue;
            }
            if (textureLoad(level_normal, p, 0).w > 0.0) {
                inside = 1.0;
            }
        }
    }
    textureStore(mask_out, gid.xy, vec4<f32>(inside, 0.0, 0.0, 0.0));
}

@compute @workgroup_size(8, 8, 1)
fn cs_clear(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = textureDimensions(samples_out);
    if (gid.x >= size.x || gid.y >= size.y) {
        return;
    }
    textureStore(samples_out, gid.xy, vec4<f32>(0.0));
    if (hp.level.z == 1u) {
        textureStore(group_out, gid.xy, vec4<f32>(0.0));
    }
}

@compute @workgroup_size(8, 8, 1)
fn cs_samples(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = textureDimensions(level_normal);
    if (gid.x >= size.x || gid.y >= size.y) {
        return;
    }
    let nrm = textureLoad(level_normal, gid.xy, 0);
    let is_coherent = nrm.w > 0.0;
    let outside = hp.level.x == 1u || textureLoad(mask_in, gid.xy, 0).r < 0.5;
    if (!(is_coherent && outside)) {
        return;
    }
    let k = hp.level.y;
    let pixel = gid.xy << vec2<u32>(k);
    textureStore(samples_out, pixel, vec4<f32>(f32(k + 1u), 0.0, 0.0, 0.0));
    // The pattern tiles each level's texels: at G-buffer pixels, every sample above level 1
    // (pixels at multiples of 4) would fall on one cell.
    let phase = hp.pattern[gid.y % 4u][gid.x % 4u];
    if (hp.level.z == 1u) {
        textureStore(cache_out, pixel, vec4<f32>(2.0, 0.0, 0.0, 0.0));
        textureStore(group_out, pixel, vec4<f32>(f32(phase + 1u), 0.0, 0.0, 0.0));
    }
    let slot = atomicAdd(&counter[0], 1u);
    if (slot < arrayLength(&list)) {
        let texel = vec4<u32>(gid.xy, k | (phase << 8u), pack_pixel(pixel));
        list[slot] = HcbSample(textureLoad(level_position, gid.xy, 0), nrm, texel, vec4<f32>(0.0), vec4<f32>(0.0));
    }
}
