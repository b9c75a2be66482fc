// Solid voxelization (Eisemann & Décoret 2008; Soler et al. 004 §4 "Visibility"): the scene
// is drawn from the camera into the grid of the first gathered level, culling off and no
// depth test; every fragment toggles the bits of its column from its slice to the back
// (XOR). A column then holds 1 where an odd number of surfaces lie in front: inside closed
// meshes. WebGPU has no logic-op blending, so the XOR is an atomicXor into a storage buffer
// from the fragment stage. A surface facing the viewer toggles at its depth moved back by its
// slope across the texel (voxel_toggle_depth; a setting, 0 = the paper's centre depth), so that
// a column turns solid only behind the whole texel's surface. The viewport maps the G-buffer's pixels onto the level's texels
// (1/2^k), so that the grid's columns are the level's texels. CPU twin:
// cpu::soler::voxelize_column. What an alpha mask cuts out (glTF alphaMode MASK) toggles
// nothing: it is not a surface (issue #37).
#import common/camera.wgsl
#import common/material.wgsl
#import soler/voxel_common.wgsl

struct Instance {
    model: mat4x4<f32>,
    prev_model: mat4x4<f32>,
    normal_matrix: mat4x4<f32>,
}

@group(0) @binding(0) var<uniform> camera: Camera;
@group(1) @binding(0) var<storage, read> instances: array<Instance>;
@group(3) @binding(0) var<uniform> params: VoxelParams;
@group(3) @binding(1) var<storage, read_write> grid: array<atomic<u32>>;

struct VsIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
}

struct VsOut {
    @builtin(position) clip: vec4<f32>,
    // View depth (clip w of the perspective projection).
    @location(0) depth: f32,
    @location(1) world: vec3<f32>,
    @location(2) normal: vec3<f32>,
    @location(3) uv: vec2<f32>,
}

@vertex
fn vs_voxelize(v: VsIn, @builtin(instance_index) instance: u32) -> VsOut {
    let world = instances[instance].model * vec4<f32>(v.position, 1.0);
    var o: VsOut;
    o.clip = camera.view_proj * world;
    o.depth = o.clip.w;
    o.world = world.xyz;
    o.normal = (instances[instance].normal_matrix * vec4<f32>(v.normal, 0.0)).xyz;
    o.uv = v.uv;
    return o;
}

@fragment
fn fs_voxelize(in: VsOut) -> @location(0) vec4<f32> {
    // The depth's change across one grid texel (the viewport's pixels are the grid's texels).
    let slope = fwidth(in.depth);
    if (material_cut(material_alpha(in.uv))) {
        discard;
    }
    let x = u32(in.clip.x);
    let y = u32(in.clip.y);
    if (x < params.grid.x && y < params.grid.y) {
        let facing = dot(in.normal, camera.position.xyz - in.world) >= 0.0;
        let first = voxel_slice(voxel_toggle_depth(in.depth, slope, facing, params), params);
        let base = (y * params.grid.x + x) * params.grid.z;
        for (var w = 0u; w < params.grid.z; w = w + 1u) {
            let mask = voxel_mask_from(first, w, params.grid.w);
            if (mask != 0u) {
                atomicXor(&grid[base + w], mask);
            }
        }
    }
    return vec4<f32>(0.0);
}
