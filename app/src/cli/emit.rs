//! `--emit-jobs slurm|parallel` of `gi-lab study` and `gi-lab sweep`: the script that runs a
//! command's shards and then its merge, either as a Slurm job array (one array task per shard,
//! the merge a job that runs only when every task succeeded) or with GNU parallel on this
//! machine and any others that share the output folder (docs/cli.md, "Scaling out").

use std::path::{Path, PathBuf};

use clap::Args;

use super::shard::shell_word;
use crate::error::CliError;

/// Where `--emit-jobs` runs the shards.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum JobEngine {
    /// A Slurm job array (`sbatch`), one array task per shard, and the merge as a dependent job.
    Slurm,
    /// A GNU parallel command line: the shards as parallel jobs, then the merge.
    Parallel,
}

/// The arguments of `--emit-jobs`, shared by `study` and `sweep`.
#[derive(Args, Debug, Clone, PartialEq)]
pub struct EmitArgs {
    /// Write the script that runs the shards and then the merge (OUT/study.slurm,
    /// OUT/sweep.parallel, …) instead of running them; see docs/cli.md, "Scaling out".
    #[arg(long, value_enum, conflicts_with = "shard")]
    pub emit_jobs: Option<JobEngine>,
    /// The number of shards of --emit-jobs.
    #[arg(long, default_value_t = 4)]
    pub shards: u32,
    /// GPUs per array task of --emit-jobs slurm (`#SBATCH --gpus-per-task`); 0 asks for none,
    /// for nodes without a GPU resource (the shards then render on the node's Vulkan driver,
    /// lavapipe on a CPU node).
    #[arg(long, default_value_t = 1, value_name = "N")]
    pub slurm_gpus: u32,
    /// The Slurm partition of the array and the merge (`--partition`).
    #[arg(long, value_name = "NAME")]
    pub slurm_partition: Option<String>,
    /// The time limit of each array task and of the merge (`--time`, e.g. 30, 2:00:00 or
    /// 1-12:00:00).
    #[arg(long, value_name = "TIME")]
    pub slurm_time: Option<String>,
    /// The account the jobs are charged to (`--account`).
    #[arg(long, value_name = "NAME")]
    pub slurm_account: Option<String>,
}

impl Default for EmitArgs {
    /// As the command line's defaults: no script, 4 shards, 1 GPU per task.
    fn default() -> Self {
        Self { emit_jobs: None, shards: 4, slurm_gpus: 1, slurm_partition: None, slurm_time: None, slurm_account: None }
    }
}

/// Is `t` one of the time formats of `sbatch --time`: `M`, `M:S`, `H:M:S`, `D-H`, `D-H:M`,
/// `D-H:M:S`, or `UNLIMITED`/`INFINITE`?
fn slurm_time_ok(t: &str) -> bool {
    if matches!(t, "UNLIMITED" | "INFINITE" | "unlimited" | "infinite") {
        return true;
    }
    let num = |s: &str| !s.is_empty() && s.len() <= 6 && s.chars().all(|c| c.is_ascii_digit());
    let (days, rest) = match t.split_once('-') {
        Some((d, r)) => (Some(d), r),
        None => (None, t),
    };
    if days.is_some_and(|d| !num(d)) {
        return false;
    }
    let parts: Vec<&str> = rest.split(':').collect();
    // With days: H, H:M or H:M:S after the dash; without: M, M:S or H:M:S.
    parts.iter().all(|p| num(p)) && (1..=3).contains(&parts.len())
}

/// A partition or account name: letters, digits, `-`, `_`, `.` (and `,` between the names of
/// a partition list), so that it stays one word on its `#SBATCH` line.
fn slurm_name_ok(s: &str) -> bool {
    !s.is_empty() && s.chars().all(|c| c.is_ascii_alphanumeric() || "-_.,".contains(c))
}

