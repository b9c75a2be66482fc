//! The settings of the last stage: exposure and the tone map (`passes/compose.rs`).

use crate::settings_group;

settings_group! {
    /// Tone mapping (stage 7): Reinhard's global photographic operator.
    pub struct TonemapSettings: "tonemap" {
        /// Exposure in stops: the HDR image is scaled by 2^EV before the operator.
        exposure_ev: f32 = 0.0,
        unit "EV", symbol "", range -16.0..=16.0, cost "free", history false;
        /// Scale by the key a over the log-average luminance L̄w (Reinhard Eq. 2) instead of
        /// using the exposure alone.
        auto_exposure: bool = true,
        unit "", symbol "", range 0..=1, cost "one reduction over the image", history false;
        /// Key value a of the automatic exposure (Reinhard Eq. 2): 0.18 is "middle grey".
        key: f32 = 0.18,
        unit "", symbol "a", range 0.01..=1.0, cost "free", history false;
        /// Smallest luminance mapped to pure white (Reinhard Eq. 4).
        white_point: f32 = 4.0,
        unit "", symbol "L_white", range 0.1..=1000.0, cost "free", history false;
    }
}
