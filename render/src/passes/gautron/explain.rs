//! Explain a pixel (issue #42) for Gautron et al.'s irradiance cache splatting (003, "From
//! Octree to Splatting": "Principle"; Gautron et al. 2005, "Radiance cache splatting"), with
//! the records lit by their hemispheres or by VPLs (GI Lab's mix). `shaders/gautron/explain.wgsl`
//! replays the splat at the pinned pixel record by record through the splat's own functions
//! (`gautron/common.wgsl`), after the frame's passes and in its encoder, and reads what the
//! frame wrote there; [`decode`] turns it into the pixel's contributions (each record's share
//! of the resolved c·DI·E/π), the records near it that the splat rejects, and the checks of the
//! sums against `gautron.accum` and `gautron.indirect` (`crate::explain`). CPU twin of each
//! weight: `cpu::gautron::weight` (tests/explain/gautron.rs).

use glam::{Vec3, Vec4};

use crate::counters::prelude::*;
use crate::explain::{Check, Contribution, Explanation, Rejection, luminance};
use crate::gpu::GpuContext;
use crate::gpu::bindings::{Bindings, Kind, binding};
use crate::passes::stages::FrameInputs;
use crate::passes::view;

/// Bind group `explain.gautron.inputs` of `shaders/gautron/explain.wgsl` (group 0).
pub const GAUTRON_INPUTS_BINDINGS: Bindings = Bindings {
    label: "explain.gautron.inputs",
    shader: "gautron/explain.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "params", Kind::Uniform),
        binding(1, "camera", Kind::Uniform),
        binding(2, "records", Kind::Storage { read_only: true }),
        binding(3, "state", Kind::Storage { read_only: true }),
        binding(4, "g_position", Kind::Texture { filterable: false }),
        binding(5, "g_normal", Kind::Texture { filterable: false }),
        binding(6, "g_albedo", Kind::Texture { filterable: false }),
        binding(7, "accum", Kind::Texture { filterable: false }),
        binding(8, "indirect", Kind::Texture { filterable: false }),
        binding(9, "irradiance", Kind::Texture { filterable: false }),
        binding(10, "explain", Kind::Uniform),
        binding(11, "header", Kind::Storage { read_only: false }),
        binding(12, "counters", Kind::Storage { read_only: false }),
        binding(13, "listed", Kind::Storage { read_only: false }),
        binding(14, "snap_records", Kind::Storage { read_only: true }),
        binding(15, "snap_states", Kind::Storage { read_only: true }),
        binding(16, "accum_dir", Kind::Texture { filterable: false }),
        binding(17, "accum_plain", Kind::Texture { filterable: false }),
        binding(18, "g_material", Kind::Texture { filterable: false }),
    ],
};

/// Flags of a listed record (`EXPLAIN_*` in the shader).
pub const COVERS: u32 = 1;
pub const PENDING: u32 = 2;
pub const IN_FRONT: u32 = 4;
pub const BELOW: u32 = 8;

/// Byte offsets of the output buffer's parts (storage bindings start at multiples of 256):
/// the header, the counters, the listed records.
const COUNTERS_OFFSET: u64 = 256;
const ENTRIES_OFFSET: u64 = 512;
/// Most records listed (those whose bound holds the pixel or that lie within 2·a·R_k of it;
/// a few dozen at the shipped accuracy).
pub const MAX_LISTED: u64 = 2048;

/// WGSL twin: `ExplainParams`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
struct ExplainParams {
    pixel: [u32; 4],
}

/// What the frame wrote at the pixel; WGSL twin: `Header`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuHeader {
    /// x, y: the pixel; z: the cache's capacity; w: its records.
    pub pixel: [u32; 4],
    /// `gautron.accum` (rgb Σ w·E, a Σ w).
    pub accum: Vec4,
    /// `gautron.indirect`.
    pub indirect: Vec4,
    /// `gautron.irradiance` (E, a: Σ w).
    pub irradiance: Vec4,
    /// rgb: the resolve's receiver factor f (c·DI/π, plus the specular lobe's with
    /// `gautron.receiver = Glossy`: `receiver_factor`); a: 1 on the background.
    pub albedo: Vec4,
    /// xyz: P.
    pub point: Vec4,
    /// xyz: n.
    pub normal: Vec4,
    /// Made this frame, computed again this frame, stale, records.
    pub state: [u32; 4],
    /// xy: the pixel's centre in NDC.
    pub ndc: Vec4,
}

