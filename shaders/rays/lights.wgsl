// The GPU path tracer's lights (issue #56 point 2): punctual lights, emissive triangles
// sampled by power, the sky sampled by its radiance; twins of `cpu::brdf::punctual_radiance`,
// `scene::emitters::Emitters::sample` and `scene::sky::SkySampler`, documented there.
// Its buffers are group 0's bindings 0–4, declared in `rays/shade.wgsl` (which imports this
// file with `rays/scene.wgsl` and common/brdf.wgsl).

// `passes::rays::pathtrace::PtLight`.
struct PtLight {
    // xyz position; w kind: 0 point, 1 spot, 2 directional.
    position: vec4<f32>,
    // xyz unit direction the light points to; w range (≤ 0: none).
    direction: vec4<f32>,
    // Colour × intensity.
    color: vec4<f32>,
    // Inner and outer cone angles (radians), spots.
    cone: vec4<f32>,
}

// `passes::rays::pathtrace::PtEmitter`: one emissive triangle in the world.
struct PtEmitter {
    // Vertex 0 and the running sum of the triangles' power shares up to this one.
    v0: vec4<f32>,
    // Vertex 1 and the area.
    v1: vec4<f32>,
    // Vertex 2 and the sides (1 or 2).
    v2: vec4<f32>,
    // Unit normal of the front side, the emissive texture's entry (bits; RAY_NO_TEXTURE).
    normal: vec4<f32>,
    // Radiance where untextured.
    radiance: vec4<f32>,
    // The emissive texture's factor, the cutout texture's entry (bits; RAY_NO_TEXTURE: none).
    factor: vec4<f32>,
    // Emissive texture coordinates of vertices 0 and 1, then 2 and the cutout's alpha factor
    // and cutoff.
    uv01: vec4<f32>,
    uv2_cut: vec4<f32>,
    // The cutout's texture coordinates (vertices 0, 1, then 2) and the radiance kept where
    // not cut (untextured emitters).
    cut_uv01: vec4<f32>,
    cut_uv2: vec4<f32>,
    kept: vec4<f32>,
}

struct PtEmitterSample {
    position: vec3<f32>,
    normal: vec3<f32>,
    radiance: vec3<f32>,
    pdf_area: f32,
    ok: bool,
}

