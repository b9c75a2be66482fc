//! Stage 2, shadow maps of the primary lights, rendered from the real triangles:
//! spot → one perspective view over the outer cone, point → six 90° cube-face views,
//! directional → one orthographic view over the scene bounds. All views are layers of one
//! `Depth32Float` array texture, registered as `direct.shadow_map`.
//! Shader: `shaders/shadow/shadow.wgsl`.

use crate::counters::prelude::*;

use glam::{Mat4, Vec3, Vec4};

use crate::buffers::{BufferKind, BufferRegistry};
use crate::gpu::GpuContext;
use crate::gpu::bindings::{Bindings, Kind, binding};
use crate::scene::upload::GpuScene;
use crate::scene::{Aabb, LightKind, SceneState, WorldLight};

/// Bind group `direct.shadow.view` of `shaders/shadow/shadow.wgsl` (group 0).
pub const DIRECT_SHADOW_VIEW_BINDINGS: Bindings = Bindings {
    label: "direct.shadow.view",
    shader: "shadow/shadow.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::VERTEX,
    list: &[binding(0, "view", Kind::UniformDynamic)],
};

/// Light record; WGSL twin: `Light` in `shaders/common/lights.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuLight {
    pub position: Vec4,
    pub direction: Vec4,
    pub color: Vec4,
    pub cone: Vec4,
    pub shadow: Vec4,
}

/// Uniform stride of the per-view matrices (dynamic offsets need 256-byte alignment).
const VIEW_STRIDE: u64 = 256;

/// Cube-face view directions and up vectors, in the order the direct shader expects
/// (+X, −X, +Y, −Y, +Z, −Z).
pub const CUBE_FACES: [(Vec3, Vec3); 6] = [
    (Vec3::X, Vec3::NEG_Y),
    (Vec3::NEG_X, Vec3::NEG_Y),
    (Vec3::Y, Vec3::Z),
    (Vec3::NEG_Y, Vec3::NEG_Z),
    (Vec3::Z, Vec3::NEG_Y),
    (Vec3::NEG_Z, Vec3::NEG_Y),
];

/// The lights of a frame, packed for the GPU, and the view-projection of every shadow layer.
#[derive(Clone, Debug, Default)]
pub struct LightSetup {
    pub lights: Vec<GpuLight>,
    pub views: Vec<Mat4>,
}

/// One view of a light: what the shadow maps and the light G-buffer of stage 3 render.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightView {
    pub view: Mat4,
    pub proj: Mat4,
    pub eye: Vec3,
    /// Unit view axis.
    pub forward: Vec3,
    /// Perspective: side of one texel of a `size`² map on the image plane at unit distance
    /// is `pixel_extent / size`; orthographic: the world side of one texel is `pixel_extent / size`.
    pub pixel_extent: f32,
    pub orthographic: bool,
}

impl LightView {
    pub fn view_proj(&self) -> Mat4 {
        self.proj * self.view
    }
}

/// The views of one light over the scene bounds: spot → one perspective view over the outer
/// cone (5 % margin), point → six 90° cube faces (order of [`CUBE_FACES`]), directional → one
/// orthographic view over the bounds.
pub fn light_views(wl: &WorldLight, bounds: Aabb) -> Vec<LightView> {
    let r = bounds.radius().max(1e-3);
    let c = bounds.center();
    let dir = wl.direction.normalize_or(Vec3::NEG_Y);
    let dist_far = wl.position.distance(c) + r * 1.05;
    let near = (r * 0.002).max(1e-3);
    let far = dist_far.max(near * 2.0);
    let up_for = |d: Vec3| if d.y.abs() > 0.99 { Vec3::Z } else { Vec3::Y };
    match wl.light.kind {
        LightKind::Point => {
            let proj = glam::camera::rh::proj::directx::perspective(std::f32::consts::FRAC_PI_2, 1.0, near, far);
            CUBE_FACES
                .iter()
                .map(|(f, up)| LightView {
                    view: glam::camera::rh::view::look_to_mat4(wl.position, *f, *up),
                    proj,
                    eye: wl.position,
                    forward: *f,
                    pixel_extent: 2.0,
                    orthographic: false,
                })
                .collect()
        }
        LightKind::Spot { outer_cone, .. } => {
            let outer = outer_cone.clamp(1e-3, std::f32::consts::FRAC_PI_2 - 1e-3);
            let fov = (2.0 * outer * 1.05).min(3.0);
            vec![LightView {
                view: glam::camera::rh::view::look_to_mat4(wl.position, dir, up_for(dir)),
                proj: glam::camera::rh::proj::directx::perspective(fov, 1.0, near, far),
                eye: wl.position,
                forward: dir,
                pixel_extent: 2.0 * (fov * 0.5).tan(),
                orthographic: false,
            }]
        }
        LightKind::Directional => {
            let eye = c - dir * (2.0 * r);
            vec![LightView {
                view: glam::camera::rh::view::look_to_mat4(eye, dir, up_for(dir)),
                proj: glam::camera::rh::proj::directx::orthographic(-r, r, -r, r, 0.0, 4.0 * r),
                eye,
                forward: dir,
                pixel_extent: 2.0 * r,
                orthographic: true,
            }]
        }
    }
}

