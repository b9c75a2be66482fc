//! `gi-lab bench --suite gautron`: Gautron et al.'s irradiance cache splatting (003,
//! "Results": 29.7–47× over Radiance, a record-versus-brute-force ratio) against a hemisphere
//! at every pixel, the brute force, made by the same machinery (a record per pixel: R_k
//! clamped to 1 px, a = 0.02, 2-pixel creation tiles). Per accuracy a: the records a cold
//! cache makes until it covers the image, the frames and the time that takes, the time per
//! record, a warm frame, FLIP against the brute force and against a path-traced truth of one
//! bounce (computed on the CPU at the bench size unless `--reference` is given), and the
//! brute force's time over the row's. The goal: ≥ 20× at equal FLIP (the cheapest row whose
//! FLIP against the truth is within 10 % of the brute force's). Run it at a small size
//! (`--size 64x64`): the brute force computes a hemisphere per pixel.
//!
//! Then GI Lab's two mixes (issue #17 "Mixes") at the preset's accuracy: the records lit by
//! the VPLs (every pass of stages 3–7 timed, the VPLs' and ISMs' included) and a hemisphere
//! at each of the HCB's samples (one frame: no cache), with the accuracy row nearest in time
//! to the latter (Nguyen's samples against Gautron's records at equal time).
//!
//! Last, the text's own comparison (003 "Results: Comparison with Radiance"): a CPU irradiance
//! cache, Radiance's way (ray-traced hemispheres made one after the other, octree lookups),
//! against the GPU cache at equal FLIP, and both across a short camera walk
//! ([`super::gautron_cpu`]).

use gi_render::ImageF32;
use gi_render::Renderer;
use gi_render::settings::pipeline::{Technique, Temporal};

use crate::error::CliError;

use super::gautron_cold::GautronRow;
use super::gautron_cold::{cold_to_covered, flip_of};

#[derive(Debug, Clone, serde::Serialize)]
pub struct GautronReport {
    pub adapter: String,
    pub timing_source: String,
    pub width: u32,
    pub height: u32,
    pub truth: String,
    /// The brute force: a hemisphere per covered pixel.
    pub brute_force: GautronRow,
    pub rows: Vec<GautronRow>,
    /// The mixes: records lit by VPLs, hemispheres at the HCB's samples.
    pub mixes: Vec<MixRow>,
    /// The text's comparison: a CPU irradiance cache against the GPU cache.
    pub cpu_cache: super::gautron_cpu::CpuComparison,
}

/// One of GI Lab's mixes with Gautron et al.
#[derive(Debug, Clone, serde::Serialize)]
pub struct MixRow {
    pub name: String,
    /// Records (VPL-lit) or HCB samples (one hemisphere each).
    pub points: u32,
    /// Frames until covered (VPL-lit records), 1 for the HCB's samples.
    pub frames: u32,
    /// Every pass of stages 3–7 over those frames (ms).
    pub ms: f64,
    pub flip_vs_brute_force: f64,
    pub flip_vs_truth: f64,
}

/// Whether a pass belongs to stages 3–7 (not the G-buffer, direct light or compose).
fn indirect_pass(name: &str) -> bool {
    !(name.starts_with("gbuffer") || name.starts_with("direct") || name.starts_with("compose"))
}

