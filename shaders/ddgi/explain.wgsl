// Explain a pixel with DDGI (issue #56 point 3; issue #42): the pinned pixel's eight probes as
// the frame read them (`ddgi/lookup.wgsl`, the same functions as `ddgi/apply.wgsl`): each
// probe's index, place, state, trilinear, backface and Chebyshev weights, its irradiance
// toward the normal; and the frame's `ddgi.indirect` at the pixel, the sum's check.
// `passes::ddgi::explain`.

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
@group(0) @binding(8) var frame_indirect: texture_2d<f32>;
// The pixel (xy).
@group(0) @binding(9) var<storage, read> explain_pixel: vec4<u32>;
// 4 records of the pixel (position and 1 when valid, normal and SI (0 with the diffuse
// receiver), albedo and DI, ddgi.indirect), then 4 per probe (index, trilinear, backface,
// visibility; weight, place; irradiance / π toward n, state; irradiance / π toward the mirror
// direction).
@group(0) @binding(10) var<storage, read_write> explain_out: array<vec4<f32>>;
@group(0) @binding(11) var g_material: texture_2d<f32>;

@compute @workgroup_size(1)
fn cs_explain() {
    let px = vec2<i32>(explain_pixel.xy);
    let nrm = textureLoad(g_normal, px, 0);
    let p = textureLoad(g_position, px, 0).xyz;
    let n = normalize(nrm.xyz);
    explain_out[0] = vec4<f32>(p, select(0.0, 1.0, nrm.w > 0.5));
    var si = textureLoad(g_material, px, 0).x;
    if (ddgi_grid.state.z < 0.5) {
        si = 0.0;
    }
    explain_out[1] = vec4<f32>(n, si);
    explain_out[2] = textureLoad(g_albedo, px, 0);
    explain_out[3] = textureLoad(frame_indirect, px, 0);
    if (nrm.w <= 0.5) {
        return;
    }
    let v = normalize(camera.position.xyz - p);
    let cell = ddgi_cell(p, n, v);
    let r = reflect(-v, n);
    for (var k = 0u; k < 8u; k = k + 1u) {
        let t = ddgi_term(cell, k, p, n);
        explain_out[4u + 4u * k] = vec4<f32>(f32(t.probe), t.trilinear, t.normal, t.visibility);
        explain_out[5u + 4u * k] = vec4<f32>(t.weight, ddgi_probe_position(t.probe));
        explain_out[6u + 4u * k] = vec4<f32>(ddgi_lookup_irradiance(t.probe, n), ddgi_probes[t.probe].w);
        explain_out[7u + 4u * k] = vec4<f32>(ddgi_lookup_irradiance(t.probe, r), 0.0);
    }
}
