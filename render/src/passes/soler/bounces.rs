//! Multi-bounce of Soler et al. (004 §4 "Multi-bounce computation", §5.3): each bounce's
//! light is kept (`soler.bounce.b`, b = 1 … n: the previous bounce's input and, with
//! alternating bounces, what the frames that do not gather it reuse) and their sum is the
//! stage's indirect light (`shaders/soler/bounces.wgsl`). With the glossy reflection each
//! bounce's specular light toward the eye is kept apart (`soler.bounce.b.specular`: the next
//! bounce gathers the diffuse light only, 004 §5.3) and added to the sum. With one bounce
//! nothing here runs.

use crate::counters::prelude::*;
use crate::gpu::bindings::{Bindings, Kind, binding};

use crate::buffers::{BufferKind, BufferRegistry};
use crate::gpu::GpuContext;
use crate::timing::Slot;

/// Bind group `soler.bounces.inputs` of `shaders/soler/bounces.wgsl` (group 0).
pub const BOUNCES_INPUTS_BINDINGS: Bindings = Bindings {
    label: "soler.bounces.inputs",
    shader: "soler/bounces.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "params", Kind::Uniform),
        binding(1, "bounce1", Kind::Texture { filterable: false }),
        binding(2, "bounce2", Kind::Texture { filterable: false }),
        binding(3, "bounce3", Kind::Texture { filterable: false }),
        binding(4, "bounce4", Kind::Texture { filterable: false }),
        binding(5, "out_sum", Kind::StorageTexture(wgpu::TextureFormat::Rgba32Float)),
        binding(6, "specular1", Kind::Texture { filterable: false }),
        binding(7, "specular2", Kind::Texture { filterable: false }),
        binding(8, "specular3", Kind::Texture { filterable: false }),
        binding(9, "specular4", Kind::Texture { filterable: false }),
        binding(10, "out_specular", Kind::StorageTexture(wgpu::TextureFormat::Rgba32Float)),
    ],
};

/// Rust twin of `BounceParams` in `shaders/soler/bounces.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct BounceParams {
    /// Bounces n, 1 when the specular light is added, unused ×2.
    pub count: [u32; 4],
}

pub struct SolerBounces {
    /// `soler.bounce.b` for b = 1 … n (empty with one bounce).
    pub light: Vec<wgpu::Texture>,
    /// `soler.bounce.b.specular` for b = 1 … n with the glossy reflection (else empty).
    pub specular: Vec<wgpu::Texture>,
    /// `soler.bounces.specular`: the sum of `specular`, the part of `soler.indirect` that
    /// Eq. 6 leaves out of its irradiance blend (None without the glossy reflection).
    pub specular_sum: Option<wgpu::Texture>,
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::ComputePipeline,
    params: wgpu::Buffer,
    dummy: wgpu::Texture,
    /// Stand-in for `specular_sum` without the glossy reflection (never read).
    no_sum: wgpu::Texture,
}

impl SolerBounces {
    pub fn new(ctx: &GpuContext) -> Self {
        let device = &ctx.device;
        let layout = BOUNCES_INPUTS_BINDINGS.layout(device);
        let module = crate::shaders::create_module(device, "soler/bounces.wgsl");
        let pipeline = crate::passes::compute_pipeline(device, "soler.bounces", &module, "cs_sum", &[&layout]);
        let params =
            crate::passes::uniform_buffer(device, "soler.bounces.params", std::mem::size_of::<BounceParams>() as u64);
        let dummy = crate::passes::create_target(
            device,
            "soler.bounce.none",
            1,
            1,
            wgpu::TextureFormat::Rgba32Float,
            wgpu::TextureUsages::empty(),
        );
        let no_sum = crate::passes::create_target(
            device,
            "soler.bounces.no_specular",
            1,
            1,
            wgpu::TextureFormat::Rgba32Float,
            wgpu::TextureUsages::STORAGE_BINDING,
        );
        Self { light: Vec::new(), specular: Vec::new(), specular_sum: None, layout, pipeline, params, dummy, no_sum }
    }

