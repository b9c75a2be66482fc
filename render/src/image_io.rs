//! Turning read-back buffers into files: PNG for viewing (false colour or normalised for
//! non-colour data) and OpenEXR (32-bit float RGBA) for HDR data.

use std::path::Path;

use crate::buffers::{BufferKind, ImageF32};

/// The turbo colour map (Mikhail 2019) as a polynomial fit, for scalar data in [0, 1].
pub fn turbo(t: f32) -> [f32; 3] {
    let t = t.clamp(0.0, 1.0);
    let r = 0.135_721_38 + t * (4.615_392_6 + t * (-42.660_324 + t * (132.131_08 + t * (-152.942_4 + t * 59.286_38))));
    let g =
        0.091_402_61 + t * (2.194_188_4 + t * (4.842_966_6 + t * (-14.185_034 + t * (4.277_298_6 + t * 2.829_566))));
    let b = 0.106_673_3 + t * (12.641_946 + t * (-60.582_05 + t * (110.362_77 + t * (-89.903_11 + t * 27.348_25))));
    [r.clamp(0.0, 1.0), g.clamp(0.0, 1.0), b.clamp(0.0, 1.0)]
}

fn srgb_encode(c: f32) -> f32 {
    let c = c.clamp(0.0, 1.0);
    if c <= 0.003_130_8 { c * 12.92 } else { 1.055 * c.powf(1.0 / 2.4) - 0.055 }
}

/// A FLIP error map (`metrics::flip`, error in the red channel) in the inferno colour map
/// (black: no visible difference, yellow: large), as the study, the grid and A/B show it.
pub fn error_map_rgba8(map: &ImageF32) -> image::RgbaImage {
    image::RgbaImage::from_fn(map.width, map.height, |x, y| {
        let e = map.data[(y * map.width + x) as usize][0];
        let c = crate::maths::colormap::colormap(crate::maths::colormap::Colormap::Inferno, e);
        image::Rgba([(c[0] * 255.0).round() as u8, (c[1] * 255.0).round() as u8, (c[2] * 255.0).round() as u8, 255])
    })
}

/// Maps a buffer to 8-bit RGBA for viewing, by its kind:
/// LDR as is; albedo clamped; directions as 0.5 + 0.5·n; HDR with x/(1+x) and sRGB;
/// depth with min–max over finite values < 1 in turbo false colour; motion as
/// 0.5 + Δ/(2·max|Δ|) in red/green; other data normalised per channel over its min–max.
pub fn to_rgba8(img: &ImageF32, kind: BufferKind) -> image::RgbaImage {
    let (lo, hi) = img.channel_range();
    let depth_range = {
        let mut lo = f32::INFINITY;
        let mut hi = f32::NEG_INFINITY;
        for p in &img.data {
            if p[0].is_finite() && p[0] < 1.0 {
                lo = lo.min(p[0]);
                hi = hi.max(p[0]);
            }
        }
        (lo, hi)
    };
    let motion_max = img.data.iter().map(|p| p[0].abs().max(p[1].abs())).filter(|x| x.is_finite()).fold(1e-6, f32::max);
    let mut out = image::RgbaImage::new(img.width, img.height);
    for (i, px) in out.pixels_mut().enumerate() {
        let p = img.data[i];
        let c: [f32; 4] = match kind {
            BufferKind::Ldr => p,
            BufferKind::Albedo => [p[0], p[1], p[2], 1.0],
            BufferKind::Direction => [0.5 + 0.5 * p[0], 0.5 + 0.5 * p[1], 0.5 + 0.5 * p[2], 1.0],
            BufferKind::Hdr => {
                let m = |x: f32| srgb_encode(x.max(0.0) / (1.0 + x.max(0.0)));
                [m(p[0]), m(p[1]), m(p[2]), 1.0]
            }
            BufferKind::Depth => {
                if p[0] >= 1.0 {
                    [0.0, 0.0, 0.0, 1.0]
                } else {
                    let t = (p[0] - depth_range.0) / (depth_range.1 - depth_range.0).max(1e-12);
                    let [r, g, b] = turbo(t);
                    [r, g, b, 1.0]
                }
            }
            BufferKind::Motion => [0.5 + 0.5 * p[0] / motion_max, 0.5 + 0.5 * p[1] / motion_max, 0.5, 1.0],
            BufferKind::Data => {
                let n = |c: usize| {
                    let span = hi[c] - lo[c];
                    if span > 0.0 && span.is_finite() { (p[c] - lo[c]) / span } else { 0.0 }
                };
                [n(0), n(1), n(2), 1.0]
            }
        };
        let q = |x: f32| if x.is_nan() { 255 } else { (x.clamp(0.0, 1.0) * 255.0).round() as u8 };
        // NaN shows as magenta so that it is never mistaken for data.
        *px = if p.iter().any(|x| x.is_nan()) {
            image::Rgba([255, 0, 255, 255])
        } else {
            image::Rgba([q(c[0]), q(c[1]), q(c[2]), q(c[3])])
        };
    }
    out
}

