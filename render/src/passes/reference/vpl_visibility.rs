//! Stage 4, exact visibility of the VPLs (docs/principles.md's pipeline table: "exact shadow
//! maps (reference)"): every VPL of a batch gets five 90° depth maps — the faces of a cube
//! oriented on its normal that cover its hemisphere — rendered from the real triangles into
//! one `Depth32Float` atlas (`vpl.shadow_atlas`). The reference Knecht 002 §5.2 measures
//! imperfect shadow maps against.
//! Shaders: `shaders/reference/shadow.wgsl`; the face geometry is in `shaders/common/vpl.wgsl`.
//!
//! Departure from a paraboloid map per VPL (the form ISMs take): a paraboloid projection
//! bends straight triangle edges, so large triangles render wrong; cube faces are exact.

use crate::counters::prelude::*;

use crate::buffers::{BufferKind, BufferRegistry};
use crate::gpu::GpuContext;
use crate::gpu::bindings::{Bindings, Kind, binding};
pub use crate::passes::stages::GatherVisibility;
use crate::passes::stages::{FrameInputs, VplSet};
use crate::scene::SceneState;
use crate::scene::upload::GpuScene;
use crate::timing::GpuTimer;
use crate::timing::PassRec;

/// Bind group `vpl.shadow.inputs` of `shaders/reference/shadow.wgsl` (group 0).
pub const SHADOW_INPUTS_BINDINGS: Bindings = Bindings {
    label: "vpl.shadow.inputs",
    shader: "reference/shadow.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::VERTEX,
    list: &[
        binding(0, "face", Kind::UniformDynamic),
        binding(1, "params", Kind::Uniform),
        binding(2, "vpls", Kind::Storage { read_only: true }),
    ],
};

/// Faces per VPL (`VPL_FACES` in `shaders/common/vpl.wgsl`).
pub const FACES: u32 = 5;

/// Uniform stride of the per-face index (dynamic offsets need 256-byte alignment).
const FACE_STRIDE: u64 = 256;

/// Uniform of the depth render and of the gather's lookups; WGSL twin: `Params` in
/// `shaders/reference/shadow.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct VisibilityParams {
    /// x: near, y: far, z: eye offset along the VPL normal (scene units).
    pub clip: glam::Vec4,
}

/// Layout of the atlas: `cols` × `rows` tiles of `size`² texels, tile = VPL × 5 + face.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AtlasLayout {
    pub size: u32,
    pub cols: u32,
    pub rows: u32,
}

impl AtlasLayout {
    /// A near-square grid for `vpls` VPLs of five `size`² faces each.
    pub fn new(vpls: u32, size: u32) -> Self {
        let tiles = vpls.max(1) * FACES;
        let cols = (tiles as f64).sqrt().ceil() as u32;
        Self { size, cols, rows: tiles.div_ceil(cols) }
    }
    pub fn width(&self) -> u64 {
        self.cols as u64 * self.size as u64
    }
    pub fn height(&self) -> u64 {
        self.rows as u64 * self.size as u64
    }
    /// Whether the atlas fits a device whose textures have at most `max_dim` texels a side.
    pub fn fits(&self, max_dim: u32) -> bool {
        self.width() <= max_dim as u64 && self.height() <= max_dim as u64
    }
    /// The most VPLs per batch whose atlas of `size`² faces fits `max_dim`.
    pub fn largest_batch(size: u32, max_dim: u32) -> u32 {
        let per_side = (max_dim / size.max(1)) as u64;
        let tiles = per_side * per_side;
        let mut n = (tiles / FACES as u64) as u32;
        while n > 0 && !Self::new(n, size).fits(max_dim) {
            n -= 1;
        }
        n
    }
}

pub struct VplVisibilityPass {
    pipeline: wgpu::RenderPipeline,
    /// The same with the alpha-cutout fragment stage, for materials with alphaMode MASK.
    cutout: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    faces: wgpu::Buffer,
    face_capacity: u32,
    pub params: wgpu::Buffer,
    pub atlas: wgpu::Texture,
    pub atlas_view: wgpu::TextureView,
    pub layout_info: AtlasLayout,
}

