// The VPL gather's uniform (Rust twin: passes::knecht::interleave::GatherParams), shared by
// the gather (knecht/interleave/gather.wgsl) and its replay at a pinned pixel (knecht/interleave/explain.wgsl).
struct GatherParams {
    // x: n, y: tile width, z: tile height, w: VPL count N
    split: vec4<u32>,
    // x: visibility (0 none, 1 ISM, 2 exact), y: atlas columns, z: map size, w: receiver
    // BRDF diffuse only (1: SI = 0, c·DI/π as the HCB's irradiance) or full (0)
    vis: vec4<u32>,
    // x: d_min², y: ISM eye offset / exact near, z: ISM bias / exact far,
    // w: ISM receiver normal offset (texels) / exact eye offset
    shade: vec4<f32>,
    // x: the near field's cut² (senders closer are left to it; 0: none)
    near: vec4<f32>,
}