/// Runs the suite with `r`'s settings as the base (Gautron's stage choices and the record
/// cache are set; the other settings are the preset's but for the accuracy). `truth`: a
/// path-traced image of one bounce at the renderer's size, or None to trace one (1,024 spp).
pub fn gautron(r: &mut Renderer, truth: Option<(ImageF32, String)>) -> Result<GautronReport, CliError> {
    let (width, height) = r.size();
    if width * height > 65536 {
        return Err(CliError::input(format!(
            "--suite gautron computes a hemisphere per pixel for the brute force: {width}x{height} is more than the cache's 65,536 records; use --size 64x64"
        )));
    }
    let original = r.settings().clone();
    let clock = r.clock;
    r.clock.anim_frame = 0;
    r.clock.playing = false;
    let (truth, truth_name) = match truth {
        Some(t) => t,
        None => {
            use gi_render::cpu::pathtrace::{PathTracer, PtSettings, Senders};
            let scene = r.scene();
            let camera = gi_render::renderer::default_camera(scene, scene.bounds(0.0), width as f32 / height as f32);
            let pt = PathTracer::new(scene, 0.0);
            let settings = PtSettings { bounces: 1, spp: 1024, seed: 1, senders: Senders::All };
            let img =
                pt.render(camera.view_proj(width as f32 / height as f32), camera.position, width, height, settings);
            (img.full, "path tracer, 1 bounce, 1,024 spp (traced here)".to_string())
        }
    };
    let mut base = original.clone();
    if !base.pipeline.uses_gautron() {
        Technique::Gautron.apply(&mut base);
    }
    base.pipeline.temporal = Temporal::RecordCache;
    let set = |r: &mut Renderer, s| r.set_settings(s).map_err(|e| CliError::failure(e.to_string()));

    let mut brute = base.clone();
    let g = &mut brute.gautron;
    (g.accuracy, g.r_min_px, g.r_max_px, g.r_min_scene) = (0.02, 0.0, 1.0, 0.0);
    // R_k ≤ 1 px leaves neighbour clamping nothing to do but its O(records × round) cost.
    g.neighbour_clamping = false;
    // One frame covers the image: 2×2-pixel tiles give a quarter of the pixels per round.
    let per_round = (width * height).div_ceil(4).min(1024);
    let rounds = (width * height).div_ceil(per_round).min(32);
    (g.creation_tile_px, g.records_per_round, g.rounds, g.capacity) = (2, per_round, rounds, 65536);
    g.creation_schedule = gi_render::passes::gautron::CreationSchedule::Fixed;
    set(r, brute)?;
    let (mut brute_force, brute_image) = cold_to_covered(r, 0.02)?;
    brute_force.flip_vs_truth = flip_of(&brute_image, &truth)?;
    brute_force.speedup = 1.0;

    let mut rows = Vec::new();
    for accuracy in [0.6, 0.4, 0.2, 0.1, 0.05] {
        let mut s = base.clone();
        s.gautron.accuracy = accuracy;
        set(r, s)?;
        let (mut row, image) = cold_to_covered(r, accuracy)?;
        row.flip_vs_brute_force = flip_of(&image, &brute_image)?;
        row.flip_vs_truth = flip_of(&image, &truth)?;
        row.speedup = brute_force.cold_ms / row.cold_ms.max(1e-9);
        rows.push(row);
    }
    let mut mixes = Vec::new();
    // Records lit by the VPLs: cold until covered.
    let mut s = base.clone();
    Technique::GautronVplRecords.apply(&mut s);
    set(r, s)?;
    r.reset_history();
    let (mut frames, mut ms) = (0, 0.0);
    loop {
        let t = r.render_frame();
        let st = r
            .gautron()
            .and_then(|g| g.read_state(&r.ctx))
            .ok_or_else(|| CliError::failure("no Gautron stage".to_string()))?;
        if st.made == 0 || frames >= 256 {
            break;
        }
        frames += 1;
        ms += t.iter().filter(|p| indirect_pass(&p.name)).map(|p| p.ms).sum::<f64>();
    }
    let points = r.gautron().and_then(|g| g.read_state(&r.ctx)).map_or(0, |s| s.count);
    let image = r.readback("final.hdr").map_err(|e| CliError::failure(e.to_string()))?;
    mixes.push(MixRow {
        name: "records lit by VPLs".into(),
        points,
        frames,
        ms,
        flip_vs_brute_force: flip_of(&image, &brute_image)?,
        flip_vs_truth: flip_of(&image, &truth)?,
    });
    // A hemisphere at each HCB sample: one frame, without the sample cache (which would light
    // only a quarter of the samples in the second frame; the row compares shading points).
    let mut s = base.clone();
    Technique::GautronAtHcbSamples.apply(&mut s);
    s.pipeline.temporal = gi_render::settings::pipeline::Temporal::None;
    set(r, s)?;
    r.render_frame();
    let t = r.render_frame();
    let points = r.gautron().and_then(|g| g.read_state(&r.ctx)).map_or(0, |s| s.made);
    let image = r.readback("final.hdr").map_err(|e| CliError::failure(e.to_string()))?;
    mixes.push(MixRow {
        name: "hemispheres at HCB samples".into(),
        points,
        frames: 1,
        ms: t.iter().filter(|p| indirect_pass(&p.name)).map(|p| p.ms).sum(),
        flip_vs_brute_force: flip_of(&image, &brute_image)?,
        flip_vs_truth: flip_of(&image, &truth)?,
    });
    let cpu_cache = super::gautron_cpu::cpu_comparison(r, &base, &truth)?;
    let adapter = r.ctx.adapter_summary();
    let timing_source = format!("{:?}", r.timing_source());
    set(r, original)?;
    r.clock = clock;
    Ok(GautronReport { adapter, timing_source, width, height, truth: truth_name, brute_force, rows, mixes, cpu_cache })
}

