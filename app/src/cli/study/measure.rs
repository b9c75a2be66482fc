//! Rendering one share of a study's jobs: per scene, the truth (traced once and cached),
//! then each job's frames through the engine of `cli::bench::run`, its FLIP and RMSE against
//! the truth, its flicker, and its image and FLIP map as PNG.

use std::path::{Path, PathBuf};
use std::time::Instant;

use gi_render::{ImageF32, LabSettings, Renderer};

use super::jobs::{Plan, Spec};
use super::results::{Machine, Part, Row, TruthInfo};
use crate::cli::bench::run::{bench_run, measure_flicker, measuring_renderer};
use crate::cli::shard::Shard;
use crate::error::CliError;
use crate::scene_args::SceneArgs;

/// This machine: host, system, processor and the adapter `r` runs on.
pub fn machine(r: &Renderer) -> Machine {
    let read = |p: &str| std::fs::read_to_string(p).unwrap_or_default();
    let cpu = read("/proc/cpuinfo")
        .lines()
        .find_map(|l| l.strip_prefix("model name").and_then(|v| v.split_once(':')).map(|(_, v)| v.trim().to_string()))
        .unwrap_or_else(|| std::env::consts::ARCH.to_string());
    Machine {
        host: read("/proc/sys/kernel/hostname").trim().to_string(),
        os: format!("{} {}", std::env::consts::OS, std::env::consts::ARCH),
        cpu,
        cores: std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1),
        adapter: r.ctx.adapter_summary(),
        timing_source: format!("{:?}", r.timing_source()),
    }
}

/// A stable 64-bit FNV-1a hash (the truth cache's key; the same in every process).
fn fnv(bytes: &[u8], mut h: u64) -> u64 {
    for b in bytes {
        h ^= *b as u64;
        h = h.wrapping_mul(0x100_0000_01b3);
    }
    h
}

/// The cache file of a scene's truth: its key covers the scene's bytes and unit, the camera,
/// the size, bounces, spp, and the lighting settings the path tracer reads.
fn truth_key(spec: &Spec, file: Option<&str>, r: &Renderer, lighting: &LabSettings) -> Result<String, CliError> {
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    if let Some(f) = file {
        let bytes = std::fs::read(f).map_err(|e| CliError::input(format!("--scene {f}: {e}")))?;
        h = fnv(&bytes, h);
    }
    let described = format!(
        "{file:?} {} {:?} {:?} {} {} {:?} {:?}",
        spec.unit_scale,
        r.view_proj().to_cols_array(),
        spec.size,
        spec.bounces,
        spec.spp,
        lighting.emitters,
        lighting.sky.background,
    );
    Ok(format!("{:016x}", fnv(described.as_bytes(), h)))
}

/// The scene's truth at time 0 from the renderer's camera: from the cache, or traced (by the
/// GPU path tracer on a real GPU, the CPU's otherwise, issue #56) and cached. Returns the
/// image, the seconds spent tracing, whether it came from the cache and the tracer in words.
fn truth(
    spec: &Spec,
    file: Option<&str>,
    r: &Renderer,
    lighting: &LabSettings,
    cache: &Path,
) -> Result<(ImageF32, f64, bool, String), CliError> {
    let path = cache.join(format!("{}.exr", truth_key(spec, file, r, lighting)?));
    if let Ok(img) = gi_render::image_io::load_float_image(&path)
        && (img.width, img.height) == spec.size
    {
        return Ok((img, 0.0, true, String::new()));
    }
    use gi_render::cpu::pathtrace::PtSettings;
    use gi_render::passes::rays::pathtrace::{TruthLighting, TruthTracer, render_truth};
    let tracer = TruthTracer::for_adapter(&r.ctx);
    let by = tracer.describe(&r.ctx);
    eprintln!(
        "path-tracing the truth of {}: {}×{}, {} spp, {} bounce(s), with {by} …",
        file.unwrap_or("the default scene"),
        spec.size.0,
        spec.size.1,
        spec.spp,
        spec.bounces
    );
    let started = Instant::now();
    let settings = PtSettings { bounces: spec.bounces, spp: spec.spp, seed: 1, ..Default::default() };
    let lights = TruthLighting { emitters: lighting.emitters.clone(), sky_background: lighting.sky.background };
    let view = (r.view_proj(), r.camera.position, spec.size);
    let img = render_truth(&r.ctx, tracer, r.scene(), 0.0, &lights, view, settings).map_err(CliError::failure)?.full;
    let seconds = started.elapsed().as_secs_f64();
    std::fs::create_dir_all(cache).map_err(|e| CliError::failure(format!("{}: {e}", cache.display())))?;
    gi_render::image_io::save_exr(&path, &img).map_err(|e| CliError::failure(format!("{}: {e}", path.display())))?;
    Ok((img, seconds, false, by))
}

fn save_png(path: &Path, img: image::RgbaImage) -> Result<(), CliError> {
    if let Some(parent) = path.parent() {
        std::fs::create_dir_all(parent).map_err(|e| CliError::failure(format!("{}: {e}", parent.display())))?;
    }
    gi_render::image_io::save_atomic(path, &image::DynamicImage::ImageRgba8(img), image::ImageFormat::Png)
        .map_err(|e| CliError::failure(format!("{}: {e}", path.display())))
}

