// Explain a pixel (issue #42) for the exact-VPL reference (vpl/gather.wgsl): this batch's
// VPLs at pixel p term by term, with the same functions the gather calls (Knecht 002
// Eq. 4.7–4.9 with the full BRDF, the exact cube-face visibility), and the running average
// they are folded into (batch k weighs 1/(k+1)). cs_explain_before reads the average before
// this frame's gather, cs_explain_terms and cs_explain_after run after it. Rust side:
// passes::reference::explain.
#import common/camera.wgsl
#import common/brdf.wgsl
#import common/vpl.wgsl

// The gather's own uniform (vpl/gather.wgsl `Params`).
struct Params {
    batch: vec4<f32>,
    clip: vec4<f32>,
    bias: vec4<f32>,
    near: vec4<f32>,
}

struct Header {
    // x, y: the pixel; z: the batch's VPL count
    pixel: vec4<u32>,
    // rgb: indirect.accum at p before this frame's gather (the previous batches' average)
    prev: vec4<f32>,
    // rgb: indirect.raw at p (this batch's sum)
    raw: vec4<f32>,
    // rgb: indirect.accum at p after it; a: the batch's weight 1/(k+1)
    accum: vec4<f32>,
}

// One VPL's term (passes::reference::explain::GpuTerm; the flags as knecht's).
struct Term {
    // x: slot; y: flags (1 empty, 4 facing, 8 near field, 16 occluded, 64 d_min clamp)
    slot: vec4<u32>,
    // rgb: its light at p with visibility; a: visibility
    light: vec4<f32>,
    // rgb: without visibility; a: the geometry term
    unshadowed: vec4<f32>,
    // x: f_y (lum), y: f_x (lum), z: the face's stored depth, w: the receiver's
    detail: vec4<f32>,
}

@group(0) @binding(0) var<uniform> camera: Camera;
@group(0) @binding(1) var<uniform> params: Params;
@group(0) @binding(2) var<storage, read> vpls: array<Vpl>;
@group(0) @binding(3) var atlas: texture_depth_2d;
@group(0) @binding(4) var g_position: texture_2d<f32>;
@group(0) @binding(5) var g_normal: texture_2d<f32>;
@group(0) @binding(6) var g_albedo: texture_2d<f32>;
@group(0) @binding(7) var g_material: texture_2d<f32>;
@group(0) @binding(8) var accum: texture_2d<f32>;
@group(0) @binding(9) var raw: texture_2d<f32>;
@group(0) @binding(10) var<storage, read_write> header: Header;
@group(0) @binding(11) var<storage, read_write> terms: array<Term>;

@compute @workgroup_size(1, 1, 1)
fn cs_explain_before() {
    header.prev = textureLoad(accum, vec2<i32>(header.pixel.xy), 0);
}

@compute @workgroup_size(1, 1, 1)
fn cs_explain_after() {
    let p = vec2<i32>(header.pixel.xy);
    header.raw = textureLoad(raw, p, 0);
    header.accum = vec4<f32>(textureLoad(accum, p, 0).rgb, params.batch.w);
    header.pixel.z = u32(params.batch.x);
}

@compute @workgroup_size(64, 1, 1)
fn cs_explain_terms(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if (i >= u32(params.batch.x)) {
        return;
    }
    var term: Term;
    term.slot = vec4<u32>(i, 0u, 0u, 0u);
    let p = vec2<i32>(header.pixel.xy);
    let nrm = textureLoad(g_normal, p, 0);
    let vpl = vpls[i];
    if (vpl.position.w < 0.5 || nrm.w < 0.5) {
        term.slot.y = 1u;
        terms[i] = term;
        return;
    }
    let x = textureLoad(g_position, p, 0).xyz;
    let nx = normalize(nrm.xyz);
    let alb = textureLoad(g_albedo, p, 0);
    let mat = textureLoad(g_material, p, 0);
    let dmin2 = params.clip.w * params.clip.w;
    let si = select(mat.x, 0.0, params.bias.w > 0.5);
    let m = vec3<f32>(alb.a, si, mat.y);
    let l = vpl_radiance(vpl, x, nx, camera.position.xyz, alb.rgb, m, dmin2, params.near.x);
    let w = vpl.position.xyz - x;
    let d2 = dot(w, w);
    let dir = w * inverseSqrt(max(d2, 1e-12));
    let cos_x = dot(nx, dir);
    let cos_y = -dot(vpl.normal.xyz, dir);
    var flags = 0u;
    if (d2 < params.near.x) {
        flags = flags | 8u;
    } else if (cos_x <= 0.0 || cos_y <= 0.0) {
        flags = flags | 4u;
    }
    if (d2 < dmin2) {
        flags = flags | 64u;
    }
    var vis = 1.0;
    var depths = vec2<f32>(0.0);
    if (params.bias.z > 0.5) {
        let cols = u32(params.batch.y);
        let size = u32(params.batch.z);
        vis = vpl_exact_visibility(atlas, i, vpl, x, nx, params.clip.xyz, cols, size, params.bias.x, params.bias.y);
        depths = vpl_exact_depths(atlas, i, vpl, x, nx, params.clip.xyz, cols, size, params.bias.x, params.bias.y);
        if (vis <= 0.0 && max(l.r, max(l.g, l.b)) > 0.0) {
            flags = flags | 16u;
        }
    }
    let lum = vec3<f32>(0.2126, 0.7152, 0.0722);
    let f_y = brdf_eval(vpl.normal.xyz, vpl.incident.xyz, -dir, vpl.albedo.rgb, vpl.normal.w, vpl.flux.a, vpl.incident.w);
    let f_x = brdf_eval(nx, dir, normalize(camera.position.xyz - x), alb.rgb, m.x, m.y, m.z);
    term.slot.y = flags;
    term.light = vec4<f32>(l * select(0.0, 1.0, vis > 0.0), vis);
    term.unshadowed = vec4<f32>(l, max(cos_x, 0.0) * max(cos_y, 0.0) / max(d2, dmin2));
    term.detail = vec4<f32>(dot(f_y, lum), dot(f_x, lum), depths);
    terms[i] = term;
}
