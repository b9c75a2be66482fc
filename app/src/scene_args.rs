//! The scene arguments shared by the window and the commands (`--scene`, `--unit-scale`,
//! `--preset`, `--set`) and loading the scene and the settings they name.

use std::path::PathBuf;

use clap::Args;
use gi_render::LabSettings;
use gi_render::scene::{self, LoadOptions, Scene};

use crate::error::CliError;

#[derive(Args, Debug, Clone)]
pub struct SceneArgs {
    /// glTF 2.0 scene (.gltf or .glb); the embedded Cornell box when omitted.
    #[arg(long)]
    pub scene: Option<PathBuf>,
    /// Multiply the scene's coordinates by this (e.g. 0.001 for millimetres); 0, the
    /// default, reads the unit from the scene's extent (millimetres beyond 3,000 units,
    /// centimetres beyond 300, else metres) and says so.
    #[arg(long, default_value_t = 0.0)]
    pub unit_scale: f32,
    /// RON preset; the defaults when omitted.
    #[arg(long)]
    pub preset: Option<PathBuf>,
    /// Override a setting, e.g. --set direct.pcf_radius=2 (repeatable).
    #[arg(long = "set", value_name = "GROUP.FIELD=VALUE")]
    pub overrides: Vec<String>,
    /// A sky around the scene: `R,G,B` (a constant linear colour), the path of an
    /// equirectangular .hdr/.exr image, or `off`; it replaces a sky saved beside the scene.
    #[arg(long, value_name = "R,G,B|IMAGE|off")]
    pub sky: Option<String>,
    /// Radiance scale of --sky, W/(m²·sr).
    #[arg(long, default_value_t = 1.0)]
    pub sky_intensity: f32,
    /// Rotation of --sky's image about the up axis, degrees.
    #[arg(long, default_value_t = 0.0)]
    pub sky_rotation: f32,
}

impl Default for SceneArgs {
    /// The embedded scene at unit scale with the default preset (as the CLI's defaults).
    fn default() -> Self {
        Self {
            scene: None,
            unit_scale: 0.0,
            preset: None,
            overrides: Vec::new(),
            sky: None,
            sky_intensity: 1.0,
            sky_rotation: 0.0,
        }
    }
}

/// Loads the scene named by the arguments (or the embedded default).
pub fn load_scene(args: &SceneArgs) -> Result<Scene, CliError> {
    if !(args.unit_scale.is_finite() && args.unit_scale >= 0.0) {
        return Err(CliError::input(format!(
            "--unit-scale {} must be a positive number (or 0: read the unit from the scene)",
            args.unit_scale
        )));
    }
    let opts = if args.unit_scale == 0.0 {
        LoadOptions::default()
    } else {
        LoadOptions { unit_scale: args.unit_scale, detect_units: false, ..LoadOptions::default() }
    };
    let mut scene = match &args.scene {
        None => scene::cornell::default_scene().map_err(|e| CliError::failure(format!("embedded scene: {e}")))?,
        Some(p) => scene::load_gltf_file(p, &opts).map_err(|e| CliError::input(e.to_string()))?,
    };
    // The lab's light edits saved beside the scene (issue #18): a broken file keeps the
    // scene's own lights and says why.
    if let Some(p) = &args.scene {
        match crate::scene_lights::load_overrides(p) {
            Some(Ok(o)) => {
                crate::scene_lights::apply_light_edits(&mut scene, &o.lights, true);
                let file = crate::scene_lights::overrides_path(p);
                scene.warnings.push(format!("lights from {} (the lab's edits; the glTF is unchanged)", file.display()));
                if let Some(sky) = &o.sky
                    && let Err(e) = crate::scene_lights::apply_sky(&mut scene, sky, p)
                {
                    scene.warnings.push(format!("the sky of {} was not applied in full: {e}", file.display()));
                }
            }
            Some(Err(e)) => scene.warnings.push(format!("the lights file was not applied: {e}")),
            None => {}
        }
    }
    if let Some(spec) = &args.sky {
        apply_sky_arg(&mut scene, spec, args.sky_intensity, args.sky_rotation).map_err(CliError::input)?;
    }
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    if let Some(v) = &scene.view {
        eprintln!("view: {}", v.reason);
    }
    Ok(scene)
}

/// Loads the preset and applies the `--set` overrides.
pub fn load_settings(args: &SceneArgs) -> Result<LabSettings, CliError> {
    let mut s = match &args.preset {
        None => LabSettings::default(),
        Some(p) => LabSettings::load(p).map_err(|e| CliError::input(e.to_string()))?,
    };
    for o in &args.overrides {
        s.apply_override(o).map_err(|e| CliError::input(format!("--set {o}: {e}")))?;
    }
    Ok(s)
}

/// `--sky SPEC` with its intensity and rotation: `off`, `R,G,B` or an image path (relative to
/// the working directory).
pub fn apply_sky_arg(scene: &mut Scene, spec: &str, intensity: f32, rotation_deg: f32) -> Result<(), String> {
    let spec = spec.trim();
    if spec.eq_ignore_ascii_case("off") {
        scene.sky.enabled = false;
        return Ok(());
    }
    let numbers: Vec<Result<f32, _>> = spec.split(',').map(|x| x.trim().parse::<f32>()).collect();
    let (color, image) = match numbers.as_slice() {
        [Ok(r), Ok(g), Ok(b)] => ([*r, *g, *b], None),
        _ if std::path::Path::new(spec).is_file() => ([1.0; 3], Some(PathBuf::from(spec))),
        _ => {
            return Err(format!(
                "--sky {spec}: not three numbers R,G,B, `off`, or an image file (.hdr or .exr) that exists"
            ));
        }
    };
    let def = crate::scene_lights::SkyDef { enabled: true, color, intensity, image, rotation_deg };
    // Image paths are taken as given (the scene file's folder is for the saved overrides).
    crate::scene_lights::apply_sky(scene, &def, std::path::Path::new("./--sky"))
        .map_err(|e| format!("--sky {spec}: {e}"))
}
