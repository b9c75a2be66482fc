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
    /// the scene's opening view fitted to its aspect.
    #[arg(long, default_value = "1920x1080")]
    pub size: String,
    /// Write every settings group, not only those the stage choices use.
    #[arg(long)]
    pub all_groups: bool,
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
    let size = super::parse_size(&a.size).map_err(|e| CliError::input(format!("--size: {e}")))?;
    let settings = load_settings(&a.scene)?;
    let scene = load_scene(&a.scene)?;
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
