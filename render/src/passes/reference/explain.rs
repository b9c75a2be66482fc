//! Explain a pixel (issue #42) for the exact-VPL reference: `shaders/reference/explain.wgsl` reads
//! the running average before this frame's gather, then replays the batch's VPL terms at the
//! pixel with the gather's own functions and uniform (Knecht 002 Eq. 4.7–4.9, full BRDF, exact
//! visibility) and reads what the gather wrote; [`decode`] makes each VPL's share (its light
//! × 1/(k+1)) and the previous batches' share (k/(k+1) × their average).

use crate::counters::prelude::*;

use glam::{Vec3, Vec4};

use crate::explain::{Check, Contribution, Explanation, Rejection, Replay};
use crate::gpu::GpuContext;
use crate::gpu::bindings::{Bindings, Kind, binding};
use crate::passes::gbuffer::GBufferViews;
use crate::passes::reference::vpl::GpuVpl;
use crate::passes::reference::vpl_gather::VplGatherPass;

/// Bind group `explain.reference.inputs` of `shaders/reference/explain.wgsl` (group 0).
pub const REFERENCE_INPUTS_BINDINGS: Bindings = Bindings {
    label: "explain.reference.inputs",
    shader: "reference/explain.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "camera", Kind::Uniform),
        binding(1, "params", Kind::Uniform),
        binding(2, "vpls", Kind::Storage { read_only: true }),
        binding(3, "atlas", Kind::Texture { filterable: false }),
        binding(4, "g_position", Kind::Texture { filterable: false }),
        binding(5, "g_normal", Kind::Texture { filterable: false }),
        binding(6, "g_albedo", Kind::Texture { filterable: false }),
        binding(7, "g_material", Kind::Texture { filterable: false }),
        binding(8, "accum", Kind::Texture { filterable: false }),
        binding(9, "raw", Kind::Texture { filterable: false }),
        binding(10, "header", Kind::Storage { read_only: false }),
        binding(11, "terms", Kind::Storage { read_only: false }),
    ],
};

/// Flags of a term (`EXPLAIN_*` in `shaders/common/vpl_explain.wgsl`).
pub const EMPTY: u32 = 1;
pub const OUTSIDE: u32 = 2;
pub const FACING: u32 = 4;
pub const NEAR: u32 = 8;
pub const OCCLUDED: u32 = 16;
pub const FILTERED: u32 = 32;
pub const CLAMPED: u32 = 64;
pub const BACKGROUND: u32 = 128;
/// One VPL slot's term, as the VPL gathers' replays write it (Knecht's and this reference's);
/// WGSL twin: `VplTerm` (`shaders/common/vpl_explain.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuTerm {
    pub slot: [u32; 4],
    pub light: Vec4,
    pub unshadowed: Vec4,
    pub detail: Vec4,
    /// rgb: its light as it reaches the pinned pixel (after the demodulated filter: reflected
    /// with that pixel's colour; else `light`).
    pub reach: Vec4,
}

const TERMS_OFFSET: u64 = 256;

/// WGSL twin: `Header`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuHeader {
    pub pixel: [u32; 4],
    pub prev: Vec4,
    pub raw: Vec4,
    pub accum: Vec4,
}

/// What decode needs of the run.
#[derive(Clone, Debug, PartialEq)]
pub struct ReferenceRun {
    pub pixel: (u32, u32),
    pub count: u32,
    /// The batch's index k (its weight is 1/(k+1)).
    pub batch: u32,
    pub technique: String,
}

/// What the replay reads of the frame.
pub struct ReferenceInputs<'a> {
    pub camera: &'a wgpu::Buffer,
    pub g: &'a GBufferViews,
    pub gather: &'a VplGatherPass,
    pub vpls: &'a wgpu::Buffer,
    pub atlas: &'a wgpu::TextureView,
}

pub struct ReferenceExplainPass {
    layout: wgpu::BindGroupLayout,
    before: wgpu::ComputePipeline,
    terms: wgpu::ComputePipeline,
    after: wgpu::ComputePipeline,
    pub out: wgpu::Buffer,
    pub info: Option<ReferenceRun>,
    vpls: Option<wgpu::Buffer>,
}