/// The goal on the rows: the cheapest row whose FLIP against the truth is within 10 % of the
/// brute force's, and its speedup (None: no row is).
pub fn goal(report: &GautronReport) -> Option<&GautronRow> {
    let bound = report.brute_force.flip_vs_truth * 1.1;
    report.rows.iter().filter(|r| r.flip_vs_truth <= bound).min_by(|a, b| a.cold_ms.total_cmp(&b.cold_ms))
}

/// The suite as text: one line per accuracy, the brute force first.
pub fn format(report: &GautronReport) -> String {
    let mut s = format!(
        "GI Lab bench suite gautron (Gautron et al. 003) — {}×{}, {} ({}); truth: {}\n\n",
        report.width, report.height, report.adapter, report.timing_source, report.truth
    );
    s += &format!(
        "{:<16} {:>8} {:>7} {:>11} {:>12} {:>9} {:>10} {:>10} {:>8}\n",
        "", "records", "frames", "cold ms*", "ms/record*", "warm ms*", "FLIP brute", "FLIP truth", "speedup"
    );
    let line = |name: String, r: &GautronRow| {
        format!(
            "{name:<16} {:>8} {:>7} {:>11.2} {:>12.4} {:>9.2} {:>10.4} {:>10.4} {:>7.1}×\n",
            r.records,
            r.frames_to_cover,
            r.cold_ms,
            r.per_record_ms,
            r.warm_ms,
            r.flip_vs_brute_force,
            r.flip_vs_truth,
            r.speedup
        )
    };
    s += &line("brute force".into(), &report.brute_force);
    for r in &report.rows {
        s += &line(format!("a = {}", r.accuracy), r);
    }
    s += "\n* sums of the Gautron passes' times (create, hemispheres, splat, resolve) over the frames from an empty cache until one makes no record; the warm frame is the next one\n";
    let pixels = report.width * report.height;
    s += &format!(
        "\npixels per record (the hemispheres saved): {}\n",
        report
            .rows
            .iter()
            .map(|r| format!("a = {}: {:.1}", r.accuracy, pixels as f64 / r.records.max(1) as f64))
            .collect::<Vec<_>>()
            .join(", ")
    );
    if !report.mixes.is_empty() {
        s += &format!(
            "\nmixes (GI Lab's)            {:>8} {:>7} {:>11} {:>10} {:>10}\n",
            "points", "frames", "ms†", "FLIP brute", "FLIP truth"
        );
        for m in &report.mixes {
            s += &format!(
                "{:<27} {:>8} {:>7} {:>11.2} {:>10.4} {:>10.4}\n",
                m.name, m.points, m.frames, m.ms, m.flip_vs_brute_force, m.flip_vs_truth
            );
        }
        s += "† every pass of stages 3–7 (the VPLs, ISMs and the HCB's build and splat included) over the frames\n";
        let hcb = report.mixes.iter().find(|m| m.name.starts_with("hemispheres"));
        let nearest = |h: &MixRow| {
            report.rows.iter().min_by(|a, b| (a.cold_ms - h.ms).abs().total_cmp(&(b.cold_ms - h.ms).abs()))
        };
        if let Some((h, r)) = hcb.and_then(|h| nearest(h).map(|r| (h, r))) {
            s += &format!(
                "at equal time: {} HCB samples in {:.1} ms, FLIP {:.4}; Gautron's a = {}: {} records in {:.1} ms, FLIP {:.4}\n",
                h.points, h.ms, h.flip_vs_truth, r.accuracy, r.records, r.cold_ms, r.flip_vs_truth
            );
        }
    }
    s += &match goal(report) {
        Some(r) => format!(
            "goal: ≥ 20× over the brute force at equal FLIP (within 10 %): a = {} is {:.1}× faster — {}\n",
            r.accuracy,
            r.speedup,
            if r.speedup >= 20.0 { "met" } else { "NOT met" }
        ),
        None => format!(
            "goal: ≥ 20× over the brute force at equal FLIP: NOT met — no row's FLIP is within 10 % of the brute force's {:.4}\n",
            report.brute_force.flip_vs_truth
        ),
    };
    s += &super::gautron_cpu::format(&report.cpu_cache);
    s
}
