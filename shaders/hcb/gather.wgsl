// Gathering at the HCB samples (Nguyen et al. §4.1): each sample of the compact list gets
// the irradiance the VPLs send it — Φ · f_y(ω_in, y→x) · cos θ_y · cos θ_x / max(d², d_min²)
// (Knecht 002 Eq. 4.7–4.8, the VPLs of stage 3) times their visibility (ISM, exact maps or
// none, as the interleaved gather). The cost scales with the samples, not the pixels.
// Irradiance, not radiance, is gathered and splatted: each pixel then reflects it with its
// own colour (c·DI/π), so that texture detail survives the interpolation (the receiver's
// glossy lobe is not included). cs_args turns the sample count into the indirect arguments
// of this dispatch and of the splat draws. With the cache the gather runs twice: over the
// samples due for recomputation (§5.3, their slots compacted in `queue`, so that the work is
// dense) and over the new ones (§5.2, the end of the list).
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
@group(0) @binding(3) var exact_atlas: texture_depth_2d;
@group(0) @binding(4) var<storage, read> counter: array<u32>;
@group(0) @binding(5) var<storage, read_write> list: array<HcbSample>;
// draw-indirect (vertices 6, instances, 0, 0), dispatch-indirect (x, y, 1), a spare word,
// draw-indirect of the samples after the cached ones (counter word 1, §5.2)
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
}

@compute @workgroup_size(64, 1, 1)
fn cs_gather(@builtin(global_invocation_id) gid: vec3<u32>) {
    let j = gid.x + gid.y * 65535u * 64u;
    if (j >= gather_count()) {
        return;
    }
    let i = gather_slot(j);
    if (i >= sample_count()) {
        return;
    }
    let s = list[i];
    let x = s.position.xyz;
    let nx = normalize(s.normal.xyz);
    var e = vec3<f32>(0.0);
    for (var k = 0u; k < params.counts.x; k = k + 1u) {
        let vpl = vpls[k];
        if (vpl.position.w < 0.5) {
            continue;
        }
        let irradiance = vpl_irradiance(vpl, x, nx, params.shade.x, params.near.x);
        if (max(irradiance.r, max(irradiance.g, irradiance.b)) <= 0.0) {
            continue;
        }
        e = e + irradiance * gather_visibility(params.counts.y, ism_atlas, exact_atlas, k, vpl, x, nx, params.counts.z, params.counts.w, params.shade.yzw);
    }
    list[i].light = vec4<f32>(e, 1.0);
}