/// The GPU record of one light (shadow fields left empty).
pub fn gpu_light(wl: &WorldLight) -> GpuLight {
    let l = &wl.light;
    let dir = wl.direction.normalize_or(Vec3::NEG_Y);
    let (kind, cone) = match l.kind {
        LightKind::Point => (0.0, Vec4::new(-1.0, 1.0, 0.0, 0.0)),
        LightKind::Spot { inner_cone, outer_cone } => {
            let outer = outer_cone.clamp(1e-3, std::f32::consts::FRAC_PI_2 - 1e-3);
            let inner = inner_cone.clamp(0.0, outer);
            let (co, ci) = (outer.cos(), inner.cos());
            (1.0, Vec4::new(co, 1.0 / (ci - co).max(1e-4), 0.0, 0.0))
        }
        LightKind::Directional => (2.0, Vec4::new(-1.0, 1.0, 0.0, 0.0)),
    };
    GpuLight {
        position: wl.position.extend(kind),
        direction: dir.extend(l.range.unwrap_or(0.0)),
        color: (l.color * l.intensity).extend(0.0),
        cone,
        shadow: Vec4::ZERO,
    }
}

/// Builds the GPU light records and shadow views; `intensity_scale` is applied by the shader.
pub fn setup_lights(lights: &[WorldLight], bounds: Aabb, shadow_map_size: u32, shadows: bool) -> LightSetup {
    let mut out = LightSetup::default();
    for wl in lights {
        let mut gl = gpu_light(wl);
        let views = light_views(wl, bounds);
        if shadows {
            gl.cone.z = out.views.len() as f32;
            gl.cone.w = views.len() as f32;
            out.views.extend(views.iter().map(LightView::view_proj));
        }
        // World size of one shadow texel: at unit distance (perspective) or absolute (ortho).
        gl.shadow.x = views[0].pixel_extent / shadow_map_size as f32;
        out.lights.push(gl);
    }
    if out.lights.is_empty() {
        out.lights.push(GpuLight { position: Vec4::W, ..bytemuck::Zeroable::zeroed() });
    }
    out
}

pub struct ShadowPass {
    pipeline: wgpu::RenderPipeline,
    /// The same with the alpha-cutout fragment stage, for materials with alphaMode MASK.
    cutout: wgpu::RenderPipeline,
    view_layout: wgpu::BindGroupLayout,
    view_buffer: wgpu::Buffer,
    view_capacity: usize,
    view_group: wgpu::BindGroup,
    pub texture: wgpu::Texture,
    /// D2Array view for sampling.
    pub array_view: wgpu::TextureView,
    /// The layer size in use, and the size asked for (they differ when the atlas at the
    /// asked size did not fit the device).
    pub size: u32,
    requested: u32,
    layers: u32,
    /// Why the layers are smaller than asked, when they are.
    pub fitted: Option<String>,
    /// What the maps were last rendered for: they are kept while nothing moved (issue #53).
    pub last: crate::fingerprint::LastRun,
}