impl VplVisibilityPass {
    pub fn new(ctx: &GpuContext, scene: &GpuScene) -> Self {
        let device = &ctx.device;
        let module = crate::shaders::create_module(device, "reference/shadow.wgsl");
        let layout = SHADOW_INPUTS_BINDINGS.layout(device);
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("vpl.shadow.layout"),
            bind_group_layouts: &[Some(&layout), Some(&scene.instance_layout), Some(&scene.material_layout)],
            immediate_size: 0,
        });
        let pipeline =
            crate::passes::depth_only_pipeline(device, "vpl.shadow.pipeline", &pipeline_layout, &module, false);
        let cutout =
            crate::passes::depth_only_pipeline(device, "vpl.shadow.cutout_pipeline", &pipeline_layout, &module, true);
        let params = device.counted_buffer(&wgpu::BufferDescriptor {
            label: Some("vpl.shadow.params"),
            size: std::mem::size_of::<VisibilityParams>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let layout_info = AtlasLayout::new(1, 16);
        let (atlas, atlas_view) = Self::create_atlas(device, layout_info);
        let faces = Self::face_buffer(ctx, FACES);
        Self { pipeline, cutout, layout, faces, face_capacity: FACES, params, atlas, atlas_view, layout_info }
    }

    fn create_atlas(device: &wgpu::Device, l: AtlasLayout) -> (wgpu::Texture, wgpu::TextureView) {
        let atlas = crate::passes::create_target(
            device,
            "vpl.shadow_atlas",
            l.width() as u32,
            l.height() as u32,
            wgpu::TextureFormat::Depth32Float,
            wgpu::TextureUsages::RENDER_ATTACHMENT,
        );
        let view = crate::passes::view(&atlas, "vpl.shadow_atlas");
        (atlas, view)
    }

    /// One 256-byte uniform slot per face: (VPL, face, tile, 0).
    fn face_buffer(ctx: &GpuContext, tiles: u32) -> wgpu::Buffer {
        let buffer = ctx.device.counted_buffer(&wgpu::BufferDescriptor {
            label: Some("vpl.shadow.faces"),
            size: FACE_STRIDE * tiles as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut data = vec![0u8; (FACE_STRIDE * tiles as u64) as usize];
        for tile in 0..tiles {
            let o = (tile as u64 * FACE_STRIDE) as usize;
            let idx = [tile / FACES, tile % FACES, tile, 0];
            data[o..o + 16].copy_from_slice(bytemuck::cast_slice(&idx));
        }
        ctx.queue.upload(&buffer, 0, &data);
        buffer
    }

    /// Sizes the atlas for `vpls` VPLs of `size`² faces (the caller checked that it fits).
    /// Returns whether it was recreated (the registry entry must be refreshed).
    pub fn ensure(&mut self, ctx: &GpuContext, vpls: u32, size: u32) -> bool {
        let l = AtlasLayout::new(vpls, size);
        let tiles = vpls * FACES;
        if tiles > self.face_capacity {
            self.faces = Self::face_buffer(ctx, tiles);
            self.face_capacity = tiles;
        }
        if l == self.layout_info {
            return false;
        }
        (self.atlas, self.atlas_view) = Self::create_atlas(&ctx.device, l);
        self.layout_info = l;
        true
    }

    pub fn register(&self, reg: &mut BufferRegistry) {
        reg.register(
            "vpl.shadow_atlas",
            BufferKind::Depth,
            "exact visibility of this batch's VPLs: five 90° cube faces on each VPL's normal, tile = VPL × 5 + face",
            &self.atlas,
        );
    }

    /// Renders the five faces of each of the first `vpls` VPLs of `vpl_list`.
    pub fn run(
        &self,
        r: PassRec<'_, '_>,
        scene: &GpuScene,
        state: &SceneState,
        vpl_list: &wgpu::Buffer,
        vpls: u32,
        params: VisibilityParams,
    ) {
        let PassRec { ctx, enc: encoder, slot } = r;
        ctx.queue.upload(&self.params, 0, bytemuck::bytes_of(&params));
        let group = SHADOW_INPUTS_BINDINGS.group(
            &ctx.device,
            &self.layout,
            [
                wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                    buffer: &self.faces,
                    offset: 0,
                    size: std::num::NonZeroU64::new(16),
                }),
                self.params.as_entire_binding(),
                vpl_list.as_entire_binding(),
            ],
        );
        let mut pass = encoder.begin_counted_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("vpl.shadow.pass"),
            color_attachments: &[],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &self.atlas_view,
                depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Clear(1.0), store: wgpu::StoreOp::Store }),
                stencil_ops: None,
            }),
            timestamp_writes: slot.and_then(|s| s.render(true, true)),
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_group(1, &scene.instance_group, &[]);
        let l = self.layout_info;
        for tile in 0..vpls.min(self.face_capacity / FACES) * FACES {
            let (x, y) = ((tile % l.cols) * l.size, (tile / l.cols) * l.size);
            pass.set_viewport(x as f32, y as f32, l.size as f32, l.size as f32, 0.0, 1.0);
            pass.set_scissor_rect(x, y, l.size, l.size);
            pass.set_group(0, &group, &[(tile as u64 * FACE_STRIDE) as u32]);
            scene.draw_depth(&mut pass, state, 2, (&self.pipeline, &self.cutout));
        }
    }

    /// Stage 4 "exact": renders the maps of `vpls` (scope `vpl.shadow`; unless `render` is
    /// false, which keeps the last ones, made for the same VPLs: issue #53) and returns them
    /// as the gathers read them; `clip` as [`crate::passes::stages::vpl_clip`] makes it.
    pub fn exact_visibility(
        &self,
        f: &FrameInputs,
        enc: &mut wgpu::CommandEncoder,
        timer: &mut GpuTimer,
        vpls: &VplSet,
        (clip, render): (glam::Vec4, bool),
    ) -> GatherVisibility {
        let (ctx, scene, state) = (f.ctx, f.gpu_scene, f.state);
        if render {
            timer.scope(ctx, enc, "vpl.shadow", |e, slot| {
                self.run(PassRec { ctx, enc: e, slot }, scene, state, &vpls.list, vpls.count, VisibilityParams { clip })
            });
        }
        let l = self.layout_info;
        GatherVisibility::Exact { atlas: self.atlas_view.clone(), cols: l.cols, size: l.size, clip: clip.truncate() }
    }
}

/// 1×1 stand-ins for the atlases a gather does not read (an ISM and an exact one).
pub fn no_visibility_atlases(device: &wgpu::Device, label: &str) -> (wgpu::TextureView, wgpu::TextureView) {
    let make = |name: String, format| {
        crate::passes::view(
            &crate::passes::create_target(device, &name, 1, 1, format, wgpu::TextureUsages::empty()),
            &name,
        )
    };
    (
        make(format!("{label}.no_ism"), wgpu::TextureFormat::R32Float),
        make(format!("{label}.no_exact"), wgpu::TextureFormat::Depth32Float),
    )
}
