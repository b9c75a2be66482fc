//! Who writes a shard and how it ended (`DIR/shard-I/status.json`), so that two runs never
//! write one shard at once and `--merge` says of each shard it lacks whether it still runs,
//! failed (and why) or never started (docs/cli.md, "Scaling out").
//!
//! A shard claims its folder before it checks anything: it refuses when another live run (a
//! Slurm job still in the queue, or a process on this host) holds it, removes the previous
//! run's result so that a merge never joins it with the new images, and records `running`;
//! it ends as `done` or `failed` with the error. A merge joins only complete sets.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::shard::Shard;
use crate::error::CliError;

/// The status file of a shard's folder.
pub const STATUS_FILE: &str = "status.json";

/// The number of shards `--emit-jobs` planned (`OUT/shards.planned`): how many a merge expects
/// before any has started.
pub const PLANNED_FILE: &str = "shards.planned";

/// Who writes a shard.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Writer {
    /// The Slurm job (`ARRAY_TASK`, e.g. `12_3`, or a plain job id) when it runs under Slurm.
    pub job: Option<String>,
    pub host: String,
    pub pid: u32,
}

fn this_host() -> String {
    std::fs::read_to_string("/proc/sys/kernel/hostname")
        .ok()
        .or_else(|| std::env::var("HOSTNAME").ok())
        .map(|h| h.trim().to_string())
        .filter(|h| !h.is_empty())
        .unwrap_or_else(|| "an unnamed host".into())
}

impl Writer {
    /// This process.
    pub fn this() -> Self {
        let var = |n: &str| std::env::var(n).ok().filter(|v| !v.is_empty());
        let job = match (var("SLURM_ARRAY_JOB_ID"), var("SLURM_ARRAY_TASK_ID")) {
            (Some(a), Some(t)) => Some(format!("{a}_{t}")),
            _ => var("SLURM_JOB_ID"),
        };
        Self { job, host: this_host(), pid: std::process::id() }
    }

    /// "Slurm job 12_3 on host n1 (pid 77)" or "pid 77 on host n1".
    pub fn describe(&self) -> String {
        match &self.job {
            Some(j) => format!("Slurm job {j} on host {} (pid {})", self.host, self.pid),
            None => format!("pid {} on host {}", self.pid, self.host),
        }
    }

    /// Whether this writer still runs, where that can be told: a process of this host by its
    /// pid, a Slurm job by `squeue`. None: unknown (another host, no `squeue`).
    fn alive(&self) -> Option<bool> {
        if self.host == this_host() {
            return Some(Path::new(&format!("/proc/{}", self.pid)).exists());
        }
        let job = self.job.as_ref()?;
        let o = std::process::Command::new("squeue").args(["-h", "-o", "%T", "-j", job]).output().ok()?;
        let states = String::from_utf8_lossy(&o.stdout).trim().to_string();
        // `squeue -j` fails for a job the controller has forgotten: it has long ended.
        Some(o.status.success() && !states.is_empty() && !states.contains("COMPLET"))
    }
}

/// How a shard's run stands.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum State {
    Running,
    Done,
    Failed,
}

/// `DIR/shard-I/status.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Status {
    pub state: State,
    pub shard: Shard,
    pub writer: Writer,
    /// Seconds since the Unix epoch.
    pub started: u64,
    pub ended: Option<u64>,
    /// Why it failed.
    pub error: Option<String>,
}

fn now() -> u64 {
    std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map(|d| d.as_secs()).unwrap_or(0)
}

fn read_status(shard_dir: &Path) -> Option<Status> {
    serde_json::from_str(&std::fs::read_to_string(shard_dir.join(STATUS_FILE)).ok()?).ok()
}

fn write_status(shard_dir: &Path, s: &Status) -> Result<(), CliError> {
    let path = shard_dir.join(STATUS_FILE);
    let text = serde_json::to_string_pretty(s).map_err(|e| CliError::failure(e.to_string()))?;
    gi_render::files::write_atomic_bytes(&path, text.as_bytes(), gi_render::files::Backup::Skip)
        .map_err(|e| CliError::failure(format!("{}: {e}", path.display())))
}

/// A shard's folder, held by this process until [`Claim::finish`].
pub struct Claim {
    dir: PathBuf,
    status: Status,
}

