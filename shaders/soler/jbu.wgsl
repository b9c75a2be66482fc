// The joint bilateral upsampling's weights (Soler et al. 004 §4 "Continuous combination", after
// Kopf et al.): fine texel p (view depth z, normal nf) takes the four coarse texels around
// (p + 0.5)/2 − 0.5 with bilinear weights times gaussians of the relative depth difference and
// of 1 − n·n_c; background texels take no part. Shared by the upsampling (soler/upsample.wgsl)
// and its replay when a pixel is explained (soler/explain.wgsl). Needs soler/common.wgsl.
// CPU twin: cpu::soler::{coarse_footprint, upsample}.

struct Jbu {
    // The four coarse texels.
    q: array<vec2<i32>, 4>,
    // Their weights bilinear × range (0 where outside or background).
    w: vec4<f32>,
    // Their range weights alone (the fallback's similarity).
    range: vec4<f32>,
    // Σ w, and the texel with the largest range weight (−1: none above 0), whose light is
    // taken where Σ w vanishes.
    wsum: f32,
    best: i32,
}

fn jbu_weights(p: vec2<u32>, z: f32, nf: vec3<f32>, coarse_position: texture_2d<f32>, coarse_normal: texture_2d<f32>, sigma: vec2<f32>) -> Jbu {
    var j: Jbu;
    j.w = vec4<f32>(0.0);
    j.range = vec4<f32>(0.0);
    j.wsum = 0.0;
    j.best = -1;
    let c = (vec2<f32>(p) + 0.5) * 0.5 - 0.5;
    let q0 = floor(c);
    let f = c - q0;
    let csize = textureDimensions(coarse_position);
    var best = 0.0;
    for (var i = 0; i < 4; i = i + 1) {
        let o = vec2<i32>(i % 2, i / 2);
        let q = vec2<i32>(q0) + o;
        j.q[i] = q;
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
        let range = gaussian((zc - z) / z, sigma.x) * gaussian(1.0 - dot(nf, nc.xyz), sigma.y);
        j.w[i] = bx * by * range;
        j.range[i] = range;
        j.wsum = j.wsum + bx * by * range;
        if (range > best) {
            best = range;
            j.best = i;
        }
    }
    return j;
}
