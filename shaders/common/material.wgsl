// The scene's material (group 2): glTF 2.0 metallic-roughness (§3.9) as Knecht's G-buffer
// reads it (002 §4.2: colour c, DI, SI, SP; the mapping is `scene::Material`'s). WGSL twin
// of `scene::upload::MaterialUniform`. Used by the G-buffers (camera, light views, Gautron's
// hemispheres) and by the depth-only views for alpha cutouts (shadow maps, exact VPL maps).

struct Material {
    base_color: vec4<f32>,
    // DI, SI, SP, has base colour texture
    params: vec4<f32>,
    // metallic, roughness, 0, 0
    extra: vec4<f32>,
    // rgb: emitted radiance L_e (glTF emissive factor × strength), w: has emissive texture
    emissive: vec4<f32>,
    // x: normal texture scale (0: none), y: has metallic-roughness texture,
    // z: alpha cutoff (< 0: opaque), w: has occlusion texture
    maps: vec4<f32>,
}

@group(2) @binding(0) var<uniform> material: Material;
@group(2) @binding(1) var base_tex: texture_2d<f32>;
@group(2) @binding(2) var base_sampler: sampler;
@group(2) @binding(3) var emissive_tex: texture_2d<f32>;
// Linear views (normal, metallic-roughness, occlusion data are not colours).
@group(2) @binding(4) var normal_tex: texture_2d<f32>;
@group(2) @binding(5) var mr_tex: texture_2d<f32>;
@group(2) @binding(6) var occlusion_tex: texture_2d<f32>;

// Whether a fragment of base colour alpha `alpha` is cut out (alphaMode MASK, §3.9.4).
fn material_cut(alpha: f32) -> bool {
    return material.maps.z >= 0.0 && alpha < material.maps.z;
}

// Base colour alpha at `uv` from mip 0 (the depth-only views' cutout test).
fn material_alpha(uv: vec2<f32>) -> f32 {
    var a = material.base_color.a;
    if (material.params.w > 0.5) {
        a = a * textureSampleLevel(base_tex, base_sampler, uv, 0.0).a;
    }
    return a;
}

// SP = 2 / α² − 2 with α = roughness², clamped to [1, 4096] (`scene::specular_power`).
fn material_specular_power(roughness: f32) -> f32 {
    let r = clamp(roughness, 0.0, 1.0);
    let a = max(r * r, 1e-3);
    return clamp(2.0 / (a * a) - 2.0, 1.0, 4096.0);
}
