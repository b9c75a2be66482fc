//! The measurement engine of `gi-lab bench`, its suites, `sweep` and `study`: renders
//! warm-up and measured frames and aggregates per-pass times, bound bytes and the frame's
//! waits; measures flicker, afterglow and quality against a reference; traces the one-bounce
//! truth. It uses no suite and no command.

use std::path::Path;

use gi_render::Renderer;

use crate::cli::compare::load_image;
use crate::error::CliError;

/// The shipped technique presets, one per paper and DDGI's probes (issue #56), that `bench
/// --suite scenes` and `gi-lab study` compare when no preset is named: (name, RON text).
pub const TECHNIQUE_PRESETS: [(&str, &str); 5] = [
    ("knecht", include_str!("../../../../presets/knecht-cornell-256.ron")),
    ("nguyen", include_str!("../../../../presets/nguyen-hcb.ron")),
    ("soler", include_str!("../../../../presets/soler-quarter-4-64.ron")),
    ("gautron", include_str!("../../../../presets/gautron-ic-splatting.ron")),
    ("ddgi", include_str!("../../../../presets/ddgi-probes.ron")),
];

/// Per-pass statistics of a benchmark run.
#[derive(Debug, Clone, serde::Serialize)]
pub struct PassStats {
    pub pass: String,
    pub mean_ms: f64,
    pub min_ms: f64,
    pub max_ms: f64,
    /// Mean bytes the pass binds per frame (`gi_render::counters::traffic`).
    pub traffic_bytes: f64,
}

#[derive(Debug, Clone, serde::Serialize)]
pub struct BenchReport {
    pub adapter: String,
    pub timing_source: String,
    pub scene: String,
    pub width: u32,
    pub height: u32,
    pub frames: u32,
    pub passes: Vec<PassStats>,
    pub total_mean_ms: f64,
    /// Mean wall-clock time of one `render_frame` call (ms): the CPU's work, the submission
    /// and whatever waiting for the GPU the frame does (its timing read-back included), so
    /// `wall_mean_ms − total_mean_ms` is roughly the time the frame is not on the GPU.
    pub wall_mean_ms: f64,
    /// Mean wall-clock time of a frame as the window renders it (ms): interactive mode, no
    /// per-pass timing and no waits, the GPU's work drained once after the frames. On a
    /// device without timestamps (lavapipe) `wall_mean_ms` includes a wait after every pass;
    /// this is the frame the user gets.
    /// Measured by plain `gi-lab bench` only (None in the suites and sweeps).
    pub window_frame_ms: Option<f64>,
    /// Times per measured frame that the CPU waited for the GPU (`gi_render::counters`). The
    /// command line waits once a frame for that frame's timings; the window never does.
    pub blocking_waits_per_frame: f64,
    /// Queue submissions per measured frame.
    pub submits_per_frame: f64,
    /// Buffers, textures, views, bind groups, samplers and query sets created per measured
    /// frame (0 in a lean steady state).
    pub objects_created_per_frame: f64,
    /// Bytes read and written per measured frame: per pass, the bytes of every resource it
    /// binds, from their formats and sizes (`gi_render::counters::traffic`), summed.
    pub traffic_bytes_per_frame: f64,
    /// Light-space work per measured frame that ran (shadow maps, light G-buffers with their
    /// importance, a fixed VPL set with its visibility: each counts once a frame) …
    pub light_space_runs_per_frame: f64,
    /// … and that was kept from an earlier frame because nothing it depends on changed
    /// (issue #53). A still scene under the default preset: the shadow maps and the light
    /// G-buffers are kept; its VPL set is new every frame (`vpl.new_set_each_frame`).
    pub light_space_skips_per_frame: f64,
    /// The same for the camera's G-buffer and the direct light (each once a frame): kept
    /// while the camera, the objects and the lights stay put.
    pub screen_space_runs_per_frame: f64,
    pub screen_space_skips_per_frame: f64,
    /// Temporal flicker of final.hdr with the animation paused and the camera still
    /// (`metrics::flicker`); None when not measured.
    pub flicker: Option<f64>,
    /// Quality against `--reference`: mean FLIP (tone-mapped x/(1+x)) and RMSE (linear).
    pub flip: Option<f64>,
    pub rmse: Option<f64>,
    /// Frames until the error against the settled image returns within 2× its steady state
    /// after the first light's intensity is halved (`metrics::afterglow`); None when not
    /// measured or when it did not settle.
    pub afterglow_frames: Option<usize>,
    /// What this device ran where a GPU and a CPU renderer run different passes with the same
    /// result (the splats' `Auto`, the gathers' shape: docs/architecture.md), e.g.
    /// "hcb.splat Auto → Binned".
    pub device_choices: Vec<String>,
}

