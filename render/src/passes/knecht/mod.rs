//! Instant radiosity with imperfect shadow maps and temporal coherence (Knecht 002): VPLs by
//! importance and hierarchical warping with further bounces (`vpl_importance`, `vpl_bounce`,
//! `irsm`), imperfect shadow maps with pull-push (`ism`), interleaved sampling and the
//! geometry-aware filter (`interleave`), the confidence merge (`temporal`). `stage` runs
//! stages 3–4 for the frame. Shaders: `shaders/knecht/vpl/{importance,reduce,warp,bounce,irsm}.wgsl`,
//! `shaders/knecht/ism/`, `shaders/knecht/interleave/`, `shaders/knecht/temporal/`.

pub mod explain;
pub mod interleave;
pub mod irsm;
pub mod ism;
pub mod point_cloud;
pub mod stage;
pub mod temporal;
pub mod vpl_bounce;
pub mod vpl_importance;