impl ReferenceExplainPass {
    pub fn new(ctx: &GpuContext) -> Self {
        let device = &ctx.device;
        let layout = REFERENCE_INPUTS_BINDINGS.layout(device);
        let module = crate::shaders::create_module(device, "reference/explain.wgsl");
        let pipeline = |label, entry| crate::passes::compute_pipeline(device, label, &module, entry, &[&layout]);
        Self {
            before: pipeline("explain.reference.before", "cs_explain_before"),
            terms: pipeline("explain.reference.terms", "cs_explain_terms"),
            after: pipeline("explain.reference.after", "cs_explain_after"),
            layout,
            out: Self::out_buffer(device, 256),
            info: None,
            vpls: None,
        }
    }

    fn out_buffer(device: &wgpu::Device, slots: u32) -> wgpu::Buffer {
        device.counted_buffer(&wgpu::BufferDescriptor {
            label: Some("explain.reference.out"),
            size: TERMS_OFFSET + slots.max(1) as u64 * std::mem::size_of::<GpuTerm>() as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        })
    }

    fn group(&self, ctx: &GpuContext, inp: &ReferenceInputs) -> wgpu::BindGroup {
        let raw = crate::passes::view(&inp.gather.raw, "indirect.raw");
        let accum = crate::passes::view(&inp.gather.accum, "indirect.accum");
        let tv = wgpu::BindingResource::TextureView;
        let part = |offset, size| crate::passes::buffer_part(&self.out, offset, size);
        REFERENCE_INPUTS_BINDINGS.group(
            &ctx.device,
            &self.layout,
            [
                inp.camera.as_entire_binding(),
                inp.gather.params().as_entire_binding(),
                inp.vpls.as_entire_binding(),
                tv(inp.atlas),
                tv(&inp.g.position),
                tv(&inp.g.normal),
                tv(&inp.g.albedo),
                tv(&inp.g.material),
                tv(&accum),
                tv(&raw),
                part(0, Some(std::mem::size_of::<GpuHeader>() as u64)),
                part(TERMS_OFFSET, None),
            ],
        )
    }

    fn dispatch(enc: &mut wgpu::CommandEncoder, pipeline: &wgpu::ComputePipeline, group: &wgpu::BindGroup, n: u32) {
        let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("explain.reference"),
            timestamp_writes: None,
        });
        pass.set_pipe(pipeline);
        pass.set_bind_group(0, group, &[]);
        pass.dispatch(n, 1, 1);
    }

    /// Before the gather: the pixel, and the average the gather is about to fold into.
    pub fn run_before(
        &mut self,
        ctx: &GpuContext,
        enc: &mut wgpu::CommandEncoder,
        inp: &ReferenceInputs,
        run: ReferenceRun,
    ) {
        if TERMS_OFFSET + run.count.max(1) as u64 * std::mem::size_of::<GpuTerm>() as u64 > self.out.size() {
            self.out = Self::out_buffer(&ctx.device, run.count.next_power_of_two());
        }
        let header = GpuHeader { pixel: [run.pixel.0, run.pixel.1, 0, 0], ..bytemuck::Zeroable::zeroed() };
        ctx.queue.upload(&self.out, 0, bytemuck::bytes_of(&header));
        let group = self.group(ctx, inp);
        Self::dispatch(enc, &self.before, &group, 1);
        self.info = Some(run);
        self.vpls = Some(inp.vpls.clone());
    }

    /// After the gather: the batch's terms and what the gather wrote.
    pub fn run_after(&mut self, ctx: &GpuContext, enc: &mut wgpu::CommandEncoder, inp: &ReferenceInputs) {
        let Some(count) = self.info.as_ref().map(|i| i.count) else { return };
        let group = self.group(ctx, inp);
        if count > 0 {
            Self::dispatch(enc, &self.terms, &group, count.div_ceil(64));
        }
        Self::dispatch(enc, &self.after, &group, 1);
    }
}

impl Replay for ReferenceExplainPass {
    fn parts(&self) -> Option<Vec<(wgpu::Buffer, u64)>> {
        let (info, vpls) = (self.info.as_ref()?, self.vpls.as_ref()?);
        let size = std::mem::size_of::<GpuTerm>() as u64;
        let list = (info.count as u64 * std::mem::size_of::<GpuVpl>() as u64).min(vpls.size());
        Some(vec![(self.out.clone(), TERMS_OFFSET + info.count as u64 * size), (vpls.clone(), list)])
    }

