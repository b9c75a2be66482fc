//! Image metrics (issue #3): how far an approximation is from the truth, per frame and
//! over time.
//!
//! - [`rmse`] and [`rel_mse`] on linear HDR radiance (RGB);
//! - [`flip`]: NVIDIA's FLIP (Andersson et al. 2020, LDR variant) on tone-mapped,
//!   sRGB-encoded images through the `nv-flip` crate, with its per-pixel error map;
//! - [`flicker`]: mean absolute relative luminance change between consecutive frames of a
//!   static camera and scene;
//! - [`afterglow`]: frames until the error returns within 2× its steady state after a
//!   sudden change.

use crate::buffers::ImageF32;
use crate::maths::luminance;

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum MetricError {
    #[error("the images differ in size: {0}×{1} and {2}×{3}")]
    Size(u32, u32, u32, u32),
    #[error("the images are empty")]
    Empty,
    #[error("a flicker measurement needs at least two frames, got {0}")]
    TooFewFrames(usize),
}

fn check(a: &ImageF32, b: &ImageF32) -> Result<(), MetricError> {
    if a.width != b.width || a.height != b.height {
        return Err(MetricError::Size(a.width, a.height, b.width, b.height));
    }
    if a.data.is_empty() {
        return Err(MetricError::Empty);
    }
    Ok(())
}

/// Root-mean-square error over all pixels and the three colour channels.
pub fn rmse(test: &ImageF32, reference: &ImageF32) -> Result<f64, MetricError> {
    check(test, reference)?;
    let sum: f64 = test
        .data
        .iter()
        .zip(&reference.data)
        .map(|(t, r)| (0..3).map(|c| (t[c] as f64 - r[c] as f64).powi(2)).sum::<f64>())
        .sum();
    Ok((sum / (3 * test.data.len()) as f64).sqrt())
}

/// Relative mean squared error, mean of (t − r)² / (r² + ε) with ε = 0.01 (the usual
/// definition of the rendering literature, which keeps dark pixels from dominating).
pub fn rel_mse(test: &ImageF32, reference: &ImageF32) -> Result<f64, MetricError> {
    check(test, reference)?;
    const EPS: f64 = 0.01;
    let sum: f64 = test
        .data
        .iter()
        .zip(&reference.data)
        .map(|(t, r)| (0..3).map(|c| (t[c] as f64 - r[c] as f64).powi(2) / ((r[c] as f64).powi(2) + EPS)).sum::<f64>())
        .sum();
    Ok(sum / (3 * test.data.len()) as f64)
}

/// The exposure that brings `img`'s log-average luminance to the middle grey 0.18 (Reinhard
/// et al. 2002's key, as the lab's automatic exposure): compare dim scenes (a room lit by a
/// weak emitter) on their visible range. 1 for a black image.
pub fn auto_exposure(img: &ImageF32) -> f32 {
    let (mut sum, mut n) = (0.0f64, 0u64);
    for p in &img.data {
        let l = luminance([p[0], p[1], p[2]]) as f64;
        if l.is_finite() && l > 0.0 {
            sum += (l + 1e-6).ln();
            n += 1;
        }
    }
    if n == 0 {
        return 1.0;
    }
    (0.18 / (sum / n as f64).exp()) as f32
}

/// `img` with its colour scaled by `k` (alpha kept).
pub fn scaled(img: &ImageF32, k: f32) -> ImageF32 {
    let data = img.data.iter().map(|p| [p[0] * k, p[1] * k, p[2] * k, p[3]]).collect();
    ImageF32 { width: img.width, height: img.height, data }
}

/// 8-bit sRGB RGB bytes of a display image with values in [0, 1] (such as `final.ldr`).
fn to_rgb8(img: &ImageF32) -> Vec<u8> {
    img.data.iter().flat_map(|p| [p[0], p[1], p[2]].map(|x| (x.clamp(0.0, 1.0) * 255.0).round() as u8)).collect()
}

/// Mean FLIP between two display images (sRGB-encoded values in [0, 1]) and the per-pixel
/// error map (r = g = b = error in [0, 1]). Viewing conditions: FLIP's default
/// (0.7 m from a 0.7 m wide 3840-pixel monitor, ≈ 67 pixels per degree).
pub fn flip(test: &ImageF32, reference: &ImageF32) -> Result<(f64, ImageF32), MetricError> {
    check(test, reference)?;
    let (w, h) = (test.width, test.height);
    let r = nv_flip::FlipImageRgb8::with_data(w, h, &to_rgb8(reference));
    let t = nv_flip::FlipImageRgb8::with_data(w, h, &to_rgb8(test));
    let map = nv_flip::flip(r, t, nv_flip::DEFAULT_PIXELS_PER_DEGREE);
    let mean = nv_flip::FlipPool::from_image(&map).mean() as f64;
    let data = map.to_vec().into_iter().map(|e| [e, e, e, 1.0]).collect();
    Ok((mean, ImageF32 { width: w, height: h, data }))
}

