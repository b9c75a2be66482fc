// Stage 1: the camera's `gbuffer.material` filled when it is read (issue #53,
// docs/architecture.md "The camera G-buffer's position"). The G-buffer keeps SI and SP alone
// (Knecht 002 §4.2's specular intensity and power, the two values every pass reads, in
// `Rg16Float`); this adds what the viewer and the probe show beside them: metallic = 1 − DI
// (the albedo's a) and the roughness r that SP shades (SP = 2/α² − 2 with α = r², inverted;
// `scene::specular_power`, which clamps SP to [1, 4096], so r shows between 0.149 and 0.904).
// 0 where no geometry covers the pixel (SP ≥ 1 on every surface; the clear is 0).

@group(0) @binding(0) var shading: texture_2d<f32>;
@group(0) @binding(1) var albedo: texture_2d<f32>;
@group(0) @binding(2) var out_material: texture_storage_2d<rgba16float, write>;

@compute @workgroup_size(8, 8, 1)
fn cs_material(@builtin(global_invocation_id) gid: vec3<u32>) {
    let size = textureDimensions(shading);
    if (gid.x >= size.x || gid.y >= size.y) {
        return;
    }
    let p = vec2<i32>(gid.xy);
    let m = textureLoad(shading, p, 0).xy;
    var out = vec4<f32>(0.0);
    if (m.y >= 0.5) {
        let roughness = sqrt(sqrt(2.0 / (m.y + 2.0)));
        out = vec4<f32>(m.x, m.y, 1.0 - textureLoad(albedo, p, 0).a, roughness);
    }
    textureStore(out_material, p, out);
}
