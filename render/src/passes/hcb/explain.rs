//! Explain a pixel (issue #42) for the hierarchical coherence buffer (Nguyen et al. 000):
//! coherence-weighted splatting (§4.2–4.3; Eq. 8 the coherence error, Eq. 9 coherence as that
//! error at most 1, Eq. 10 the weight) and Eq. 11's normalisation, whatever lit the samples
//! (the VPL gather at the samples, §4.1; GI Lab's mixes: Soler's ring gather or Gautron's
//! hemispheres at the samples), with the sample cache (§5) or the confidence merge after it.
//! `shaders/hcb/explain.wgsl` replays every sample's splat at the pinned pixel through the
//! splat's own `splat_quad` and `splat_value` (`shaders/hcb/common.wgsl`), after the frame's
//! passes and in its encoder, and reads what the frame wrote there; [`decode`] turns it into
//! the pixel's contributions (each coherent sample's share w_s·E_s / Σ w × the receiver's
//! factor f: c·DI/π, plus the specular lobe's with `hcb.receiver = Glossy`), the
//! samples whose quad holds the pixel but which fail Eq. 9, and the checks of the sums
//! against `hcb.weight_sum`, `hcb.irradiance` and the stage's output `hcb.indirect`
//! (`crate::explain`). CPU twin of each weight: `cpu::hcb::weight` (tests/explain/hcb.rs).

use crate::counters::prelude::*;

use glam::{Vec3, Vec4};

use super::stage::HcbStage;
use crate::explain::{Check, Contribution, Explanation, Rejection, luminance};
use crate::gpu::GpuContext;
use crate::gpu::bindings::{Bindings, Kind, binding};
use crate::passes::knecht::temporal::TemporalPass;
use crate::passes::stages::FrameInputs;
use crate::passes::view;

/// Bind group `explain.hcb.inputs` of `shaders/hcb/explain.wgsl` (group 0).
pub const HCB_INPUTS_BINDINGS: Bindings = Bindings {
    label: "explain.hcb.inputs",
    shader: "hcb/explain.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "camera", Kind::Uniform),
        binding(1, "hp", Kind::Uniform),
        binding(2, "explain", Kind::Uniform),
        binding(3, "samples", Kind::Storage { read_only: true }),
        binding(4, "counter", Kind::Storage { read_only: true }),
        binding(5, "g_position", Kind::Texture { filterable: false }),
        binding(6, "g_normal", Kind::Texture { filterable: false }),
        binding(7, "g_albedo", Kind::Texture { filterable: false }),
        binding(8, "g_motion", Kind::Texture { filterable: false }),
        binding(9, "weight_sum", Kind::Texture { filterable: false }),
        binding(10, "irradiance", Kind::Texture { filterable: false }),
        binding(11, "indirect", Kind::Texture { filterable: false }),
        binding(12, "final_light", Kind::Texture { filterable: false }),
        binding(13, "confidence", Kind::Texture { filterable: false }),
        binding(14, "history_prev", Kind::Texture { filterable: false }),
        binding(15, "header", Kind::Storage { read_only: false }),
        binding(16, "tally", Kind::Storage { read_only: false }),
        binding(17, "entries", Kind::Storage { read_only: false }),
        binding(18, "weight_dir", Kind::Texture { filterable: false }),
        binding(19, "g_material", Kind::Texture { filterable: false }),
        binding(20, "split_prev", Kind::UintTexture),
    ],
};

/// Bind group `explain.hcb.args` of `shaders/hcb/explain.wgsl` (group 1).
pub const HCB_ARGS_BINDINGS: Bindings = Bindings {
    label: "explain.hcb.args",
    shader: "hcb/explain.wgsl",
    group: 1,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[binding(0, "args", Kind::Storage { read_only: false })],
};

/// Flags of a listed sample (`EXPLAIN_*` in the shader).
pub const COHERENT: u32 = 1;
pub const CACHED: u32 = 2;
pub const REGATHERED: u32 = 4;
pub const NEW: u32 = 8;

