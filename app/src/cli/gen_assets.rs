//! `gi-lab gen-assets`: regenerates the embedded default scene (assets/cornell_box.glb).

use std::path::Path;

use gi_render::scene;

use crate::error::CliError;

/// Writes the embedded Cornell box as a .glb to `out`.
pub(super) fn gen_assets(out: &Path) -> Result<(), CliError> {
    gi_render::preset::write_atomic_bytes(out, &scene::cornell::build_glb(), gi_render::preset::Backup::Skip)
        .map(|_| println!("wrote {}", out.display()))
        .map_err(|e| CliError::input(format!("{}: {e}", out.display())))
}