/// Temporal flicker of a frame sequence: the mean over consecutive pairs and pixels of
/// |L_t − L_{t−1}| / max((L_t + L_{t−1}) / 2, ε), L the Rec. 709 luminance and ε = 10⁻⁴.
/// The symmetric denominator makes the measure the same whichever frame comes first; a
/// constant sequence gives 0, a pixel alternating between a and b gives 2|a − b| / (a + b).
pub fn flicker(frames: &[ImageF32]) -> Result<f64, MetricError> {
    if frames.len() < 2 {
        return Err(MetricError::TooFewFrames(frames.len()));
    }
    let mut sum = 0.0f64;
    let mut count = 0u64;
    for pair in frames.windows(2) {
        check(&pair[1], &pair[0])?;
        for (a, b) in pair[0].data.iter().zip(&pair[1].data) {
            let la = luminance([a[0], a[1], a[2]]) as f64;
            let lb = luminance([b[0], b[1], b[2]]) as f64;
            sum += (lb - la).abs() / ((la + lb) * 0.5).max(1e-4);
            count += 1;
        }
    }
    Ok(sum / count as f64)
}

/// Afterglow: given the per-frame error after a sudden change at frame `change` (errors[i]
/// is frame i's error against its own reference), the number of frames from the change
/// until the error is back within 2× the steady state — the mean error of the last quarter
/// of the sequence. None when it never comes back.
pub fn afterglow(errors: &[f64], change: usize) -> Option<usize> {
    if errors.len() < 4 || change >= errors.len() {
        return None;
    }
    let tail = &errors[errors.len() - errors.len() / 4..];
    let steady = tail.iter().sum::<f64>() / tail.len() as f64;
    errors[change..].iter().position(|&e| e <= 2.0 * steady)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn constant(w: u32, h: u32, v: [f32; 4]) -> ImageF32 {
        ImageF32 { width: w, height: h, data: vec![v; (w * h) as usize] }
    }

    fn gradient(w: u32, h: u32) -> ImageF32 {
        let data = (0..w * h).map(|i| {
            let x = (i % w) as f32 / w as f32;
            let y = (i / w) as f32 / h as f32;
            [x, y, 0.5 * (x + y), 1.0]
        });
        ImageF32 { width: w, height: h, data: data.collect() }
    }

    #[test]
    fn identical_images_have_zero_error() {
        let g = gradient(64, 48);
        assert_eq!(rmse(&g, &g), Ok(0.0));
        assert_eq!(rel_mse(&g, &g), Ok(0.0));
        let (mean, map) = flip(&g, &g).expect("flip");
        assert_eq!(mean, 0.0);
        assert!(map.data.iter().all(|p| p[0] == 0.0));
    }

    #[test]
    fn known_pairs_give_known_values() {
        // A uniform offset d in every channel: RMSE = d, relMSE = d² / (r² + 0.01).
        let r = constant(8, 8, [0.5, 0.5, 0.5, 1.0]);
        let t = constant(8, 8, [0.7, 0.7, 0.7, 1.0]);
        assert!((rmse(&t, &r).expect("rmse") - 0.2).abs() < 1e-6);
        let want = 0.04 / (0.25 + 0.01);
        assert!((rel_mse(&t, &r).expect("relmse") - want).abs() < 1e-6);
        // Black against white is FLIP's largest colour difference: close to 1 everywhere.
        let black = constant(32, 32, [0.0, 0.0, 0.0, 1.0]);
        let white = constant(32, 32, [1.0, 1.0, 1.0, 1.0]);
        let (mean, _) = flip(&black, &white).expect("flip");
        assert!(mean > 0.9, "FLIP(black, white) = {mean}");
        // A small change gives a small but non-zero FLIP, a larger one a larger FLIP.
        let grey = constant(32, 32, [0.5, 0.5, 0.5, 1.0]);
        let (small, _) = flip(&constant(32, 32, [0.52, 0.5, 0.5, 1.0]), &grey).expect("flip");
        let (large, _) = flip(&constant(32, 32, [0.8, 0.5, 0.5, 1.0]), &grey).expect("flip");
        assert!(small > 0.0 && small < large, "small {small} large {large}");
        assert_eq!(rmse(&r, &gradient(8, 9)), Err(MetricError::Size(8, 8, 8, 9)));
    }

    #[test]
    fn flicker_of_constant_and_alternating_sequences() {
        let a = constant(16, 16, [1.0, 1.0, 1.0, 1.0]);
        assert_eq!(flicker(&[a.clone(), a.clone(), a.clone()]), Ok(0.0));
        // Luminance alternating between 1 and 3: 2·|3 − 1| / (3 + 1) = 1 for every pair.
        let b = constant(16, 16, [3.0, 3.0, 3.0, 1.0]);
        let f = flicker(&[a.clone(), b.clone(), a.clone(), b.clone(), a]).expect("flicker");
        assert!((f - 1.0).abs() < 1e-6, "{f}");
        assert_eq!(flicker(&[b]), Err(MetricError::TooFewFrames(1)));
    }

    #[test]
    fn afterglow_counts_frames_back_to_steady_state() {
        // Steady error 0.1, a change at frame 10 raises it to 1, decaying by half per frame.
        let mut e = vec![0.1; 10];
        let mut x = 1.0;
        for _ in 0..30 {
            e.push(f64::max(x, 0.1));
            x *= 0.5;
        }
        // 1, .5, .25, .125 ≤ 0.2: three frames after the change.
        assert_eq!(afterglow(&e, 10), Some(3));
        assert_eq!(afterglow(&[1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0], 0), Some(0));
        assert_eq!(afterglow(&[0.1, 0.1], 0), None);
    }
}