/// The fields of a sample's contribution: Eq. 8's distance, normal and pose errors, Eq. 10's
/// weight, the luminance of the sample's light E_s and its HCB level.
pub const E_DISTANCE: &str = "e_d";
pub const E_NORMAL: &str = "e_n";
pub const E_POSE: &str = "e_p";
pub const WEIGHT: &str = "w (Eq. 10)";
pub const LIGHT: &str = "E_s (lum)";
pub const LEVEL: &str = "level";

/// Byte offsets of the output buffer's parts (storage bindings start at multiples of 256):
/// the header, the tally, the listed samples.
const TALLY_OFFSET: u64 = 256;
const ENTRIES_OFFSET: u64 = 512;
/// Most samples listed (those whose quad holds the pixel: a few dozen at the shipped
/// thresholds; the header counts them all).
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
    /// Samples in the list, 0, the cached ones (§5.1), the re-gathered ones (§5.3).
    pub counts: [u32; 4],
    /// 1 when the pixel has a surface, 0, the pixel x, y.
    pub state: [u32; 4],
    /// `hcb.weight_sum`: rgb Σ w·E, a Σ w.
    pub weight_sum: Vec4,
    /// `hcb.irradiance` (Eq. 11).
    pub irradiance: Vec4,
    /// `hcb.indirect` (the stage's output).
    pub indirect: Vec4,
    /// rgb: the normalize pass's receiver factor f (c·DI/π, and the specular lobe's factor
    /// with the glossy receiver: `receiver_factor`).
    pub factor: Vec4,
    /// The confidence merge: rgb the history it read, a its confidence c.
    pub history: Vec4,
    /// The chain's last output (the pixel's indirect value).
    pub final_value: Vec4,
}

/// One sample whose quad holds the pixel; WGSL twin: `Entry`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuEntry {
    /// Index in the list, flags, texel.z (level in bits 0–7), G-buffer pixel x | y << 16.
    pub index: [u32; 4],
    /// xyz: world position, w: a^w.
    pub position: Vec4,
    /// Eq. 8's distance, normal and pose errors; w: Eq. 10's weight (−1: incoherent, Eq. 9).
    pub errors: Vec4,
    /// rgb: E_s; a: 1 once gathered.
    pub light: Vec4,
    /// Its splat's quad in NDC (x0, y0, x1, y1), for the overlay.
    pub quad: Vec4,
}

/// What the frame's HCB chain was, for [`decode`].
#[derive(Clone, Debug, PartialEq)]
pub struct HcbInfo {
    pub pixel: (u32, u32),
    /// The sample cache (§5) is stage 7's choice.
    pub cache: bool,
    /// The confidence merge (Knecht 002 §3.5, Eq. 3.6) ran after the splat.
    pub merge: bool,
    /// The buffer holding the pixel's indirect value (the chain's last output).
    pub buffer: String,
    pub technique: String,
}

pub struct HcbExplainPass {
    layout: wgpu::BindGroupLayout,
    args_layout: wgpu::BindGroupLayout,
    args_pipeline: wgpu::ComputePipeline,
    samples_pipeline: wgpu::ComputePipeline,
    /// The splat's uniform (`HcbParams`) and the pixel's (`ExplainParams`).
    hcb_params: wgpu::Buffer,
    params: wgpu::Buffer,
    /// Header, tally and the listed samples (`ENTRIES_OFFSET` + 64 bytes each).
    pub out: wgpu::Buffer,
    /// The dispatch over the samples (written by `cs_explain_args`), and what group 1 binds
    /// while that dispatch reads it.
    args: wgpu::Buffer,
    no_args: wgpu::Buffer,
    /// Stands for the confidence merge's textures when it did not run.
    dummy: wgpu::TextureView,
    /// Stands in for the demodulated merge's split history when it did not run.
    dummy_split: wgpu::TextureView,
    /// The last run's chain.
    pub info: Option<HcbInfo>,
}

impl crate::explain::Replay for HcbExplainPass {
    fn parts(&self) -> Option<Vec<(wgpu::Buffer, u64)>> {
        self.info.as_ref()?;
        Some(vec![(self.out.clone(), self.out.size())])
    }

    fn decode(&self, parts: &[Vec<u8>]) -> Option<Explanation> {
        let [out] = parts else { return None };
        decode(self.info.as_ref()?, out)
    }
}

