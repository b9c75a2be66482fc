// The light a view of a punctual light sends through its image plane (Knecht 002 §4.3–4.4:
// the light G-buffer is rendered from this view). Perspective views (spot, point cube faces):
// the flux through d(uv) is I · falloff · e² cos³θ d(uv), the image plane at unit distance
// spanning e = pixel extent and θ the angle to the view axis; orthographic (directional):
// E · e² d(uv). Rust twin: passes::vpl::SampleParams / passes::vpl_importance::ViewParams.
#import common/lights.wgsl

struct LightView {
    // xyz: eye of the view; w: 1 for an orthographic view
    eye: vec4<f32>,
    // xyz: unit view axis; w: extent e of the image plane (unit distance, or world units)
    forward: vec4<f32>,
}

// Uniform of one light view's importance and warp passes (Rust twin:
// passes::vpl_importance::ViewParams).
struct ViewParams {
    view: LightView,
    // x: first VPL slot, y: VPL count N_v of this view, z: light index, w: importance layer
    range: vec4<u32>,
    // x: Halton index of this frame's first sample
    seq: vec4<u32>,
    // x: flux scale (the direct light's intensity scale), y: finest level's side, z: Eq. 4.3's
    // constant b of (b + SP') (`vpl.importance_bias`)
    scale: vec4<f32>,
}

// Flux per unit uv area (W) that `light` sends through the view toward surface point p.
fn flux_per_uv(light: Light, view: LightView, p: vec3<f32>) -> vec3<f32> {
    let e2 = view.forward.w * view.forward.w;
    if (view.eye.w > 0.5) {
        return light.color.rgb * e2;
    }
    let d_vec = p - view.eye.xyz;
    let d = length(d_vec);
    let dir = d_vec / max(d, 1e-9);
    let cos_axis = max(dot(dir, view.forward.xyz), 0.0);
    var falloff = range_window(light.direction.w, d);
    if (light.position.w == LIGHT_SPOT) {
        falloff = falloff * spot_falloff(light, dir);
    }
    return light.color.rgb * falloff * e2 * cos_axis * cos_axis * cos_axis;
}

// Unit direction from p toward the light of the view.
fn toward_light(view: LightView, p: vec3<f32>) -> vec3<f32> {
    if (view.eye.w > 0.5) {
        return -view.forward.xyz;
    }
    return normalize(view.eye.xyz - p);
}
