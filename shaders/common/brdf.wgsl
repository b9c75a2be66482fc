// The one BRDF of GI Lab (CPU twin: render/src/cpu/brdf.rs, documented there).
// Knecht 002 Eq. 4.9 shades with c·DI + SI·max(0, n·h)^SP; we use its energy-normalised
// form so that it integrates to at most 1 and matches the path tracer:
//   f(l, v) = c·DI / π + SI · (SP + 8) / (8π) · max(0, n·h)^SP
const PI: f32 = 3.14159265358979;

fn brdf_eval(n: vec3<f32>, l: vec3<f32>, v: vec3<f32>, albedo: vec3<f32>, di: f32, si: f32, sp: f32) -> vec3<f32> {
    let h = normalize(l + v);
    let ndh = max(dot(n, h), 0.0);
    let spec = si * (sp + 8.0) / (8.0 * PI) * pow(ndh, sp);
    return brdf_diffuse(albedo, di) + vec3<f32>(spec);
}

// The diffuse term c·DI/π alone: what the demodulated filter (knecht/interleave/filter.wgsl) takes
// apart from the light and applies again, to the bit as brdf_eval adds it.
fn brdf_diffuse(albedo: vec3<f32>, di: f32) -> vec3<f32> {
    return albedo * di / PI;
}
