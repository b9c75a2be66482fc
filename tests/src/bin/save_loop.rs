//! `save_loop DIR`: saves a preset, the session and captures into DIR through GI Lab's own
//! saving code, generation after generation, until it is killed (the crash-safety test,
//! `tests/tests/crash_safe.rs`). It starts one past the newest generation found in DIR and
//! prints `start G`, then `saved G` after each complete generation.

use std::io::Write;
use std::path::PathBuf;

use gi_lab_tests::crash_safe;

fn main() {
    let Some(dir) = std::env::args_os().nth(1).map(PathBuf::from) else {
        eprintln!("usage: save_loop DIR");
        std::process::exit(2);
    };
    let fail = |e: String| -> ! {
        eprintln!("save_loop: {e}");
        std::process::exit(1);
    };
    let mut g = crash_safe::next_generation(&dir).unwrap_or_else(|e| fail(e));
    let mut out = std::io::stdout().lock();
    let _ = writeln!(out, "start {g}").and_then(|()| out.flush());
    loop {
        crash_safe::save_generation(&dir, g).unwrap_or_else(|e| fail(e));
        let _ = writeln!(out, "saved {g}").and_then(|()| out.flush());
        g += 1;
    }
}
