// The splat's resolve (Gautron et al. 003, "Principle": "dividing the weighted sum of
// contributions by the sum of the weights"): E = RGB / A where some record covers the pixel,
// and the indirect light the compose adds, reflected diffusely as c·DI·E/π (as the HCB's
// splat reflects its irradiance). Pixels no record covers after the last round stay black
// (their share shows in the coverage view and the bench's counters).
#import common/fullscreen.wgsl

@group(0) @binding(0) var accum: texture_2d<f32>;
@group(0) @binding(1) var accum_plain: texture_2d<f32>;
@group(0) @binding(2) var g_albedo: texture_2d<f32>;
@group(0) @binding(3) var out_indirect: texture_storage_2d<rgba32float, write>;
@group(0) @binding(4) var out_irradiance: texture_storage_2d<rgba32float, write>;
@group(0) @binding(5) var out_plain: texture_storage_2d<rgba32float, write>;

const INV_PI: f32 = 0.31830988618;

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
    if (s.a > 0.0) {
        e = s.rgb / s.a;
    }
    if (sp.a > 0.0) {
        ep = sp.rgb / sp.a;
    }
    let alb = textureLoad(g_albedo, px, 0);
    textureStore(out_indirect, px, vec4<f32>(alb.rgb * alb.a * e * INV_PI, 1.0));
    textureStore(out_irradiance, px, vec4<f32>(e, s.a));
    textureStore(out_plain, px, vec4<f32>(ep, sp.a));
}
