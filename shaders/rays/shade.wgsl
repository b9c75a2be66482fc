// Lighting a ray's hit as the path tracers do (issue #56 points 2–3): a hit's surface read
// as the G-buffer reads it, its emission, and its direct light by next-event estimation
// (every punctual light, one emitter point, one sky direction, each tested by a shadow ray),
// twins of `cpu::pathtrace` (documented there). Shared by the GPU truth (`rays/pathtrace.wgsl`)
// and DDGI's probe trace (`ddgi/trace.wgsl`), so that a probe's ray sees the light the truth
// sees. Group 0, bindings 0–4 (`passes::rays::shade::ShadeLights`).

#import common/brdf.wgsl
#import rays/scene.wgsl
#import rays/lights.wgsl

// `passes::rays::shade::PtShade`.
struct PtShade {
    // Ray offset ε (x).
    eps: vec4<f32>,
    // Lights, emitters, sky image width and height.
    counts: vec4<u32>,
    // 0, 0, 0, flags (PT_SKY_*).
    config: vec4<u32>,
    // Sky: 0, 0, 0, rotation about +Y (radians).
    sky: vec4<f32>,
    // Constant sky radiance (xyz), the image's intensity (w).
    sky_more: vec4<f32>,
    // The image's table total (x).
    sky_total: vec4<f32>,
}

const PT_SKY_LIT: u32 = 1u;
const PT_SKY_BACKGROUND: u32 = 2u;
const PT_SKY_IMAGE: u32 = 4u;

@group(0) @binding(0) var<storage, read> pt_shade: PtShade;
@group(0) @binding(1) var<storage, read> pt_lights: array<PtLight>;
@group(0) @binding(2) var<storage, read> pt_emitters: array<PtEmitter>;
@group(0) @binding(3) var<storage, read> pt_sky_texels: array<vec4<f32>>;
// The sky image's rows' running sums (w·h, row-major), then the rows' (h).
@group(0) @binding(4) var<storage, read> pt_sky_tables: array<f32>;

// PCG (O'Neill 2014), 32-bit state: uniform in [0, 1) with 24 bits.
fn pt_rand(state: ptr<function, u32>) -> f32 {
    let s = *state;
    *state = s * 747796405u + 2891336453u;
    let w = ((s >> ((s >> 28u) + 4u)) ^ s) * 277803737u;
    return f32(((w >> 22u) ^ w) >> 8u) / 16777216.0;
}

fn pt_hash(v: u32) -> u32 {
    let s = v * 747796405u + 2891336453u;
    let w = ((s >> ((s >> 28u) + 4u)) ^ s) * 277803737u;
    return (w >> 22u) ^ w;
}

// A surface point with its material read as the G-buffer reads it (the path tracer's `Hit`).
struct PtSurface {
    p: vec3<f32>,
    n: vec3<f32>,
    uv: vec2<f32>,
    material: u32,
    c: vec3<f32>,
    di: f32,
    si: f32,
    sp: f32,
    // The pixel's ∂uv/∂x (xy) and ∂uv/∂y (zw) at a camera hit, zero elsewhere (level 0).
    duv: vec4<f32>,
}

// A texture at a hit: trilinear at the footprint's level (`duv` ≠ 0, a camera hit), else
// bilinear at level 0 (`PathTracer::read`).
fn pt_read(entry: u32, uv: vec2<f32>, duv: vec4<f32>, srgb: bool) -> vec4<f32> {
    if (all(duv == vec4<f32>(0.0))) {
        return ray_sample_level(entry, uv, srgb);
    }
    let e = ray_textures[entry];
    let size = vec2<f32>(f32(e.width), f32(e.height));
    let rho = max(length(duv.xy * size), length(duv.zw * size));
    var lod = 0.0;
    if (rho > 0.0 && rho < 3.4e38) {
        lod = log2(rho);
    }
    return ray_sample(entry, uv, lod, srgb);
}

// SP = 2 / α² − 2 with α = roughness², clamped to [1, 4096] (`scene::specular_power`).
fn pt_specular_power(roughness: f32) -> f32 {
    let a = max(pow(clamp(roughness, 0.0, 1.0), 2.0), 1e-3);
    return clamp(2.0 / (a * a) - 2.0, 1.0, 4096.0);
}

