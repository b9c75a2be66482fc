// Stage 1, G-buffer (Knecht 002 §4.2). World-space position, normal, albedo + diffuse
// intensity DI, specular intensity SI and power SP, and the movement buffer m_buf of
// §3.5.1: the screen-space offset from each pixel to where its surface point was in the
// previous frame, from the previous camera and the previous object transform.
// ⚠[knecht.movement-sign] Reading chosen: the thesis writes (x_s − x_prev, y_s − y_prev) but then looks up
// I_prev(x_s + Δx, y_s + Δy); we store Δ = prev − current so that the lookup is right.
// z holds the point's linear depth in the previous frame (previous camera, previous object
// transform): Soler et al.'s W "accounts for both the camera and the moving object" (004 §4),
// so the temporal filter compares the history's depth with this one.
#import common/camera.wgsl
#import common/material.wgsl
#import common/normal.wgsl

struct Instance {
    model: mat4x4<f32>,
    prev_model: mat4x4<f32>,
    normal_matrix: mat4x4<f32>,
}

// Whether the pipeline draws materials with textures (issue #53): the camera's G-buffer draws
// untextured materials with this false, so that its fragment stage carries none of the
// texture branches (on lavapipe they cost about a third of the pass even when not taken).
override TEXTURED: bool = true;

// Whether target 0 is the camera's `gbuffer.linear_depth` (R32Float, issue #53): it then gets
// the linear depth alone, and the passes rebuild the position from it
// (common/camera.wgsl `world_from_linear_depth`); false: the light views' and the hemispheres'
// `position` (world position in xyz, linear depth in w).
override LINEAR_DEPTH: bool = false;

@group(0) @binding(0) var<uniform> camera: Camera;
@group(1) @binding(0) var<storage, read> instances: array<Instance>;

struct VsIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    // xyz: object-space tangent, w: bitangent sign (0 0 0 0: none)
    @location(3) tangent: vec4<f32>,
}

struct VsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
    @location(3) cur_clip: vec4<f32>,
    @location(4) prev_clip: vec4<f32>,
    @location(5) tangent: vec4<f32>,
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
    o.tangent = vec4<f32>((inst.model * vec4<f32>(v.tangent.xyz, 0.0)).xyz, v.tangent.w);
    o.cur_clip = o.clip;
    o.prev_clip = camera.prev_view_proj * prev_world;
    return o;
}

struct FsOut {
    @location(0) position: vec4<f32>,
    @location(1) normal: vec4<f32>,
    @location(2) albedo: vec4<f32>,
    @location(3) material: vec4<f32>,
    @location(4) motion: vec4<f32>,
    @location(5) emission: vec4<f32>,
}

@fragment
fn fs_main(i: VsOut, @builtin(front_facing) front: bool) -> FsOut {
    return gbuffer_fragment(i, front);
}

// The camera's G-buffer (issue #53): target 0 the linear depth (LINEAR_DEPTH), target 1 the
// normal packed in one word (common/normal.wgsl, `passes::gbuffer::PACKED_NORMAL_FORMAT`), 4
// bytes a pixel instead of 8; `gbuffer.normal` is unpacked from it (gbuffer/normal.wgsl).
struct FsCameraOut {
    @location(0) linear_depth: vec4<f32>,
    @location(1) normal: u32,
    @location(2) albedo: vec4<f32>,
    @location(3) material: vec4<f32>,
    @location(4) motion: vec4<f32>,
    @location(5) emission: vec4<f32>,
}

@fragment
fn fs_camera(i: VsOut, @builtin(front_facing) front: bool) -> FsCameraOut {
    let o = gbuffer_fragment(i, front);
    return FsCameraOut(o.position, pack_normal(o.normal), o.albedo, o.material, o.motion, o.emission);
}

// A data map (normal, metallic-roughness, occlusion) at the fragment, filtered as the base
// colour is: by the camera's footprint, or at the light view's level.
fn sample_map(t: texture_2d<f32>, uv: vec2<f32>) -> vec4<f32> {
    if (camera.lod.x >= 0.0) {
        return textureSampleLevel(t, base_sampler, uv, camera.lod.x);
    }
    return textureSample(t, base_sampler, uv);
}

