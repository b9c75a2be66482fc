//! Explain a pixel (issue #42) for the VPL gather at tiles or at every pixel (Knecht 002
//! §3.4.1, §4.5), the geometry-aware filter after it (§3.4.1, Eq. 4.2) and the confidence
//! merge (§3.5, Eq. 3.6), in either `temporal.order`. `shaders/knecht/interleave/explain.wgsl`
//! replays every VPL slot's term at the pixel of the filter's window that its tile reached,
//! with the frame's own inputs, and reads the buffers the frame wrote there; [`decode`] turns
//! that into the pixel's contributions and checks (`crate::explain`). CPU twin of each term:
//! `cpu::knecht::vpl_radiance` (tests/explain/vpl.rs).

use crate::counters::prelude::*;

use glam::{Vec3, Vec4};

use crate::explain::{Check, Contribution, Explanation, Rejection};
use crate::gpu::GpuContext;
use crate::gpu::bindings::{Bindings, Kind, binding};
use crate::passes::gbuffer::GBufferViews;
use crate::passes::knecht::interleave::InterleavePass;
use crate::passes::knecht::temporal::{MergeOrder, TemporalPass};
use crate::passes::reference::explain::{BACKGROUND, EMPTY, FILTERED, GpuTerm, OUTSIDE, term_fields, term_rejection};
use crate::passes::reference::vpl::GpuVpl;
use crate::passes::reference::vpl_visibility::GatherVisibility;

/// Bind group `explain.vpl.inputs` of `shaders/knecht/interleave/explain.wgsl` (group 0).
pub const VPL_INPUTS_BINDINGS: Bindings = Bindings {
    label: "explain.vpl.inputs",
    shader: "knecht/interleave/explain.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "camera", Kind::Uniform),
        binding(1, "params", Kind::Uniform),
        binding(2, "vpls", Kind::Storage { read_only: true }),
        binding(3, "ism_atlas", Kind::Texture { filterable: false }),
        binding(4, "exact_atlas", Kind::Texture { filterable: false }),
        binding(5, "g_position", Kind::Texture { filterable: false }),
        binding(6, "g_normal", Kind::Texture { filterable: false }),
        binding(7, "g_albedo", Kind::Texture { filterable: false }),
        binding(8, "g_material", Kind::Texture { filterable: false }),
        binding(9, "tile_offsets", Kind::Storage { read_only: true }),
        binding(10, "explain", Kind::Uniform),
        binding(11, "merged", Kind::Texture { filterable: false }),
        binding(12, "filtered", Kind::Texture { filterable: false }),
        binding(13, "confidence", Kind::Texture { filterable: false }),
        binding(14, "history_prev", Kind::Texture { filterable: false }),
        binding(15, "history_out", Kind::Texture { filterable: false }),
        binding(16, "g_motion", Kind::Texture { filterable: false }),
        binding(17, "final_light", Kind::Texture { filterable: false }),
        binding(18, "header", Kind::Storage { read_only: false }),
        binding(19, "window", Kind::Storage { read_only: false }),
        binding(20, "terms", Kind::Storage { read_only: false }),
        binding(21, "split_prev", Kind::UintTexture),
    ],
};

/// Flags of a window pixel (`EXPLAIN_W_*`).
pub const W_INSIDE: u32 = 1;
pub const W_ACCEPTED: u32 = 2;

/// Byte offsets of the output buffer's parts (storage bindings start at multiples of 256).
const WINDOW_OFFSET: u64 = 256;
const WINDOW_PIXELS: u64 = 64;
const TERMS_OFFSET: u64 = WINDOW_OFFSET + WINDOW_PIXELS * 64;

/// WGSL twin: `ExplainParams`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
struct ExplainParams {
    pixel: [u32; 4],
    thresholds: Vec4,
}

/// One pixel of the filter's window; WGSL twin: `WindowPixel`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuWindow {
    pub pixel: [u32; 4],
    pub merged: Vec4,
    pub history: Vec4,
    pub out: Vec4,
}

/// WGSL twin: `Header`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuHeader {
    pub final_value: Vec4,
    pub filtered: Vec4,
    pub counts: [u32; 4],
    pub pad: [u32; 4],
}