/// One listed record; WGSL twin: `Entry`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuEntry {
    /// x: the record's index, y: flags.
    pub index: [u32; 4],
    /// x: w clamped, y: w before the clamp, z: ‖P − P_k‖/R_k, w: √(1 − n·n_k).
    pub weight: Vec4,
    /// rgb: E_k(P) with the gradients as set; a: the "in front" test's margin.
    pub e: Vec4,
    /// rgb: (n_k × n)·∇_r E_k.
    pub rot: Vec4,
    /// rgb: (P − P_k)·∇_t E_k.
    pub trans: Vec4,
    /// The record's own `GpuRecord::{position, normal, irradiance, pixel}`.
    pub position: Vec4,
    pub normal: Vec4,
    pub irradiance: Vec4,
    pub pixel: Vec4,
}

impl GpuEntry {
    /// Whether the splat added it at the pixel.
    pub fn accepted(&self) -> bool {
        let flags = self.index[1];
        flags & COVERS != 0 && flags & (PENDING | IN_FRONT | BELOW) == 0
    }
}

/// What the frame's splat was, for [`decode`].
#[derive(Clone, Debug, PartialEq)]
pub struct GautronInfo {
    pub pixel: (u32, u32),
    /// Ward's accuracy a and the weight's clamp w_max.
    pub accuracy: f32,
    pub weight_clamp: f32,
    pub rotational: bool,
    pub translational: bool,
    pub neighbour_clamping: bool,
    /// The frame's index (`GpuRecord::irradiance.w` of the records computed in it).
    pub frame: u32,
    /// The replay read the cache as each splat did (`Snapshots`), not as the frame left it.
    pub snapshots: bool,
    pub technique: String,
}

/// What the replay reads of the stage (issue #52: the explain replay takes its inputs, not
/// the stage): its uniforms, the record cache and its state, the splat's outputs, and the
/// cache as each splat read it.
#[derive(Clone, Copy)]
pub struct StageParts<'s> {
    pub params: &'s wgpu::Buffer,
    pub records: &'s wgpu::Buffer,
    pub state: &'s wgpu::Buffer,
    pub splat: &'s super::splat::SplatPass,
    pub snapshots: Option<&'s Snapshots>,
}

pub struct GautronExplainPass {
    layout: wgpu::BindGroupLayout,
    pixel_pipeline: wgpu::ComputePipeline,
    records_pipeline: wgpu::ComputePipeline,
    explain: wgpu::Buffer,
    /// Stands in for the snapshots' counters when there are none (never read).
    no_states: wgpu::Buffer,
    /// Header, counters and the listed records.
    pub out: wgpu::Buffer,
    /// The last run's splat.
    pub info: Option<GautronInfo>,
}

impl crate::explain::Replay for GautronExplainPass {
    fn parts(&self) -> Option<Vec<(wgpu::Buffer, u64)>> {
        self.info.as_ref()?;
        Some(vec![(self.out.clone(), self.out.size())])
    }

    fn decode(&self, parts: &[Vec<u8>]) -> Option<Explanation> {
        let [out] = parts else { return None };
        decode(self.info.as_ref()?, out)
    }
}

impl GautronExplainPass {
    pub fn new(ctx: &GpuContext) -> Self {
        let device = &ctx.device;
        let layout = GAUTRON_INPUTS_BINDINGS.layout(device);
        let module = crate::shaders::create_module(device, "gautron/explain.wgsl");
        let pipeline = |label, entry| crate::passes::compute_pipeline(device, label, &module, entry, &[&layout]);
        Self {
            pixel_pipeline: pipeline("explain.gautron.pixel", "cs_explain_pixel"),
            records_pipeline: pipeline("explain.gautron.records", "cs_explain_records"),
            layout,
            explain: crate::passes::uniform_buffer(
                device,
                "explain.gautron.pixel",
                std::mem::size_of::<ExplainParams>() as u64,
            ),
            out: crate::passes::buffer(
                device,
                "explain.gautron.out",
                ENTRIES_OFFSET + MAX_LISTED * std::mem::size_of::<GpuEntry>() as u64,
                wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
            ),
            no_states: crate::passes::buffer(device, "explain.gautron.no_snapshots", 256, wgpu::BufferUsages::STORAGE),
            info: None,
        }
    }

