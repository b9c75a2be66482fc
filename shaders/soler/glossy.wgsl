// Screen-space importance sampling of glossy receivers (Soler et al. 004 §4, Fig. 3 middle):
// f(θ) = α + exp(−s (θ_r − θ)² / 2π) with s = k·SP, θ_r the screen angle of the projected
// mirror direction; the spiral's angle is mapped through the inverse CDF of f's mixture
// (uniform part, truncated gaussian by erf⁻¹) and the sample stands for dP / (2π p(θ)). The readings are documented in the CPU twin
// render/src/cpu/soler_glossy.rs (erf, erfinv, importance, cdf, invert, lobe_angle, warp, specular).
// Needs soler/common.wgsl (PI).

// erf by Abramowitz & Stegun 7.1.26.
fn gloss_erf(x: f32) -> f32 {
    let t = 1.0 / (1.0 + 0.3275911 * abs(x));
    let poly = t * (0.2548296 + t * (-0.28449674 + t * (1.4214137 + t * (-1.453152 + t * 1.0614054))));
    let y = 1.0 - poly * exp(-x * x);
    return select(y, -y, x < 0.0);
}

fn gloss_importance(d: f32, alpha: f32, s: f32) -> f32 {
    return alpha + exp(-s * d * d / (2.0 * PI));
}

fn gloss_cdf(d: f32, alpha: f32, s: f32) -> f32 {
    let sigma = sqrt(PI / max(s, 1e-6));
    let k = sigma * 1.4142135;
    return alpha * (d + PI) + sigma * sqrt(0.5 * PI) * (gloss_erf(d / k) + gloss_erf(PI / k));
}

// erf⁻¹ by Giles' single-precision approximation (2010).
fn gloss_erfinv(x: f32) -> f32 {
    var w = -log(max((1.0 - x) * (1.0 + x), 1e-30));
    var p: f32;
    if (w < 5.0) {
        w = w - 2.5;
        p = 2.8102264e-8;
        p = 3.4327394e-7 + p * w;
        p = -3.5233877e-6 + p * w;
        p = -4.3915065e-6 + p * w;
        p = 2.1858087e-4 + p * w;
        p = -1.253725e-3 + p * w;
        p = -4.1776816e-3 + p * w;
        p = 0.24664073 + p * w;
        p = 1.5014094 + p * w;
    } else {
        w = sqrt(w) - 3.0;
        p = -2.0021426e-4;
        p = 1.0095056e-4 + p * w;
        p = 1.3493432e-3 + p * w;
        p = -3.6734284e-3 + p * w;
        p = 5.7395077e-3 + p * w;
        p = -7.622461e-3 + p * w;
        p = 9.4388705e-3 + p * w;
        p = 1.001674 + p * w;
        p = 2.8329768 + p * w;
    }
    return p * x;
}

// d with CDF fraction u, drawn as the mixture (uniform part, then the truncated gaussian).
fn gloss_invert(u_in: f32, alpha: f32, s: f32) -> f32 {
    let u = clamp(u_in, 0.0, 1.0);
    let w_uniform = 2.0 * PI * alpha / gloss_cdf(PI, alpha, s);
    if (u < w_uniform) {
        return -PI + 2.0 * PI * u / w_uniform;
    }
    let v = min((u - w_uniform) / max(1.0 - w_uniform, 1e-12), 1.0);
    let k = sqrt(PI / max(s, 1e-6)) * 1.4142135;
    return clamp(k * gloss_erfinv((2.0 * v - 1.0) * gloss_erf(PI / k)), -PI, PI);
}

// θ_r at a receiver (texel axes, y down), or a w of 0 where the mirror direction projects to
// a point. axes: right, up, forward.
fn gloss_lobe_angle(p: vec3<f32>, n: vec3<f32>, eye: vec3<f32>, right: vec3<f32>, up: vec3<f32>, fwd: vec3<f32>, tan_half: vec2<f32>) -> vec2<f32> {
    let q = p - eye;
    let v = -normalize(q);
    let refl = 2.0 * dot(n, v) * n - v;
    let c = dot(q, fwd);
    let dz = dot(refl, fwd);
    if (c <= 1e-6) {
        return vec2<f32>(0.0, 0.0);
    }
    let dx = dot(refl, right) - dot(q, right) * dz / c;
    let dy = dot(refl, up) - dot(q, up) * dz / c;
    if (dx * dx + dy * dy < 1e-6) {
        return vec2<f32>(0.0, 0.0);
    }
    return vec2<f32>(atan2(-dy / tan_half.y, dx / tan_half.x), 1.0);
}

// The sample's angle and area factor (cpu::soler_glossy::warp); lobe = (θ_r, s), on = false:
// uniform.
fn gloss_warp(phi: f32, lobe: vec2<f32>, on: bool, alpha: f32) -> vec2<f32> {
    if (!on) {
        return vec2<f32>(phi, 1.0);
    }
    let turn = (phi - lobe.x) / (2.0 * PI) + 0.5;
    let u = turn - floor(turn);
    let d = gloss_invert(u, alpha, lobe.y);
    let pdf = gloss_importance(d, alpha, lobe.y) / gloss_cdf(PI, alpha, lobe.y);
    return vec2<f32>(lobe.x + d, 1.0 / (2.0 * PI * pdf));
}

// The specular lobe of the one BRDF (common/brdf.wgsl's brdf_eval without its diffuse term):
// SI (SP + 8) / 8π · max(0, n·h)^SP.
fn gloss_specular(n: vec3<f32>, l: vec3<f32>, v: vec3<f32>, si: f32, sp: f32) -> f32 {
    let hv = l + v;
    if (dot(hv, hv) <= 0.0) {
        return 0.0;
    }
    let ndh = max(dot(n, normalize(hv)), 0.0);
    return si * (sp + 8.0) / (8.0 * PI) * pow(ndh, sp);
}
