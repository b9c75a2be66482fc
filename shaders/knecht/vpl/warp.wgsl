// Stage 3 (Knecht 002 §3.3, §4.4): one pass creates a view's VPLs. Sample i is the Halton
// point (h₂(k), h₃(k)) with k = first index of this frame + i (a new set each frame when the
// first index advances); hierarchical warping (Clarberg et al. 2005) moves it down the
// importance pyramid, from the 2×2 level to the finest: a vertical split by the upper and
// lower children's summed importance, then a horizontal split in the chosen row, rescaling
// the sample into the chosen child. The texel reached is looked up in the light G-buffer;
// the VPL's flux is the flux through the texel's uv area divided by the sampling density
// N_v · pdf, pdf = importance / mean importance, so that the set is an unbiased estimate of
// the light the view delivers. CPU twins: cpu::knecht::{halton, Pyramid::warp}.
#import common/light_view.wgsl
#import common/vpl.wgsl
#import common/random.wgsl

@group(0) @binding(0) var<storage, read> vp: ViewParams;
@group(0) @binding(1) var<storage, read> lights: array<Light>;
@group(0) @binding(2) var lg_position: texture_2d<f32>;
@group(0) @binding(3) var lg_normal: texture_2d<f32>;
@group(0) @binding(4) var lg_albedo: texture_2d<f32>;
@group(0) @binding(5) var lg_material: texture_2d<f32>;
@group(0) @binding(6) var importance: texture_2d_array<f32>;
@group(0) @binding(7) var<storage, read_write> vpls: array<Vpl>;
// Warped sample positions (uv, pdf, texel index) for the tests and the VPL overlay.
@group(0) @binding(8) var<storage, read_write> warped: array<vec4<f32>>;

// (1 if the second half is chosen, u rescaled into the chosen half).
fn split(u: f32, p: f32) -> vec2<f32> {
    if (p <= 0.0) {
        return vec2<f32>(1.0, u);
    }
    if (p >= 1.0) {
        return vec2<f32>(0.0, u);
    }
    if (u < p) {
        return vec2<f32>(0.0, u / p);
    }
    return vec2<f32>(1.0, min((u - p) / (1.0 - p), 0.99999994));
}

fn imp(level: u32, c: vec2<u32>) -> f32 {
    return textureLoad(importance, c, vp.range.w, level).r;
}

@compute @workgroup_size(64, 1, 1)
fn cs_warp(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if (i >= vp.range.y) {
        return;
    }
    let slot = vp.range.x + i;
    var empty: Vpl;
    empty.position = vec4<f32>(0.0);
    empty.flux = vec4<f32>(0.0);
    let k = vp.seq.x + i;
    var u = vec2<f32>(halton(k, 2u), halton(k, 3u));
    let top = textureNumLevels(importance) - 1u;
    let mean = imp(top, vec2<u32>(0u));
    if (mean <= 0.0) {
        vpls[slot] = empty;
        warped[slot] = vec4<f32>(u, 0.0, -1.0);
        return;
    }
    var cell = vec2<u32>(0u);
    for (var level = i32(top) - 1; level >= 0; level = level - 1) {
        let l = u32(level);
        let c = cell * 2u;
        let a00 = imp(l, c);
        let a10 = imp(l, c + vec2<u32>(1u, 0u));
        let a01 = imp(l, c + vec2<u32>(0u, 1u));
        let a11 = imp(l, c + vec2<u32>(1u, 1u));
        let upper = a00 + a10;
        let lower = a01 + a11;
        var p_upper = 0.5;
        if (upper + lower > 0.0) {
            p_upper = upper / (upper + lower);
        }
        let sv = split(u.y, p_upper);
        var left = a00;
        var right = a10;
        if (sv.x > 0.5) {
            left = a01;
            right = a11;
        }
        var p_left = 0.5;
        if (left + right > 0.0) {
            p_left = left / (left + right);
        }
        let sh = split(u.x, p_left);
        u = vec2<f32>(sh.y, sv.y);
        cell = c + vec2<u32>(u32(sh.x), u32(sv.x));
    }
    let pdf = imp(0u, cell) / mean;
    let size = textureDimensions(importance).x;
    warped[slot] = vec4<f32>((vec2<f32>(cell) + u) / f32(size), pdf, f32(cell.y * size + cell.x));
    let nrm = textureLoad(lg_normal, cell, 0);
    if (nrm.w < 0.5 || pdf <= 0.0) {
        vpls[slot] = empty;
        return;
    }
    let p = textureLoad(lg_position, cell, 0).xyz;
    let n = normalize(nrm.xyz);
    let to_light = toward_light(vp.view, p);
    let flux = flux_per_uv(lights[vp.range.z], vp.view, p) * vp.scale.x / (f32(vp.range.y) * pdf);
    if (dot(n, to_light) <= 0.0 || max(flux.r, max(flux.g, flux.b)) <= 0.0) {
        vpls[slot] = empty;
        return;
    }
    let alb = textureLoad(lg_albedo, cell, 0);
    let mat = textureLoad(lg_material, cell, 0);
    var v: Vpl;
    v.position = vec4<f32>(p, 1.0);
    v.normal = vec4<f32>(n, alb.a);
    v.flux = vec4<f32>(flux, mat.x);
    v.incident = vec4<f32>(to_light, mat.y);
    v.albedo = vec4<f32>(alb.rgb, 0.0);
    vpls[slot] = v;
}
