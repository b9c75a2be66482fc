//! `gi-lab bench`: per-pass times of rendered frames, with flicker, afterglow and quality
//! against a reference; `--suite` runs one suite.
//!
//! The folder is one way round: [`run`] is the measurement engine (`bench_run`, the
//! report, the flicker, afterglow and quality measurements, the one-bounce truth); each
//! suite has its own file and uses the engine; this file parses the arguments and picks the
//! suite. `gi-lab study` and `gi-lab sweep` use the engine the same way. Nothing in `run`
//! reaches a suite or this file.

pub mod gautron;
pub mod gautron_cold;
pub mod gautron_cpu;
pub mod knecht;
pub mod nguyen;
pub mod quality;
pub mod rays;
pub mod run;
pub mod scenes;
pub mod soler;

use std::path::PathBuf;

use super::compare::load_image;
use super::{parse_size, renderer};
use crate::error::CliError;
use crate::scene_args::SceneArgs;
use clap::Args;
use run::{bench_run, format_bench_table, measure_afterglow, measure_flicker, quality_against, window_frames};

#[derive(Args, Debug)]
pub struct BenchArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    #[arg(long, default_value = "1280x720", value_parser = parse_size)]
    pub size: (u32, u32),
    /// Measured frames (after 3 warm-up frames).
    #[arg(long, default_value_t = 30)]
    pub frames: u32,
    /// Frames of the paused scene over which temporal flicker is measured (0: skip).
    #[arg(long, default_value_t = 8)]
    pub flicker_frames: u32,
    /// Frames over which the afterglow of a sudden light change is measured (0: skip).
    #[arg(long, default_value_t = 12)]
    pub afterglow_frames: u32,
    /// A ground-truth EXR of the same scene, camera and size at animation time 0 (`gi-lab
    /// reference`): adds FLIP and RMSE of final.hdr at time 0 against it.
    #[arg(long)]
    pub reference: Option<PathBuf>,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Hold the animation at its start while measuring: the still view a lighting artist
    /// tunes, where the light-space passes are kept from frame to frame (issue #53). By
    /// default the scene's animation plays.
    #[arg(long)]
    pub paused: bool,
    /// Redo every pass every frame, as before issue #53 (`Renderer::reuse_unchanged` off):
    /// the same images, for a before/after comparison with one binary.
    #[arg(long)]
    pub no_reuse: bool,
    /// Samples per pixel of the one-bounce ground truth that `--suite quality` traces when no
    /// --reference is given.
    #[arg(long, default_value_t = 256)]
    pub spp: u32,
    /// Run a suite of rows instead of one configuration: `knecht` reproduces the shape of
    /// `knecht`: Knecht's Tables 5.1–5.3 (frame time against VPL count and ISM size, the
    /// temporal coherence overhead, multi-bounce against IRSM); `nguyen`: the HCB against
    /// gathering at every pixel at 1024 VPLs, with the samples' share of the pixels. Both
    /// start from --preset. `quality`: on any --scene, mean FLIP of the shipped technique
    /// presets against --reference (a path-traced image of one bounce at --size, `gi-lab
    /// reference --bounces 1`; traced here with --spp when not given), each row's frame time
    /// and the FLIP it reaches within the default preset's time (equal time), and the HCB
    /// against the diffuse-only gather at every pixel.
    /// `soler`: Soler et al.'s Fig. 9 (four parameter sets with and without visibility, per
    /// part; run it at --size 1280x720).
    /// `gautron`: irradiance cache splatting from a cold cache at five accuracies against a
    /// hemisphere at every pixel (records, time per record, cold and warm frames, FLIP, the
    /// speedup; run it at --size 64x64; --reference: the one-bounce truth, else traced), then
    /// the text's comparison: a CPU irradiance cache (ray-traced hemispheres, octree lookups)
    /// against the GPU cache at four accuracies, at equal FLIP and over a short camera walk.
    /// `scenes`: every scene below --scenes-dir (default assets/; triangles, lights, emitters, load
    /// time, the frame time of each technique preset; run it at --size 256x256).
    /// `rays`: the default scene and every scene below --scenes-dir: the GPU ray caster against
    /// the CPU's traversal on the same rays (the camera's at --size and a bounce from each
    /// hit), the GPU path tracer against the CPU's (one bounce, --size, --spp).
    #[arg(long, value_enum)]
    pub suite: Option<BenchSuite>,
    /// The scenes of `--suite scenes` (every .gltf/.glb below it; by default the project's
    /// own `assets/`, which holds the real scenes of `assets/scenes/`).
    #[arg(long, default_value = "assets")]
    pub scenes_dir: PathBuf,
}

