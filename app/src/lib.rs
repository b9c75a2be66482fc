//! GI Lab application: the eframe window and the `gi-lab` command line.
//!
//! Two rooms: `cli` (one module per command) and `ui` (the window). `cli` reaches `ui` only
//! to open the window (`ui::run`); `ui` never uses `cli`. Beside them sits what is not one
//! room's own: the window's launch options (`args`), the scene arguments and their loading
//! (`scene_args`), the error type (`error`), and the CPU chart renderer (`plot`, egui's
//! fonts without a window) that draws the sweep's Pareto plot.

pub mod args;
pub mod cli;
pub mod error;
pub mod heap;
pub mod plot;
pub mod runtime_dir;
pub mod scene_args;
pub mod scene_lights;
pub mod ui;
