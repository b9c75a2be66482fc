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
            unit_scale: 1.0,
            recent_scenes: Vec::new(),
            recent_presets: Vec::new(),
            camera: None,
            bookmarks: Vec::new(),
            lights: Vec::new(),
            lights_complete: false,
            viewers: Vec::new(),
            probes: Vec::new(),
            render_scale: default_render_scale(),
            playing: true,
            speed: 1.0,
            loop_s: 0.0,
            time_s: 0.0,
            history_frames: 240,
        }
    }
}

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

    /// Loads the session; a missing file gives the default, an unreadable one is kept as
    /// `session.ron.broken` (never deleted) and the default is used, with the reason.
    pub fn load(dir: &Path) -> (Self, Option<String>) {
        let path = Self::file(dir);
        let Ok(text) = std::fs::read_to_string(&path) else { return (Self::default(), None) };
        match ron::from_str::<Session>(&text) {
            Ok(s) => (s, None),
            Err(e) => {
                let broken = dir.join("session.ron.broken");
                let _ = std::fs::copy(&path, &broken);
                (
                    Self::default(),
                    Some(format!(
                        "the saved session {} could not be read ({e}); it was kept as {} and a new session started",
                        path.display(),
                        broken.display()
                    )),
                )
            }
        }
    }

    pub fn to_ron(&self) -> String {
        ron::ser::to_string_pretty(self, ron::ser::PrettyConfig::new().struct_names(false))
            .unwrap_or_else(|e| format!("// serialisation failed: {e}"))
    }

    /// Writes the session atomically.
    pub fn save(&self, dir: &Path) -> Result<(), String> {
        std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        let path = Self::file(dir);
        gi_render::preset::write_atomic(&path, &self.to_ron()).map_err(|e| format!("{}: {e}", path.display()))
    }

    /// Puts `path` first in a recent-files list (at most 10, no duplicates).
    pub fn remember(list: &mut Vec<PathBuf>, path: &Path) {
        list.retain(|p| p != path);
        list.insert(0, path.to_path_buf());
        list.truncate(10);
    }
}

/// The default layout: settings, scene and presets as tabs on the left; the viewport with
/// timings and probes under it in the middle; one buffer viewer on the right.
pub fn default_layout() -> egui_tiles::Tree<Pane> {
    let mut tiles = egui_tiles::Tiles::default();
    let left =
        vec![tiles.insert_pane(Pane::Settings), tiles.insert_pane(Pane::Scene), tiles.insert_pane(Pane::Presets)];
    let left = tiles.insert_tab_tile(left);
    let viewport = tiles.insert_pane(Pane::Viewport);
    let bottom = vec![tiles.insert_pane(Pane::Timings), tiles.insert_pane(Pane::Probe)];
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
