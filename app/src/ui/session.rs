//! The lab's session: everything a user would expect to find as they left it — panel
//! layout, live settings (saved or not), the preset they came from, scene, camera and
//! bookmarks, light edits, viewers, pinned probes, render scale and timeline. It is
//! autosaved (atomically) to the platform config directory every few seconds and on exit,
//! so a crash loses at most those seconds; presets themselves are never written by it.

use std::path::{Path, PathBuf};

use gi_render::camera::Camera;
use serde::{Deserialize, Serialize};

use crate::ui::viewer::ViewerState;

/// The panels of the lab (egui_tiles panes).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Pane {
    Viewport,
    Settings,
    Scene,
    Presets,
    Timings,
    Probe,
    /// The undo history (issue #39).
    History,
    /// The pinned pixel explained (issue #42).
    Explain,
    /// A buffer viewer; the number keys its state in [`Session::viewers`].
    Viewer(u32),
}

/// A named camera position.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Bookmark {
    pub name: String,
    pub camera: Camera,
}

pub use crate::scene_lights::{LightDef, LightEdit, LightKindDef};

/// A pinned probe: a frame pixel and the buffer/channel its history plot shows.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PinnedProbe {
    pub pixel: (u32, u32),
    pub buffer: String,
    pub channel: usize,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Session {
    pub layout: Option<egui_tiles::Tree<Pane>>,
    /// The live settings as preset text (loaded leniently, so that a session written by an
    /// older GI Lab still restores what it can).
    pub settings_ron: Option<String>,
    /// The preset the settings came from (None: defaults / a new preset).
    pub preset_path: Option<PathBuf>,
    pub scene: Option<PathBuf>,
    /// The scene's unit scale; 0: read from the scene's extent (issue #37 point 2).
    pub unit_scale: f32,
    pub recent_scenes: Vec<PathBuf>,
    pub recent_presets: Vec<PathBuf>,
    pub camera: Option<Camera>,
    pub bookmarks: Vec<Bookmark>,
    pub lights: Vec<LightEdit>,
    /// Whether `lights` lists every light of the scene (lights it does not list were
    /// removed); false for sessions of older GI Labs, whose list only edits.
    pub lights_complete: bool,
    pub viewers: Vec<(u32, ViewerState)>,
    pub probes: Vec<PinnedProbe>,
    /// Render resolution relative to the viewport's pixels.
    pub render_scale: f32,
    /// Frames per second the window keeps while the user drags, by lowering the render
    /// scale (`crate::ui::adaptive`); 0: off.
    pub target_fps: f32,
    pub playing: bool,
    pub speed: f64,
    pub loop_s: f64,
    pub time_s: f64,
    /// Frames of history in the probe and timing plots.
    pub history_frames: usize,
}

impl Default for Session {
    fn default() -> Self {
        Self {
            layout: None,
            settings_ron: None,
            preset_path: None,
            scene: None,
            unit_scale: 0.0,
            recent_scenes: Vec::new(),
            recent_presets: Vec::new(),
            camera: None,
            bookmarks: Vec::new(),
            lights: Vec::new(),
            lights_complete: false,
            viewers: Vec::new(),
            probes: Vec::new(),
            render_scale: default_render_scale(),
            target_fps: 15.0,
            playing: true,
            speed: 1.0,
            loop_s: 0.0,
            time_s: 0.0,
            history_frames: 240,
        }
    }
}

/// The render scales the View menu offers and the viewport accepts: down to 2 % (a few
/// dozen pixels, for a software device or a test that asks what the window does, not what it
/// shows) and up to supersampling by 2.
pub const RENDER_SCALE_RANGE: std::ops::RangeInclusive<f32> = 0.02..=2.0;

/// Half resolution in debug builds (software Vulkan is slow), full in release builds.
pub fn default_render_scale() -> f32 {
    if cfg!(debug_assertions) { 0.5 } else { 1.0 }
}

