//! Helpers shared by the Knecht test files (`tests/knecht*.rs`).

use gi_render::settings::pipeline::Technique;
use gi_render::{GpuContext, LabSettings};
use glam::Vec3;

/// The default settings with Knecht's technique.
pub fn knecht_settings() -> LabSettings {
    let mut s = LabSettings::default();
    Technique::Knecht.apply(&mut s);
    s
}

/// A storage buffer's first `bytes`, read back.
pub fn read_buffer(ctx: &GpuContext, src: &wgpu::Buffer, bytes: u64) -> Vec<u8> {
    gi_render::buffers::read_storage(ctx, src, bytes).expect("map")
}

/// A texture's first layer and level, read back.
pub fn read(ctx: &GpuContext, t: &wgpu::Texture) -> gi_render::buffers::ImageF32 {
    gi_render::buffers::read_texture(ctx, "test", t, 0, 0).expect("readback")
}

/// A small deterministic generator (PCG-style hash), so that the synthetic inputs are
/// random-looking but identical on every run.
pub struct Rng(pub u64);

impl Rng {
    pub fn next_f32(&mut self) -> f32 {
        self.0 = self.0.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
        ((self.0 >> 40) as f32) / (1u64 << 24) as f32
    }
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.next_f32()
    }
    pub fn unit(&mut self) -> Vec3 {
        loop {
            let v = Vec3::new(self.range(-1.0, 1.0), self.range(-1.0, 1.0), self.range(-1.0, 1.0));
            if (0.05..1.0).contains(&v.length_squared()) {
                return v.normalize();
            }
        }
    }
    /// A multiple of 1/255, stored exactly by an 8-bit unorm target.
    pub fn unorm8(&mut self) -> f32 {
        (self.next_f32() * 255.0).round() / 255.0
    }
}
