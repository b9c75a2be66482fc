//! Low-discrepancy and hash sequences shared by the GPU passes (which upload what they give),
//! the CPU twins and the scene's samplers (docs/architecture.md, "Layers").

/// Element `index` of the Halton sequence in base `base`, in [0, 1) (Halton 1964; Knecht §3.3
/// uses it as the low-discrepancy set that hierarchical warping redistributes).
pub fn halton(mut index: u32, base: u32) -> f32 {
    let (mut f, mut r) = (1.0f32, 0.0f32);
    while index > 0 {
        f /= base as f32;
        r += f * (index % base) as f32;
        index /= base;
    }
    r
}

/// PCG hash (Jarzynski & Olano, JCGT 2020), the GPU's random source for the bounce selection.
pub fn pcg_hash(v: u32) -> u32 {
    let state = v.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277_803_737);
    (word >> 22) ^ word
}

/// The golden angle (radians): successive spiral samples are this far apart.
pub const GOLDEN_ANGLE: f32 = 2.399_963_2;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn halton_is_the_radical_inverse() {
        assert_eq!([1, 2, 3, 4].map(|i| halton(i, 2)), [0.5, 0.25, 0.75, 0.125]);
        assert!((halton(5, 3) - 7.0 / 9.0).abs() < 1e-6);
    }
}
