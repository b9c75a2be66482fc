//! A host that runs a GI Lab port kit knowing nothing but the kit (issue #54 point 3;
//! docs/port-kit.md, "Bringing a kit up"). It depends on wgpu, serde and pollster only —
//! not on gi-render or gi-lab — so that what it reproduces proves the kit complete: it
//! makes every resource of the manifest, loads the kit's WGSL, makes each pipeline from the
//! manifest's raster state and a layout from the step's bindings and the shaders'
//! declarations, uploads each frame's golden inputs, runs every frame's passes step by step,
//! and writes each pass's outputs where `gi-lab verify` looks for them.

mod host;
mod kit;
mod names;
mod run;

pub use run::{Summary, run};