    /// Records the replay of `info.pixel` into `enc`, after the stage's last splat and resolve
    /// (`indirect` is the resolve's output, `gautron.indirect`).
    pub fn run(
        &mut self,
        f: &FrameInputs,
        enc: &mut wgpu::CommandEncoder,
        stage: StageParts<'_>,
        indirect: &wgpu::TextureView,
        info: GautronInfo,
    ) {
        let ctx = f.ctx;
        let snapshots = stage.snapshots.filter(|s| s.taken > 0 && s.capacity == stage.records.size());
        let taken = snapshots.map(|s| s.taken).unwrap_or(0);
        let p = ExplainParams { pixel: [info.pixel.0, info.pixel.1, taken, 0] };
        let info = GautronInfo { snapshots: taken > 0, ..info };
        ctx.queue.upload(&self.explain, 0, bytemuck::bytes_of(&p));
        enc.counted_clear_buffer(&self.out, 0, Some(ENTRIES_OFFSET));
        let tv = wgpu::BindingResource::TextureView;
        let part = |offset, size| crate::passes::buffer_part(&self.out, offset, size);
        let (accum, irradiance) = (stage.splat.accum_view(), view(&stage.splat.irradiance, "gautron.irradiance"));
        let g = f.gbuffer;
        let (accum_dir, accum_plain) = stage.splat.receiver_views();
        let group = GAUTRON_INPUTS_BINDINGS.group(
            &ctx.device,
            &self.layout,
            [
                stage.params.as_entire_binding(),
                f.camera_buffer.as_entire_binding(),
                stage.records.as_entire_binding(),
                stage.state.as_entire_binding(),
                tv(&g.position),
                tv(&g.normal),
                tv(&g.albedo),
                tv(&accum),
                tv(indirect),
                tv(&irradiance),
                self.explain.as_entire_binding(),
                part(0, Some(std::mem::size_of::<GpuHeader>() as u64)),
                part(COUNTERS_OFFSET, Some(16)),
                part(ENTRIES_OFFSET, None),
                snapshots.map_or(stage.records.as_entire_binding(), |s| s.records.as_entire_binding()),
                snapshots.map_or(self.no_states.as_entire_binding(), |s| s.states.as_entire_binding()),
                tv(&accum_dir),
                tv(&accum_plain),
                tv(&g.material),
            ],
        );
        let records = (stage.records.size() / super::RECORD_BYTES).max(1);
        let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("explain.gautron"),
            timestamp_writes: None,
        });
        pass.set_bind_group(0, &group, &[]);
        pass.set_pipe(&self.pixel_pipeline);
        pass.dispatch(1, 1, 1);
        pass.set_pipe(&self.records_pipeline);
        pass.dispatch(records.div_ceil(64) as u32, 1, 1);
        drop(pass);
        self.info = Some(info);
    }
}

/// The cache as each splat of a frame read it (the cached records' splat, then each round's),
/// taken while a pixel is explained: a cached record computed again in a round, or whose R_k
/// a later round's neighbour clamping shrank, was splatted before that, and the replay must
/// weigh it as the splat did.
pub struct Snapshots {
    /// `slots` copies of the records buffer, one after the other.
    pub records: wgpu::Buffer,
    /// The cache's counters after each splat, 256 bytes apart.
    pub states: wgpu::Buffer,
    /// The records buffer's size (one snapshot).
    pub capacity: u64,
    pub slots: u32,
    /// Snapshots taken this frame.
    pub taken: u32,
}

impl Snapshots {
    /// Room for `slots` snapshots of a `records` buffer of `capacity` bytes.
    pub fn new(ctx: &GpuContext, capacity: u64, slots: u32) -> Self {
        let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
        let buffer = |label, size| crate::passes::buffer(&ctx.device, label, size, usage);
        Self {
            records: buffer("explain.gautron.snapshot_records", capacity * slots as u64),
            states: buffer("explain.gautron.snapshot_states", 256 * slots as u64),
            capacity,
            slots,
            taken: 0,
        }
    }

