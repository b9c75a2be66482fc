// Each new record's hemisphere tile reduced to its terms (Gautron et al. 003, "Simple plane
// sampling"; "Irradiance Caching": irradiance, gradients, harmonic mean distance), one
// workgroup per slot, with the per-texel table of cpu::gautron::HemisphereTable (solid
// angles A·cos³θ, the border band of the chosen compensation, the texel edges):
//   E   = Σ L cosθ Ω + Σ L · band                       (the band: the directions the aperture misses)
//   H   = Σ cosθ Ω / Σ_hit cosθ Ω / r                    (Ward's harmonic mean; misses are infinitely far)
//   ∇_r = Σ L Ω (n × ω) + Σ L ∫_band (n × ω) dω           (the derivative of ∫ L max(0, n·ω) dω under rotation)
//   ∇_t = −Σ_edges (L_a − L_b) cosθ_e l_e m_e / min(r_a, r_b)   (Ward–Heckbert / Křivánek: the nearer
//         surface owns a texel boundary and its image moves by −t⊥/r)
// then R_k = H clamped in scene units, then in pixels at the record's depth; and the scene
// draws the tile saw (the atlas's motion target holds the draw's index), for the record
// cache's invalidation. Twin: cpu::gautron::reduce.
#import gautron/common.wgsl

struct TexelTerms {
    dir: vec4<f32>,
    band: vec4<f32>,
    right: vec4<f32>,
    down: vec4<f32>,
}


@group(0) @binding(0) var<uniform> params: GautronParams;
@group(0) @binding(1) var<storage, read> state: CacheState;
@group(0) @binding(2) var<storage, read> table: array<TexelTerms>;
@group(0) @binding(3) var<storage, read> cameras: array<HemisphereCamera>;
@group(0) @binding(4) var<storage, read_write> records: array<Record>;
@group(0) @binding(5) var radiance: texture_2d<f32>;
@group(0) @binding(6) var position: texture_2d<f32>;
@group(0) @binding(7) var normal: texture_2d<f32>;
@group(0) @binding(8) var object: texture_2d<f32>;

const FAR: f32 = 1e30;
const TERMS: u32 = 26u;
var<workgroup> part: array<f32, 1664>;
var<workgroup> seen_bits: array<atomic<u32>, 4>;

struct Seen {
    light: vec3<f32>,
    r: f32,
}

fn seen(origin: vec2<i32>, i: u32, j: u32, p: vec3<f32>) -> Seen {
    let px = origin + vec2<i32>(i32(i), i32(j));
    var s: Seen;
    s.light = textureLoad(radiance, px, 0).rgb;
    s.r = FAR;
    if (textureLoad(normal, px, 0).w > 0.5) {
        s.r = max(distance(textureLoad(position, px, 0).xyz, p), 1e-6);
    }
    return s;
}

fn edge(a: Seen, b: Seen, terms: vec4<f32>) -> mat3x3<f32> {
    let rmin = min(a.r, b.r);
    if (terms.w <= 0.0 || rmin >= FAR * 0.5) {
        return mat3x3<f32>(vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0));
    }
    let d = (a.light - b.light) * (terms.w / rmin);
    return mat3x3<f32>(-d.x * terms.xyz, -d.y * terms.xyz, -d.z * terms.xyz);
}

