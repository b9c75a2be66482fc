// Stage 4, exact visibility of the VPLs: for each VPL, five 90° faces of a cube oriented on
// its normal (common/vpl.wgsl), rendered from the real triangles into one depth atlas. The
// exact-VPL reference (Knecht 002 §5.2 compares against VPLs with standard shadow maps) and
// the baseline that separates imperfect visibility from the VPL approximation.
#import common/vpl.wgsl
#import common/material.wgsl

struct Instance {
    model: mat4x4<f32>,
    prev_model: mat4x4<f32>,
    normal_matrix: mat4x4<f32>,
}

struct Face {
    // x: VPL index, y: face, z: tile of the atlas
    index: vec4<u32>,
}

struct Params {
    // x: near, y: far, z: offset of the eye along the normal (scene units)
    clip: vec4<f32>,
}

@group(0) @binding(0) var<uniform> face: Face;
@group(0) @binding(1) var<uniform> params: Params;
@group(0) @binding(2) var<storage, read> vpls: array<Vpl>;
@group(1) @binding(0) var<storage, read> instances: array<Instance>;

struct VsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) uv: vec2<f32>,
}

@vertex
fn vs_main(@location(0) position: vec3<f32>, @location(2) uv: vec2<f32>, @builtin(instance_index) instance: u32) -> VsOut {
    var o: VsOut;
    o.uv = uv;
    let vpl = vpls[face.index.x];
    if (vpl.position.w < 0.5) {
        // Empty slot: put every vertex beyond the far plane.
        o.clip = vec4<f32>(0.0, 0.0, 2.0, 1.0);
        return o;
    }
    let world = (instances[instance].model * vec4<f32>(position, 1.0)).xyz;
    let n = vpl.normal.xyz;
    let eye = vpl.position.xyz + n * params.clip.z;
    let axes = vpl_face_axes(vpl_basis(n), face.index.y);
    o.clip = vpl_face_clip(eye, axes, world, params.clip.x, params.clip.y);
    return o;
}

// Alpha cutout of the depth-only view (§3.9.4).
@fragment
fn fs_cutout(i: VsOut) {
    if (material_cut(material_alpha(i.uv))) {
        discard;
    }
}
