// Stage 6's geometry-aware n×n box filter at one pixel (Knecht 002 §3.4.1 after Laine et al.
// 2007), shared by the filter pass (knecht/interleave/filter.wgsl) and the filter fused into
// the confidence merge (knecht/temporal/filter_merge.wgsl, issue #53): the average over the
// window −⌊n/2⌋ … n−1−⌊n/2⌋ (one pixel of every interleaving tile) of the pixels on the
// centre's surface: linear depth difference at most α (Eq. 4.2's depth), normals' dot product
// at least β. CPU twin: cpu::knecht::geometry_aware_filter.
//
// Demodulated (issue #51, docs/readings.md knecht.demodulated-filter): the window's mean
// irradiance E is reflected with the centre's own diffuse reflectance k = c·DI/π and the mean
// of the specular light S = L − k·E is added, so that the albedo's texture is not blurred;
// otherwise L is averaged as the thesis does.
//
// The including module declares `src` (the gathered light), `g_position` (the camera
// G-buffer's linear depth, issue #53), `g_normal` (its packed normal, common/normal.wgsl),
// `irradiance` and `g_albedo`.
#import common/brdf.wgsl
#import common/normal.wgsl

struct FilterParams {
    // x: n (1 = copy); y: 1 to filter demodulated light
    n: vec4<u32>,
    // x: α · (z_far − z_near) (the thesis' linear depth, Eq. 4.2), y: β (normal dot product)
    thresholds: vec4<f32>,
}

// A pixel's filtered light and the mean irradiance it reflects (0 when not demodulated);
// `covered` false where no geometry covers the centre.
struct Filtered {
    light: vec3<f32>,
    irradiance: vec3<f32>,
    covered: bool,
}

// The pixel's diffuse reflectance k = c·DI/π (brdf_eval's diffuse term; 0 when the filter
// averages L itself).
fn filter_reflectance(q: vec2<i32>, demodulate: bool) -> vec3<f32> {
    if (!demodulate) {
        return vec3<f32>(0.0);
    }
    let alb = textureLoad(g_albedo, q, 0);
    return brdf_diffuse(alb.rgb, alb.a);
}

fn filter_irradiance_at(q: vec2<i32>, demodulate: bool) -> vec3<f32> {
    if (!demodulate) {
        return vec3<f32>(0.0);
    }
    return textureLoad(irradiance, q, 0).rgb;
}

fn filter_window(p: vec2<i32>, size: vec2<u32>, fp: FilterParams) -> Filtered {
    let cn = gbuffer_normal(textureLoad(g_normal, p, 0).x);
    if (cn.w < 0.5) {
        return Filtered(vec3<f32>(0.0), vec3<f32>(0.0), false);
    }
    let demodulate = fp.n.y != 0u;
    let cd = textureLoad(g_position, p, 0).x;
    let n = i32(fp.n.x);
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
            let qn = gbuffer_normal(textureLoad(g_normal, q, 0).x);
            let qd = textureLoad(g_position, q, 0).x;
            if (qn.w < 0.5 || abs(qd - cd) > fp.thresholds.x || dot(qn.xyz, cn.xyz) < fp.thresholds.y) {
                continue;
            }
            let e = filter_irradiance_at(q, demodulate);
            sum = sum + (textureLoad(src, q, 0).rgb - filter_reflectance(q, demodulate) * e);
            irr = irr + e;
            count = count + 1.0;
        }
    }
    let c = max(count, 1.0);
    return Filtered((filter_reflectance(p, demodulate) * irr + sum) / c, irr / c, true);
}
