// The hierarchical coherence buffer (Nguyen et al., 000 §3). Each level is two rgba32float
// textures: position (xyz world, w = a^w, the radius of the sphere the texel stands for)
// and normal (xyz, w = n^w, the group coherence; 0 = incoherent or background). Level k has
// ⌈w/2⌉ × ⌈h/2⌉ texels of level k − 1; texel (x, y) covers the 3×3 block centred at (2x, 2y).
// CPU twin: render/src/cpu/hcb.rs (the readings of the paper are documented there).

// Rust twin: passes::hcb::HcbParams.
struct HcbParams {
    // x: cos θ_max, y: cos γ_max, z: d_max (scene units), w: pixel scale 2 tan(fov_y/2) / height
    thresholds: vec4<f32>,
    // xyz: eye position
    eye: vec4<f32>,
    // x: 1 when this is the top level (sample pass), y: level index
    level: vec4<u32>,
}

// One sample of the compact list (Rust twin: passes::hcb::GpuHcbSample).
struct HcbSample {
    // xyz: world position (the level texel's), w: a^w, the radius of the sphere it stands for
    position: vec4<f32>,
    // xyz: normal, w: n^w
    normal: vec4<f32>,
    // x, y: texel at its level, z: level, w: 0
    texel: vec4<u32>,
    // rgb: the light gathered at the sample (irradiance), a: 1 once gathered
    light: vec4<f32>,
}
