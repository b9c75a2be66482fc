//! Colour maths shared by the tone mapper's twin and the scene's sky sampler.

/// Rec. 709 luminance.
pub fn luminance(c: [f32; 3]) -> f32 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}
