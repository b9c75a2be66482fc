// Stage 3 (Knecht 002 §4.3): the importance of every light G-buffer texel, Eq. 4.3,
//   importance = lightIntensity · (surfaceColor · lightColor) · (0.5 + SP),
// and its mip pyramid (each level the average of its 2×2 children) that hierarchical
// warping descends (knecht/vpl/warp.wgsl). Readings chosen:
// - ⚠[knecht.importance-flux] lightIntensity · lightColor is the flux the light sends through
//   the texel (common/light_view.wgsl), so that the importance is proportional to the VPL's
//   power;
// - ⚠[knecht.importance-reflectance] surfaceColor is the reflectance c·DI + SI (a black glossy
//   surface still reflects), and the product with the light colour is the mean over r, g, b;
// - ⚠[knecht.importance-power] SP is the thesis' 8-bit normalised power; ours is a Blinn-Phong
//   exponent 1…4096, so SP' = saturate(log2(SP) / 12) enters as (b + SP'),
//   b = `vpl.importance_bias` (0.5 as the thesis).
// Surfaces facing away from the light and the background have importance 0.
// CPU twin of the pyramid: cpu::knecht::Pyramid.
#import common/light_view.wgsl

@group(0) @binding(0) var<storage, read> vp: ViewParams;
@group(0) @binding(1) var<storage, read> lights: array<Light>;
@group(0) @binding(2) var lg_position: texture_2d<f32>;
@group(0) @binding(3) var lg_normal: texture_2d<f32>;
@group(0) @binding(4) var lg_albedo: texture_2d<f32>;
@group(0) @binding(5) var lg_material: texture_2d<f32>;
@group(0) @binding(6) var importance: texture_storage_2d_array<r32float, write>;

@compute @workgroup_size(8, 8, 1)
fn cs_importance(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = textureDimensions(lg_position);
    if (gid.x >= size.x || gid.y >= size.y) {
        return;
    }
    let texel = vec2<i32>(gid.xy);
    let nrm = textureLoad(lg_normal, texel, 0);
    var value = 0.0;
    if (nrm.w > 0.5) {
        let p = textureLoad(lg_position, texel, 0).xyz;
        let n = normalize(nrm.xyz);
        if (dot(n, toward_light(vp.view, p)) > 0.0) {
            let alb = textureLoad(lg_albedo, texel, 0);
            let mat = textureLoad(lg_material, texel, 0);
            let reflectance = alb.rgb * alb.a + vec3<f32>(mat.x);
            let flux = flux_per_uv(lights[vp.range.z], vp.view, p);
            let sp = clamp(log2(max(mat.y, 1.0)) / 12.0, 0.0, 1.0);
            value = dot(flux, reflectance) / 3.0 * (vp.scale.z + sp);
        }
    }
    textureStore(importance, texel, vp.range.w, vec4<f32>(value, 0.0, 0.0, 0.0));
}