    /// The snapshot after splat `k` of the frame (0: the cached records'; k ≥ 1: round k − 1's).
    pub fn take(&mut self, enc: &mut wgpu::CommandEncoder, records: &wgpu::Buffer, state: &wgpu::Buffer, k: u32) {
        if k >= self.slots || records.size() != self.capacity {
            return;
        }
        enc.copy_buffer_to_buffer(records, 0, &self.records, k as u64 * self.capacity, self.capacity);
        enc.copy_buffer_to_buffer(state, 0, &self.states, k as u64 * 256, state.size().min(256) & !3);
        self.taken = k + 1;
    }
}

/// Why the splat left a listed record out, None when it added it.
pub fn rejection(e: &GpuEntry) -> Option<Rejection> {
    let flags = e.index[1];
    if flags & PENDING != 0 {
        Some(Rejection::Pending)
    } else if flags & COVERS == 0 {
        Some(Rejection::OutsideBound)
    } else if flags & IN_FRONT != 0 {
        Some(Rejection::InFront)
    } else if flags & BELOW != 0 {
        Some(Rejection::WeightBelowCutoff)
    } else {
        None
    }
}

/// The words of a record's state (`GpuRecord::pixel.w`).
fn state_word(state: f32) -> &'static str {
    match state.round() as i32 {
        0 => "being computed",
        1 => "fresh",
        _ => "stale",
    }
}