@compute @workgroup_size(64, 1, 1)
fn cs_reduce(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    let s = wg.x;
    if (s >= state.new_count + state.refresh) {
        return;
    }
    if (li < 4u) {
        atomicStore(&seen_bits[li], 0u);
    }
    workgroupBarrier();
    let cam = cameras[s];
    let n_px = u32(params.hemisphere.x);
    let per_row = u32(params.hemisphere.y);
    let origin = vec2<i32>(i32((s % per_row) * n_px), i32((s / per_row) * n_px));
    let p = cam.position.xyz;
    var e = vec3<f32>(0.0);
    var h_num = 0.0;
    var h_den = 0.0;
    var rot = mat3x3<f32>(vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0));
    var trans = mat3x3<f32>(vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0));
    var dir = vec3<f32>(0.0);
    for (var k = li; k < n_px * n_px; k = k + 64u) {
        let i = k % n_px;
        let j = k / n_px;
        let tt = table[k];
        let a = seen(origin, i, j, p);
        if (a.r < FAR * 0.5) {
            let draw = u32(textureLoad(object, origin + vec2<i32>(i32(i), i32(j)), 0).x) % 128u;
            atomicOr(&seen_bits[draw / 32u], 1u << (draw % 32u));
        }
        let c_omega = tt.dir.z * tt.dir.w;
        e = e + a.light * (c_omega + tt.band.x);
        dir = dir + dot(a.light, vec3<f32>(0.2126, 0.7152, 0.0722)) * c_omega * tt.dir.xyz;
        h_num = h_num + c_omega;
        if (a.r < FAR * 0.5) {
            h_den = h_den + c_omega / a.r;
        }
        // n × ω in the local frame (n = z), and the band's integral of it
        let cross_n = vec3<f32>(-tt.dir.y, tt.dir.x, 0.0) * tt.dir.w + vec3<f32>(tt.band.z, tt.band.w, 0.0);
        rot = rot + mat3x3<f32>(a.light.x * cross_n, a.light.y * cross_n, a.light.z * cross_n);
        if (i + 1u < n_px) {
            trans = trans + edge(a, seen(origin, i + 1u, j, p), tt.right);
        }
        if (j + 1u < n_px) {
            trans = trans + edge(a, seen(origin, i, j + 1u, p), tt.down);
        }
    }
    let o = li * TERMS;
    part[o] = e.x;
    part[o + 1u] = e.y;
    part[o + 2u] = e.z;
    part[o + 3u] = h_num;
    part[o + 4u] = h_den;
    for (var c = 0u; c < 3u; c = c + 1u) {
        for (var d = 0u; d < 3u; d = d + 1u) {
            part[o + 5u + c * 3u + d] = rot[c][d];
            part[o + 14u + c * 3u + d] = trans[c][d];
        }
    }
    part[o + 23u] = dir.x;
    part[o + 24u] = dir.y;
    part[o + 25u] = dir.z;
    // The 64 invocations' terms summed in a tree (issue #38: one invocation used to add all
    // 64 × 23 in turn).
    for (var stride = 32u; stride > 0u; stride = stride >> 1u) {
        workgroupBarrier();
        if (li < stride) {
            for (var q = 0u; q < TERMS; q = q + 1u) {
                part[o + q] = part[o + q] + part[(li + stride) * TERMS + q];
            }
        }
    }
    if (li != 0u) {
        return;
    }
    var sum: array<f32, 26>;
    for (var q = 0u; q < TERMS; q = q + 1u) {
        sum[q] = part[q];
    }
    let frame = mat3x3<f32>(cam.t.xyz, cam.b.xyz, cam.n.xyz);
    let index = u32(cam.n.w);
    var rec = records[index];
    rec.irradiance = vec4<f32>(sum[0], sum[1], sum[2], rec.irradiance.w);
    rec.dir = vec4<f32>(frame * vec3<f32>(sum[23], sum[24], sum[25]), 0.0);
    for (var c = 0u; c < 3u; c = c + 1u) {
        let rl = vec3<f32>(sum[5u + c * 3u], sum[6u + c * 3u], sum[7u + c * 3u]);
        let tl = vec3<f32>(sum[14u + c * 3u], sum[15u + c * 3u], sum[16u + c * 3u]);
        rec.rot[c] = vec4<f32>(frame * rl, 0.0);
        rec.trans[c] = vec4<f32>(frame * tl, 0.0);
    }
    var h = FAR;
    if (sum[4] > 0.0) {
        h = sum[3] / sum[4];
    }
    rec.position.w = clamped_radius(params, h, rec);
    rec.normal.w = h;
    rec.pixel.w = RECORD_VALID;
    rec.seen = vec4<u32>(atomicLoad(&seen_bits[0]), atomicLoad(&seen_bits[1]), atomicLoad(&seen_bits[2]), atomicLoad(&seen_bits[3]));
    records[index] = rec;
}
