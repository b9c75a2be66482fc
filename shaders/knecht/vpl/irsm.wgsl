// The multi-bounce baseline of Knecht 002 §3.6 after Ritschel et al. 2008: imperfect
// reflective shadow maps. Each VPL of the source bounce gets an IRSM splatted from its
// N-th of the point cloud (knecht/ism/splat.wgsl cs_splat + cs_owner: every texel knows the nearest
// point that covers it), whose texels store that point's illumination from the VPL; the
// next bounce's N VPLs are then importance-sampled from all IRSMs together (so one source
// VPL may get several new VPLs, or none, unlike §3.6.1).
//
// - cs_cdf (one workgroup per IRSM): texel weight C_t = lum(Φ_s ⊙ (c_s·DI_s + SI_s·SI_v)) of
//   the owning sample s (common/bounce.wgsl), the IRSM's inclusive prefix sum in `cdf`, its
//   total in `totals[i]`, and the texels each sample owns in `coverage[s]`.
// - cs_sample (one workgroup): the running sum of the totals, then new VPL k draws
//   u₁ = (k + ξ)/N over it (stratified) to pick an IRSM and u₂ = ξ' inside its CDF to pick a
//   texel. A sample owning n_s texels is drawn with p_s = n_s C_s / ΣC, so the new VPL's flux
//   is Φ_s / (N p_s) = Φ_s · ΣC / (N n_s C_s): the N VPLs estimate the bounce without bias
//   over the samples the IRSMs show.
//
// CPU twin: cpu::knecht::irsm_pick.
#import common/bounce.wgsl

const WG: u32 = 256u;

@group(0) @binding(0) var<uniform> ip: BounceParams;
@group(0) @binding(1) var<storage, read> points: array<IsmPoint>;
@group(0) @binding(2) var<storage, read> surfaces: array<PointSurface>;
@group(0) @binding(3) var<storage, read> instances: array<Instance>;
@group(0) @binding(4) var<storage, read> owner: array<u32>;
@group(0) @binding(5) var<storage, read_write> cdf: array<f32>;
// totals[i] for IRSM i, then their running sum in totals[N + i]
@group(0) @binding(6) var<storage, read_write> totals: array<f32>;
@group(0) @binding(7) var<storage, read_write> coverage: array<atomic<u32>>;
@group(0) @binding(8) var<storage, read_write> vpls: array<Vpl>;
// `irsm.illumination`: each texel's weight (Fig. 3.6)
@group(0) @binding(9) var illumination: texture_storage_2d<r32float, write>;

var<workgroup> partial: array<f32, WG>;

fn per_vpl(i: u32) -> u32 {
    if (i >= ip.counts.x) {
        return 0u;
    }
    return (ip.counts.x - i + ip.counts.y - 1u) / ip.counts.y;
}

// Atlas texel of texel t (row-major in the tile) of IRSM i.
fn texel_of(i: u32, t: u32) -> vec2<u32> {
    let size = ip.counts.w;
    return vpl_tile_origin(i, ip.counts.z, size) + vec2<u32>(t % size, t / size);
}

// Owner (point index + 1) of texel t of IRSM i.
fn texel_owner(i: u32, t: u32) -> u32 {
    let a = texel_of(i, t);
    return owner[a.y * ip.counts.z * ip.counts.w + a.x];
}

fn sample_light(i: u32, j: u32) -> vec4<f32> {
    let vpl = vpls[ip.slots.x + i];
    let p = bounce_point(points[j], instances[points[j].draw]);
    return bounce_light(vpl, p, surfaces[j], per_vpl(i), ip.geom.z);
}

@compute @workgroup_size(256, 1, 1)
fn cs_cdf(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let i = wid.x;
    let texels = ip.counts.w * ip.counts.w;
    let per_thread = texels / WG;
    let first = lid * per_thread;
    let valid = vpls[ip.slots.x + i].position.w > 0.5;
    var run = 0.0;
    for (var t = first; t < first + per_thread; t = t + 1u) {
        let o = texel_owner(i, t);
        var c = 0.0;
        if (valid && o != 0u) {
            c = sample_light(i, o - 1u).w;
            run = run + c;
            if (c > 0.0) {
                atomicAdd(&coverage[o - 1u], 1u);
            }
        }
        textureStore(illumination, texel_of(i, t), vec4<f32>(c, 0.0, 0.0, 0.0));
        cdf[i * texels + t] = run;
    }
    partial[lid] = run;
    workgroupBarrier();
    if (lid == 0u) {
        var acc = 0.0;
        for (var k = 0u; k < WG; k = k + 1u) {
            let v = partial[k];
            partial[k] = acc;
            acc = acc + v;
        }
        totals[i] = acc;
    }
    workgroupBarrier();
    let offset = partial[lid];
    for (var t = first; t < first + per_thread; t = t + 1u) {
        cdf[i * texels + t] = cdf[i * texels + t] + offset;
    }
}

// First index in [lo, hi) of the non-decreasing `cdf` whose value exceeds u (hi − 1 if none).
fn search_cdf(lo: u32, hi: u32, u: f32) -> u32 {
    var a = lo;
    var b = hi - 1u;
    while (a < b) {
        let m = (a + b) / 2u;
        if (cdf[m] > u) {
            b = m;
        } else {
            a = m + 1u;
        }
    }
    return a;
}

fn search_totals(n: u32, u: f32) -> u32 {
    var a = 0u;
    var b = n - 1u;
    while (a < b) {
        let m = (a + b) / 2u;
        if (totals[n + m] > u) {
            b = m;
        } else {
            a = m + 1u;
        }
    }
    return a;
}

@compute @workgroup_size(256, 1, 1)
fn cs_sample(@builtin(local_invocation_index) lid: u32) {
    let n = ip.counts.y;
    if (lid == 0u) {
        var acc = 0.0;
        for (var i = 0u; i < n; i = i + 1u) {
            acc = acc + totals[i];
            totals[n + i] = acc;
        }
    }
    storageBarrier();
    workgroupBarrier();
    let grand = totals[2u * n - 1u];
    let texels = ip.counts.w * ip.counts.w;
    for (var k = lid; k < n; k = k + WG) {
        let slot = ip.slots.y + k;
        if (!(grand > 0.0)) {
            vpls[slot] = empty_vpl();
            continue;
        }
        let u1 = (f32(k) + bounce_uniform(ip.seed.x, 2u * k)) / f32(n) * grand;
        let i = search_totals(n, u1);
        let u2 = bounce_uniform(ip.seed.x, 2u * k + 1u) * totals[i];
        let t = search_cdf(i * texels, (i + 1u) * texels, u2) - i * texels;
        let o = texel_owner(i, t);
        if (o == 0u) {
            vpls[slot] = empty_vpl();
            continue;
        }
        let j = o - 1u;
        let source = vpls[ip.slots.x + i];
        let p = bounce_point(points[j], instances[points[j].draw]);
        let l = bounce_light(source, p, surfaces[j], per_vpl(i), ip.geom.z);
        let covered = f32(max(atomicLoad(&coverage[j]), 1u));
        if (!(l.w > 0.0)) {
            vpls[slot] = empty_vpl();
            continue;
        }
        vpls[slot] = bounce_vpl(source, p, surfaces[j], l.xyz, grand / (f32(n) * covered * l.w));
    }
}
