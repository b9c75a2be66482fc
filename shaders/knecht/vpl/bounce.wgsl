// Stage 3, further light bounces (Knecht 002 §3.6.1): every point of the point cloud is
// assigned to one VPL of the current bounce (point j → VPL j mod N, the same assignment as
// its ISM splat), lit by it with the glossy bounce of Eq. 4.8 and the geometry term of
// Eq. 4.7, and tested against that VPL's ISM; per VPL one sample becomes the VPL of the
// next bounce. One workgroup per source VPL. The shadow test (`ism.bounce_test`) reads the
// pulled maps with the gather's depth bias and receiver normal offset (common/ism.wgsl:
// ism_visibility), or the raw splats with the depth bias alone.
//
// - Incident flux on sample s: Φ_s = Φ_v · f_v(ω_in, v→s) · cos θ_v · cos θ_s / max(d², d_min²)
//   · V · A_s, with A_s = W / (w_s · P_v) the surface area the sample stands for among the P_v
//   samples of this VPL (W: the cloud's total area × object weight, w_s: its object's weight).
// - Contribution (the light the sample would send on): C_s = lum(Φ_s ⊙ (c_s·DI_s + SI_s)).
// - Selection: the thesis keeps the largest C_s by a depth test (strongest); its §6.1 asks
//   for a choice ∝ C_s (proportional), done here as an exponential race: the largest
//   C_s / (−ln u_s) wins with probability C_s / ΣC. Both are reductions of a key per sample:
//   a workgroup atomicMax on the key's f32 bits (positive floats order like their bits), then
//   atomicMin on the sample index among the maxima (exact arg-max, ties to the lowest index).
// - The new VPL: position and normal of the sample, Φ = Φ_s · ΣC / C_s (so that its
//   contribution is the sum over the samples it stands for; unbiased for the proportional
//   choice), SI = SI_s (not §3.6.1's SI_s · SI_v: Φ_s already holds the source's BRDF; see
//   common/bounce.wgsl), ω_in toward the source VPL.
//
// CPU twin: cpu::knecht::{bounce_incident, select_bounce}.
#import common/bounce.wgsl

const WG: u32 = 64u;

@group(0) @binding(0) var<uniform> bp: BounceParams;
@group(0) @binding(1) var<storage, read> points: array<IsmPoint>;
@group(0) @binding(2) var<storage, read> surfaces: array<PointSurface>;
@group(0) @binding(3) var<storage, read> instances: array<Instance>;
@group(0) @binding(4) var<storage, read> depth: array<u32>;
@group(0) @binding(5) var<storage, read_write> vpls: array<Vpl>;
@group(0) @binding(6) var pulled: texture_2d<f32>;

var<workgroup> sums: array<f32, WG>;
var<workgroup> best_bits: atomic<u32>;
var<workgroup> best_index: atomic<u32>;

// The splatted ISM of VPL slot `v` at the direction of x: whether x is visible.
fn splat_visible(v: u32, vpl: Vpl, x: vec3<f32>) -> bool {
    let eye = ism_eye(vpl, bp.geom.x);
    let w = x - eye;
    let d = length(w);
    let tbn = vpl_basis(vpl.normal.xyz);
    let q = vec3<f32>(dot(w, tbn[0]), dot(w, tbn[1]), dot(w, tbn[2])) / max(d, 1e-9);
    if (q.z < 0.0) {
        return false;
    }
    let size = bp.counts.w;
    let t = min(vec2<u32>(paraboloid_project(q) * f32(size)), vec2<u32>(size - 1u));
    let a = vpl_tile_origin(v, bp.counts.z, size) + t;
    let bits = depth[a.y * bp.counts.z * size + a.x];
    var stored = ISM_EMPTY;
    if (bits != 0u) {
        stored = bitcast<f32>(~bits);
    }
    return d * (1.0 - bp.geom.y) <= stored;
}

struct Sample {
    x: vec3<f32>,
    n: vec3<f32>,
    flux: vec3<f32>,
    c: f32,
}

fn incident(j: u32, v: u32, vpl: Vpl, per_vpl: u32) -> Sample {
    let p = bounce_point(points[j], instances[points[j].draw]);
    var s = Sample(p.x, p.n, vec3<f32>(0.0), 0.0);
    if (bp.slots.w == 1u && !splat_visible(v, vpl, p.x)) {
        return s;
    }
    if (bp.slots.w == 2u
        && ism_visibility(pulled, v, vpl, p.x, p.n, bp.geom.x, bp.counts.z, bp.counts.w, bp.geom.y, bp.geom.w) < 0.5) {
        return s;
    }
    let l = bounce_light(vpl, p, surfaces[j], per_vpl, bp.geom.z);
    s.flux = l.xyz;
    s.c = l.w;
    return s;
}

@compute @workgroup_size(64, 1, 1)
fn cs_bounce(@builtin(workgroup_id) wid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let i = wid.x;
    let n = bp.counts.y;
    let total_points = bp.counts.x;
    if (lid == 0u) {
        atomicStore(&best_bits, 0u);
        atomicStore(&best_index, 0xFFFFFFFFu);
    }
    workgroupBarrier();
    let v = bp.slots.x + i;
    let vpl = vpls[v];
    var per_vpl = 0u;
    if (i < total_points) {
        per_vpl = (total_points - i + n - 1u) / n;
    }
    var sum = 0.0;
    var key = 0.0;
    var best = Sample(vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0), 0.0);
    var best_j = 0xFFFFFFFFu;
    if (vpl.position.w > 0.5) {
        for (var m = lid; m < per_vpl; m = m + WG) {
            let j = i + m * n;
            let s = incident(j, v, vpl, per_vpl);
            if (s.c > 0.0) {
                sum = sum + s.c;
                var k = s.c;
                if (bp.slots.z == 1u) {
                    k = s.c / -log(bounce_uniform(bp.seed.x, j));
                }
                if (k > key) {
                    key = k;
                    best = s;
                    best_j = j;
                }
            }
        }
    }
    sums[lid] = sum;
    if (key > 0.0) {
        atomicMax(&best_bits, bitcast<u32>(key));
    }
    workgroupBarrier();
    for (var stride = WG / 2u; stride > 0u; stride = stride / 2u) {
        if (lid < stride) {
            sums[lid] = sums[lid] + sums[lid + stride];
        }
        workgroupBarrier();
    }
    let top = atomicLoad(&best_bits);
    if (key > 0.0 && bitcast<u32>(key) == top) {
        atomicMin(&best_index, best_j);
    }
    workgroupBarrier();
    let winner = atomicLoad(&best_index);
    let slot = bp.slots.y + i;
    if (winner == 0xFFFFFFFFu) {
        if (lid == 0u) {
            vpls[slot] = empty_vpl();
        }
        return;
    }
    if (best_j == winner) {
        vpls[slot] = bounce_vpl(vpl, BouncePoint(best.x, best.n), surfaces[winner], best.flux, sums[0] / best.c);
    }
}
