//! The scene's scale for its relative settings (issue #51 point 4; the measuring is
//! `crate::scale`).

use crate::{settings_enum, settings_group};

settings_enum! {
    /// What "the scene's radius" of the scene-relative settings means.
    pub enum ScaleReference {
        /// Half the diagonal of the room the camera stands in (the loader's interior view),
        /// else the model's bounding radius.
        Room = "the room the camera is in, else the model",
        /// The model's bounding radius (GI Lab before issue #51).
        Model = "the whole model's bounding sphere",
    }
    default Room
}

settings_group! {
    /// The scene's scale for its relative settings (HCB d_max, Gautron's radius clamps, the
    /// near field's split).
    pub struct ScaleSettings: "scale" {
        /// The length the scene-relative settings are fractions of.
        reference: ScaleReference = ScaleReference::Room,
        unit "", symbol "", range 0..=1, cost "free", history true;
    }
}
