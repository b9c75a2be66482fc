//! CPU reference of the tone mapper (`shaders/compose/luminance.wgsl`,
//! `shaders/compose/tonemap.wgsl`): Reinhard et al. [RSSF02] Eq. 1 (log-average over
//! pixels with Lw > 0, as the GPU does), Eq. 2 and Eq. 4, then sRGB encoding.

use crate::buffers::ImageF32;
use crate::maths::luminance;
use crate::settings::compose::TonemapSettings;

/// L̄w = exp(mean log(δ + Lw)) over pixels with Lw > 0 (1 when there are none), each log
/// clamped to ±30 (Lw ≤ e^30 ≈ 10^13) as the GPU's sums are.
pub fn log_average(hdr: &ImageF32) -> f32 {
    let (mut sum, mut n) = (0.0f64, 0u64);
    for p in &hdr.data {
        let lw = luminance([p[0].max(0.0), p[1].max(0.0), p[2].max(0.0)]);
        if lw > 0.0 {
            // ±30 as the GPU's fixed-point sums clamp it (compose.wgsl, LOG_LIMIT).
            sum += (1e-4 + lw as f64).ln().clamp(-30.0, 30.0);
            n += 1;
        }
    }
    if n == 0 { 1.0 } else { (sum / n as f64).exp() as f32 }
}

/// sRGB encoding of a linear value in [0, 1].
pub fn srgb_encode(c: f32) -> f32 {
    if c <= 0.003_130_8 { c * 12.92 } else { 1.055 * c.powf(1.0 / 2.4) - 0.055 }
}

/// The display value (sRGB-encoded, in [0, 1]) of an HDR colour.
pub fn reinhard(c: [f32; 3], settings: &TonemapSettings, log_avg: f32) -> [f32; 3] {
    let c = c.map(|x| x.max(0.0));
    let lw = luminance(c);
    let mut s = settings.exposure_ev.exp2();
    if settings.auto_exposure {
        s *= settings.key / log_avg.max(1e-6);
    }
    let l = s * lw;
    let ld = l * (1.0 + l / (settings.white_point * settings.white_point)) / (1.0 + l);
    let ratio = if lw > 0.0 { ld / lw } else { 0.0 };
    c.map(|x| srgb_encode((x * ratio).clamp(0.0, 1.0)))
}