/// The display image on which HDR images are compared (FLIP, the CLI, the tests): each
/// channel tone-mapped by x / (1 + x), sRGB-encoded and quantised to 8 bits, as values in
/// [0, 1] — the same mapping as the PNG of an HDR buffer.
pub fn hdr_display(img: &ImageF32) -> ImageF32 {
    let ldr = to_rgba8(img, BufferKind::Hdr);
    ImageF32 {
        width: img.width,
        height: img.height,
        data: ldr.pixels().map(|p| p.0.map(|x| x as f32 / 255.0)).collect(),
    }
}

/// Writes the buffer as an 8-bit PNG mapped by [`to_rgba8`], atomically (see
/// [`save_atomic`]).
pub fn save_png(path: &Path, img: &ImageF32, kind: BufferKind) -> Result<(), image::ImageError> {
    save_atomic(path, &image::DynamicImage::ImageRgba8(to_rgba8(img, kind)), image::ImageFormat::Png)
}

/// Encodes `img` in memory and writes it with [`crate::files::write_atomic_bytes`]: a
/// temporary file renamed over `path`, so that a crash or a kill mid-save leaves either the
/// old or the new complete image, never a truncated one. No `.bak` is kept (captures are
/// not edited, and each usually has a new name).
pub fn save_atomic(
    path: &Path,
    img: &image::DynamicImage,
    format: image::ImageFormat,
) -> Result<(), image::ImageError> {
    let mut bytes = std::io::Cursor::new(Vec::new());
    img.write_to(&mut bytes, format)?;
    crate::files::write_atomic_bytes(path, bytes.get_ref(), crate::files::Backup::Skip)
        .map_err(image::ImageError::IoError)
}

/// `img` as an `image` crate 32-bit float RGBA image.
fn rgba32f(img: &ImageF32) -> Result<image::DynamicImage, image::ImageError> {
    let flat: Vec<f32> = img.data.iter().flatten().copied().collect();
    let buf: image::Rgba32FImage = image::ImageBuffer::from_raw(img.width, img.height, flat).ok_or_else(|| {
        image::ImageError::Parameter(image::error::ParameterError::from_kind(
            image::error::ParameterErrorKind::DimensionMismatch,
        ))
    })?;
    Ok(image::DynamicImage::ImageRgba32F(buf))
}

/// `img` as a 32-bit float RGBA OpenEXR file in memory.
pub fn exr_bytes(img: &ImageF32) -> Result<Vec<u8>, image::ImageError> {
    let mut out = std::io::Cursor::new(Vec::new());
    rgba32f(img)?.write_to(&mut out, image::ImageFormat::OpenExr)?;
    Ok(out.into_inner())
}

/// Writes 32-bit float RGBA OpenEXR, atomically (see [`save_atomic`]).
pub fn save_exr(path: &Path, img: &ImageF32) -> Result<(), image::ImageError> {
    save_atomic(path, &rgba32f(img)?, image::ImageFormat::OpenExr)
}

/// Reads an OpenEXR (or any float image) back as f32 RGBA.
pub fn load_float_image(path: &Path) -> Result<ImageF32, image::ImageError> {
    let img = image::open(path)?.into_rgba32f();
    Ok(ImageF32 { width: img.width(), height: img.height(), data: img.pixels().map(|p| p.0).collect() })
}
