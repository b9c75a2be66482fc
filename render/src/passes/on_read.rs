//! A pass run when its output is read, after a frame that did its work elsewhere or left it
//! undone because nothing read it then (issue #53; docs/architecture.md "The filter fused
//! into the merge", "The ISM's pull-push in fewer passes", "`final.hdr` only when it is
//! read"): Knecht's geometry-aware filter when the frame fused it into the confidence merge
//! (`indirect.filtered` and its irradiance), the normals the demodulated merge kept in its
//! split history (`temporal.prev_normal`), the merge's confidence (`temporal.confidence`),
//! the ISM atlas as splatted (`ism.atlas`: the frame resolves straight into the pulled atlas)
//! and the compose's `final.hdr`. The registry's derived buffers (`buffers::Derived`) call it
//! with the inputs that frame left, so the viewer, the probe and the read-backs see what the
//! frame would have written.

use std::sync::{Arc, Mutex};

use crate::buffers::Derived;
use crate::gpu::GpuContext;

pub struct OnRead {
    ctx: GpuContext,
    /// The pass's name: its timing and traffic scope; its objects are labelled `{name}.on_read`.
    name: &'static str,
    size: (u32, u32),
    /// The pass's pipeline and bind group of the last frame that left its work undone, until
    /// it runs (None: the outputs are up to date).
    pending: Mutex<Option<(wgpu::ComputePipeline, wgpu::BindGroup, Vec<u32>)>>,
}

impl OnRead {
    pub fn new(ctx: &GpuContext, name: &'static str, size: (u32, u32)) -> Arc<Self> {
        Arc::new(Self { ctx: ctx.clone(), name, size, pending: Mutex::new(None) })
    }

    /// `Some`: this frame left the pass's work undone, to be done by this pipeline with these
    /// inputs (its outputs are stale until read); None: the outputs were written.
    pub fn arm(&self, pass: Option<(&wgpu::ComputePipeline, wgpu::BindGroup)>) {
        self.arm_with(pass, &[]);
    }

    /// [`Self::arm`] for a group with dynamic offsets.
    pub fn arm_with(&self, pass: Option<(&wgpu::ComputePipeline, wgpu::BindGroup)>, offsets: &[u32]) {
        *self.pending.lock().unwrap_or_else(|p| p.into_inner()) = pass.map(|(p, g)| (p.clone(), g, offsets.to_vec()));
    }
}

impl Derived for OnRead {
    fn refresh(&self) {
        let Some((pipeline, group, offsets)) = self.pending.lock().unwrap_or_else(|p| p.into_inner()).take() else {
            return;
        };
        self.ctx.make_current();
        let label = format!("{}.on_read", self.name);
        let mut enc = self.ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(&label) });
        crate::counters::traffic::begin_scope(self.name);
        crate::passes::dispatch_2d(&mut enc, &label, &pipeline, &group, &offsets, None, self.size);
        crate::counters::traffic::end_scope();
        self.ctx.submit([enc.finish()]);
    }
}
