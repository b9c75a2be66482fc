//! Stage 2's average of the direct light over still frames while the sky's directions rotate
//! (issue #51 point 2, `sky.rotate_each_frame`): the sky lights each frame with another
//! shifted set of `sky.directions` directional lights (`scene::sky::sky_shift`), and this pass
//! keeps the running mean of `direct.radiance` (`direct.sky_history`), which the frame then
//! uses as its direct light (the compose, Soler's senders). Anything else that changes what
//! the direct light is — the camera, a light but the sky's rotation, an object's transform,
//! a setting, the size — restarts it with that frame's light alone, as
//! `Renderer::reset_history` does. Shader `shaders/direct/sky_history.wgsl`.

use crate::buffers::{BufferKind, BufferRegistry};
use crate::counters::prelude::CountedQueue;
use crate::gpu::GpuContext;
use crate::gpu::bindings::{Bindings, Kind, binding};
use crate::passes::{create_target, view};
use crate::timing::PassRec;

/// Bind group `direct.sky_history.inputs` of `shaders/direct/sky_history.wgsl` (group 0).
pub const SKY_HISTORY_INPUTS_BINDINGS: Bindings = Bindings {
    label: "direct.sky_history.inputs",
    shader: "direct/sky_history.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::COMPUTE,
    list: &[
        binding(0, "params", Kind::Uniform),
        binding(1, "prev", Kind::Texture { filterable: false }),
        binding(2, "current", Kind::Texture { filterable: false }),
        binding(3, "next", Kind::StorageTexture(wgpu::TextureFormat::Rgba32Float)),
    ],
};

/// The format of the history (the mean of many frames of half floats).
const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

/// The weight of frame `k` (1-based) of a running mean: 1/k.
pub fn running_weight(k: u32) -> f32 {
    1.0 / k.max(1) as f32
}

pub struct DirectHistory {
    /// A ping-pong pair: `direct.sky_history` is `history[current]`.
    history: [wgpu::Texture; 2],
    current: usize,
    /// Frames in the mean (0: none yet).
    pub frames: u32,
    /// What the mean depends on (camera, steady lights, transforms, settings); a change
    /// restarts it.
    fingerprint: Vec<f32>,
    settings: Option<String>,
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::ComputePipeline,
    params: wgpu::Buffer,
}

impl DirectHistory {
    pub fn new(ctx: &GpuContext, width: u32, height: u32) -> Self {
        let device = &ctx.device;
        let layout = SKY_HISTORY_INPUTS_BINDINGS.layout(device);
        let module = crate::shaders::create_module(device, "direct/sky_history.wgsl");
        let pipeline = crate::passes::compute_pipeline(device, "direct.sky_history", &module, "cs_average", &[&layout]);
        let params = crate::passes::uniform_buffer(device, "direct.sky_history.params", 16);
        Self {
            history: Self::targets(device, width, height),
            current: 0,
            frames: 0,
            fingerprint: Vec::new(),
            settings: None,
            layout,
            pipeline,
            params,
        }
    }

    fn targets(device: &wgpu::Device, width: u32, height: u32) -> [wgpu::Texture; 2] {
        let (w, h) = (width.max(1), height.max(1));
        let st = wgpu::TextureUsages::STORAGE_BINDING;
        [
            create_target(device, "direct.sky_history", w, h, FORMAT, st),
            create_target(device, "direct.sky_history", w, h, FORMAT, st),
        ]
    }

    /// Resizes (and restarts) for a new size; true when the textures were replaced.
    pub fn ensure(&mut self, ctx: &GpuContext, width: u32, height: u32) -> bool {
        if (self.history[0].width(), self.history[0].height()) == (width.max(1), height.max(1)) {
            return false;
        }
        self.history = Self::targets(&ctx.device, width, height);
        self.reset();
        true
    }

    /// Forgets the mean: the next frame starts it again.
    pub fn reset(&mut self) {
        self.frames = 0;
    }

    pub fn register(&self, reg: &mut BufferRegistry) {
        reg.register(
            "direct.sky_history",
            BufferKind::Hdr,
            "the direct light averaged over the still frames while the sky's directions rotate (sky.rotate_each_frame): the frame's direct light",
            &self.history[self.current],
        );
    }

    /// Adds this frame's `direct.radiance` to the mean (restarting it when `fingerprint` or
    /// `settings` differ from the last frame's) and returns the mean's view.
    pub fn run(
        &mut self,
        r: PassRec<'_, '_>,
        radiance: &wgpu::TextureView,
        fingerprint: Vec<f32>,
        settings: String,
    ) -> wgpu::TextureView {
        let PassRec { ctx, enc: encoder, slot } = r;
        if fingerprint != self.fingerprint || self.settings.as_ref() != Some(&settings) {
            self.fingerprint = fingerprint;
            self.settings = Some(settings);
            self.frames = 0;
        }
        self.frames = self.frames.saturating_add(1);
        let w = running_weight(self.frames);
        ctx.queue.upload(&self.params, 0, bytemuck::cast_slice(&[w, 0.0, 0.0, 0.0]));
        let (src, dst) = (self.current, 1 - self.current);
        let (prev, next) =
            (view(&self.history[src], "direct.sky_history"), view(&self.history[dst], "direct.sky_history"));
        let tv = wgpu::BindingResource::TextureView;
        let group = SKY_HISTORY_INPUTS_BINDINGS.group(
            &ctx.device,
            &self.layout,
            [self.params.as_entire_binding(), tv(&prev), tv(radiance), tv(&next)],
        );
        let size = (self.history[0].width(), self.history[0].height());
        crate::passes::dispatch_2d(
            encoder,
            "direct.sky_history",
            &self.pipeline,
            &group,
            &[],
            slot.and_then(|s| s.compute(true, true)),
            size,
        );
        self.current = dst;
        next
    }
}
