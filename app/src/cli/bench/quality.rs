//! `gi-lab bench --suite quality`: the quality table of `gi_render::quality` on any scene.

use super::BenchArgs;
use super::run::one_bounce_truth;
use crate::cli::compare::load_image;
use crate::error::CliError;

/// `gi-lab bench --suite quality`: the quality table of `gi_render::quality` on any scene,
/// against `--reference` or a one-bounce ground truth traced here at `--size` with `--spp`,
/// with each row's frame time and its FLIP at equal time (issue #37 point 5); `--set` lays
/// its values over every row's preset.
pub fn quality(args: &BenchArgs) -> Result<(), CliError> {
    let scene = crate::scene_args::load_scene(&args.scene)?;
    let (truth, against) = match &args.reference {
        Some(reference) => (load_image(reference)?.0, reference.display().to_string()),
        None => {
            if args.spp == 0 {
                return Err(CliError::input("--spp must be at least 1"));
            }
            let settings = crate::scene_args::load_settings(&args.scene)?;
            eprintln!(
                "path-tracing the one-bounce ground truth at {}x{}, {} spp (give --reference to reuse one) …",
                args.size.0, args.size.1, args.spp
            );
            let start = std::time::Instant::now();
            let img = one_bounce_truth(&scene, &settings, args.size, args.spp);
            eprintln!("traced in {:.1} s", start.elapsed().as_secs_f64());
            (img, format!("the path tracer (1 bounce, {} spp, traced here)", args.spp))
        }
    };
    let ctx = gi_render::GpuContext::headless().map_err(|e| CliError::failure(e.to_string()))?;
    let mut rows = gi_render::quality::quality_table_with(
        &ctx,
        &scene,
        &truth,
        args.size,
        gi_render::quality::Timing::EqualTime,
        &args.scene.overrides,
    )
    .map_err(CliError::input)?;
    // The goals were set for the default scene as it ships: elsewhere they mean nothing.
    let default_scene = args.scene.scene.is_none() && args.scene.sky.is_none() && args.scene.overrides.is_empty();
    if !default_scene {
        rows.iter_mut().for_each(|r| r.goal = None);
    }
    if args.json {
        println!("{}", serde_json::to_string_pretty(&rows).map_err(|e| CliError::failure(e.to_string()))?);
    } else {
        let name =
            args.scene.scene.as_ref().map(|p| p.display().to_string()).unwrap_or_else(|| "default Cornell box".into());
        println!(
            "GI Lab bench suite quality — {name} at {}x{}, paused at time 0, mean FLIP (tone-mapped) against {against}; {} ({})\n",
            args.size.0,
            args.size.1,
            ctx.adapter_summary(),
            if gi_render::timing::GpuTimer::timestamps_reliable(&ctx) {
                "GPU timestamps"
            } else {
                "wall clock per pass"
            }
        );
        if !args.scene.overrides.is_empty() {
            println!("every row's preset with --set {}\n", args.scene.overrides.join(" --set "));
        }
        print!("{}", gi_render::quality::format_table(&rows));
        println!(
            "\nframe ms: mean of the passes' times; equal time: the frames each row renders in the default preset's time for 16 frames, and the FLIP they reach"
        );
        if default_scene {
            println!(
                "goals: issue #15's rows 1–4, issue #16's row 6 (below rows 1 and 5), for the default scene at 256x256"
            );
        }
    }
    Ok(())
}
