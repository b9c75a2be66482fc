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
#import reference/gather_params.wgsl

@group(0) @binding(0) var<uniform> camera: Camera;
@group(0) @binding(1) var<uniform> params: Params;
@group(0) @binding(2) var<storage, read> vpls: array<Vpl>;
@group(0) @binding(3) var atlas: texture_2d<f32>;
@group(0) @binding(4) var g_position: texture_2d<f32>;
@group(0) @binding(5) var g_normal: texture_2d<f32>;
@group(0) @binding(6) var g_albedo: texture_2d<f32>;
@group(0) @binding(7) var g_material: texture_2d<f32>;
@group(0) @binding(8) var accum_prev: texture_2d<f32>;
@group(0) @binding(9) var out_raw: texture_storage_2d<rgba32float, write>;
@group(0) @binding(10) var out_accum: texture_storage_2d<rgba32float, write>;

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
        let count = u32(params.batch.x);
        let dmin2 = params.clip.w * params.clip.w;
        for (var i = 0u; i < count; i = i + 1u) {
            let vpl = vpls[i];
            if (vpl.position.w < 0.5) {
                continue;
            }
            if (params.bias.z > 0.5) {
                let vis = vpl_exact_visibility(atlas, i, vpl, x, nx, params.clip.xyz, u32(params.batch.y), u32(params.batch.z), params.bias.x, params.bias.y);
                if (vis <= 0.0) {
                    continue;
                }
            }
            let si = select(mat.x, 0.0, params.bias.w > 0.5);
            sum = sum + vpl_radiance(vpl, x, nx, camera.position.xyz, alb.rgb, vec3<f32>(alb.a, si, mat.y), dmin2, params.near.x);
        }
    }
    textureStore(out_raw, px, vec4<f32>(sum, 1.0));
    let prev = textureLoad(accum_prev, px, 0).rgb;
    textureStore(out_accum, px, vec4<f32>(mix(prev, sum, params.batch.w), 1.0));
}