/// What the frame's VPL gather chain was, for [`decode`].
#[derive(Clone, Debug, PartialEq)]
pub struct ChainInfo {
    pub pixel: (u32, u32),
    pub count: u32,
    pub filter: bool,
    /// The filter ran demodulated (`interleave.demodulate`, on this frame's gather).
    pub demodulated: bool,
    /// The confidence merge ran, in this order with the filter.
    pub temporal: Option<MergeOrder>,
    /// The buffer holding the pixel's indirect value (the chain's last output).
    pub buffer: String,
    /// Slot ranges and their sources (`stages::VplSet::sources`).
    pub sources: Vec<(u32, u32, String)>,
    pub technique: String,
}

/// What the explain pass reads of the frame.
pub struct ExplainInputs<'a> {
    pub pixel: (u32, u32),
    pub camera: &'a wgpu::Buffer,
    pub g: &'a GBufferViews,
    pub interleave: &'a InterleavePass,
    pub vpls: &'a wgpu::Buffer,
    pub vis: &'a GatherVisibility,
    /// (α · (z_far − z_near), β) when the geometry-aware filter ran.
    pub filter: Option<(f32, f32)>,
    /// The filter ran demodulated (`ChainInfo::demodulated`).
    pub demodulated: bool,
    pub temporal: Option<&'a TemporalPass>,
    /// The chain's last output (the pixel's indirect value).
    pub last: &'a wgpu::TextureView,
}

pub struct VplExplainPass {
    layout: wgpu::BindGroupLayout,
    pixel_pipeline: wgpu::ComputePipeline,
    vpl_pipeline: wgpu::ComputePipeline,
    params: wgpu::Buffer,
    /// Header, window and terms (`TERMS_OFFSET` + 64 bytes per slot).
    pub out: wgpu::Buffer,
    dummy: wgpu::TextureView,
    /// Stands in for the demodulated merge's split history when it did not run.
    dummy_split: wgpu::TextureView,
    dummy_ism: wgpu::TextureView,
    dummy_exact: wgpu::TextureView,
    /// The last run's chain, and its slot count.
    pub info: Option<ChainInfo>,
    /// The last run's VPL list.
    vpls: Option<wgpu::Buffer>,
}

impl crate::explain::Replay for VplExplainPass {
    fn parts(&self) -> Option<Vec<(wgpu::Buffer, u64)>> {
        let (info, vpls) = (self.info.as_ref()?, self.vpls.as_ref()?);
        let list = (info.count as u64 * std::mem::size_of::<GpuVpl>() as u64).min(vpls.size());
        Some(vec![(self.out.clone(), self.bytes()), (vpls.clone(), list)])
    }

    fn decode(&self, parts: &[Vec<u8>]) -> Option<Explanation> {
        let [out, list] = parts else { return None };
        decode(self.info.as_ref()?, out, &bytemuck::pod_collect_to_vec::<u8, GpuVpl>(list))
    }
}

impl VplExplainPass {
    pub fn new(ctx: &GpuContext) -> Self {
        let device = &ctx.device;
        let layout = VPL_INPUTS_BINDINGS.layout(device);
        let module = crate::shaders::create_module(device, "knecht/interleave/explain.wgsl");
        let pipeline = |label, entry| crate::passes::compute_pipeline(device, label, &module, entry, &[&layout]);
        let (dummy_ism, dummy_exact) =
            crate::passes::reference::vpl_visibility::no_visibility_atlases(device, "explain.vpl");
        let dummy = crate::passes::view(
            &crate::passes::create_target(
                device,
                "explain.vpl.none",
                1,
                1,
                wgpu::TextureFormat::Rgba32Float,
                wgpu::TextureUsages::empty(),
            ),
            "explain.vpl.none",
        );
        Self {
            pixel_pipeline: pipeline("explain.vpl.pixel", "cs_explain_pixel"),
            vpl_pipeline: pipeline("explain.vpl.terms", "cs_explain_vpls"),
            layout,
            params: crate::passes::uniform_buffer(
                device,
                "explain.vpl.params",
                std::mem::size_of::<ExplainParams>() as u64,
            ),
            out: Self::out_buffer(device, 256),
            dummy,
            dummy_split: crate::passes::knecht::temporal::no_split_view(device, "explain.vpl.no_split"),
            dummy_ism,
            dummy_exact,
            info: None,
            vpls: None,
        }
    }