impl EmitArgs {
    /// Checks the arguments before anything is written.
    pub fn check(&self) -> Result<(), CliError> {
        if self.shards == 0 {
            return Err(CliError::input("--shards must be at least 1"));
        }
        if self.emit_jobs != Some(JobEngine::Slurm) {
            let given = [
                ("--slurm-partition", self.slurm_partition.is_some()),
                ("--slurm-time", self.slurm_time.is_some()),
                ("--slurm-account", self.slurm_account.is_some()),
                ("--slurm-gpus", self.slurm_gpus != 1),
            ];
            if let Some((flag, _)) = given.iter().find(|(_, g)| *g) {
                return Err(CliError::input(format!("{flag} applies to --emit-jobs slurm only")));
            }
        }
        for (flag, v) in [("--slurm-partition", &self.slurm_partition), ("--slurm-account", &self.slurm_account)] {
            if let Some(v) = v.as_deref().filter(|v| !slurm_name_ok(v)) {
                return Err(CliError::input(format!(
                    "{flag} '{v}': a Slurm name is letters, digits, '-', '_' and '.' (',' between names)"
                )));
            }
        }
        if let Some(t) = self.slurm_time.as_deref().filter(|t| !slurm_time_ok(t)) {
            return Err(CliError::input(format!(
                "--slurm-time '{t}': Slurm takes minutes, M:S, H:M:S, D-H, D-H:M or D-H:M:S (e.g. 30 or 2:00:00)"
            )));
        }
        Ok(())
    }

    /// The `sbatch` options the array and the merge share, as `--name=value` words.
    fn shared_options(&self) -> Vec<String> {
        let mut v = Vec::new();
        if let Some(p) = &self.slurm_partition {
            v.push(format!("--partition={p}"));
        }
        if let Some(t) = &self.slurm_time {
            v.push(format!("--time={t}"));
        }
        if let Some(a) = &self.slurm_account {
            v.push(format!("--account={a}"));
        }
        v
    }
}

/// The absolute form of `out` (the jobs may start in any folder).
fn absolute(out: &Path) -> Result<PathBuf, CliError> {
    if out.is_absolute() {
        return Ok(out.to_path_buf());
    }
    Ok(std::env::current_dir().map_err(|e| CliError::failure(e.to_string()))?.join(out))
}

/// The script that runs `gi-lab COMMAND ARGS --out OUT --shard I/N` for every shard and then
/// `gi-lab COMMAND --merge OUT` on the engine of `emit`: (its path, `OUT/COMMAND.slurm` or
/// `OUT/COMMAND.parallel`, and its text). `args` are the command's arguments without `--out`
/// and `--shard`, every path in them absolute.
pub fn script(command: &str, args: &[String], out: &Path, emit: &EmitArgs) -> Result<(PathBuf, String), CliError> {
    let engine = emit.emit_jobs.ok_or_else(|| CliError::failure("script() without --emit-jobs"))?;
    let exe = std::env::current_exe()
        .map(|p| p.display().to_string())
        .map_err(|e| CliError::failure(format!("the path of gi-lab itself: {e}")))?;
    let out_abs = absolute(out)?;
    let dir = shell_word(&out_abs.display().to_string());
    let shards = emit.shards;
    let mut shard_cmd = vec![shell_word(&exe), command.to_string()];
    shard_cmd.extend(args.iter().map(|a| shell_word(a)));
    shard_cmd.extend(["--out".into(), dir.clone()]);
    let shard_cmd = shard_cmd.join(" ");
    let merge = format!("{} {command} --merge {dir}", shell_word(&exe));
    let text = match engine {
        JobEngine::Parallel => format!(
            "#!/usr/bin/env bash\n\
             # GI Lab {command}: {shards} shards run by GNU parallel, then the merge into {dir}.\n\
             # Run: bash {dir}/{command}.parallel   (add e.g. -S host1,host2 after `parallel` to spread\n\
             # the shards over machines that share {dir}).\n\
             set -euo pipefail\n\
             parallel --will-cite --halt now,fail=1 --line-buffer -q {shard_cmd} --shard '{{}}/{shards}' ::: $(seq 1 {shards})\n\
             {merge}\n"
        ),
        JobEngine::Slurm => slurm(command, &dir, &shard_cmd, &merge, emit),
    };
    let ext = match engine {
        JobEngine::Parallel => "parallel",
        JobEngine::Slurm => "slurm",
    };
    Ok((out.join(format!("{command}.{ext}")), text))
}

