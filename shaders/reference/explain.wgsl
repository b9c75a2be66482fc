// Explain a pixel (issue #42) for the exact-VPL reference (reference/gather.wgsl): this batch's
// VPLs at pixel p term by term, with the same functions the gather calls (Knecht 002
// Eq. 4.7–4.9 with the full BRDF, the exact cube-face visibility), and the running average
// they are folded into (batch k weighs 1/(k+1)). cs_explain_before reads the average before
// this frame's gather, cs_explain_terms and cs_explain_after run after it. Rust side:
// passes::reference::explain.
#import common/camera.wgsl
#import common/brdf.wgsl
#import common/vpl.wgsl
#import common/vpl_explain.wgsl
#import reference/gather_params.wgsl

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

@group(0) @binding(0) var<uniform> camera: Camera;
@group(0) @binding(1) var<uniform> params: Params;
@group(0) @binding(2) var<storage, read> vpls: array<Vpl>;
@group(0) @binding(3) var atlas: texture_2d<f32>;
@group(0) @binding(4) var g_position: texture_2d<f32>;
@group(0) @binding(5) var g_normal: texture_2d<f32>;
@group(0) @binding(6) var g_albedo: texture_2d<f32>;
@group(0) @binding(7) var g_material: texture_2d<f32>;
@group(0) @binding(8) var accum: texture_2d<f32>;
@group(0) @binding(9) var raw: texture_2d<f32>;
@group(0) @binding(10) var<storage, read_write> header: Header;
@group(0) @binding(11) var<storage, read_write> terms: array<VplTerm>;

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
    let p = vec2<i32>(header.pixel.xy);
    let nrm = textureLoad(g_normal, p, 0);
    let vpl = vpls[i];
    if (vpl.position.w < 0.5 || nrm.w < 0.5) {
        var empty: VplTerm;
        empty.slot = vec4<u32>(i, EXPLAIN_EMPTY, 0u, 0u);
        terms[i] = empty;
        return;
    }
    let x = textureLoad(g_position, p, 0).xyz;
    let nx = normalize(nrm.xyz);
    let alb = textureLoad(g_albedo, p, 0);
    let mat = textureLoad(g_material, p, 0);
    let dmin2 = params.clip.w * params.clip.w;
    let si = select(mat.x, 0.0, params.bias.w > 0.5);
    let seen = vpl_term(vpl, x, nx, camera.position.xyz, alb.rgb, vec3<f32>(alb.a, si, mat.y), dmin2, params.near.x);
    // The gather's exact test, with the reference's own biases (reference/gather.wgsl).
    var test = vec3<f32>(1.0, 0.0, 0.0);
    if (params.bias.z > 0.5) {
        let cols = u32(params.batch.y);
        let size = u32(params.batch.z);
        let vis = vpl_exact_visibility(atlas, i, vpl, x, nx, params.clip.xyz, cols, size, params.bias.x, params.bias.y);
        test = vec3<f32>(select(0.0, 1.0, vis > 0.0), vpl_exact_depths(atlas, i, vpl, x, nx, params.clip.xyz, cols, size, params.bias.x, params.bias.y));
    }
    var term = vpl_term_seen(seen, test, 1.0);
    term.slot.x = i;
    terms[i] = term;
}
