//! `gi-lab soak`: a seeded random walk over everything a user can do without a window
//! (`soak_walk`), one step and one frame at a time, counting what must never happen:
//! panics (caught per step), wgpu validation and other uncaptured errors, non-finite pixels
//! in `final.hdr`, inputs accepted that should have been refused (or refused and yet
//! changing something), and resources that grow. Every `--check-every` frames the walk
//! returns to its starting point (scene, settings, size, camera) and counts the device's live
//! objects, its allocator's bytes and the process's resident memory: at the same state they
//! must not grow (`soak_memory`). One summary line at the end, with the seed and the step of the first failure so
//! that `--frames STEP --verbose` replays it.

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use std::time::Instant;

use clap::Args;
use gi_render::{GpuContext, LabSettings, Renderer};

use super::parse_size;
use super::soak_memory::{Checkpoint, RssJudged, memory_verdict, rss_judged, rss_mib};
use super::soak_walk::{self as walk, Outcome, Rng, SceneChoice};
use crate::error::CliError;
use crate::scene_args::{SceneArgs, load_scene, load_settings};

#[derive(Args, Debug)]
pub struct SoakArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Frames to render; each follows one step of the walk.
    #[arg(long, default_value_t = 1000)]
    pub frames: u64,
    /// Seed of the walk (the same seed, scene and size replay the same steps).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// The size the walk starts from and returns to.
    #[arg(long, default_value = "64x64", value_parser = parse_size)]
    pub size: (u32, u32),
    /// Frames between returns to the starting state, where resources are counted.
    #[arg(long, default_value_t = 100)]
    pub check_every: u64,
    /// The kinds of step the walk takes (comma-separated; default all): settings, choices,
    /// resize, camera, scene, shader, animation. Narrowing them finds which one a failure or
    /// a growth comes from.
    #[arg(long, value_delimiter = ',', value_parser = ["settings", "choices", "resize", "camera", "scene", "shader", "animation"])]
    pub actions: Vec<String>,
    /// Report the resident memory without letting it decide the verdict (GPU memory still
    /// does). Without it the resident memory is judged unless a probe at the start finds the
    /// driver keeping memory per dispatch by itself (`soak_memory`: Mesa 22.3's lavapipe).
    #[arg(long)]
    pub no_rss_check: bool,
    /// Print every step (to replay a failure up to its step).
    #[arg(long)]
    pub verbose: bool,
    /// Folder for the files the walk opens (a scene without lights, broken files); default:
    /// a new temporary folder.
    #[arg(long)]
    pub work_dir: Option<PathBuf>,
}

#[derive(Default)]
struct Counts {
    panics: u64,
    gpu_errors: u64,
    nonfinite_frames: u64,
    nonfinite_pixels: u64,
    wrong: u64,
    refused: u64,
    device_lost: bool,
}

/// The first thing that went wrong: its step, what the step did and what happened.
struct Failure {
    step: u64,
    action: String,
    what: String,
}

/// Uncaptured GPU errors (validation, out of memory, internal) as the device reports them.
#[derive(Default)]
struct GpuErrors {
    count: u64,
    last: Option<String>,
}

