// Gathering at the HCB samples (Nguyen et al. §4.1): each sample of the compact list gets
// the irradiance the VPLs send it — Φ · f_y(ω_in, y→x) · cos θ_y · cos θ_x / max(d², d_min²)
// (Knecht 002 Eq. 4.7–4.8, the VPLs of stage 3) times their visibility (ISM, exact maps or
// none, as the interleaved gather). The cost scales with the samples, not the pixels.
// ⚠[nguyen.irradiance-samples] Irradiance, not radiance, is gathered and splatted (§4.1 says
// only that "the result of indirect lighting is stored at each sample"): each pixel then
// reflects it with its own colour (c·DI/π), so that texture detail survives the interpolation
// (the receiver's glossy lobe is lit from the mean direction kept beside it, `dir`:
// ⚠[nguyen.glossy-receiver], common/receiver.wgsl). cs_args turns the sample count into the
// indirect arguments of this dispatch and of the splat draws. With the cache the gather runs
// twice: over the samples due for recomputation (§5.3, their slots compacted in `queue`, so
// that the work is dense) and over the new ones (§5.2, the end of the list).
// On a GPU, cs_gather: one workgroup per sample, its 64 invocations over every 64th VPL,
// summed in shared memory (issue #38: with one invocation per sample looping over all VPLs,
// a gather of few samples, the cache's usual case, took as long as one 1,024-VPL loop). On a
// CPU renderer, whose barriers are dear, cs_gather_serial: one invocation per sample.
#import common/ism.wgsl
#import hcb/common.wgsl

// Rust twin: passes::hcb::HcbGatherParams.
struct HcbGatherParams {
    // x: VPL count, y: visibility (0 none, 1 ISM, 2 exact), z: atlas columns, w: map size
    counts: vec4<u32>,
    // x: which samples (0 every sample of the list; 1 the cached samples due for
    // recomputation, listed in `queue`, §5.3; 2 the new samples after the cached ones, §5.2)
    mode: vec4<u32>,
    // x: d_min², y: ISM eye offset / exact near, z: ISM bias / exact far,
    // w: ISM receiver normal offset (texels) / exact eye offset
    shade: vec4<f32>,
    // x: the near field's cut² (senders closer are left to it; 0: none)
    near: vec4<f32>,
}

@group(0) @binding(0) var<uniform> params: HcbGatherParams;
@group(0) @binding(1) var<storage, read> vpls: array<Vpl>;
@group(0) @binding(2) var ism_atlas: texture_2d<f32>;
@group(0) @binding(3) var exact_atlas: texture_2d<f32>;
@group(0) @binding(4) var<storage, read> counter: array<u32>;
@group(0) @binding(5) var<storage, read_write> list: array<HcbSample>;
// draw-indirect (vertices 6, instances, 0, 0), dispatch-indirect (x, y, 1) of 64-wide
// workgroups over the samples, a spare word, draw-indirect of the samples after the cached
// ones (counter word 1, §5.2), dispatch-indirect (x, y, 1) of one workgroup per gathered
// sample, a spare word
@group(0) @binding(6) var<storage, read_write> args: array<u32>;
// the list slots of the samples to recompute (counter word 2 of them; mode 1)
@group(0) @binding(7) var<storage, read> queue: array<u32>;

fn sample_count() -> u32 {
    return min(counter[0], arrayLength(&list));
}

// How many samples this dispatch gathers, and where the n-th of them is in the list.
fn gather_count() -> u32 {
    let n = sample_count();
    switch (params.mode.x) {
        case 1u: {
            return min(counter[2], n);
        }
        case 2u: {
            return n - min(counter[1], n);
        }
        default: {
            return n;
        }
    }
}

fn gather_slot(i: u32) -> u32 {
    switch (params.mode.x) {
        case 1u: {
            return queue[i];
        }
        case 2u: {
            return counter[1] + i;
        }
        default: {
            return i;
        }
    }
}

