// Stage 6 of the exact-VPL reference: every pixel gathers this batch's VPLs with exact
// visibility (stage 4's cube-face atlas) and the full BRDF at both ends,
//   L(x→eye) = Σ Φ · f(y; ω_in, y→x) · cos θ_y · f(x; x→y, v) · cos θ_x / max(d², d_min²) · V(x, y),
// (the VPL gather of Knecht 002 Eq. 4.7–4.9 without its approximations: full BRDF, exact
// visibility, and the distance clamp d_min a setting that defaults to 0), and averages the
// batches into `indirect.accum` (progressive: batch k has weight 1/(k+1)).
#import common/camera.wgsl
#import common/brdf.wgsl
#import common/vpl.wgsl
#import common/fullscreen.wgsl

struct Params {
    // x: VPL count of the batch, y: atlas columns, z: tile size, w: weight of this batch 1/(k+1)
    batch: vec4<f32>,
    // x: near, y: far, z: eye offset along the VPL normal, w: d_min (scene units)
    clip: vec4<f32>,
    // x: depth bias (texels), y: normal offset (texels), z: visibility on (1) / off (0)
    bias: vec4<f32>,
}

@group(0) @binding(0) var<uniform> camera: Camera;
@group(0) @binding(1) var<uniform> params: Params;
@group(0) @binding(2) var<storage, read> vpls: array<Vpl>;
@group(0) @binding(3) var atlas: texture_depth_2d;
@group(0) @binding(4) var g_position: texture_2d<f32>;
@group(0) @binding(5) var g_normal: texture_2d<f32>;
@group(0) @binding(6) var g_albedo: texture_2d<f32>;
@group(0) @binding(7) var g_material: texture_2d<f32>;
@group(0) @binding(8) var accum_prev: texture_2d<f32>;
@group(0) @binding(9) var out_raw: texture_storage_2d<rgba32float, write>;
@group(0) @binding(10) var out_accum: texture_storage_2d<rgba32float, write>;

// Exact visibility of x (receiver normal nx) from VPL i: one depth comparison in the face of
// its cube that sees x. Biases are world offsets of the receiver in texels of that face at
// the receiver's distance (as the primary shadow maps).
fn visibility(i: u32, vpl: Vpl, x: vec3<f32>, nx: vec3<f32>) -> f32 {
    if (params.bias.z < 0.5) {
        return 1.0;
    }
    let n = vpl.normal.xyz;
    let eye = vpl.position.xyz + n * params.clip.z;
    let size = u32(params.batch.z);
    let d = distance(x, eye);
    let texel = 2.0 * d / params.batch.z;
    let to_eye = (eye - x) / max(d, 1e-6);
    let p = x + nx * texel * params.bias.y + to_eye * texel * params.bias.x;
    let tbn = vpl_basis(n);
    let face = vpl_face_of(tbn, p - eye);
    let clip = vpl_face_clip(eye, vpl_face_axes(tbn, face), p, params.clip.x, params.clip.y);
    if (clip.w <= 0.0) {
        return 0.0;
    }
    let ndc = clip.xyz / clip.w;
    let origin = vpl_tile_origin(i * VPL_FACES + face, u32(params.batch.y), size);
    let uv = clamp(vec2<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5), vec2<f32>(0.0), vec2<f32>(1.0));
    let t = min(vec2<u32>(uv * f32(size)), vec2<u32>(size - 1u));
    let stored = textureLoad(atlas, origin + t, 0);
    return select(0.0, 1.0, ndc.z <= stored);
}

@compute @workgroup_size(TILE, TILE, 1)
fn cs_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = textureDimensions(out_raw);
    if (gid.x >= size.x || gid.y >= size.y) {
        return;
    }
    let px = vec2<i32>(gid.xy);
    var sum = vec3<f32>(0.0);
    let nrm = textureLoad(g_normal, px, 0);
    if (nrm.w > 0.5) {
        let x = textureLoad(g_position, px, 0).xyz;
        let nx = normalize(nrm.xyz);
        let alb = textureLoad(g_albedo, px, 0);
        let mat = textureLoad(g_material, px, 0);
        let v = normalize(camera.position.xyz - x);
        let count = u32(params.batch.x);
        let dmin2 = params.clip.w * params.clip.w;
        for (var i = 0u; i < count; i = i + 1u) {
            let vpl = vpls[i];
            if (vpl.position.w < 0.5) {
                continue;
            }
            let w = vpl.position.xyz - x;
            let d2 = dot(w, w);
            let l = w * inverseSqrt(max(d2, 1e-12));
            let cos_x = dot(nx, l);
            let cos_y = -dot(vpl.normal.xyz, l);
            if (cos_x <= 0.0 || cos_y <= 0.0) {
                continue;
            }
            let vis = visibility(i, vpl, x, nx);
            if (vis <= 0.0) {
                continue;
            }
            let f_y = brdf_eval(vpl.normal.xyz, vpl.incident.xyz, -l, vpl.albedo.rgb, vpl.normal.w, vpl.flux.a, vpl.incident.w);
            let f_x = brdf_eval(nx, l, v, alb.rgb, alb.a, mat.x, mat.y);
            sum = sum + vpl.flux.rgb * f_y * cos_y * f_x * cos_x / max(d2, dmin2) * vis;
        }
    }
    textureStore(out_raw, px, vec4<f32>(sum, 1.0));
    let prev = textureLoad(accum_prev, px, 0).rgb;
    textureStore(out_accum, px, vec4<f32>(mix(prev, sum, params.batch.w), 1.0));
}
