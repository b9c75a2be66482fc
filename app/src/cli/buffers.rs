//! `gi-lab buffers`: the names of the inspectable buffers.

use super::renderer;
use crate::error::CliError;
use crate::scene_args::SceneArgs;

pub(super) fn buffers(args: &SceneArgs) -> Result<(), CliError> {
    let r = renderer(args, (16, 16))?;
    for e in r.buffers().entries() {
        println!("{:<22} {:<14} {}", e.name, format!("{:?}", e.texture.format()), e.description);
    }
    Ok(())
}