/// Where the session lives: `--config-dir`, else `$GI_LAB_CONFIG_DIR`, else the platform
/// config directory (`~/.config/gi-lab` on Linux).
pub fn config_dir(explicit: Option<&Path>) -> Option<PathBuf> {
    if let Some(p) = explicit {
        return Some(p.to_path_buf());
    }
    if let Some(p) = std::env::var_os("GI_LAB_CONFIG_DIR") {
        return Some(PathBuf::from(p));
    }
    dirs::config_dir().map(|d| d.join("gi-lab"))
}

impl Session {
    pub fn file(dir: &Path) -> PathBuf {
        dir.join("session.ron")
    }

    /// Loads the session. A missing file gives the default. A file that cannot be read or
    /// parsed is moved aside to `session.ron.corrupt` (`.corrupt.1`, `.corrupt.2`, … when
    /// that name is taken; never deleted), and the session starts from `session.ron.bak`
    /// (the version before the last save) when that parses, else from the defaults; the
    /// message says which, and why.
    pub fn load(dir: &Path) -> (Self, Option<String>) {
        let path = Self::file(dir);
        let error = match Self::read(&path) {
            Ok(Some(s)) => return (s, None),
            Ok(None) => return (Self::default(), None),
            Err(e) => e,
        };
        let kept = match move_aside(&path) {
            Ok(to) => format!("it was moved to {}", to.display()),
            Err(e) => format!("it could not be moved aside ({e})"),
        };
        let bak = path.with_file_name("session.ron.bak");
        let (session, outcome) = match Self::read(&bak) {
            Ok(Some(s)) => (s, format!("the previous session was restored from {}", bak.display())),
            Ok(None) => (Self::default(), "a new session started".to_string()),
            Err(e) => (Self::default(), format!("a new session started ({e})")),
        };
        (session, Some(format!("the saved session could not be read ({error}); {kept} and {outcome}")))
    }

    /// Reads and parses a session file: None when it does not exist.
    fn read(path: &Path) -> Result<Option<Self>, String> {
        let bytes = match std::fs::read(path) {
            Ok(b) => b,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
            Err(e) => return Err(format!("{}: {e}", path.display())),
        };
        let text = std::str::from_utf8(&bytes).map_err(|e| format!("{}: {e}", path.display()))?;
        ron::from_str::<Session>(text).map(Some).map_err(|e| format!("{}: {e}", path.display()))
    }

    pub fn to_ron(&self) -> String {
        ron::ser::to_string_pretty(self, ron::ser::PrettyConfig::new().struct_names(false))
            .unwrap_or_else(|e| format!("// serialisation failed: {e}"))
    }

    /// Writes the session atomically.
    pub fn save(&self, dir: &Path) -> Result<(), String> {
        std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        let path = Self::file(dir);
        gi_render::files::write_atomic(&path, &self.to_ron()).map_err(|e| format!("{}: {e}", path.display()))
    }

    /// Puts `path` first in a recent-files list (at most 10, no duplicates).
    pub fn remember(list: &mut Vec<PathBuf>, path: &Path) {
        list.retain(|p| p != path);
        list.insert(0, path.to_path_buf());
        list.truncate(10);
    }
}

/// Renames a corrupt session file to `<name>.corrupt`, or `<name>.corrupt.N` with the first
/// free N, so that an earlier corrupt file is never overwritten; returns the new name.
fn move_aside(path: &Path) -> std::io::Result<PathBuf> {
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_else(|| "session.ron".into());
    let free = (0..1000u32)
        .map(|i| path.with_file_name(if i == 0 { format!("{name}.corrupt") } else { format!("{name}.corrupt.{i}") }))
        .find(|p| std::fs::symlink_metadata(p).is_err())
        .ok_or_else(|| std::io::Error::other("too many corrupt sessions kept"))?;
    std::fs::rename(path, &free)?;
    Ok(free)
}

