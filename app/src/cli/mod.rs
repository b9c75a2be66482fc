//! The `gi-lab` command line: the app (default), `render`, `buffers`, `bench`,
//! `settings` and `gen-assets`. Bad arguments or input exit with code 2 and a message that
//! says what is wrong; a missing GPU exits with code 1 and says how to install lavapipe.

pub mod bench;
pub mod buffers;
pub mod compare;
pub mod emit;
pub mod export;
pub mod gen_assets;
pub mod hcb_stats;
pub mod reference;
pub mod render;
pub mod settings;
pub mod shard;
pub mod shard_status;
pub mod soak;
pub mod soak_memory;
pub mod soak_walk;
pub mod study;
pub mod sweep;
pub mod sweep_run;
pub mod upgrade;
pub mod verify;

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use gi_render::{GpuContext, Renderer};

use crate::args::AppArgs;
use crate::error::CliError;
use crate::scene_args::{SceneArgs, load_scene, load_settings};
use bench::BenchArgs;
use compare::CompareArgs;
use export::ExportArgs;
use hcb_stats::HcbStatsArgs;
use reference::ReferenceArgs;
use render::RenderArgs;
use upgrade::UpgradeArgs;

#[derive(Parser, Debug)]
#[command(name = "gi-lab", version, about = "GI Lab: a laboratory for real-time global illumination")]
pub struct Cli {
    #[command(subcommand)]
    pub command: Option<Command>,
    #[command(flatten)]
    pub app: AppArgs,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Render headless and write final.png plus the named buffers (PNG, and EXR for float data).
    Render(RenderArgs),
    /// List the names of the inspectable buffers.
    Buffers(SceneArgs),
    /// Render frames and print per-pass times (GPU timestamps where available).
    Bench(BenchArgs),
    /// List every setting with its unit, range and default.
    Settings,
    /// Compare two images (PNG or EXR): RMSE, relative MSE and mean FLIP.
    Compare(CompareArgs),
    /// Path-trace a ground-truth image on the CPU (writes F, F.direct.exr, F.indirect.exr
    /// and a PNG preview).
    Reference(ReferenceArgs),
    /// Render every combination of swept settings; write sweep.csv (settings, per-pass ms,
    /// FLIP, RMSE, flicker) and pareto.png (quality against time). `--shard I/N` renders a
    /// share, `--merge DIR` joins the shards, `--emit-jobs slurm|parallel` writes the script
    /// that runs them.
    Sweep(sweep::SweepArgs),
    /// Scenes × presets (× swept settings) against a path-traced truth per scene: writes
    /// DIR/index.html (image grids with FLIP maps, tables, time per pass, error against time,
    /// the equal-time and equal-error winners), results.csv and results.json. `--shard I/N`
    /// renders a share, `--merge DIR` joins the shards, `--emit-jobs slurm|parallel` writes
    /// the script that runs them.
    Study(study::StudyArgs),
    /// Export a preset for engines: JSON or RON with schema id and provenance (GI Lab
    /// version, scene, camera, date); see docs/preset-schema.md.
    Export(ExportArgs),
    /// Compare a port's per-pass outputs with a port kit's goldens (docs/port-kit.md): a
    /// table, the first pass that diverges, a non-zero exit beyond --tolerance.
    Verify(verify::VerifyArgs),
    /// Print the hierarchical coherence buffer's samples per level as Table 1 of Nguyen et
    /// al. lays them out (the preset's technique is switched to the HCB).
    HcbStats(HcbStatsArgs),
    /// A seeded random walk over every setting, stage choice, size, camera, scene, shader
    /// reload and animation control, counting panics, GPU errors, non-finite pixels, wrong
    /// answers to bad input and growing memory; one summary line (exit 1 on a failure).
    Soak(soak::SoakArgs),
    /// Rewrite presets of an older version in the current one (the loader's migration),
    /// keeping their leading comment; the old file is kept as `<name>.bak`.
    Upgrade(UpgradeArgs),
    /// Regenerate the embedded default scene (assets/cornell_box.glb).
    GenAssets {
        /// Where to write the .glb.
        #[arg(long, default_value = "assets/cornell_box.glb")]
        out: PathBuf,
        /// Also write the framing test cases (a box room, two rooms, a corridor, a closed
        /// sphere, an object, a floor plan, two cameras) into this folder, each in metres and
        /// in millimetres (`NAME-m.glb`, `NAME-mm.glb`).
        #[arg(long)]
        framing_cases: Option<PathBuf>,
    },
}

/// Parses `WIDTHxHEIGHT`.
pub fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(|| format!("'{s}' is not WIDTHxHEIGHT (e.g. 640x480)"))?;
    let w: u32 = w.trim().parse().map_err(|_| format!("width '{w}' is not a positive whole number"))?;
    let h: u32 = h.trim().parse().map_err(|_| format!("height '{h}' is not a positive whole number"))?;
    if w == 0 || h == 0 {
        return Err(format!("'{s}': width and height must be at least 1"));
    }
    Ok((w, h))
}

pub fn renderer(args: &SceneArgs, size: (u32, u32)) -> Result<Renderer, CliError> {
    let scene = load_scene(args)?;
    let settings = load_settings(args)?;
    let ctx = GpuContext::headless().map_err(|e| CliError::failure(e.to_string()))?;
    Renderer::new(ctx, scene, settings, size.0, size.1).map_err(|e| CliError::input(e.to_string()))
}

/// Runs the command line; returns the process exit code.
pub fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            // clap prints help/version with exit 0 and usage errors with exit 2.
            let _ = e.print();
            return ExitCode::from(e.exit_code().clamp(0, 255) as u8);
        }
    };
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    let result = match &cli.command {
        None => crate::ui::run(cli.app.clone()).map_err(CliError::failure),
        Some(Command::Render(a)) => render::render(a),
        Some(Command::Buffers(a)) => buffers::buffers(a),
        Some(Command::Bench(a)) => bench::bench(a),
        Some(Command::Compare(a)) => compare::compare(a),
        Some(Command::Reference(a)) => reference::reference(a),
        Some(Command::HcbStats(a)) => hcb_stats::hcb_stats(a),
        Some(Command::Sweep(a)) => sweep_run::sweep(a),
        Some(Command::Study(a)) => study::study(a),
        Some(Command::Settings) => {
            settings::settings();
            Ok(())
        }
        Some(Command::Export(a)) => export::export(a),
        Some(Command::Verify(a)) => verify::verify(a),
        Some(Command::Upgrade(a)) => upgrade::upgrade(a),
        Some(Command::Soak(a)) => soak::soak(a),
        Some(Command::GenAssets { out, framing_cases }) => {
            gen_assets::gen_assets(out).and_then(|_| match framing_cases {
                Some(dir) => gen_assets::framing_cases(dir),
                None => Ok(()),
            })
        }
    };
    // A lost device (a driver reset) makes every later GPU call fail with errors that do
    // not say why: the loss is the error, whatever happened after it.
    let result = match (result, gi_render::gpu::device_lost_in_process()) {
        (r, None) => r,
        (Ok(()), Some(why)) | (Err(_), Some(why)) => Err(CliError::failure(format!(
            "the GPU device was lost ({why}); what this command wrote before is complete, the rest was not written. Run it again (a driver reset passes; a device lost again and again needs a driver update)"
        ))),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("gi-lab: error: {}", e.message);
            ExitCode::from(e.code)
        }
    }
}
