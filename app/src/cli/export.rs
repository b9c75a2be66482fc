//! `gi-lab export`: a preset for engines (JSON or RON with provenance).

use std::path::PathBuf;

use clap::Args;

use crate::error::CliError;
use crate::scene_args::{SceneArgs, load_scene, load_settings};

#[derive(Args, Debug, Clone)]
pub struct ExportArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// json or ron.
    #[arg(long, default_value = "json")]
    pub format: String,
    /// Output file; standard output when omitted.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Instead of exporting, write the schema documentation (docs/preset-schema.md) here.
    #[arg(long)]
    pub schema_doc: Option<PathBuf>,
    /// The image the pixel-relative settings are resolved for (WIDTHxHEIGHT); the camera is
    /// the scene's opening view fitted to its aspect. Default 1920x1080, and 320x180 for a
    /// port kit (its frames are drawn).
    #[arg(long)]
    pub size: Option<String>,
    /// Write every settings group, not only those the stage choices use.
    #[arg(long)]
    pub all_groups: bool,
    /// Write a port kit into this folder instead (docs/port-kit.md): the manifest of the
    /// frame's passes, the export, the shaders and a README.
    #[arg(long, value_name = "DIR")]
    pub port_kit: Option<PathBuf>,
    /// Port kit: frames drawn from a fresh start, each recorded in the goldens (at least 2).
    #[arg(long, default_value_t = 4)]
    pub frames: u32,
    /// Port kit: replace an existing folder (only once the new kit is complete).
    #[arg(long)]
    pub force: bool,
    /// Port kit: leave out the sizes and counts as expressions of W and H (they take six more
    /// captures at probe sizes; docs/port-kit.md, "Sizes as expressions").
    #[arg(long)]
    pub no_expressions: bool,
}

/// `gi-lab export`: the preset (with overrides) as an engine export.
pub(super) fn export(a: &ExportArgs) -> Result<(), CliError> {
    use gi_render::export::ExportView;
    use gi_render::files::write_atomic;
    use gi_render::preset::{Export, ExportFormat, Provenance, schema_markdown};
    if let Some(path) = &a.schema_doc {
        return write_atomic(path, &schema_markdown())
            .map(|_| println!("wrote {}", path.display()))
            .map_err(|e| CliError::input(format!("{}: {e}", path.display())));
    }
    let format = ExportFormat::parse(&a.format)
        .ok_or_else(|| CliError::input(format!("--format {}: expected json or ron", a.format)))?;
    let default_size = if a.port_kit.is_some() { "320x180" } else { "1920x1080" };
    let size = super::parse_size(a.size.as_deref().unwrap_or(default_size))
        .map_err(|e| CliError::input(format!("--size: {e}")))?;
    let settings = load_settings(&a.scene)?;
    let scene = load_scene(&a.scene)?;
    if let Some(dir) = &a.port_kit {
        return port_kit(a, dir, scene, settings, size);
    }
    let bounds = scene.bounds(0.0);
    let camera = gi_render::renderer::default_camera(&scene, bounds, size.0 as f32 / size.1 as f32);
    let name = a.scene.scene.as_ref().map(|p| p.display().to_string()).unwrap_or_else(|| scene.name.clone());
    let view = ExportView::of_scene(&name, &scene, bounds, camera, size, &settings);
    let text = Export::new(settings, Provenance::now(&view)).with_all_groups(a.all_groups).to_text(format);
    match &a.out {
        None => {
            println!("{text}");
            Ok(())
        }
        Some(path) => write_atomic(path, &text)
            .map(|_| println!("wrote {}", path.display()))
            .map_err(|e| CliError::input(format!("{}: {e}", path.display()))),
    }
}

/// `gi-lab export --port-kit DIR`: draws the preset's frames under a capture and writes the kit.
fn port_kit(
    a: &ExportArgs,
    dir: &std::path::Path,
    scene: gi_render::scene::Scene,
    settings: gi_render::LabSettings,
    size: (u32, u32),
) -> Result<(), CliError> {
    use gi_render::export::port_kit::{self, KitRequest};
    if dir.exists() && !a.force {
        return Err(CliError::input(format!(
            "--port-kit {}: the folder exists; choose another or pass --force to replace it",
            dir.display()
        )));
    }
    let preset = a
        .scene
        .preset
        .as_ref()
        .and_then(|p| p.file_stem())
        .map(|s| s.to_string_lossy().to_string())
        .unwrap_or_else(|| "default".into());
    let name = a.scene.scene.as_ref().map(|p| p.display().to_string()).unwrap_or_else(|| scene.name.clone());
    let ctx = gi_render::GpuContext::headless().map_err(|e| CliError::failure(e.to_string()))?;
    let req = KitRequest {
        preset: &preset,
        settings,
        scene,
        scene_name: &name,
        size,
        frames: a.frames,
        goldens: true,
        camera: None,
        expressions: !a.no_expressions,
        settings_probed: None,
    };
    let kit = port_kit::build(ctx, req).map_err(|e| CliError::failure(format!("port kit: {e}")))?;
    port_kit::write(&kit, dir, a.force).map_err(|e| CliError::input(format!("--port-kit: {e}")))?;
    let m = &kit.manifest;
    let steps: usize = m.passes.iter().map(|p| p.steps.len()).sum();
    println!(
        "wrote {}: {} passes, {} steps, {} resources, {} shader modules",
        dir.display(),
        m.passes.len(),
        steps,
        m.resources.len(),
        m.shaders.len()
    );
    Ok(())
}
