// Irradiance splatting (Gautron et al. 003, "From Octree to Splatting": "Principle"): each
// record is drawn as the screen-aligned quad that bounds its sphere of influence (radius
// a·R_k, inside which the simplified weight R_k/‖P − P_k‖ exceeds 1/a); the quad is the exact
// bound of the sphere's perspective image (the tangent planes through the eye in x and in y;
// the text's TransformVertex is exact only on the view axis), the whole screen when the
// sphere reaches the near plane. The fragment evaluates Ward's full weight at the visible
// point, discards below 1/a, and outputs RGB = w·E_k(extrapolated), A = w, added by the
// blending into float targets (target 0 with the gradients as set, target 1 without any).
// Twin: cpu::gautron::{sphere_ndc_rect, accumulate}.
#import gautron/common.wgsl
#import common/camera.wgsl

@group(0) @binding(0) var<uniform> params: GautronParams;
@group(0) @binding(1) var<uniform> camera: Camera;
@group(0) @binding(2) var<storage, read> records: array<Record>;
@group(0) @binding(3) var g_position: texture_2d<f32>;
@group(0) @binding(4) var g_normal: texture_2d<f32>;

struct SplatOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) @interpolate(flat) index: u32,
}

// The NDC interval [lo, hi] of a circle (centre (c, d) with d the distance in front of the
// eye, radius ρ) seen from the eye along one axis; scale is P00 or P11.
fn tangent_interval(c: f32, d: f32, rho: f32, scale: f32) -> vec2<f32> {
    let k = d * d - rho * rho;
    let root = sqrt(max(c * c + k, 0.0));
    let lo = (c * d - rho * root) / k;
    let hi = (c * d + rho * root) / k;
    return vec2<f32>(lo, hi) * scale;
}

@vertex
fn vs_splat(@builtin(vertex_index) vi: u32, @builtin(instance_index) index: u32) -> SplatOut {
    var o: SplatOut;
    o.index = index;
    let rec = records[index];
    if (rec.pixel.w < 0.5) {
        o.clip = vec4<f32>(0.0, 0.0, 0.0, 1.0);
        return o;
    }
    let rho = params.weight.x * rec.position.w;
    let c = (camera.view * vec4<f32>(rec.position.xyz, 1.0)).xyz;
    let d = -c.z;
    var rect = vec4<f32>(-1.0, -1.0, 1.0, 1.0);
    if (d - rho > camera.params.x) {
        let x = tangent_interval(c.x, d, rho, params.misc.y);
        let y = tangent_interval(c.y, d, rho, params.misc.z);
        // half a pixel more on every side: a sphere smaller than a pixel (R_k clamped to
        // ~1 px, the brute force of the bench) still reaches its own pixel's centre despite
        // the rounding of its position
        let half_px = vec2<f32>(1.0) / camera.viewport.xy;
        rect = vec4<f32>(x.x - half_px.x, y.x - half_px.y, x.y + half_px.x, y.y + half_px.y);
        rect = vec4<f32>(max(rect.xy, vec2<f32>(-1.0)), min(rect.zw, vec2<f32>(1.0)));
    }
    // two triangles: (0, 0) (1, 0) (0, 1) · (0, 1) (1, 0) (1, 1)
    let corners = array<vec2<f32>, 6>(
        vec2<f32>(0.0, 0.0), vec2<f32>(1.0, 0.0), vec2<f32>(0.0, 1.0),
        vec2<f32>(0.0, 1.0), vec2<f32>(1.0, 0.0), vec2<f32>(1.0, 1.0),
    );
    let q = corners[vi % 6u];
    o.clip = vec4<f32>(mix(rect.xy, rect.zw, q), 0.0, 1.0);
    return o;
}

struct SplatTargets {
    @location(0) weighted: vec4<f32>,
    @location(1) plain: vec4<f32>,
}

@fragment
fn fs_splat(i: SplatOut) -> SplatTargets {
    let px = vec2<i32>(i.clip.xy);
    let nrm = textureLoad(g_normal, px, 0);
    if (nrm.w < 0.5) {
        discard;
    }
    let p = textureLoad(g_position, px, 0).xyz;
    let n = normalize(nrm.xyz);
    let rec = records[i.index];
    let w = ward_weight(rec, p, n, params.weight.y);
    if (w <= 1.0 / params.weight.x) {
        discard;
    }
    var o: SplatTargets;
    let e = extrapolate(rec, p, n, params.weight.z > 0.5, params.weight.w > 0.5);
    o.weighted = vec4<f32>(w * e, w);
    o.plain = vec4<f32>(w * rec.irradiance.rgb, w);
    return o;
}
