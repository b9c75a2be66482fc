//! `gi-lab compare`: RMSE, relative MSE and mean FLIP of two images.

use std::path::{Path, PathBuf};

use clap::Args;

use crate::error::CliError;

#[derive(Args, Debug)]
pub struct CompareArgs {
    /// The test image.
    pub test: PathBuf,
    /// The reference image (same size).
    pub reference: PathBuf,
    /// Write the FLIP error map here (PNG, turbo false colour).
    #[arg(long)]
    pub flip_map: Option<PathBuf>,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
    /// Scale both float images by this before tone mapping for FLIP, or `auto`: the exposure
    /// that brings the reference's log-average luminance to 0.18 (dim scenes, such as a
    /// room lit by a weak emitter, would otherwise compare as black).
    #[arg(long, default_value = "1", value_parser = parse_exposure)]
    pub exposure: Exposure,
}

/// `--exposure`: a factor or `auto`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Exposure {
    Factor(f32),
    Auto,
}

fn parse_exposure(s: &str) -> Result<Exposure, String> {
    if s.trim().eq_ignore_ascii_case("auto") {
        return Ok(Exposure::Auto);
    }
    match s.trim().parse::<f32>() {
        Ok(k) if k.is_finite() && k > 0.0 => Ok(Exposure::Factor(k)),
        _ => Err(format!("'{s}' is not a positive number or 'auto'")),
    }
}

/// Metrics of one image pair.
#[derive(Debug, Clone, serde::Serialize)]
pub struct CompareReport {
    /// Whether the inputs were float (HDR) images; FLIP then runs on their tone-mapped
    /// versions (x / (1 + x), sRGB).
    pub hdr: bool,
    pub rmse: f64,
    pub rel_mse: f64,
    pub flip: f64,
}

/// Loads an image as f32 RGBA: EXR and other float formats as linear values, 8-bit images
/// as their display values in [0, 1]. Returns whether it was a float image.
pub fn load_image(path: &Path) -> Result<(gi_render::ImageF32, bool), CliError> {
    let img = image::open(path).map_err(|e| CliError::input(format!("{}: {e}", path.display())))?;
    let float = matches!(img.color(), image::ColorType::Rgb32F | image::ColorType::Rgba32F);
    let rgba = img.into_rgba32f();
    Ok((
        gi_render::ImageF32 { width: rgba.width(), height: rgba.height(), data: rgba.pixels().map(|p| p.0).collect() },
        float,
    ))
}

/// Compares two image files.
pub fn compare_files(test: &Path, reference: &Path, flip_map: Option<&Path>) -> Result<CompareReport, CliError> {
    compare_files_exposed(test, reference, flip_map, Exposure::Factor(1.0))
}

/// Compares two image files, the float ones scaled by `exposure` for FLIP.
pub fn compare_files_exposed(
    test: &Path,
    reference: &Path,
    flip_map: Option<&Path>,
    exposure: Exposure,
) -> Result<CompareReport, CliError> {
    use gi_render::metrics;
    let (t, t_float) = load_image(test)?;
    let (r, r_float) = load_image(reference)?;
    let hdr = t_float && r_float;
    let err = |e: metrics::MetricError| CliError::input(format!("{} vs {}: {e}", test.display(), reference.display()));
    let rmse = metrics::rmse(&t, &r).map_err(err)?;
    let rel_mse = metrics::rel_mse(&t, &r).map_err(err)?;
    let k = match exposure {
        Exposure::Factor(k) => k,
        Exposure::Auto => metrics::auto_exposure(&r),
    };
    let display = |i: &gi_render::ImageF32| {
        if hdr { gi_render::image_io::hdr_display(&metrics::scaled(i, k)) } else { i.clone() }
    };
    let (flip, map) = metrics::flip(&display(&t), &display(&r)).map_err(err)?;
    if let Some(path) = flip_map {
        let mut png = image::RgbaImage::new(map.width, map.height);
        for (px, e) in png.pixels_mut().zip(&map.data) {
            let [r, g, b] = gi_render::image_io::turbo(e[0]);
            *px = image::Rgba([r, g, b, 1.0].map(|x| (x * 255.0).round() as u8));
        }
        gi_render::image_io::save_atomic(path, &image::DynamicImage::ImageRgba8(png), image::ImageFormat::Png)
            .map_err(|e| CliError::input(format!("{}: {e}", path.display())))?;
    }
    Ok(CompareReport { hdr, rmse, rel_mse, flip })
}

pub(super) fn compare(args: &CompareArgs) -> Result<(), CliError> {
    let r = compare_files_exposed(&args.test, &args.reference, args.flip_map.as_deref(), args.exposure)?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&r).map_err(|e| CliError::failure(e.to_string()))?);
    } else {
        println!("RMSE     {:.6}{}", r.rmse, if r.hdr { " (linear HDR)" } else { " (display values)" });
        println!("relMSE   {:.6}", r.rel_mse);
        println!("FLIP     {:.6} (mean{})", r.flip, if r.hdr { ", on tone-mapped images" } else { "" });
    }
    Ok(())
}
