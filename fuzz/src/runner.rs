//! The fuzzing loop: corpus, stacked mutations, per-input time cap, caught panics, summary.
//!
//! Each iteration takes a corpus input (the seeds first, each once as it is; then a random
//! one, the large or slow seeds rarely), applies 1–8 stacked mutations and runs the target. Without
//! coverage instrumentation (stable Rust, no sanitizer runtime), the corpus grows by a cheap
//! substitute: a mutant is kept when its outcome *signature* (the error message with its
//! numbers removed, or what was loaded) has not been seen before, since a new message means
//! a new check was reached (a refused mutant only one time in 8: its own mutants mostly fail
//! the same way).
//!
//! Caps: a watchdog thread saves the input and ends the process (status 2) when one input
//! runs longer than the time cap; the memory cap is the counting allocator's
//! ([`crate::alloc`]), active where that allocator is installed. Panics are caught per input
//! with `catch_unwind` (the default hook's output is silenced and its message kept); each
//! distinct panic location saves its first input, and the run goes on.

use std::collections::{HashMap, HashSet};
use std::panic::AssertUnwindSafe;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use crate::alloc;
use crate::rng::Rng;
use crate::seeds::{LARGE, Seed};
use crate::targets::{Outcome, Target};

/// How a run is configured (the CLI's options).
#[derive(Clone, Debug)]
pub struct Config {
    pub target: Target,
    /// Executions, the unmutated seeds included.
    pub iterations: u64,
    /// Seed of the mutation RNG: the same seed gives the same inputs.
    pub seed: u64,
    /// Longest time one input may run.
    pub time_cap: Duration,
    /// Live-heap cap in bytes (enforced only where [`alloc::CountingAlloc`] is the global allocator).
    pub mem_cap: Option<usize>,
    /// Extra seed files (every file in the folder).
    pub corpus_dir: Option<PathBuf>,
    /// Where failing inputs are written.
    pub crash_dir: PathBuf,
    /// Include the large seeds (the real chair and hotel room scenes).
    pub large_seeds: bool,
    /// A seed that runs longer than this is slow: it is mutated rarely (one pick in 256,
    /// with the large seeds), and a mutant that runs longer is not kept.
    pub slow: Duration,
    /// Never mutate slow seeds (the CI tests, whose debug build is ~20× slower).
    pub drop_slow_seeds: bool,
    /// Print a progress line every this often (None: silent).
    pub progress: Option<Duration>,
    /// Count the outcome signatures (what the inputs reached) for [`Summary::signatures`].
    pub stats: bool,
}

impl Config {
    /// The defaults of the CLI for `target`: 10,000 iterations, 2 s and 512 MiB per input.
    pub fn new(target: Target) -> Self {
        Self {
            target,
            iterations: 10_000,
            seed: 1,
            time_cap: Duration::from_secs(2),
            mem_cap: Some(512 << 20),
            corpus_dir: None,
            crash_dir: crate::seeds::project_root().join("fuzz/crashes"),
            large_seeds: true,
            slow: Duration::from_millis(20),
            drop_slow_seeds: false,
            progress: None,
            stats: false,
        }
    }
}

/// One distinct failure: its message, how often it happened and the saved input.
#[derive(Clone, Debug)]
pub struct Failure {
    pub message: String,
    pub count: u64,
    pub saved: Option<PathBuf>,
}

/// What a run did.
#[derive(Clone, Debug)]
pub struct Summary {
    pub target: Target,
    pub executions: u64,
    pub elapsed: Duration,
    pub panics: u64,
    /// Inputs over the time cap (a hang ends the run, so this is 0 in a summary that is printed).
    pub hangs: u64,
    /// Allocations over the memory cap (likewise 0: the allocator ends the run).
    pub over_cap: u64,
    pub accepted: u64,
    pub rejected: u64,
    /// Seeds plus the mutants kept.
    pub corpus: usize,
    /// The largest live heap seen (0 without the counting allocator).
    pub peak_bytes: usize,
    /// The most one input made the heap grow (0 without the counting allocator).
    pub largest_input_bytes: usize,
    /// That input, saved when it grew the heap by more than half the memory cap.
    pub largest_input: Option<PathBuf>,
    /// Distinct panics by location.
    pub failures: Vec<Failure>,
    /// With [`Config::stats`]: how often each outcome signature occurred, most frequent first.
    pub signatures: Vec<(String, u64)>,
}

