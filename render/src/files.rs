//! Files written so that a crash never leaves half of one (docs/reliability.md): the atomic
//! write every preset, session, export and capture goes through, and the clean-up of the
//! temporary files a killed writer leaves.

use std::path::Path;

/// Whether an atomic write keeps the file it replaces as `<name>.bak`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Backup {
    /// Presets, the session, exports: the replaced version is kept as `<name>.bak`
    /// (itself written atomically, so it is always a complete earlier version).
    Keep,
    /// Captures and other outputs that are regenerated rather than edited: no `.bak`.
    Skip,
}

/// Writes `contents` atomically: a temporary file in the same folder, flushed to disk, then
/// renamed over `path`; a replaced file is first copied to `<path>.bak`, atomically too (a
/// temporary copy, flushed, renamed). A failure or a kill at any step leaves `path` either
/// the old or the new complete version and `<path>.bak` a complete earlier version;
/// temporary files (`.<name>.<pid>.<n>.tmp`, hidden, ending in `.tmp`) may be left behind
/// by a kill.
pub fn write_atomic(path: &Path, contents: &str) -> std::io::Result<()> {
    write_atomic_with(path, contents, || Ok(()))
}

/// [`write_atomic`] with a hook run just before the rename (tests interrupt the save there).
pub fn write_atomic_with(
    path: &Path,
    contents: &str,
    before_rename: impl FnOnce() -> std::io::Result<()>,
) -> std::io::Result<()> {
    write_atomic_impl(path, contents.as_bytes(), Backup::Keep, before_rename)
}

/// [`write_atomic`] for binary files (images), with or without the `.bak` of the replaced
/// file: captures use [`Backup::Skip`], since a capture is not edited and a `.bak` beside
/// every image would only double the folder.
pub fn write_atomic_bytes(path: &Path, bytes: &[u8], backup: Backup) -> std::io::Result<()> {
    write_atomic_impl(path, bytes, backup, || Ok(()))
}

/// A temporary file name beside `path` that no other writer uses: hidden, with this
/// process's id and a per-process counter, ending in `.tmp` (never `.ron`, so that no
/// listing of presets mistakes it for one).
fn temp_beside(path: &Path, name: &str) -> std::path::PathBuf {
    use std::sync::atomic::{AtomicU64, Ordering};
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    path.with_file_name(format!(".{name}.{}.{n}.tmp", std::process::id()))
}

/// Removes the temporary files of [`write_atomic`] left in `dir` by a process that was killed
/// mid-save (named `.NAME.PID.N.tmp`): those whose process no longer runs (Linux: no
/// `/proc/PID`) or, where that cannot be known, older than an hour. A save in progress in
/// another process is left alone. Returns how many were removed.
pub fn remove_stale_temps(dir: &Path) -> usize {
    let Ok(entries) = std::fs::read_dir(dir) else { return 0 };
    let mut removed = 0;
    for entry in entries.flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        let Some(pid) = temp_pid(&name) else { continue };
        let stale = if cfg!(target_os = "linux") {
            !Path::new(&format!("/proc/{pid}")).exists()
        } else {
            let age = entry.metadata().and_then(|m| m.modified()).ok().and_then(|t| t.elapsed().ok());
            age.is_some_and(|a| a.as_secs() > 3600)
        };
        if stale && std::fs::remove_file(entry.path()).is_ok() {
            removed += 1;
        }
    }
    removed
}

/// The writer's process id in a temporary name of [`temp_beside`] (`.NAME.PID.N.tmp`).
fn temp_pid(file_name: &str) -> Option<u32> {
    let rest = file_name.strip_prefix('.')?.strip_suffix(".tmp")?;
    let mut parts = rest.rsplitn(3, '.');
    let n = parts.next()?;
    let pid = parts.next()?;
    let stem = parts.next()?;
    (!stem.is_empty() && n.parse::<u64>().is_ok()).then_some(())?;
    pid.parse().ok()
}

/// Writes `bytes` to a new temporary file beside `path` and flushes it to disk; the file is
/// removed again on failure.
fn write_temp(path: &Path, name: &str, bytes: &[u8]) -> std::io::Result<std::path::PathBuf> {
    use std::io::Write;
    let tmp = temp_beside(path, name);
    let mut f = std::fs::OpenOptions::new().write(true).create_new(true).open(&tmp)?;
    match f.write_all(bytes).and_then(|()| f.sync_all()) {
        Ok(()) => Ok(tmp),
        Err(e) => {
            let _ = std::fs::remove_file(&tmp);
            Err(e)
        }
    }
}

