//! GI Lab's renderer: a deferred wgpu pipeline for real-time global illumination that
//! runs with or without a window. See `docs/principles.md` for the seven-stage pipeline;
//! `frame.rs` reads top to bottom as its table.

pub mod buffers;
pub mod camera;
pub mod chain;
pub mod clock;
pub mod counters;
pub mod cpu;
pub mod explain;
pub mod export;
pub mod files;
pub mod fingerprint;
pub mod frame;
pub mod gpu;
pub mod image_io;
pub mod lab_settings;
pub mod maths;
pub mod metrics;
pub mod passes;
pub mod preset;
pub mod quality;
pub mod readback;
pub mod renderer;
pub mod scale;
pub mod scene;
pub mod settings;
pub mod shaders;
pub mod timing;

pub use buffers::{BufferKind, BufferRegistry, ImageF32};
pub use gpu::GpuContext;
pub use lab_settings::LabSettings;
pub use renderer::{RenderError, Renderer};
