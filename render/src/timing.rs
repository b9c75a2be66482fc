//! GPU timing: one scope per pass, measured with GPU timestamp queries where the adapter
//! has them, and otherwise by CPU wall time around a separately submitted and awaited
//! command buffer per scope (slower, but honest). Later passes only add a scope.

use std::time::Instant;

use crate::gpu::GpuContext;

/// Most scopes per frame.
const MAX_SCOPES: u32 = 64;

/// Time one pass took in the last measured frame.
#[derive(Clone, Debug, PartialEq)]
pub struct PassTiming {
    /// The pass's name (same dotted prefix as its buffers: `gbuffer`, `direct.shadow`).
    pub name: String,
    pub ms: f64,
}

/// How the timings were measured.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TimingSource {
    GpuTimestamps,
    CpuWallClock,
}

/// Query indices of one scope; hand them to the pass descriptors.
#[derive(Clone, Copy)]
pub struct Slot<'a> {
    query_set: &'a wgpu::QuerySet,
    begin: u32,
}

impl<'a> Slot<'a> {
    /// Timestamp writes for a render pass; `first`/`last` say whether this pass opens
    /// and/or closes the scope (a scope may span several passes, e.g. shadow map layers).
    /// A pass in the middle of a scope writes none.
    pub fn render(&self, first: bool, last: bool) -> Option<wgpu::RenderPassTimestampWrites<'a>> {
        (first || last).then(|| wgpu::RenderPassTimestampWrites {
            query_set: self.query_set,
            beginning_of_pass_write_index: first.then_some(self.begin),
            end_of_pass_write_index: last.then_some(self.begin + 1),
        })
    }
    /// Timestamp writes for a compute pass, as [`Self::render`].
    pub fn compute(&self, first: bool, last: bool) -> Option<wgpu::ComputePassTimestampWrites<'a>> {
        (first || last).then(|| wgpu::ComputePassTimestampWrites {
            query_set: self.query_set,
            beginning_of_pass_write_index: first.then_some(self.begin),
            end_of_pass_write_index: last.then_some(self.begin + 1),
        })
    }
}

/// Per-frame GPU timer.
pub struct GpuTimer {
    gpu: Option<GpuQueries>,
    names: Vec<String>,
    cpu_ms: Vec<f64>,
    last: Vec<PassTiming>,
}

struct GpuQueries {
    set: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    readback: wgpu::Buffer,
    period_ns: f32,
}

impl GpuTimer {
    /// GPU timestamps when the device has them, unless `GI_LAB_CPU_TIMING=1` asks for the
    /// CPU wall-clock mode (to cross-check a driver's timestamps).
    pub fn new(ctx: &GpuContext) -> Self {
        let force_cpu = std::env::var("GI_LAB_CPU_TIMING").is_ok_and(|v| v == "1");
        let gpu = (ctx.has_timestamps() && !force_cpu).then(|| {
            let count = MAX_SCOPES * 2;
            GpuQueries {
                set: ctx.device.create_query_set(&wgpu::QuerySetDescriptor {
                    label: Some("timing.queries"),
                    ty: wgpu::QueryType::Timestamp,
                    count,
                }),
                resolve: ctx.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("timing.resolve"),
                    size: count as u64 * 8,
                    usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                    mapped_at_creation: false,
                }),
                readback: ctx.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("timing.readback"),
                    size: count as u64 * 8,
                    usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
                    mapped_at_creation: false,
                }),
                period_ns: ctx.queue.get_timestamp_period(),
            }
        });
        Self { gpu, names: Vec::new(), cpu_ms: Vec::new(), last: Vec::new() }
    }

    pub fn source(&self) -> TimingSource {
        if self.gpu.is_some() { TimingSource::GpuTimestamps } else { TimingSource::CpuWallClock }
    }

    /// Timings of the last collected frame, in pass order.
    pub fn last(&self) -> &[PassTiming] {
        &self.last
    }

    /// Records one scope. In GPU mode `f` records into the frame's encoder with a slot for
    /// timestamps; in CPU mode the pending work is flushed, `f` records into its own
    /// encoder, which is submitted and awaited, and the wall time is the pass's time.
    pub fn scope<R>(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        name: &str,
        f: impl FnOnce(&mut wgpu::CommandEncoder, Option<Slot<'_>>) -> R,
    ) -> R {
        let index = self.names.len() as u32;
        self.names.push(name.to_string());
        match &self.gpu {
            Some(q) if index < MAX_SCOPES => f(encoder, Some(Slot { query_set: &q.set, begin: index * 2 })),
            Some(_) => {
                log::warn!("more than {MAX_SCOPES} timing scopes; '{name}' is not timed");
                f(encoder, None)
            }
            None => {
                let pending = std::mem::replace(encoder, new_encoder(ctx));
                ctx.queue.submit([pending.finish()]);
                ctx.wait_idle();
                let start = Instant::now();
                let mut own = new_encoder(ctx);
                let r = f(&mut own, None);
                ctx.queue.submit([own.finish()]);
                ctx.wait_idle();
                self.cpu_ms.push(start.elapsed().as_secs_f64() * 1e3);
                r
            }
        }
    }

    /// Adds the query resolve to the frame's encoder (call once after the last scope).
    pub fn resolve(&self, encoder: &mut wgpu::CommandEncoder) {
        if let Some(q) = &self.gpu {
            let n = (self.names.len() as u32).min(MAX_SCOPES) * 2;
            if n > 0 {
                encoder.resolve_query_set(&q.set, 0..n, &q.resolve, 0);
                encoder.copy_buffer_to_buffer(&q.resolve, 0, &q.readback, 0, n as u64 * 8);
            }
        }
    }

    /// Reads the frame's timings back (blocks until the GPU finished the frame) and starts
    /// the next frame.
    pub fn collect(&mut self, ctx: &GpuContext) -> &[PassTiming] {
        let names = std::mem::take(&mut self.names);
        let cpu = std::mem::take(&mut self.cpu_ms);
        self.last = match &self.gpu {
            None => names.into_iter().zip(cpu).map(|(name, ms)| PassTiming { name, ms }).collect(),
            Some(q) => match crate::buffers::map_read(ctx, &q.readback) {
                Ok(bytes) => names
                    .into_iter()
                    .take(MAX_SCOPES as usize)
                    .enumerate()
                    .map(|(i, name)| {
                        let t = |k: usize| u64::from_le_bytes(bytes[8 * k..8 * k + 8].try_into().unwrap_or([0; 8]));
                        let ticks = t(2 * i + 1).saturating_sub(t(2 * i));
                        PassTiming { name, ms: ticks as f64 * q.period_ns as f64 * 1e-6 }
                    })
                    .collect(),
                Err(e) => {
                    log::warn!("timestamp readback failed: {e}");
                    Vec::new()
                }
            },
        };
        &self.last
    }
}

fn new_encoder(ctx: &GpuContext) -> wgpu::CommandEncoder {
    ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("timing.scope") })
}
