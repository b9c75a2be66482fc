//! `gi-lab gen-assets`: regenerates the embedded default scene (assets/cornell_box.glb) and,
//! on request, writes the framing test cases (`scene::framing_cases`).

use std::path::Path;

use gi_render::scene;

use crate::error::CliError;

/// Writes the embedded Cornell box as a .glb to `out`.
pub(super) fn gen_assets(out: &Path) -> Result<(), CliError> {
    gi_render::files::write_atomic_bytes(out, &scene::cornell::build_glb(), gi_render::files::Backup::Skip)
        .map(|_| println!("wrote {}", out.display()))
        .map_err(|e| CliError::input(format!("{}: {e}", out.display())))
}

/// Writes every framing case in metres and in millimetres into `dir`.
pub(super) fn framing_cases(dir: &Path) -> Result<(), CliError> {
    std::fs::create_dir_all(dir).map_err(|e| CliError::input(format!("{}: {e}", dir.display())))?;
    for name in scene::framing_cases::CASES {
        for (suffix, unit) in [("m", 1.0), ("mm", 1000.0)] {
            let bytes = scene::framing_cases::case_glb(name, unit)
                .ok_or_else(|| CliError::failure(format!("framing case {name} could not be built")))?;
            let out = dir.join(format!("{name}-{suffix}.glb"));
            gi_render::files::write_atomic_bytes(&out, &bytes, gi_render::files::Backup::Skip)
                .map_err(|e| CliError::input(format!("{}: {e}", out.display())))?;
            println!("wrote {}", out.display());
        }
    }
    Ok(())
}
