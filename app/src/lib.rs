//! GI Lab application: the eframe window and the `gi-lab` command line.

pub mod app;
pub mod cli;
pub mod settings_ui;