/// Writes the script of [`script`] (executable) and gives its path.
pub fn write_script(command: &str, args: &[String], out: &Path, emit: &EmitArgs) -> Result<PathBuf, CliError> {
    let (path, text) = script(command, args, out, emit)?;
    std::fs::create_dir_all(out).map_err(|e| CliError::input(format!("--out {}: {e}", out.display())))?;
    // The number of shards, for a merge that runs before any of them has started.
    let planned = out.join(super::shard_status::PLANNED_FILE);
    gi_render::files::write_atomic_bytes(&planned, emit.shards.to_string().as_bytes(), gi_render::files::Backup::Skip)
        .map_err(|e| CliError::failure(format!("{}: {e}", planned.display())))?;
    gi_render::files::write_atomic_bytes(&path, text.as_bytes(), gi_render::files::Backup::Skip)
        .map_err(|e| CliError::failure(format!("{}: {e}", path.display())))?;
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let _ = std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o755));
    }
    Ok(path)
}

/// The Slurm job array script: run by hand (no `SLURM_ARRAY_TASK_ID`) it submits itself as
/// the array and then the merge with `--dependency=afterok` on it (and
/// `--kill-on-invalid-dep=yes`, so that a failed shard cancels the merge instead of leaving it
/// pending forever); run by Slurm as array task I it renders shard I.
fn slurm(command: &str, dir: &str, shard_cmd: &str, merge: &str, emit: &EmitArgs) -> String {
    let shards = emit.shards;
    let name = format!("gi-lab-{command}");
    let mut sbatch = vec![
        format!("--job-name={name}"),
        format!("--array=1-{shards}"),
        "--ntasks=1".into(),
        format!("--chdir={dir}"),
        format!("--output={dir}/logs/shard-%a.log"),
    ];
    if emit.slurm_gpus > 0 {
        sbatch.push(format!("--gpus-per-task={}", emit.slurm_gpus));
    }
    let shared = emit.shared_options();
    sbatch.extend(shared.iter().cloned());
    let lines: String = sbatch.iter().map(|o| format!("#SBATCH {o}\n")).collect();
    let mut merge_opts = vec![
        "--parsable".to_string(),
        "--dependency=afterok:\"$array\"".into(),
        "--kill-on-invalid-dep=yes".into(),
        format!("--job-name={name}-merge"),
        "--ntasks=1".into(),
        format!("--chdir={dir}"),
        format!("--output={dir}/logs/merge.log"),
    ];
    merge_opts.extend(shared);
    let merge_opts = merge_opts.join(" ");
    let wrap = shell_word(merge);
    let what = format!("{shards} shards of the {command} into {dir}");
    // A cluster without a GPU resource refuses `--gpus-per-task` as a bad gres.
    let gpu_hint = if emit.slurm_gpus > 0 {
        format!(
            "\x20   case \"$array\" in *gres*|*GRES*|*gpu*) echo \"{command}.slurm: the array asks for {} GPU(s) per \
             task; where the nodes have no GPU resource, write the script again with --slurm-gpus 0\" >&2;; esac\n",
            emit.slurm_gpus
        )
    } else {
        String::new()
    };
    format!(
        "#!/usr/bin/env bash\n\
         # GI Lab {command}: {shards} shards as a Slurm job array, then the merge into {dir} as a job\n\
         # that runs only when every shard succeeded. Run `bash {dir}/{command}.slurm` on a login\n\
         # node: it submits both. Each shard's output: {dir}/logs/shard-I.log; the merge's:\n\
         # {dir}/logs/merge.log. The jobs take the environment they are submitted from.\n\
         {lines}\
         set -euo pipefail\n\
         if [ -z \"${{SLURM_ARRAY_TASK_ID:-}}\" ]; then\n\
         \x20 if ! command -v sbatch >/dev/null 2>&1; then\n\
         \x20   echo \"{command}.slurm: no sbatch on the PATH: submit the job array {name} ({what}) from a Slurm login node, or run the shards here with --emit-jobs parallel\" >&2\n\
         \x20   exit 1\n\
         \x20 fi\n\
         \x20 mkdir -p {dir}/logs\n\
         \x20 if ! array=$(sbatch --parsable \"$0\" 2>&1); then\n\
         \x20   echo \"{command}.slurm: Slurm refused the job array {name} ({what}): $array\" >&2\n\
         {gpu_hint}\
         \x20   exit 1\n\
         \x20 fi\n\
         \x20 array=$(printf '%s\\n' \"$array\" | tail -n 1)\n\
         \x20 array=${{array%%;*}}\n\
         \x20 if ! merge=$(sbatch {merge_opts} --wrap {wrap} 2>&1); then\n\
         \x20   echo \"{command}.slurm: Slurm refused the merge job of the job array $array: $merge; cancelling the array\" >&2\n\
         \x20   scancel \"$array\" || true\n\
         \x20   exit 1\n\
         \x20 fi\n\
         \x20 merge=$(printf '%s\\n' \"$merge\" | tail -n 1)\n\
         \x20 merge=${{merge%%;*}}\n\
         \x20 echo \"submitted the job array $array ({what}) and its merge, job $merge\"\n\
         \x20 echo \"follow them with: squeue -j $array,$merge   (logs in {dir}/logs/)\"\n\
         \x20 exit 0\n\
         fi\n\
         exec {shard_cmd} --shard \"$SLURM_ARRAY_TASK_ID/{shards}\"\n"
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn emit(engine: JobEngine) -> EmitArgs {
        EmitArgs { emit_jobs: Some(engine), shards: 3, ..EmitArgs::default() }
    }

    #[test]
    fn slurm_times_are_checked_as_sbatch_reads_them() {
        for ok in ["30", "30:00", "2:00:00", "1-12", "1-12:30", "1-12:30:00", "UNLIMITED"] {
            assert!(slurm_time_ok(ok), "{ok}");
        }
        for bad in ["", "1h", "1:2:3:4", "-5", "1-", "1-2:3:4:5", "2 hours", "1:00\n#SBATCH --x"] {
            assert!(!slurm_time_ok(bad), "{bad}");
        }
    }

    #[test]
    fn slurm_options_need_slurm_and_one_word() {
        let mut e = emit(JobEngine::Parallel);
        e.slurm_partition = Some("gpu".into());
        assert!(e.check().is_err_and(|x| x.message.contains("--slurm-partition applies to --emit-jobs slurm")));
        let mut e = emit(JobEngine::Slurm);
        e.slurm_partition = Some("gpu a".into());
        assert!(e.check().is_err_and(|x| x.message.contains("'gpu a'")));
        e.slurm_partition = Some("gpu,gpu-long".into());
        e.slurm_account = Some("lab_42".into());
        e.slurm_time = Some("0:30:00".into());
        assert!(e.check().is_ok());
        e.shards = 0;
        assert!(e.check().is_err());
    }

    #[test]
    fn gpus_partition_time_and_account_reach_the_array_and_the_merge() {
        let mut e = emit(JobEngine::Slurm);
        e.slurm_gpus = 2;
        e.slurm_partition = Some("gpu".into());
        e.slurm_time = Some("1:00:00".into());
        e.slurm_account = Some("lab".into());
        let (path, text) = script("sweep", &["--param".into(), "a.b=1,2".into()], Path::new("/o"), &e).unwrap();
        assert_eq!(path, Path::new("/o/sweep.slurm"));
        for line in [
            "#SBATCH --array=1-3\n",
            "#SBATCH --gpus-per-task=2\n",
            "#SBATCH --partition=gpu\n",
            "#SBATCH --time=1:00:00\n",
            "#SBATCH --account=lab\n",
            "#SBATCH --output=/o/logs/shard-%a.log\n",
        ] {
            assert!(text.contains(line), "{line} in\n{text}");
        }
        let merge = text.lines().find(|l| l.contains("--wrap")).unwrap();
        for opt in [
            "--partition=gpu",
            "--time=1:00:00",
            "--account=lab",
            "--dependency=afterok:",
            "--output=/o/logs/merge.log",
        ] {
            assert!(merge.contains(opt), "{opt} in {merge}");
        }
        assert!(!merge.contains("gpus"), "the merge needs no GPU: {merge}");
        assert!(text.contains("sweep --param a.b=1,2 --out /o --shard \"$SLURM_ARRAY_TASK_ID/3\""), "{text}");
        e.slurm_gpus = 0;
        let (_, text) = script("sweep", &[], Path::new("/o"), &e).unwrap();
        assert!(!text.contains("gpus-per-task"), "{text}");
    }
}