// The surface `s` of a hit (`ray_surface`), its material read (`PathTracer::intersect` and
// `Material::intensities_at`).
fn pt_surface(s: RaySurface, duv: vec4<f32>) -> PtSurface {
    let m = ray_materials[s.material];
    var c = m.base_color.rgb;
    if (m.textures.x != RAY_NO_TEXTURE) {
        c = c * pt_read(m.textures.x, s.uv, duv, true).rgb;
    }
    var metallic = clamp(m.factors.x, 0.0, 1.0);
    var roughness = clamp(m.factors.y, 0.0, 1.0);
    var lum_of = m.base_color.rgb;
    if (m.textures.w != RAY_NO_TEXTURE) {
        let mr = pt_read(m.textures.w, s.uv, duv, false);
        metallic = clamp(m.factors.x * mr.z, 0.0, 1.0);
        roughness = clamp(m.factors.y * mr.y, 0.0, 1.0);
        lum_of = c;
    }
    var si = m.factors.w;
    if (si < 0.0) {
        si = 0.04 * (1.0 - metallic) + pt_luminance(lum_of) * metallic;
    }
    var n = s.n;
    if (m.textures.z != RAY_NO_TEXTURE) {
        let geo = s.vertex_normal;
        let tan = s.tangent;
        if (any(geo != vec3<f32>(0.0)) && dot(tan.xyz, tan.xyz) > 1e-12 && tan.w != 0.0) {
            let sign = select(1.0, -1.0, tan.w < 0.0);
            let tx = ray_normalize_or_zero(tan.xyz - geo * dot(geo, tan.xyz));
            let b = cross(geo, tx) * sign;
            var t = pt_read(m.textures.z, s.uv, duv, false).xyz * 2.0 - vec3<f32>(1.0);
            t = vec3<f32>(t.x * m.emissive.w, t.y * m.emissive.w, t.z);
            let bent = ray_normalize_or_zero(tx * t.x + b * t.y + geo * t.z);
            if (any(bent != vec3<f32>(0.0))) {
                n = select(bent, -bent, dot(geo, s.n) < 0.0);
            }
        }
    }
    return PtSurface(s.p, n, s.uv, s.material, c, 1.0 - metallic, si, pt_specular_power(roughness), duv);
}

// Emitted radiance at a surface (the camera's first hit shows it).
fn pt_emission(s: PtSurface) -> vec3<f32> {
    let m = ray_materials[s.material];
    var e = m.emissive.rgb;
    if (m.textures.y != RAY_NO_TEXTURE) {
        e = e * pt_read(m.textures.y, s.uv, s.duv, true).rgb;
    }
    return e;
}

