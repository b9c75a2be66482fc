// DDGI at every pixel (Majercik et al. 2019 §3.4, Eq. 5–6; 2021 §4.2): the probes' irradiance E
// at the G-buffer's point (`ddgi/lookup.wgsl`, CPU twin `cpu::ddgi::sample`), reflected as
// c·DI/π·E, plus with the glossy receiver (⚠[ddgi.glossy-receiver]) SI · E(r)/π, the probes'
// irradiance toward the view's mirror direction r with the same weights. `passes::ddgi::apply`.

#import common/camera.wgsl
#import ddgi/lookup.wgsl

@group(0) @binding(0) var<storage, read> ddgi_grid: DdgiGrid;
@group(0) @binding(1) var<storage, read> ddgi_probes: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> ddgi_irradiance: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> ddgi_distance: array<vec4<f32>>;
@group(0) @binding(4) var g_position: texture_2d<f32>;
@group(0) @binding(5) var g_normal: texture_2d<f32>;
@group(0) @binding(6) var g_albedo: texture_2d<f32>;
@group(0) @binding(7) var<uniform> camera: Camera;
@group(0) @binding(8) var out_indirect: texture_storage_2d<rgba32float, write>;
@group(0) @binding(9) var out_irradiance: texture_storage_2d<rgba32float, write>;
// SI (r), SP (g).
@group(0) @binding(10) var g_material: texture_2d<f32>;

// The light a pixel reflects of the probes: c·DI/π·E(n) + SI·E(r)/π (the glossy receiver).
fn ddgi_reflect(e: DdgiPair, albedo: vec4<f32>, si: f32) -> vec3<f32> {
    var l = albedo.rgb * albedo.a / 3.14159265358979 * e.n;
    if (ddgi_grid.state.z > 0.5 && si > 0.0) {
        l = l + si * e.dir / 3.14159265358979;
    }
    return l;
}

@compute @workgroup_size(8, 8)
fn cs_apply(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = textureDimensions(out_indirect);
    if (gid.x >= size.x || gid.y >= size.y) {
        return;
    }
    let px = vec2<i32>(gid.xy);
    let nrm = textureLoad(g_normal, px, 0);
    var e = vec3<f32>(0.0);
    var radiance = vec3<f32>(0.0);
    if (nrm.w > 0.5) {
        let p = textureLoad(g_position, px, 0).xyz;
        let n = normalize(nrm.xyz);
        let v = normalize(camera.position.xyz - p);
        let pair = ddgi_sample_pair(p, n, v, reflect(-v, n));
        e = pair.n;
        radiance = ddgi_reflect(pair, textureLoad(g_albedo, px, 0), textureLoad(g_material, px, 0).x);
    }
    textureStore(out_indirect, px, vec4<f32>(radiance, 1.0));
    textureStore(out_irradiance, px, vec4<f32>(e, 1.0));
}
