//! Read-backs without waiting (issue #38 point 1; docs/architecture.md, "Read-backs").
//!
//! The window's probe, stats panes, overlays, viewer auto-range and A/B metrics ask for data
//! by key with [`Readbacks::request`]. The copies are recorded into the next frame's own
//! encoder (no extra submit), land in staging buffers taken from a pool, and are mapped
//! after the frame's submission; the caller gets the newest copy that has arrived, a frame
//! or two late, and never waits. At most [`MAX_IN_FLIGHT`] copies per key are in flight,
//! so a slow GPU bounds the memory; staging buffers are reused, so steady state creates
//! none.

use std::collections::BTreeMap;
use std::sync::{Arc, Mutex};

use crate::buffers::{BufferRegistry, ImageF32, ProbePlan, ProbeValue, TexelPlan, TexturePlan};
use crate::counters::prelude::*;
use crate::gpu::GpuContext;

/// Copies per key that may be in flight at once.
pub const MAX_IN_FLIGHT: usize = 3;
/// Free staging buffers kept for reuse.
const POOL: usize = 12;

/// What to copy back.
#[derive(Clone, Debug)]
pub enum Readback {
    /// Every registered buffer's value at each pixel of the frame (the pixel probe).
    Probe(Vec<(u32, u32)>),
    /// One layer / level of a registered buffer, whole.
    Image { name: String, layer: u32, mip: u32 },
    /// Single texels of registered buffers: (name, x, y) in each buffer's own texels.
    Texels(Vec<(String, u32, u32)>),
    /// The first bytes of storage buffers (which need COPY_SRC), each (buffer, bytes).
    Storage(Vec<(wgpu::Buffer, u64)>),
}

/// What arrived.
#[derive(Clone, Debug)]
pub enum Readout {
    Probe(Vec<Vec<ProbeValue>>),
    Image(ImageF32),
    Texels(Vec<[f32; 4]>),
    /// One byte vector per storage buffer asked for.
    Bytes(Vec<Vec<u8>>),
}

/// One arrived read-back: the frame it was copied in, the caller's tag of its request and
/// its data (or why it failed).
#[derive(Clone, Debug)]
pub struct Arrived {
    pub frame: u64,
    pub tag: u64,
    pub data: Result<Readout, String>,
}

enum Plan {
    Probe(ProbePlan),
    Texels(TexelPlan),
    Image(TexturePlan),
    /// Each part's (offset, bytes) in the staging buffer.
    Storage(Vec<(u64, u64)>),
}

impl Plan {
    fn decode(&self, bytes: &[u8]) -> Readout {
        match self {
            Plan::Probe(p) => Readout::Probe(p.decode(bytes)),
            Plan::Image(p) => Readout::Image(p.decode(bytes)),
            Plan::Texels(p) => Readout::Texels(p.decode(bytes)),
            Plan::Storage(parts) => Readout::Bytes(
                parts
                    .iter()
                    .map(|&(o, n)| bytes.get(o as usize..(o + n) as usize).unwrap_or_default().to_vec())
                    .collect(),
            ),
        }
    }
}

type MapState = Arc<Mutex<Option<Result<(), String>>>>;

struct InFlight {
    key: String,
    frame: u64,
    tag: u64,
    staging: wgpu::Buffer,
    plan: Plan,
    /// None until `start_maps`; then set by the map callback.
    mapped: Option<MapState>,
}

/// The buffers a frame's read-backs copy ([`Readbacks::wanted`]).
#[derive(Clone, Debug, Default)]
pub struct Wanted {
    /// A probe: every buffer.
    pub all: bool,
    pub names: Vec<String>,
}

impl Wanted {
    pub fn reads(&self, name: &str) -> bool {
        self.all || self.names.iter().any(|n| n == name)
    }
}

/// The read-back ring of one renderer.
#[derive(Default)]
pub struct Readbacks {
    requested: BTreeMap<String, (Readback, u64)>,
    in_flight: Vec<InFlight>,
    latest: BTreeMap<String, Arc<Arrived>>,
    pool: Vec<wgpu::Buffer>,
}

