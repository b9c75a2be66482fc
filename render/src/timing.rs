//! GPU timing: one scope per pass, measured with GPU timestamp queries where the adapter
//! has them, and otherwise by CPU wall time around a separately submitted and awaited
//! command buffer per scope (slower, but honest). Later passes only add a scope.

use crate::counters::prelude::*;

use std::time::Instant;

use crate::gpu::GpuContext;

/// Most scopes per frame.
const MAX_SCOPES: u32 = 256;

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
    /// No per-pass times: the device has no timestamps and the renderer may not wait for the
    /// GPU (the window, issue #38); `gi-lab bench` times the passes by the wall clock.
    Off,
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

/// Where one pass records (issue #52): the device and queue, the encoder of its timing scope
/// and the scope's timestamp slot ([`GpuTimer::pass`]).
pub struct PassRec<'a, 's> {
    pub ctx: &'a GpuContext,
    pub enc: &'a mut wgpu::CommandEncoder,
    pub slot: Option<Slot<'s>>,
}

/// Where a stage records its passes (issue #52): the frame's encoder and its pass timer.
pub struct Recorder<'a> {
    pub enc: &'a mut wgpu::CommandEncoder,
    pub timer: &'a mut GpuTimer,
}

/// Per-frame GPU timer.
pub struct GpuTimer {
    gpu: Option<GpuQueries>,
    names: Vec<String>,
    cpu_ms: Vec<f64>,
    last: Vec<PassTiming>,
    /// Never wait for the GPU (interactive mode): without timestamps no pass is timed, and a
    /// frame whose timestamp slot would have to wait goes untimed.
    no_wait: bool,
}

/// Frames whose timestamps may be in flight at once in the non-blocking mode.
const RING: usize = 3;

struct GpuQueries {
    set: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    /// Readback buffers, each with the scope names of the frame it holds and whether its
    /// mapping has completed (None: free).
    ring: Vec<RingSlot>,
    /// Ring slot of the frame being recorded.
    current: usize,
    /// This frame found no free slot and is not timed.
    skip: bool,
    period_ns: f32,
}

struct RingSlot {
    buffer: wgpu::Buffer,
    names: Vec<String>,
    mapped: Option<std::sync::Arc<std::sync::atomic::AtomicBool>>,
}

impl GpuTimer {
    /// GPU timestamps when the device has them, unless `GI_LAB_CPU_TIMING=1` asks for the
    /// CPU wall-clock mode (to cross-check a driver's timestamps).
    pub fn new(ctx: &GpuContext) -> Self {
        Self::with_source(ctx, TimingSource::GpuTimestamps)
    }

    /// Whether the adapter's timestamps can be trusted per pass: lavapipe (a CPU device)
    /// writes them where it records, not where the work runs, so that a compute pass's time
    /// lands in a later scope (measured: the ISM splat read 3 ms against 33 ms of wall clock,
    /// and a later splat 117 ms against 26 ms).
    pub fn timestamps_reliable(ctx: &GpuContext) -> bool {
        ctx.adapter_info.device_type != wgpu::DeviceType::Cpu
    }

    /// Like [`Self::new`], with `prefer` as the source (GPU timestamps fall back to the wall
    /// clock on devices without them).
    pub fn with_source(ctx: &GpuContext, prefer: TimingSource) -> Self {
        let force_cpu =
            prefer == TimingSource::CpuWallClock || std::env::var("GI_LAB_CPU_TIMING").is_ok_and(|v| v == "1");
        let gpu = (ctx.has_timestamps() && !force_cpu).then(|| {
            let count = MAX_SCOPES * 2;
            GpuQueries {
                set: ctx.device.counted_query_set(&wgpu::QuerySetDescriptor {
                    label: Some("timing.queries"),
                    ty: wgpu::QueryType::Timestamp,
                    count,
                }),
                resolve: ctx.device.counted_buffer(&wgpu::BufferDescriptor {
                    label: Some("timing.resolve"),
                    size: count as u64 * 8,
                    usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                    mapped_at_creation: false,
                }),
                ring: (0..RING)
                    .map(|_| RingSlot {
                        buffer: ctx.device.counted_buffer(&wgpu::BufferDescriptor {
                            label: Some("timing.readback"),
                            size: count as u64 * 8,
                            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
                            mapped_at_creation: false,
                        }),
                        names: Vec::new(),
                        mapped: None,
                    })
                    .collect(),
                current: 0,
                skip: false,
                period_ns: ctx.queue.get_timestamp_period(),
            }
        });
        Self { gpu, names: Vec::new(), cpu_ms: Vec::new(), last: Vec::new(), no_wait: false }
    }

