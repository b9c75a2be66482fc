//! CPU reference implementations of the GPU kernels (docs/principles.md principle 9): tests compare
//! the passes' outputs with these on small inputs.

pub mod brdf;
pub mod ddgi;
pub mod gautron;
pub mod hcb;
pub mod irradiance_cache;
pub mod knecht;
pub mod knecht_bounce;
pub mod pathtrace;
pub mod soler;
pub mod soler_glossy;
pub mod soler_temporal;
pub mod soler_vote;
pub mod tonemap;
pub mod view;
