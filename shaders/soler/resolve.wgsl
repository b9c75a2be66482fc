// The receiver reflects the combined irradiance of every level diffusely (Soler et al. 004
// Fig. 4: "multiplied by the albedo buffer"): c·DI/π · E, the indirect light compose adds;
// with the glossy reflection (004 §4 "Screen-space importance sampling") its upsampled
// specular light is added (flags.x), the last reflection before the camera.
const PI: f32 = 3.14159265358979;

@group(0) @binding(0) var resolve_light: texture_2d<f32>;
@group(0) @binding(1) var g_albedo: texture_2d<f32>;
@group(0) @binding(2) var out_radiance: texture_storage_2d<rgba32float, write>;
@group(0) @binding(3) var resolve_specular: texture_2d<f32>;
// x: 1 adds resolve_specular; y, z, w: unused
@group(0) @binding(4) var<uniform> flags: vec4<u32>;

@compute @workgroup_size(8, 8, 1)
fn cs_resolve(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = textureDimensions(out_radiance);
    if (gid.x >= size.x || gid.y >= size.y) {
        return;
    }
    let e = textureLoad(resolve_light, vec2<i32>(gid.xy), 0).rgb;
    let alb = textureLoad(g_albedo, vec2<i32>(gid.xy), 0);
    var out = alb.rgb * alb.a / PI * e;
    if (flags.x != 0u) {
        out = out + textureLoad(resolve_specular, vec2<i32>(gid.xy), 0).rgb;
    }
    textureStore(out_radiance, gid.xy, vec4<f32>(out, 1.0));
}
