// Stage 3 of the exact-VPL reference: VPLs placed by uniform sampling of one light view's
// G-buffer (the light G-buffer of Knecht 002 §4.3 rendered from the light). VPL j of the
// view (j = b·N + i for the view's b-th batch) picks the texel under the Halton point
// (h₂(j+1), h₃(j+1)) shifted by a random toroidal offset of the seed (Cranley–Patterson
// rotation): each point is uniform over the texels, so the estimate stays unbiased, while
// the whole set and every prefix of batches is stratified over the light view — the
// quasi-random sampling of Keller's instant radiosity (1997), which makes the reference
// converge faster than independent texels did (CPU twin: cpu::knecht::reference_uv). Its
// incident flux is the light's power through that texel,
// Φ = I(ω) · dω (spot, point and emitter point: intensity × falloff × the texel's solid
// angle dω = s² cos³θ; an emitter point's falloff is its cosine lobe max(n · ω, 0)) or Φ = E · s² (directional), divided by the sampling density N / (R² · V)
// (N VPLs over R² texels, this view one of the V views taken in turn), so that the set is
// an unbiased estimate of the power the light delivers to the visible surfaces. The
// reference keeps this uniform sampling; Knecht's importance sampling by hierarchical warping
// (§3.3, §4.4) is `knecht/vpl/importance.wgsl`.
#import common/lights.wgsl
#import common/vpl.wgsl
#import common/random.wgsl

struct Params {
    // xyz: eye of the light view; w: 1 for an orthographic view
    eye: vec4<f32>,
    // xyz: unit view axis; w: texel side s (image plane at unit distance, or world units)
    forward: vec4<f32>,
    // x: flux scale R² · V / N × intensity scale; y: VPL count N
    scale: vec4<f32>,
    // x: seed, y: batch index, z: light index, w: batch index within this view (b)
    seed: vec4<u32>,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> lights: array<Light>;
@group(0) @binding(2) var lg_position: texture_2d<f32>;
@group(0) @binding(3) var lg_normal: texture_2d<f32>;
@group(0) @binding(4) var lg_albedo: texture_2d<f32>;
@group(0) @binding(5) var lg_material: texture_2d<f32>;
@group(0) @binding(6) var<storage, read_write> vpls: array<Vpl>;

// The rotated Halton point of VPL j (CPU twin: cpu::knecht::reference_uv).
fn reference_uv(seed: u32, j: u32) -> vec2<f32> {
    let h = pcg_hash(seed);
    let offset = vec2<f32>(f32(h >> 8u), f32(pcg_hash(h) >> 8u)) / 16777216.0;
    return fract(vec2<f32>(halton(j + 1u, 2u), halton(j + 1u, 3u)) + offset);
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
    let uv = reference_uv(params.seed.x, params.seed.w * count + i);
    let texel = min(vec2<u32>(uv * vec2<f32>(size)), size - vec2<u32>(1u));
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
        if (light.position.w == LIGHT_EMITTER) {
            falloff = falloff * max(dot(light.direction.xyz, dir), 0.0);
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
