//! A private runtime directory when the environment has none (issue #18 point 6): Mesa's
//! drivers (lavapipe included) print "XDG_RUNTIME_DIR is invalid or not set in the
//! environment" once per instance when `$XDG_RUNTIME_DIR` is missing or not a directory,
//! which a newcomer reads as an error. `main` sets the variable to [`private_runtime_dir`]
//! before any thread or GPU instance exists. Linux only (the variable is a freedesktop
//! convention; other systems do not read it).

use std::path::PathBuf;

/// Whether `$XDG_RUNTIME_DIR` names a directory (what Mesa checks).
pub fn runtime_dir_is_set() -> bool {
    std::env::var_os("XDG_RUNTIME_DIR").is_some_and(|d| std::path::Path::new(&d).is_dir())
}

/// `<temp>/gi-lab-runtime-<uid>`, made if missing, owned by this user and private (0700), as
/// the specification asks of a runtime directory. A path that exists but is not ours (or not
/// a directory) is left alone and a fresh `gi-lab-runtime-<uid>-<pid>` is made instead.
#[cfg(unix)]
pub fn private_runtime_dir() -> std::io::Result<PathBuf> {
    use std::os::unix::fs::{DirBuilderExt, MetadataExt, PermissionsExt};
    let uid = std::fs::metadata("/proc/self").map(|m| m.uid()).unwrap_or(0);
    let base = std::env::temp_dir();
    let ours = |p: &std::path::Path| {
        std::fs::symlink_metadata(p).is_ok_and(|m| m.is_dir() && !m.file_type().is_symlink() && m.uid() == uid)
    };
    for dir in
        [base.join(format!("gi-lab-runtime-{uid}")), base.join(format!("gi-lab-runtime-{uid}-{}", std::process::id()))]
    {
        match std::fs::DirBuilder::new().mode(0o700).create(&dir) {
            Ok(()) => return Ok(dir),
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists && ours(&dir) => {
                std::fs::set_permissions(&dir, std::fs::Permissions::from_mode(0o700))?;
                return Ok(dir);
            }
            Err(_) => continue,
        }
    }
    Err(std::io::Error::other("no private runtime directory could be made in the temp folder"))
}

#[cfg(not(unix))]
pub fn private_runtime_dir() -> std::io::Result<PathBuf> {
    Err(std::io::Error::other("runtime directories are a Unix convention"))
}