/// A renderer of its own for one measurement: paused at the start of the animation, every
/// pass redone every frame, and timed by the wall clock per pass on a device whose timestamps
/// land in the wrong passes.
/// Each job of a study, point of a sweep and row of the scenes suite gets one, so that its
/// result does not depend on what a renderer rendered before (its frame count seeds the
/// sample patterns).
pub fn measuring_renderer(
    ctx: &gi_render::GpuContext,
    scene: &gi_render::scene::Scene,
    settings: gi_render::LabSettings,
    (w, h): (u32, u32),
) -> Result<Renderer, gi_render::renderer::RenderError> {
    let mut r = Renderer::new(ctx.clone(), scene.clone(), settings, w, h)?;
    if !gi_render::timing::GpuTimer::timestamps_reliable(&r.ctx) {
        r.set_timing_source(gi_render::timing::TimingSource::CpuWallClock);
    }
    r.clock.playing = false;
    r.clock.anim_frame = 0;
    // Every pass of every frame is timed, as in a frame where something moves: a study's or
    // sweep's frame time is comparable between techniques and with earlier runs. What the
    // passes kept while nothing moves save (issue #53) is `gi-lab bench --paused`'s measure.
    r.reuse_unchanged = false;
    Ok(r)
}

/// Renders warm-up and measured frames and aggregates the per-pass times.
pub fn bench_run(r: &mut Renderer, frames: u32, scene_name: &str) -> BenchReport {
    for _ in 0..3 {
        r.render_frame();
    }
    let mut names: Vec<String> = Vec::new();
    let mut samples: Vec<Vec<f64>> = Vec::new();
    let started = std::time::Instant::now();
    let counted = gi_render::counters::now();
    let mut traffic: Vec<(String, u64)> = Vec::new();
    for _ in 0..frames {
        let timings = r.render_frame();
        for (pass, bytes) in r.traffic() {
            match traffic.iter_mut().find(|(n, _)| n == pass) {
                Some(t) => t.1 += bytes,
                None => traffic.push((pass.clone(), *bytes)),
            }
        }
        // A pass that runs several times a frame (Gautron's rounds and chunks, the bounces'
        // pull-pushes) is one sample per frame: the sum of its scopes.
        let mut frame: Vec<(String, f64)> = Vec::new();
        for t in timings {
            match frame.iter_mut().find(|(n, _)| *n == t.name) {
                Some(f) => f.1 += t.ms,
                None => frame.push((t.name, t.ms)),
            }
        }
        for (name, ms) in frame {
            let i = match names.iter().position(|n| *n == name) {
                Some(i) => i,
                None => {
                    names.push(name);
                    samples.push(Vec::new());
                    names.len() - 1
                }
            };
            samples[i].push(ms);
        }
    }
    let passes: Vec<PassStats> = names
        .into_iter()
        .zip(samples)
        .map(|(pass, s)| PassStats {
            mean_ms: s.iter().sum::<f64>() / s.len().max(1) as f64,
            min_ms: s.iter().copied().fold(f64::INFINITY, f64::min),
            max_ms: s.iter().copied().fold(0.0, f64::max),
            traffic_bytes: traffic.iter().find(|(n, _)| *n == pass).map_or(0.0, |t| t.1 as f64 / frames.max(1) as f64),
            pass,
        })
        .collect();
    let wall_mean_ms = started.elapsed().as_secs_f64() * 1e3 / frames.max(1) as f64;
    let counts = gi_render::counters::now() - counted;

    let per_frame = |n: u64| n as f64 / frames.max(1) as f64;
    let (width, height) = r.size();
    let device_choices = device_choices(r);
    BenchReport {
        adapter: r.ctx.adapter_summary(),
        timing_source: format!("{:?}", r.timing_source()),
        scene: scene_name.to_string(),
        width,
        height,
        frames,
        total_mean_ms: passes.iter().map(|p| p.mean_ms).sum(),
        wall_mean_ms,
        window_frame_ms: None,
        blocking_waits_per_frame: per_frame(counts.blocking_waits),
        submits_per_frame: per_frame(counts.submits),
        objects_created_per_frame: per_frame(counts.objects_created),
        traffic_bytes_per_frame: per_frame(counts.traffic_bytes),
        light_space_runs_per_frame: per_frame(counts.light_space_runs),
        light_space_skips_per_frame: per_frame(counts.light_space_skips),
        screen_space_runs_per_frame: per_frame(counts.screen_space_runs),
        screen_space_skips_per_frame: per_frame(counts.screen_space_skips),
        passes,
        flicker: None,
        flip: None,
        rmse: None,
        afterglow_frames: None,
        device_choices,
    }
}

