//! A real one-node Slurm for the tests of `--emit-jobs slurm` (issue #55): started once per
//! test binary by `scripts/slurm-local.sh start DIR --owner PID`, whose watchdog stops it and
//! removes DIR as soon as the binary ends, however its tests end.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;
use std::time::{Duration, Instant};

pub struct Slurm {
    pub conf: PathBuf,
}

/// The cluster of this test binary (started on first use).
pub fn slurm() -> &'static Slurm {
    static CLUSTER: OnceLock<Slurm> = OnceLock::new();
    CLUSTER.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("gi-lab-slurm-{}", std::process::id()));
        let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scripts/slurm-local.sh");
        let o = Command::new("bash")
            .arg(&script)
            .arg("start")
            .arg(&dir)
            .arg("--owner")
            .arg(std::process::id().to_string())
            .output()
            .expect("bash runs scripts/slurm-local.sh");
        assert!(
            o.status.success(),
            "a one-node Slurm did not start (scripts/slurm-local.sh installs slurmctld, slurmd, slurm-client and \
             munge as root; otherwise: sudo apt-get install -y --no-install-recommends slurmctld slurmd \
             slurm-client munge):\n{}\n{}",
            String::from_utf8_lossy(&o.stdout),
            String::from_utf8_lossy(&o.stderr)
        );
        Slurm { conf: dir.join("etc/slurm.conf") }
    })
}

/// One job (or array task) as `scontrol show job -o` prints it: its `Key=Value` fields.
pub struct Job(Vec<(String, String)>);

impl Job {
    pub fn get(&self, key: &str) -> &str {
        self.0.iter().find(|(k, _)| k == key).map(|(_, v)| v.as_str()).unwrap_or("")
    }
}

impl Slurm {
    /// `program` talking to this cluster.
    pub fn command(&self, program: &str) -> Command {
        let mut c = Command::new(program);
        c.env("SLURM_CONF", &self.conf);
        c
    }

    /// Runs an emitted `*.slurm` script as a user would (`bash OUT/study.slurm`) and gives the
    /// job ids it printed: (the array, the merge).
    pub fn submit(&self, script: &Path) -> (String, String) {
        let o = self.command("bash").arg(script).output().expect("bash runs");
        let out = String::from_utf8_lossy(&o.stdout).to_string();
        assert!(o.status.success(), "{} failed: {out}\n{}", script.display(), String::from_utf8_lossy(&o.stderr));
        let line = out.lines().find(|l| l.starts_with("submitted the job array ")).expect("the submitted line");
        let array = line["submitted the job array ".len()..].split(' ').next().expect("array id").to_string();
        let merge = line.rsplit(' ').next().expect("merge id").to_string();
        (array, merge)
    }

    /// Waits until none of `jobs` is in the queue (`squeue`), at most `limit`; on timeout it
    /// fails with the queue and the jobs' logs below `logs`.
    pub fn wait(&self, jobs: &[&str], limit: Duration, logs: &Path) -> Duration {
        let start = Instant::now();
        let list = jobs.join(",");
        loop {
            let o = self.command("squeue").args(["-h", "-o", "%i %T %r", "-j", &list]).output().expect("squeue runs");
            let queue = String::from_utf8_lossy(&o.stdout).trim().to_string();
            if o.status.success() && queue.is_empty() {
                return start.elapsed();
            }
            if start.elapsed() > limit {
                let mut text = format!("jobs {list} still queued after {limit:?}:\n{queue}\n");
                for e in std::fs::read_dir(logs).into_iter().flatten().flatten() {
                    text += &format!(
                        "--- {}\n{}\n",
                        e.path().display(),
                        std::fs::read_to_string(e.path()).unwrap_or_default()
                    );
                }
                panic!("{text}");
            }
            std::thread::sleep(Duration::from_millis(250));
        }
    }

    /// The jobs of `id` (every task of an array) as the controller remembers them.
    pub fn jobs(&self, id: &str) -> Vec<Job> {
        let o = self.command("scontrol").args(["show", "job", "-o", id]).output().expect("scontrol runs");
        assert!(o.status.success(), "scontrol show job {id}: {}", String::from_utf8_lossy(&o.stderr));
        String::from_utf8_lossy(&o.stdout)
            .lines()
            .filter(|l| !l.trim().is_empty())
            .map(|l| {
                Job(l
                    .split_whitespace()
                    .filter_map(|w| w.split_once('=').map(|(k, v)| (k.to_string(), v.to_string())))
                    .collect())
            })
            .collect()
    }
}