/// Claims `OUT/shard-I/` for this process (see the module's comment); `result` is the file a
/// finished shard writes there (`shard.json`, `sweep.json`).
pub fn claim(out: &Path, shard: Shard, result: &str) -> Result<Claim, CliError> {
    let dir = shard.dir(out);
    let me = Writer::this();
    if let Some(old) = read_status(&dir).filter(|s| s.state == State::Running) {
        let same_job = old.writer.job.is_some() && old.writer.job == me.job;
        if !same_job && old.writer != me && old.writer.alive() != Some(false) {
            let ago = now().saturating_sub(old.started);
            let cancel = old.writer.job.as_ref().map(|j| format!(" (scancel {j})")).unwrap_or_default();
            return Err(CliError::input(format!(
                "shard {}/{} of {} is already being written by {}, started {ago} s ago; this run ({}) \
                 would write it twice. Wait for it to end or cancel it{cancel}; if it is gone, remove {}",
                shard.index,
                shard.count,
                out.display(),
                old.writer.describe(),
                me.describe(),
                dir.join(STATUS_FILE).display()
            )));
        }
    }
    std::fs::create_dir_all(&dir).map_err(|e| CliError::input(format!("--out {}: {e}", dir.display())))?;
    let stale = dir.join(result);
    if stale.exists() {
        std::fs::remove_file(&stale).map_err(|e| CliError::failure(format!("{}: {e}", stale.display())))?;
    }
    let status = Status { state: State::Running, shard, writer: me, started: now(), ended: None, error: None };
    write_status(&dir, &status)?;
    Ok(Claim { dir, status })
}

impl Claim {
    /// Records how the shard ended and gives `outcome` back.
    pub fn finish(mut self, outcome: Result<(), CliError>) -> Result<(), CliError> {
        self.status.ended = Some(now());
        match &outcome {
            Ok(()) => self.status.state = State::Done,
            Err(e) => {
                self.status.state = State::Failed;
                self.status.error = Some(e.message.clone());
            }
        }
        let written = write_status(&self.dir, &self.status);
        outcome.and(written)
    }
}

/// Why shard `index` of `count` below `out` is not there to merge, in words.
fn why_missing(out: &Path, index: u32, count: u32) -> String {
    let dir = Shard { index, count }.dir(out);
    let log = out.join("logs").join(format!("shard-{index}.log"));
    let log = if log.is_file() { format!("; its log: {}", log.display()) } else { String::new() };
    let head = format!("shard {index}/{count}");
    let Some(s) = read_status(&dir) else {
        return if dir.is_dir() {
            format!("{head} has no results in {}{log}", dir.display())
        } else {
            format!("{head} has not run (no {}){log}", dir.display())
        };
    };
    match s.state {
        State::Running => format!(
            "{head} is still running ({}, started {} s ago): merge when it has ended{log}",
            s.writer.describe(),
            now().saturating_sub(s.started)
        ),
        State::Failed => {
            format!(
                "{head} failed ({}): {}{log}",
                s.writer.describe(),
                s.error.as_deref().unwrap_or("no reason recorded")
            )
        }
        State::Done => {
            format!("{head} ended ({}) but its results are gone from {}", s.writer.describe(), dir.display())
        }
    }
}

