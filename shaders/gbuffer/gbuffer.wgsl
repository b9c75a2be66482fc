// Stage 1, G-buffer (Knecht 002 §4.2). World-space position, normal, albedo + diffuse
// intensity DI, specular intensity SI and power SP, and the movement buffer m_buf of
// §3.5.1: the screen-space offset from each pixel to where its surface point was in the
// previous frame, from the previous camera and the previous object transform.
// Reading chosen: the thesis writes (x_s − x_prev, y_s − y_prev) but then looks up
// I_prev(x_s + Δx, y_s + Δy); we store Δ = prev − current so that the lookup is right.
#import common/camera.wgsl

struct Instance {
    model: mat4x4<f32>,
    prev_model: mat4x4<f32>,
    normal_matrix: mat4x4<f32>,
}

struct Material {
    base_color: vec4<f32>,
    // DI, SI, SP, has_texture
    params: vec4<f32>,
    // metallic, roughness, 0, 0
    extra: vec4<f32>,
    // rgb: emitted radiance L_e (glTF emissive factor × strength), w: has emissive texture
    emissive: vec4<f32>,
}

@group(0) @binding(0) var<uniform> camera: Camera;
@group(1) @binding(0) var<storage, read> instances: array<Instance>;
@group(2) @binding(0) var<uniform> material: Material;
@group(2) @binding(1) var base_tex: texture_2d<f32>;
@group(2) @binding(2) var base_sampler: sampler;
@group(2) @binding(3) var emissive_tex: texture_2d<f32>;

struct VsIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
}

struct VsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @location(3) cur_clip: vec4<f32>,
    @location(4) prev_clip: vec4<f32>,
}

@vertex
fn vs_main(v: VsIn, @builtin(instance_index) instance: u32) -> VsOut {
    let inst = instances[instance];
    let world = inst.model * vec4<f32>(v.position, 1.0);
    let prev_world = inst.prev_model * vec4<f32>(v.position, 1.0);
    var o: VsOut;
    o.clip = camera.view_proj * world;
    o.world = world.xyz;
    o.normal = (inst.normal_matrix * vec4<f32>(v.normal, 0.0)).xyz;
    o.uv = v.uv;
    o.cur_clip = o.clip;
    o.prev_clip = camera.prev_view_proj * prev_world;
    return o;
}

struct FsOut {
    @location(0) position: vec4<f32>,
    @location(1) normal: vec4<f32>,
    @location(2) albedo: vec4<f32>,
    @location(3) material: vec4<f32>,
    @location(4) motion: vec2<f32>,
    @location(5) emission: vec4<f32>,
}

@fragment
fn fs_main(i: VsOut, @builtin(front_facing) front: bool) -> FsOut {
    return gbuffer_fragment(i, front);
}

// The G-buffer's outputs for one fragment (also Gautron's hemisphere atlas, whose fragment
// stage adds the object's index).
fn gbuffer_fragment(i: VsOut, front: bool) -> FsOut {
    var n = normalize(i.normal);
    if (!front) {
        n = -n;
    }
    var color = material.base_color;
    if (material.params.w > 0.5) {
        if (camera.lod.x >= 0.0) {
            color = color * textureSampleLevel(base_tex, base_sampler, i.uv, camera.lod.x);
        } else {
            color = color * textureSample(base_tex, base_sampler, i.uv);
        }
    }
    let view_pos = camera.view * vec4<f32>(i.world, 1.0);
    var o: FsOut;
    // w: linear view-space depth in scene units (distance along the view axis).
    o.position = vec4<f32>(i.world, -view_pos.z);
    // w = 1 marks covered pixels (the background keeps 0).
    o.normal = vec4<f32>(n, 1.0);
    o.albedo = vec4<f32>(color.rgb, material.params.x);
    o.material = vec4<f32>(material.params.y, material.params.z, material.extra.x, material.extra.y);
    o.motion = clip_to_pixel(i.prev_clip, camera.viewport) - clip_to_pixel(i.cur_clip, camera.viewport);
    var emission = material.emissive.rgb;
    if (material.emissive.w > 0.5) {
        // The camera filters by its footprint like the base colour; the light views read mip
        // 0 (their colour blur is for the VPLs' albedo, §4.3). The emitters' light samples
        // read the same texels on the CPU (scene::texture).
        if (camera.lod.x >= 0.0) {
            emission = emission * textureSampleLevel(emissive_tex, base_sampler, i.uv, 0.0).rgb;
        } else {
            emission = emission * textureSample(emissive_tex, base_sampler, i.uv).rgb;
        }
    }
    o.emission = vec4<f32>(emission, 1.0);
    return o;
}