impl Summary {
    /// Executions per second.
    pub fn rate(&self) -> f64 {
        self.executions as f64 / self.elapsed.as_secs_f64().max(1e-9)
    }

    /// The one-line summary of issue #19.
    pub fn line(&self) -> String {
        format!(
            "target {}: {} executions in {:.1} s ({:.0} execs/s), {} panics, {} hangs, {} over-cap allocations, corpus {} ({} accepted, {} rejected), peak heap {} MiB (one input: +{} MiB)",
            self.target.name(),
            self.executions,
            self.elapsed.as_secs_f64(),
            self.rate(),
            self.panics,
            self.hangs,
            self.over_cap,
            self.corpus,
            self.accepted,
            self.rejected,
            self.peak_bytes >> 20,
            self.largest_input_bytes >> 20
        )
    }
}

thread_local! {
    /// Set while this thread runs a fuzz input: its panics are recorded, not printed.
    static IN_TARGET: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
    /// The message of this thread's last recorded panic.
    static LAST_PANIC: std::cell::RefCell<Option<String>> = const { std::cell::RefCell::new(None) };
}

/// Installs (once) a panic hook that records the message and location of panics raised
/// while an input runs ([`run_one`]) instead of printing them; other panics (a failing test,
/// a bug in the fuzzer) go to the previous hook as usual.
pub fn install_quiet_panic_hook() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if !IN_TARGET.with(std::cell::Cell::get) {
                previous(info);
                return;
            }
            let payload = info.payload();
            let msg = payload
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "(non-string panic payload)".to_string());
            let at = info.location().map_or_else(String::new, |l| format!("{}:{}", l.file(), l.line()));
            LAST_PANIC.with(|l| *l.borrow_mut() = Some(format!("{at}: {msg}")));
        }));
    });
}

/// Writes `input` to `<dir>/<target>-<hash>.bin`.
pub fn save_input(dir: &Path, target: Target, input: &[u8]) -> Option<PathBuf> {
    std::fs::create_dir_all(dir).ok()?;
    let path = dir.join(format!("{}-{:016x}.bin", target.name(), alloc::fnv1a(input)));
    std::fs::write(&path, input).ok()?;
    Some(path)
}

/// The input being run and when it started, shared with the watchdog.
struct Current {
    input: Mutex<Vec<u8>>,
    /// Milliseconds since `epoch` at which the current input started (0: idle).
    started_ms: AtomicU64,
    done: AtomicBool,
}

/// Starts the watchdog: an input running over `cap` is saved and the process exits (status 2).
fn watchdog(current: Arc<Current>, epoch: Instant, cap: Duration, dir: PathBuf, target: Target) {
    let tick = (cap / 8).clamp(Duration::from_millis(5), Duration::from_millis(100));
    std::thread::spawn(move || {
        while !current.done.load(Ordering::Relaxed) {
            std::thread::sleep(tick);
            let started = current.started_ms.load(Ordering::Relaxed);
            if started == 0 {
                continue;
            }
            let now = epoch.elapsed().as_millis() as u64;
            if now.saturating_sub(started) > cap.as_millis() as u64 {
                let input = current.input.lock().map(|i| i.clone()).unwrap_or_default();
                let saved = save_input(&dir, target, &input);
                eprintln!(
                    "\nHANG: one {} input ran for more than {} ms (the time cap); saved to {}",
                    target.name(),
                    cap.as_millis(),
                    saved.map_or_else(|| "(could not save)".to_string(), |p| p.display().to_string())
                );
                std::process::exit(2);
            }
        }
    });
}

/// A path-independent description of an outcome: the message with digits removed.
fn signature(outcome: Outcome, message: &str) -> String {
    let mut s: String = message.chars().filter(|c| !c.is_ascii_digit()).take(96).collect();
    s.insert_str(0, if outcome == Outcome::Accepted { "ok " } else { "err " });
    s
}

/// The corpus: the seeds and the mutants that reached a new outcome.
struct Corpus {
    small: Vec<Vec<u8>>,
    large: Vec<Vec<u8>>,
    kept: Vec<Vec<u8>>,
    kept_bytes: usize,
}

/// At most this many bytes of mutants are kept (the memory cap counts them too).
const MAX_KEPT_BYTES: usize = 32 << 20;
/// Mutants larger than this are not kept (they would slow every later pick of them).
const MAX_KEPT_INPUT: usize = 64 << 10;
/// At most this many mutants are kept (later ones replace random earlier ones).
const MAX_KEPT: usize = 4096;

