// GI Lab's mix of Nguyen et al. and Soler et al. (issue #16 "Mixes"): Soler's screen-space
// gather evaluated at the HCB's samples (000 §3) instead of at every texel of every level,
// then splatted by coherence (000 §4.2–4.3, hcb/splat.wgsl). A sample at G-buffer pixel p
// (position x, normal n_x) gathers, on each of Soler's gathered levels k, the ring of the
// level's texel q = p >> k (the same rotated spiral, full disc on the first level, r/2 … r
// after) with x as the receiver: Eq. 1–4 and the voxel visibility as soler/gather.wgsl, the
// levels summed (one dispatch per level adds its share; the first writes). What the
// per-pixel path gets by upsampling, each sample gets exactly at its point. Irradiance only
// (the splat reflects it with each pixel's c·DI/π, as the HCB's VPL gather). CPU twin:
// cpu::soler::gather_at.
#import soler/common.wgsl
#import soler/voxel_common.wgsl
#import common/random.wgsl
#import hcb/common.wgsl
#import soler/ring.wgsl

@group(0) @binding(0) var<uniform> params: GatherParams;
@group(0) @binding(1) var level_position: texture_2d<f32>;
@group(0) @binding(2) var level_normal: texture_2d<f32>;
@group(0) @binding(3) var level_radiance: texture_2d<f32>;
@group(0) @binding(4) var<storage, read> grid: array<u32>;
@group(0) @binding(5) var<storage, read> counter: array<u32>;
@group(0) @binding(6) var<storage, read_write> list: array<HcbSample>;

@group(1) @binding(0) var<storage, read_write> args: array<u32>;

fn sample_count() -> u32 {
    return min(counter[0], arrayLength(&list));
}

// The indirect arguments of this gather and of the splat (every sample is gathered).
@compute @workgroup_size(1, 1, 1)
fn cs_args() {
    let n = sample_count();
    let words = hcb_args(n, n, 0u);
    for (var i = 0u; i < 12u; i = i + 1u) {
        args[i] = words[i];
    }
}

@compute @workgroup_size(64, 1, 1)
fn cs_gather(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x + gid.y * 65535u * 64u;
    if (i >= sample_count()) {
        return;
    }
    let s = list[i];
    let x = s.position.xyz;
    let n = normalize(s.normal.xyz);
    let size = textureDimensions(level_position);
    let pixel = vec2<u32>(s.texel.w & 0xffffu, s.texel.w >> 16u);
    let k = params.counts.z;
    let q = min(pixel >> vec2<u32>(k, k), size - vec2<u32>(1u, 1u));
    let zx = dot(x - params.eye.xyz, params.forward.xyz);
    var e = vec3<f32>(0.0);
    if (params.counts.y == 0u) {
        e = list[i].light.rgb;
    }
    let inner = ring_inner();
    let dp = ring_area(inner);
    let rot = rotation(q);
    for (var j = 0u; j < params.counts.x; j = j + 1u) {
        let o = ring_offset(j, inner, rot + f32(j) * GOLDEN_ANGLE);
        if (o.x == 0 && o.y == 0) {
            continue;
        }
        let t = vec2<i32>(q) + o;
        let st = sender(t, x, n);
        if (!st.lit) {
            continue;
        }
        if (params.voxels.grid.x > 0u && !visible(vec2<i32>(q), zx, t, st.position.w)) {
            continue;
        }
        let ds = surface_area(st.position, st.normal, dp);
        e = e + textureLoad(level_radiance, t, 0).rgb * kernel(st.cos_t, st.cos_tp, ds, st.r2);
    }
    list[i].light = vec4<f32>(e, 1.0);
}