impl Readbacks {
    /// Asks for `what` under `key`, copied in the next frame (a newer request under the same
    /// key replaces one not yet recorded), `tag` coming back with it; returns the newest
    /// read-back of `key` that has arrived, if any. Never waits.
    pub fn request(&mut self, key: &str, what: Readback, tag: u64) -> Option<Arc<Arrived>> {
        self.collect();
        let flying = self.in_flight.iter().filter(|f| f.key == key).count();
        if flying < MAX_IN_FLIGHT {
            self.requested.insert(key.to_string(), (what, tag));
        }
        self.latest.get(key).cloned()
    }

    /// The newest read-back of `key` that has arrived, without asking for another.
    pub fn latest(&mut self, key: &str) -> Option<Arc<Arrived>> {
        self.collect();
        self.latest.get(key).cloned()
    }

    /// Forgets `key`'s arrived data and pending request (its owner closed).
    pub fn forget(&mut self, key: &str) {
        self.requested.remove(key);
        self.latest.remove(key);
    }

    /// The buffers the requests not yet recorded read (a probe reads them all).
    pub fn wanted(&self) -> Wanted {
        let mut w = Wanted::default();
        for (what, _) in self.requested.values() {
            match what {
                Readback::Probe(_) => w.all = true,
                Readback::Image { name, .. } => w.names.push(name.clone()),
                Readback::Texels(points) => w.names.extend(points.iter().map(|(n, _, _)| n.clone())),
                Readback::Storage(_) => {}
            }
        }
        w
    }

    /// Read-backs requested or in flight.
    pub fn pending(&self) -> usize {
        self.requested.len() + self.in_flight.len()
    }

    /// Records the requested copies into the frame's encoder (called by `render_frame`
    /// before its submission). A request that cannot be planned (an unknown buffer) arrives
    /// at once as its error.
    pub(crate) fn record(
        &mut self,
        ctx: &GpuContext,
        enc: &mut wgpu::CommandEncoder,
        registry: &BufferRegistry,
        depth_probe: &crate::buffers::DepthProbe,
        frame_size: (u32, u32),
        frame: u64,
    ) {
        for (key, (what, tag)) in std::mem::take(&mut self.requested) {
            let plan = match what {
                Readback::Probe(pixels) => registry.probe_plan(frame_size, &pixels).map(Plan::Probe),
                Readback::Image { name, layer, mip } => {
                    registry.get(&name).and_then(|e| TexturePlan::new(&name, &e.texture, layer, mip)).map(Plan::Image)
                }
                Readback::Texels(points) => {
                    let points: Vec<(&str, u32, u32)> = points.iter().map(|(n, x, y)| (n.as_str(), *x, *y)).collect();
                    registry.texel_plan(&points).map(Plan::Texels)
                }
                Readback::Storage(sources) => {
                    let mut parts = Vec::with_capacity(sources.len());
                    let mut total = 0;
                    for (b, n) in &sources {
                        let n = (*n).min(b.size()) & !3;
                        parts.push((total, n));
                        total += n.next_multiple_of(wgpu::COPY_BUFFER_ALIGNMENT.max(4));
                    }
                    let staging = self.staging(ctx, total.max(4));
                    for ((b, _), &(o, n)) in sources.iter().zip(&parts) {
                        if n > 0 {
                            enc.copy_buffer_to_buffer(b, 0, &staging, o, n);
                        }
                    }
                    let plan = Plan::Storage(parts);
                    self.in_flight.push(InFlight { key, frame, tag, staging, plan, mapped: None });
                    continue;
                }
            };
            let plan = match plan {
                Ok(p) => p,
                Err(e) => {
                    self.latest.insert(key, Arc::new(Arrived { frame, tag, data: Err(e.to_string()) }));
                    continue;
                }
            };
            let bytes = match &plan {
                Plan::Probe(p) => p.bytes(),
                Plan::Image(p) => p.bytes(),
                Plan::Texels(p) => p.bytes(),
                Plan::Storage(_) => 0,
            };
            let staging = self.staging(ctx, bytes.max(4));
            match &plan {
                Plan::Probe(p) => p.record(ctx, enc, depth_probe, &staging),
                Plan::Image(p) => p.record(enc, &staging),
                Plan::Texels(p) => p.record(enc, &staging),
                Plan::Storage(_) => {}
            }
            self.in_flight.push(InFlight { key, frame, tag, staging, plan, mapped: None });
        }
    }

