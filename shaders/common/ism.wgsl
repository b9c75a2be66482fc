// Imperfect shadow maps (Knecht 002 §2.6.5, after Ritschel et al. 2008): one paraboloid map
// of each VPL's upper hemisphere (Brabec et al. 2002) in an atlas of `size`² tiles, tile =
// VPL index. Texels hold the distance from the VPL's eye (scene units); ISM_EMPTY marks a hole.
// CPU twins: cpu::knecht::{paraboloid_project, paraboloid_unproject, ISM_EMPTY}.
#import common/vpl.wgsl

const ISM_EMPTY: f32 = 1.0e30;

// Paraboloid coordinates in [0, 1]² (v downward) of a VPL-local direction q (z along the
// normal, |q| = 1, q.z ≥ 0): (q.x, q.y) / (1 + q.z) mapped from the unit disk.
fn paraboloid_project(q: vec3<f32>) -> vec2<f32> {
    let p = q.xy / (1.0 + q.z);
    return vec2<f32>(p.x * 0.5 + 0.5, 0.5 - p.y * 0.5);
}

// The eye of a VPL's ISM: its position lifted along the normal by `offset` (scene units), so
// that the surface it sits on does not shadow it.
fn ism_eye(vpl: Vpl, offset: f32) -> vec3<f32> {
    return vpl.position.xyz + vpl.normal.xyz * offset;
}

// Angular size (radians) of a paraboloid texel at cos θ from the map's axis: the map's
// radius 1 spans tan(θ/2), so a texel of 2/size spans 2 (1 + cos θ) / size.
fn ism_texel_angle(cos_theta: f32, size: u32) -> f32 {
    return 2.0 * (1.0 + max(cos_theta, 0.0)) / f32(size);
}

// Visibility of x (normal nx) from VPL i in the ISM atlas: x is first moved along its normal
// by `normal_offset` texels of the map at its distance (a slope-aware bias: the receiving
// surface's own splats reach around each point and lie nearer on grazing surfaces), then its
// distance from the VPL's eye, less `bias` × that distance, is tested against the stored
// distance at its paraboloid texel.
fn ism_visibility(atlas: texture_2d<f32>, i: u32, vpl: Vpl, x: vec3<f32>, nx: vec3<f32>, offset: f32, cols: u32, size: u32, bias: f32, normal_offset: f32) -> f32 {
    let t = ism_depths(atlas, i, vpl, x, nx, offset, cols, size, bias, normal_offset);
    return select(0.0, 1.0, t.x >= 0.0 && t.y <= t.x);
}

// The comparison behind ism_visibility: (the pulled distance stored at x's texel, x's biased
// distance d·(1 − bias)); (−1, d) when x lies behind the map's hemisphere. Explaining a pixel
// (knecht/interleave/explain.wgsl) shows both.
fn ism_depths(atlas: texture_2d<f32>, i: u32, vpl: Vpl, x: vec3<f32>, nx: vec3<f32>, offset: f32, cols: u32, size: u32, bias: f32, normal_offset: f32) -> vec2<f32> {
    let eye = ism_eye(vpl, offset);
    let w0 = x - eye;
    let d0 = length(w0);
    let cos0 = dot(w0, vpl.normal.xyz) / max(d0, 1e-9);
    let w = w0 + nx * (normal_offset * d0 * ism_texel_angle(cos0, size));
    let d = length(w);
    let tbn = vpl_basis(vpl.normal.xyz);
    let q = vec3<f32>(dot(w, tbn[0]), dot(w, tbn[1]), dot(w, tbn[2])) / max(d, 1e-9);
    if (q.z < 0.0) {
        return vec2<f32>(-1.0, d);
    }
    let uv = paraboloid_project(q);
    let t = min(vec2<u32>(uv * f32(size)), vec2<u32>(size - 1u));
    let stored = textureLoad(atlas, vpl_tile_origin(i, cols, size) + t, 0).r;
    return vec2<f32>(stored, d * (1.0 - bias));
}

// Visibility of x (normal nx) from VPL k as a gather chooses it: `mode` 0 none, 1 the ISM
// atlas, 2 the exact cube-face atlas; atlas columns and map size; p = (ISM eye offset, bias,
// receiver normal offset) or (exact near, far, eye offset).
// The visibility mode a pipeline is made for (0 none, 1 ISM, 2 exact; issue #53), so that the
// others' code is left out of it; 3 (the default): the mode its caller passes at run time.
override VISIBILITY_MODE: u32 = 3u;

fn gather_visibility(mode_at_run: u32, ism: texture_2d<f32>, exact: texture_2d<f32>, k: u32, vpl: Vpl, x: vec3<f32>, nx: vec3<f32>, cols: u32, size: u32, p: vec3<f32>) -> f32 {
    let mode = select(mode_at_run, VISIBILITY_MODE, VISIBILITY_MODE < 3u);
    if (mode == 1u) {
        return ism_visibility(ism, k, vpl, x, nx, p.x, cols, size, p.y, p.z);
    }
    if (mode == 2u) {
        return vpl_exact_visibility(exact, k, vpl, x, nx, p, cols, size, 1.0, 1.0);
    }
    return 1.0;
}

// gather_visibility's test in full: (visibility, the stored depth, the receiver's depth) in
// the map's own unit (the ISM's distance, the exact face's [0, 1] depth; 0, 0 without a map).
fn gather_test(mode: u32, ism: texture_2d<f32>, exact: texture_2d<f32>, k: u32, vpl: Vpl, x: vec3<f32>, nx: vec3<f32>, cols: u32, size: u32, p: vec3<f32>) -> vec3<f32> {
    var t = vec2<f32>(0.0);
    if (mode == 1u) {
        t = ism_depths(ism, k, vpl, x, nx, p.x, cols, size, p.y, p.z);
    } else if (mode == 2u) {
        t = vpl_exact_depths(exact, k, vpl, x, nx, p, cols, size, 1.0, 1.0);
    }
    return vec3<f32>(gather_visibility(mode, ism, exact, k, vpl, x, nx, cols, size, p), t);
}
