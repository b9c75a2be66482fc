//! The settings of the exact-VPL reference, the per-pixel gather every VPL technique is
//! compared with (`passes/reference/`).

use crate::settings_group;

settings_group! {
    /// Exact-VPL reference (issue #3): many VPLs, each with an exact visibility map rendered
    /// from the real triangles, accumulated over frames (Knecht 002 §5.2's reference).
    pub struct ReferenceSettings: "reference" {
        /// VPLs rendered per frame (one batch); each has five depth maps rendered per frame.
        vpls_per_frame: u32 = 64,
        unit "VPLs", symbol "", range 1..=1024, cost "five depth renders of the scene and one gather term per pixel per VPL", history true;
        /// Total VPLs after which accumulation stops (the image is then final).
        total_vpls: u32 = 4096,
        unit "VPLs", symbol "N", range 1..=1048576, cost "frames = total / per frame", history false;
        /// Side of the light G-buffer the VPLs are sampled from.
        light_gbuffer_size: u32 = 512,
        unit "px", symbol "", range 64..=4096, cost "one G-buffer render of this size per frame", history true;
        /// Side of each of the five cube faces of a VPL's visibility map.
        shadow_map_size: u32 = 128,
        unit "px", symbol "", range 16..=1024, cost "memory 20 B/texel² per VPL of a batch; raster time", history true;
        /// Distance clamp of the geometry term (1/max(d², d_min²), Knecht 002 Eq. 4.7);
        /// 0 keeps the reference unbiased.
        min_distance_m: f32 = 0.0,
        unit "m", symbol "d_min", range 0.0..=10.0, cost "free", history true;
        /// Receiver offset toward the VPL, in texels of its depth map at the receiver's distance.
        depth_bias: f32 = 1.0,
        unit "texels", symbol "", range 0.0..=8.0, cost "free", history true;
        /// Receiver offset along its normal, in texels of the VPL's depth map.
        normal_offset: f32 = 1.0,
        unit "texels", symbol "", range 0.0..=8.0, cost "free", history true;
        /// Seed of the VPL sampling (identical seeds give identical images).
        seed: u32 = 1,
        unit "", symbol "", range 0..=4294967295u32, cost "free", history true;
        /// Points on the emissive surfaces whose first bounce the reference samples exactly
        /// (each a cosine-lobed point light with five views taken in turn with the lights'
        /// views; issue #18). Their direct light is stage 2's, with `emitters.vpls` points.
        emitter_points: u32 = 16,
        unit "points", symbol "", range 1..=256, cost "five more light views in the batches' cycle per point", history true;
    }
    legacy {
        /// Version 1: exact visibility on or off; now `pipeline.vpl_visibility` (Exact or None).
        visibility: bool;
    }
}
