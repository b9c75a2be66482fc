//! One cold-to-covered run of Gautron's record cache (`bench --suite gautron`'s rows, and the
//! GPU side of its CPU comparison in [`super::gautron_cpu`]): the frames and time from an
//! empty cache until a frame makes no record, then one warm frame.

use gi_render::Renderer;
use gi_render::metrics::flip;
use gi_render::{ImageF32, image_io::hdr_display};

use crate::error::CliError;

/// One cold-to-covered run.
#[derive(Debug, Clone, serde::Serialize)]
pub struct GautronRow {
    pub accuracy: f32,
    /// Records in the cache once it covers the image.
    pub records: u32,
    /// Frames from an empty cache until a frame makes no record.
    pub frames_to_cover: u32,
    /// Every Gautron pass of those frames (ms).
    pub cold_ms: f64,
    /// Record creation and hemispheres (create, raster, lighting, reduction) per record (ms).
    pub per_record_ms: f64,
    /// A frame with the covered cache (splat and resolve; ms).
    pub warm_ms: f64,
    pub flip_vs_brute_force: f64,
    pub flip_vs_truth: f64,
    /// The brute force's cold time over this row's.
    pub speedup: f64,
}

/// Renders from an empty cache until a frame makes no record (at most 256 frames), then one
/// warm frame; returns the row (FLIPs and speedup filled in later) and the final image.
pub fn cold_to_covered(r: &mut Renderer, accuracy: f32) -> Result<(GautronRow, ImageF32), CliError> {
    let fail = |e: String| CliError::failure(e);
    r.reset_history();
    let gautron = |t: &[gi_render::timing::PassTiming], keep: &dyn Fn(&str) -> bool| {
        t.iter().filter(|p| p.name.starts_with("gautron.") && keep(&p.name)).map(|p| p.ms).sum::<f64>()
    };
    let (mut cold_ms, mut making_ms, mut frames) = (0.0, 0.0, 0);
    loop {
        let t = r.render_frame();
        let st = r.gautron().and_then(|g| g.read_state(&r.ctx)).ok_or_else(|| fail("no Gautron stage".into()))?;
        if st.made == 0 {
            break;
        }
        frames += 1;
        cold_ms += gautron(&t, &|_| true);
        making_ms += gautron(&t, &|n| n == "gautron.create" || n == "gautron.hemispheres");
        if frames >= 256 {
            return Err(fail(format!("a = {accuracy}: the cache still grew after 256 frames")));
        }
    }
    let warm = r.render_frame();
    let records = r.gautron().and_then(|g| g.read_state(&r.ctx)).map_or(0, |s| s.count);
    let image = r.readback("final.hdr").map_err(|e| fail(e.to_string()))?;
    let row = GautronRow {
        accuracy,
        records,
        frames_to_cover: frames,
        cold_ms,
        per_record_ms: making_ms / records.max(1) as f64,
        warm_ms: gautron(&warm, &|_| true),
        flip_vs_brute_force: 0.0,
        flip_vs_truth: 0.0,
        speedup: 0.0,
    };
    Ok((row, image))
}

pub fn flip_of(a: &ImageF32, b: &ImageF32) -> Result<f64, CliError> {
    flip(&hdr_display(a), &hdr_display(b)).map(|(f, _)| f).map_err(|e| CliError::input(e.to_string()))
}
