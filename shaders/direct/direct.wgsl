// Stage 2, direct light: every punctual light evaluated with the BRDF of
// common/brdf.wgsl at each G-buffer pixel, visibility from the shadow map with
// percentage-closer filtering over (2r+1)² comparisons; and every emitter VPL
// (passes/emitters.rs: emissive surfaces as lights) with the irradiance of common/vpl.wgsl
// (Knecht 002 Eq. 4.7, d_min clamped) and the visibility of common/ism.wgsl's
// gather_visibility (imperfect shadow maps, exact maps or none). The surface's own emission
// is not added here: the compose adds it.
#import common/camera.wgsl
#import common/brdf.wgsl
#import common/lights.wgsl
#import common/fullscreen.wgsl
#import common/ism.wgsl
#import common/normal.wgsl

struct Params {
    // x: PCF radius in texels, y: shadow map size, z: depth bias in texels (toward the
    // light), w: normal offset in texels
    shadow: vec4<f32>,
    // x: intensity scale, y: shadows enabled
    light: vec4<f32>,
    // x: emitter VPLs, y: their visibility (0 none, 1 ISM, 2 exact), z: atlas columns,
    // w: map size
    emitter_counts: vec4<u32>,
    // xyz: gather_visibility's parameters, w: d_min²
    emitter_vis: vec4<f32>,
}

// Whether the pipeline evaluates emitter VPLs (issue #53): a scene without emitters runs a
// pipeline with this false, whose loop over them is left out (on lavapipe the loop's code
// cost about a fifth of the pass even with no emitter to loop over).
override EMITTERS: bool = true;
// Whether g_position is the camera G-buffer's linear depth (the screen's entries, issue #53)
// rather than world positions (the hemisphere atlas).
override LINEAR_DEPTH: bool = true;

@group(0) @binding(0) var<uniform> camera: Camera;
@group(0) @binding(1) var<uniform> params: Params;
@group(0) @binding(2) var<storage, read> lights: array<Light>;
@group(0) @binding(3) var<storage, read> light_view_proj: array<mat4x4<f32>>;
@group(0) @binding(4) var shadow_map: texture_depth_2d_array;
@group(0) @binding(5) var shadow_sampler: sampler_comparison;
@group(0) @binding(6) var<storage, read> emitter_vpls: array<Vpl>;
@group(0) @binding(7) var emitter_ism: texture_2d<f32>;
@group(0) @binding(8) var emitter_exact: texture_2d<f32>;
// The camera G-buffer's linear depth (LINEAR_DEPTH: cs_main, cs_main_diffuse; issue #53), or
// the hemisphere atlas's world positions (cs_atlas).
@group(1) @binding(0) var g_position: texture_2d<f32>;
@group(1) @binding(1) var g_normal: texture_2d<f32>;
@group(1) @binding(2) var g_albedo: texture_2d<f32>;
@group(1) @binding(3) var g_material: texture_2d<f32>;
@group(1) @binding(4) var out_radiance: texture_storage_2d<rgba16float, write>;
// The camera G-buffer's packed normals (LINEAR_DEPTH, common/normal.wgsl, issue #53), where
// g_normal is a 1×1 stand-in; the atlas's normals are g_normal (this a stand-in).
@group(1) @binding(5) var g_normal_packed: texture_2d<u32>;

// Picks the cube face of a point light from the major axis of the light-to-surface vector
// (faces ordered +X, −X, +Y, −Y, +Z, −Z as in passes/shadow.rs).
fn cube_face(d: vec3<f32>) -> u32 {
    let a = abs(d);
    if (a.x >= a.y && a.x >= a.z) {
        return select(1u, 0u, d.x > 0.0);
    }
    if (a.y >= a.z) {
        return select(3u, 2u, d.y > 0.0);
    }
    return select(5u, 4u, d.z > 0.0);
}