    fn out_buffer(device: &wgpu::Device, slots: u32) -> wgpu::Buffer {
        device.counted_buffer(&wgpu::BufferDescriptor {
            label: Some("explain.vpl.out"),
            size: TERMS_OFFSET + slots.max(1) as u64 * std::mem::size_of::<GpuTerm>() as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        })
    }

    /// The bytes a read-back of the last run needs.
    pub fn bytes(&self) -> u64 {
        let slots = self.info.as_ref().map(|i| i.count).unwrap_or(0) as u64;
        (TERMS_OFFSET + slots * std::mem::size_of::<GpuTerm>() as u64).min(self.out.size())
    }

    /// Records the replay of `inp.pixel` into `enc`, after the frame's passes.
    pub fn run(&mut self, ctx: &GpuContext, enc: &mut wgpu::CommandEncoder, inp: &ExplainInputs, info: ChainInfo) {
        let count = info.count;
        if TERMS_OFFSET + count.max(1) as u64 * std::mem::size_of::<GpuTerm>() as u64 > self.out.size() {
            self.out = Self::out_buffer(&ctx.device, count.next_power_of_two());
        }
        let window = match inp.filter {
            Some(_) => inp.interleave.n().clamp(1, 8),
            None => 1,
        };
        let (alpha, beta) = inp.filter.unwrap_or((0.0, 0.0));
        // The demodulated merge read a split history (E, S) instead of `temporal.history_prev`.
        let split_prev = inp.temporal.and_then(|t| t.split_prev());
        let p = ExplainParams {
            pixel: [inp.pixel.0, inp.pixel.1, window, inp.temporal.is_some() as u32],
            thresholds: Vec4::new(alpha, beta, inp.demodulated as u32 as f32, split_prev.is_some() as u32 as f32),
        };
        ctx.queue.upload(&self.params, 0, bytemuck::bytes_of(&p));
        let (_, ism, exact, _, _, _) = inp.vis.parts(&self.dummy_ism, &self.dummy_exact);
        let v = |t: &wgpu::Texture, l: &str| crate::passes::view(t, l);
        let filtered = v(&inp.interleave.filtered, "indirect.filtered");
        let merged = v(&inp.interleave.merged, "indirect.merged");
        let (confidence, prev, out) = match inp.temporal {
            Some(t) => (
                v(&t.confidence, "temporal.confidence"),
                v(t.history_prev(), "temporal.history_prev"),
                v(t.history(), "temporal.history"),
            ),
            None => (self.dummy.clone(), self.dummy.clone(), self.dummy.clone()),
        };
        let tv = wgpu::BindingResource::TextureView;
        let part = |offset, size| crate::passes::buffer_part(&self.out, offset, size);
        let group = VPL_INPUTS_BINDINGS.group(
            &ctx.device,
            &self.layout,
            [
                inp.camera.as_entire_binding(),
                inp.interleave.gather_params().as_entire_binding(),
                inp.vpls.as_entire_binding(),
                tv(ism),
                tv(exact),
                tv(&inp.g.position),
                tv(&inp.g.normal),
                tv(&inp.g.albedo),
                tv(&inp.g.material),
                inp.interleave.tile_offsets().as_entire_binding(),
                self.params.as_entire_binding(),
                tv(&merged),
                tv(&filtered),
                tv(&confidence),
                tv(&prev),
                tv(&out),
                tv(&inp.g.motion),
                tv(inp.last),
                part(0, Some(std::mem::size_of::<GpuHeader>() as u64)),
                part(WINDOW_OFFSET, Some(WINDOW_PIXELS * 64)),
                part(TERMS_OFFSET, None),
                tv(&split_prev.map_or(self.dummy_split.clone(), |t| v(t, "temporal.history_split_prev"))),
            ],
        );
        let mut pass =
            enc.begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("explain.vpl"), timestamp_writes: None });
        pass.set_bind_group(0, &group, &[]);
        pass.set_pipe(&self.pixel_pipeline);
        pass.dispatch(1, 1, 1);
        if count > 0 {
            pass.set_pipe(&self.vpl_pipeline);
            pass.dispatch(count.div_ceil(64), 1, 1);
        }
        drop(pass);
        self.info = Some(info);
        self.vpls = Some(inp.vpls.clone());
    }
}

