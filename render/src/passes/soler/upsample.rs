//! Stage 6 "joint bilateral upsampling" (Soler et al. 004 §4, "Continuous combination of all
//! levels"): from the coarsest gathered level down to the G-buffer, the accumulated light is
//! up-sampled with bilinear × depth × normal weights and each gathered level's own light is
//! added (`soler.accum.k`); the receiver then reflects it with c·DI/π (`soler.indirect`).
//! With the glossy reflection the levels' specular light goes up the same chain
//! (`soler.specular.accum.k`) and is added after the resolve.
//! Shaders `soler/{upsample,resolve}.wgsl`; CPU twin `cpu::soler::upsample`.

use super::STRIDE;
use crate::buffers::{BufferKind, BufferRegistry};
use crate::counters::prelude::CountedQueue;
use crate::gpu::GpuContext;
use crate::gpu::bindings::{Bindings, Kind, binding};
use crate::timing::PassRec;

/// Bind group `soler.upsample.inputs` of `shaders/soler/upsample.wgsl` (group 0): one step of
/// the bilateral upsampling (Soler 004 §3.3).
pub const UPSAMPLE_INPUTS_BINDINGS: Bindings = Bindings {
    label: "soler.upsample.inputs",
    shader: "soler/upsample.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "params", Kind::UniformDynamic),
        binding(1, "fine_position", Kind::Texture { filterable: false }),
        binding(2, "fine_normal", Kind::Texture { filterable: false }),
        binding(3, "fine_light", Kind::Texture { filterable: false }),
        binding(4, "coarse_position", Kind::Texture { filterable: false }),
        binding(5, "coarse_normal", Kind::Texture { filterable: false }),
        binding(6, "coarse_light", Kind::Texture { filterable: false }),
        binding(7, "out_light", Kind::StorageTexture(wgpu::TextureFormat::Rgba32Float)),
    ],
};

/// Bind group `soler.resolve.inputs` of `shaders/soler/resolve.wgsl` (group 0).
pub const RESOLVE_INPUTS_BINDINGS: Bindings = Bindings {
    label: "soler.resolve.inputs",
    shader: "soler/resolve.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "resolve_light", Kind::Texture { filterable: false }),
        binding(1, "g_albedo", Kind::Texture { filterable: false }),
        binding(2, "out_radiance", Kind::StorageTexture(wgpu::TextureFormat::Rgba32Float)),
        binding(3, "resolve_specular", Kind::Texture { filterable: false }),
        binding(4, "flags", Kind::Uniform),
    ],
};

/// Rust twin of `UpsampleParams` in `shaders/soler/upsample.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct UpsampleParams {
    /// σ depth, σ normal, 1 when the fine level adds its own light, unused.
    pub sigma: [f32; 4],
}

/// Most upsampling steps (levels above the G-buffer: start 2 + 8 levels − 1).
pub const MAX_STEPS: usize = 10;