    pub fn source(&self) -> TimingSource {
        match (&self.gpu, self.no_wait) {
            (Some(_), _) => TimingSource::GpuTimestamps,
            (None, false) => TimingSource::CpuWallClock,
            (None, true) => TimingSource::Off,
        }
    }

    /// Interactive mode: never wait for the GPU (see [`TimingSource::Off`]).
    pub fn set_no_wait(&mut self, no_wait: bool) {
        self.no_wait = no_wait;
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
        crate::counters::traffic::begin_scope(name);
        let r = if crate::counters::capture::goldens_on() {
            // The port kit's goldens: the pass alone in its submission, then read back.
            let pending = std::mem::replace(encoder, new_encoder(ctx));
            ctx.submit([pending.finish()]);
            let mut own = new_encoder(ctx);
            let r = f(&mut own, None);
            ctx.submit([own.finish()]);
            ctx.wait_idle();
            crate::readback::read_back_open_pass(ctx);
            r
        } else {
            self.scope_inner(ctx, encoder, name, index, f)
        };
        crate::counters::traffic::end_scope();
        r
    }

    /// [`Self::scope`] handing the pass one [`PassRec`].
    pub fn pass<R>(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        name: &str,
        f: impl FnOnce(PassRec<'_, '_>) -> R,
    ) -> R {
        self.scope(ctx, encoder, name, |enc, slot| f(PassRec { ctx, enc, slot }))
    }

