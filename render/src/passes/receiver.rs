//! How a pixel reflects the irradiance that a technique interpolated to it (issue #51 point 1):
//! the HCB's splatted samples (Nguyen 000 §4.1–4.3) and Gautron's splatted records (003).
//! Both keep the irradiance's luminance-weighted mean incident direction beside it, so that a
//! glossy receiver gets its indirect specular light (`shaders/common/receiver.wgsl`, CPU twin
//! `cpu::brdf::receive_irradiance`, where the reading is documented).

use crate::settings_enum;

settings_enum! {
    /// How a pixel reflects the irradiance interpolated to it (the HCB's and Gautron's splats).
    pub enum IrradianceReceiver {
        /// The full BRDF: c·DI/π·E plus the specular lobe lit from the irradiance's mean
        /// incident direction, widened by its spread (`cpu::brdf::receive_irradiance`).
        Glossy = "full BRDF (E and its mean direction)",
        /// The papers' receiver, c·DI/π·E: a glossy surface loses its indirect specular light.
        DiffuseOnly = "diffuse only (as printed)",
    }
    default Glossy
}

impl IrradianceReceiver {
    /// The shaders' flag: 1 for the glossy receiver.
    pub fn flag(self) -> f32 {
        (self == IrradianceReceiver::Glossy) as u32 as f32
    }
}
