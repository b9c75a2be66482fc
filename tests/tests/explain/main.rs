//! Explain a pixel (issue #42): every technique's GPU replay against the buffers the frame
//! wrote and against its CPU twin, and the window's key, menu, pane and overlay. One test
//! binary for all of them (one link instead of five).

mod gautron;
mod hcb;
mod soler;
mod vpl;
mod window;
