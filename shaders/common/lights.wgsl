// Punctual lights (KHR_lights_punctual) as the Rust side packs them (passes::shadow::GpuLight).
struct Light {
    // xyz position; w: kind (0 point, 1 spot, 2 directional).
    position: vec4<f32>,
    // xyz unit direction the light points to; w: range (0 = infinite).
    direction: vec4<f32>,
    // rgb: colour × intensity (W/sr for point and spot, W/m² for directional).
    color: vec4<f32>,
    // x: cos(outer cone), y: 1 / max(ε, cos(inner) − cos(outer)), z: first shadow layer,
    // w: shadow layer count (0: no shadow).
    cone: vec4<f32>,
    // x: world size of one shadow texel at unit distance (perspective) or absolute (ortho).
    shadow: vec4<f32>,
}

const LIGHT_POINT: f32 = 0.0;
const LIGHT_SPOT: f32 = 1.0;
const LIGHT_DIRECTIONAL: f32 = 2.0;
// A point of an emissive surface as a light (only in the exact-VPL reference's sampling
// list): radiant intensity color · max(n · ω, 0), n = direction.xyz.
const LIGHT_EMITTER: f32 = 3.0;

// KHR_lights_punctual recommended spot falloff: t = saturate((cos θ − cos θ_outer) ·
// 1/(cos θ_inner − cos θ_outer)); attenuation t².
fn spot_falloff(light: Light, l_to_surface: vec3<f32>) -> f32 {
    let cd = dot(light.direction.xyz, l_to_surface);
    let t = clamp((cd - light.cone.x) * light.cone.y, 0.0, 1.0);
    return t * t;
}

// KHR_lights_punctual range window: saturate(1 − (d/range)⁴).
fn range_window(range: f32, d: f32) -> f32 {
    if (range <= 0.0) {
        return 1.0;
    }
    let r = d / range;
    return clamp(1.0 - r * r * r * r, 0.0, 1.0);
}
