//! Explain a pixel (issue #42) with DDGI (issue #56 point 3): `shaders/ddgi/explain.wgsl` reads
//! the pinned pixel's eight probes with the frame's own functions (`ddgi/lookup.wgsl`), and
//! [`DdgiExplainPass::decode`] makes each probe's share of the pixel's indirect light,
//! c·DI/π · π · w_k E_k / Σ w (Majercik et al. 2019 §3.4, Eq. 5–6; with the glossy receiver
//! also SI/π · π · w_k E_k(r) / Σ w), with its trilinear,
//! backface and Chebyshev weights, checked against the frame's `ddgi.indirect` there.

use crate::counters::prelude::*;

use glam::{Vec3, Vec4};

use crate::explain::{Check, Contribution, Explanation, Replay};
use crate::gpu::GpuContext;
use crate::gpu::bindings::{Bindings, Kind, binding};

const READ: Kind = Kind::Storage { read_only: true };
const TEX: Kind = Kind::Texture { filterable: false };

/// The replay's group 0.
pub const EXPLAIN_BINDINGS: Bindings = Bindings {
    label: "explain.ddgi.inputs",
    shader: "ddgi/explain.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "ddgi_grid", READ),
        binding(1, "ddgi_probes", READ),
        binding(2, "ddgi_irradiance", READ),
        binding(3, "ddgi_distance", READ),
        binding(4, "g_position", TEX),
        binding(5, "g_normal", TEX),
        binding(6, "g_albedo", TEX),
        binding(7, "camera", Kind::Uniform),
        binding(8, "frame_indirect", TEX),
        binding(9, "explain_pixel", READ),
        binding(10, "explain_out", Kind::Storage { read_only: false }),
        binding(11, "g_material", TEX),
    ],
};

/// Records written: 4 of the pixel, 4 per probe.
const RECORDS: u64 = 4 + 4 * 8;

/// The replay.
pub struct DdgiExplainPass {
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::ComputePipeline,
    pixel_buffer: wgpu::Buffer,
    out: wgpu::Buffer,
    /// The pixel of the last run (None before one).
    pixel: Option<(u32, u32)>,
}

/// What the replay reads of the frame.
pub struct ExplainInputs<'a> {
    /// The grid's parameters, the probes, the irradiance and distance atlases.
    pub probes: [&'a wgpu::Buffer; 4],
    pub g: &'a crate::passes::gbuffer::GBufferViews,
    pub camera: &'a wgpu::Buffer,
    pub indirect: &'a wgpu::TextureView,
}

impl DdgiExplainPass {
    pub fn new(ctx: &GpuContext) -> Self {
        let device = &ctx.device;
        let layout = EXPLAIN_BINDINGS.layout(device);
        let module = crate::shaders::create_module(device, "ddgi/explain.wgsl");
        let pipeline = crate::passes::compute_pipeline(device, "explain.ddgi", &module, "cs_explain", &[&layout]);
        let pixel_buffer = crate::passes::rays::storage(ctx, "explain.ddgi.pixel", &[0u8; 16], 16);
        let out = crate::passes::rays::storage(ctx, "explain.ddgi.out", &vec![0u8; (RECORDS * 16) as usize], 16);
        Self { layout, pipeline, pixel_buffer, out, pixel: None }
    }

    /// Records the replay of `pixel` after the frame's reading of the probes.
    pub fn record(&mut self, ctx: &GpuContext, enc: &mut wgpu::CommandEncoder, i: &ExplainInputs, pixel: (u32, u32)) {
        ctx.queue.upload(&self.pixel_buffer, 0, bytemuck::cast_slice(&[pixel.0, pixel.1, 0, 0]));
        let [grid, probes, irradiance, distance] = i.probes;
        let group = EXPLAIN_BINDINGS.group(
            &ctx.device,
            &self.layout,
            [
                grid.as_entire_binding(),
                probes.as_entire_binding(),
                irradiance.as_entire_binding(),
                distance.as_entire_binding(),
                wgpu::BindingResource::TextureView(&i.g.position),
                wgpu::BindingResource::TextureView(&i.g.normal),
                wgpu::BindingResource::TextureView(&i.g.albedo),
                i.camera.as_entire_binding(),
                wgpu::BindingResource::TextureView(i.indirect),
                self.pixel_buffer.as_entire_binding(),
                self.out.as_entire_binding(),
                wgpu::BindingResource::TextureView(&i.g.material),
            ],
        );
        let mut pass = enc
            .begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("explain.ddgi"), timestamp_writes: None });
        pass.set_pipe(&self.pipeline);
        pass.set_group(0, &group, &[]);
        pass.dispatch(1, 1, 1);
        self.pixel = Some(pixel);
    }
}

