//! `gi-lab bench --suite knecht`: the shape of Knecht's Tables 5.1–5.3 (002 §5) on one
//! scene — frame time against the VPL count (4…1024, expected linear), against the ISM
//! resolution (64…512), and the share of the frame that temporal coherence costs (thesis
//! ≈ 11 %, our goal ≤ 10 %), and the time of multi-bounce VPL generation by the point cloud
//! (§3.6.1) against imperfect reflective shadow maps for 2…6 bounces (Table 5.3: thesis ≈ 11×
//! faster, goal ≥ 10×; as there, only the bounce passes count, not the ISMs or the shading).
//! Each row is a `bench_run` of the preset with one setting
//! changed; ratios are to the first row of its table, so that they compare within one run.
//! Rows that the device cannot hold (an ISM atlas too large) print the refusal instead.

use gi_render::Renderer;
use gi_render::passes::knecht::vpl_bounce::BounceMethod;
use gi_render::settings::pipeline::{ShadingPoints, Technique, Temporal, VplSource, VplVisibility};

use super::run::{bench_run, focus};
use crate::error::CliError;

/// One row: what changed, and the measured frame (None: refused, with the reason).
#[derive(Debug, Clone, serde::Serialize)]
pub struct SuiteRow {
    pub table: String,
    pub setting: String,
    /// Sum of every pass's fastest frame.
    pub total_ms: Option<f64>,
    /// Sum of the fastest frame of the passes whose names start with the table's focus (e.g. `ism.` for the
    /// ISM table), so that the part the setting drives is visible beside the frame.
    pub focus_ms: Option<f64>,
    pub refused: Option<String>,
}

#[derive(Debug, Clone, serde::Serialize)]
pub struct SuiteReport {
    pub adapter: String,
    pub timing_source: String,
    pub width: u32,
    pub height: u32,
    pub frames: u32,
    pub rows: Vec<SuiteRow>,
    /// Share of the frame the temporal pass (confidence and merge) takes with coherence on,
    /// at the preset's VPLs.
    pub temporal_overhead: Option<f64>,
    /// Per bounce count B: (IRSM bounce time, point-cloud bounce time, speed-up).
    pub bounce_speedup: Vec<(u32, f64, f64, f64)>,
}

