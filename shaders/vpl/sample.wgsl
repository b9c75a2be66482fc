// Stage 3 of the exact-VPL reference: VPLs placed by uniform sampling of one light view's
// G-buffer (the light G-buffer of Knecht 002 §4.3 rendered from the light). Each VPL picks
// a uniformly random texel; its incident flux is the light's power through that texel,
// Φ = I(ω) · dω (spot and point: intensity × falloff × the texel's solid angle
// dω = s² cos³θ) or Φ = E · s² (directional), divided by the sampling density N / (R² · V)
// (N VPLs over R² texels, this view one of the V views taken in turn), so that the set is
// an unbiased estimate of the power the light delivers to the visible surfaces. Importance
// sampling by hierarchical warping (Knecht §3.3, §4.4) replaces this with the Knecht issue.
#import common/lights.wgsl
#import common/vpl.wgsl

struct Params {
    // xyz: eye of the light view; w: 1 for an orthographic view
    eye: vec4<f32>,
    // xyz: unit view axis; w: texel side s (image plane at unit distance, or world units)
    forward: vec4<f32>,
    // x: flux scale R² · V / N × intensity scale; y: VPL count N
    scale: vec4<f32>,
    // x: seed, y: batch index, z: light index
    seed: vec4<u32>,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> lights: array<Light>;
@group(0) @binding(2) var lg_position: texture_2d<f32>;
@group(0) @binding(3) var lg_normal: texture_2d<f32>;
@group(0) @binding(4) var lg_albedo: texture_2d<f32>;
@group(0) @binding(5) var lg_material: texture_2d<f32>;
@group(0) @binding(6) var<storage, read_write> vpls: array<Vpl>;

// PCG hash (Jarzynski and Olano, JCGT 2020).
fn pcg(v: u32) -> u32 {
    let state = v * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

@compute @workgroup_size(64, 1, 1)
fn cs_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    let count = u32(params.scale.y);
    if (i >= count) {
        return;
    }
    var empty: Vpl;
    empty.position = vec4<f32>(0.0);
    empty.flux = vec4<f32>(0.0);
    let size = textureDimensions(lg_position);
    let h = pcg(pcg(params.seed.x ^ pcg(params.seed.y)) ^ (i * 0x9E3779B9u));
    let h2 = pcg(h);
    let texel = vec2<u32>(h % size.x, h2 % size.y);
    let nrm = textureLoad(lg_normal, texel, 0);
    if (nrm.w < 0.5) {
        vpls[i] = empty;
        return;
    }
    let p = textureLoad(lg_position, texel, 0).xyz;
    let n = normalize(nrm.xyz);
    let light = lights[params.seed.z];
    let s = params.forward.w;
    var to_light: vec3<f32>;
    var power: vec3<f32>;
    if (params.eye.w > 0.5) {
        to_light = -params.forward.xyz;
        power = light.color.rgb * s * s;
    } else {
        let d_vec = p - params.eye.xyz;
        let d = length(d_vec);
        let dir = d_vec / d;
        to_light = -dir;
        let cos_axis = max(dot(dir, params.forward.xyz), 0.0);
        var falloff = range_window(light.direction.w, d);
        if (light.position.w == LIGHT_SPOT) {
            falloff = falloff * spot_falloff(light, dir);
        }
        power = light.color.rgb * falloff * s * s * cos_axis * cos_axis * cos_axis;
    }
    if (dot(n, to_light) <= 0.0 || max(power.r, max(power.g, power.b)) <= 0.0) {
        vpls[i] = empty;
        return;
    }
    let alb = textureLoad(lg_albedo, texel, 0);
    let mat = textureLoad(lg_material, texel, 0);
    var v: Vpl;
    v.position = vec4<f32>(p, 1.0);
    v.normal = vec4<f32>(n, alb.a);
    v.flux = vec4<f32>(power * params.scale.x, mat.x);
    v.incident = vec4<f32>(to_light, mat.y);
    v.albedo = vec4<f32>(alb.rgb, 0.0);
    vpls[i] = v;
}