impl Corpus {
    /// A large or slow seed 1 time in 256, otherwise a small seed or a kept mutant (even odds).
    fn pick<'a>(&'a self, rng: &mut Rng) -> &'a [u8] {
        let pool = if !self.large.is_empty() && (rng.one_in(256) || self.small.len() + self.kept.len() == 0) {
            &self.large
        } else if self.kept.is_empty() || (!self.small.is_empty() && rng.one_in(2)) {
            &self.small
        } else {
            &self.kept
        };
        pool.get(rng.below(pool.len())).map_or(&[], Vec::as_slice)
    }

    fn keep(&mut self, rng: &mut Rng, input: &[u8]) {
        if input.len() > MAX_KEPT_INPUT {
            return;
        }
        if self.kept_bytes + input.len() > MAX_KEPT_BYTES || self.kept.len() >= MAX_KEPT {
            // Full: replace a random mutant instead.
            let i = rng.below(self.kept.len());
            if let Some(slot) = self.kept.get_mut(i) {
                self.kept_bytes = self.kept_bytes.saturating_sub(slot.len()) + input.len();
                *slot = input.to_vec();
            }
            return;
        }
        self.kept_bytes += input.len();
        self.kept.push(input.to_vec());
    }

    fn len(&self) -> usize {
        self.small.len() + self.large.len() + self.kept.len()
    }
}

/// Reads every file of `dir` as a seed.
fn corpus_dir_seeds(dir: &Path) -> Vec<Seed> {
    let mut paths: Vec<PathBuf> = std::fs::read_dir(dir)
        .map(|d| d.filter_map(Result::ok).map(|e| e.path()).filter(|p| p.is_file()).collect())
        .unwrap_or_default();
    paths.sort();
    paths.into_iter().filter_map(|p| Some(Seed::new(p.display().to_string(), std::fs::read(&p).ok()?))).collect()
}

/// Runs one input with the panic caught; returns the outcome and its description, or the
/// panic's location and message. Call [`install_quiet_panic_hook`] first to keep panics quiet.
pub fn run_one(target: Target, input: &[u8]) -> Result<(Outcome, String), String> {
    IN_TARGET.with(|f| f.set(true));
    let result = std::panic::catch_unwind(AssertUnwindSafe(|| target.execute_with_message(input)));
    IN_TARGET.with(|f| f.set(false));
    result.map_err(|_| {
        LAST_PANIC.with(|l| l.borrow_mut().take()).unwrap_or_else(|| "panic without a message".to_string())
    })
}

