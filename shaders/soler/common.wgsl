// Shared by Soler et al.'s passes (004 §3–4). CPU twin: render/src/cpu/soler.rs.
// A level texel: position (xyz world, w view depth z), normal (xyz, w 1 on a surface and 0
// on the background), radiance (rgb leaving the texel: the previous bounce).

const PI: f32 = 3.14159265358979;

// exp(−x² / 2σ²) (cpu::soler::gaussian).
fn gaussian(x: f32, sigma: f32) -> f32 {
    return exp(-(x * x) / max(2.0 * sigma * sigma, 1e-12));
}

// Eq. 2's factor z² · cos α / cos β of a texel at `position` (w: view depth) with `normal`,
// seen from `eye` (cos β clamped below by `min_cos_beta`): its surface area per unit screen
// area, up to the level's constant 4 tan(f_h/2) tan(f_v/2) / (W H) (cpu::soler::area_factor).
fn area_factor(position: vec4<f32>, normal: vec3<f32>, eye: vec3<f32>, min_cos_beta: f32) -> f32 {
    let to_eye = eye - position.xyz;
    let dist = max(length(to_eye), 1e-12);
    let cos_alpha = min(position.w / dist, 1.0);
    let cos_beta = max(abs(dot(normal, to_eye)) / dist, min_cos_beta);
    return position.w * position.w * cos_alpha / cos_beta;
}

fn inside(p: vec2<i32>, size: vec2<u32>) -> bool {
    return p.x >= 0 && p.y >= 0 && p.x < i32(size.x) && p.y < i32(size.y);
}
