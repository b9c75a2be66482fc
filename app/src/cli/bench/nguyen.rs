//! `gi-lab bench --suite nguyen`: the hierarchical coherence buffer (Nguyen et al.) against
//! gathering at every pixel, cached and per frame.

use gi_render::Renderer;
use gi_render::settings::pipeline::{Technique, Temporal};

use super::run::{BenchReport, bench_run, focus};
use crate::error::CliError;

/// `gi-lab bench --suite nguyen`: the HCB (Nguyen et al.) against gathering at every pixel
/// (levels = 1, where every covered pixel is a sample) with the same VPLs — 1024 as the issue
/// asks — at equal resolution; the cached HCB (§5) against the per-frame one, on a still view
/// and with the animation playing; the samples' share of the pixels (the paper: 1.9–4.4 %).
#[derive(Debug, Clone, serde::Serialize)]
pub struct NguyenReport {
    pub adapter: String,
    pub timing_source: String,
    pub width: u32,
    pub height: u32,
    pub frames: u32,
    pub vpls: u32,
    /// Frame time (fastest frame per pass, summed) with the HCB and with every pixel gathered.
    pub hcb_ms: f64,
    pub per_pixel_ms: f64,
    /// The gather and splat passes alone (`hcb.gather`, `hcb.splat`).
    pub hcb_gather_ms: f64,
    pub per_pixel_gather_ms: f64,
    pub samples: u32,
    pub samples_per_level: Vec<u32>,
    pub sample_share: f64,
    /// The cached HCB (§5), the view still and with the animation playing.
    pub cached_still: CachedRun,
    pub cached_moving: CachedRun,
    /// The per-frame HCB's passes (`hcb.*`) with the animation playing, against which
    /// `cached_moving.hcb_passes_ms` compares.
    pub moving_hcb_passes_ms: f64,
    /// The per-frame HCB's passes (`hcb.*`) on the still view.
    pub hcb_passes_ms: f64,
}

/// One run of the cached HCB.
#[derive(Debug, Clone, serde::Serialize)]
pub struct CachedRun {
    /// Frame time (fastest frame per pass, summed).
    pub frame_ms: f64,
    /// All HCB passes (`hcb.*`: cache update, recomputation, splats, build, gather).
    pub hcb_passes_ms: f64,
    /// The last frame's samples: reused, new and recomputed (gathered = new + recomputed).
    pub counts: CacheCountsReport,
}

#[derive(Debug, Clone, serde::Serialize)]
pub struct CacheCountsReport {
    pub total: u32,
    pub cached: u32,
    pub new: u32,
    pub recomputed: u32,
    pub removed: u32,
}

