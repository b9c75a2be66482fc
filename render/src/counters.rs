//! What the CPU side of a frame costs: blocking waits for the GPU, queue submissions and GPU
//! objects created (issue #38 point 4; docs/performance.md, "Frame counters").
//!
//! Every blocking wait in `gi-render` goes through [`crate::GpuContext::wait`], every
//! submission through [`crate::GpuContext::submit`], and every buffer, texture, view, bind
//! group, sampler and query set through the [`CountedDevice`] / [`CountedTexture`] methods,
//! so the counts are complete by construction. The counters are per thread: a renderer is
//! driven from one thread (the window's or the command line's), and tests running side by
//! side do not see each other's counts.

use std::cell::Cell;

/// Counts since the thread started; subtract two snapshots for an interval.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct Counts {
    /// Times the CPU waited for the GPU to finish (`poll` with a wait).
    pub blocking_waits: u64,
    /// Queue submissions.
    pub submits: u64,
    /// Buffers, textures, texture views, bind groups, samplers and query sets created.
    pub objects_created: u64,
    /// Bytes the recorded passes touch (see [`traffic`]).
    pub traffic_bytes: u64,
    /// Light-space work that ran: each frame, each of the shadow maps, the light G-buffers
    /// with their importance, and a fixed VPL set with its visibility counts once when its
    /// inputs changed (`fingerprint::LastRun`, issue #53) …
    pub light_space_runs: u64,
    /// … and once when they did not and its last result was kept.
    pub light_space_skips: u64,
    /// The same for the camera's G-buffer and direct light (kept while the camera, the
    /// objects and the lights stay put).
    pub screen_space_runs: u64,
    pub screen_space_skips: u64,
}

impl std::ops::Sub for Counts {
    type Output = Counts;
    fn sub(self, o: Counts) -> Counts {
        Counts {
            blocking_waits: self.blocking_waits.saturating_sub(o.blocking_waits),
            submits: self.submits.saturating_sub(o.submits),
            objects_created: self.objects_created.saturating_sub(o.objects_created),
            traffic_bytes: self.traffic_bytes.saturating_sub(o.traffic_bytes),
            light_space_runs: self.light_space_runs.saturating_sub(o.light_space_runs),
            light_space_skips: self.light_space_skips.saturating_sub(o.light_space_skips),
            screen_space_runs: self.screen_space_runs.saturating_sub(o.screen_space_runs),
            screen_space_skips: self.screen_space_skips.saturating_sub(o.screen_space_skips),
        }
    }
}

thread_local! {
    static COUNTS: Cell<Counts> = const {
        Cell::new(Counts {
            blocking_waits: 0,
            submits: 0,
            objects_created: 0,
            traffic_bytes: 0,
            light_space_runs: 0,
            light_space_skips: 0,
            screen_space_runs: 0,
            screen_space_skips: 0,
        })
    };
}

thread_local! {
    static CONTEXT: Cell<u64> = const { Cell::new(0) };
}

/// Sets the context (`GpuContext::make_current`) whose objects this thread creates next.
pub(crate) fn set_context(nonce: u64) {
    CONTEXT.with(|c| c.set(nonce));
}

/// The current context's number, mixed into every key of `reuse` and `traffic`.
pub(crate) fn context() -> u64 {
    CONTEXT.with(Cell::get)
}

/// A key for a GPU object of the current context (`traffic`'s sizes, `capture`'s
/// descriptions).
pub(crate) fn key<T: std::hash::Hash>(t: &T) -> u64 {
    use std::hash::{Hash, Hasher};
    let mut h = std::collections::hash_map::DefaultHasher::new();
    context().hash(&mut h);
    t.hash(&mut h);
    h.finish()
}

/// This thread's counts so far.
pub fn now() -> Counts {
    COUNTS.with(Cell::get)
}

fn bump(f: impl FnOnce(&mut Counts)) {
    COUNTS.with(|c| {
        let mut v = c.get();
        f(&mut v);
        c.set(v);
    });
}

pub(crate) fn note_wait() {
    bump(|c| c.blocking_waits += 1);
}

pub(crate) fn note_submit() {
    bump(|c| c.submits += 1);
}

pub(crate) fn note_created() {
    bump(|c| c.objects_created += 1);
}

/// Where a kept pass works (`fingerprint::LastRun`), for the counts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Space {
    /// Shadow maps, light G-buffers, VPL sets and their visibility
    /// ([`Counts::light_space_runs`] / [`Counts::light_space_skips`]).
    Light,
    /// The camera's G-buffer and direct light ([`Counts::screen_space_runs`] /
    /// [`Counts::screen_space_skips`]).
    Screen,
}

pub(crate) fn note_kept(space: Space, ran: bool) {
    bump(|c| match (space, ran) {
        (Space::Light, true) => c.light_space_runs += 1,
        (Space::Light, false) => c.light_space_skips += 1,
        (Space::Screen, true) => c.screen_space_runs += 1,
        (Space::Screen, false) => c.screen_space_skips += 1,
    });
}

