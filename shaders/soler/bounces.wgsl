// Multi-bounce (Soler et al. 004 §4 "Multi-bounce computation", §5.3): the indirect light is
// the sum of every bounce's newest result, L_1 + … + L_n (each c·DI/π · E of its bounce;
// bounce b gathered bounce b − 1's light). With alternating bounces only one of them is new
// each frame. With the glossy reflection each bounce's specular light toward the eye (kept
// apart: the next bounce gathers the diffuse light only) is added too. Unused inputs
// (count < 4) are not read.

// Rust twin: passes::soler::bounces::BounceParams.
struct BounceParams {
    // x: bounces n (1–4), y: 1 adds the specular inputs, z, w: unused
    count: vec4<u32>,
}

@group(0) @binding(0) var<uniform> params: BounceParams;
@group(0) @binding(1) var bounce1: texture_2d<f32>;
@group(0) @binding(2) var bounce2: texture_2d<f32>;
@group(0) @binding(3) var bounce3: texture_2d<f32>;
@group(0) @binding(4) var bounce4: texture_2d<f32>;
@group(0) @binding(5) var out_sum: texture_storage_2d<rgba32float, write>;
@group(0) @binding(6) var specular1: texture_2d<f32>;
@group(0) @binding(7) var specular2: texture_2d<f32>;
@group(0) @binding(8) var specular3: texture_2d<f32>;
@group(0) @binding(9) var specular4: texture_2d<f32>;
// The specular part of out_sum alone (what Eq. 6 keeps out of its irradiance blend,
// passes::soler::TemporalQuantity::Irradiance); written when params.count.y != 0.
@group(0) @binding(10) var out_specular: texture_storage_2d<rgba32float, write>;

@compute @workgroup_size(8, 8, 1)
fn cs_sum(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = textureDimensions(out_sum);
    if (gid.x >= size.x || gid.y >= size.y) {
        return;
    }
    let p = vec2<i32>(gid.xy);
    let n = params.count.x;
    var sum = textureLoad(bounce1, p, 0).rgb;
    if (n > 1u) {
        sum = sum + textureLoad(bounce2, p, 0).rgb;
    }
    if (n > 2u) {
        sum = sum + textureLoad(bounce3, p, 0).rgb;
    }
    if (n > 3u) {
        sum = sum + textureLoad(bounce4, p, 0).rgb;
    }
    if (params.count.y != 0u) {
        var spec = textureLoad(specular1, p, 0).rgb;
        if (n > 1u) {
            spec = spec + textureLoad(specular2, p, 0).rgb;
        }
        if (n > 2u) {
            spec = spec + textureLoad(specular3, p, 0).rgb;
        }
        if (n > 3u) {
            spec = spec + textureLoad(specular4, p, 0).rgb;
        }
        sum = sum + spec;
        textureStore(out_specular, gid.xy, vec4<f32>(spec, 1.0));
    }
    textureStore(out_sum, gid.xy, vec4<f32>(sum, 1.0));
}