/// Runs the Knecht suite on `r`, whose settings are the base (switched to instant radiosity
/// when another technique is set). The renderer's settings are restored afterwards.
pub fn knecht(r: &mut Renderer, frames: u32, scene: &str) -> Result<SuiteReport, CliError> {
    let original = r.settings().clone();
    let mut base = original.clone();
    // Instant radiosity as the preset sets it, else Knecht's choices.
    if base.pipeline.vpl_source != VplSource::ImportanceWarping
        || base.pipeline.shading_points == ShadingPoints::HcbSamples
        || !base.pipeline.uses_knecht_vpls()
    {
        Technique::Knecht.apply(&mut base);
    }
    let mut rows = Vec::new();
    let mut run = |r: &mut Renderer, table: &str, setting: String, s: gi_render::LabSettings, f: &[&str]| match r
        .set_settings(s)
    {
        Ok(_) => {
            let b = bench_run(r, frames, scene);
            rows.push(SuiteRow {
                table: table.into(),
                setting,
                total_ms: Some(focus(&b, &[""])),
                focus_ms: Some(focus(&b, f)),
                refused: None,
            });
            Some((focus(&b, &[""]), focus(&b, f)))
        }
        Err(e) => {
            rows.push(SuiteRow {
                table: table.into(),
                setting,
                total_ms: None,
                focus_ms: None,
                refused: Some(e.to_string()),
            });
            None
        }
    };
    // Table 5.1: VPL count. Interleaving needs N ≥ n²: small counts use the largest n that fits.
    for count in [4u32, 16, 64, 256, 1024] {
        let mut s = base.clone();
        s.vpl.count = count;
        s.ism.points = s.ism.points.max(count);
        while s.interleave.n > 1 && count < s.interleave.n * s.interleave.n {
            s.interleave.n -= 1;
        }
        let label = format!("N = {count} (n = {})", s.interleave.n);
        run(r, "VPL count", label, s, &["vpl.", "ism.", "interleave."]);
    }
    // Table 5.2: ISM resolution at the base VPL count.
    for size in [64u32, 128, 256, 512] {
        let mut s = base.clone();
        s.ism.map_size = size;
        s.pipeline.vpl_visibility = VplVisibility::Imperfect;
        run(r, "ISM size", format!("{size}² × {} VPLs", s.vpl.count), s, &["ism."]);
    }
    // Temporal-coherence overhead at the base VPL count.
    let mut on = base.clone();
    on.pipeline.temporal = Temporal::ConfidenceMerge;
    let mut off = base.clone();
    off.pipeline.temporal = Temporal::None;
    // Off, the stage choice runs no temporal pass. On, the geometry-aware filter runs fused
    // into the merge (`temporal.filter_merge`, issue #53), so both rows focus on the filter
    // and the merge together, and what coherence costs is the difference of the two foci as a
    // share of the frame with coherence on. The difference of the two frames is kept in the
    // table but is within a CPU device's frame-to-frame noise.
    let focus = ["interleave.filter", "temporal"];
    let t_on = run(r, "temporal coherence", "on".into(), on, &focus);
    let t_off = run(r, "temporal coherence", "off".into(), off, &focus);
    let temporal_overhead = t_on
        .zip(t_off)
        .filter(|(on, _)| on.0 > 0.0)
        .map(|((frame, with), (_, without))| (with - without).max(0.0) / frame);
    // Table 5.3: multi-bounce VPL generation, point cloud (§3.6.1) against IRSM.
    let mut bounce_speedup = Vec::new();
    for bounces in 2u32..=6 {
        let mut times = Vec::new();
        for method in [BounceMethod::PointCloud, BounceMethod::Irsm] {
            let mut s = base.clone();
            s.vpl.bounces = bounces;
            s.vpl.bounce_method = method;
            let label = match method {
                BounceMethod::PointCloud => format!("B = {bounces}, point cloud"),
                BounceMethod::Irsm => {
                    format!("B = {bounces}, IRSM {}²", gi_render::passes::knecht::irsm::irsm_size(s.vpl.irsm_size))
                }
            };
            times.push(run(r, "bounces (focus: bounce passes only)", label, s, &["vpl.bounce."]).map(|t| t.1));
        }
        if let [Some(pc), Some(irsm)] = times[..]
            && pc > 0.0
        {
            bounce_speedup.push((bounces, irsm, pc, irsm / pc));
        }
    }
    let (width, height) = r.size();
    let adapter = r.ctx.adapter_summary();
    let timing_source = format!("{:?}", r.timing_source());
    r.set_settings(original).map_err(|e| CliError::failure(e.to_string()))?;
    Ok(SuiteReport { adapter, timing_source, width, height, frames, rows, temporal_overhead, bounce_speedup })
}

/// The suite as text tables, with each row's ratio to its table's first measured row.
pub fn format(report: &SuiteReport) -> String {
    let mut s = format!(
        "GI Lab bench suite knecht — {}×{}, {} frames per row, {} ({})\n",
        report.width, report.height, report.frames, report.adapter, report.timing_source
    );
    let mut table = String::new();
    let mut first = None;
    for row in &report.rows {
        if row.table != table {
            table = row.table.clone();
            first = row.total_ms;
            s += &format!("\n{table}\n{:<24} {:>10} {:>8} {:>10}\n", "setting", "frame ms*", "ratio", "focus ms*");
        }
        match (row.total_ms, &row.refused) {
            (Some(t), _) => {
                let ratio = first.filter(|f| *f > 0.0).map_or(String::from("—"), |f| format!("{:.2}", t / f));
                s += &format!("{:<24} {:>10.3} {:>8} {:>10.3}\n", row.setting, t, ratio, row.focus_ms.unwrap_or(0.0));
            }
            (None, reason) => s += &format!("{:<24} refused: {}\n", row.setting, reason.as_deref().unwrap_or("")),
        }
    }
    s += "\n* per pass the fastest of the frames, summed\n";
    if let Some(o) = report.temporal_overhead {
        s += &format!(
            "\ntemporal coherence overhead: the temporal pass is {:.1} % of the frame (thesis ≈ 11 %, goal ≤ 10 %)\n",
            100.0 * o
        );
    }
    if !report.bounce_speedup.is_empty() {
        s += "\nmulti-bounce VPL generation (Table 5.3), bounce passes only\n";
        s += &format!("{:<10} {:>12} {:>16} {:>10}\n", "bounces", "IRSM ms", "point cloud ms", "speed-up");
        for (b, irsm, pc, x) in &report.bounce_speedup {
            s += &format!("{b:<10} {irsm:>12.3} {pc:>16.3} {x:>9.1}×\n");
        }
        let mean = report.bounce_speedup.iter().map(|r| r.3).sum::<f64>() / report.bounce_speedup.len() as f64;
        s += &format!("mean speed-up {mean:.1}× (thesis ≈ 11×, goal ≥ 10×)\n");
    }
    s
}
