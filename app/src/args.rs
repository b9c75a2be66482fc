//! The windowed app's launch options (the default command of `gi-lab`).

use std::path::PathBuf;

use clap::Args;

use crate::scene_args::SceneArgs;

/// Options of the windowed app (the default command).
#[derive(Args, Debug, Clone)]
pub struct AppArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Save a screenshot of the window to this PNG after --frames frames, then exit.
    #[arg(long)]
    pub screenshot: Option<PathBuf>,
    /// Frames to render before the screenshot.
    #[arg(long, default_value_t = 30)]
    pub screenshot_frames: u64,
    /// Folder of the session file (default: $GI_LAB_CONFIG_DIR, else the platform config
    /// directory, e.g. ~/.config/gi-lab).
    #[arg(long)]
    pub config_dir: Option<PathBuf>,
    /// Start from defaults instead of restoring the last session (it is still autosaved).
    #[arg(long)]
    pub fresh: bool,
    /// Folder the preset browser lists (default: ./presets).
    #[arg(long, default_value = "presets")]
    pub presets_dir: PathBuf,
    /// Folder of WGSL sources watched by the shader hot reload.
    #[arg(long, default_value = "shaders")]
    pub shaders_dir: PathBuf,
    /// Shader hot reload on or off (default: on in debug builds).
    #[arg(long)]
    pub hot_reload: Option<bool>,
}

impl Default for AppArgs {
    fn default() -> Self {
        Self {
            scene: SceneArgs::default(),
            screenshot: None,
            screenshot_frames: 30,
            config_dir: None,
            fresh: false,
            presets_dir: PathBuf::from("presets"),
            shaders_dir: PathBuf::from("shaders"),
            hot_reload: None,
        }
    }
}