/// Object creation that counts (see the module docs). Import `crate::counters::*`.
pub trait CountedDevice {
    fn counted_buffer(&self, desc: &wgpu::BufferDescriptor) -> wgpu::Buffer;
    fn counted_buffer_init(&self, desc: &wgpu::util::BufferInitDescriptor) -> wgpu::Buffer;
    fn counted_texture(&self, desc: &wgpu::TextureDescriptor) -> wgpu::Texture;
    fn counted_bind_group(&self, desc: &wgpu::BindGroupDescriptor) -> wgpu::BindGroup;
    fn counted_sampler(&self, desc: &wgpu::SamplerDescriptor) -> wgpu::Sampler;
    fn counted_query_set(&self, desc: &wgpu::QuerySetDescriptor) -> wgpu::QuerySet;
    fn counted_compute_pipeline(&self, desc: &wgpu::ComputePipelineDescriptor) -> wgpu::ComputePipeline;
    fn counted_render_pipeline(&self, desc: &wgpu::RenderPipelineDescriptor) -> wgpu::RenderPipeline;
}

impl CountedDevice for wgpu::Device {
    fn counted_buffer(&self, desc: &wgpu::BufferDescriptor) -> wgpu::Buffer {
        note_created();
        let usage = capture::buffer_usage(desc.usage);
        let b = self.create_buffer(&wgpu::BufferDescriptor { usage, ..desc.clone() });
        capture::remember_buffer(&b, desc.label, desc.usage);
        b
    }
    fn counted_buffer_init(&self, desc: &wgpu::util::BufferInitDescriptor) -> wgpu::Buffer {
        use wgpu::util::DeviceExt;
        note_created();
        let usage = capture::buffer_usage(desc.usage);
        let b = self.create_buffer_init(&wgpu::util::BufferInitDescriptor { usage, ..*desc });
        capture::remember_buffer(&b, desc.label, desc.usage);
        b
    }
    fn counted_texture(&self, desc: &wgpu::TextureDescriptor) -> wgpu::Texture {
        note_created();
        let usage = capture::texture_usage(desc.usage);
        let t = self.create_texture(&wgpu::TextureDescriptor { usage, ..desc.clone() });
        capture::remember_texture(&t, desc);
        t
    }
    fn counted_bind_group(&self, desc: &wgpu::BindGroupDescriptor) -> wgpu::BindGroup {
        let key = reuse::group_key(desc);
        if let Some(g) = key.and_then(reuse::cached_group) {
            return g;
        }
        note_created();
        let group = self.create_bind_group(desc);
        traffic::remember_group(&group, desc);
        capture::remember_group(&group, desc);
        if let Some(k) = key {
            reuse::keep_group(k, &group);
        }
        group
    }
    fn counted_sampler(&self, desc: &wgpu::SamplerDescriptor) -> wgpu::Sampler {
        note_created();
        let s = self.create_sampler(desc);
        capture::remember_sampler(&s, desc);
        s
    }
    fn counted_query_set(&self, desc: &wgpu::QuerySetDescriptor) -> wgpu::QuerySet {
        note_created();
        self.create_query_set(desc)
    }
    fn counted_compute_pipeline(&self, desc: &wgpu::ComputePipelineDescriptor) -> wgpu::ComputePipeline {
        let p = self.create_compute_pipeline(desc);
        capture::remember_compute(&p, desc);
        p
    }
    fn counted_render_pipeline(&self, desc: &wgpu::RenderPipelineDescriptor) -> wgpu::RenderPipeline {
        let p = self.create_render_pipeline(desc);
        capture::remember_render(&p, desc);
        p
    }
}

/// View creation that counts.
pub trait CountedTexture {
    fn counted_view(&self, desc: &wgpu::TextureViewDescriptor) -> wgpu::TextureView;
}

impl CountedTexture for wgpu::Texture {
    fn counted_view(&self, desc: &wgpu::TextureViewDescriptor) -> wgpu::TextureView {
        let key = reuse::view_key(self, desc);
        if let Some(v) = reuse::cached_view(key) {
            return v;
        }
        note_created();
        let view = self.create_view(desc);
        traffic::remember_view(&view, self, desc);
        capture::remember_view(&view, self, desc);
        reuse::keep_view(key, &view);
        view
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_are_per_thread_and_subtract() {
        let before = now();
        note_wait();
        note_submit();
        note_submit();
        note_created();
        let d = now() - before;
        assert_eq!(d, Counts { blocking_waits: 1, submits: 2, objects_created: 1, ..Counts::default() });
        let other = std::thread::spawn(now).join().expect("thread");
        assert_eq!(other, Counts::default());
    }
}

/// The traits, for `use crate::counters::prelude::*`.
pub mod prelude {
    pub use super::traffic::{CountedCompute, CountedEncoder, CountedPass, CountedQueue, CountedRender};
    pub use super::{CountedDevice, CountedTexture};
}

pub mod capture;
pub mod reuse;
pub mod traffic;