/// The device-dependent choices of the stages `r` runs (see [`BenchReport::device_choices`]).
fn device_choices(r: &mut Renderer) -> Vec<String> {
    let shape = |wide: bool, item: &str| {
        if wide { format!("a workgroup per {item}") } else { format!("an invocation per {item}") }
    };
    let hcb_wide = r.hcb_mut().map(|h| h.gather.wide);
    let records_wide = r.gautron_mut().and_then(|g| g.vpl_records_mut().map(|p| p.wide));
    let has_gautron = r.gautron().is_some();
    let s = r.settings();
    let mut v = Vec::new();
    if let Some(wide) = hcb_wide {
        v.push(format!("hcb.splat {:?} → {:?}", s.hcb.splat, s.hcb.splat.on(&r.ctx)));
        v.push(format!("HCB gather: {}", shape(wide, "sample")));
    }
    if has_gautron {
        v.push(format!("gautron.splat {:?} → {:?}", s.gautron.splat, s.gautron.splat.on(&r.ctx)));
    }
    if let Some(wide) = records_wide {
        v.push(format!("VPL-lit records: {}", shape(wide, "record")));
    }
    v
}

/// Mean wall-clock ms of `frames` frames as the window renders them: interactive mode (no
/// per-pass timing, no waits), after one frame to settle the mode, the GPU drained once at
/// the end.
pub fn window_frames(r: &mut Renderer, frames: u32) -> f64 {
    r.set_interactive(true);
    r.render_frame();
    r.ctx.wait_idle();
    let started = std::time::Instant::now();
    for _ in 0..frames {
        r.render_frame();
    }
    r.ctx.wait_idle();
    r.set_interactive(false);
    started.elapsed().as_secs_f64() * 1e3 / frames.max(1) as f64
}

pub fn format_bench_table(b: &BenchReport) -> String {
    let mut s = format!(
        "GI Lab bench — {} at {}×{}, {} frames, {} ({})\n",
        b.scene, b.width, b.height, b.frames, b.adapter, b.timing_source
    );
    s += &format!("{:<16} {:>10} {:>10} {:>10} {:>10}\n", "pass", "mean ms", "min ms", "max ms", "MB bound");
    for p in &b.passes {
        let mb = p.traffic_bytes / 1e6;
        s += &format!("{:<16} {:>10.3} {:>10.3} {:>10.3} {:>10.1}\n", p.pass, p.mean_ms, p.min_ms, p.max_ms, mb);
    }
    s += &format!("{:<16} {:>10.3} {:>32.1}\n", "total", b.total_mean_ms, b.traffic_bytes_per_frame / 1e6);
    s += &format!(
        "{:<16} {:>10.3}   (wall clock per render_frame call, CPU and waits included)\n",
        "frame wall", b.wall_mean_ms
    );
    if let Some(ms) = b.window_frame_ms {
        s += &format!(
            "{:<16} {:>10.3}   (wall clock per frame as the window renders it: no per-pass timing, no waits)\n",
            "window frame", ms
        );
    }
    s += &format!(
        "per frame: {:.1} blocking waits, {:.1} submits, {:.1} GPU objects created\n",
        b.blocking_waits_per_frame, b.submits_per_frame, b.objects_created_per_frame
    );
    s += &format!(
        "kept while nothing moved, per frame: light space {:.1} redone, {:.1} kept; G-buffer and direct light {:.1} redone, {:.1} kept\n",
        b.light_space_runs_per_frame,
        b.light_space_skips_per_frame,
        b.screen_space_runs_per_frame,
        b.screen_space_skips_per_frame
    );
    if !b.device_choices.is_empty() {
        s += &format!("on this device: {}\n", b.device_choices.join("; "));
    }
    if let Some(f) = b.flicker {
        s += &format!("flicker (static scene) {f:.6}\n");
    }
    if let Some(a) = b.afterglow_frames {
        s += &format!("afterglow (first light halved) {a} frames\n");
    }
    if let (Some(flip), Some(rmse)) = (b.flip, b.rmse) {
        s += &format!("quality vs reference: FLIP {flip:.4}, RMSE {rmse:.5}\n");
    }
    s
}

