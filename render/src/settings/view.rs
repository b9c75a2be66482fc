//! How the buffer viewer maps one buffer to colour (its panel's settings; the pass is
//! `passes/view.rs`, the CPU twin `cpu::view`).

use serde::{Deserialize, Serialize};

use crate::buffers::BufferKind;

/// Which values are shown.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum ViewMode {
    /// The xyz channels as red, green and blue.
    #[default]
    Rgb,
    /// One channel through a colour map.
    Channel,
    /// The length of xyz (speed of a motion vector, norm of a normal) through a colour map.
    Length,
}

/// How one buffer is mapped to colour.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ViewSettings {
    pub mode: ViewMode,
    /// Channel index 0–3 (r, g, b, a) for [`ViewMode::Channel`].
    pub channel: u32,
    pub colormap: Colormap,
    /// Values in [range.0, range.1] (after the exposure scale) map to [0, 1].
    pub range: [f32; 2],
    /// Scale by 2^exposure_ev before the range (HDR buffers).
    pub exposure_ev: f32,
    /// Logarithmic mapping of the range (needs range.0 > 0; smaller values clamp).
    pub log: bool,
    /// Apply the sRGB transfer to RGB output (linear data such as radiance and albedo).
    pub srgb: bool,
    /// Paint NaN magenta and ±Inf green.
    pub flag_nan_inf: bool,
    /// Paint negative values cyan.
    pub flag_negative: bool,
    /// Array layer (shadow-map faces, atlases).
    pub layer: u32,
    /// Mip level (pyramids: HCB levels, pull-push levels, SSIL mips).
    pub level: u32,
}

impl Default for ViewSettings {
    fn default() -> Self {
        Self {
            mode: ViewMode::Rgb,
            channel: 0,
            colormap: Colormap::Viridis,
            range: [0.0, 1.0],
            exposure_ev: 0.0,
            log: false,
            srgb: true,
            flag_nan_inf: true,
            flag_negative: true,
            layer: 0,
            level: 0,
        }
    }
}

impl ViewSettings {
    /// A sensible first view of a buffer of this kind.
    pub fn for_kind(kind: BufferKind) -> Self {
        let d = Self::default();
        match kind {
            BufferKind::Ldr => Self { srgb: false, ..d },
            BufferKind::Hdr | BufferKind::Albedo => d,
            BufferKind::Direction => Self { range: [-1.0, 1.0], srgb: false, flag_negative: false, ..d },
            BufferKind::Data => Self { srgb: false, flag_negative: false, ..d },
            BufferKind::Depth => {
                Self { mode: ViewMode::Channel, colormap: Colormap::Grey, range: [0.9, 1.0], srgb: false, ..d }
            }
            BufferKind::Motion => Self {
                mode: ViewMode::Length,
                colormap: Colormap::Turbo,
                range: [0.0, 4.0],
                srgb: false,
                flag_negative: false,
                ..d
            },
        }
    }
}

/// False-colour maps.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum Colormap {
    #[default]
    Grey,
    Viridis,
    Turbo,
    Inferno,
}

impl Colormap {
    pub const ALL: [Colormap; 4] = [Colormap::Grey, Colormap::Viridis, Colormap::Turbo, Colormap::Inferno];
}