impl ShadowPass {
    pub fn new(ctx: &GpuContext, scene: &GpuScene) -> Self {
        let device = &ctx.device;
        let module = crate::shaders::create_module(device, "shadow/shadow.wgsl");
        let view_layout = DIRECT_SHADOW_VIEW_BINDINGS.layout(device);
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("direct.shadow.layout"),
            bind_group_layouts: &[Some(&view_layout), Some(&scene.instance_layout), Some(&scene.material_layout)],
            immediate_size: 0,
        });
        let pipeline = super::depth_only_pipeline(device, "direct.shadow.pipeline", &layout, &module, false);
        let cutout = super::depth_only_pipeline(device, "direct.shadow.cutout_pipeline", &layout, &module, true);
        let (view_buffer, view_group) = Self::view_resources(device, &view_layout, 8);
        let (texture, array_view) = Self::create_texture(device, 16, 1);
        Self {
            pipeline,
            cutout,
            view_layout,
            view_buffer,
            view_capacity: 8,
            view_group,
            texture,
            array_view,
            size: 16,
            requested: 16,
            layers: 1,
            fitted: None,
            last: Default::default(),
        }
    }

    fn view_resources(
        device: &wgpu::Device,
        layout: &wgpu::BindGroupLayout,
        capacity: usize,
    ) -> (wgpu::Buffer, wgpu::BindGroup) {
        let buffer = device.counted_buffer(&wgpu::BufferDescriptor {
            label: Some("direct.shadow.views"),
            size: VIEW_STRIDE * capacity as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        // One view's 64 bytes at a dynamic offset.
        let view = wgpu::BindingResource::Buffer(wgpu::BufferBinding {
            buffer: &buffer,
            offset: 0,
            size: std::num::NonZeroU64::new(64),
        });
        let group = DIRECT_SHADOW_VIEW_BINDINGS.group_labelled(device, "direct.shadow.views", layout, [view]);
        (buffer, group)
    }

    fn create_texture(device: &wgpu::Device, size: u32, layers: u32) -> (wgpu::Texture, wgpu::TextureView) {
        let texture = device.counted_texture(&wgpu::TextureDescriptor {
            label: Some("direct.shadow_map"),
            size: wgpu::Extent3d { width: size, height: size, depth_or_array_layers: layers },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Depth32Float,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                | wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        let view = texture.counted_view(&wgpu::TextureViewDescriptor {
            label: Some("direct.shadow_map.array"),
            dimension: Some(wgpu::TextureViewDimension::D2Array),
            array_layer_count: Some(layers),
            ..Default::default()
        });
        (texture, view)
    }

    /// Makes sure the atlas has `size`² texels and `layers` layers. Returns whether the
    /// texture was recreated (the registry entry must then be refreshed). An atlas the device
    /// cannot allocate (a few large point lights at 8192² need gigabytes) is made with layers
    /// half as large, and again, down to 64²: the frame renders with coarser shadows instead
    /// of failing, and [`Self::fitted`] says so (the window shows it under the settings).
    pub fn ensure(&mut self, ctx: &GpuContext, size: u32, layers: u32) -> bool {
        let layers = layers.max(1);
        let mut changed = false;
        if size != self.requested || layers != self.layers {
            let mut s = size;
            loop {
                let oom = ctx.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
                let invalid = ctx.device.push_error_scope(wgpu::ErrorFilter::Validation);
                let (t, v) = Self::create_texture(&ctx.device, s, layers);
                let failed = [pollster::block_on(invalid.pop()), pollster::block_on(oom.pop())];
                let failed = failed.into_iter().flatten().next();
                if failed.is_none() || s <= 64 {
                    if let Some(e) = failed {
                        log::error!("the shadow maps do not fit this device even at 64²: {e}");
                    }
                    self.texture = t;
                    self.array_view = v;
                    break;
                }
                s /= 2;
            }
            let gib = |s: u32| s as f64 * s as f64 * 4.0 * layers as f64 / (1u64 << 30) as f64;
            self.fitted = (s != size).then(|| {
                format!(
                    "shadow maps: {layers} layers of {size}² ({:.1} GiB) do not fit this device; they render at {s}² ({:.2} GiB)",
                    gib(size),
                    gib(s)
                )
            });
            self.size = s;
            self.requested = size;
            self.layers = layers;
            self.last.invalidate();
            changed = true;
        }
        if layers as usize > self.view_capacity {
            let cap = (layers as usize).next_power_of_two();
            let (b, g) = Self::view_resources(&ctx.device, &self.view_layout, cap);
            self.view_buffer = b;
            self.view_group = g;
            self.view_capacity = cap;
        }
        changed
    }

    pub fn register(&self, reg: &mut BufferRegistry) {
        reg.register(
            "direct.shadow_map",
            BufferKind::Depth,
            "shadow maps of the primary lights: one layer per spot / directional light, six per point light",
            &self.texture,
        );
    }

    /// Renders every shadow layer.
    pub fn run(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        slot: Option<crate::timing::Slot<'_>>,
        scene: &GpuScene,
        state: &SceneState,
        views: &[Mat4],
    ) {
        let mut data = vec![0u8; VIEW_STRIDE as usize * views.len().max(1)];
        for (i, m) in views.iter().enumerate() {
            let o = i * VIEW_STRIDE as usize;
            data[o..o + 64].copy_from_slice(bytemuck::bytes_of(m));
        }
        ctx.queue.upload(&self.view_buffer, 0, &data);
        let count = views.len().max(1);
        for layer in 0..count {
            let view = self.texture.counted_view(&wgpu::TextureViewDescriptor {
                label: Some("direct.shadow_map.layer"),
                dimension: Some(wgpu::TextureViewDimension::D2),
                base_array_layer: layer as u32,
                array_layer_count: Some(1),
                ..Default::default()
            });
            let mut pass = encoder.begin_counted_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("direct.shadow.pass"),
                color_attachments: &[],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &view,
                    depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(1.0), store: wgpu::StoreOp::Store }),
                    stencil_ops: None,
                }),
                timestamp_writes: slot.and_then(|s| s.render(layer == 0, layer + 1 == count)),
                occlusion_query_set: None,
                multiview_mask: None,
            });
            if layer < views.len() {
                pass.set_group(0, &self.view_group, &[(layer as u64 * VIEW_STRIDE) as u32]);
                pass.set_group(1, &scene.instance_group, &[]);
                scene.draw_depth(&mut pass, state, 2, (&self.pipeline, &self.cutout));
            }
        }
    }
}