/// Benchmark suites of `gi-lab bench --suite`.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum BenchSuite {
    Knecht,
    Nguyen,
    Quality,
    Soler,
    Gautron,
    Scenes,
    Rays,
}

pub(crate) fn bench(args: &BenchArgs) -> Result<(), CliError> {
    if args.frames == 0 {
        return Err(CliError::input("--frames must be at least 1"));
    }
    if let Some(BenchSuite::Quality) = args.suite {
        return quality::quality(args);
    }
    if let Some(BenchSuite::Rays) = args.suite {
        let rows = rays::rays_suite(&args.scenes_dir, args.size, args.spp)?;
        if args.json {
            println!("{}", serde_json::to_string_pretty(&rows).map_err(|e| CliError::failure(e.to_string()))?);
        } else {
            let ctx = gi_render::GpuContext::headless().map_err(|e| CliError::failure(e.to_string()))?;
            print!("{}", rays::format(&rows, &ctx.adapter_summary(), args.size, args.spp));
        }
        return Ok(());
    }
    if let Some(BenchSuite::Scenes) = args.suite {
        let rows = scenes::scenes(&args.scenes_dir, args.size, args.frames, &args.scene.overrides)?;
        if args.json {
            println!("{}", serde_json::to_string_pretty(&rows).map_err(|e| CliError::failure(e.to_string()))?);
        } else {
            print!("{}", scenes::format(&rows, args.size, args.frames, &args.scene.overrides));
        }
        return Ok(());
    }
    let mut r = renderer(&args.scene, args.size)?;
    if !gi_render::timing::GpuTimer::timestamps_reliable(&r.ctx) {
        // A software device's timestamps land in the wrong passes: time each pass by the
        // wall clock instead (each scope is submitted and awaited on its own).
        r.set_timing_source(gi_render::timing::TimingSource::CpuWallClock);
    }
    let name =
        args.scene.scene.as_ref().map(|p| p.display().to_string()).unwrap_or_else(|| "default Cornell box".into());
    if let Some(BenchSuite::Knecht) = args.suite {
        let report = knecht::knecht(&mut r, args.frames, &name)?;
        if args.json {
            println!("{}", serde_json::to_string_pretty(&report).map_err(|e| CliError::failure(e.to_string()))?);
        } else {
            print!("{}", knecht::format(&report));
        }
        return Ok(());
    }
    if let Some(BenchSuite::Soler) = args.suite {
        let report = soler::soler(&mut r, args.frames)?;
        if args.json {
            println!("{}", serde_json::to_string_pretty(&report).map_err(|e| CliError::failure(e.to_string()))?);
        } else {
            print!("{}", soler::format(&report));
        }
        return Ok(());
    }
    if let Some(BenchSuite::Gautron) = args.suite {
        let truth = match &args.reference {
            Some(p) => Some((load_image(p)?.0, p.display().to_string())),
            None => None,
        };
        let report = gautron::gautron(&mut r, truth)?;
        if args.json {
            println!("{}", serde_json::to_string_pretty(&report).map_err(|e| CliError::failure(e.to_string()))?);
        } else {
            print!("{}", gautron::format(&report));
        }
        return Ok(());
    }
    if let Some(BenchSuite::Nguyen) = args.suite {
        let report = nguyen::nguyen(&mut r, args.frames, &name)?;
        if args.json {
            println!("{}", serde_json::to_string_pretty(&report).map_err(|e| CliError::failure(e.to_string()))?);
        } else {
            print!("{}", nguyen::format_nguyen(&report));
        }
        return Ok(());
    }
    if args.paused {
        r.clock.playing = false;
        r.clock.anim_frame = 0;
    }
    r.reuse_unchanged = !args.no_reuse;
    let mut report = bench_run(&mut r, args.frames, &name);
    report.window_frame_ms = Some(window_frames(&mut r, args.frames));
    if args.flicker_frames == 1 {
        return Err(CliError::input("--flicker-frames must be 0 or at least 2"));
    }
    if args.flicker_frames >= 2 {
        report.flicker = Some(measure_flicker(&mut r, args.flicker_frames)?);
    }
    if args.afterglow_frames > 0 && args.afterglow_frames < 4 {
        return Err(CliError::input("--afterglow-frames must be 0 or at least 4"));
    }
    if args.afterglow_frames >= 4 {
        report.afterglow_frames = measure_afterglow(&mut r, args.afterglow_frames)?;
    }
    if let Some(reference) = &args.reference {
        let (flip, rmse) = quality_against(&mut r, reference)?;
        report.flip = Some(flip);
        report.rmse = Some(rmse);
    }
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report).map_err(|e| CliError::failure(e.to_string()))?);
    } else {
        print!("{}", format_bench_table(&report));
    }
    Ok(())
}
