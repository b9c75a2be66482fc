//! How the splatting techniques sum and reflect what they splat (Nguyen 000 §4.1–4.3's
//! samples, Gautron 003's records): the splat's method, and how a pixel reflects the
//! irradiance interpolated to it (issue #51 point 1; `shaders/common/receiver.wgsl`, CPU twin
//! `cpu::brdf::receive_irradiance`, where the reading is documented).

use crate::gpu::GpuContext;
use crate::settings_enum;

settings_enum! {
    /// How a splat's weighted light is summed at the pixels (Gautron's records, the HCB's
    /// samples); every method gives the same sums, in the same order.
    pub enum SplatMethod {
        /// The fastest on this device: binned on a GPU, blended quads on a CPU renderer
        /// (lavapipe), where the binning was measured 3.5× slower (docs/performance.md).
        Auto = "the device's fastest",
        /// One quad per item, added by blending into float targets (the texts' `GL_ONE,
        /// GL_ONE`): the cost is the quads' overdraw.
        Blend = "blended quads (the texts)",
        /// The items binned into 64-pixel squares in compute, each pixel summing the items of
        /// its square (GI Lab, issue #38: no overdraw nor blending; 46× cheaper than the
        /// quads for Gautron's splat on an H200, docs/performance.md).
        Binned = "binned in compute (GI Lab)",
    }
    default Auto
}

impl SplatMethod {
    /// The method that runs on `ctx`'s device: `Auto` resolved by the adapter's type.
    pub fn on(self, ctx: &GpuContext) -> SplatMethod {
        match self {
            SplatMethod::Auto if ctx.adapter_info.device_type == wgpu::DeviceType::Cpu => SplatMethod::Blend,
            SplatMethod::Auto => SplatMethod::Binned,
            m => m,
        }
    }
}

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