    fn decode(&self, parts: &[Vec<u8>]) -> Option<Explanation> {
        let [out, list] = parts else { return None };
        decode(self.info.as_ref()?, out, &bytemuck::pod_collect_to_vec::<u8, GpuVpl>(list))
    }
}

/// The pixel's explanation from the replay's output and the batch's VPL list.
pub fn decode(info: &ReferenceRun, bytes: &[u8], vpls: &[GpuVpl]) -> Option<Explanation> {
    let header: GpuHeader = bytemuck::pod_read_unaligned(bytes.get(..std::mem::size_of::<GpuHeader>())?);
    if (header.pixel[0], header.pixel[1]) != info.pixel || header.pixel[2] != info.count {
        return None;
    }
    let size = std::mem::size_of::<GpuTerm>();
    let terms: Vec<GpuTerm> = bytemuck::pod_collect_to_vec(
        bytes.get(TERMS_OFFSET as usize..TERMS_OFFSET as usize + info.count as usize * size)?,
    );
    let v3 = |v: Vec4| v.truncate();
    let w = header.accum.w;
    let mut contributions = Vec::new();
    let mut sum = Vec3::ZERO;
    for t in &terms {
        let flags = t.slot[1];
        if flags & EMPTY != 0 {
            continue;
        }
        let k = t.slot[0];
        let vpl = vpls.get(k as usize)?;
        sum += v3(t.light);
        let rejected = term_rejection(flags);
        let fields = term_fields(vpl, t);
        contributions.push(Contribution {
            name: format!("VPL {k}"),
            source: format!("batch {}", info.batch),
            position: Some(v3(vpl.position)),
            value: if rejected.is_some() { Vec3::ZERO } else { v3(t.light) * w },
            weight: w,
            rejected,
            via: None,
            fields,
        });
    }
    contributions.push(Contribution {
        name: "previous batches".into(),
        source: format!("the average of batches 0…{}", info.batch.saturating_sub(1)),
        position: None,
        value: v3(header.prev) * (1.0 - w),
        weight: 1.0 - w,
        rejected: None,
        via: None,
        fields: vec![("batches", info.batch as f32)],
    });
    let checks = vec![Check {
        what: "Σ this batch's VPL terms".into(),
        sum,
        buffer: "indirect.raw".into(),
        value: v3(header.raw),
    }];
    let mut e = Explanation {
        pixel: info.pixel,
        technique: info.technique.clone(),
        contributions,
        buffer: "indirect.accum".into(),
        value: v3(header.accum),
        checks,
        notes: vec![format!(
            "batch k = {} ({} VPLs), weight 1/(k+1) = {w:.4}; the previous batches keep k/(k+1)",
            info.batch, info.count
        )],
    };
    e.sort();
    Some(e)
}

/// Why a VPL's term adds nothing, from the flags `common/vpl_explain.wgsl` sets at the
/// receiver (None: it adds its light).
pub fn term_rejection(flags: u32) -> Option<Rejection> {
    if flags & NEAR != 0 {
        Some(Rejection::NearField)
    } else if flags & FACING != 0 {
        Some(Rejection::Facing)
    } else if flags & OCCLUDED != 0 {
        Some(Rejection::Occluded)
    } else {
        None
    }
}

/// What made a VPL's term (`vpl_term` in `common/vpl_explain.wgsl`): its flux, the geometry
/// term, both BRDFs, the visibility with the map's depths, its light without visibility and
/// the d_min clamp.
pub fn term_fields(vpl: &GpuVpl, t: &GpuTerm) -> Vec<(&'static str, f32)> {
    let v3 = |v: Vec4| v.truncate();
    let mut fields = vec![
        ("Φ (lum)", crate::explain::luminance(v3(vpl.flux))),
        ("G", t.unshadowed.w),
        ("f_y", t.detail.x),
        ("f_x", t.detail.y),
        ("V", t.light.w),
        ("unshadowed (lum)", crate::explain::luminance(v3(t.unshadowed))),
    ];
    if t.detail.z != 0.0 || t.detail.w != 0.0 {
        fields.push(("map depth", t.detail.z));
        fields.push(("receiver depth", t.detail.w));
    }
    if t.slot[1] & CLAMPED != 0 {
        fields.push(("d_min clamp", 1.0));
    }
    fields
}