// The first emitter whose running sum exceeds u (`Emitters::pick`).
fn pt_pick_emitter(u: f32, count: u32) -> u32 {
    var lo = 0u;
    var hi = count;
    while (lo < hi) {
        let mid = (lo + hi) / 2u;
        if (pt_emitters[mid].v0.w <= u) {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    return min(lo, count - 1u);
}

// A point of the emitters for uniforms u ∈ [0, 1)³ (`Emitters::sample`).
fn pt_sample_emitter(u: vec3<f32>, count: u32) -> PtEmitterSample {
    let i = pt_pick_emitter(u.x, count);
    let t = pt_emitters[i];
    var lo = 0.0;
    if (i > 0u) {
        lo = pt_emitters[i - 1u].v0.w;
    }
    let p_tri = max(t.v0.w - lo, 1.17549435e-38);
    let within = clamp((u.x - lo) / p_tri, 0.0, 1.0);
    var normal = t.normal.xyz;
    if (t.v2.w == 2.0 && within >= 0.5) {
        normal = -normal;
    }
    let s = sqrt(u.y);
    let b1 = 1.0 - s;
    let b2 = u.z * s;
    let b3 = 1.0 - b1 - b2;
    let position = t.v0.xyz * b1 + t.v1.xyz * b2 + t.v2.xyz * b3;
    let pdf_area = p_tri / (t.v1.w * t.v2.w);
    var radiance = t.radiance.xyz;
    let tex = bitcast<u32>(t.normal.w);
    if (tex != RAY_NO_TEXTURE) {
        let uv = t.uv01.xy * b1 + t.uv01.zw * b2 + t.uv2_cut.xy * b3;
        radiance = t.factor.xyz * ray_sample_level(tex, uv, true).rgb;
    }
    let cut = bitcast<u32>(t.factor.w);
    if (cut != RAY_NO_TEXTURE) {
        let at = t.cut_uv01.xy * b1 + t.cut_uv01.zw * b2 + t.cut_uv2.xy * b3;
        if (t.uv2_cut.z * ray_sample_level(cut, at, true).a < t.uv2_cut.w) {
            radiance = vec3<f32>(0.0);
        } else if (tex == RAY_NO_TEXTURE) {
            radiance = t.kept.xyz;
        }
    }
    return PtEmitterSample(position, normal, radiance, pdf_area, true);
}

// The light of a punctual light at p (normal n, view v, surface c, DI, SI, SP) unshadowed,
// and the point a shadow ray must reach (`cpu::brdf::punctual_radiance`, far = 10⁶).
struct PtPunctual {
    radiance: vec3<f32>,
    target_point: vec3<f32>,
}

fn pt_spot_falloff(cos_theta: f32, inner: f32, outer: f32) -> f32 {
    let co = cos(outer);
    let ci = cos(inner);
    let t = clamp((cos_theta - co) / max(ci - co, 1e-4), 0.0, 1.0);
    return t * t;
}

fn pt_punctual(light: PtLight, p: vec3<f32>, n: vec3<f32>, v: vec3<f32>, c: vec3<f32>, di: f32, si: f32, sp: f32) -> PtPunctual {
    var l: vec3<f32>;
    var e: f32;
    var target_point: vec3<f32>;
    let intensity = light.color.w;
    if (light.position.w == 2.0) {
        l = -light.direction.xyz;
        e = intensity;
        target_point = p + l * 1e6;
    } else {
        let to_l = light.position.xyz - p;
        let d2 = max(dot(to_l, to_l), 1e-12);
        let d = sqrt(d2);
        l = to_l / d;
        var falloff = 1.0;
        if (light.position.w == 1.0) {
            falloff = pt_spot_falloff(dot(light.direction.xyz, -l), light.cone.x, light.cone.y);
        }
        var window = 1.0;
        if (light.direction.w > 0.0) {
            let r = d / light.direction.w;
            window = clamp(1.0 - r * r * r * r, 0.0, 1.0);
        }
        e = intensity * falloff * window / d2;
        target_point = light.position.xyz;
    }
    let ndl = dot(n, l);
    if (ndl <= 0.0 || e <= 0.0) {
        return PtPunctual(vec3<f32>(0.0), target_point);
    }
    let f = brdf_eval(n, l, v, c, di, si, sp);
    return PtPunctual(f * light.color.rgb * e * ndl, target_point);
}

// The sky (`scene::sky::SkySampler`): an equirectangular image (texel (x, y) covers
// φ ∈ 2π[x, x+1)/w, θ ∈ π[y, y+1)/h from +Y, the centre looks along −Z, rotated about +Y) or
// a constant colour.
fn pt_sky_direction(u: f32, v: f32) -> vec3<f32> {
    let phi = 2.0 * PI * u - PI + pt_shade.sky.w;
    let theta = PI * v;
    return vec3<f32>(sin(theta) * sin(phi), cos(theta), -sin(theta) * cos(phi));
}

fn pt_sky_texel(d: vec3<f32>) -> u32 {
    let w = pt_shade.counts.z;
    let h = pt_shade.counts.w;
    let phi = atan2(d.x, -d.z) - pt_shade.sky.w + PI;
    let u = phi / (2.0 * PI) - floor(phi / (2.0 * PI));
    let v = acos(clamp(d.y, -1.0, 1.0)) / PI;
    let x = min(u32(u * f32(w)), w - 1u);
    let y = min(u32(v * f32(h)), h - 1u);
    return y * w + x;
}

fn pt_sky_has_image() -> bool {
    return (pt_shade.config.w & PT_SKY_IMAGE) != 0u;
}

// Radiance seen along d (pointing into the sky).
fn pt_sky_radiance(d: vec3<f32>) -> vec3<f32> {
    if (!pt_sky_has_image()) {
        return pt_shade.sky_more.xyz;
    }
    return pt_sky_texels[pt_sky_texel(d)].rgb * pt_shade.sky_more.w;
}

fn pt_luminance(c: vec3<f32>) -> f32 {
    return dot(c, vec3<f32>(0.2126, 0.7152, 0.0722));
}

// Density over solid angle of the image's sampling toward d.
fn pt_sky_pdf(d: vec3<f32>) -> f32 {
    return pt_luminance(pt_sky_texels[pt_sky_texel(d)].rgb) / pt_shade.sky_total.x;
}

// The first index of `count` running sums from `base` in the sky's tables exceeding `target_sum`.
fn pt_sky_pick(base: u32, count: u32, target_sum: f32) -> u32 {
    var lo = 0u;
    var hi = count;
    while (lo < hi) {
        let mid = (lo + hi) / 2u;
        if (pt_sky_tables[base + mid] <= target_sum) {
            lo = mid + 1u;
        } else {
            hi = mid;
        }
    }
    return min(lo, count - 1u);
}

fn pt_row_cos(y: u32, h: u32) -> f32 {
    return cos(PI * f32(y) / f32(h));
}

struct PtSkySample {
    dir: vec3<f32>,
    radiance: vec3<f32>,
    pdf: f32,
    ok: bool,
}

// A direction into the sky from a surface of normal n (`SkySampler::sample_at`): ∝ cos θ
// for a constant sky, by the image's radiance otherwise.
fn pt_sample_sky(n: vec3<f32>, u: vec2<f32>) -> PtSkySample {
    if (!pt_sky_has_image()) {
        let b = pt_onb(n);
        let r = sqrt(u.x);
        let phi = 2.0 * PI * u.y;
        let c = sqrt(max(1.0 - u.x, 0.0));
        let d = normalize(b[0] * (r * cos(phi)) + b[1] * (r * sin(phi)) + n * c);
        let pdf = max(dot(n, d), 0.0) / PI;
        return PtSkySample(d, pt_sky_radiance(d), pdf, pdf > 0.0);
    }
    let total = pt_shade.sky_total.x;
    if (total <= 0.0) {
        return PtSkySample(vec3<f32>(0.0, 1.0, 0.0), vec3<f32>(0.0), 0.0, false);
    }
    let w = pt_shade.counts.z;
    let h = pt_shade.counts.w;
    let marginal = w * h;
    let y = pt_sky_pick(marginal, h, u.x * total);
    var row_start = 0.0;
    if (y > 0u) {
        row_start = pt_sky_tables[marginal + y - 1u];
    }
    let row_total = pt_sky_tables[marginal + y] - row_start;
    let x = pt_sky_pick(y * w, w, u.y * row_total);
    let fy = clamp((u.x * total - row_start) / max(row_total, 1e-30), 0.0, 0.999999);
    var before_x = 0.0;
    if (x > 0u) {
        before_x = pt_sky_tables[y * w + x - 1u];
    }
    let fx = clamp((u.y * row_total - before_x) / max(pt_sky_tables[y * w + x] - before_x, 1e-30), 0.0, 0.999999);
    let c0 = pt_row_cos(y, h);
    let c1 = pt_row_cos(y + 1u, h);
    let v = acos(clamp(c0 + fy * (c1 - c0), -1.0, 1.0)) / PI;
    let d = pt_sky_direction((f32(x) + fx) / f32(w), clamp(v, 0.0, 0.999999));
    let pdf = pt_sky_pdf(d);
    return PtSkySample(d, pt_sky_radiance(d), pdf, pdf > 0.0);
}

// A right-handed orthonormal pair about the unit n (Duff et al. 2017, glam's
// `any_orthonormal_vector`, as the path tracer's `onb`).
fn pt_onb(n: vec3<f32>) -> array<vec3<f32>, 2> {
    let sign = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    let t = vec3<f32>(b, sign + n.y * n.y * a, -n.y);
    return array<vec3<f32>, 2>(t, cross(n, t));
}
