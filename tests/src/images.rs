//! Image arithmetic the render tests compare with: mean luminance, differences and FLIP at
//! the reference's exposure.

use gi_render::ImageF32;
use gi_render::image_io::hdr_display;
use gi_render::metrics::{auto_exposure, flip, scaled};

/// Rec. 709 luminance of a pixel.
pub fn luminance(p: &[f32; 4]) -> f64 {
    gi_render::maths::luminance([p[0], p[1], p[2]]) as f64
}

/// Mean luminance of an image.
pub fn mean(img: &ImageF32) -> f64 {
    img.data.iter().map(luminance).sum::<f64>() / img.data.len() as f64
}

/// `a − b`, pixel by pixel (alpha 1).
pub fn sub(a: &ImageF32, b: &ImageF32) -> ImageF32 {
    let data = a.data.iter().zip(&b.data).map(|(x, y)| [x[0] - y[0], x[1] - y[1], x[2] - y[2], 1.0]).collect();
    ImageF32 { width: a.width, height: a.height, data }
}

/// FLIP of `test` against `truth`, both at the exposure that brings the truth to middle grey
/// (dim scenes such as a box lit by a 1 W quad compare at a readable brightness).
pub fn exposed_flip(test: &ImageF32, truth: &ImageF32) -> f64 {
    let k = auto_exposure(truth);
    flip(&hdr_display(&scaled(test, k)), &hdr_display(&scaled(truth, k))).expect("same size").0
}
