// Stage 7, composition (Knecht 002 §4.6): final.hdr = emission + direct + indirect + near
// field (the surface's own emission L_e, `gbuffer.emission`, is kept out of direct.radiance so
// that no gather takes an emitter for a sender besides its VPLs; each
// indirect input is black when no stage provides it; the near field is `pipeline.near_field`'s
// screen-space gather of the senders closer than the split, the indirect input the VPLs'). Tone mapping: compose/tonemap.wgsl.
// Where the G-buffer is empty, the scene's sky (issue #18, `sky.background`): its radiance
// along the pixel's ray, read from the equirectangular image at the texel the CPU's
// scene::sky::SkySampler::radiance reads (nearest, no filtering) or the constant colour.
#import common/fullscreen.wgsl
#import common/camera.wgsl
#import compose/reinhard.wgsl

struct SkyParams {
    // rgb: constant radiance or image scale; w: 0 none, 1 constant, 2 image
    radiance: vec4<f32>,
    // x: rotation about +Y (radians)
    rotation: vec4<f32>,
}

@group(0) @binding(1) var direct: texture_2d<f32>;
@group(0) @binding(2) var indirect: texture_2d<f32>;
@group(0) @binding(3) var out_hdr: texture_storage_2d<rgba16float, write>;
@group(0) @binding(4) var near_field: texture_2d<f32>;
@group(0) @binding(5) var emission: texture_2d<f32>;
@group(0) @binding(6) var<uniform> sky: SkyParams;
@group(0) @binding(7) var sky_image: texture_2d<f32>;
@group(0) @binding(8) var<uniform> camera: Camera;
// The camera G-buffer's linear depth (issue #53): 0 where no geometry covers the pixel.
@group(0) @binding(9) var gbuffer_depth: texture_2d<f32>;
struct Tone {
    // x: 2^EV, y: key a, z: L_white, w: 0 no tone mapping here (compose/tonemap.wgsl
    // follows), 1 manual exposure, 2 automatic with the previous frame's L̄w
    tone: vec4<f32>,
    // x: 1 to store final.hdr (0: nothing reads it in this frame and a 1×1 stand-in is bound;
    // a read of it runs this pass again, issue #53); y: 1 to store final.ldr and the tiles'
    // log-luminance (0: final.hdr alone, for that read)
    store: vec4<u32>,
}
@group(0) @binding(10) var<uniform> tp: Tone;
@group(0) @binding(11) var<storage, read> log_average: array<f32>;
@group(0) @binding(12) var out_ldr: texture_storage_2d<rgba8unorm, write>;
// Per tile: Σ round(log(δ + Lw) · LOG_SCALE), then the count of pixels with Lw > 0.
@group(0) @binding(13) var<storage, read_write> partials: array<atomic<i32>>;

// Fixed-point steps per unit of log(δ + Lw) (compose/luminance.wgsl divides by it), and the
// largest |log| summed (Lw up to e^30 ≈ 10^13; δ keeps it above −9.3): a tile of TILE²
// pixels then sums to less than 64 · 30 · 2^20 < 2^31, no overflow.
const LOG_SCALE: f32 = 1048576.0;
const LOG_LIMIT: f32 = 30.0;

const PI: f32 = 3.14159265358979;

// Radiance of the sky seen along the unit direction d (Rust twin: SkySampler::radiance).
fn sky_radiance(d: vec3<f32>) -> vec3<f32> {
    if (sky.radiance.w < 1.5) {
        return sky.radiance.rgb;
    }
    let size = textureDimensions(sky_image);
    let phi = atan2(d.x, -d.z) - sky.rotation.x + PI;
    let u = fract(phi / (2.0 * PI));
    let v = acos(clamp(d.y, -1.0, 1.0)) / PI;
    let x = min(u32(u * f32(size.x)), size.x - 1u);
    let y = min(u32(v * f32(size.y)), size.y - 1u);
    return textureLoad(sky_image, vec2<u32>(x, y), 0).rgb * sky.radiance.rgb;
}

// The camera ray through pixel px's centre (Rust twin: cpu::raycast::primary_ray).
fn pixel_ray(px: vec2<u32>, size: vec2<u32>) -> vec3<f32> {
    let ndc = vec2<f32>((f32(px.x) + 0.5) / f32(size.x) * 2.0 - 1.0, 1.0 - (f32(px.y) + 0.5) / f32(size.y) * 2.0);
    let near = camera.inv_view_proj * vec4<f32>(ndc, 0.0, 1.0);
    let far = camera.inv_view_proj * vec4<f32>(ndc, 1.0, 1.0);
    return normalize(far.xyz / far.w - near.xyz / near.w);
}

@compute @workgroup_size(TILE, TILE, 1)
fn cs_compose(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let size = textureDimensions(out_ldr);
    if (gid.x >= size.x || gid.y >= size.y) {
        return;
    }
    let px = vec2<i32>(gid.xy);
    var c = textureLoad(emission, px, 0).rgb + textureLoad(direct, px, 0).rgb + textureLoad(indirect, px, 0).rgb + textureLoad(near_field, px, 0).rgb;
    if (sky.radiance.w > 0.5 && textureLoad(gbuffer_depth, px, 0).x <= 0.0) {
        c = c + sky_radiance(pixel_ray(gid.xy, size));
    }
    if (tp.store.x == 1u) {
        textureStore(out_hdr, px, vec4<f32>(c, 1.0));
    }
    if (tp.store.y == 0u) {
        return;
    }
    if (tp.tone.w > 0.5) {
        let t = vec4<f32>(tp.tone.xyz, select(0.0, 1.0, tp.tone.w > 1.5));
        textureStore(out_ldr, px, vec4<f32>(reinhard(c, t, log_average[0]), 1.0));
    }
    let lw = luminance_of(max(c, vec3<f32>(0.0)));
    if (lw > 0.0) {
        let tile = 2u * (wg.y * groups.x + wg.x);
        let l = clamp(log(1e-4 + lw), -LOG_LIMIT, LOG_LIMIT);
        atomicAdd(&partials[tile], i32(round(l * LOG_SCALE)));
        atomicAdd(&partials[tile + 1u], 1);
    }
}
