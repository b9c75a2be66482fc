//! The exact-VPL reference (Knecht 002 §5.2's baseline): uniformly sampled VPL batches
//! (`vpl`), exact cube-face visibility maps (`vpl_visibility`, also instant radiosity's exact
//! visibility) and the full-BRDF gather folded into a running average (`vpl_gather`).
//! Shaders: `shaders/reference/{sample,shadow,gather}.wgsl`.

pub mod explain;
pub mod stage;
pub mod vpl;
pub mod vpl_gather;
pub mod vpl_visibility;
