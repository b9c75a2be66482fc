//! `gi-lab bench --suite soler`: the shape of Soler et al.'s Fig. 9 (004 §5.1) — the cost
//! of the screen-space indirect light for four parameter sets (quarter / 4 levels / 64
//! samples, quarter / 4 / 256, half / 4 / 64, half / 5 / 64, r = 40 px as in the paper), each
//! without and with visibility, split into the paper's parts: the voxel grid, each gathered
//! level ("SSIL level k"), the upsampling with temporal coherence, and the rest of ours (the
//! voting pyramid). Ratios are to the first row; the goals are checked on them:
//! quarter ≥ 2.5× cheaper than half at equal samples, a fifth level ≤ 5 %, visibility ≤ 6×
//! (the paper's totals: 3.0×, 1 %, 5.9×). Run it at 1280×720 (`--size 1280x720`), the paper's size.

use gi_render::Renderer;
use gi_render::passes::soler::StartResolution;
use gi_render::settings::pipeline::{Technique, Temporal};

use super::run::{BenchReport, bench_run};
use crate::error::CliError;

/// One row of Fig. 9: the parameter set and its parts (per pass the fastest frame, in ms).
#[derive(Debug, Clone, serde::Serialize)]
pub struct SolerRow {
    pub start: String,
    pub levels: u32,
    pub samples: u32,
    pub visibility: bool,
    pub voxels_ms: f64,
    /// The gather of each level, finest first (the paper's "SSIL level 1 …").
    pub levels_ms: Vec<f64>,
    /// The voting pyramid (Eq. 5), not a row of Fig. 9.
    pub pyramid_ms: f64,
    /// Upsampling and resolve plus the temporal filter (Fig. 9's "Upsampling + TC").
    pub upsampling_tc_ms: f64,
    /// Everything Soler's stage costs (the parts above).
    pub total_ms: f64,
}

#[derive(Debug, Clone, serde::Serialize)]
pub struct SolerReport {
    pub adapter: String,
    pub timing_source: String,
    pub width: u32,
    pub height: u32,
    pub frames: u32,
    pub radius_px: f32,
    pub rows: Vec<SolerRow>,
}

/// The start resolution as Fig. 9 names it.
fn start_name(s: StartResolution) -> &'static str {
    StartResolution::LABELS[s.level() as usize]
}

fn part(report: &BenchReport, keep: impl Fn(&str) -> bool) -> f64 {
    report.passes.iter().filter(|p| keep(&p.pass)).map(|p| p.min_ms).sum()
}

/// Runs the suite with `r`'s settings as the base (Soler's stage choices with Eq. 6 are set;
/// the other Soler settings are the preset's, but for the four parameters and r = 40). The
/// renderer's settings are restored afterwards.
pub fn soler(r: &mut Renderer, frames: u32) -> Result<SolerReport, CliError> {
    let original = r.settings().clone();
    let mut base = original.clone();
    Technique::Soler.apply(&mut base);
    base.pipeline.temporal = Temporal::WarpedBlend;
    base.soler.radius_px = 40.0;
    base.soler.bounces = 1;
    let sets = [
        (StartResolution::Quarter, 4, 64),
        (StartResolution::Quarter, 4, 256),
        (StartResolution::Half, 4, 64),
        (StartResolution::Half, 5, 64),
    ];
    let mut rows = Vec::new();
    for (start, levels, samples) in sets {
        for visibility in [false, true] {
            let mut s = base.clone();
            s.soler.start_resolution = start;
            s.soler.levels = levels;
            s.soler.samples = samples;
            s.soler.visibility = visibility;
            r.set_settings(s).map_err(|e| CliError::failure(e.to_string()))?;
            let b = bench_run(r, frames, "");
            let first = start.level();
            let levels_ms =
                (first..first + levels).map(|k| part(&b, |p| p == format!("soler.gather.{k}").as_str())).collect();
            let voxels_ms = part(&b, |p| p == "soler.voxels");
            let pyramid_ms = part(&b, |p| p == "soler.pyramid");
            let upsampling_tc_ms = part(&b, |p| p == "soler.upsample" || p == "soler.temporal");
            rows.push(SolerRow {
                start: start_name(start).to_string(),
                levels,
                samples,
                visibility,
                voxels_ms,
                levels_ms,
                pyramid_ms,
                upsampling_tc_ms,
                total_ms: part(&b, |p| p.starts_with("soler.")),
            });
        }
    }
    let (width, height) = r.size();
    let adapter = r.ctx.adapter_summary();
    let timing_source = format!("{:?}", r.timing_source());
    r.set_settings(original).map_err(|e| CliError::failure(e.to_string()))?;
    Ok(SolerReport { adapter, timing_source, width, height, frames, radius_px: 40.0, rows })
}