pub fn nguyen(r: &mut Renderer, frames: u32, scene: &str) -> Result<NguyenReport, CliError> {
    let original = r.settings().clone();
    let playing = r.clock.playing;
    let mut base = original.clone();
    Technique::Nguyen.apply(&mut base);
    base.vpl.count = 1024;
    // The cache needs the same VPLs from frame to frame (see presets/nguyen-hcb-cached.ron);
    // the per-frame runs use them too.
    base.vpl.new_set_each_frame = false;
    type Run = (BenchReport, Option<gi_render::passes::hcb::stage::HcbStats>);
    let run = |r: &mut Renderer, levels: u32, cache: bool, play: bool| -> Result<Run, CliError> {
        let mut s = base.clone();
        s.hcb.levels = levels;
        s.pipeline.temporal = if cache { Temporal::HcbSampleCache } else { Temporal::None };
        r.set_settings(s).map_err(|e| CliError::input(e.to_string()))?;
        r.clock.playing = play;
        let b = bench_run(r, frames, scene);
        Ok((b, r.hcb_stats()))
    };
    let (hcb, stats) = run(r, base.hcb.levels, false, false)?;
    let (per_pixel, _) = run(r, 1, false, false)?;
    let (moving, _) = run(r, base.hcb.levels, false, true)?;
    let cached = |r: &mut Renderer, play: bool| -> Result<CachedRun, CliError> {
        let (b, st) = run(r, base.hcb.levels, true, play)?;
        let c = st.and_then(|s| s.cache).ok_or_else(|| CliError::failure("the cache produced no counts"))?;
        Ok(CachedRun {
            frame_ms: focus(&b, &[""]),
            hcb_passes_ms: focus(&b, &["hcb."]),
            counts: CacheCountsReport {
                total: c.total,
                cached: c.cached,
                new: c.new_samples(),
                recomputed: c.recomputed,
                removed: c.invalid + c.surplus + c.dropped,
            },
        })
    };
    let cached_still = cached(r, false)?;
    let cached_moving = cached(r, true)?;
    let stats = stats.ok_or_else(|| CliError::failure("the HCB produced no statistics"))?;
    let (width, height) = r.size();
    let report = NguyenReport {
        adapter: r.ctx.adapter_summary(),
        timing_source: format!("{:?}", r.timing_source()),
        width,
        height,
        frames,
        vpls: base.vpl.count,
        hcb_ms: focus(&hcb, &[""]),
        per_pixel_ms: focus(&per_pixel, &[""]),
        hcb_gather_ms: focus(&hcb, &["hcb.gather", "hcb.splat"]),
        per_pixel_gather_ms: focus(&per_pixel, &["hcb.gather", "hcb.splat"]),
        samples: stats.samples(),
        samples_per_level: stats.samples_per_level.clone(),
        sample_share: 100.0 * stats.samples() as f64 / (width * height).max(1) as f64,
        cached_still,
        cached_moving,
        moving_hcb_passes_ms: focus(&moving, &["hcb."]),
        hcb_passes_ms: focus(&hcb, &["hcb."]),
    };
    r.set_settings(original).map_err(|e| CliError::failure(e.to_string()))?;
    r.clock.playing = playing;
    Ok(report)
}

pub fn format_nguyen(r: &NguyenReport) -> String {
    let ratio = |a: f64, b: f64| if a > 0.0 { format!("{:.1}×", b / a) } else { "—".into() };
    format!(
        "GI Lab bench suite nguyen — {}×{}, {} VPLs, {} frames, {} ({})\n\n\
         {:<28} {:>12} {:>12} {:>9}\n\
         {:<28} {:>12.3} {:>12.3} {:>9}\n\
         {:<28} {:>12.3} {:>12.3} {:>9}\n\n\
         samples: {} ({:.2} % of the pixels; the paper: 1.9–4.4 %), per level {:?}\n\n\
         {:<28} {:>12} {:>12} {:>9}   {}\n\
         {:<28} {:>12.3} {:>12.3} {:>9}   {}\n\
         {:<28} {:>12.3} {:>12.3} {:>9}   {}\n\n\
         times: per pass the fastest of the frames, summed; HCB passes: every hcb.* scope\n",
        r.width,
        r.height,
        r.vpls,
        r.frames,
        r.adapter,
        r.timing_source,
        "",
        "HCB ms",
        "per-pixel ms",
        "cheaper",
        "frame",
        r.hcb_ms,
        r.per_pixel_ms,
        ratio(r.hcb_ms, r.per_pixel_ms),
        "gather + splat",
        r.hcb_gather_ms,
        r.per_pixel_gather_ms,
        ratio(r.hcb_gather_ms, r.per_pixel_gather_ms),
        r.samples,
        r.sample_share,
        r.samples_per_level,
        "cached vs per-frame",
        "cached ms",
        "per-frame ms",
        "cheaper",
        "samples of the last frame",
        "HCB passes, still view",
        r.cached_still.hcb_passes_ms,
        r.hcb_passes_ms,
        ratio(r.cached_still.hcb_passes_ms, r.hcb_passes_ms),
        counts(&r.cached_still.counts),
        "HCB passes, animation",
        r.cached_moving.hcb_passes_ms,
        r.moving_hcb_passes_ms,
        ratio(r.cached_moving.hcb_passes_ms, r.moving_hcb_passes_ms),
        counts(&r.cached_moving.counts),
    )
}

fn counts(c: &CacheCountsReport) -> String {
    format!("{} = {} cached + {} new, {} recomputed, {} removed", c.total, c.cached, c.new, c.recomputed, c.removed)
}