/// The pixel's explanation from the pass's output (`bytes`, the whole output buffer).
pub fn decode(info: &GautronInfo, bytes: &[u8]) -> Option<Explanation> {
    let header: GpuHeader = bytemuck::pod_read_unaligned(bytes.get(..std::mem::size_of::<GpuHeader>())?);
    let counters: [u32; 4] =
        bytemuck::pod_read_unaligned(bytes.get(COUNTERS_OFFSET as usize..COUNTERS_OFFSET as usize + 16)?);
    if (header.pixel[0], header.pixel[1]) != info.pixel {
        return None;
    }
    let size = std::mem::size_of::<GpuEntry>();
    let listed = (counters[0] as u64).min(MAX_LISTED) as usize;
    let start = ENTRIES_OFFSET as usize;
    let mut entries: Vec<GpuEntry> = bytemuck::pod_collect_to_vec(bytes.get(start..start + listed * size)?);
    // The splat adds the records in increasing index (the blending's order, and the bins').
    entries.sort_by_key(|e| e.index[0]);
    let v3 = |v: Vec4| v.truncate();
    // The resolve's factor f: its light is f·E (c·DI/π, and the glossy lobe's factor).
    let c_di = v3(header.albedo);
    let accepted: Vec<&GpuEntry> = entries.iter().filter(|e| e.accepted()).collect();
    let (mut sum_we, mut sum_w) = (Vec3::ZERO, 0.0f32);
    for e in &accepted {
        sum_we += e.weight.x * v3(e.e);
        sum_w += e.weight.x;
    }
    let mut rejected: Vec<&GpuEntry> = entries.iter().filter(|e| !e.accepted()).collect();
    rejected.sort_by(|a, b| b.weight.y.total_cmp(&a.weight.y));
    let [made, refreshed, stale, count] = header.state;
    // A record computed in this frame below the frame's new ones was computed again in place
    // (`gautron.invalidation` Refresh): the splat added its old E.
    // (With the snapshots the replay reads such a record as the splat did: nothing to mark.)
    let again = |e: &GpuEntry| {
        !info.snapshots && e.irradiance.w as u32 == info.frame && e.index[0] < count.saturating_sub(made)
    };
    let row = |e: &GpuEntry| {
        let rejected = rejection(e);
        let share = if rejected.is_none() && sum_w > 0.0 { e.weight.x / sum_w } else { 0.0 };
        // The replay's clamp at 1e30 stands for none: P = P_k, n = n_k gives 1/0.
        let unclamped = if e.weight.y >= 1e30 { f32::INFINITY } else { e.weight.y };
        let mut fields = vec![("w", unclamped), ("w clamped", e.weight.x), ("E (lum)", luminance(v3(e.e)))];
        if info.rotational {
            fields.push(("∇r term (lum)", luminance(v3(e.rot))));
        }
        if info.translational {
            fields.push(("∇t term (lum)", luminance(v3(e.trans))));
        }
        fields.extend([
            ("R_k", e.position.w),
            ("a·R_k", info.accuracy * e.position.w),
            ("H", e.normal.w),
            ("‖P−P_k‖/R_k", e.weight.z),
            ("√(1−n·n_k)", e.weight.w),
        ]);
        Contribution {
            name: format!("record {}", e.index[0]),
            source: format!(
                "made at ({}, {}) in frame {}, {}{}",
                e.pixel.x as u32,
                e.pixel.y as u32,
                e.irradiance.w as u32,
                state_word(e.pixel.w),
                if again(e) { ", recomputed" } else { "" }
            ),
            position: Some(v3(e.position)),
            // f · w_k·E_k(P) / Σ w: its share of the resolve's f · RGB / A
            value: if share > 0.0 { c_di * (e.weight.x * v3(e.e)) / sum_w } else { Vec3::ZERO },
            weight: share,
            rejected,
            via: None,
            fields,
        }
    };
    let contributions: Vec<Contribution> = accepted.iter().chain(&rejected).map(|e| row(e)).collect();
    let accum = header.accum;
    let resolved = if accum.w > 0.0 { c_di * (v3(accum) / accum.w) } else { Vec3::ZERO };
    let checks = vec![
        Check {
            what: format!("Σ w_k·E_k(P) over the {} records the splat adds", accepted.len()),
            sum: sum_we,
            buffer: "gautron.accum (rgb)".into(),
            value: v3(accum),
        },
        Check {
            what: "Σ w_k".into(),
            sum: Vec3::splat(sum_w),
            buffer: "gautron.accum (a)".into(),
            value: Vec3::splat(accum.w),
        },
        Check {
            what: "f · RGB / A of gautron.accum (the resolve; f: the receiver's factor)".into(),
            sum: resolved,
            buffer: "gautron.indirect".into(),
            value: v3(header.indirect),
        },
    ];
    let mut notes = Vec::new();
    if header.albedo.w > 0.5 {
        notes.push("the G-buffer is empty at the pixel: no record splats there".into());
    }
    notes.push(format!(
        "{count} records in the cache (of {}); {} bounds hold the pixel, {} of them pass w > 1/a = {:.4} (a = {}, w clamped at {}); {} more listed within 2·a·R_k",
        header.pixel[2],
        counters[1],
        counters[2],
        1.0 / info.accuracy,
        info.accuracy,
        info.weight_clamp,
        entries.len() - entries.iter().filter(|e| e.index[1] & COVERS != 0).count(),
    ));
    let e = if sum_w > 0.0 { sum_we / sum_w } else { Vec3::ZERO };
    notes.push(format!(
        "Σ w = {sum_w:.4} (covered from 1/a); E = Σ w·E / Σ w = ({:.4e}, {:.4e}, {:.4e}); f = ({:.4}, {:.4}, {:.4}) (c·DI/π, plus the specular lobe with gautron.receiver = Glossy); gautron.irradiance = ({:.4e}, {:.4e}, {:.4e})",
        e.x, e.y, e.z, c_di.x, c_di.y, c_di.z, header.irradiance.x, header.irradiance.y, header.irradiance.z
    ));
    notes.push(format!(
        "gradients: rotational {}, translational {} (E = E_k + the terms that are on, clamped at 0)",
        if info.rotational { "on" } else { "off" },
        if info.translational { "on" } else { "off" }
    ));
    if (made > 0 || refreshed > 0) && info.snapshots {
        notes.push(format!(
            "this frame made {made} records and computed {refreshed} stale ones again ({stale} wait); each record is \
             replayed as the splat that added it read it (the cache copied after each splat)"
        ));
    } else if made > 0 || refreshed > 0 {
        let mut why =
            format!("this frame made {made} records and computed {refreshed} stale ones again ({stale} wait)");
        if refreshed > 0 {
            why.push_str("; a record computed again (\"recomputed\") was splatted with its old E");
        }
        if made > 0 && info.neighbour_clamping {
            why.push_str("; neighbour clamping may have shrunk a cached record's R_k after its splat");
        }
        why.push_str(
            "; the replay reads the records as the frame left them, so the checks may differ (a frame \
             that makes none and computes none again replays exactly)",
        );
        notes.push(why);
    }
    if counters[0] as u64 > MAX_LISTED {
        notes.push(format!("{} records not listed (the list holds {MAX_LISTED})", counters[0] as u64 - MAX_LISTED));
    }
    let mut e = Explanation {
        pixel: info.pixel,
        technique: info.technique.clone(),
        contributions,
        buffer: "gautron.indirect".into(),
        value: v3(header.indirect),
        checks,
        notes,
    };
    e.sort();
    Some(e)
}