// Direct light at a surface seen from v (`PathTracer::direct`): every punctual light, one
// emitter point and one sky direction, each unoccluded. The shadow rays go through one call
// of `ray_trace` in a loop over the candidates: a GPU compiler inlines every call of the walk,
// and lavapipe's LLVM took about 20 s for the kernel with a call per kind of light.
fn pt_direct(s: PtSurface, v: vec3<f32>, rng: ptr<function, u32>) -> vec3<f32> {
    let eps = pt_shade.eps.x;
    let origin = s.p + s.n * eps;
    let lights = pt_shade.counts.x;
    var eu = vec3<f32>(0.0);
    if (pt_shade.counts.y > 0u) {
        eu = vec3<f32>(pt_rand(rng), pt_rand(rng), pt_rand(rng));
    }
    var su = vec2<f32>(0.0);
    if ((pt_shade.config.w & PT_SKY_LIT) != 0u) {
        su = vec2<f32>(pt_rand(rng), pt_rand(rng));
    }
    var sum = vec3<f32>(0.0);
    for (var k = 0u; k < lights + 2u; k = k + 1u) {
        // The candidate's light, and the segment a shadow ray tests (tmax < 0: no test, as
        // `PathTracer::occluded` skips segments shorter than 2ε).
        var light = vec3<f32>(0.0);
        var dir = vec3<f32>(0.0, 1.0, 0.0);
        var tmin = eps;
        var tmax = -1.0;
        var to = vec3<f32>(0.0);
        var has_end = false;
        if (k < lights) {
            let r = pt_punctual(pt_lights[k], s.p, s.n, v, s.c, s.di, s.si, s.sp);
            light = r.radiance;
            to = r.target_point;
            has_end = true;
        } else if (k == lights && pt_shade.counts.y > 0u) {
            let e = pt_sample_emitter(eu, pt_shade.counts.y);
            let w = e.position - s.p;
            let d2 = dot(w, w);
            let l = w / max(sqrt(d2), 1e-12);
            let cos_x = dot(s.n, l);
            let cos_y = -dot(e.normal, l);
            if (cos_x > 0.0 && cos_y > 0.0 && d2 > 0.0) {
                light = e.radiance * brdf_eval(s.n, l, v, s.c, s.di, s.si, s.sp) * (cos_x * cos_y / (d2 * e.pdf_area));
                to = e.position;
                has_end = true;
            }
        } else if (k == lights + 1u && (pt_shade.config.w & PT_SKY_LIT) != 0u) {
            let q = pt_sample_sky(s.n, su);
            let cos_x = dot(s.n, q.dir);
            if (q.ok && cos_x > 0.0) {
                light = q.radiance * brdf_eval(s.n, q.dir, v, s.c, s.di, s.si, s.sp) * (cos_x / q.pdf);
                dir = q.dir;
                tmin = 0.0;
                tmax = 3.4e38;
            }
        }
        if (all(light == vec3<f32>(0.0))) {
            continue;
        }
        if (has_end) {
            let d = to - origin;
            let len = length(d);
            if (len > 2.0 * eps) {
                dir = d / len;
                tmax = len - eps;
            }
        }
        if (tmax < 0.0 || !ray_trace(origin, dir, tmin, tmax, RAY_ANY).hit) {
            sum = sum + light;
        }
    }
    return sum;
}

// A direction from the BRDF mixture and its weight f·cos/pdf (`PathTracer::sample_brdf`);
// w = 0 when none.
struct PtBounce {
    l: vec3<f32>,
    weight: vec3<f32>,
    ok: bool,
}

fn pt_sample_brdf(s: PtSurface, v: vec3<f32>, rng: ptr<function, u32>) -> PtBounce {
    let none = PtBounce(vec3<f32>(0.0), vec3<f32>(0.0), false);
    let wd = s.di * pt_luminance(s.c);
    let ws = max(s.si, 0.0);
    if (wd + ws <= 0.0) {
        return none;
    }
    let pd = wd / (wd + ws);
    let b = pt_onb(s.n);
    let u1 = pt_rand(rng);
    let u2 = pt_rand(rng);
    var l: vec3<f32>;
    if (pt_rand(rng) < pd) {
        let r = sqrt(u1);
        let phi = 2.0 * PI * u2;
        l = normalize(b[0] * (r * cos(phi)) + b[1] * (r * sin(phi)) + s.n * sqrt(max(1.0 - u1, 0.0)));
    } else {
        let ct = pow(u1, 1.0 / (s.sp + 1.0));
        let st = sqrt(max(1.0 - ct * ct, 0.0));
        let phi = 2.0 * PI * u2;
        let hv = normalize(b[0] * (st * cos(phi)) + b[1] * (st * sin(phi)) + s.n * ct);
        l = 2.0 * dot(v, hv) * hv - v;
    }
    let ndl = dot(s.n, l);
    if (ndl <= 0.0) {
        return none;
    }
    let hv = ray_normalize_or_zero(l + v);
    let ndh = max(dot(s.n, hv), 0.0);
    let vdh = max(abs(dot(v, hv)), 1e-6);
    let pdf_d = ndl / PI;
    let pdf_s = (s.sp + 1.0) / (2.0 * PI) * pow(ndh, s.sp) / (4.0 * vdh);
    let pdf = pd * pdf_d + (1.0 - pd) * pdf_s;
    if (pdf <= 0.0) {
        return none;
    }
    return PtBounce(l, brdf_eval(s.n, l, v, s.c, s.di, s.si, s.sp) * ndl / pdf, true);
}
