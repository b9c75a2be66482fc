// GI Lab's mix of Gautron et al. 003 and Knecht 002 (issue #17 "Mixes"): irradiance records
// lit by the VPL gather (instant radiosity at the records) instead of a rasterized
// hemisphere. One thread per slot of the round (a new record, or a stale one computed
// again; the slot's record and frame from cs_cameras):
// - E_k = Σ_i V_i · Φ_i f_i cos θ_i cos θ_x / max(d_i², d_min²) over the VPLs of stage 3
//   with stage 4's visibility V_i (ISM, exact maps or none), as the HCB's gather at its
//   samples (hcb/gather.wgsl; Knecht 002 Eq. 4.7–4.8);
// - ⚠[gautron.vpl-record-h] H (Ward's harmonic mean distance to the surfaces seen, "Irradiance
//   Caching") from the VPLs: H = Σ_i ℓ_i / Σ_i (ℓ_i / d_i), the harmonic mean of the visible
//   VPLs' distances weighted by the luminance ℓ_i each sends (a hemisphere's texels weigh every
//   direction by its solid angle; the VPLs stand for the lit surfaces only). R_k then takes the
//   clamps.
// - the gradients ∇_r, ∇_t ("Irradiance Interpolation"; Křivánek's forms integrate over
//   the hemisphere's texels, which do not exist here) by central differences of the same
//   sum with each VPL's visibility held at P_k: the normal turned by ±ε about t and b, the
//   position moved by ±ε along t and b; ∇ = t·D_t + b·D_b in the tangent plane, as the
//   reduction's.
// The record sees every draw (`seen` all ones): any moved object invalidates it. CPU twin of
// the sums: cpu::gautron::vpl_record.
// On a GPU, cs_vpl_records: one workgroup per slot, its 64 invocations over every 64th VPL,
// the sums added in shared memory (issue #38: one invocation per slot looping over all VPLs
// took as long as one whole loop, however few the slots). On a CPU renderer, whose barriers
// are dear, cs_vpl_records_serial: one invocation per slot.
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
@group(0) @binding(7) var exact_atlas: texture_2d<f32>;

fn irradiance(vpl: Vpl, x: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    return vpl_irradiance(vpl, x, n, vparams.shade.x, vparams.misc.x);
}

// The sums over a record's VPLs: E, the four translated and four rotated sums of the
// gradients' differences, and H's numerator and denominator.
struct VplSums {
    e: vec3<f32>,
    dt: array<vec3<f32>, 4>,
    dr: array<vec3<f32>, 4>,
    h: vec2<f32>,
    // Σ lum(E_k) ω_k, the glossy receiver's direction sum (the record's `dir`)
    dir: vec3<f32>,
}

fn no_sums() -> VplSums {
    let z = vec3<f32>(0.0);
    return VplSums(z, array<vec3<f32>, 4>(z, z, z, z), array<vec3<f32>, 4>(z, z, z, z), vec2<f32>(0.0), z);
}

fn add_sums(a: VplSums, b: VplSums) -> VplSums {
    var s = a;
    s.e = a.e + b.e;
    for (var i = 0u; i < 4u; i = i + 1u) {
        s.dt[i] = a.dt[i] + b.dt[i];
        s.dr[i] = a.dr[i] + b.dr[i];
    }
    s.h = a.h + b.h;
    s.dir = a.dir + b.dir;
    return s;
}

// Slot s's sums over VPLs first, first + step, ….
fn slot_sums(cam: HemisphereCamera, first: u32, step: u32) -> VplSums {
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
    var s = no_sums();
    for (var k = first; k < vparams.counts.x; k = k + step) {
        let vpl = vpls[k];
        if (vpl.position.w < 0.5) {
            continue;
        }
        let v = gather_visibility(vparams.counts.y, ism_atlas, exact_atlas, k, vpl, x, n, vparams.counts.z, vparams.counts.w, vparams.shade.yzw);
        if (v <= 0.0) {
            continue;
        }
        let ek = irradiance(vpl, x, n) * v;
        s.e = s.e + ek;
        let l = dot(ek, vec3<f32>(0.2126, 0.7152, 0.0722));
        if (l > 0.0) {
            s.h = s.h + vec2<f32>(l, l / max(distance(vpl.position.xyz, x), 1e-6));
            s.dir = s.dir + l * normalize(vpl.position.xyz - x);
        }
        s.dt[0] = s.dt[0] + irradiance(vpl, x + et * t, n) * v;
        s.dt[1] = s.dt[1] + irradiance(vpl, x - et * t, n) * v;
        s.dt[2] = s.dt[2] + irradiance(vpl, x + et * b, n) * v;
        s.dt[3] = s.dt[3] + irradiance(vpl, x - et * b, n) * v;
        s.dr[0] = s.dr[0] + irradiance(vpl, x, nt) * v;
        s.dr[1] = s.dr[1] + irradiance(vpl, x, nt_) * v;
        s.dr[2] = s.dr[2] + irradiance(vpl, x, nb) * v;
        s.dr[3] = s.dr[3] + irradiance(vpl, x, nb_) * v;
    }
    return s;
}

// The record of slot `cam` from its sums: E, the gradients, H and R_k.
fn store_record(cam: HemisphereCamera, s: VplSums) {
    let index = u32(cam.n.w);
    var rec = records[index];
    let t = cam.t.xyz;
    let b = cam.b.xyz;
    let et = vparams.misc.y;
    let er = vparams.misc.z;
    rec.irradiance = vec4<f32>(s.e, rec.irradiance.w);
    rec.dir = vec4<f32>(s.dir, 0.0);
    let gt = (s.dt[0] - s.dt[1]) / (2.0 * et);
    let gb = (s.dt[2] - s.dt[3]) / (2.0 * et);
    let rt = (s.dr[0] - s.dr[1]) / (2.0 * er);
    let rb = (s.dr[2] - s.dr[3]) / (2.0 * er);
    for (var c = 0u; c < 3u; c = c + 1u) {
        rec.trans[c] = vec4<f32>(t * gt[c] + b * gb[c], 0.0);
        rec.rot[c] = vec4<f32>(t * rt[c] + b * rb[c], 0.0);
    }
    // no VPL seen: H is unbounded (R_k takes the upper clamps), as the reduction's
    var h = 1e30;
    if (s.h.y > 0.0) {
        h = s.h.x / s.h.y;
    }
    rec.position.w = clamped_radius(params, h, rec);
    rec.normal.w = h;
    rec.pixel.w = RECORD_VALID;
    rec.seen = vec4<u32>(0xffffffffu);
    records[index] = rec;
}

var<workgroup> partial: array<VplSums, 64>;

// GPU: one workgroup per slot.
@compute @workgroup_size(64, 1, 1)
fn cs_vpl_records(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    // Uniform per workgroup: every invocation returns or none does (the barriers below).
    if (wg.x >= state.new_count + state.refresh) {
        return;
    }
    let cam = cameras[wg.x];
    partial[li] = slot_sums(cam, li, 64u);
    for (var stride = 32u; stride > 0u; stride = stride >> 1u) {
        workgroupBarrier();
        if (li < stride) {
            partial[li] = add_sums(partial[li], partial[li + stride]);
        }
    }
    if (li == 0u) {
        store_record(cam, partial[0]);
    }
}

// CPU renderer: one invocation per slot.
@compute @workgroup_size(64, 1, 1)
fn cs_vpl_records_serial(@builtin(global_invocation_id) gid: vec3<u32>) {
    if (gid.x >= state.new_count + state.refresh) {
        return;
    }
    let cam = cameras[gid.x];
    store_record(cam, slot_sums(cam, 0u, 1u));
}