/// Fuzzes `cfg.target` for `cfg.iterations` executions.
pub fn run(cfg: &Config) -> Summary {
    install_quiet_panic_hook();
    let target = cfg.target;
    let mut seeds = target.seeds(cfg.large_seeds);
    // The inputs of past crashes are seeds too: mutations around them look for their relatives.
    seeds.extend(corpus_dir_seeds(&crate::seeds::project_root().join("fuzz/regressions").join(target.name())));
    if let Some(dir) = &cfg.corpus_dir {
        seeds.extend(corpus_dir_seeds(dir));
    }
    let dictionary = match target {
        Target::Gltf => crate::gltf_mutate::DICTIONARY.to_vec(),
        Target::Preset | Target::Set => crate::seeds::settings_dictionary(),
    };
    // Filled as the seeds run (each once, first): large or slow seeds go to the rare pool.
    let mut corpus = Corpus { small: Vec::new(), large: Vec::new(), kept: Vec::new(), kept_bytes: 0 };
    let epoch = Instant::now();
    let current = Arc::new(Current {
        input: Mutex::new(Vec::new()),
        started_ms: AtomicU64::new(0),
        done: AtomicBool::new(false),
    });
    watchdog(Arc::clone(&current), epoch, cfg.time_cap, cfg.crash_dir.clone(), target);
    if cfg.mem_cap.is_some() {
        let _ = std::fs::create_dir_all(&cfg.crash_dir);
        alloc::set_crash_prefix(cfg.crash_dir.join(format!("{}-", target.name())).display().to_string());
    }
    alloc::reset_peak();
    alloc::set_cap(cfg.mem_cap);

    let mut rng = Rng::new(cfg.seed);
    let mut seen: HashSet<String> = HashSet::new();
    let mut counts: HashMap<String, u64> = HashMap::new();
    let mut failures: HashMap<String, Failure> = HashMap::new();
    let (mut panics, mut accepted, mut rejected) = (0u64, 0u64, 0u64);
    let mut last_progress = Instant::now();
    let mut executions = 0;
    let (mut peak, mut largest, mut largest_input) = (alloc::peak(), 0usize, Vec::new());
    for i in 0..cfg.iterations {
        let input: Vec<u8> = match seeds.get(i as usize) {
            Some(seed) => seed.bytes.clone(),
            None => {
                let mut data = corpus.pick(&mut rng).to_vec();
                // 1 mutation half of the time, 2 a quarter, … up to 8: mostly small steps
                // from inputs that work, sometimes big jumps.
                let stack = 1 + (rng.next_u64().trailing_zeros() as usize).min(7);
                for _ in 0..stack {
                    let other = corpus.pick(&mut rng);
                    target.mutate(&mut rng, &mut data, Some(other), &dictionary);
                }
                data
            }
        };
        // The watchdog saves this copy if the input hangs (the allocator reads `input` itself).
        if let Ok(mut slot) = current.input.lock() {
            slot.clear();
            slot.extend_from_slice(&input);
        }
        alloc::set_current_input(&input);
        let live_before = alloc::live();
        alloc::reset_peak();
        current.started_ms.store((epoch.elapsed().as_millis() as u64).max(1), Ordering::Relaxed);
        let started = Instant::now();
        let result = run_one(target, &input);
        let slow = started.elapsed() > cfg.slow;
        current.started_ms.store(0, Ordering::Relaxed);
        alloc::clear_current_input();
        executions += 1;
        let input_peak = alloc::peak();
        peak = peak.max(input_peak);
        if input_peak.saturating_sub(live_before) > largest {
            largest = input_peak - live_before;
            largest_input.clone_from(&input);
        }
        if (i as usize) < seeds.len() {
            if !slow && input.len() < LARGE {
                corpus.small.push(input.clone());
            } else if !(slow && cfg.drop_slow_seeds) {
                corpus.large.push(input.clone());
            }
        }
        match result {
            Ok((outcome, message)) => {
                match outcome {
                    Outcome::Accepted => accepted += 1,
                    Outcome::Rejected => rejected += 1,
                }
                let sig = signature(outcome, &message);
                if cfg.stats {
                    *counts.entry(sig.clone()).or_default() += 1;
                }
                // A refused mutant is kept less often: most of its children fail the same way.
                let worth = !slow && (outcome == Outcome::Accepted || rng.one_in(8));
                if seen.insert(sig) && i as usize >= seeds.len() && worth {
                    corpus.keep(&mut rng, &input);
                }
            }
            Err(message) => {
                panics += 1;
                let location = message.split(": ").next().unwrap_or_default().to_string();
                let f = failures.entry(location).or_insert_with(|| Failure {
                    message: message.clone(),
                    count: 0,
                    saved: save_input(&cfg.crash_dir, target, &input),
                });
                f.count += 1;
                if f.count == 1
                    && let Some(p) = &f.saved
                {
                    eprintln!("PANIC ({}): {message}\n  input saved to {}", target.name(), p.display());
                }
            }
        }
        if let Some(every) = cfg.progress
            && last_progress.elapsed() >= every
        {
            last_progress = Instant::now();
            let secs = epoch.elapsed().as_secs_f64();
            eprintln!(
                "  {} {executions}/{} execs, {:.0}/s, {panics} panics, corpus {}, heap {} MiB (peak {} MiB)",
                target.name(),
                cfg.iterations,
                executions as f64 / secs,
                corpus.len(),
                alloc::live() >> 20,
                peak >> 20
            );
        }
    }
    current.done.store(true, Ordering::Relaxed);
    alloc::set_cap(None);
    let largest_saved = match cfg.mem_cap {
        Some(cap) if largest > cap / 2 => save_input(&cfg.crash_dir, target, &largest_input),
        _ => None,
    };
    let mut failures: Vec<Failure> = failures.into_values().collect();
    failures.sort_by_key(|f| std::cmp::Reverse(f.count));
    let mut signatures: Vec<(String, u64)> = counts.into_iter().collect();
    signatures.sort_by(|a, b| b.1.cmp(&a.1).then_with(|| a.0.cmp(&b.0)));
    Summary {
        target,
        executions,
        elapsed: epoch.elapsed(),
        panics,
        hangs: 0,
        over_cap: 0,
        accepted,
        rejected,
        corpus: corpus.len(),
        peak_bytes: peak,
        largest_input_bytes: largest,
        largest_input: largest_saved,
        failures,
        signatures,
    }
}
