// "Updating cache" of Nguyen et al. §5.1 (Fig. 5): the samples of the previous frame (the
// sample cache, double-buffered with this frame's sample list) are taken into the current
// view. cs_validate projects each one and compares its position and normal with the
// G-buffer's there: farther than the distance threshold or turned by more than the normal
// threshold, it is invalid; outside the view it is dropped. cache_removal.wgsl then
// draw every invalid sample as a quad of `surplus_quad_px` at a smaller depth and every
// valid one as a point at a larger depth into `hcb.cache` (the paper's depth-test trick: the
// removal quads win wherever they overlap a valid sample, whatever the order). cs_compact
// keeps the valid samples whose point survived, appends them to the current list at their
// new pixel and advances their recompute counter (§5.3): when it reaches the period the
// light is marked for gathering this frame and the counter restarts; so is the light of a
// sample not gathered yet. CPU twins: cpu::hcb::{validate, advance_counter}.
#import common/camera.wgsl
#import hcb/common.wgsl

@group(0) @binding(0) var<uniform> camera: Camera;
@group(0) @binding(1) var<uniform> cp: CacheParams;
@group(0) @binding(2) var<storage, read_write> prev_counter: array<u32>;
@group(0) @binding(3) var<storage, read_write> prev: array<HcbSample>;
@group(0) @binding(4) var g_position: texture_2d<f32>;
@group(0) @binding(5) var g_normal: texture_2d<f32>;
// this frame's counter: total, cached, recomputed, invalid, surplus, dropped
@group(0) @binding(6) var<storage, read_write> counter: array<atomic<u32>>;
@group(0) @binding(7) var<storage, read_write> list: array<HcbSample>;
@group(0) @binding(8) var removal: texture_2d<f32>;
@group(0) @binding(9) var samples_out: texture_storage_2d<r32float, write>;
@group(0) @binding(10) var group_out: texture_storage_2d<r32float, write>;
// the list slots of the samples to recompute this frame (for the gather, dense)
@group(0) @binding(11) var<storage, read_write> queue: array<u32>;
// draw-indirect of the removal (6, cached samples, 0, 0), dispatch-indirect (x, y, 1)
@group(1) @binding(0) var<storage, read_write> args: array<u32>;

fn cached_count() -> u32 {
    return min(prev_counter[0], arrayLength(&prev));
}

fn index(gid: vec3<u32>) -> u32 {
    return gid.x + gid.y * 65535u * 64u;
}

@compute @workgroup_size(1, 1, 1)
fn cs_args() {
    let n = cached_count();
    var words = indirect_words(n, n);
    for (var i = 0u; i < 8u; i = i + 1u) {
        args[i] = words[i];
    }
}

@compute @workgroup_size(64, 1, 1)
fn cs_validate(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = index(gid);
    if (i >= cached_count()) {
        return;
    }
    var s = prev[i];
    var st = DROPPED;
    let clip = camera.view_proj * vec4<f32>(s.position.xyz, 1.0);
    let size = vec2<f32>(textureDimensions(g_normal));
    if (clip.w > 0.0) {
        let p = clip_to_pixel(clip, camera.viewport);
        if (all(p >= vec2<f32>(0.0)) && all(p < size)) {
            let px = vec2<u32>(p);
            let gn = textureLoad(g_normal, px, 0);
            let gp = textureLoad(g_position, px, 0);
            st = INVALID;
            if (gn.w >= 0.5 && length(gp.xyz - s.position.xyz) <= cp.limits.x
                && dot(normalize(gn.xyz), normalize(s.normal.xyz)) >= cp.limits.y) {
                st = VALID;
            }
            s.texel.w = pack_pixel(px);
        }
    }
    if (st == DROPPED) {
        atomicAdd(&counter[5], 1u);
    } else if (st == INVALID) {
        atomicAdd(&counter[3], 1u);
    }
    prev[i].texel = vec4<u32>(s.texel.xy, (s.texel.z & 0xffffu) | (st << 16u), s.texel.w);
}

@compute @workgroup_size(64, 1, 1)
fn cs_compact(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = index(gid);
    if (i >= cached_count()) {
        return;
    }
    let s = prev[i];
    if (status(s) != VALID) {
        return;
    }
    let px = unpack_pixel(s.texel.w);
    if (textureLoad(removal, px, 0).r != 1.0) {
        // Inside the quad of an invalid sample: a surplus sample.
        atomicAdd(&counter[4], 1u);
        return;
    }
    let period = u32(cp.limits.w);
    var c = ((s.texel.z >> 8u) & 0xffu) + 1u;
    let level = s.texel.z & 0xffu;
    let slot = atomicAdd(&counter[0], 1u);
    atomicAdd(&counter[1], 1u);
    var light = s.light;
    // Due (§5.3), or never lit: a sample whose gather a frame could not fit (the hemisphere
    // mix bounds its chunks by a late count, issue #53) is gathered as soon as it can be,
    // its counter's phase kept.
    if (c >= period) {
        c = 0u;
    }
    if (c == 0u || light.a < 0.5) {
        light.a = 0.0;
        let r = atomicAdd(&counter[2], 1u);
        if (r < arrayLength(&queue)) {
            queue[r] = slot;
        }
    }
    if (slot < arrayLength(&list)) {
        list[slot] = HcbSample(s.position, s.normal, vec4<u32>(px >> vec2<u32>(level), level | (c << 8u), s.texel.w), light, s.dir);
    }
    textureStore(samples_out, px, vec4<f32>(f32(level + 1u), 0.0, 0.0, 0.0));
    textureStore(group_out, px, vec4<f32>(f32(c + 1u), 0.0, 0.0, 0.0));
}