/// The row with these parameters.
fn row<'a>(report: &'a SolerReport, start: &str, levels: u32, samples: u32, visibility: bool) -> Option<&'a SolerRow> {
    report
        .rows
        .iter()
        .find(|r| r.start == start && r.levels == levels && r.samples == samples && r.visibility == visibility)
}

/// The total of the row with these parameters.
fn total(report: &SolerReport, start: &str, levels: u32, samples: u32, visibility: bool) -> Option<f64> {
    row(report, start, levels, samples, visibility).map(|r| r.total_ms)
}

/// The goals on the ratios: (what, measured, goal, met; None: shown for comparison).
pub fn goals(report: &SolerReport) -> Vec<(String, f64, String, Option<bool>)> {
    let (q, h) = (start_name(StartResolution::Quarter), start_name(StartResolution::Half));
    let mut out = Vec::new();
    if let (Some(a), Some(b)) = (total(report, q, 4, 64, false), total(report, h, 4, 64, false)) {
        out.push((
            "half / quarter start, 4 levels, 64 samples".into(),
            b / a,
            "≥ 2.5 (paper 3.0)".into(),
            Some(b >= 2.5 * a),
        ));
    }
    // The same on the gathers alone (Fig. 9's "Total SSIL"): the fixed full-resolution passes
    // (voting, upsampling, temporal) weigh far more on a CPU device than on the paper's GPU.
    let ssil =
        |start: &str, visibility: bool| row(report, start, 4, 64, visibility).map(|r| r.levels_ms.iter().sum::<f64>());
    if let (Some(a), Some(b)) = (ssil(q, false), ssil(h, false)) {
        out.push(("  the same, gathers only (total SSIL)".into(), b / a, "(paper 3.9)".into(), None));
    }
    if let (Some(a), Some(b)) = (total(report, h, 4, 64, false), total(report, h, 5, 64, false)) {
        out.push(("5 levels / 4 levels, half start".into(), b / a, "≤ 1.05 (paper 1.01)".into(), Some(b <= 1.05 * a)));
    }
    if let (Some(a), Some(b)) = (total(report, q, 4, 64, false), total(report, q, 4, 64, true)) {
        out.push(("visibility on / off, quarter 4 64".into(), b / a, "≤ 6 (paper 5.9)".into(), Some(b <= 6.0 * a)));
    }
    if let (Some(a), Some(b)) = (ssil(q, false), ssil(q, true)) {
        let b = b + row(report, q, 4, 64, true).map_or(0.0, |r| r.voxels_ms);
        out.push(("  the same, gathers and voxel grid only".into(), b / a, "(paper 8.3)".into(), None));
    }
    out
}

/// Fig. 9 as text: one column per parameter set and visibility, as the paper prints it.
pub fn format(report: &SolerReport) -> String {
    let mut s = format!(
        "GI Lab bench suite soler (Soler et al. 004 Fig. 9) — {}×{}, r = {} px, {} frames per row, {} ({})\n\n",
        report.width, report.height, report.radius_px, report.frames, report.adapter, report.timing_source
    );
    let rows = &report.rows;
    let cell = |v: f64| if v > 0.0 { format!("{v:>9.3}") } else { format!("{:>9}", "") };
    let line = |name: &str, f: &dyn Fn(&SolerRow) -> String| {
        let mut l = format!("{name:<22}");
        for r in rows {
            l += &f(r);
        }
        l + "\n"
    };
    s += &line("start resolution", &|r| format!("{:>9}", r.start));
    s += &line("mip levels", &|r| format!("{:>9}", r.levels));
    s += &line("samples per level", &|r| format!("{:>9}", r.samples));
    s += &line("visibility", &|r| format!("{:>9}", if r.visibility { "yes" } else { "no" }));
    s += &line("voxel grid", &|r| cell(r.voxels_ms));
    let most = rows.iter().map(|r| r.levels_ms.len()).max().unwrap_or(0);
    for k in 0..most {
        s += &line(&format!("SSIL level {}", k + 1), &|r| cell(r.levels_ms.get(k).copied().unwrap_or(0.0)));
    }
    s += &line("total SSIL (1 bounce)", &|r| cell(r.levels_ms.iter().sum()));
    s += &line("upsampling + TC", &|r| cell(r.upsampling_tc_ms));
    s += &line("voting pyramid", &|r| cell(r.pyramid_ms));
    s += &line("total (ms*)", &|r| cell(r.total_ms));
    let first = rows.first().map_or(0.0, |r| r.total_ms);
    s += &line("ratio to column 1", &|r| {
        if first > 0.0 { format!("{:>9.2}", r.total_ms / first) } else { format!("{:>9}", "—") }
    });
    s += "\n* per pass the fastest of the frames, summed; ratios compare within this run\n\ngoals\n";
    for (what, v, goal, met) in goals(report) {
        let verdict = match met {
            Some(true) => "met",
            Some(false) => "NOT met",
            None => "",
        };
        s += &format!("{what:<42} {v:>7.2}  {goal:<20} {verdict}\n");
    }
    s
}
