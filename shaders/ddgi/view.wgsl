// DDGI's buffers for the viewer (issue #56 point 3): both atlases, each probe's rays of the
// frame (a row per probe: radiance, distance) and the probes (a texel per probe: offset,
// state) copied from their storage buffers into textures. `passes::ddgi::stage`.

#import ddgi/probes.wgsl

@group(0) @binding(0) var<storage, read> ddgi: DdgiUpdate;
@group(0) @binding(1) var<storage, read> ddgi_rays: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> ddgi_irradiance: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> ddgi_distance: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read> ddgi_probes: array<vec4<f32>>;
@group(0) @binding(5) var view_irradiance: texture_storage_2d<rgba32float, write>;
@group(0) @binding(6) var view_distance: texture_storage_2d<rgba32float, write>;
@group(0) @binding(7) var view_rays: texture_storage_2d<rgba32float, write>;
@group(0) @binding(8) var view_probes: texture_storage_2d<rgba32float, write>;


@compute @workgroup_size(8, 8)
fn cs_view(@builtin(global_invocation_id) gid: vec3<u32>) {
    let p = gid.xy;
    let wi = textureDimensions(view_irradiance);
    if (p.x < wi.x && p.y < wi.y) {
        textureStore(view_irradiance, vec2<i32>(p), vec4<f32>(ddgi_irradiance[p.y * wi.x + p.x].rgb, 1.0));
    }
    let wd = textureDimensions(view_distance);
    if (p.x < wd.x && p.y < wd.y) {
        textureStore(view_distance, vec2<i32>(p), vec4<f32>(ddgi_distance[p.y * wd.x + p.x].xy, 0.0, 1.0));
    }
    let wr = textureDimensions(view_rays);
    if (p.x < wr.x && p.y < wr.y) {
        textureStore(view_rays, vec2<i32>(p), ddgi_rays[p.y * wr.x + p.x]);
    }
    let wp = textureDimensions(view_probes);
    if (p.x < wp.x && p.y < wp.y) {
        let i = p.y * wp.x + p.x;
        if (i < ddgi.counts.x) {
            textureStore(view_probes, vec2<i32>(p), ddgi_probes[i]);
        }
    }
}