    /// One texture per bounce at the G-buffer's `size` (none for one bounce), and one for
    /// its specular light with the glossy reflection (`specular`); true when replaced (the
    /// stored bounces are lost: they restart black).
    pub fn ensure(&mut self, ctx: &GpuContext, bounces: u32, size: (u32, u32), specular: bool) -> bool {
        let n = if bounces > 1 { bounces as usize } else { 0 };
        let ns = if specular { n } else { 0 };
        let fits = |v: &[wgpu::Texture], n: usize| v.len() == n && v.iter().all(|t| (t.width(), t.height()) == size);
        if fits(&self.light, n) && fits(&self.specular, ns) {
            return false;
        }
        let usage = wgpu::TextureUsages::COPY_DST;
        let rgba = wgpu::TextureFormat::Rgba32Float;
        let make = |name: &str| crate::passes::create_target(&ctx.device, name, size.0, size.1, rgba, usage);
        self.light = (1..=n).map(|b| make(&format!("soler.bounce.{b}"))).collect();
        self.specular = (1..=ns).map(|b| make(&format!("soler.bounce.{b}.specular"))).collect();
        self.specular_sum = (ns > 0).then(|| {
            let st = wgpu::TextureUsages::STORAGE_BINDING;
            crate::passes::create_target(&ctx.device, "soler.bounces.specular", size.0, size.1, rgba, st)
        });
        true
    }

    pub fn register(&self, reg: &mut BufferRegistry) {
        if let Some(t) = &self.specular_sum {
            reg.register(
                "soler.bounces.specular",
                BufferKind::Hdr,
                "Soler multi-bounce with the glossy reflection: the sum of every bounce's specular light, the part of soler.indirect Eq. 6 leaves out of its irradiance blend",
                t,
            );
        }
        for (i, t) in self.light.iter().enumerate() {
            reg.register(
                &format!("soler.bounce.{}", i + 1),
                BufferKind::Hdr,
                "Soler multi-bounce (004 §4): the newest light of this bounce, c·DI/π · E of a gather of the bounce before (the first: of the direct light)",
                t,
            );
        }
        for (i, t) in self.specular.iter().enumerate() {
            reg.register(
                &format!("soler.bounce.{}.specular", i + 1),
                BufferKind::Hdr,
                "Soler multi-bounce (004 §4, §5.3): the light this bounce's receivers reflect toward the eye with their specular lobe (added to the sum, not gathered by the next bounce)",
                t,
            );
        }
    }

    /// Keeps `light` (this frame's diffuse result of bounce `b`, 0-based) as
    /// `soler.bounce.{b+1}`, and its glossy reflection `specular` when kept.
    pub fn keep(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        light: &wgpu::Texture,
        specular: Option<&wgpu::Texture>,
        b: usize,
    ) {
        let pairs = [(Some(light), self.light.get(b)), (specular, self.specular.get(b))];
        for (from, to) in pairs {
            if let (Some(from), Some(to)) = (from, to) {
                encoder.counted_copy_texture(from.as_image_copy(), to.as_image_copy(), to.size());
            }
        }
    }

    /// Writes the sum of every bounce into `out`.
    pub fn sum(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        slot: Option<Slot<'_>>,
        out: &wgpu::Texture,
    ) {
        let spec = !self.specular.is_empty();
        let p = BounceParams { count: [self.light.len() as u32, spec as u32, 0, 0] };
        ctx.queue.upload(&self.params, 0, bytemuck::bytes_of(&p));
        let view = |t: &wgpu::Texture| crate::passes::view(t, "soler.bounce.view");
        let views: Vec<wgpu::TextureView> = (0..4).map(|b| view(self.light.get(b).unwrap_or(&self.dummy))).collect();
        let spec_views: Vec<wgpu::TextureView> =
            (0..4).map(|b| view(self.specular.get(b).unwrap_or(&self.dummy))).collect();
        let out_view = view(out);
        let tv = wgpu::BindingResource::TextureView;
        let mut resources = vec![self.params.as_entire_binding()];
        resources.extend(views.iter().map(tv));
        resources.push(tv(&out_view));
        resources.extend(spec_views.iter().map(tv));
        let sum_view = view(self.specular_sum.as_ref().unwrap_or(&self.no_sum));
        resources.push(tv(&sum_view));
        let group = BOUNCES_INPUTS_BINDINGS.group(&ctx.device, &self.layout, resources);
        let stamps = slot.and_then(|s| s.compute(true, true));
        crate::passes::dispatch_2d(
            encoder,
            "soler.bounces",
            &self.pipeline,
            &group,
            &[],
            stamps,
            (out.width(), out.height()),
        );
    }
}
