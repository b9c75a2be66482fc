//! Shader hot reload (issue #4 item 11; rerun's way): a file watcher (notify) on the
//! `shaders/` folder. When a WGSL file changes, every entry module that includes it is
//! validated with naga against the new text *before* anything is installed; if all pass,
//! the new source replaces the embedded one and only the passes built from those modules
//! are rebuilt (`Renderer::reload_shaders`). A file that does not compile keeps the last
//! good pipelines running, and its error is shown until a later save fixes it.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::mpsc;

use gi_render::shaders;

pub struct HotReload {
    dir: PathBuf,
    watcher: Option<notify::RecommendedWatcher>,
    events: Option<mpsc::Receiver<notify::Result<notify::Event>>>,
    /// Compile errors by shader file, shown until fixed.
    pub errors: BTreeMap<String, String>,
    /// What the last successful reload rebuilt.
    pub last_reload: Option<String>,
}

/// What a poll found: entry modules to rebuild (already validated and installed).
#[derive(Default, Debug)]
pub struct Changes {
    pub entries: Vec<&'static str>,
    pub files: Vec<String>,
}

impl HotReload {
    pub fn new(dir: PathBuf) -> Self {
        Self { dir, watcher: None, events: None, errors: BTreeMap::new(), last_reload: None }
    }

    pub fn dir(&self) -> &Path {
        &self.dir
    }

    pub fn enabled(&self) -> bool {
        self.watcher.is_some()
    }

    /// Starts or stops watching; an error says why watching is impossible (no folder).
    pub fn set_enabled(&mut self, on: bool) -> Result<(), String> {
        if !on {
            self.watcher = None;
            self.events = None;
            return Ok(());
        }
        if self.watcher.is_some() {
            return Ok(());
        }
        if !self.dir.is_dir() {
            return Err(format!("no shader folder at {} to watch", self.dir.display()));
        }
        let (tx, rx) = mpsc::channel();
        let mut w = notify::recommended_watcher(move |e| {
            let _ = tx.send(e);
        })
        .map_err(|e| format!("cannot watch {}: {e}", self.dir.display()))?;
        notify::Watcher::watch(&mut w, &self.dir, notify::RecursiveMode::Recursive)
            .map_err(|e| format!("cannot watch {}: {e}", self.dir.display()))?;
        self.watcher = Some(w);
        self.events = Some(rx);
        Ok(())
    }

    /// The path of a changed file relative to the shader folder, if it is one of ours.
    fn shader_name(&self, p: &Path) -> Option<String> {
        let dir = std::fs::canonicalize(&self.dir).unwrap_or_else(|_| self.dir.clone());
        let full = std::fs::canonicalize(p).unwrap_or_else(|_| p.to_path_buf());
        let rel = full.strip_prefix(&dir).ok()?;
        let name = rel.to_string_lossy().replace('\\', "/");
        shaders::SOURCES.iter().any(|(s, _)| *s == name).then_some(name)
    }

    /// Drains the watcher and installs every changed file that compiles.
    pub fn poll(&mut self) -> Changes {
        let mut changed: Vec<String> = Vec::new();
        if let Some(rx) = &self.events {
            while let Ok(e) = rx.try_recv() {
                let Ok(e) = e else { continue };
                if matches!(e.kind, notify::EventKind::Access(_)) {
                    continue;
                }
                for p in &e.paths {
                    if let Some(n) = self.shader_name(p)
                        && !changed.contains(&n)
                    {
                        changed.push(n);
                    }
                }
            }
        }
        let mut out = Changes::default();
        for file in changed {
            let Ok(text) = std::fs::read_to_string(self.dir.join(&file)) else { continue };
            let current = shaders::override_of(&file)
                .or_else(|| shaders::SOURCES.iter().find(|(p, _)| *p == file).map(|(_, s)| s.to_string()));
            if current.as_deref() == Some(text.as_str()) {
                self.errors.remove(&file);
                continue;
            }
            let entries = shaders::dependents(&file);
            let result: Result<(), String> =
                entries.iter().try_for_each(|e| shaders::validate_candidate(e, Some((&file, &text))));
            match result {
                Ok(()) => {
                    if shaders::set_override(&file, &text).is_ok() {
                        self.errors.remove(&file);
                        out.entries.extend(entries);
                        out.files.push(file);
                    }
                }
                Err(e) => {
                    log::warn!("shader {file} does not compile; the last good version stays: {e}");
                    self.errors.insert(file, e);
                }
            }
        }
        out.entries.sort();
        out.entries.dedup();
        out
    }
}
