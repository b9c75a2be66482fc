//! GI Lab application: the eframe window and the `gi-lab` command line.

pub mod ab;
pub mod app;
pub mod bench_suites;
pub mod cli;
pub mod hot_reload;
pub mod panes;
pub mod plot;
pub mod session;
pub mod settings_ui;
pub mod sweep;
pub mod viewer;
