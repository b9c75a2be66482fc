//! `gi-lab-fuzz`: runs the mutation fuzzer on one target and prints a one-line summary.
//!
//! ```text
//! cargo run --release -p gi-lab-fuzz -- --target gltf|preset|set --iterations N \
//!     [--seed S] [--time-cap-ms MS] [--mem-cap-mb MB] [--corpus DIR]
//! cargo run --release -p gi-lab-fuzz -- --target gltf --replay fuzz/crashes/gltf-….bin
//! ```
//!
//! Exit status: 0 when nothing failed, 1 when inputs panicked (each distinct panic's input is
//! in the crashes folder), 2 when an input ran over the time cap, 3 when an allocation would
//! have passed the memory cap (the input is saved in both cases).

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

use clap::Parser;
use gi_lab_fuzz::alloc::CountingAlloc;
use gi_lab_fuzz::{Config, Target, run};

#[global_allocator]
static ALLOC: CountingAlloc = CountingAlloc;

/// Mutation fuzzer of GI Lab's glTF loader, preset parser and --set parser.
#[derive(Parser, Debug)]
#[command(name = "gi-lab-fuzz", version)]
struct Args {
    /// What to fuzz: gltf (the glTF/GLB loader), preset (the preset parsers) or set (--set).
    #[arg(long, value_parser = ["gltf", "preset", "set"])]
    target: String,
    /// Number of executions (the unmutated seeds included).
    #[arg(long, default_value_t = 10_000)]
    iterations: u64,
    /// Seed of the mutations: the same seed gives the same inputs.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Longest time one input may run, in milliseconds.
    #[arg(long, default_value_t = 2000)]
    time_cap_ms: u64,
    /// Cap on the live heap, in MiB (0: no cap).
    #[arg(long, default_value_t = 512)]
    mem_cap_mb: usize,
    /// A folder of extra seed inputs (every file in it).
    #[arg(long)]
    corpus: Option<PathBuf>,
    /// Where failing inputs are written.
    #[arg(long)]
    crashes: Option<PathBuf>,
    /// Leave out the large seeds (the real chair and hotel room scenes).
    #[arg(long)]
    no_large: bool,
    /// Run these files once each (no mutation) and report what each does.
    #[arg(long, num_args = 1..)]
    replay: Vec<PathBuf>,
    /// Write the target's seed corpus to this folder (one file per seed) and exit.
    #[arg(long)]
    dump_seeds: Option<PathBuf>,
    /// Print the 40 most frequent outcomes (error messages without their numbers) at the end.
    #[arg(long)]
    stats: bool,
    /// Seconds between progress lines on stderr (0: none).
    #[arg(long, default_value_t = 10)]
    progress_s: u64,
}

fn main() -> ExitCode {
    let args = Args::parse();
    let Some(target) = Target::parse(&args.target) else {
        eprintln!("unknown target '{}'", args.target);
        return ExitCode::from(2);
    };
    let mut cfg = Config::new(target);
    cfg.iterations = args.iterations;
    cfg.seed = args.seed;
    cfg.time_cap = Duration::from_millis(args.time_cap_ms.max(1));
    cfg.mem_cap = (args.mem_cap_mb > 0).then(|| args.mem_cap_mb.saturating_mul(1 << 20));
    cfg.corpus_dir = args.corpus;
    if let Some(dir) = args.crashes {
        cfg.crash_dir = dir;
    }
    cfg.large_seeds = !args.no_large;
    cfg.progress = (args.progress_s > 0).then(|| Duration::from_secs(args.progress_s));
    cfg.stats = args.stats;
    if let Some(dir) = &args.dump_seeds {
        return dump_seeds(target, dir, cfg.large_seeds);
    }
    if !args.replay.is_empty() {
        return replay(target, &args.replay, &cfg);
    }
    let summary = run(&cfg);
    println!("{}", summary.line());
    if let Some(p) = &summary.largest_input {
        println!("  the input that grew the heap most (over half the cap) is saved as {}", p.display());
    }
    for (sig, n) in summary.signatures.iter().take(40) {
        println!("  {n:>9}  {sig}");
    }
    for f in &summary.failures {
        println!(
            "  {} × {}\n    input: {}",
            f.count,
            f.message,
            f.saved.as_ref().map_or_else(|| "(not saved)".to_string(), |p| p.display().to_string())
        );
    }
    if summary.panics > 0 { ExitCode::from(1) } else { ExitCode::SUCCESS }
}

/// Runs each file once under the caps and prints its outcome.
fn replay(target: Target, files: &[PathBuf], cfg: &Config) -> ExitCode {
    gi_lab_fuzz::runner::install_quiet_panic_hook();
    gi_lab_fuzz::alloc::set_cap(cfg.mem_cap);
    let mut failed = false;
    for f in files {
        let bytes = match std::fs::read(f) {
            Ok(b) => b,
            Err(e) => {
                eprintln!("{}: {e}", f.display());
                failed = true;
                continue;
            }
        };
        gi_lab_fuzz::alloc::reset_peak();
        let start = std::time::Instant::now();
        gi_lab_fuzz::alloc::set_current_input(&bytes);
        let result = gi_lab_fuzz::runner::run_one(target, &bytes);
        gi_lab_fuzz::alloc::clear_current_input();
        let ms = start.elapsed().as_secs_f64() * 1e3;
        let peak = gi_lab_fuzz::alloc::peak() >> 20;
        match result {
            Ok((outcome, message)) => {
                let short: String = message.chars().take(200).collect();
                println!("{}: {outcome:?} in {ms:.1} ms, peak heap {peak} MiB: {short}", f.display());
            }
            Err(panic) => {
                failed = true;
                println!("{}: PANIC in {ms:.1} ms: {panic}", f.display());
            }
        }
    }
    if failed { ExitCode::from(1) } else { ExitCode::SUCCESS }
}

/// Writes the seeds of `target` to `dir`, one file each, named after the seed.
fn dump_seeds(target: Target, dir: &std::path::Path, large: bool) -> ExitCode {
    if let Err(e) = std::fs::create_dir_all(dir) {
        eprintln!("{}: {e}", dir.display());
        return ExitCode::from(1);
    }
    for (i, seed) in target.seeds(large).iter().enumerate() {
        let name: String =
            seed.name.chars().map(|c| if c.is_ascii_alphanumeric() || ".-_".contains(c) { c } else { '_' }).collect();
        let path = dir.join(format!("{i:03}-{name}"));
        if let Err(e) = std::fs::write(&path, &seed.bytes) {
            eprintln!("{}: {e}", path.display());
            return ExitCode::from(1);
        }
    }
    println!("wrote {} seeds to {}", target.seeds(large).len(), dir.display());
    ExitCode::SUCCESS
}
