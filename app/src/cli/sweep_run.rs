//! Running `gi-lab sweep`: every point (or a shard's share of them, `--shard I/N`) rendered on
//! a renderer of its own and measured against the reference, then `sweep.csv` and
//! `pareto.png`; `--merge DIR` joins the shards' `sweep.json` into the same files.

use std::path::Path;

use gi_render::{GpuContext, LabSettings, Renderer};
use serde::{Deserialize, Serialize};

use super::shard::{Shard, shard_dirs};
use super::shard_status::check_complete;
use super::sweep::{Param, PointResult, SweepArgs, csv, grid, mark_pareto, pareto_plot, parse_param, settings_at};
use crate::error::CliError;

/// What one shard measured: `DIR/shard-I/sweep.json`.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct SweepShard {
    /// The sweep's arguments but where it writes and its share: shards of one sweep agree.
    pub spec: String,
    pub shard: Shard,
    /// Points in the whole sweep.
    pub points: usize,
    pub params: Vec<String>,
    pub size: (u32, u32),
    pub adapter: String,
    pub rows: Vec<PointResult>,
}

fn spec_of(args: &SweepArgs) -> String {
    let mut a = args.clone();
    a.out = None;
    a.shard = None;
    a.merge = None;
    a.emit = super::emit::EmitArgs::default();
    format!("{a:?}")
}

/// Path-traces the ground truth of `scene` at time 0 for the renderer's camera.
fn path_trace(r: &Renderer, spp: u32, bounces: u32) -> gi_render::ImageF32 {
    use gi_render::cpu::pathtrace::{PathTracer, PtSettings};
    let (w, h) = r.size();
    let pt = PathTracer::new(r.scene(), 0.0);
    pt.render(r.view_proj(), r.camera.position, w, h, PtSettings { bounces, spp, seed: 1, ..Default::default() }).full
}

fn write(path: &Path, bytes: &[u8]) -> Result<(), CliError> {
    gi_render::files::write_atomic_bytes(path, bytes, gi_render::files::Backup::Skip)
        .map_err(|e| CliError::failure(format!("{}: {e}", path.display())))
}

/// `path` made absolute (the shards of `--emit-jobs` may start in any folder).
fn absolute(path: &Path, flag: &str) -> Result<String, CliError> {
    std::fs::canonicalize(path)
        .map(|a| a.display().to_string())
        .map_err(|e| CliError::input(format!("{flag} {}: {e}", path.display())))
}

/// The sweep's arguments but `--out`, `--shard`, `--merge` and `--emit-jobs`, its files as
/// absolute paths: what each shard of `--emit-jobs` runs.
fn shard_args(args: &SweepArgs) -> Result<Vec<String>, CliError> {
    let mut v: Vec<String> = Vec::new();
    let mut push = |flag: &str, value: String| v.extend([flag.to_string(), value]);
    let s = &args.scene;
    if let Some(p) = &s.scene {
        push("--scene", absolute(p, "--scene")?);
    }
    push("--unit-scale", s.unit_scale.to_string());
    if let Some(p) = &s.preset {
        push("--preset", absolute(p, "--preset")?);
    }
    for o in &s.overrides {
        push("--set", o.clone());
    }
    if let Some(sky) = &s.sky {
        // A colour or `off` as it is; an image by its absolute path.
        let image = Path::new(sky);
        push("--sky", if image.is_file() { absolute(image, "--sky")? } else { sky.clone() });
    }
    push("--sky-intensity", s.sky_intensity.to_string());
    push("--sky-rotation", s.sky_rotation.to_string());
    for p in &args.params {
        push("--param", p.clone());
    }
    push("--size", format!("{}x{}", args.size.0, args.size.1));
    push("--frames", args.frames.to_string());
    push("--flicker-frames", args.flicker_frames.to_string());
    if let Some(r) = &args.reference {
        push("--reference", absolute(r, "--reference")?);
    }
    push("--reference-spp", args.reference_spp.to_string());
    Ok(v)
}

pub fn sweep(args: &SweepArgs) -> Result<(), CliError> {
    if let Some(dir) = &args.merge {
        return merge(dir);
    }
    let Some(out) = args.out.clone() else { return Err(CliError::input("--out DIR is required (or --merge DIR)")) };
    args.emit.check()?;
    match args.shard {
        // A shard claims its folder first, so that even its bad input is recorded there for
        // the merge to name (crate::cli::shard_status).
        Some(shard) => {
            let claim = super::shard_status::claim(&out, shard, "sweep.json")?;
            claim.finish(run(args, &out))
        }
        None => run(args, &out),
    }
}

