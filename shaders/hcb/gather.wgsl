// Gathering at the HCB samples (Nguyen et al. §4.1): each sample of the compact list gets
// the irradiance the VPLs send it — Φ · f_y(ω_in, y→x) · cos θ_y · cos θ_x / max(d², d_min²)
// (Knecht 002 Eq. 4.7–4.8, the VPLs of stage 3) times their visibility (ISM, exact maps or
// none, as the interleaved gather). The cost scales with the samples, not the pixels.
// Irradiance, not radiance, is gathered and splatted: each pixel then reflects it with its
// own colour (c·DI/π), so that texture detail survives the interpolation (the receiver's
// glossy lobe is not included). cs_args turns the sample count into the indirect arguments
// of this dispatch and of the splat draw.
#import common/ism.wgsl
#import hcb/common.wgsl

// Rust twin: passes::hcb::HcbGatherParams.
struct HcbGatherParams {
    // x: VPL count, y: visibility (0 none, 1 ISM, 2 exact), z: atlas columns, w: map size
    counts: vec4<u32>,
    // x: d_min², y: ISM eye offset / exact near, z: ISM bias / exact far,
    // w: ISM receiver normal offset (texels) / exact eye offset
    shade: vec4<f32>,
}

@group(0) @binding(0) var<uniform> params: HcbGatherParams;
@group(0) @binding(1) var<storage, read> vpls: array<Vpl>;
@group(0) @binding(2) var ism_atlas: texture_2d<f32>;
@group(0) @binding(3) var exact_atlas: texture_depth_2d;
@group(0) @binding(4) var<storage, read> counter: array<u32>;
@group(0) @binding(5) var<storage, read_write> list: array<HcbSample>;
// draw-indirect (vertices 6, instances, 0, 0) then dispatch-indirect (x, y, 1)
@group(0) @binding(6) var<storage, read_write> args: array<u32>;

fn sample_count() -> u32 {
    return min(counter[0], arrayLength(&list));
}

@compute @workgroup_size(1, 1, 1)
fn cs_args() {
    let n = sample_count();
    let groups = (n + 63u) / 64u;
    args[0] = 6u;
    args[1] = n;
    args[2] = 0u;
    args[3] = 0u;
    args[4] = min(groups, 65535u);
    args[5] = max((groups + 65534u) / 65535u, 1u);
    args[6] = 1u;
}

@compute @workgroup_size(64, 1, 1)
fn cs_gather(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x + gid.y * 65535u * 64u;
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
        let w = vpl.position.xyz - x;
        let d2 = dot(w, w);
        let l = w * inverseSqrt(max(d2, 1e-12));
        let cos_x = dot(nx, l);
        let cos_y = -dot(vpl.normal.xyz, l);
        if (cos_x <= 0.0 || cos_y <= 0.0) {
            continue;
        }
        var vis = 1.0;
        if (params.counts.y == 1u) {
            vis = ism_visibility(ism_atlas, k, vpl, x, nx, params.shade.y, params.counts.z, params.counts.w, params.shade.z, params.shade.w);
        } else if (params.counts.y == 2u) {
            vis = vpl_exact_visibility(exact_atlas, k, vpl, x, nx, params.shade.yzw, params.counts.z, params.counts.w, 1.0, 1.0);
        }
        if (vis <= 0.0) {
            continue;
        }
        let f_y = brdf_eval(vpl.normal.xyz, vpl.incident.xyz, -l, vpl.albedo.rgb, vpl.normal.w, vpl.flux.a, vpl.incident.w);
        e = e + vis * vpl.flux.rgb * f_y * cos_y * cos_x / max(d2, params.shade.x);
    }
    list[i].light = vec4<f32>(e, 1.0);
}
