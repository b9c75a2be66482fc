// Stage 2, shadow maps: depth from the light's view for every light view (spot: one
// perspective view, point: six cube-face views, directional: one orthographic view over
// the scene bounds). Rendered from the real triangles; a material with alphaMode MASK is
// drawn by the cutout pipeline (`fs_cutout`), so that a cut-out leaf casts a cut-out shadow.
#import common/material.wgsl
struct Instance {
    model: mat4x4<f32>,
    prev_model: mat4x4<f32>,
    normal_matrix: mat4x4<f32>,
}

struct View {
    view_proj: mat4x4<f32>,
}

@group(0) @binding(0) var<uniform> view: View;
@group(1) @binding(0) var<storage, read> instances: array<Instance>;

struct VsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) uv: vec2<f32>,
}

@vertex
fn vs_main(@location(0) position: vec3<f32>, @location(2) uv: vec2<f32>, @builtin(instance_index) instance: u32) -> VsOut {
    var o: VsOut;
    o.clip = view.view_proj * (instances[instance].model * vec4<f32>(position, 1.0));
    o.uv = uv;
    return o;
}

// Alpha cutout of the depth-only view (§3.9.4).
@fragment
fn fs_cutout(i: VsOut) {
    if (material_cut(material_alpha(i.uv))) {
        discard;
    }
}
