//! `gi-lab bench --suite knecht`: the shape of Knecht's Tables 5.1–5.3 (002 §5) on one
//! scene — frame time against the VPL count (4…1024, expected linear), against the ISM
//! resolution (64…512), and the share of the frame that temporal coherence costs (thesis
//! ≈ 11 %, our goal ≤ 10 %). Each row is a `bench_run` of the preset with one setting
//! changed; ratios are to the first row of its table, so that they compare within one run.
//! Rows that the device cannot hold (an ISM atlas too large) print the refusal instead.

use gi_render::Renderer;
use gi_render::lab_settings::IndirectTechnique;

use crate::cli::{BenchReport, CliError, bench_run};

/// One row: what changed, and the measured frame (None: refused, with the reason).
#[derive(Debug, Clone, serde::Serialize)]
pub struct SuiteRow {
    pub table: String,
    pub setting: String,
    pub total_ms: Option<f64>,
    /// Mean time of the passes whose names start with the table's focus (e.g. `ism.` for the
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
    /// (frame with − frame without temporal coherence) / frame with, at the preset's VPLs.
    pub temporal_overhead: Option<f64>,
}

fn focus(report: &BenchReport, prefixes: &[&str]) -> f64 {
    report.passes.iter().filter(|p| prefixes.iter().any(|f| p.pass.starts_with(f))).map(|p| p.mean_ms).sum()
}

/// Runs the Knecht suite on `r`, whose settings are the base (switched to instant radiosity
/// when another technique is set). The renderer's settings are restored afterwards.
pub fn knecht(r: &mut Renderer, frames: u32, scene: &str) -> Result<SuiteReport, CliError> {
    let original = r.settings().clone();
    let mut base = original.clone();
    base.indirect.technique = IndirectTechnique::InstantRadiosity;
    let mut rows = Vec::new();
    let mut run = |r: &mut Renderer, table: &str, setting: String, s: gi_render::LabSettings, f: &[&str]| match r
        .set_settings(s)
    {
        Ok(_) => {
            let b = bench_run(r, frames, scene);
            rows.push(SuiteRow {
                table: table.into(),
                setting,
                total_ms: Some(b.total_mean_ms),
                focus_ms: Some(focus(&b, f)),
                refused: None,
            });
            Some(b.total_mean_ms)
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
        s.ism.visibility = gi_render::passes::ism::VplVisibility::Imperfect;
        run(r, "ISM size", format!("{size}² × {} VPLs", s.vpl.count), s, &["ism."]);
    }
    // Temporal-coherence overhead at the base VPL count.
    let mut on = base.clone();
    on.temporal.enabled = true;
    let mut off = base.clone();
    off.temporal.enabled = false;
    let t_on = run(r, "temporal coherence", "on".into(), on, &["temporal"]);
    let t_off = run(r, "temporal coherence", "off".into(), off, &["temporal"]);
    let temporal_overhead = match (t_on, t_off) {
        (Some(a), Some(b)) if a > 0.0 => Some((a - b) / a),
        _ => None,
    };
    let (width, height) = r.size();
    let adapter = r.ctx.adapter_summary();
    let timing_source = format!("{:?}", r.timing_source());
    r.set_settings(original).map_err(|e| CliError::failure(e.to_string()))?;
    Ok(SuiteReport { adapter, timing_source, width, height, frames, rows, temporal_overhead })
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
            s += &format!("\n{table}\n{:<24} {:>10} {:>8} {:>10}\n", "setting", "frame ms", "ratio", "focus ms");
        }
        match (row.total_ms, &row.refused) {
            (Some(t), _) => {
                let ratio = first.filter(|f| *f > 0.0).map_or(String::from("—"), |f| format!("{:.2}", t / f));
                s += &format!("{:<24} {:>10.3} {:>8} {:>10.3}\n", row.setting, t, ratio, row.focus_ms.unwrap_or(0.0));
            }
            (None, reason) => s += &format!("{:<24} refused: {}\n", row.setting, reason.as_deref().unwrap_or("")),
        }
    }
    if let Some(o) = report.temporal_overhead {
        s += &format!("\ntemporal coherence overhead: {:.1} % of the frame (thesis ≈ 11 %, goal ≤ 10 %)\n", 100.0 * o);
    }
    s += "\nmulti-bounce VPL generation against IRSM (Table 5.3): not implemented yet (issue #5)\n";
    s
}