/// The sweep (or its shard) into `out`, or the script of `--emit-jobs`.
fn run(args: &SweepArgs, out: &Path) -> Result<(), CliError> {
    let out = out.to_path_buf();
    if args.frames == 0 {
        return Err(CliError::input("--frames must be at least 1"));
    }
    if args.flicker_frames == 1 {
        return Err(CliError::input("--flicker-frames must be 0 or at least 2"));
    }
    let params: Vec<Param> =
        args.params.iter().map(|s| parse_param(s)).collect::<Result<_, _>>().map_err(CliError::input)?;
    let base = crate::scene_args::load_settings(&args.scene)?;
    let points = grid(&params);
    // Every point is checked before anything renders.
    let settings = settings_at(&base, &points).map_err(CliError::input)?;
    if args.emit.emit_jobs.is_some() {
        let path = super::emit::write_script("sweep", &shard_args(args)?, &out, &args.emit)?;
        println!("wrote {} ({} points in {} shards)", path.display(), points.len(), args.emit.shards);
        return Ok(());
    }
    let shard = args.shard.unwrap_or(Shard { index: 1, count: 1 });
    let dir = if args.shard.is_some() { shard.dir(&out) } else { out.clone() };
    std::fs::create_dir_all(&dir).map_err(|e| CliError::input(format!("--out {}: {e}", dir.display())))?;
    let scene = crate::scene_args::load_scene(&args.scene)?;
    let ctx = GpuContext::headless().map_err(|e| CliError::failure(e.to_string()))?;
    // Each point renders on a renderer of its own: a renderer's frame count (its sample
    // patterns' seeds) and caches would make a point's result depend on the points before it,
    // and so on how the sweep is split.
    let fresh = |s: LabSettings| {
        super::bench::run::measuring_renderer(&ctx, &scene, s, args.size).map_err(|e| CliError::input(e.to_string()))
    };
    let first = fresh(base.clone())?;
    let reference = match &args.reference {
        Some(path) => super::compare::load_image(path)?.0,
        None => {
            use gi_render::settings::pipeline::{Gather, ShadingPoints};
            let p = &base.pipeline;
            let bounces = if p.gather == Gather::None {
                0
            } else if p.uses_knecht_vpls() && p.shading_points != ShadingPoints::HcbSamples {
                base.vpl.bounces
            } else {
                1
            };
            eprintln!(
                "path-tracing the ground truth: {}×{}, {} spp, {bounces} bounce(s) …",
                args.size.0, args.size.1, args.reference_spp
            );
            let img = path_trace(&first, args.reference_spp.max(1), bounces);
            // Every shard traces the same image (seed 1) and writes it to the sweep's folder.
            let path = out.join("reference.exr");
            gi_render::image_io::save_exr(&path, &img)
                .map_err(|e| CliError::failure(format!("{}: {e}", path.display())))?;
            img
        }
    };
    let adapter = first.ctx.adapter_summary();
    drop(first);
    let range = shard.range(points.len());
    let bar = indicatif::ProgressBar::new(range.len() as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} points, {elapsed} elapsed, ETA {eta} {msg}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let display_ref = gi_render::image_io::hdr_display(&reference);
    let mut results = Vec::with_capacity(range.len());
    for i in range {
        let pt = &points[i];
        let mut r = fresh(settings[i].clone()).map_err(|e| CliError::input(format!("point {pt:?}: {}", e.message)))?;
        let report = super::bench::run::bench_run(&mut r, args.frames, "sweep");
        let hdr = r.readback("final.hdr").map_err(|e| CliError::failure(e.to_string()))?;
        let metric = |e: gi_render::metrics::MetricError| CliError::input(format!("reference: {e}"));
        let rmse = gi_render::metrics::rmse(&hdr, &reference).map_err(metric)?;
        let (flip, _) =
            gi_render::metrics::flip(&gi_render::image_io::hdr_display(&hdr), &display_ref).map_err(metric)?;
        let flicker = if args.flicker_frames >= 2 {
            Some(super::bench::run::measure_flicker(&mut r, args.flicker_frames)?)
        } else {
            None
        };
        results.push(PointResult {
            index: i,
            assignments: pt.iter().map(|(p, v)| (p.clone(), v.to_string())).collect(),
            passes: report.passes.iter().map(|p| (p.pass.clone(), p.mean_ms)).collect(),
            total_ms: report.total_mean_ms,
            flip,
            rmse,
            flicker,
            pareto: false,
        });
        bar.inc(1);
    }
    bar.finish_and_clear();
    let part = SweepShard {
        spec: spec_of(args),
        shard,
        points: points.len(),
        params: params.iter().map(|p| p.path.clone()).collect(),
        size: args.size,
        adapter,
        rows: results,
    };
    if args.shard.is_some() {
        let path = dir.join("sweep.json");
        let text = serde_json::to_string_pretty(&part).map_err(|e| CliError::failure(e.to_string()))?;
        write(&path, text.as_bytes())?;
        println!(
            "shard {}/{}: {} of {} points in {}; join the shards with: gi-lab sweep --merge {}",
            shard.index,
            shard.count,
            part.rows.len(),
            part.points,
            dir.display(),
            out.display()
        );
        return Ok(());
    }
    finish(&out, vec![part])
}

