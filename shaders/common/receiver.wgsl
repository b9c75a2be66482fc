// How a pixel reflects the irradiance a technique interpolated to it (issue #51 point 1;
// CPU twin: cpu::brdf::receive_irradiance, where the reading is documented).
// E (rgb) is the irradiance; d (xyz) its luminance-weighted mean incident direction,
// Σ lum(E_k) ω_k / Σ lum(E_k), whose length r ≤ 1 says how concentrated the light is.
// The diffuse term is c·DI/π·E, exact; the specular term lights the lobe from d's direction,
// the lobe's power SP widened by the spread of the light (a von Mises–Fisher lobe of
// sharpness κ from r, 4κ in the half-vector's angle): 1/SP' = 1/SP + 1/(4κ).
#import common/brdf.wgsl

fn receiver_sharpness(r: f32) -> f32 {
    let q = clamp(r, 0.0, 0.999);
    return q * (3.0 - q * q) / (1.0 - q * q);
}

fn receive_irradiance(e: vec3<f32>, d: vec3<f32>, n: vec3<f32>, v: vec3<f32>, albedo: vec3<f32>, di: f32, si: f32, sp: f32, glossy: bool) -> vec3<f32> {
    let diffuse = albedo * di / PI * e;
    let r = length(d);
    if (!glossy || si <= 0.0 || r <= 1e-4) {
        return diffuse;
    }
    let l = d / r;
    let kappa = receiver_sharpness(r);
    let sp_eff = 1.0 / (1.0 / max(sp, 1e-3) + 1.0 / max(4.0 * kappa, 1e-3));
    let h = normalize(l + v);
    let ndh = max(dot(n, h), 0.0);
    let spec = si * (sp_eff + 8.0) / (8.0 * PI) * pow(ndh, sp_eff);
    return diffuse + spec * e;
}