/// Renders the jobs of `shard` into `dir` (`img/SCENE/…`); the truth cache is `out/truth-cache`,
/// shared by the shards of one output folder.
pub fn run(spec: &Spec, plan: &Plan, shard: Shard, out: &Path, dir: &Path) -> Result<Part, CliError> {
    let jobs: Vec<usize> = shard.range(plan.jobs.len()).collect();
    let mut scenes: Vec<usize> = jobs.iter().map(|&j| plan.jobs[j].scene).collect();
    scenes.dedup();
    // Every scene of the share loads before anything renders: a broken file stops the shard
    // at once, not after hours of others.
    let mut loaded = Vec::new();
    for &s in &scenes {
        let file = plan.scenes[s].file.as_ref().map(PathBuf::from);
        let args = SceneArgs { scene: file, unit_scale: spec.unit_scale, ..Default::default() };
        loaded.push(crate::scene_args::load_scene(&args)?);
    }
    let ctx = gi_render::GpuContext::headless().map_err(|e| CliError::failure(e.to_string()))?;
    let cache = out.join("truth-cache");
    let mut lighting = LabSettings::default();
    for o in &spec.overrides {
        lighting.apply_override(o).map_err(|e| CliError::input(format!("--set {o}: {e}")))?;
    }
    let bar = indicatif::ProgressBar::new(jobs.len() as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} jobs, {elapsed} elapsed, ETA {eta} {msg}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let mut rows = Vec::new();
    let mut truths = Vec::new();
    let mut machine_seen = None;
    for (&s, scene) in scenes.iter().zip(loaded) {
        let info = &plan.scenes[s];
        let scene_jobs: Vec<usize> = jobs.iter().copied().filter(|&j| plan.jobs[j].scene == s).collect();
        // Each job renders on a renderer of its own, made for it: a renderer carries its frame
        // count (the seeds of its sample patterns) and caches from job to job, and a job must
        // measure the same on whichever shard runs it, first or after others.
        let fresh = |settings: LabSettings| {
            measuring_renderer(&ctx, &scene, settings, spec.size)
                .map_err(|e| CliError::input(format!("{}: {e}", info.name)))
        };
        let r = fresh(plan.settings(plan.jobs[scene_jobs[0]]))?;
        machine_seen.get_or_insert_with(|| machine(&r));
        let (truth_img, seconds, cached, tracer) = truth(spec, info.file.as_deref(), &r, &lighting, &cache)?;
        let truth_rel = format!("img/{}/truth.png", info.slug);
        save_png(
            &dir.join(&truth_rel),
            gi_render::image_io::to_rgba8(&truth_img, gi_render::buffers::BufferKind::Hdr),
        )?;
        truths.push((s, TruthInfo { image: truth_rel, seconds, cached, tracer }));
        let display_truth = gi_render::image_io::hdr_display(&truth_img);
        for j in scene_jobs {
            let job = plan.jobs[j];
            let name = format!("{} / {}", info.name, plan.presets[job.preset].name);
            bar.set_message(name.clone());
            let mut r = fresh(plan.settings(job))?;
            let report = bench_run(&mut r, spec.frames, &info.name);
            let hdr = r.readback("final.hdr").map_err(|e| CliError::failure(e.to_string()))?;
            let metric = |e: gi_render::metrics::MetricError| CliError::failure(format!("{name}: {e}"));
            let rmse = gi_render::metrics::rmse(&hdr, &truth_img).map_err(metric)?;
            let (flip, map) =
                gi_render::metrics::flip(&gi_render::image_io::hdr_display(&hdr), &display_truth).map_err(metric)?;
            let flicker =
                if spec.flicker_frames >= 2 { Some(measure_flicker(&mut r, spec.flicker_frames)?) } else { None };
            let stem = format!("img/{}/{}", info.slug, plan.job_slug(job));
            let (image, flip_map) = (format!("{stem}.png"), format!("{stem}-flip.png"));
            save_png(&dir.join(&image), gi_render::image_io::to_rgba8(&hdr, gi_render::buffers::BufferKind::Hdr))?;
            save_png(&dir.join(&flip_map), gi_render::image_io::error_map_rgba8(&map))?;
            rows.push(Row {
                job: j,
                scene: job.scene,
                preset: job.preset,
                point: job.point,
                assignments: plan.points[job.point].iter().map(|(p, v)| (p.clone(), v.to_string())).collect(),
                technique: plan.presets[job.preset].technique.clone(),
                frame_ms: report.total_mean_ms,
                wall_ms: report.wall_mean_ms,
                passes: report.passes.iter().map(|p| (p.pass.clone(), p.mean_ms)).collect(),
                flip,
                rmse,
                flicker,
                image,
                flip_map,
                machine: 0,
                pareto: false,
            });
            bar.inc(1);
        }
    }
    bar.finish_and_clear();
    let machine = match machine_seen {
        Some(m) => m,
        // An empty share (more shards than jobs) still says where it ran.
        None => Machine {
            host: std::fs::read_to_string("/proc/sys/kernel/hostname").unwrap_or_default().trim().to_string(),
            os: format!("{} {}", std::env::consts::OS, std::env::consts::ARCH),
            cpu: String::new(),
            cores: std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1),
            adapter: ctx.adapter_summary(),
            timing_source: String::new(),
        },
    };
    Ok(Part {
        spec: spec.clone(),
        shard,
        jobs: plan.jobs.len(),
        scenes: plan.scenes.clone(),
        presets: plan.presets.clone(),
        params: plan.params.iter().map(|p| p.path.clone()).collect(),
        machine,
        rows,
        truths,
    })
}
