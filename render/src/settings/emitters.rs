//! The settings of the emissive surfaces as VPL senders (`passes/emitters.rs`).

use crate::{settings_enum, settings_group};

settings_enum! {
    /// How the direct light of emitter VPLs is shadowed.
    pub enum EmitterVisibility {
        /// An imperfect shadow map per emitter VPL (Ritschel et al. 2008; the `ism.*` settings).
        Imperfect = "imperfect shadow maps (Ritschel)",
        /// Five 90° depth maps per emitter VPL rendered from the triangles.
        Exact = "exact maps",
        /// No shadows from emitters.
        None = "none",
    }
    default Imperfect
}

settings_group! {
    /// Emissive surfaces as lights (stage 2; issue #18): VPLs on the emitters give their direct
    /// light and, with the VPL techniques, the first bounce.
    pub struct EmitterSettings: "emitters" {
        /// Emissive surfaces light the scene; off: they only glow (their emission is shown,
        /// nothing is lit by it).
        enabled: bool = true,
        unit "", symbol "", range 0..=1, cost "the passes below, only in scenes with emissive surfaces", history true;
        /// VPLs on the emitters per frame (direct light; the first bounce's sources are the
        /// first of them). 64 keeps the direct pass near 160 ms at 663×601 on lavapipe (256:
        /// 630 ms, every pixel sums every emitter VPL); soft shadows band below about 64.
        vpls: u32 = 64,
        unit "VPLs", symbol "N_e", range 1..=4096, cost "one term per pixel and emitter VPL; one ISM (or five depth maps) each", history true;
        /// Shadows of the emitters' direct light.
        visibility: EmitterVisibility = EmitterVisibility::Imperfect,
        unit "", symbol "", range 0..=2, cost "ISMs: one splat of the cloud and pull-push; exact: five scene renders per VPL", history true;
        /// Distance clamp of the emitter VPLs' geometry term, in units of their spacing
        /// √(A/N_e): a point sample's 1/d² is clamped where the area it stands for subtends
        /// more than it (0: no clamp, bright spots next to emitters).
        min_distance: f32 = 1.0,
        unit "× spacing", symbol "", range 0.0..=16.0, cost "free", history true;
        /// Double-sided materials (glTF `doubleSided`) emit from both sides; off: from the
        /// side their normals face (see `scene::emitters`).
        two_sided: bool = false,
        unit "", symbol "", range 0..=1, cost "free", history true;
    }
}
