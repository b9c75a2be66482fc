// Stage 2, shadow maps: depth from the light's view for every light view (spot: one
// perspective view, point: six cube-face views, directional: one orthographic view over
// the scene bounds). Rendered from the real triangles.
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

@vertex
fn vs_main(@location(0) position: vec3<f32>, @builtin(instance_index) instance: u32) -> @builtin(position) vec4<f32> {
    return view.view_proj * (instances[instance].model * vec4<f32>(position, 1.0));
}
