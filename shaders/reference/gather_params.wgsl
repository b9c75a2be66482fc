// The exact-VPL reference's gather uniform (Rust twin: passes::reference::vpl_gather::GatherParams),
// shared by the gather (reference/gather.wgsl) and its replay at a pinned pixel (reference/explain.wgsl).
struct Params {
    // x: VPL count of the batch, y: atlas columns, z: tile size, w: weight of this batch 1/(k+1)
    batch: vec4<f32>,
    // x: near, y: far, z: eye offset along the VPL normal, w: d_min (scene units)
    clip: vec4<f32>,
    // x: depth bias (texels), y: normal offset (texels), z: visibility on (1) / off (0),
    // w: receiver BRDF diffuse only (1: SI = 0) or full (0)
    bias: vec4<f32>,
    // x: the near field's cut² (senders closer are left to it; 0: none)
    near: vec4<f32>,
}