/// The source of slot `k` (`ChainInfo::sources`).
fn source_of(sources: &[(u32, u32, String)], k: u32) -> String {
    sources
        .iter()
        .find(|(first, count, _)| (*first..first + count).contains(&k))
        .map(|(_, _, s)| s.clone())
        .unwrap_or_else(|| "—".into())
}

/// The pixel's explanation from the pass's output (`bytes`, as [`VplExplainPass::bytes`]
/// asks) and the frame's VPL list (`vpls`, every slot).
pub fn decode(info: &ChainInfo, bytes: &[u8], vpls: &[GpuVpl]) -> Option<Explanation> {
    let header: GpuHeader = bytemuck::pod_read_unaligned(bytes.get(..std::mem::size_of::<GpuHeader>())?);
    let window: Vec<GpuWindow> =
        bytemuck::pod_collect_to_vec(bytes.get(WINDOW_OFFSET as usize..(WINDOW_OFFSET + WINDOW_PIXELS * 64) as usize)?);
    let term_bytes = bytes.get(TERMS_OFFSET as usize..)?;
    let size = std::mem::size_of::<GpuTerm>();
    let terms: Vec<GpuTerm> = bytemuck::pod_collect_to_vec(
        term_bytes.get(..(info.count as usize * size).min(term_bytes.len() / size * size))?,
    );
    if terms.len() != info.count as usize || header.counts[0] != info.count {
        return None;
    }
    let side = header.counts[3].max(1);
    let window = &window[..(side * side) as usize];
    let p = info.pixel;
    let at = |q: (u32, u32)| window.iter().find(|w| (w.pixel[0], w.pixel[1]) == q && w.pixel[2] & W_INSIDE != 0);
    let centre = at(p)?;
    let accepted: Vec<&GpuWindow> = window.iter().filter(|w| w.pixel[2] & W_ACCEPTED != 0).collect();
    let m = if info.filter { accepted.len().max(1) as f32 } else { 1.0 };
    let c_p = centre.history.w;
    let v3 = |v: Vec4| v.truncate();
    let mut contributions = Vec::new();
    // Each term's weight from its light to the pixel.
    let weight = |q: &GpuWindow| {
        let merge = match info.temporal {
            Some(MergeOrder::FilterThenMerge) => 1.0 - c_p,
            Some(MergeOrder::MergeThenFilter) => 1.0 - q.history.w,
            None => 1.0,
        };
        merge / m
    };
    let mut per_pixel: Vec<((u32, u32), Vec3)> = Vec::new();
    for t in &terms {
        let flags = t.slot[1];
        if flags & EMPTY != 0 || (side == 1 && flags & OUTSIDE != 0) {
            continue;
        }
        let k = t.slot[0];
        let q = (t.slot[2] & 0xffff, t.slot[2] >> 16);
        let vpl = vpls.get(k as usize)?;
        let rejected = if flags & (OUTSIDE | BACKGROUND) != 0 {
            Some(Rejection::Outside)
        } else {
            // A term the filter leaves out still counts at q: its own reason first.
            term_rejection(flags).or((flags & FILTERED != 0).then_some(Rejection::Filter))
        };
        let w = at(q).map(weight).unwrap_or(0.0);
        // The tile's N / N_t (gather.wgsl's scale; the window pixel's merged.a is its N_t).
        let scale = at(q).map(|x| info.count as f32 / x.merged.w.max(1.0)).unwrap_or(0.0);
        if flags & (OUTSIDE | BACKGROUND) == 0 {
            match per_pixel.iter_mut().find(|(x, _)| *x == q) {
                Some((_, s)) => *s += v3(t.light),
                None => per_pixel.push((q, v3(t.light))),
            }
        }
        let mut fields = term_fields(vpl, t);
        fields.insert(5, ("N/N_t", scale));
        contributions.push(Contribution {
            name: format!("VPL {k}"),
            source: source_of(&info.sources, k),
            position: Some(v3(vpl.position)),
            value: if rejected.is_some() { Vec3::ZERO } else { v3(t.reach) * w },
            weight: w,
            rejected,
            via: (q != p).then_some(q),
            fields,
        });
    }
    // The history's share (Eq. 3.6: I = c · I_prev + (1 − c) · I_new).
    match info.temporal {
        Some(MergeOrder::FilterThenMerge) => contributions.push(history_row(centre, 1.0, None)),
        Some(MergeOrder::MergeThenFilter) => {
            for q in &accepted {
                let qp = (q.pixel[0], q.pixel[1]);
                contributions.push(history_row(q, 1.0 / m, (qp != p).then_some(qp)));
            }
        }
        None => {}
    }
    let mut checks = Vec::new();
    if let Some((_, s)) = per_pixel.iter().find(|(q, _)| *q == p) {
        checks.push(Check {
            what: format!("Σ VPL terms at ({}, {})", p.0, p.1),
            sum: *s,
            buffer: "indirect.merged".into(),
            value: v3(centre.merged),
        });
    }
    // The worst of the window's other pixels (each its own tile's sum).
    if let Some((q, s, v)) =
        per_pixel.iter().filter(|(q, _)| *q != p).filter_map(|(q, s)| Some((*q, *s, v3(at(*q)?.merged)))).max_by(
            |a, b| {
                let e = |x: &(_, Vec3, Vec3)| (x.1 - x.2).abs().max_element();
                e(a).total_cmp(&e(b))
            },
        )
    {
        checks.push(Check {
            what: format!("Σ VPL terms at ({}, {}), the window's worst", q.0, q.1),
            sum: s,
            buffer: "indirect.merged".into(),
            value: v,
        });
    }
    if info.demodulated {
        // Each accepted pixel's terms reflected with the pixel's colour (the filter's
        // k_p·mean(E) + mean(L − k·E)).
        let accepted_terms = terms.iter().filter(|t| t.slot[1] & (EMPTY | OUTSIDE | BACKGROUND | FILTERED) == 0);
        checks.push(Check {
            what: format!("Σ VPL terms of the window's {} accepted pixels, demodulated, / {m}", accepted.len()),
            sum: accepted_terms.map(|t| v3(t.reach)).sum::<Vec3>() / m,
            buffer: "indirect.filtered".into(),
            value: v3(header.filtered),
        });
    } else if info.filter && info.temporal != Some(MergeOrder::MergeThenFilter) {
        let mean: Vec3 = accepted.iter().map(|q| v3(q.merged)).sum::<Vec3>() / m;
        checks.push(Check {
            what: format!("mean of the window's {} accepted merged pixels", accepted.len()),
            sum: mean,
            buffer: "indirect.filtered".into(),
            value: v3(header.filtered),
        });
    }
    let mut notes = vec![format!(
        "N = {} VPL slots; the pixel's tile {} gathers N_t = {} of them, scaled by N / N_t",
        header.counts[0], centre.pixel[3], header.counts[1]
    )];
    if info.filter {
        notes.push(format!(
            "geometry-aware filter: {} of the {}×{} window's pixels on the pixel's surface (weight 1/{})",
            accepted.len(),
            side,
            side,
            accepted.len()
        ));
    }
    if info.demodulated {
        notes.push(
            "demodulated: each term's irradiance is reflected with this pixel's colour, its specular light with its own pixel's"
                .into(),
        );
    }
    if info.temporal.is_some() {
        notes.push(format!("confidence merge (Eq. 3.6): c = {c_p:.4} at the pixel (the history's share)"));
    }
    let mut e = Explanation {
        pixel: p,
        technique: info.technique.clone(),
        contributions,
        buffer: info.buffer.clone(),
        value: v3(header.final_value),
        checks,
        notes,
    };
    e.sort();
    Some(e)
}

fn history_row(q: &GpuWindow, scale: f32, via: Option<(u32, u32)>) -> Contribution {
    let c = q.history.w;
    Contribution {
        name: "history".into(),
        source: "previous frame (reprojected)".into(),
        position: None,
        value: q.history.truncate() * c * scale,
        weight: c * scale,
        rejected: None,
        via,
        fields: vec![("c", c)],
    }
}
