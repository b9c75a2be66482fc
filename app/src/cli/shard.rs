//! Splitting a command's jobs across machines (`--shard I/N`) and finding the shards again
//! for `--merge DIR`. The split is deterministic and contiguous: shard I of N takes jobs
//! `⌊(I−1)·n/N⌋ .. ⌊I·n/N⌋` of the command's job list, so that the shards of a study share
//! as few scenes (and their ground truths) as they can. Shard I writes into `DIR/shard-I/`.

use std::path::{Path, PathBuf};

/// One share of the jobs: `index` of `count`, both counted from 1.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Shard {
    pub index: u32,
    pub count: u32,
}

/// Parses `I/N` with 1 ≤ I ≤ N.
pub fn parse_shard(s: &str) -> Result<Shard, String> {
    let (i, n) = s.split_once('/').ok_or_else(|| format!("'{s}' is not I/N (e.g. 2/3: the second of three shards)"))?;
    let i: u32 = i.trim().parse().map_err(|_| format!("'{s}': I must be a whole number"))?;
    let n: u32 = n.trim().parse().map_err(|_| format!("'{s}': N must be a whole number"))?;
    if n == 0 || i == 0 || i > n {
        return Err(format!("'{s}': the shard must be 1 ≤ I ≤ N (shards count from 1)"));
    }
    Ok(Shard { index: i, count: n })
}

impl Shard {
    /// The jobs of this shard out of `jobs` (a contiguous range; empty when N > jobs).
    pub fn range(self, jobs: usize) -> std::ops::Range<usize> {
        let at = |k: u32| (k as usize * jobs) / self.count as usize;
        at(self.index - 1)..at(self.index)
    }

    /// The folder this shard writes into below the study's `--out`.
    pub fn dir(self, out: &Path) -> PathBuf {
        out.join(format!("shard-{}", self.index))
    }
}

/// The `shard-I` folders below `dir` that hold `file`, in shard order, each with its index
/// (none found is for `shard_status::check_complete` to explain).
pub fn shard_dirs(dir: &Path, file: &str) -> Result<Vec<(u32, PathBuf)>, String> {
    let entries = std::fs::read_dir(dir).map_err(|e| format!("--merge {}: {e}", dir.display()))?;
    let mut found = Vec::new();
    for e in entries.flatten() {
        let name = e.file_name().to_string_lossy().to_string();
        if let Some(i) = name.strip_prefix("shard-").and_then(|i| i.parse::<u32>().ok())
            && e.path().join(file).is_file()
        {
            found.push((i, e.path()));
        }
    }
    found.sort_by_key(|(i, _)| *i);
    Ok(found)
}

/// A word for the shell: quoted when it holds anything but safe characters.
pub fn shell_word(s: &str) -> String {
    if !s.is_empty() && s.chars().all(|c| c.is_ascii_alphanumeric() || "-_./=:,+@%".contains(c)) {
        s.to_string()
    } else {
        format!("'{}'", s.replace('\'', r"'\''"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_cover_every_job_once_in_order() {
        for jobs in [0usize, 1, 2, 5, 6, 7, 100] {
            for n in 1..=8u32 {
                let mut all = Vec::new();
                for i in 1..=n {
                    all.extend(Shard { index: i, count: n }.range(jobs));
                }
                assert_eq!(all, (0..jobs).collect::<Vec<_>>(), "{jobs} jobs in {n} shards");
            }
        }
        assert_eq!(Shard { index: 2, count: 3 }.range(6), 2..4);
    }

    #[test]
    fn shard_specs_parse_and_bad_ones_say_why() {
        assert_eq!(parse_shard("2/3"), Ok(Shard { index: 2, count: 3 }));
        for bad in ["0/3", "4/3", "1/0", "a/2", "3", ""] {
            assert!(parse_shard(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn shell_words_quote_what_the_shell_would_split() {
        assert_eq!(shell_word("a/b.ron"), "a/b.ron");
        assert_eq!(shell_word("my scene.glb"), "'my scene.glb'");
        assert_eq!(shell_word("it's"), r"'it'\''s'");
    }
}