    /// Starts mapping what `record` copied (called after the frame's submission).
    pub(crate) fn start_maps(&mut self) {
        for f in self.in_flight.iter_mut().filter(|f| f.mapped.is_none()) {
            let state: MapState = Arc::new(Mutex::new(None));
            let s = state.clone();
            f.staging.slice(..).map_async(wgpu::MapMode::Read, move |r| {
                if let Ok(mut g) = s.lock() {
                    *g = Some(r.map_err(|e| e.to_string()));
                }
            });
            f.mapped = Some(state);
        }
    }

    /// Moves every completed map into `latest` (newest frame wins) and its staging buffer
    /// back to the pool. Needs the device polled (the window polls once per frame).
    fn collect(&mut self) {
        let mut k = 0;
        while k < self.in_flight.len() {
            let done = self.in_flight[k].mapped.as_ref().and_then(|m| m.lock().ok().and_then(|g| g.clone()));
            let Some(result) = done else {
                k += 1;
                continue;
            };
            let f = self.in_flight.remove(k);
            let data = result.and_then(|()| {
                let bytes = f.staging.slice(..).get_mapped_range().map_err(|e| e.to_string())?;
                Ok(f.plan.decode(&bytes))
            });
            f.staging.unmap();
            let newer = self.latest.get(&f.key).is_some_and(|a| a.frame > f.frame);
            if !newer {
                self.latest.insert(f.key, Arc::new(Arrived { frame: f.frame, tag: f.tag, data }));
            }
            self.give_back(f.staging);
        }
    }

    /// A staging buffer of at least `bytes` (and at most twice that) from the pool, else new.
    fn staging(&mut self, ctx: &GpuContext, bytes: u64) -> wgpu::Buffer {
        if let Some(i) = self.pool.iter().position(|b| b.size() >= bytes && b.size() <= bytes.saturating_mul(2)) {
            return self.pool.swap_remove(i);
        }
        ctx.device.counted_buffer(&wgpu::BufferDescriptor {
            label: Some("readback.staging"),
            size: bytes.next_multiple_of(256),
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        })
    }

    fn give_back(&mut self, b: wgpu::Buffer) {
        self.pool.push(b);
        if self.pool.len() > POOL {
            self.pool.remove(0);
        }
    }
}

/// A `u32` the GPU writes each frame (a count that sizes later work), read a frame or two
/// late without waiting: each frame's copy goes to one of three small staging buffers, its
/// map starts on the next frame (after the copy's submission) and is taken in once done.
pub struct LateCount {
    slots: Vec<LateSlot>,
    frame: u64,
    latest: Option<(u64, u32)>,
}

#[derive(Default)]
enum LateState {
    #[default]
    Free,
    /// Copied in the frame given; its map not started yet.
    Copied(u64),
    /// Mapping; the callback sets the flag.
    Mapping(u64, Arc<Mutex<Option<bool>>>),
}

struct LateSlot {
    buffer: wgpu::Buffer,
    state: LateState,
}

impl LateCount {
    pub fn new(ctx: &GpuContext, label: &str) -> Self {
        let slots = (0..3)
            .map(|_| LateSlot {
                buffer: ctx.device.counted_buffer(&wgpu::BufferDescriptor {
                    label: Some(label),
                    size: 4,
                    usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
                    mapped_at_creation: false,
                }),
                state: LateState::Free,
            })
            .collect();
        Self { slots, frame: 0, latest: None }
    }