/// The explanation from the replay's records (see `shaders/ddgi/explain.wgsl`).
pub fn decode(pixel: (u32, u32), r: &[Vec4]) -> Option<Explanation> {
    if r.len() < RECORDS as usize {
        return None;
    }
    let value = r[3].truncate();
    let mut e = Explanation {
        pixel,
        technique: "DDGI probes (Majercik et al. 2019 §3.4, Eq. 5–6; 2021 §4.2, §5)".into(),
        contributions: Vec::new(),
        buffer: "ddgi.indirect".into(),
        value,
        checks: Vec::new(),
        notes: Vec::new(),
    };
    if r[0].w < 0.5 {
        e.notes.push("the pixel shows no surface (background): no probe reads it".into());
        return Some(e);
    }
    // w_k / Σ w · (c·DI · E_k + SI · E_k(r)), E_k the probe's irradiance / π toward the
    // normal, E_k(r) toward the mirror direction (the glossy receiver; SI = 0 without it).
    let (reflect, si) = (r[2].truncate() * r[2].w, r[1].w);
    let total: f32 = (0..8).map(|k| r[5 + 4 * k].x).sum();
    for k in 0..8 {
        let (a, b, c, d) = (r[4 + 4 * k], r[5 + 4 * k], r[6 + 4 * k], r[7 + 4 * k]);
        let share = if total > 0.0 { b.x / total } else { 0.0 };
        let inactive = c.w > 0.5;
        e.contributions.push(Contribution {
            name: format!("probe {}", a.x as u32),
            source: if inactive { "inactive (2021 §5.2)".into() } else { "active".into() },
            position: Some(Vec3::new(b.y, b.z, b.w)),
            value: (reflect * c.truncate() + d.truncate() * si) * share,
            weight: share,
            rejected: None,
            via: None,
            fields: vec![
                ("trilinear", a.y),
                ("backface ((d·n+1)/2)²+0.2", a.z),
                ("Chebyshev³", a.w),
                ("w", b.x),
                ("E/π toward n (lum)", crate::explain::luminance(c.truncate())),
                ("E/π toward r (lum)", crate::explain::luminance(d.truncate())),
            ],
        });
    }
    e.notes.push(format!(
        "point {:.3?}, normal {:.3?}; Σ w = {total:.4}; the light is c·DI/π · π Σ w_k E_k / Σ w{}",
        r[0].truncate(),
        r[1].truncate(),
        if si > 0.0 {
            format!(" + SI/π · π Σ w_k E_k(r) / Σ w with SI = {si:.3} (the glossy receiver)")
        } else {
            " (a diffuse receiver)".into()
        }
    ));
    let sum = e.sum();
    e.checks.push(Check {
        what: format!("Σ of the 8 probes' shares at {pixel:?}"),
        sum,
        buffer: "ddgi.indirect".into(),
        value,
    });
    e.sort();
    Some(e)
}

impl Replay for DdgiExplainPass {
    fn parts(&self) -> Option<Vec<(wgpu::Buffer, u64)>> {
        self.pixel?;
        Some(vec![(self.out.clone(), RECORDS * 16)])
    }

    fn decode(&self, parts: &[Vec<u8>]) -> Option<Explanation> {
        let bytes = parts.first()?;
        let records: Vec<Vec4> = bytemuck::pod_collect_to_vec(bytes.get(..(RECORDS * 16) as usize)?);
        decode(self.pixel?, &records)
    }
}
