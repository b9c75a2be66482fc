//! Crash-safe files (issue #19 point 4): `save_loop` saves a preset, the session and
//! captures through GI Lab's saving code in a loop and is killed (SIGKILL on Unix) at
//! random moments, hundreds of times on the same folder. After every kill each file must
//! load with the lab's loaders and be one complete version (its generation's exact bytes
//! or pixels), the `.bak`s too; no file goes back to an older version, none is older than
//! the last generation the loop reported complete, and the `.bak` is never newer than its
//! file. Temporary files a kill leaves behind are hidden `.tmp` files (which no preset
//! listing shows), and nothing else appears in the folder; the lab's start-up cleaning
//! (`files::remove_stale_temps`) removes them all and nothing else.

use std::collections::BTreeMap;
use std::io::{BufRead, BufReader, Read};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use gi_lab_tests::crash_safe;

/// Kills of the loop (the issue asks for at least 200).
const KILLS: usize = 240;
/// Every this many kills, one run measures how long a generation takes now.
const CALIBRATE_EVERY: usize = 40;

/// xorshift64*: the kill delays, reproducible from the seed.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
}

/// Every file's generation, after checking each is a complete version (panics otherwise).
fn check_files(dir: &std::path::Path, context: &str) -> BTreeMap<String, u64> {
    let mut gens = BTreeMap::new();
    for name in crash_safe::file_names() {
        match crash_safe::generation(dir, &name) {
            Ok(Some(g)) => {
                gens.insert(name, g);
            }
            Ok(None) => {}
            Err(e) => panic!("{context}: {e}"),
        }
    }
    gens
}

#[test]
fn files_survive_sigkill_mid_save() {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("crash_safe");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("test folder");
    let started = Instant::now();
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    // Newest generation of each file seen so far, and the last one the loop reported whole.
    let mut seen: BTreeMap<String, u64> = BTreeMap::new();
    let mut reported: Option<u64> = None;
    let mut saves_per_run = Vec::new();
    let mut killed_before_first = 0;
    let mut killed_mid_generation = 0;
    let mut window = Duration::from_millis(50);
    for kill in 0..KILLS {
        let mut child = Command::new(env!("CARGO_BIN_EXE_save_loop"))
            .arg(&dir)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("start save_loop");
        let mut stdout = BufReader::new(child.stdout.take().expect("stdout"));
        let mut line = String::new();
        stdout.read_line(&mut line).expect("read the start line");
        let mut rest = String::new();
        let delay = if kill % CALIBRATE_EVERY == 0 {
            // Calibration: the time of one generation (20–60 ms in a debug build, more on
            // busy cores) sets the window of the next kills, killed after its second save.
            let mut times = Vec::new();
            while times.len() < 2 && stdout.read_line(&mut rest).is_ok_and(|n| n > 0) {
                times.push(Instant::now());
            }
            if let [a, b] = times[..] {
                window = (b - a).mul_f64(1.5).max(Duration::from_millis(5));
            }
            Duration::ZERO
        } else {
            // A random moment in that window: mostly inside the first generation (which
            // replaces the files of the run before, .bak included), sometimes after it.
            let d = window.mul_f64((rng.next() % 1_000_000) as f64 / 1e6);
            std::thread::sleep(d);
            d
        };
        child.kill().expect("SIGKILL save_loop");
        let status = child.wait().expect("wait for save_loop");
        stdout.read_to_string(&mut rest).expect("read the loop's output");
        let mut err = String::new();
        if let Some(mut e) = child.stderr.take() {
            let _ = e.read_to_string(&mut err);
        }
        let context = format!("kill {kill} after {delay:?} (window {window:?})");
        assert!(err.is_empty() && !status.success(), "{context}: save_loop failed ({status}): {err}");
        // The loop starts one past the newest generation on disk.
        let start: u64 = line
            .strip_prefix("start ")
            .and_then(|s| s.trim().parse().ok())
            .unwrap_or_else(|| panic!("{context}: unexpected first line {line:?}"));
        let newest = seen.values().max().map_or(0, |g| g + 1);
        assert_eq!(start, newest, "{context}: the loop did not start after the newest file");
        let saved: Vec<u64> = rest.lines().filter_map(|l| l.strip_prefix("saved ")?.trim().parse().ok()).collect();
        if saved.is_empty() {
            killed_before_first += 1;
        }
        saves_per_run.push(saved.len());
        if let Some(&last) = saved.last() {
            reported = Some(last);
        }
        // At most the generation being written when the kill came is newer than reported.
        let limit = saved.last().map_or(start, |g| g + 1);
        let gens = check_files(&dir, &context);
        let main: Vec<u64> = gens.iter().filter(|(n, _)| !n.ends_with(".bak")).map(|(_, &g)| g).collect();
        if main.iter().any(|&g| main.first() != Some(&g)) {
            killed_mid_generation += 1;
        }
        for (name, &g) in &gens {
            let before = seen.get(name).copied();
            assert!(before.is_none_or(|b| g >= b), "{context}: {name} went back from {before:?} to {g}");
            assert!(g <= limit, "{context}: {name} has generation {g}, past {limit}");
            if !name.ends_with(".bak") {
                assert!(reported.is_none_or(|r| g >= r), "{context}: {name} ({g}) is older than {reported:?}");
            }
        }
        for base in crash_safe::WITH_BACKUP {
            if let Some(&b) = gens.get(&format!("{base}.bak")) {
                let file = gens.get(*base).copied();
                assert!(file.is_some_and(|f| b <= f), "{context}: {base}.bak ({b}) is newer than {base} ({file:?})");
            }
        }
        if let Some(gone) = seen.keys().find(|n| !gens.contains_key(*n)) {
            panic!("{context}: {gone} disappeared");
        }
        let (_, others) = crash_safe::strays(&dir).expect("list the folder");
        assert!(others.is_empty(), "{context}: unexpected files {others:?}");
        seen = gens;
    }
    let (temps, _) = crash_safe::strays(&dir).expect("list the folder");
    let elapsed = started.elapsed();
    let saves: usize = saves_per_run.iter().sum();
    println!(
        "{KILLS} kills in {elapsed:.1?}: {saves} complete generations, {killed_before_first} runs killed before their \
         first, {killed_mid_generation} kills left files of two generations; newest {reported:?}; {} temporary \
         files left by kills; last kill window {window:?}",
        temps.len()
    );
    // The test means something only if kills came inside generations and some completed.
    assert!(reported.is_some() && killed_mid_generation > 0, "the kills did not spread over the saves");
    for b in crash_safe::WITH_BACKUP {
        assert!(seen.contains_key(&format!("{b}.bak")), "no {b}.bak was written");
    }
    // Every writer is dead: the lab's start-up cleaning removes all they left, and only that.
    let removed = gi_render::files::remove_stale_temps(&dir);
    let (left, _) = crash_safe::strays(&dir).expect("list the folder");
    if cfg!(target_os = "linux") {
        assert!(
            left.is_empty() && removed == temps.len(),
            "{removed} of {} temporary files removed: {left:?}",
            temps.len()
        );
        assert_eq!(check_files(&dir, "after the cleaning").len(), seen.len(), "the cleaning removed a saved file");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