pub fn soak(args: &SoakArgs) -> Result<(), CliError> {
    if args.frames == 0 || args.check_every == 0 {
        return Err(CliError::input("--frames and --check-every must be at least 1"));
    }
    let main_scene = load_scene(&args.scene)?;
    let base_settings = load_settings(&args.scene)?;
    let ctx = GpuContext::headless().map_err(|e| CliError::failure(e.to_string()))?;
    let errors = Arc::new(Mutex::new(GpuErrors::default()));
    let sink = errors.clone();
    ctx.device.on_uncaptured_error(Arc::new(move |e| {
        if let Ok(mut g) = sink.lock() {
            g.count += 1;
            g.last = Some(e.to_string());
        }
    }));
    // Before the renderer exists: whether the driver itself grows per dispatch.
    let rss = rss_judged(&ctx, args.no_rss_check);
    if let RssJudged::No(why) = &rss {
        eprintln!("soak: resident memory is reported, not judged: {why}");
    }
    let work_dir = match &args.work_dir {
        Some(d) => d.clone(),
        None => std::env::temp_dir().join(format!("gi-lab-soak-{}", std::process::id())),
    };
    let mut scenes = walk::scene_files(&work_dir).map_err(CliError::failure)?;
    let main_name =
        args.scene.scene.as_ref().map(|p| p.display().to_string()).unwrap_or_else(|| main_scene.name.clone());
    scenes.push(SceneChoice::Good {
        name: main_name.clone(),
        path: args.scene.scene.clone(),
        unit_scale: args.scene.unit_scale,
        cached: Some(Box::new(main_scene.clone())),
    });
    if args.scene.scene.is_some() {
        scenes.push(SceneChoice::Good { name: "embedded box".into(), path: None, unit_scale: 1.0, cached: None });
    }
    let (w, h) = args.size;
    let fresh = |settings: &LabSettings| {
        Renderer::new(ctx.clone(), main_scene.clone(), settings.clone(), w, h)
            .map_err(|e| CliError::input(format!("the starting state does not render: {e}")))
    };
    let mut r = fresh(&base_settings)?;
    let mut rng = Rng::new(args.seed);
    let mut counts = Counts::default();
    let mut failure: Option<Failure> = None;
    let mut checkpoints: Vec<Checkpoint> = Vec::new();
    let start = Instant::now();
    let quiet_hook = std::panic::take_hook();
    // Panics are caught and counted per step; their message goes into the report.
    let panic_message = Arc::new(Mutex::new(String::new()));
    let pm = panic_message.clone();
    std::panic::set_hook(Box::new(move |info| {
        if let Ok(mut m) = pm.lock() {
            *m = format!("{info}");
        }
    }));
    // Whether the renderer is still the one made for the starting scene: returns to the start
    // then keep it (growth while one renderer lives is what a long session meets).
    let mut on_main = true;
    let mut step = 0u64;
    while step < args.frames {
        step += 1;
        let checkpoint = step.is_multiple_of(args.check_every);
        let errors_before = errors.lock().map(|g| g.count).unwrap_or(0);
        let result = catch_unwind(AssertUnwindSafe(|| {
            let outcome = if checkpoint {
                Outcome { action: "return to the starting state".into(), refused: None, wrong: None }
            } else {
                one_step(&mut rng, &ctx, &mut r, &mut scenes, args.size, &args.actions)
            };
            if outcome.action.starts_with("open scene") && outcome.refused.is_none() {
                on_main = outcome.action == format!("open scene {main_name}");
            }
            if checkpoint {
                // The starting scene, settings, size, camera and timeline, rendered twice
                // (history restarts) before counting: on the same renderer while it shows
                // the starting scene, else on a new one.
                if on_main {
                    r.set_settings(base_settings.clone()).map_err(|e| e.to_string())?;
                    r.resize(w, h).map_err(|e| e.to_string())?;
                    r.camera = walk::home_camera(&r);
                    r.clock = gi_render::clock::Clock::new(base_settings.animation.time_step_s as f64);
                    r.reset_history();
                } else {
                    r = fresh(&base_settings).map_err(|e| e.message)?;
                    on_main = true;
                }
                r.render_frame();
            }
            r.render_frame();
            let bad_camera = outcome.action.starts_with("camera jump") && outcome.refused.is_some();
            let camera_wrong = match (bad_camera, r.camera_problem()) {
                (true, None) => Some("a camera that cannot render was used".to_string()),
                (false, Some(p)) if outcome.action.starts_with("camera jump") => {
                    Some(format!("a good camera was refused: {p}"))
                }
                _ => None,
            };
            let hdr = r.readback("final.hdr").map_err(|e| e.to_string())?;
            let nonfinite = hdr.data.iter().filter(|p| p.iter().any(|x| !x.is_finite())).count() as u64;
            Ok::<_, String>((outcome, camera_wrong, nonfinite))
        }));
        let mut action = String::from("?");
        match result {
            Ok(Ok((outcome, camera_wrong, nonfinite))) => {
                action = outcome.action.clone();
                if args.verbose {
                    let note = outcome
                        .refused
                        .as_deref()
                        .map(|m| format!(" → refused: {}", first_line(m)))
                        .unwrap_or_default();
                    println!("step {step}: {}{note}", outcome.action);
                }
                if outcome.refused.is_some() {
                    counts.refused += 1;
                }
                if let Some(w) = outcome.wrong.or(camera_wrong) {
                    counts.wrong += 1;
                    fail(&mut failure, step, &action, w);
                }
                if nonfinite > 0 {
                    counts.nonfinite_frames += 1;
                    counts.nonfinite_pixels += nonfinite;
                    fail(&mut failure, step, &action, format!("{nonfinite} non-finite pixels in final.hdr"));
                }
            }
            Ok(Err(e)) => {
                counts.wrong += 1;
                fail(&mut failure, step, &action, e);
            }
            Err(_) => {
                counts.panics += 1;
                let msg = panic_message.lock().map(|m| m.clone()).unwrap_or_default();
                fail(&mut failure, step, &action, format!("panic: {msg}"));
                // The renderer may be half-updated: start again from the starting state.
                match catch_unwind(AssertUnwindSafe(|| fresh(&base_settings))) {
                    Ok(Ok(fresh_r)) => {
                        r = fresh_r;
                        on_main = true;
                    }
                    _ => break,
                }
            }
        }
        ctx.wait_idle();
        let (count, last) = errors.lock().map(|g| (g.count, g.last.clone())).unwrap_or_default();
        if count > errors_before {
            counts.gpu_errors += count - errors_before;
            let msg = last.unwrap_or_default().replace('\n', " ");
            fail(&mut failure, step, &action, format!("GPU error: {msg}"));
        }
        if let Some(l) = ctx.lost_reason() {
            counts.device_lost = true;
            fail(&mut failure, step, &action, format!("device lost: {l}"));
            break;
        }
        if checkpoint {
            // The reuse cache holds what the last frames used (bounded by construction,
            // `gi_render::counters::reuse`); the checkpoint counts what the renderer keeps.
            gi_render::counters::reuse::clear();
            ctx.wait_idle();
            if let Some(live) = ctx.live_resources() {
                let c = Checkpoint {
                    frame: step,
                    buffers: live.buffers,
                    textures: live.textures,
                    bind_groups: live.bind_groups,
                    pipelines: live.pipelines,
                    allocated_bytes: live.allocated_bytes,
                    heap_mib: crate::heap::live_bytes().map(|b| b as f64 / (1024.0 * 1024.0)),
                    rss_mib: rss_mib(),
                };
                if args.verbose {
                    println!("checkpoint {c:?}");
                }
                checkpoints.push(c);
            }
        }
    }
    std::panic::set_hook(quiet_hook);
    if args.work_dir.is_none() {
        let _ = std::fs::remove_dir_all(&work_dir);
    }
    let memory = memory_verdict(&checkpoints, &rss);
    let ok = counts.panics == 0
        && counts.gpu_errors == 0
        && counts.nonfinite_frames == 0
        && counts.wrong == 0
        && !counts.device_lost
        && memory.flat;
    println!(
        "soak: {} seed {}, {main_name} at {w}×{h}, {step} frames in {:.0} s: {} panics, {} GPU errors, {} non-finite pixels (in {} frames), {} wrong answers, {} inputs refused with a message; {}; {}",
        if ok { "PASS" } else { "FAIL" },
        args.seed,
        start.elapsed().as_secs_f64(),
        counts.panics,
        counts.gpu_errors,
        counts.nonfinite_pixels,
        counts.nonfinite_frames,
        counts.wrong,
        counts.refused,
        memory.text,
        match &failure {
            None => "no failure".to_string(),
            Some(f) => format!(
                "first failure at step {} ({}): {} — replay: gi-lab soak --seed {} --frames {} --verbose",
                f.step,
                f.action,
                first_line(&f.what),
                args.seed,
                f.step
            ),
        }
    );
    if ok { Ok(()) } else { Err(CliError::failure("the soak found failures (see the line above)")) }
}

