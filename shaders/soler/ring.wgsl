// The ring gather's parameters and per-sample terms (Soler et al. 004 §3–4, Eq. 1–4,
// Fig. 3), shared by the gather on every texel of a level (soler/gather.wgsl) and the gather
// at the HCB's samples (soler/hcb_gather.wgsl). Needs soler/common.wgsl and
// soler/voxel_common.wgsl; the includer binds `params`, `grid` and the level's
// `level_position` and `level_normal`. CPU twin: cpu::soler.

// Rust twin: passes::soler::gather::GatherParams.
struct GatherParams {
    // x: samples N, y: first gathered level (full disc) 1/0, z: level index, w: frame
    counts: vec4<u32>,
    // x: r (level texels), y: point-to-disc 1 / point-to-point 0, z: min cos β, w: the
    // near field's cut² (senders farther are the VPLs'; 0: none)
    shape: vec4<f32>,
    // xyz: the eye; w unused
    eye: vec4<f32>,
    // x: tan(f_h/2), y: tan(f_v/2), z: W, w: H (the level's size)
    screen: vec4<f32>,
    // This level's voxel grid (grid.x = 0: no visibility).
    voxels: VoxelParams,
    // x: texels skipped at both ends of the march, y: depth bias (slices), z, w: unused
    march: vec4<f32>,
    // x: α, y: k (s = k·SP), z: the least SP importance sampled, w: 1 glossy reflection
    // + 2 importance sampling
    gloss: vec4<f32>,
    // The camera's right, up and forward axes (xyz).
    right: vec4<f32>,
    up: vec4<f32>,
    forward: vec4<f32>,
}

const GOLDEN_ANGLE: f32 = 2.3999632;

// v_i: false when a solid voxel of the grid lies between texel a (view depth za) and texel b
// (view depth zb). CPU twin: cpu::soler::march_visible.
fn visible(a: vec2<i32>, za: f32, b: vec2<i32>, zb: f32) -> bool {
    let v = params.voxels;
    let d = vec2<f32>(b - a);
    let n = max(abs(d.x), abs(d.y));
    let bias = params.march.x;
    let steps = i32(ceil(n));
    for (var i = 1; i < steps; i = i + 1) {
        let fi = f32(i);
        if (fi < bias || n - fi < bias) {
            continue;
        }
        let t = fi / n;
        let p = vec2<i32>(round(vec2<f32>(a) + d * t));
        if (p.x < 0 || p.y < 0 || p.x >= i32(v.grid.x) || p.y >= i32(v.grid.y)) {
            continue;
        }
        let z = 1.0 / mix(1.0 / za, 1.0 / zb, t);
        let sf = floor((z - v.depth.x) / max(v.depth.y - v.depth.x, 1e-12) * f32(v.grid.w) - params.march.y);
        if (sf < 0.0 || sf >= f32(v.grid.w)) {
            continue;
        }
        let s = u32(sf);
        let word = grid[(u32(p.y) * v.grid.x + u32(p.x)) * v.grid.z + s / 32u];
        if (((word >> (s % 32u)) & 1u) != 0u) {
            return false;
        }
    }
    return true;
}

fn rotation(p: vec2<u32>) -> f32 {
    let h = pcg_hash(p.x ^ pcg_hash(p.y ^ pcg_hash(params.counts.z ^ pcg_hash(params.counts.w))));
    return f32(h >> 8u) / 16777216.0 * 2.0 * PI;
}

// Eq. 2 at a sample: z² · 4 tan(f_h/2) tan(f_v/2) · dP / (W H) · cos α / cos β.
fn surface_area(position: vec4<f32>, normal: vec3<f32>, dp: f32) -> f32 {
    return area_factor(position, normal, params.eye.xyz, params.shape.z) * 4.0 * params.screen.x * params.screen.y * dp
        / (params.screen.z * params.screen.w);
}

fn kernel(cos_t: f32, cos_tp: f32, ds: f32, r2: f32) -> f32 {
    if (params.shape.y > 0.5) {
        let big_r2 = cos_tp * ds / PI;
        return PI * big_r2 * cos_t / max(r2 + big_r2, 1e-20);
    }
    return cos_t * cos_tp * ds / max(r2, 1e-20);
}


// The ring of this level (Fig. 3): its inner radius (0 on the first gathered level, which
// samples the full disc) and the screen area dP each of the N samples stands for.
fn ring_inner() -> f32 {
    if (params.counts.y == 1u) {
        return 0.0;
    }
    return 0.5 * params.shape.x;
}

fn ring_area(inner: f32) -> f32 {
    let r = params.shape.x;
    return PI * (r * r - inner * inner) / f32(max(params.counts.x, 1u));
}

// The texel offset of sample j at angle phi: √ of its area fraction of the ring, rounded to
// the nearest texel (cpu::soler::{ring_radius, ring_offset}).
fn ring_offset(j: u32, inner: f32, phi: f32) -> vec2<i32> {
    let r = params.shape.x;
    let u = (f32(j) + 0.5) / f32(max(params.counts.x, 1u));
    let rho = sqrt(inner * inner + u * (r * r - inner * inner));
    return vec2<i32>(round(vec2<f32>(rho * cos(phi), rho * sin(phi))));
}

// A sender texel t of the level seen from receiver x (normal n): Eq. 1's direction, r² and
// cosines; lit = false off the image, on the background, beyond the near field's cut or
// facing away (cpu::soler::facing).
struct Sender {
    position: vec4<f32>,
    normal: vec3<f32>,
    w: vec3<f32>,
    r2: f32,
    cos_t: f32,
    cos_tp: f32,
    lit: bool,
}

fn sender(t: vec2<i32>, x: vec3<f32>, n: vec3<f32>) -> Sender {
    var s: Sender;
    s.lit = false;
    if (!inside(t, textureDimensions(level_position))) {
        return s;
    }
    let nt = textureLoad(level_normal, t, 0);
    if (nt.w < 0.5) {
        return s;
    }
    s.position = textureLoad(level_position, t, 0);
    s.normal = nt.xyz;
    let d = s.position.xyz - x;
    s.r2 = dot(d, d);
    if (s.r2 <= 0.0 || (params.shape.w > 0.0 && s.r2 >= params.shape.w)) {
        return s;
    }
    s.w = d / sqrt(s.r2);
    s.cos_t = max(dot(n, s.w), 0.0);
    s.cos_tp = max(-dot(s.normal, s.w), 0.0);
    s.lit = s.cos_t > 0.0 && s.cos_tp > 0.0;
    return s;
}