/// One step's views: the fine level (position, normal, its own gathered light if any) and
/// the coarse level (position, normal, accumulated light).
pub struct Step<'a> {
    pub fine: [&'a wgpu::TextureView; 2],
    pub fine_light: Option<&'a wgpu::TextureView>,
    pub coarse: [&'a wgpu::TextureView; 3],
}

pub struct SolerUpsample {
    /// `soler.accum.k` for k = 0 … top − 1 (the coarsest level's accumulator is its light).
    pub accum: Vec<wgpu::Texture>,
    /// `soler.indirect`: c·DI/π · E at G-buffer resolution (plus the glossy reflection,
    /// when the resolve adds it).
    pub indirect: wgpu::Texture,
    /// `soler.specular.accum.k`, k = 0 … top − 1: the glossy reflection's chain (empty
    /// without it); level 0's is the stage's `soler.specular`.
    pub spec_accum: Vec<wgpu::Texture>,
    resolve_params: wgpu::Buffer,
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::ComputePipeline,
    resolve_layout: wgpu::BindGroupLayout,
    resolve_pipeline: wgpu::ComputePipeline,
    params: wgpu::Buffer,
    dummy: wgpu::Texture,
}

impl SolerUpsample {
    pub fn new(ctx: &GpuContext, sizes: &[(u32, u32)]) -> Self {
        let device = &ctx.device;
        let rgba = wgpu::TextureFormat::Rgba32Float;
        let layout = UPSAMPLE_INPUTS_BINDINGS.layout(device);
        let resolve_layout = RESOLVE_INPUTS_BINDINGS.layout(device);
        let m_up = crate::shaders::create_module(device, "soler/upsample.wgsl");
        let m_resolve = crate::shaders::create_module(device, "soler/resolve.wgsl");
        let pipeline = crate::passes::compute_pipeline(device, "soler.upsample", &m_up, "cs_upsample", &[&layout]);
        let resolve_pipeline =
            crate::passes::compute_pipeline(device, "soler.resolve", &m_resolve, "cs_resolve", &[&resolve_layout]);
        let params = crate::passes::uniform_buffer(device, "soler.upsample.params", STRIDE * MAX_STEPS as u64);
        let storage = wgpu::TextureUsages::STORAGE_BINDING;
        let dummy = crate::passes::create_target(device, "soler.no_own_light", 1, 1, rgba, storage);
        let (accum, indirect) = Self::targets(device, sizes, "soler.accum");
        let resolve_params = crate::passes::uniform_buffer(device, "soler.resolve.params", 16);
        Self {
            accum,
            indirect,
            spec_accum: Vec::new(),
            resolve_params,
            layout,
            pipeline,
            resolve_layout,
            resolve_pipeline,
            params,
            dummy,
        }
    }

    /// `sizes`: levels 0 (the G-buffer) … top − 1.
    fn targets(device: &wgpu::Device, sizes: &[(u32, u32)], name: &str) -> (Vec<wgpu::Texture>, wgpu::Texture) {
        let storage = wgpu::TextureUsages::STORAGE_BINDING;
        let rgba = wgpu::TextureFormat::Rgba32Float;
        let accum = sizes
            .iter()
            .enumerate()
            .map(|(k, &(w, h))| crate::passes::create_target(device, &format!("{name}.{k}"), w, h, rgba, storage))
            .collect();
        let (w, h) = sizes.first().copied().unwrap_or((1, 1));
        (accum, crate::passes::create_target(device, "soler.indirect", w, h, rgba, storage))
    }

    /// Resizes for the accumulators of levels 0 … top − 1 (`sizes`, the first the G-buffer's)
    /// and the glossy reflection's chain (`specular`); true when replaced.
    pub fn ensure(&mut self, ctx: &GpuContext, sizes: &[(u32, u32)], gbuffer: (u32, u32), specular: bool) -> bool {
        let size_of = |v: &[wgpu::Texture]| -> Vec<(u32, u32)> { v.iter().map(|t| (t.width(), t.height())).collect() };
        let want_spec: &[(u32, u32)] = if specular { sizes } else { &[] };
        let spec_changed = size_of(&self.spec_accum) != want_spec;
        if spec_changed {
            self.spec_accum = Self::targets(&ctx.device, want_spec, "soler.specular.accum").0;
        }
        if size_of(&self.accum) == sizes && (self.indirect.width(), self.indirect.height()) == gbuffer {
            return spec_changed;
        }
        let storage = wgpu::TextureUsages::STORAGE_BINDING;
        (self.accum, _) = Self::targets(&ctx.device, sizes, "soler.accum");
        self.indirect = crate::passes::create_target(
            &ctx.device,
            "soler.indirect",
            gbuffer.0,
            gbuffer.1,
            wgpu::TextureFormat::Rgba32Float,
            storage,
        );
        true
    }

    pub fn register(&self, reg: &mut BufferRegistry) {
        for (k, t) in self.accum.iter().enumerate() {
            reg.register(
                &format!("soler.accum.{k}"),
                BufferKind::Hdr,
                "Soler accumulator after the upsampling step to level k (004 §4): the irradiance of every coarser level, bilaterally up-sampled, plus level k's own",
                t,
            );
        }
        for (k, t) in self.spec_accum.iter().enumerate() {
            reg.register(
                &format!("soler.specular.accum.{k}"),
                BufferKind::Hdr,
                "Soler glossy reflection after the upsampling step to level k (004 §4 \"Screen-space importance sampling\"): every coarser level's specular light, bilaterally up-sampled, plus level k's own; level 0 is what the resolve adds",
                t,
            );
        }
        reg.register(
            "soler.indirect",
            BufferKind::Hdr,
            "Soler indirect light (004 Fig. 4): the combined irradiance of all levels reflected with c·DI/π",
            &self.indirect,
        );
    }

    /// Runs `steps` (coarse to fine: the last writes `soler.accum.0`), the glossy reflection's
    /// `spec_steps` when it is on (into `soler.specular.accum.k`), and the resolve of
    /// `last_light` (the accumulator at G-buffer resolution) with `albedo`; the resolve adds
    /// the glossy reflection's `last_spec` when `add_specular`.
    pub fn run(
        &self,
        r: PassRec<'_, '_>,
        sigma: [f32; 2],
        steps: &[Step<'_>],
        last_light: &wgpu::TextureView,
        albedo: &wgpu::TextureView,
        (spec, add_specular): (Option<(&[Step<'_>], &wgpu::TextureView)>, bool),
    ) {
        let PassRec { ctx, enc: encoder, slot } = r;
        let params: Vec<UpsampleParams> = steps
            .iter()
            .map(|s| UpsampleParams { sigma: [sigma[0], sigma[1], s.fine_light.is_some() as u32 as f32, 0.0] })
            .collect();
        ctx.queue.upload(&self.params, 0, &crate::passes::strided_bytes(STRIDE, params.len().max(1), &params));
        let flags: [u32; 4] = [(add_specular && spec.is_some()) as u32, 0, 0, 0];
        ctx.queue.upload(&self.resolve_params, 0, bytemuck::bytes_of(&flags));
        fn tv(v: &wgpu::TextureView) -> wgpu::BindingResource<'_> {
            wgpu::BindingResource::TextureView(v)
        }
        let dummy = crate::passes::view(&self.dummy, "soler.no_own_light");
        let mut first = true;
        let chains = std::iter::once((steps, &self.accum)).chain(spec.map(|(s, _)| (s, &self.spec_accum)));
        for (steps, accum) in chains {
            let n = steps.len();
            // Step i writes the accumulator of level n − 1 − i.
            for (i, s) in steps.iter().enumerate() {
                let k = n - 1 - i;
                let Some(t) = accum.get(k) else { continue };
                let out = crate::passes::view(t, "soler.accum.view");
                let views =
                    [s.fine[0], s.fine[1], s.fine_light.unwrap_or(&dummy), s.coarse[0], s.coarse[1], s.coarse[2], &out];
                let uniform = crate::passes::dynamic_slot(&self.params, std::mem::size_of::<UpsampleParams>());
                let resources = std::iter::once(uniform).chain(views.map(tv));
                let group = UPSAMPLE_INPUTS_BINDINGS.group(&ctx.device, &self.layout, resources);
                let stamps = slot.as_ref().and_then(|s| s.compute(first, false));
                first = false;
                let offset = [(i as u64 * STRIDE) as u32];
                let size = (t.width(), t.height());
                crate::passes::dispatch_2d(encoder, "soler.upsample", &self.pipeline, &group, &offset, stamps, size);
            }
        }
        let out = crate::passes::view(&self.indirect, "soler.indirect");
        let last_spec = spec.map_or(&dummy, |(_, v)| v);
        let mut resources: Vec<wgpu::BindingResource<'_>> = [last_light, albedo, &out, last_spec].map(tv).into();
        resources.push(self.resolve_params.as_entire_binding());
        let group = RESOLVE_INPUTS_BINDINGS.group(&ctx.device, &self.resolve_layout, resources);
        let stamps = slot.as_ref().and_then(|s| s.compute(first, true));
        let size = (self.indirect.width(), self.indirect.height());
        crate::passes::dispatch_2d(encoder, "soler.resolve", &self.resolve_pipeline, &group, &[], stamps, size);
    }
}