    fn scope_inner<R>(
        &mut self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        name: &str,
        index: u32,
        f: impl FnOnce(&mut wgpu::CommandEncoder, Option<Slot<'_>>) -> R,
    ) -> R {
        match &self.gpu {
            Some(q) if index < MAX_SCOPES => f(encoder, Some(Slot { query_set: &q.set, begin: index * 2 })),
            Some(_) => {
                log::warn!("more than {MAX_SCOPES} timing scopes; '{name}' is not timed");
                f(encoder, None)
            }
            None if self.no_wait => f(encoder, None),
            None => {
                let pending = std::mem::replace(encoder, new_encoder(ctx));
                ctx.submit([pending.finish()]);
                ctx.wait_idle();
                let start = Instant::now();
                let mut own = new_encoder(ctx);
                let r = f(&mut own, None);
                ctx.submit([own.finish()]);
                ctx.wait_idle();
                self.cpu_ms.push(start.elapsed().as_secs_f64() * 1e3);
                r
            }
        }
    }

    /// Adds the query resolve to the frame's encoder (call once after the last scope). When
    /// every read-back slot is still in flight (the non-blocking mode, on a GPU more than
    /// [`RING`] frames behind), this frame goes untimed rather than waiting.
    pub fn resolve(&mut self, _ctx: &GpuContext, encoder: &mut wgpu::CommandEncoder) {
        let Some(q) = &mut self.gpu else { return };
        let free = (0..RING).map(|k| (q.current + k) % RING).find(|&i| q.ring[i].mapped.is_none());
        let Some(slot) = free else {
            q.skip = true;
            return;
        };
        q.skip = false;
        q.current = slot;
        let n = (self.names.len() as u32).min(MAX_SCOPES) * 2;
        if n > 0 {
            encoder.resolve_query_set(&q.set, 0..n, &q.resolve, 0);
            encoder.counted_copy_buffer(&q.resolve, 0, &q.ring[slot].buffer, 0, n as u64 * 8);
        }
    }

    /// After the frame's submission: starts reading its timings back. With `block`, waits
    /// for them (headless rendering, benchmarks, tests: the timings are this frame's);
    /// without, returns the newest frame whose timings have arrived (the app: no CPU–GPU
    /// synchronisation, timings one or two frames late).
    pub fn collect(&mut self, ctx: &GpuContext, block: bool) -> &[PassTiming] {
        let names = std::mem::take(&mut self.names);
        let cpu = std::mem::take(&mut self.cpu_ms);
        let Some(q) = &mut self.gpu else {
            // Without timestamps in the non-blocking mode nothing was timed (`TimingSource::Off`).
            self.last = names.into_iter().zip(cpu).map(|(name, ms)| PassTiming { name, ms }).collect();
            return &self.last;
        };
        let slot = q.current;
        if std::mem::take(&mut q.skip) {
            // Untimed (see `resolve`): only take in what has arrived.
            if let Err(e) = ctx.device.poll(wgpu::PollType::Poll) {
                log::warn!("device poll failed: {e}");
            }
            for k in 0..RING {
                let i = (slot + k) % RING;
                let done = q.ring[i].mapped.as_ref().is_some_and(|m| m.load(std::sync::atomic::Ordering::Acquire));
                if done && let Some(t) = read_slot(q, i) {
                    self.last = t;
                }
            }
            return &self.last;
        }
        let flag = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
        let f = flag.clone();
        q.ring[slot].names = names;
        q.ring[slot].buffer.slice(..).map_async(wgpu::MapMode::Read, move |r| {
            if let Err(e) = r {
                log::warn!("timestamp readback failed: {e}");
            }
            f.store(true, std::sync::atomic::Ordering::Release);
        });
        q.ring[slot].mapped = Some(flag);
        q.current = (slot + 1) % RING;
        let polled = if block {
            ctx.wait()
        } else {
            ctx.device.poll(wgpu::PollType::Poll).map(|_| ()).map_err(|e| e.to_string())
        };
        if let Err(e) = polled {
            log::warn!("device poll failed: {e}");
        }
        // Oldest first, so that the newest arrived frame wins.
        for k in 1..=RING {
            let i = (slot + k) % RING;
            let done = q.ring[i].mapped.as_ref().is_some_and(|m| m.load(std::sync::atomic::Ordering::Acquire));
            if done && let Some(t) = read_slot(q, i) {
                self.last = t;
            }
        }
        &self.last
    }
}

/// Reads and frees ring slot `i` (its mapping must have been requested); waits when it has
/// not completed yet.
fn read_slot(q: &mut GpuQueries, i: usize) -> Option<Vec<PassTiming>> {
    q.ring[i].mapped.take()?;
    let slot = &mut q.ring[i];
    let timings = match slot.buffer.slice(..).get_mapped_range() {
        Ok(bytes) => {
            let t = |k: usize| u64::from_le_bytes(bytes[8 * k..8 * k + 8].try_into().unwrap_or([0; 8]));
            std::mem::take(&mut slot.names)
                .into_iter()
                .take(MAX_SCOPES as usize)
                .enumerate()
                .map(|(j, name)| {
                    let ticks = t(2 * j + 1).saturating_sub(t(2 * j));
                    PassTiming { name, ms: ticks as f64 * q.period_ns as f64 * 1e-6 }
                })
                .collect()
        }
        Err(e) => {
            log::warn!("timestamp readback failed: {e}");
            Vec::new()
        }
    };
    slot.buffer.unmap();
    Some(timings)
}

fn new_encoder(ctx: &GpuContext) -> wgpu::CommandEncoder {
    ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("timing.scope") })
}