/// The shards a merge of `out` needs, checked: `found` are the results read (each with its
/// folder), which must be exactly shards 1..=N of one N, each once. Returns N; else a message
/// that names each missing shard and why it is missing (running, failed, never run).
pub fn check_complete(out: &Path, found: &[(PathBuf, Shard)], result: &str) -> Result<u32, String> {
    let mut statuses: Vec<Status> = Vec::new();
    if let Ok(entries) = std::fs::read_dir(out) {
        for e in entries.flatten() {
            if e.file_name().to_string_lossy().starts_with("shard-")
                && let Some(s) = read_status(&e.path())
            {
                statuses.push(s);
            }
        }
    }
    let planned: Option<u32> =
        std::fs::read_to_string(out.join(PLANNED_FILE)).ok().and_then(|t| t.trim().parse().ok()).filter(|n| *n > 0);
    let first = found.first().map(|(_, s)| s.count).or_else(|| statuses.first().map(|s| s.shard.count));
    let Some(n) = first.or(planned) else {
        return Err(format!(
            "--merge {}: no shard-I/{result} below it (run the shards with --out {0} --shard I/N first)",
            out.display()
        ));
    };
    let counts = found.iter().map(|(_, s)| s.count).chain(statuses.iter().map(|s| s.shard.count));
    if let Some(other) = counts.into_iter().find(|c| *c != n) {
        return Err(format!("--merge {}: shards of {n} and of {other} are mixed", out.display()));
    }
    for (i, (dir, s)) in found.iter().enumerate() {
        if let Some((twin, _)) = found[..i].iter().find(|(_, t)| t.index == s.index) {
            return Err(format!(
                "--merge {}: shard {}/{n} is written twice, in {} and in {}: remove the one that is not this run's, \
                 then merge again (nothing was written)",
                out.display(),
                s.index,
                twin.display(),
                dir.display()
            ));
        }
    }
    let missing: Vec<String> = (1..=n)
        .filter(|i| !found.iter().any(|(_, s)| s.index == *i))
        .map(|i| format!("  {}", why_missing(out, i, n)))
        .collect();
    if !missing.is_empty() {
        return Err(format!(
            "--merge {}: {} of {n} shards are not there, so nothing was written:\n{}\nRun them (--shard I/{n}), then merge again",
            out.display(),
            missing.len(),
            missing.join("\n")
        ));
    }
    Ok(n)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("gi-lab-shard-status-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    fn other(pid: u32, job: &str) -> Writer {
        Writer { job: Some(job.into()), host: this_host(), pid }
    }

    fn running(out: &Path, shard: Shard, w: Writer) {
        let dir = shard.dir(out);
        std::fs::create_dir_all(&dir).unwrap();
        let s = Status { state: State::Running, shard, writer: w, started: now(), ended: None, error: None };
        write_status(&dir, &s).unwrap();
    }

    #[test]
    fn a_shard_held_by_a_live_run_is_refused_and_a_dead_ones_is_taken_over() {
        let out = temp("claim");
        let shard = Shard { index: 2, count: 3 };
        // A live process of this host (ours, under another job name) holds the shard.
        let mut live = std::process::Command::new("sleep").arg("30").spawn().unwrap();
        running(&out, shard, other(live.id(), "41_2"));
        let e = claim(&out, shard, "shard.json").err().expect("refused");
        assert!(e.message.contains("shard 2/3") && e.message.contains("Slurm job 41_2"), "{}", e.message);
        assert!(e.message.contains("scancel 41_2"), "{}", e.message);
        let _ = live.kill();
        let _ = live.wait();
        // Its process has gone: the claim is stale, this run takes the shard and clears the old result.
        std::fs::write(shard.dir(&out).join("shard.json"), "{}").unwrap();
        let c = claim(&out, shard, "shard.json").expect("taken over");
        assert!(!shard.dir(&out).join("shard.json").exists(), "the old result is removed");
        assert_eq!(read_status(&shard.dir(&out)).unwrap().state, State::Running);
        let r = c.finish(Err(CliError::input("--scene b.glb: no such file")));
        assert!(r.is_err());
        let s = read_status(&shard.dir(&out)).unwrap();
        assert_eq!((s.state, s.error.as_deref()), (State::Failed, Some("--scene b.glb: no such file")));
        let _ = std::fs::remove_dir_all(&out);
    }

    #[test]
    fn a_merge_names_each_missing_shard_and_why_and_refuses_twins() {
        let out = temp("merge");
        let s = |index| Shard { index, count: 4 };
        // Shard 1 finished; shard 2 runs; shard 3 failed; shard 4 never ran.
        let found = vec![(s(1).dir(&out), s(1))];
        let me = std::process::id();
        running(&out, s(2), other(me, "7_2"));
        running(&out, s(3), other(me, "7_3"));
        let c = Claim { dir: s(3).dir(&out), status: read_status(&s(3).dir(&out)).unwrap() };
        let _ = c.finish(Err(CliError::input("--scene /x/b.glb: No such file or directory")));
        let e = check_complete(&out, &found, "shard.json").unwrap_err();
        assert!(e.contains("3 of 4 shards are not there, so nothing was written"), "{e}");
        assert!(e.contains("shard 2/4 is still running (Slurm job 7_2"), "{e}");
        assert!(e.contains("shard 3/4 failed (Slurm job 7_3") && e.contains("b.glb: No such file"), "{e}");
        assert!(e.contains("shard 4/4 has not run"), "{e}");
        // One shard's results in two folders.
        let twins = vec![(s(1).dir(&out), s(1)), (out.join("shard-9"), s(1))];
        let e = check_complete(&out, &twins, "shard.json").unwrap_err();
        assert!(e.contains("shard 1/4 is written twice"), "{e}");
        let mixed = vec![(s(1).dir(&out), s(1)), (out.join("shard-2"), Shard { index: 2, count: 2 })];
        assert!(check_complete(&out, &mixed, "shard.json").unwrap_err().contains("mixed"));
        let _ = std::fs::remove_dir_all(&out);
        let e = check_complete(&out, &[], "shard.json").unwrap_err();
        assert!(e.contains("no shard-I/shard.json below it"), "{e}");
        // Written by --emit-jobs: the shards a merge expects before any has started.
        std::fs::create_dir_all(&out).unwrap();
        std::fs::write(out.join(PLANNED_FILE), "2").unwrap();
        let e = check_complete(&out, &[], "shard.json").unwrap_err();
        assert!(e.contains("2 of 2 shards are not there") && e.contains("shard 2/2 has not run"), "{e}");
        let _ = std::fs::remove_dir_all(&out);
    }
}
