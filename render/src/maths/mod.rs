//! The floor of the render crate (issue #52 point 2): pure functions and tables that GPU
//! passes, CPU twins and scene code all need — sequences, the VPL budget, the HCB's recompute
//! pattern, colour maths, colour maps, the hemisphere camera's table, bounding boxes. It imports
//! nothing of the crate but a setting's type (a leaf), so that `passes/` never reaches into
//! `cpu/` at run time and `scene/` into neither (docs/architecture.md, "Layers").

pub mod aabb;
pub mod budget;
pub mod colormap;
pub mod colour;
pub mod hemisphere;
pub mod pattern;
pub mod sequence;

pub use aabb::Aabb;
pub use budget::{split_budget, tile_offsets, tile_slots};
pub use colour::luminance;
pub use pattern::recompute_pattern;
pub use sequence::{GOLDEN_ANGLE, halton, pcg_hash};