impl HcbExplainPass {
    pub fn new(ctx: &GpuContext) -> Self {
        let device = &ctx.device;
        let layout = HCB_INPUTS_BINDINGS.layout(device);
        let args_layout = HCB_ARGS_BINDINGS.layout(device);
        let module = crate::shaders::create_module(device, "hcb/explain.wgsl");
        let layouts = [&layout, &args_layout];
        let args_pipeline =
            crate::passes::compute_pipeline(device, "explain.hcb.header", &module, "cs_explain_args", &layouts);
        let samples_pipeline =
            crate::passes::compute_pipeline(device, "explain.hcb.samples", &module, "cs_explain_samples", &layouts);
        let size = std::mem::size_of::<super::HcbParams>() as u64;
        let out = crate::passes::buffer(
            device,
            "explain.hcb.out",
            ENTRIES_OFFSET + MAX_LISTED * std::mem::size_of::<GpuEntry>() as u64,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        );
        let args = crate::passes::buffer(
            device,
            "explain.hcb.dispatch_args",
            16,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::INDIRECT,
        );
        let no_args = crate::passes::buffer(device, "explain.hcb.no_args", 16, wgpu::BufferUsages::STORAGE);
        let dummy = view(
            &crate::passes::create_target(
                device,
                "explain.hcb.none",
                1,
                1,
                wgpu::TextureFormat::Rgba32Float,
                wgpu::TextureUsages::empty(),
            ),
            "explain.hcb.none",
        );
        Self {
            layout,
            args_layout,
            args_pipeline,
            samples_pipeline,
            hcb_params: crate::passes::uniform_buffer(device, "explain.hcb.splat_params", size),
            params: crate::passes::uniform_buffer(
                device,
                "explain.hcb.params",
                std::mem::size_of::<ExplainParams>() as u64,
            ),
            out,
            args,
            no_args,
            dummy,
            dummy_split: crate::passes::knecht::temporal::no_split_view(device, "explain.hcb.no_split"),
            info: None,
        }
    }

    /// Records the replay of `info.pixel`'s splat into `enc`, after the frame's passes: the
    /// samples of `stage`'s list, the splat's sums, Eq. 11's output, the confidence merge's
    /// textures when `temporal` is given, and `last`, the chain's last output.
    pub fn run(
        &mut self,
        f: &FrameInputs,
        enc: &mut wgpu::CommandEncoder,
        stage: &HcbStage,
        temporal: Option<&TemporalPass>,
        last: &wgpu::TextureView,
        info: HcbInfo,
    ) {
        let ctx = f.ctx;
        ctx.queue.upload(&self.hcb_params, 0, bytemuck::bytes_of(&super::stage::HcbStage::frame(f).params([0; 4])));
        // w: 1 when the confidence merge ran, 2 when it ran demodulated (its history is split).
        let split_prev = temporal.and_then(|t| t.split_prev());
        let merge = match (temporal, split_prev) {
            (None, _) => 0,
            (Some(_), None) => 1,
            (Some(_), Some(_)) => 2,
        };
        let p = ExplainParams { pixel: [info.pixel.0, info.pixel.1, info.cache as u32, merge] };
        ctx.queue.upload(&self.params, 0, bytemuck::bytes_of(&p));
        let tv = wgpu::BindingResource::TextureView;
        let part = |offset, size| crate::passes::buffer_part(&self.out, offset, size);
        let g = f.gbuffer;
        let weight_sum = stage.splat.weight_sum_view();
        let weight_dir = view(stage.splat.weight_dir(), "hcb.weight_sum.direction");
        let irradiance = view(&stage.splat.irradiance, "hcb.irradiance");
        let indirect = view(&stage.splat.indirect, "hcb.indirect");
        let (confidence, history_prev) = match temporal {
            Some(t) => (view(&t.confidence, "temporal.confidence"), view(t.history_prev(), "temporal.history_prev")),
            None => (self.dummy.clone(), self.dummy.clone()),
        };
        let group = HCB_INPUTS_BINDINGS.group(
            &ctx.device,
            &self.layout,
            [
                f.camera_buffer.as_entire_binding(),
                self.hcb_params.as_entire_binding(),
                self.params.as_entire_binding(),
                stage.build.list.as_entire_binding(),
                stage.build.counter.as_entire_binding(),
                tv(&g.position),
                tv(&g.normal),
                tv(&g.albedo),
                tv(&g.motion),
                tv(&weight_sum),
                tv(&irradiance),
                tv(&indirect),
                tv(last),
                tv(&confidence),
                tv(&history_prev),
                part(0, Some(std::mem::size_of::<GpuHeader>() as u64)),
                part(TALLY_OFFSET, Some(16)),
                part(ENTRIES_OFFSET, None),
                tv(&weight_dir),
                tv(&g.material),
                tv(&split_prev.map_or(self.dummy_split.clone(), |t| view(t, "temporal.history_split_prev"))),
            ],
        );
        let args_group = HCB_ARGS_BINDINGS.group(&ctx.device, &self.args_layout, [self.args.as_entire_binding()]);
        let no_args = HCB_ARGS_BINDINGS.group_labelled(
            &ctx.device,
            "explain.hcb.no_args",
            &self.args_layout,
            [self.no_args.as_entire_binding()],
        );
        let mut pass =
            enc.begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("explain.hcb"), timestamp_writes: None });
        pass.set_group(0, &group, &[]);
        pass.set_group(1, &args_group, &[]);
        pass.set_pipe(&self.args_pipeline);
        pass.dispatch(1, 1, 1);
        // A buffer cannot be both storage and indirect arguments in one dispatch.
        pass.set_group(1, &no_args, &[]);
        pass.set_pipe(&self.samples_pipeline);
        pass.dispatch_indirect(&self.args, 0);
        drop(pass);
        self.info = Some(info);
    }
}

