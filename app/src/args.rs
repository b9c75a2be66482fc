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
    /// Set by the lab when it restarts itself after the GPU device was lost: why, to show.
    #[arg(long, hide = true)]
    pub recovered: Option<String>,
    /// Restart the lab (with its saved session) when the GPU device is lost; tests turn it
    /// off to check what the lab saved and says.
    #[arg(long = "no-restart-on-device-loss", action = clap::ArgAction::SetFalse, hide = true)]
    pub restart_on_device_loss: bool,
    /// Lower the render scale while dragging to keep View → target frame rate (issue #39);
    /// tests turn it off so that their render sizes stay fixed.
    #[arg(long = "no-adaptive-scale", action = clap::ArgAction::SetFalse)]
    pub adaptive_scale: bool,
    /// Explain pixel X,Y of the render from the start (issue #42; as right-click → Explain
    /// this pixel): the Explain pane and its overlay show where its indirect light comes from.
    #[arg(long, value_parser = parse_pixel)]
    pub explain: Option<(u32, u32)>,
}

/// `X,Y` as a pixel.
pub fn parse_pixel(s: &str) -> Result<(u32, u32), String> {
    let (x, y) = s.split_once(',').ok_or_else(|| format!("'{s}': expected X,Y (e.g. 120,80)"))?;
    let n = |v: &str| v.trim().parse::<u32>().map_err(|_| format!("'{s}': '{v}' is not a pixel coordinate"));
    Ok((n(x)?, n(y)?))
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
            recovered: None,
            restart_on_device_loss: true,
            adaptive_scale: true,
            explain: None,
        }
    }
}
