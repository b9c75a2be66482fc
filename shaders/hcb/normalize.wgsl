// Eq. 11 of Nguyen et al.: each pixel's irradiance is Σ w E / Σ w of the samples coherent
// to it (`hcb.irradiance`, a = 1), and its indirect light the diffuse reflection of it,
// c·DI/π · E (`hcb.indirect`). A covered pixel no sample reaches keeps a = 0 and is counted,
// so that it is shown, never silently black: `uncovered` holds the count, then the first
// UNCOVERED_LIST of those pixels as x | y << 16 (in no particular order), which the overlay
// reads back instead of two whole images (issue #38).
@group(0) @binding(0) var accum: texture_2d<f32>;
@group(0) @binding(1) var g_normal: texture_2d<f32>;
@group(0) @binding(2) var out_light: texture_storage_2d<rgba32float, write>;
@group(0) @binding(3) var<storage, read_write> uncovered: array<atomic<u32>>;
@group(0) @binding(4) var g_albedo: texture_2d<f32>;
@group(0) @binding(5) var out_radiance: texture_storage_2d<rgba32float, write>;

// Rust twin: passes::hcb::UNCOVERED_LIST.
const UNCOVERED_LIST: u32 = 65536u;

@compute @workgroup_size(8, 8, 1)
fn cs_normalize(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = textureDimensions(out_light);
    if (gid.x >= size.x || gid.y >= size.y) {
        return;
    }
    let a = textureLoad(accum, gid.xy, 0);
    var out = vec4<f32>(0.0);
    if (a.a > 0.0) {
        out = vec4<f32>(a.rgb / a.a, 1.0);
    } else if (textureLoad(g_normal, gid.xy, 0).w > 0.5) {
        let i = atomicAdd(&uncovered[0], 1u);
        if (i < UNCOVERED_LIST) {
            atomicStore(&uncovered[4u + i], gid.x | (gid.y << 16u));
        }
    }
    textureStore(out_light, gid.xy, out);
    let alb = textureLoad(g_albedo, gid.xy, 0);
    textureStore(out_radiance, gid.xy, vec4<f32>(alb.rgb * alb.a / 3.14159265 * out.rgb, out.a));
}