/// Renames `tmp` over `to` (removing `tmp` on failure) and flushes the folder, so that the
/// rename itself survives a power cut where the platform allows (best effort).
fn rename_over(tmp: &Path, to: &Path) -> std::io::Result<()> {
    std::fs::rename(tmp, to).inspect_err(|_| {
        let _ = std::fs::remove_file(tmp);
    })?;
    #[cfg(unix)]
    if let Some(dir) = to.parent() {
        let dir = if dir.as_os_str().is_empty() { Path::new(".") } else { dir };
        let _ = std::fs::File::open(dir).and_then(|d| d.sync_all());
    }
    Ok(())
}

fn write_atomic_impl(
    path: &Path,
    bytes: &[u8],
    backup: Backup,
    before_rename: impl FnOnce() -> std::io::Result<()>,
) -> std::io::Result<()> {
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_else(|| "preset".into());
    let tmp = write_temp(path, &name, bytes)?;
    let r = (|| {
        if backup == Backup::Keep {
            // The replaced version, read through one open handle (a concurrent rename over
            // `path` cannot mix two versions), becomes the .bak in one rename.
            match std::fs::read(path) {
                Ok(old) => {
                    let bak = path.with_file_name(format!("{name}.bak"));
                    let bak_tmp = write_temp(&bak, &format!("{name}.bak"), &old)?;
                    rename_over(&bak_tmp, &bak)?;
                }
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
                Err(e) => return Err(e),
            }
        }
        before_rename()
    })();
    if let Err(e) = r {
        let _ = std::fs::remove_file(&tmp);
        return Err(e);
    }
    rename_over(&tmp, path)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn temporary_files_of_dead_writers_are_removed_and_live_ones_kept() {
        let dir = std::env::temp_dir().join(format!("gi-lab-stale-temps-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("dir");
        let live = dir.join(format!(".session.ron.{}.3.tmp", std::process::id()));
        // No process has this id (Linux allows at most 2^22).
        let dead = dir.join(".session.ron.4294967.0.tmp");
        let other = dir.join(".hidden.tmp");
        for p in [&live, &dead, &other] {
            std::fs::write(p, "x").expect("write");
        }
        assert_eq!(temp_pid(".my.preset.ron.123.7.tmp"), Some(123));
        assert_eq!(temp_pid(".hidden.tmp"), None);
        assert_eq!(temp_pid("session.ron"), None);
        if cfg!(target_os = "linux") {
            assert_eq!(remove_stale_temps(&dir), 1);
            assert!(!dead.exists() && live.exists() && other.exists());
        }
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn atomic_write_keeps_a_backup_and_never_a_half_file() {
        let dir = std::env::temp_dir().join(format!("gi-lab-atomic-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let p = dir.join("p.ron");
        write_atomic(&p, "one").expect("first write");
        write_atomic(&p, "two").expect("second write");
        assert_eq!(std::fs::read_to_string(&p).ok().as_deref(), Some("two"));
        assert_eq!(std::fs::read_to_string(dir.join("p.ron.bak")).ok().as_deref(), Some("one"));
        // A save interrupted before the rename leaves the old file intact.
        let crash = || Err(std::io::Error::other("interrupted"));
        assert!(write_atomic_with(&p, "three", crash).is_err());
        assert_eq!(std::fs::read_to_string(&p).ok().as_deref(), Some("two"));
        // A write into a folder that does not exist fails before touching anything.
        assert!(write_atomic(&dir.join("missing/p.ron"), "x").is_err());
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn atomic_bytes_skip_the_backup_and_leave_no_temporary_files() {
        let dir = std::env::temp_dir().join(format!("gi-lab-atomic-bytes-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        let img = dir.join("c.png");
        write_atomic_bytes(&img, &[1, 2, 3], Backup::Skip).expect("first write");
        write_atomic_bytes(&img, &[4, 5], Backup::Skip).expect("second write");
        assert_eq!(std::fs::read(&img).ok(), Some(vec![4, 5]));
        assert!(!dir.join("c.png.bak").exists(), "Backup::Skip wrote a .bak");
        let bin = dir.join("d.bin");
        write_atomic_bytes(&bin, &[0, 255], Backup::Keep).expect("first write");
        write_atomic_bytes(&bin, &[7], Backup::Keep).expect("second write");
        assert_eq!(std::fs::read(dir.join("d.bin.bak")).ok(), Some(vec![0, 255]));
        // Every temporary file was renamed or removed, and two of them never share a name.
        let crash = || Err(std::io::Error::other("interrupted"));
        assert!(write_atomic_with(&bin, "x", crash).is_err());
        let names: Vec<String> = std::fs::read_dir(&dir)
            .expect("list")
            .filter_map(|e| e.ok().map(|e| e.file_name().to_string_lossy().into_owned()))
            .collect();
        assert!(names.iter().all(|n| !n.ends_with(".tmp")), "temporary files left: {names:?}");
        assert_ne!(temp_beside(&bin, "d.bin"), temp_beside(&bin, "d.bin"));
        let _ = std::fs::remove_dir_all(&dir);
    }
}