// Both biases are world-space offsets of the receiver, measured in shadow-map texels at the
// receiver's distance, so they mean the same in every scene and at every distance (a
// constant NDC bias would be metres wide far from a close near plane).
fn shadow_visibility(light: Light, p: vec3<f32>, n: vec3<f32>, l: vec3<f32>) -> f32 {
    if (light.cone.w < 0.5 || params.light.y < 0.5) {
        return 1.0;
    }
    // Normal offset proportional to the texel footprint at p.
    var texel = light.shadow.x;
    if (light.position.w != LIGHT_DIRECTIONAL) {
        texel = texel * distance(p, light.position.xyz);
    }
    let pn = p + n * texel * params.shadow.w + l * texel * params.shadow.z;
    var layer = u32(light.cone.z);
    if (light.position.w == LIGHT_POINT) {
        layer = layer + cube_face(pn - light.position.xyz);
    }
    let clip = light_view_proj[layer] * vec4<f32>(pn, 1.0);
    if (clip.w <= 0.0) {
        return 0.0;
    }
    let ndc = clip.xyz / clip.w;
    let uv = vec2<f32>(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5);
    if (ndc.z > 1.0) {
        return 1.0;
    }
    let depth_ref = ndc.z;
    let r = i32(params.shadow.x);
    let inv_size = 1.0 / params.shadow.y;
    var sum = 0.0;
    var count = 0.0;
    for (var y = -r; y <= r; y = y + 1) {
        for (var x = -r; x <= r; x = x + 1) {
            let o = vec2<f32>(f32(x), f32(y)) * inv_size;
            sum = sum + textureSampleCompareLevel(shadow_map, shadow_sampler, uv + o, i32(layer), depth_ref);
            count = count + 1.0;
        }
    }
    return sum / count;
}

// What the lights give a point: the radiance reflected toward the viewer by the whole BRDF,
// and the irradiance E (the diffuse part's c·DI/π · E is what a diffuse sender re-emits,
// Soler et al. 004 §5.3).
struct Reflected {
    radiance: vec3<f32>,
    irradiance: vec3<f32>,
}

// The light of every emitter VPL reflected toward v at p.
fn reflected_emitters(p: vec3<f32>, n: vec3<f32>, v: vec3<f32>, alb: vec4<f32>, mat: vec4<f32>) -> Reflected {
    var radiance = vec3<f32>(0.0);
    var irradiance = vec3<f32>(0.0);
    let ec = params.emitter_counts;
    let count = min(ec.x, arrayLength(&emitter_vpls));
    for (var k = 0u; k < count; k = k + 1u) {
        let vpl = emitter_vpls[k];
        let e = vpl_irradiance(vpl, p, n, params.emitter_vis.w, 0.0);
        if (max(e.r, max(e.g, e.b)) <= 0.0) {
            continue;
        }
        let vis = gather_visibility(ec.y, emitter_ism, emitter_exact, k, vpl, p, n, ec.z, ec.w, params.emitter_vis.xyz);
        if (vis <= 0.0) {
            continue;
        }
        let l = normalize(vpl.position.xyz - p);
        radiance = radiance + brdf_eval(n, l, v, alb.rgb, alb.a, mat.x, mat.y) * e * vis;
        irradiance = irradiance + e * vis;
    }
    return Reflected(radiance, irradiance);
}

// The light of every punctual light and emitter VPL reflected toward v at p.
fn reflected_direct(p: vec3<f32>, n: vec3<f32>, v: vec3<f32>, alb: vec4<f32>, mat: vec4<f32>) -> Reflected {
    var radiance = vec3<f32>(0.0);
    var irradiance = vec3<f32>(0.0);
    if (EMITTERS) {
        let emitted = reflected_emitters(p, n, v, alb, mat);
        radiance = emitted.radiance;
        irradiance = emitted.irradiance;
    }
    let count = arrayLength(&lights);
    for (var i = 0u; i < count; i = i + 1u) {
        let light = lights[i];
        var l: vec3<f32>;
        var irradiance_scale: f32;
        if (light.position.w == LIGHT_DIRECTIONAL) {
            l = -light.direction.xyz;
            irradiance_scale = 1.0;
        } else {
            let to_p = p - light.position.xyz;
            let d = length(to_p);
            l = -to_p / d;
            irradiance_scale = range_window(light.direction.w, d) / (d * d);
            if (light.position.w == LIGHT_SPOT) {
                irradiance_scale = irradiance_scale * spot_falloff(light, -l);
            }
        }
        let ndl = dot(n, l);
        if (ndl <= 0.0 || irradiance_scale <= 0.0) {
            continue;
        }
        let vis = shadow_visibility(light, p, n, l);
        let e = light.color.rgb * params.light.x * irradiance_scale * ndl * vis;
        radiance = radiance + brdf_eval(n, l, v, alb.rgb, alb.a, mat.x, mat.y) * e;
        irradiance = irradiance + e;
    }
    return Reflected(radiance, irradiance);
}

