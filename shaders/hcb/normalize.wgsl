// Eq. 11 of Nguyen et al.: each pixel's irradiance is Σ w E / Σ w of the samples coherent
// to it (`hcb.irradiance`, a = 1), and its indirect light the reflection of it
// (`hcb.indirect`): c·DI/π · E as printed, or with `hcb.receiver` = Glossy also the specular
// lobe lit from the samples' mean incident direction, Σ w·dir / Σ w over lum(E)
// (⚠[nguyen.glossy-receiver], common/receiver.wgsl). A covered pixel no sample reaches keeps
// a = 0 and is counted, so that it is shown, never silently black: `uncovered` holds the
// count, then the first UNCOVERED_LIST of those pixels as x | y << 16 (in no particular
// order), which the overlay reads back instead of two whole images (issue #38).
#import hcb/common.wgsl
#import common/receiver.wgsl

@group(0) @binding(0) var accum: texture_2d<f32>;
@group(0) @binding(1) var g_normal: texture_2d<f32>;
@group(0) @binding(2) var out_light: texture_storage_2d<rgba32float, write>;
@group(0) @binding(3) var<storage, read_write> uncovered: array<atomic<u32>>;
@group(0) @binding(4) var g_albedo: texture_2d<f32>;
@group(0) @binding(5) var out_radiance: texture_storage_2d<rgba32float, write>;
@group(0) @binding(6) var accum_dir: texture_2d<f32>;
@group(0) @binding(7) var g_position: texture_2d<f32>;
@group(0) @binding(8) var g_material: texture_2d<f32>;
@group(0) @binding(9) var<uniform> hp: HcbParams;

// Rust twin: passes::hcb::UNCOVERED_LIST.
const UNCOVERED_LIST: u32 = 65536u;

@compute @workgroup_size(8, 8, 1)
fn cs_normalize(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = textureDimensions(out_light);
    if (gid.x >= size.x || gid.y >= size.y) {
        return;
    }
    let a = textureLoad(accum, gid.xy, 0);
    let nb = textureLoad(g_normal, gid.xy, 0);
    var out = vec4<f32>(0.0);
    var d = vec3<f32>(0.0);
    if (a.a > 0.0) {
        out = vec4<f32>(a.rgb / a.a, 1.0);
        d = receiver_direction(textureLoad(accum_dir, gid.xy, 0).xyz, a.rgb);
    } else if (nb.w > 0.5) {
        let i = atomicAdd(&uncovered[0], 1u);
        if (i < UNCOVERED_LIST) {
            atomicStore(&uncovered[4u + i], gid.x | (gid.y << 16u));
        }
    }
    textureStore(out_light, gid.xy, out);
    let alb = textureLoad(g_albedo, gid.xy, 0);
    var radiance = vec3<f32>(0.0);
    if (out.a > 0.0) {
        let mat = textureLoad(g_material, gid.xy, 0);
        let x = textureLoad(g_position, gid.xy, 0).xyz;
        let v = normalize(hp.eye.xyz - x);
        radiance = receive_irradiance(out.rgb, d, normalize(nb.xyz), v, alb.rgb, alb.a, mat.x, mat.y, hp.cache.y > 0.5);
    }
    textureStore(out_radiance, gid.xy, vec4<f32>(radiance, out.a));
}