/// Temporal flicker over `frames` frames with the animation paused (the clock restored).
pub fn measure_flicker(r: &mut Renderer, frames: u32) -> Result<f64, CliError> {
    let playing = r.clock.playing;
    r.clock.playing = false;
    let mut images = Vec::new();
    for _ in 0..frames {
        r.render_frame();
        images.push(r.readback("final.hdr").map_err(|e| CliError::failure(e.to_string()))?);
    }
    r.clock.playing = playing;
    gi_render::metrics::flicker(&images).map_err(|e| CliError::input(format!("--flicker-frames: {e}")))
}

/// Afterglow of a sudden light change: the first light's intensity is halved and the RMSE of
/// each of the next `frames` frames is taken against the image the renderer settles on when
/// it starts with the halved light (`frames` frames after a history reset). The scene is
/// paused; the light and the clock are restored afterwards. None when the scene has no light
/// or the error does not settle.
pub fn measure_afterglow(r: &mut Renderer, frames: u32) -> Result<Option<usize>, CliError> {
    let Some(li) = r.scene().lights.iter().position(|_| true) else { return Ok(None) };
    let clock = r.clock;
    r.clock.playing = false;
    let original = r.scene().lights[li].intensity;
    let read = |r: &Renderer| r.readback("final.hdr").map_err(|e| CliError::failure(e.to_string()));
    let run = |r: &mut Renderer, intensity: f32, reset: bool| {
        r.scene_mut().lights[li].intensity = intensity;
        if reset {
            r.reset_history();
        }
    };
    run(r, original * 0.5, true);
    for _ in 0..frames {
        r.render_frame();
    }
    let settled = read(r)?;
    run(r, original, true);
    for _ in 0..frames {
        r.render_frame();
    }
    // The sudden change: no reset, the renderer must notice by itself.
    run(r, original * 0.5, false);
    let mut errors = Vec::with_capacity(frames as usize);
    for _ in 0..frames {
        r.render_frame();
        let e = gi_render::metrics::rmse(&read(r)?, &settled).map_err(|e| CliError::failure(e.to_string()))?;
        errors.push(e);
    }
    run(r, original, true);
    r.clock = clock;
    Ok(gi_render::metrics::afterglow(&errors, 0))
}

/// FLIP (tone-mapped) and RMSE (linear) of the renderer's final.hdr against a reference of
/// the scene at animation time 0 (as `gi-lab reference` renders it): the clock is set back
/// to 0 and paused for that frame.
pub fn quality_against(r: &mut Renderer, reference: &Path) -> Result<(f64, f64), CliError> {
    let (reference_img, _) = load_image(reference)?;
    let clock = r.clock;
    r.clock.anim_frame = 0;
    r.clock.playing = false;
    r.render_frame();
    r.clock = clock;
    let hdr = r.readback("final.hdr").map_err(|e| CliError::failure(e.to_string()))?;
    let err = |e: gi_render::metrics::MetricError| CliError::input(format!("--reference {}: {e}", reference.display()));
    let rmse = gi_render::metrics::rmse(&hdr, &reference_img).map_err(err)?;
    let (flip, map) = gi_render::metrics::flip(
        &gi_render::image_io::hdr_display(&hdr),
        &gi_render::image_io::hdr_display(&reference_img),
    )
    .map_err(err)?;
    r.set_flip_map(&map);
    Ok((flip, rmse))
}

/// The one-bounce path-traced ground truth of `scene` at `size` from its opening view, with
/// the emitters and the sky's background as `settings` say (as `gi-lab reference` traces it).
pub fn one_bounce_truth(
    scene: &gi_render::scene::Scene,
    settings: &gi_render::LabSettings,
    (w, h): (u32, u32),
    spp: u32,
) -> gi_render::ImageF32 {
    use gi_render::cpu::pathtrace::{PathTracer, PtSettings};
    let camera = gi_render::renderer::default_camera(scene, scene.bounds(0.0), w as f32 / h as f32);
    let mut pt = PathTracer::new(scene, 0.0);
    pt.use_emitter_settings(&settings.emitters, scene, 0.0);
    pt.set_sky_background(settings.sky.background);
    pt.render(
        camera.view_proj(w as f32 / h as f32),
        camera.position,
        w,
        h,
        PtSettings { bounces: 1, spp, seed: 1, ..Default::default() },
    )
    .full
}

/// Sum over the passes whose names start with one of `prefixes` of each pass's fastest frame:
/// the least disturbed measurement (a CPU device's per-pass wall clock varies several-fold
/// between frames with the machine's other work).
pub fn focus(report: &BenchReport, prefixes: &[&str]) -> f64 {
    report.passes.iter().filter(|p| prefixes.iter().any(|f| p.pass.starts_with(f))).map(|p| p.min_ms).sum()
}
