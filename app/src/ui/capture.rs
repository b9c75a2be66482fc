//! Captures: the viewport saved as PNG and EXR, recorded frame sequences, and the
//! `--screenshot` of the window. Each image is written atomically (encoded in memory, then a
//! temporary file renamed over it), so a crash never leaves a truncated image.

use std::path::{Path, PathBuf};

/// A recording of N frames to a folder (File → Record).
pub struct Recording {
    pub dir: PathBuf,
    pub remaining: u32,
    pub index: u32,
}

/// A file-name-safe UTC time stamp for captures (`2026-11-22T17-03-46Z`).
pub fn capture_stamp() -> String {
    gi_render::preset::utc_now().replace(':', "-")
}

/// Writes a window screenshot in the format its extension names (PNG when it names none),
/// atomically (`gi_render::image_io::save_atomic`: a kill mid-save leaves the old file or
/// the new complete one).
pub fn save_color_image(path: &Path, img: &egui::ColorImage) -> Result<(), String> {
    let [w, h] = img.size;
    let bytes: Vec<u8> = img.pixels.iter().flat_map(|c| c.to_array()).collect();
    let i = image::RgbaImage::from_raw(w as u32, h as u32, bytes).ok_or("screenshot has inconsistent size")?;
    let format = image::ImageFormat::from_path(path).unwrap_or(image::ImageFormat::Png);
    gi_render::image_io::save_atomic(path, &image::DynamicImage::ImageRgba8(i), format)
        .map_err(|e| format!("cannot write screenshot {}: {e}", path.display()))
}
