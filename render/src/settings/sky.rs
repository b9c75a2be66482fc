//! The settings of the sky as light: its directions and background (`passes/sky.rs`).

use crate::settings_group;

settings_group! {
    /// The sky light's sampling (stage 2; issue #18): how many directional VPLs stand for it.
    pub struct SkySettings: "sky" {
        /// Directions the sky is sampled in, each a directional light with its own shadow map
        /// (a layer of `direct.shadow_map` at `direct.shadow_map_size`², 4 MiB at 1024²) and
        /// light view. 16 shows banded penumbrae of wide occluders; 64 is smoother.
        directions: u32 = 16,
        unit "directions", symbol "N_sky", range 1..=64, cost "one shadow map (direct.shadow_map_size²) and one light view each, only with the scene's sky on", history true;
        /// Rotate the directions every frame (issue #51: a Cranley–Patterson shift of the
        /// stratified set, `scene::sky::sky_shift`): while nothing moves, the direct light's
        /// average over frames (`direct.sky_history`) and the bounce light the temporal stages
        /// and the exact-VPL reference accumulate converge to the true sky. Off: the same
        /// N_sky directions every frame (a plane gets between 0.8× and 1.2× its irradiance
        /// with 16, and the directions' hard shadows overlap).
        rotate_each_frame: bool = true,
        unit "", symbol "", range 0..=1, cost "a history of the direct light (16 B a pixel) while the sky is on", history true;
        /// Draw the sky behind the scene: pixels the scene does not cover show the sky's
        /// radiance along their ray (stage 7's compose; the path tracer's escaping camera
        /// rays see it too). Off: black, the sky only lights.
        background: bool = true,
        unit "", symbol "", range 0..=1, cost "free", history false;
    }
}