    /// Takes in the finished maps, starts the maps of last frame's copy, and records this
    /// frame's copy of the first word of `src` into `enc`. Returns the newest count that has
    /// arrived (None until one has).
    pub fn update(&mut self, enc: &mut wgpu::CommandEncoder, src: &wgpu::Buffer) -> Option<u32> {
        for s in &mut self.slots {
            let done = match &s.state {
                LateState::Mapping(frame, flag) => flag.lock().ok().and_then(|f| *f).map(|ok| (*frame, ok)),
                _ => None,
            };
            if let Some((frame, ok)) = done {
                if ok && let Ok(bytes) = s.buffer.slice(..).get_mapped_range() {
                    let v = u32::from_le_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]);
                    if self.latest.is_none_or(|(f, _)| f < frame) {
                        self.latest = Some((frame, v));
                    }
                }
                if ok {
                    s.buffer.unmap();
                }
                s.state = LateState::Free;
            }
        }
        for s in &mut self.slots {
            if let LateState::Copied(frame) = s.state {
                let flag = Arc::new(Mutex::new(None));
                let f = flag.clone();
                s.buffer.slice(..).map_async(wgpu::MapMode::Read, move |r| {
                    if let Ok(mut g) = f.lock() {
                        *g = Some(r.is_ok());
                    }
                });
                s.state = LateState::Mapping(frame, flag);
            }
        }
        self.frame += 1;
        if let Some(s) = self.slots.iter_mut().find(|s| matches!(s.state, LateState::Free)) {
            enc.copy_buffer_to_buffer(src, 0, &s.buffer, 0, 4);
            s.state = LateState::Copied(self.frame);
        }
        self.latest.map(|(_, v)| v)
    }
}

/// The port kit's goldens (`counters::capture::start_with_goldens`): after a pass has run
/// alone and the GPU is idle, reads back every texture and buffer it touched into its
/// snapshots; blocks.
pub(crate) fn read_back_open_pass(ctx: &GpuContext) {
    use crate::counters::capture::{Snapshot, open_pass_targets, set_open_pass_snapshots};
    let mut snapshots = Vec::new();
    for t in open_pass_targets() {
        let (texture, bytes) = match (&t.texture, &t.buffer) {
            (Some(tex), _) => (true, read_texture_raw(ctx, tex)),
            (_, Some(b)) => (false, crate::buffers::read_storage(ctx, b, b.size())),
            _ => continue,
        };
        match bytes {
            Ok(bytes) => snapshots.push(Snapshot { key: t.key, texture, bytes }),
            Err(e) => log::warn!("golden read-back failed: {e}"),
        }
    }
    set_open_pass_snapshots(snapshots);
}

/// Every level and layer of `t`, rows packed; blocks.
fn read_texture_raw(ctx: &GpuContext, t: &wgpu::Texture) -> Result<Vec<u8>, String> {
    let format = t.format();
    let aspect =
        if format.is_depth_stencil_format() { wgpu::TextureAspect::DepthOnly } else { wgpu::TextureAspect::All };
    let bpp = format.block_copy_size(Some(aspect)).ok_or_else(|| format!("{format:?} cannot be copied"))?;
    let layers = if t.dimension() == wgpu::TextureDimension::D3 { 1 } else { t.depth_or_array_layers() };
    let mut out = Vec::new();
    for mip in 0..t.mip_level_count() {
        let (w, h) = ((t.width() >> mip).max(1), (t.height() >> mip).max(1));
        let depth = if t.dimension() == wgpu::TextureDimension::D3 {
            (t.depth_or_array_layers() >> mip).max(1)
        } else {
            layers
        };
        let row = w * bpp;
        let padded = row.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
        let size = padded as u64 * h as u64 * depth as u64;
        let staging = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("capture.golden_readback"),
            size,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        let mut enc =
            ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("capture.golden") });
        enc.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo { texture: t, mip_level: mip, origin: wgpu::Origin3d::ZERO, aspect },
            wgpu::TexelCopyBufferInfo {
                buffer: &staging,
                layout: wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(padded), rows_per_image: Some(h) },
            },
            wgpu::Extent3d { width: w, height: h, depth_or_array_layers: depth },
        );
        ctx.submit([enc.finish()]);
        let data = crate::buffers::map_read(ctx, &staging)?;
        for z in 0..depth {
            for y in 0..h {
                let o = ((z * h + y) * padded) as usize;
                out.extend_from_slice(&data[o..o + row as usize]);
            }
        }
    }
    Ok(out)
}