/// Where a listed sample stands and what the cache made of it.
fn source(e: &GpuEntry, cache: bool) -> String {
    let (x, y) = (e.index[3] & 0xffff, e.index[3] >> 16);
    let mut s = format!("level {} at ({x}, {y})", e.index[2] & 0xff);
    if cache {
        let flags = e.index[1];
        s += if flags & NEW != 0 {
            ", new"
        } else if flags & REGATHERED != 0 {
            ", cached, re-gathered"
        } else {
            ", cached"
        };
    }
    s
}

/// The pixel's explanation from the pass's output (the whole `out` buffer).
pub fn decode(info: &HcbInfo, bytes: &[u8]) -> Option<Explanation> {
    let header: GpuHeader = bytemuck::pod_read_unaligned(bytes.get(..std::mem::size_of::<GpuHeader>())?);
    if (header.state[2], header.state[3]) != info.pixel {
        return None;
    }
    let tally: u32 = bytemuck::pod_read_unaligned(bytes.get(TALLY_OFFSET as usize..TALLY_OFFSET as usize + 4)?);
    let size = std::mem::size_of::<GpuEntry>();
    let listed = (tally as usize).min(MAX_LISTED as usize);
    let entry_bytes = bytes.get(ENTRIES_OFFSET as usize..ENTRIES_OFFSET as usize + listed * size)?;
    let mut entries: Vec<GpuEntry> = bytemuck::pod_collect_to_vec(entry_bytes);
    // The splat adds the samples in increasing index (the blending's order and the binned
    // splat's): so do the sums here.
    entries.sort_by_key(|e| e.index[0]);
    let v3 = |v: Vec4| v.truncate();
    let coherent = |e: &&GpuEntry| e.index[1] & COHERENT != 0;
    let (mut sum_w, mut sum_we) = (0.0f32, Vec3::ZERO);
    for e in entries.iter().filter(coherent) {
        sum_w += e.errors.w;
        sum_we += e.errors.w * v3(e.light);
    }
    let factor = v3(header.factor);
    // Eq. 3.6: I = c · I_prev + (1 − c) · I_new (the history's share c, when it merged).
    let c = if info.merge { header.history.w } else { 0.0 };
    let p = info.pixel;
    let mut contributions: Vec<Contribution> = entries
        .iter()
        .map(|e| {
            let w = e.errors.w;
            let ok = e.index[1] & COHERENT != 0;
            let share = if ok && sum_w > 0.0 { w / sum_w } else { 0.0 };
            let mut fields = vec![
                (E_DISTANCE, e.errors.x),
                (E_NORMAL, e.errors.y),
                (E_POSE, e.errors.z),
                (WEIGHT, if ok { w } else { 0.0 }),
                (LIGHT, luminance(v3(e.light))),
                (LEVEL, (e.index[2] & 0xff) as f32),
                ("a^w", e.position.w),
                // The splat's quad in NDC (the overlay draws it).
                ("quad x0 (NDC)", e.quad.x),
                ("quad y0 (NDC)", e.quad.y),
                ("quad x1 (NDC)", e.quad.z),
                ("quad y1 (NDC)", e.quad.w),
            ];
            if e.light.w < 0.5 {
                fields.push(("not gathered", 1.0));
            }
            Contribution {
                name: format!("sample {}", e.index[0]),
                source: source(e, info.cache),
                position: Some(v3(e.position)),
                value: if ok && sum_w > 0.0 { factor * (w * v3(e.light)) / sum_w * (1.0 - c) } else { Vec3::ZERO },
                weight: share * (1.0 - c),
                rejected: (!ok).then_some(Rejection::Incoherent),
                via: None,
                fields,
            }
        })
        .collect();
    if info.merge && c > 0.0 {
        contributions.push(Contribution {
            name: "history".into(),
            source: "previous frame (reprojected)".into(),
            position: None,
            value: v3(header.history) * c,
            weight: c,
            rejected: None,
            via: None,
            fields: vec![("c", c)],
        });
    }
    let at = format!("at ({}, {})", p.0, p.1);
    let ws = header.weight_sum;
    let mut checks = vec![
        Check { what: format!("Σ w·E_s {at}"), sum: sum_we, buffer: "hcb.weight_sum (rgb)".into(), value: v3(ws) },
        Check {
            what: format!("Σ w {at}"),
            sum: Vec3::splat(sum_w),
            buffer: "hcb.weight_sum (a)".into(),
            value: Vec3::splat(ws.w),
        },
    ];
    let normalized = if sum_w > 0.0 { sum_we / sum_w } else { Vec3::ZERO };
    checks.push(Check {
        what: "Σ w·E_s / Σ w (Eq. 11)".into(),
        sum: normalized,
        buffer: "hcb.irradiance".into(),
        value: v3(header.irradiance),
    });
    if info.merge {
        checks.push(Check {
            what: "f · Σ w·E_s / Σ w (f: the receiver's factor)".into(),
            sum: factor * normalized,
            buffer: "hcb.indirect".into(),
            value: v3(header.indirect),
        });
    }
    let accepted = entries.iter().filter(coherent).count();
    let mut notes = Vec::new();
    if header.state[0] == 0 {
        notes.push("the pixel has no surface: the splat adds nothing there".into());
    }
    let mut counts = format!("{} samples in the list", header.counts[0]);
    if info.cache {
        let (cached, regathered) = (header.counts[2], header.counts[3]);
        counts += &format!(
            " ({cached} cached, {regathered} of them re-gathered, {} new; §5)",
            header.counts[0].saturating_sub(cached)
        );
    }
    notes.push(format!(
        "{counts}; the quads of {tally} hold the pixel, {accepted} of them coherent to it (Eq. 9: max error ≤ 1)"
    ));
    notes.push("e_d, e_n, e_p: Eq. 8's distance, normal and pose errors; w = (1 − e_d)(1 − e_n)(1 − e_p)".into());
    if tally as u64 > MAX_LISTED {
        notes.push(format!("only the first {MAX_LISTED} of them are listed: the sums are partial"));
    }
    if header.state[0] != 0 && sum_w <= 0.0 {
        notes.push("no sample is coherent to the pixel: it is uncovered (hcb.irradiance a = 0)".into());
    }
    notes.push(format!(
        "Σ w = {:.6} (Eq. 11 divides by it); f = ({:.4}, {:.4}, {:.4}) (normalize's reflection: c·DI/π, plus the specular lobe lit from the samples' mean direction with hcb.receiver = Glossy)",
        sum_w, factor.x, factor.y, factor.z
    ));
    if info.merge {
        notes.push(format!("confidence merge (Eq. 3.6): c = {c:.4} at the pixel (the history's share)"));
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
