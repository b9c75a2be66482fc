// How a pixel reflects the irradiance a technique interpolated to it (issue #51 point 1;
// CPU twin: cpu::brdf::receive_irradiance, where the reading is documented).
// E (rgb) is the irradiance; d (xyz) its luminance-weighted mean incident direction,
// Σ lum(E_k) ω_k / Σ lum(E_k), whose length r ≤ 1 says how concentrated the light is.
// The diffuse term is c·DI/π·E, exact; the specular term lights the lobe from d's direction,
// the lobe's power SP widened by the spread of the light (a von Mises–Fisher lobe of
// sharpness κ from r, 4κ in the half-vector's angle): 1/SP' = 1/SP + 1/(4κ).
#import common/brdf.wgsl

// 1/(4κ) for the lobe of mean resultant length r, κ ≈ r(3 − r²)/(1 − r²) (CPU twin:
// cpu::brdf::receiver_spread): 0 for light from one direction.
fn receiver_spread(r: f32) -> f32 {
    let q = clamp(r, 1e-4, 1.0);
    return (1.0 - q * q) / (4.0 * q * (3.0 - q * q));
}

// The reflected radiance per unit irradiance (per channel): c·DI/π plus the specular lobe's
// factor; the pixel's light is this times E (so that a replay can split it over the
// contributions to E).
fn receiver_factor(d: vec3<f32>, n: vec3<f32>, v: vec3<f32>, albedo: vec3<f32>, di: f32, si: f32, sp: f32, glossy: bool) -> vec3<f32> {
    let diffuse = albedo * di / PI;
    let r = length(d);
    if (!glossy || si <= 0.0 || r <= 1e-4) {
        return diffuse;
    }
    let l = d / r;
    let sp_eff = 1.0 / (1.0 / max(sp, 1e-3) + receiver_spread(r));
    let h = normalize(l + v);
    let ndh = max(dot(n, h), 0.0);
    return diffuse + vec3<f32>(si * (sp_eff + 8.0) / (8.0 * PI) * pow(ndh, sp_eff));
}

// The mean incident direction d from the splat's sums: Σ w·dir over lum(Σ w·E) (the sums of
// the irradiance the directions were weighted with).
fn receiver_direction(dir_sum: vec3<f32>, e_sum: vec3<f32>) -> vec3<f32> {
    let lum = dot(e_sum, vec3<f32>(0.2126, 0.7152, 0.0722));
    if (lum <= 0.0) {
        return vec3<f32>(0.0);
    }
    return dir_sum / lum;
}

fn receive_irradiance(e: vec3<f32>, d: vec3<f32>, n: vec3<f32>, v: vec3<f32>, albedo: vec3<f32>, di: f32, si: f32, sp: f32, glossy: bool) -> vec3<f32> {
    return receiver_factor(d, n, v, albedo, di, si, sp, glossy) * e;
}