/// The default layout: settings, scene and presets as tabs on the left; the viewport with
/// timings and probes under it in the middle; one buffer viewer on the right.
pub fn default_layout() -> egui_tiles::Tree<Pane> {
    let mut tiles = egui_tiles::Tiles::default();
    let left =
        vec![tiles.insert_pane(Pane::Settings), tiles.insert_pane(Pane::Scene), tiles.insert_pane(Pane::Presets)];
    let left = tiles.insert_tab_tile(left);
    let viewport = tiles.insert_pane(Pane::Viewport);
    let bottom = vec![
        tiles.insert_pane(Pane::Timings),
        tiles.insert_pane(Pane::Probe),
        tiles.insert_pane(Pane::Explain),
        tiles.insert_pane(Pane::History),
    ];
    let bottom = tiles.insert_tab_tile(bottom);
    let middle = tiles.insert_vertical_tile(vec![viewport, bottom]);
    let viewer = tiles.insert_pane(Pane::Viewer(1));
    let right = tiles.insert_tab_tile(vec![viewer]);
    let root = tiles.insert_horizontal_tile(vec![left, middle, right]);
    if let Some(egui_tiles::Tile::Container(egui_tiles::Container::Linear(l))) = tiles.get_mut(root) {
        l.shares.set_share(left, 1.45);
        l.shares.set_share(middle, 2.4);
        l.shares.set_share(right, 1.3);
    }
    if let Some(egui_tiles::Tile::Container(egui_tiles::Container::Linear(l))) = tiles.get_mut(middle) {
        l.shares.set_share(viewport, 3.0);
        l.shares.set_share(bottom, 1.0);
    }
    egui_tiles::Tree::new(egui::Id::unique("gi_lab_layout"), root, tiles)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp_dir(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("gi-lab-session-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("temp dir");
        dir
    }

    #[test]
    fn a_corrupt_session_is_moved_aside_and_the_defaults_start() {
        let dir = temp_dir("corrupt");
        let garbage = b"(layout: Some(\xff\x00 not a session";
        std::fs::write(dir.join("session.ron"), garbage).expect("write");
        let (s, message) = Session::load(&dir);
        assert_eq!(s, Session::default());
        let message = message.expect("the corrupt session is reported");
        assert!(message.contains("session.ron.corrupt") && message.contains("new session"), "{message}");
        assert_eq!(std::fs::read(dir.join("session.ron.corrupt")).ok().as_deref(), Some(&garbage[..]));
        assert!(!Session::file(&dir).exists(), "the corrupt file is still session.ron");
        // A second corrupt session does not replace the first one kept.
        std::fs::write(dir.join("session.ron"), "garbage 2").expect("write");
        let (_, message) = Session::load(&dir);
        assert!(message.is_some_and(|m| m.contains("session.ron.corrupt.1")));
        assert_eq!(std::fs::read(dir.join("session.ron.corrupt")).ok().as_deref(), Some(&garbage[..]));
        assert_eq!(std::fs::read_to_string(dir.join("session.ron.corrupt.1")).ok().as_deref(), Some("garbage 2"));
        // No file: the defaults, silently.
        assert_eq!(Session::load(&dir), (Session::default(), None));
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_corrupt_session_restores_the_previous_one_from_the_bak() {
        let dir = temp_dir("restore");
        let older = Session { time_s: 1.5, render_scale: 0.25, ..Session::default() };
        older.save(&dir).expect("save");
        Session { time_s: 2.5, ..Session::default() }.save(&dir).expect("save");
        assert!(dir.join("session.ron.bak").exists());
        std::fs::write(Session::file(&dir), "(time_s: 3.5, render_scale: ").expect("truncate");
        let (s, message) = Session::load(&dir);
        assert_eq!(s, older);
        let message = message.expect("the restore is reported");
        assert!(message.contains("restored") && message.contains("session.ron.bak"), "{message}");
        assert!(dir.join("session.ron.corrupt").exists());
        // The next save keeps the restored .bak: there is no session.ron to copy over it.
        s.save(&dir).expect("save");
        assert_eq!(Session::load(&dir), (older, None));
        let _ = std::fs::remove_dir_all(&dir);
    }
}
