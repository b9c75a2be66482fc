//! Multi-bounce of Soler et al. (004 §4 "Multi-bounce computation", §5.3): each bounce's
//! light is kept (`soler.bounce.b`, b = 1 … n: the previous bounce's input and, with
//! alternating bounces, what the frames that do not gather it reuse) and their sum is the
//! stage's indirect light (`shaders/soler/bounces.wgsl`). With one bounce nothing here runs.

use crate::buffers::{BufferKind, BufferRegistry};
use crate::gpu::GpuContext;
use crate::passes::bgl;
use crate::timing::Slot;

/// Rust twin of `BounceParams` in `shaders/soler/bounces.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct BounceParams {
    /// Bounces n, unused ×3.
    pub count: [u32; 4],
}

pub struct SolerBounces {
    /// `soler.bounce.b` for b = 1 … n (empty with one bounce).
    pub light: Vec<wgpu::Texture>,
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::ComputePipeline,
    params: wgpu::Buffer,
    dummy: wgpu::Texture,
}

impl SolerBounces {
    pub fn new(ctx: &GpuContext) -> Self {
        let device = &ctx.device;
        let cs = wgpu::ShaderStages::COMPUTE;
        let mut entries = vec![bgl::uniform(0, cs)];
        entries.extend((1..=4).map(|b| bgl::texture(b, cs, false)));
        entries.push(bgl::storage_texture(5, wgpu::TextureFormat::Rgba32Float));
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("soler.bounces.inputs"),
            entries: &entries,
        });
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
        Self { light: Vec::new(), layout, pipeline, params, dummy }
    }

    /// One texture per bounce at the G-buffer's `size` (none for one bounce); true when
    /// replaced (the stored bounces are lost: they restart black).
    pub fn ensure(&mut self, ctx: &GpuContext, bounces: u32, size: (u32, u32)) -> bool {
        let n = if bounces > 1 { bounces as usize } else { 0 };
        if self.light.len() == n && self.light.iter().all(|t| (t.width(), t.height()) == size) {
            return false;
        }
        let usage = wgpu::TextureUsages::COPY_DST;
        let rgba = wgpu::TextureFormat::Rgba32Float;
        self.light = (1..=n)
            .map(|b| {
                crate::passes::create_target(&ctx.device, &format!("soler.bounce.{b}"), size.0, size.1, rgba, usage)
            })
            .collect();
        true
    }

    pub fn register(&self, reg: &mut BufferRegistry) {
        for (i, t) in self.light.iter().enumerate() {
            reg.register(
                &format!("soler.bounce.{}", i + 1),
                BufferKind::Hdr,
                "Soler multi-bounce (004 §4): the newest light of this bounce, c·DI/π · E of a gather of the bounce before (the first: of the direct light)",
                t,
            );
        }
    }

    /// Keeps `light` (this frame's result of bounce `b`, 0-based) as `soler.bounce.{b+1}`.
    pub fn keep(&self, encoder: &mut wgpu::CommandEncoder, light: &wgpu::Texture, b: usize) {
        if let Some(t) = self.light.get(b) {
            encoder.copy_texture_to_texture(light.as_image_copy(), t.as_image_copy(), t.size());
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
        let p = BounceParams { count: [self.light.len() as u32, 0, 0, 0] };
        ctx.queue.write_buffer(&self.params, 0, bytemuck::bytes_of(&p));
        let view = |t: &wgpu::Texture| crate::passes::view(t, "soler.bounce.view");
        let views: Vec<wgpu::TextureView> = (0..4).map(|b| view(self.light.get(b).unwrap_or(&self.dummy))).collect();
        let out_view = view(out);
        let tv = wgpu::BindingResource::TextureView;
        let mut resources = vec![self.params.as_entire_binding()];
        resources.extend(views.iter().map(tv));
        resources.push(tv(&out_view));
        let group = crate::passes::bind_group(&ctx.device, "soler.bounces.inputs", &self.layout, resources);
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
