// Stage 6: the geometry-aware n×n box filter (Knecht 002 §3.4.1 after Laine et al. 2007): the
// average over the window −⌊n/2⌋ … n−1−⌊n/2⌋ (one pixel of every interleaving tile) of the
// pixels on the centre's surface: depth difference at most α in linear depth, normals' dot product
// at least β. CPU twin: cpu::knecht::geometry_aware_filter.
//
// Demodulated (n.y = 1; issue #51, docs/readings.md knecht.demodulated-filter): the window's
// mean irradiance E is reflected with the centre's own diffuse reflectance k = c·DI/π and the
// mean of the specular light S = L − k·E is added, so that the albedo's texture is not
// blurred; n.y = 0 averages L as the thesis does. The mean irradiance goes to
// `indirect.filtered_irradiance` for the demodulated confidence merge (knecht/temporal/confidence.wgsl).
#import common/fullscreen.wgsl
#import common/brdf.wgsl

struct FilterParams {
    // x: n (1 = copy); y: 1 to filter demodulated light
    n: vec4<u32>,
    // x: α · (z_far − z_near) (the thesis' linear depth, Eq. 4.2), y: β (normal dot product)
    thresholds: vec4<f32>,
}

@group(0) @binding(0) var<uniform> params: FilterParams;
@group(0) @binding(1) var src: texture_2d<f32>;
// The camera G-buffer's linear depth (issue #53).
@group(0) @binding(2) var g_position: texture_2d<f32>;
@group(0) @binding(3) var g_normal: texture_2d<f32>;
@group(0) @binding(4) var dst: texture_storage_2d<rgba16float, write>;
@group(0) @binding(5) var irradiance: texture_2d<f32>;
@group(0) @binding(6) var g_albedo: texture_2d<f32>;
@group(0) @binding(7) var dst_irradiance: texture_storage_2d<rgba16float, write>;

// The pixel's diffuse reflectance k = c·DI/π (brdf_eval's diffuse term; 0 when the filter
// averages L itself).
fn reflectance(q: vec2<i32>) -> vec3<f32> {
    if (params.n.y == 0u) {
        return vec3<f32>(0.0);
    }
    let alb = textureLoad(g_albedo, q, 0);
    return brdf_diffuse(alb.rgb, alb.a);
}

fn irradiance_at(q: vec2<i32>) -> vec3<f32> {
    if (params.n.y == 0u) {
        return vec3<f32>(0.0);
    }
    return textureLoad(irradiance, q, 0).rgb;
}

@compute @workgroup_size(TILE, TILE, 1)
fn cs_filter(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = textureDimensions(dst);
    if (gid.x >= size.x || gid.y >= size.y) {
        return;
    }
    let p = vec2<i32>(gid.xy);
    let cn = textureLoad(g_normal, p, 0);
    if (cn.w < 0.5) {
        textureStore(dst, p, vec4<f32>(0.0, 0.0, 0.0, 1.0));
        textureStore(dst_irradiance, p, vec4<f32>(0.0, 0.0, 0.0, 1.0));
        return;
    }
    let cd = textureLoad(g_position, p, 0).x;
    let n = i32(params.n.x);
    let lo = -(n / 2);
    var sum = vec3<f32>(0.0);
    var irr = vec3<f32>(0.0);
    var count = 0.0;
    for (var dy = lo; dy < lo + n; dy = dy + 1) {
        for (var dx = lo; dx < lo + n; dx = dx + 1) {
            let q = p + vec2<i32>(dx, dy);
            if (q.x < 0 || q.y < 0 || q.x >= i32(size.x) || q.y >= i32(size.y)) {
                continue;
            }
            let qn = textureLoad(g_normal, q, 0);
            let qd = textureLoad(g_position, q, 0).x;
            if (qn.w < 0.5 || abs(qd - cd) > params.thresholds.x || dot(qn.xyz, cn.xyz) < params.thresholds.y) {
                continue;
            }
            let e = irradiance_at(q);
            sum = sum + (textureLoad(src, q, 0).rgb - reflectance(q) * e);
            irr = irr + e;
            count = count + 1.0;
        }
    }
    textureStore(dst, p, vec4<f32>((reflectance(p) * irr + sum) / max(count, 1.0), 1.0));
    textureStore(dst_irradiance, p, vec4<f32>(irr / max(count, 1.0), 1.0));
}