/// One random step of the walk (without rendering).
fn one_step(
    rng: &mut Rng,
    ctx: &GpuContext,
    r: &mut Renderer,
    scenes: &mut [SceneChoice],
    base: (u32, u32),
    only: &[String],
) -> Outcome {
    let kind = |roll: usize| match roll {
        0..40 => "settings",
        40..52 => "choices",
        52..60 => "resize",
        60..70 | 90..94 => "camera",
        70..74 => "scene",
        74..77 => "shader",
        77..90 => "animation",
        _ => "render",
    };
    let mut roll = rng.below(100);
    while !only.is_empty() && !only.iter().any(|k| k == kind(roll)) {
        roll = rng.below(100);
    }
    match roll {
        0..40 => walk::set_setting(rng, r, false),
        40..52 => walk::set_setting(rng, r, true),
        52..60 => walk::resize(rng, r, base),
        60..70 => walk::camera_jump(rng, r),
        70..74 => {
            let i = rng.below(scenes.len());
            walk::switch_scene(ctx, r, &mut scenes[i])
        }
        74..77 => walk::broken_shader(rng, r),
        77..90 => walk::animation(rng, r),
        90..94 => {
            r.camera = walk::home_camera(r);
            Outcome { action: "camera home".into(), refused: None, wrong: None }
        }
        _ => Outcome { action: "render".into(), refused: None, wrong: None },
    }
}

/// Reports a failure and keeps the first.
fn fail(failure: &mut Option<Failure>, step: u64, action: &str, what: String) {
    eprintln!("soak: step {step} ({action}): {what}");
    failure.get_or_insert(Failure { step, action: action.to_string(), what });
}

fn first_line(s: &str) -> &str {
    s.lines().next().unwrap_or("")
}
