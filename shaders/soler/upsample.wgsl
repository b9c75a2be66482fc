// Continuous combination of the mip levels (Soler et al. 004 §4): starting from the coarsest
// gathered level, the accumulated light is up-sampled to the next finer level by joint
// bilateral upsampling (soler/jbu.wgsl: bilinear weights of the four coarse texels times
// gaussians of the relative depth difference and of 1 − n·n_c; background texels take no
// part), and that level's own gathered light is added. Where every weight vanishes (a thin
// feature no coarse texel resembles) the most similar valid coarse texel gives its light, so
// that light never comes from the background. soler/resolve.wgsl reflects the
// full-resolution irradiance with c·DI/π. CPU twin: cpu::soler::{coarse_footprint, upsample}.
#import soler/common.wgsl
#import soler/jbu.wgsl

// Rust twin: passes::soler::upsample::UpsampleParams.
struct UpsampleParams {
    // x: σ depth (relative), y: σ normal (on 1 − n·n), z: 1 when the fine level has its own
    // gathered light to add, w: unused
    sigma: vec4<f32>,
}

@group(0) @binding(0) var<uniform> params: UpsampleParams;
@group(0) @binding(1) var fine_position: texture_2d<f32>;
@group(0) @binding(2) var fine_normal: texture_2d<f32>;
@group(0) @binding(3) var fine_light: texture_2d<f32>;
@group(0) @binding(4) var coarse_position: texture_2d<f32>;
@group(0) @binding(5) var coarse_normal: texture_2d<f32>;
@group(0) @binding(6) var coarse_light: texture_2d<f32>;
@group(0) @binding(7) var out_light: texture_storage_2d<rgba32float, write>;

@compute @workgroup_size(8, 8, 1)
fn cs_upsample(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = textureDimensions(out_light);
    if (gid.x >= size.x || gid.y >= size.y) {
        return;
    }
    let p = vec2<i32>(gid.xy);
    let nf = textureLoad(fine_normal, p, 0);
    if (nf.w < 0.5) {
        textureStore(out_light, gid.xy, vec4<f32>(0.0));
        return;
    }
    let z = textureLoad(fine_position, p, 0).w;
    var jbu = jbu_weights(gid.xy, z, nf.xyz, coarse_position, coarse_normal, params.sigma.xy);
    var sum = vec3<f32>(0.0);
    for (var i = 0; i < 4; i = i + 1) {
        if (jbu.w[i] > 0.0) {
            sum = sum + textureLoad(coarse_light, jbu.q[i], 0).rgb * jbu.w[i];
        }
    }
    var up = vec3<f32>(0.0);
    if (jbu.best >= 0) {
        up = textureLoad(coarse_light, jbu.q[jbu.best], 0).rgb;
    }
    if (jbu.wsum > 1e-6) {
        up = sum / jbu.wsum;
    }
    var own = vec3<f32>(0.0);
    if (params.sigma.z > 0.5) {
        own = textureLoad(fine_light, p, 0).rgb;
    }
    textureStore(out_light, gid.xy, vec4<f32>(up + own, 1.0));
}
