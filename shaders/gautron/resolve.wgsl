// The splat's resolve (Gautron et al. 003, "Principle": "dividing the weighted sum of
// contributions by the sum of the weights"): E = RGB / A where some record covers the pixel,
// and the indirect light the compose adds: the text's diffuse reflection c·DI·E/π, or with
// `gautron.receiver` = Glossy also the specular lobe lit from the records' mean incident
// direction, Σ w·dir / Σ w over lum(E) (⚠[gautron.glossy-receiver], common/receiver.wgsl).
// Pixels no record covers after the last round stay black (their share shows in the coverage
// view and the bench's counters).
#import common/fullscreen.wgsl
#import gautron/common.wgsl
#import common/camera.wgsl
#import common/receiver.wgsl

@group(0) @binding(0) var accum: texture_2d<f32>;
@group(0) @binding(1) var accum_plain: texture_2d<f32>;
@group(0) @binding(2) var g_albedo: texture_2d<f32>;
@group(0) @binding(3) var out_indirect: texture_storage_2d<rgba32float, write>;
@group(0) @binding(4) var out_irradiance: texture_storage_2d<rgba32float, write>;
@group(0) @binding(5) var out_plain: texture_storage_2d<rgba32float, write>;
@group(0) @binding(6) var accum_dir: texture_2d<f32>;
@group(0) @binding(7) var g_position: texture_2d<f32>;
@group(0) @binding(8) var g_normal: texture_2d<f32>;
@group(0) @binding(9) var g_material: texture_2d<f32>;
@group(0) @binding(10) var<uniform> params: GautronParams;
@group(0) @binding(11) var<uniform> camera: Camera;

@compute @workgroup_size(TILE, TILE, 1)
fn cs_resolve(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = textureDimensions(out_indirect);
    if (gid.x >= size.x || gid.y >= size.y) {
        return;
    }
    let px = vec2<i32>(gid.xy);
    let s = textureLoad(accum, px, 0);
    let sp = textureLoad(accum_plain, px, 0);
    var e = vec3<f32>(0.0);
    var ep = vec3<f32>(0.0);
    var d = vec3<f32>(0.0);
    if (s.a > 0.0) {
        e = s.rgb / s.a;
        // The records' own E_k weigh their directions: Σ w·dir / Σ w·lum(E_k).
        d = receiver_direction(textureLoad(accum_dir, px, 0).xyz, sp.rgb);
    }
    if (sp.a > 0.0) {
        ep = sp.rgb / sp.a;
    }
    let alb = textureLoad(g_albedo, px, 0);
    var radiance = vec3<f32>(0.0);
    let nrm = textureLoad(g_normal, px, 0);
    if (s.a > 0.0 && nrm.w > 0.5) {
        let mat = textureLoad(g_material, px, 0);
        let v = normalize(camera.position.xyz - textureLoad(g_position, px, 0).xyz);
        radiance = receive_irradiance(e, d, normalize(nrm.xyz), v, alb.rgb, alb.a, mat.x, mat.y, params.rules.y > 0.5);
    }
    textureStore(out_indirect, px, vec4<f32>(radiance, 1.0));
    textureStore(out_irradiance, px, vec4<f32>(e, s.a));
    textureStore(out_plain, px, vec4<f32>(ep, sp.a));
}
