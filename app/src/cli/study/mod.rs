//! `gi-lab study`: scenes × presets × swept settings, each rendered, timed and compared with
//! a path-traced truth per scene, written as a report that answers "which technique for
//! this scene at this budget" (`DIR/index.html` with its images and SVG plots,
//! `results.csv`, `results.json`). `--shard I/N` renders a share of the jobs into
//! `DIR/shard-I/` and `--merge DIR` joins the shards into the same report; `--emit-jobs`
//! writes the Slurm job array or GNU parallel command line that runs the shards
//! (docs/architecture.md, "Studies").
//!
//! The layout: [`jobs`] (the study's canonical spec, its job list and the scripts),
//! [`measure`] (rendering one share of the jobs with the engine of `cli::bench::run`),
//! [`results`] (rows, the derived front and winners, CSV, JSON, the merge), [`page`] and
//! [`svg`] (the report).

pub mod jobs;
pub mod measure;
pub mod page;
pub mod report;
pub mod results;
pub mod svg;

use std::path::{Path, PathBuf};

use clap::Args;

use super::parse_size;
use super::shard::{Shard, parse_shard};
use crate::error::CliError;

#[derive(Args, Debug, Clone)]
pub struct StudyArgs {
    /// A glTF scene (repeatable); the embedded Cornell box when none is given.
    #[arg(long = "scene")]
    pub scenes: Vec<PathBuf>,
    /// Multiply every scene's coordinates by this; 0 reads each scene's unit from its extent.
    #[arg(long, default_value_t = 0.0)]
    pub unit_scale: f32,
    /// A RON preset (repeatable); the shipped technique presets (knecht, nguyen, soler,
    /// gautron, ddgi) when none is given.
    #[arg(long = "preset")]
    pub presets: Vec<PathBuf>,
    /// Override a setting in every preset, e.g. --set direct.pcf_radius=2 (repeatable).
    #[arg(long = "set", value_name = "GROUP.FIELD=VALUE")]
    pub overrides: Vec<String>,
    /// A swept setting as `gi-lab sweep` takes it (`GROUP.FIELD=FROM..TO:STEPS` or
    /// `GROUP.FIELD=A,B`), applied to every preset; repeatable (every combination).
    #[arg(long = "param", value_name = "GROUP.FIELD=FROM..TO:STEPS")]
    pub params: Vec<String>,
    #[arg(long, default_value = "256x256", value_parser = parse_size)]
    pub size: (u32, u32),
    /// Timed frames per job (after 3 warm-up frames), the scene paused at time 0.
    #[arg(long, default_value_t = 10)]
    pub frames: u32,
    /// Frames over which flicker is measured per job (0: skip).
    #[arg(long, default_value_t = 4)]
    pub flicker_frames: u32,
    /// Bounces of the path-traced truth (1: one bounce, as most of the techniques compute).
    #[arg(long, default_value_t = 1)]
    pub bounces: u32,
    /// Samples per pixel of the truth (traced once per scene, cached in `DIR/truth-cache/`
    /// by scene, camera, size, bounces, spp and lighting).
    #[arg(long, default_value_t = 64)]
    pub spp: u32,
    /// The frame budget of the "equal time" winner (ms); the median frame time of the scene's
    /// jobs when omitted.
    #[arg(long)]
    pub budget_ms: Option<f64>,
    /// The error target of the "equal error" winner (mean FLIP); the median FLIP of the
    /// scene's jobs when omitted.
    #[arg(long)]
    pub target_flip: Option<f64>,
    /// Output folder: index.html, results.csv, results.json, img/, plots/ (shards write into
    /// DIR/shard-I/).
    #[arg(long, required_unless_present = "merge")]
    pub out: Option<PathBuf>,
    /// Render only share I of N of the jobs (a deterministic, contiguous split) into
    /// DIR/shard-I/; `--merge DIR` joins the shards.
    #[arg(long, value_parser = parse_shard, value_name = "I/N")]
    pub shard: Option<Shard>,
    /// Join DIR/shard-*/ into DIR's report, CSV and JSON (as an unsharded run writes them).
    #[arg(long, value_name = "DIR", conflicts_with_all = ["shard", "emit_jobs"])]
    pub merge: Option<PathBuf>,
    #[command(flatten)]
    pub emit: crate::cli::emit::EmitArgs,
}

pub fn study(args: &StudyArgs) -> Result<(), CliError> {
    if let Some(dir) = &args.merge {
        return report::merge(dir);
    }
    let Some(out) = args.out.clone() else {
        return Err(CliError::input("--out DIR is required (or --merge DIR)"));
    };
    args.emit.check()?;
    match args.shard {
        // A shard claims its folder before anything else, so that even its bad input is
        // recorded there for the merge to name (crate::cli::shard_status).
        Some(shard) => {
            let claim = crate::cli::shard_status::claim(&out, shard, "shard.json")?;
            claim.finish(run(args, &out, Some(shard)))
        }
        None => run(args, &out, None),
    }
}

/// The study (or its `shard`) into `out`, or the script of `--emit-jobs`.
fn run(args: &StudyArgs, out: &Path, sharded: Option<Shard>) -> Result<(), CliError> {
    let spec = jobs::Spec::from_args(args)?;
    // Everything is checked before anything renders or is written.
    let plan = jobs::Plan::new(&spec)?;
    if args.emit.emit_jobs.is_some() {
        plan.check_scenes(&plan.jobs)?;
        let path = crate::cli::emit::write_script("study", &spec.args(), out, &args.emit)?;
        println!("wrote {} ({} jobs in {} shards)", path.display(), plan.jobs.len(), args.emit.shards);
        return Ok(());
    }
    let shard = sharded.unwrap_or(Shard { index: 1, count: 1 });
    let dir = if sharded.is_some() { shard.dir(out) } else { out.to_path_buf() };
    std::fs::create_dir_all(&dir).map_err(|e| CliError::input(format!("--out {}: {e}", dir.display())))?;
    let part = measure::run(&spec, &plan, shard, out, &dir)?;
    if sharded.is_some() {
        results::write_shard(&dir, &part)?;
        println!(
            "shard {}/{}: {} of {} jobs in {}; join the shards with: gi-lab study --merge {}",
            shard.index,
            shard.count,
            part.rows.len(),
            plan.jobs.len(),
            dir.display(),
            out.display()
        );
        return Ok(());
    }
    let study = results::Study::assemble(vec![part])?;
    report::write_report(out, &study)?;
    Ok(())
}
