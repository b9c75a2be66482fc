// Shared by Soler et al.'s passes (004 §3–4). CPU twin: render/src/cpu/soler.rs.
// A level texel: position (xyz world, w view depth z), normal (xyz, w 1 on a surface and 0
// on the background), radiance (rgb leaving the texel: the previous bounce).

const PI: f32 = 3.14159265358979;

// exp(−x² / 2σ²) (cpu::soler::gaussian).
fn gaussian(x: f32, sigma: f32) -> f32 {
    return exp(-(x * x) / max(2.0 * sigma * sigma, 1e-12));
}

fn inside(p: vec2<i32>, size: vec2<u32>) -> bool {
    return p.x >= 0 && p.y >= 0 && p.x < i32(size.x) && p.y < i32(size.y);
}