@compute @workgroup_size(1, 1, 1)
fn cs_args() {
    let words = hcb_args(sample_count(), gather_count(), counter[1]);
    for (var i = 0u; i < 12u; i = i + 1u) {
        args[i] = words[i];
    }
    // One workgroup per sample, x within the 65535 limit.
    let n = gather_count();
    args[12] = min(n, 65535u);
    args[13] = max((n + 65534u) / 65535u, 1u);
    args[14] = 1u;
    args[15] = 0u;
}

// Each invocation's share of the sample's irradiance and of its direction sum.
var<workgroup> partial: array<vec3<f32>, 64>;
var<workgroup> partial_dir: array<vec3<f32>, 64>;

// The sample's irradiance from VPLs first, first + step, … (Knecht 002 Eq. 4.7–4.8 times the
// visibility), and Σ lum(E_k) ω_k, the direction sum of the glossy receiver.
struct Gathered {
    e: vec3<f32>,
    dir: vec3<f32>,
}

fn gather_vpls(x: vec3<f32>, nx: vec3<f32>, first: u32, step: u32) -> Gathered {
    var e = vec3<f32>(0.0);
    var dir = vec3<f32>(0.0);
    for (var k = first; k < params.counts.x; k = k + step) {
        let vpl = vpls[k];
        if (vpl.position.w < 0.5) {
            continue;
        }
        let irradiance = vpl_irradiance(vpl, x, nx, params.shade.x, params.near.x);
        if (max(irradiance.r, max(irradiance.g, irradiance.b)) <= 0.0) {
            continue;
        }
        let seen = irradiance * gather_visibility(params.counts.y, ism_atlas, exact_atlas, k, vpl, x, nx, params.counts.z, params.counts.w, params.shade.yzw);
        e = e + seen;
        dir = dir + dot(seen, vec3<f32>(0.2126, 0.7152, 0.0722)) * normalize(vpl.position.xyz - x);
    }
    return Gathered(e, dir);
}

const NO_SAMPLE: u32 = 0xffffffffu;

// The list slot of the j-th sample this dispatch gathers, or NO_SAMPLE past them.
fn gathered(j: u32) -> u32 {
    if (j >= gather_count()) {
        return NO_SAMPLE;
    }
    let i = gather_slot(j);
    if (i >= sample_count()) {
        return NO_SAMPLE;
    }
    return i;
}

// GPU: one workgroup per sample (dispatch words 12–14).
@compute @workgroup_size(64, 1, 1)
fn cs_gather(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    // Uniform per workgroup: every invocation returns or none does (the barriers below).
    let i = gathered(wg.x + wg.y * 65535u);
    if (i == NO_SAMPLE) {
        return;
    }
    let s = list[i];
    let g = gather_vpls(s.position.xyz, normalize(s.normal.xyz), li, 64u);
    partial[li] = g.e;
    partial_dir[li] = g.dir;
    for (var stride = 32u; stride > 0u; stride = stride >> 1u) {
        workgroupBarrier();
        if (li < stride) {
            partial[li] = partial[li] + partial[li + stride];
            partial_dir[li] = partial_dir[li] + partial_dir[li + stride];
        }
    }
    if (li == 0u) {
        list[i].light = vec4<f32>(partial[0], 1.0);
        list[i].dir = vec4<f32>(partial_dir[0], 0.0);
    }
}

// CPU renderer: one invocation per sample (dispatch words 4–6).
@compute @workgroup_size(64, 1, 1)
fn cs_gather_serial(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gathered(gid.x + gid.y * 65535u * 64u);
    if (i == NO_SAMPLE) {
        return;
    }
    let s = list[i];
    let g = gather_vpls(s.position.xyz, normalize(s.normal.xyz), 0u, 1u);
    list[i].light = vec4<f32>(g.e, 1.0);
    list[i].dir = vec4<f32>(g.dir, 0.0);
}
