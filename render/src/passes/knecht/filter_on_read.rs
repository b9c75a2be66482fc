//! The geometry-aware filter's own pass, run when `indirect.filtered` (or its irradiance) is
//! read after a frame that fused the filter into the confidence merge (issue #53,
//! `TemporalPass::run_fused`; docs/architecture.md "The filter fused into the merge"): the
//! registry's derived buffers (`buffers::Derived`) call it with the inputs that frame left,
//! so the viewer, the probe and the read-backs see what the two passes would have written.

use std::sync::{Arc, Mutex};

use crate::buffers::Derived;
use crate::gpu::GpuContext;

pub struct FilterOnRead {
    ctx: GpuContext,
    pipeline: wgpu::ComputePipeline,
    size: (u32, u32),
    /// The filter's bind group of the last frame that fused it, until it runs (None: the
    /// filter's outputs are up to date).
    pending: Mutex<Option<wgpu::BindGroup>>,
}

impl FilterOnRead {
    pub fn new(ctx: &GpuContext, pipeline: &wgpu::ComputePipeline, size: (u32, u32)) -> Arc<Self> {
        Arc::new(Self { ctx: ctx.clone(), pipeline: pipeline.clone(), size, pending: Mutex::new(None) })
    }

    /// `Some`: this frame fused the filter with these inputs (its outputs are stale until
    /// read); None: the filter's own pass ran.
    pub fn arm(&self, group: Option<wgpu::BindGroup>) {
        *self.pending.lock().unwrap_or_else(|p| p.into_inner()) = group;
    }
}

impl Derived for FilterOnRead {
    fn refresh(&self) {
        let Some(group) = self.pending.lock().unwrap_or_else(|p| p.into_inner()).take() else { return };
        self.ctx.make_current();
        let mut enc = self
            .ctx
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("interleave.filter.on_read") });
        crate::counters::traffic::begin_scope("interleave.filter");
        crate::passes::dispatch_2d(&mut enc, "interleave.filter.on_read", &self.pipeline, &group, &[], None, self.size);
        crate::counters::traffic::end_scope();
        self.ctx.submit([enc.finish()]);
    }
}
