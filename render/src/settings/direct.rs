//! The settings of stage 2, the direct light and its shadow maps (`passes/direct.rs`).

use crate::settings_group;

settings_group! {
    /// Direct light and its shadow maps (stage 2).
    pub struct DirectSettings: "direct" {
        /// Scales the intensity of every primary light (the scene's own values are in
        /// KHR_lights_punctual units: candela for spot and point, lux for directional).
        intensity_scale: f32 = 1.0,
        unit "×", symbol "", range 0.0..=1000.0, cost "free", history true;
        /// Render shadow maps and test visibility; off lights everything the cone reaches.
        shadows: bool = true,
        unit "", symbol "", range 0..=1, cost "one depth pass per light view", history true;
        /// Resolution of each shadow map layer (spot and directional: one layer, point: six).
        shadow_map_size: u32 = 1024,
        unit "px", symbol "", range 64..=8192, cost "memory 4 B/texel per layer; raster time grows with it", history true;
        /// Percentage-closer filtering radius: (2r+1)² depth comparisons per pixel and light.
        pcf_radius: u32 = 1,
        unit "texels", symbol "r", range 0..=4, cost "(2r+1)² comparisons per pixel and light", history true;
        /// Receiver offset toward the light, in shadow-map texels at the receiver's distance
        /// (a world-space depth bias: the same in every scene and at every distance).
        depth_bias: f32 = 1.0,
        unit "texels", symbol "", range 0.0..=8.0, cost "free", history true;
        /// Receiver offset along its normal, in shadow-map texels at the receiver's distance.
        normal_offset: f32 = 1.5,
        unit "texels", symbol "", range 0.0..=8.0, cost "free", history true;
    }
}