// The G-buffer's outputs for one fragment (also Gautron's hemisphere atlas, whose fragment
// stage adds the object's index).
fn gbuffer_fragment(i: VsOut, front: bool) -> FsOut {
    var color = material.base_color;
    if (TEXTURED && material.params.w > 0.5) {
        if (camera.lod.x >= 0.0) {
            color = color * textureSampleLevel(base_tex, base_sampler, i.uv, camera.lod.x);
        } else {
            color = color * textureSample(base_tex, base_sampler, i.uv);
        }
    }
    // glTF alphaMode MASK (§3.9.4): the cut-out part is not a surface.
    if (material_cut(color.a)) {
        discard;
    }
    // The shading normal: the interpolated one, bent by the normal texture (§3.9.3: tangent
    // space x = tangent, y = bitangent = sign · n × t, z = n; xy × scale), then turned to the
    // side the camera sees.
    var n = normalize(i.normal);
    if (TEXTURED && material.maps.x != 0.0) {
        var tn = sample_map(normal_tex, i.uv).xyz * 2.0 - 1.0;
        tn = vec3<f32>(tn.xy * material.maps.x, tn.z);
        let t_len = length(i.tangent.xyz);
        if (t_len > 1e-6 && i.tangent.w != 0.0) {
            let t = normalize(i.tangent.xyz - n * dot(n, i.tangent.xyz));
            let b = cross(n, t) * sign(i.tangent.w);
            let bent = t * tn.x + b * tn.y + n * tn.z;
            if (dot(bent, bent) > 1e-12) {
                n = normalize(bent);
            }
        }
    }
    if (!front) {
        n = -n;
    }
    // Metallic-roughness texture (§3.9.2: B = metallic, G = roughness, times the factors):
    // DI, SI and SP per fragment by `scene::Material::intensities_at`'s mapping.
    var params = material.params;
    var metal_rough = material.extra.xy;
    if (TEXTURED && material.maps.y > 0.5) {
        let mr = sample_map(mr_tex, i.uv);
        let metallic = clamp(material.extra.x * mr.b, 0.0, 1.0);
        let roughness = clamp(material.extra.y * mr.g, 0.0, 1.0);
        let lum = dot(color.rgb, vec3<f32>(0.2126, 0.7152, 0.0722));
        params = vec4<f32>(1.0 - metallic, 0.04 * (1.0 - metallic) + lum * metallic,
            material_specular_power(roughness), params.w);
        metal_rough = vec2<f32>(metallic, roughness);
    }
    let view_pos = camera.view * vec4<f32>(i.world, 1.0);
    var o: FsOut;
    // w: linear view-space depth in scene units (distance along the view axis).
    o.position = vec4<f32>(i.world, -view_pos.z);
    if (LINEAR_DEPTH) {
        o.position = vec4<f32>(-view_pos.z, 0.0, 0.0, 0.0);
    }
    // w = 1 marks covered pixels (the background keeps 0).
    o.normal = vec4<f32>(n, 1.0);
    o.albedo = vec4<f32>(color.rgb, params.x);
    o.material = vec4<f32>(params.y, params.z, metal_rough.x, metal_rough.y);
    // The fragment's own position is the pixel centre (issue #53: one interpolated input less
    // than projecting the interpolated clip position again).
    let m = clip_to_pixel(i.prev_clip, camera.viewport) - i.clip.xy;
    o.motion = vec4<f32>(m, i.prev_clip.w, 1.0);
    var emission = material.emissive.rgb;
    if (TEXTURED && material.emissive.w > 0.5) {
        // The camera filters by its footprint like the base colour; the light views read mip
        // 0 (their colour blur is for the VPLs' albedo, §4.3). The emitters' light samples
        // read the same texels on the CPU (scene::texture).
        if (camera.lod.x >= 0.0) {
            emission = emission * textureSampleLevel(emissive_tex, base_sampler, i.uv, 0.0).rgb;
        } else {
            emission = emission * textureSample(emissive_tex, base_sampler, i.uv).rgb;
        }
    }
    // a: the occlusion texture's R (§3.9.5), 1 without one: loaded so that it can be viewed,
    // never multiplied into the computed light.
    var occlusion = 1.0;
    if (TEXTURED && material.maps.w > 0.5) {
        occlusion = sample_map(occlusion_tex, i.uv).r;
    }
    o.emission = vec4<f32>(emission, occlusion);
    return o;
}