/// Joins the parts of one sweep (checked: one spec, every point once) and writes sweep.csv
/// and pareto.png into `out`.
fn finish(out: &Path, parts: Vec<SweepShard>) -> Result<(), CliError> {
    let first = parts.first().ok_or_else(|| CliError::input("no shard to join"))?.clone();
    let mut results: Vec<PointResult> = Vec::new();
    for p in &parts {
        if p.spec != first.spec || p.points != first.points {
            return Err(CliError::input(format!(
                "shard {}/{} belongs to another sweep (its arguments differ from shard {}/{}'s)",
                p.shard.index, p.shard.count, first.shard.index, first.shard.count
            )));
        }
        results.extend(p.rows.iter().cloned());
    }
    results.sort_by_key(|p| p.index);
    if results.iter().map(|p| p.index).collect::<Vec<_>>() != (0..first.points).collect::<Vec<_>>() {
        return Err(CliError::input(format!(
            "the shards hold {} points of {}: a shard is missing, repeated or unfinished",
            results.len(),
            first.points
        )));
    }
    mark_pareto(&mut results);
    let csv_path = out.join("sweep.csv");
    write(&csv_path, csv(&first.params, &results).as_bytes())?;
    let mut adapters: Vec<&str> = parts.iter().map(|p| p.adapter.as_str()).collect();
    adapters.dedup();
    let title = format!(
        "GI Lab sweep: {} points at {}×{}, {}",
        results.len(),
        first.size.0,
        first.size.1,
        adapters.join(" + ")
    );
    let plot_path = out.join("pareto.png");
    let plot = image::DynamicImage::ImageRgba8(pareto_plot(&title, &results));
    gi_render::image_io::save_atomic(&plot_path, &plot, image::ImageFormat::Png)
        .map_err(|e| CliError::failure(format!("{}: {e}", plot_path.display())))?;
    println!("wrote {} and {}", csv_path.display(), plot_path.display());
    for p in results.iter().filter(|p| p.pareto) {
        let settings: Vec<String> = p.assignments.iter().map(|(n, v)| format!("{n}={v}")).collect();
        println!("pareto #{}: {:.3} ms, FLIP {:.4} — {}", p.index, p.total_ms, p.flip, settings.join(", "));
    }
    Ok(())
}

/// `gi-lab sweep --merge DIR`.
fn merge(dir: &Path) -> Result<(), CliError> {
    let found = shard_dirs(dir, "sweep.json").map_err(CliError::input)?;
    let mut parts = Vec::new();
    let mut shards = Vec::new();
    for (_, d) in &found {
        let path = d.join("sweep.json");
        let text = std::fs::read_to_string(&path).map_err(|e| CliError::input(format!("{}: {e}", path.display())))?;
        let part: SweepShard = serde_json::from_str(&text)
            .map_err(|e| CliError::input(format!("{}: not a sweep shard: {e}", path.display())))?;
        shards.push((d.clone(), part.shard));
        parts.push(part);
    }
    check_complete(dir, &shards, "sweep.json").map_err(CliError::input)?;
    finish(dir, parts)
}
