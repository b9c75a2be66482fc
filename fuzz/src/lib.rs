//! GI Lab's mutation fuzzer on stable Rust (issue #19 point 2): the glTF/GLB loader, the
//! preset parsers and the `--set` parser, fuzzed without nightly, sanitizers or coverage.
//!
//! - [`rng`]: the seeded generator (SplitMix64 seeding, xorshift64*).
//! - [`mutate`]: byte mutations (bit flips, boundary values, insert, delete, duplicate,
//!   splice) and token mutations for text (boundary numbers, lines, identifiers).
//! - [`gltf_mutate`]: glTF-aware mutations that keep the GLB container valid and favour the
//!   fields that size allocations (`count`, `byteLength`, `byteOffset`, `byteStride`).
//! - [`seeds`] and [`hostile`]: the seed corpora (the real scenes, the loader tests' hostile
//!   files, every preset, every `--set` path).
//! - [`targets`]: what an input is run through and the properties checked.
//! - [`runner`]: the loop with its time cap, caught panics and summary; [`alloc`]: the
//!   counting global allocator of the memory cap (installed by the binary only).
//!
//! Usage: `cargo run --release -p gi-lab-fuzz -- --target gltf --iterations 1000000` (see
//! `fuzz/README.md`).

pub mod alloc;
pub mod gltf_mutate;
pub mod hostile;
pub mod mutate;
pub mod rng;
pub mod runner;
pub mod seeds;
pub mod targets;

pub use runner::{Config, Summary, run};
pub use targets::{Outcome, Target};
