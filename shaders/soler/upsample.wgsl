// Continuous combination of the mip levels (Soler et al. 004 §4): starting from the coarsest
// gathered level, the accumulated light is up-sampled to the next finer level by joint
// bilateral upsampling (Kopf et al.: bilinear weights of the four coarse texels times
// gaussians of the relative depth difference and of 1 − n·n_c; background texels take no
// part), and that level's own gathered light is added. Where every weight vanishes (a thin
// feature no coarse texel resembles) the most similar valid coarse texel gives its light, so
// that light never comes from the background. soler/resolve.wgsl reflects the
// full-resolution irradiance with c·DI/π. CPU twin: cpu::soler::{coarse_footprint, upsample}.
#import soler/common.wgsl

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
    let c = (vec2<f32>(gid.xy) + 0.5) * 0.5 - 0.5;
    let q0 = floor(c);
    let f = c - q0;
    let csize = textureDimensions(coarse_position);
    var sum = vec3<f32>(0.0);
    var wsum = 0.0;
    var best = 0.0;
    var best_light = vec3<f32>(0.0);
    for (var j = 0; j < 4; j = j + 1) {
        let o = vec2<i32>(j % 2, j / 2);
        let q = vec2<i32>(q0) + o;
        if (!inside(q, csize)) {
            continue;
        }
        let nc = textureLoad(coarse_normal, q, 0);
        if (nc.w < 0.5) {
            continue;
        }
        let zc = textureLoad(coarse_position, q, 0).w;
        let bx = select(1.0 - f.x, f.x, o.x == 1);
        let by = select(1.0 - f.y, f.y, o.y == 1);
        let range = gaussian((zc - z) / z, params.sigma.x) * gaussian(1.0 - dot(nf.xyz, nc.xyz), params.sigma.y);
        let light = textureLoad(coarse_light, q, 0).rgb;
        sum = sum + light * bx * by * range;
        wsum = wsum + bx * by * range;
        if (range > best) {
            best = range;
            best_light = light;
        }
    }
    var up = best_light;
    if (wsum > 1e-6) {
        up = sum / wsum;
    }
    var own = vec3<f32>(0.0);
    if (params.sigma.z > 0.5) {
        own = textureLoad(fine_light, p, 0).rgb;
    }
    textureStore(out_light, gid.xy, vec4<f32>(up + own, 1.0));
}