// The direct light at G-buffer texel px reflected toward `viewer`: the whole radiance and its
// diffuse part c·DI/π · E, alpha 1; both 0 where the texel holds no surface.
struct Shaded {
    radiance: vec4<f32>,
    diffuse: vec4<f32>,
}

fn shade_texel(px: vec2<i32>, viewer: vec3<f32>) -> Shaded {
    var nrm = textureLoad(g_normal, px, 0);
    if (LINEAR_DEPTH) {
        nrm = gbuffer_normal(textureLoad(g_normal_packed, px, 0).x);
    }
    if (nrm.w < 0.5) {
        return Shaded(vec4<f32>(0.0), vec4<f32>(0.0));
    }
    var p = textureLoad(g_position, px, 0).xyz;
    if (LINEAR_DEPTH) {
        p = world_from_linear_depth(camera, px, p.x);
    }
    let alb = textureLoad(g_albedo, px, 0);
    let mat = textureLoad(g_material, px, 0);
    let r = reflected_direct(p, normalize(nrm.xyz), normalize(viewer - p), alb, mat);
    return Shaded(vec4<f32>(r.radiance, 1.0), vec4<f32>(alb.rgb * alb.a / PI * r.irradiance, 1.0));
}

@compute @workgroup_size(TILE, TILE, 1)
fn cs_main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = textureDimensions(out_radiance);
    if (gid.x >= size.x || gid.y >= size.y) {
        return;
    }
    let px = vec2<i32>(gid.xy);
    textureStore(out_radiance, px, shade_texel(px, camera.position.xyz).radiance);
}

// cs_main, and the diffuse part of the same light, c·DI/π · E, into out_diffuse: what Soler
// et al.'s gather takes as the senders' radiance under §5.3's "diffuse approximation of this
// light" (`soler.sender`).
@group(2) @binding(2) var out_diffuse: texture_storage_2d<rgba16float, write>;

@compute @workgroup_size(TILE, TILE, 1)
fn cs_main_diffuse(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = textureDimensions(out_radiance);
    if (gid.x >= size.x || gid.y >= size.y) {
        return;
    }
    let px = vec2<i32>(gid.xy);
    let s = shade_texel(px, camera.position.xyz);
    textureStore(out_radiance, px, s.radiance);
    textureStore(out_diffuse, px, s.diffuse);
}

// An atlas of G-buffer tiles, each seen from its own viewpoint: the hemispheres of Gautron
// et al.'s records (003, "Simple plane sampling": "the shadowing effects can be accounted for
// using … shadow mapping"), lit by the same lights, shadow maps and BRDF as the screen, toward
// the record. Emission is not counted: emitters light the record through their VPLs, as the
// path tracer reaches them by next-event estimation.
struct AtlasParams {
    // x: tile side in texels, y: tiles per row
    tile: vec4<u32>,
}
@group(2) @binding(0) var<uniform> atlas: AtlasParams;
@group(2) @binding(1) var<storage, read> viewers: array<vec4<f32>>;

@compute @workgroup_size(TILE, TILE, 1)
fn cs_atlas(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = textureDimensions(out_radiance);
    if (gid.x >= size.x || gid.y >= size.y) {
        return;
    }
    let px = vec2<i32>(gid.xy);
    let cell = gid.xy / atlas.tile.x;
    let viewer = viewers[min(cell.y * atlas.tile.y + cell.x, arrayLength(&viewers) - 1u)];
    if (viewer.w < 0.5) {
        textureStore(out_radiance, px, vec4<f32>(0.0));
        return;
    }
    textureStore(out_radiance, px, shade_texel(px, viewer.xyz).radiance);
}
