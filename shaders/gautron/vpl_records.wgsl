// GI Lab's mix of Gautron et al. 003 and Knecht 002 (issue #17 "Mixes"): irradiance records
// lit by the VPL gather (instant radiosity at the records) instead of a rasterized
// hemisphere. One thread per slot of the round (a new record, or a stale one computed
// again; the slot's record and frame from cs_cameras):
// - E_k = Σ_i V_i · Φ_i f_i cos θ_i cos θ_x / max(d_i², d_min²) over the VPLs of stage 3
//   with stage 4's visibility V_i (ISM, exact maps or none), as the HCB's gather at its
//   samples (hcb/gather.wgsl; Knecht 002 Eq. 4.7–4.8);
// - ⚠ H (Ward's harmonic mean distance to the surfaces seen, "Irradiance Caching") from the
//   VPLs: H = Σ_i ℓ_i / Σ_i (ℓ_i / d_i), the harmonic mean of the visible VPLs' distances
//   weighted by the luminance ℓ_i each sends (a hemisphere's texels weigh every direction by
//   its solid angle; the VPLs stand for the lit surfaces only). R_k then takes the clamps.
// - the gradients ∇_r, ∇_t ("Irradiance Interpolation"; Křivánek's forms integrate over
//   the hemisphere's texels, which do not exist here) by central differences of the same
//   sum with each VPL's visibility held at P_k: the normal turned by ±ε about t and b, the
//   position moved by ±ε along t and b; ∇ = t·D_t + b·D_b in the tangent plane, as the
//   reduction's.
// The record sees every draw (`seen` all ones): any moved object invalidates it. CPU twin of
// the sums: cpu::gautron::vpl_record.
#import gautron/common.wgsl
#import common/ism.wgsl

// Rust twin: passes::gautron::vpl_records::VplRecordParams.
struct VplRecordParams {
    // x: VPL count, y: visibility (0 none, 1 ISM, 2 exact), z: atlas columns, w: map size
    counts: vec4<u32>,
    // x: d_min², y–w: the visibility's parameters (interleave::GatherParams::shade's yzw)
    shade: vec4<f32>,
    // x: the near field's cut² (0: none), y: ε of the translational differences (scene
    // units), z: ε of the rotational ones (radians)
    misc: vec4<f32>,
}

@group(0) @binding(0) var<uniform> params: GautronParams;
@group(0) @binding(1) var<uniform> vparams: VplRecordParams;
@group(0) @binding(2) var<storage, read> state: CacheState;
@group(0) @binding(3) var<storage, read> cameras: array<HemisphereCamera>;
@group(0) @binding(4) var<storage, read_write> records: array<Record>;
@group(0) @binding(5) var<storage, read> vpls: array<Vpl>;
@group(0) @binding(6) var ism_atlas: texture_2d<f32>;
@group(0) @binding(7) var exact_atlas: texture_depth_2d;

fn irradiance(vpl: Vpl, x: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    return vpl_irradiance(vpl, x, n, vparams.shade.x, vparams.misc.x);
}

@compute @workgroup_size(64, 1, 1)
fn cs_vpl_records(@builtin(global_invocation_id) gid: vec3<u32>) {
    let s = gid.x;
    if (s >= state.new_count + state.refresh) {
        return;
    }
    let cam = cameras[s];
    let index = u32(cam.n.w);
    var rec = records[index];
    let x = cam.position.xyz;
    let n = cam.n.xyz;
    let t = cam.t.xyz;
    let b = cam.b.xyz;
    let et = vparams.misc.y;
    let er = vparams.misc.z;
    // the normal turned by ±ε about t (toward ∓b) and about b (toward ±t)
    let nt = normalize(n - er * b);
    let nt_ = normalize(n + er * b);
    let nb = normalize(n + er * t);
    let nb_ = normalize(n - er * t);
    var e = vec3<f32>(0.0);
    var dt = array<vec3<f32>, 4>(vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0));
    var dr = array<vec3<f32>, 4>(vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0));
    var h_num = 0.0;
    var h_den = 0.0;
    for (var k = 0u; k < vparams.counts.x; k = k + 1u) {
        let vpl = vpls[k];
        if (vpl.position.w < 0.5) {
            continue;
        }
        let v = gather_visibility(vparams.counts.y, ism_atlas, exact_atlas, k, vpl, x, n, vparams.counts.z, vparams.counts.w, vparams.shade.yzw);
        if (v <= 0.0) {
            continue;
        }
        let ek = irradiance(vpl, x, n) * v;
        e = e + ek;
        let l = dot(ek, vec3<f32>(0.2126, 0.7152, 0.0722));
        if (l > 0.0) {
            h_num = h_num + l;
            h_den = h_den + l / max(distance(vpl.position.xyz, x), 1e-6);
        }
        dt[0] = dt[0] + irradiance(vpl, x + et * t, n) * v;
        dt[1] = dt[1] + irradiance(vpl, x - et * t, n) * v;
        dt[2] = dt[2] + irradiance(vpl, x + et * b, n) * v;
        dt[3] = dt[3] + irradiance(vpl, x - et * b, n) * v;
        dr[0] = dr[0] + irradiance(vpl, x, nt) * v;
        dr[1] = dr[1] + irradiance(vpl, x, nt_) * v;
        dr[2] = dr[2] + irradiance(vpl, x, nb) * v;
        dr[3] = dr[3] + irradiance(vpl, x, nb_) * v;
    }
    rec.irradiance = vec4<f32>(e, rec.irradiance.w);
    let gt = (dt[0] - dt[1]) / (2.0 * et);
    let gb = (dt[2] - dt[3]) / (2.0 * et);
    let rt = (dr[0] - dr[1]) / (2.0 * er);
    let rb = (dr[2] - dr[3]) / (2.0 * er);
    for (var c = 0u; c < 3u; c = c + 1u) {
        rec.trans[c] = vec4<f32>(t * gt[c] + b * gb[c], 0.0);
        rec.rot[c] = vec4<f32>(t * rt[c] + b * rb[c], 0.0);
    }
    // no VPL seen: H is unbounded (R_k takes the upper clamps), as the reduction's
    var h = 1e30;
    if (h_den > 0.0) {
        h = h_num / h_den;
    }
    rec.position.w = clamped_radius(params, h, rec);
    rec.normal.w = h;
    rec.pixel.w = RECORD_VALID;
    rec.seen = vec4<u32>(0xffffffffu);
    records[index] = rec;
}
