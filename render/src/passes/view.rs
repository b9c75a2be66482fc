//! The buffer viewer's colour mapping (docs/principles.md principle 6; RenderDoc's texture viewer):
//! one pass that turns any registered buffer — float, uint or depth, 2D or array, any mip
//! level — into a display-encoded RGBA8 image. Raw texels are fetched, never filtered, so
//! every format shows safely (egui only ever samples the RGBA8 result). Shader:
//! `shaders/view/view.wgsl`; CPU twin: `crate::cpu::view`.
//!
//! The pass is not part of the frame: each viewer owns a [`BufferView`] (its own uniform
//! and output) and runs it after the frame on the buffer it shows.

use crate::counters::prelude::*;

use std::sync::Arc;

use glam::{UVec4, Vec4};

use crate::buffers::{BufferEntry, BufferError};
use crate::gpu::GpuContext;
use crate::gpu::bindings::{Bindings, Kind, binding};
pub use crate::settings::view::Colormap;
pub use crate::settings::view::{ViewMode, ViewSettings};

/// Bind group `view.inputs` of `shaders/view/view.wgsl` (group 0): the viewer's parameters,
/// one source texture per kind (the buffer's own at its kind's binding, 1×1 stand-ins at the
/// others), the colour maps and the auto-range statistics.
pub const VIEW_INPUTS_BINDINGS: Bindings = Bindings {
    label: "view.inputs",
    shader: "view/view.wgsl",
    group: 0,
    entry: None,
    visibility: wgpu::ShaderStages::FRAGMENT.union(wgpu::ShaderStages::COMPUTE),
    list: &[
        binding(0, "params", Kind::Uniform),
        binding(1, "src_float", Kind::Texture { filterable: false }),
        binding(2, "src_float_array", Kind::TextureArray { filterable: false }),
        binding(3, "src_uint", Kind::UintTexture),
        binding(4, "src_uint_array", Kind::UintTextureArray),
        binding(5, "src_depth", Kind::Depth),
        binding(6, "src_depth_array", Kind::DepthArray),
        binding(7, "colormaps", Kind::Storage { read_only: true }),
        binding(8, "range_stats", Kind::Storage { read_only: false }),
    ],
};

/// Uniform of the view pass; WGSL twin: `ViewParams` in `shaders/view/view.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ViewParams {
    pub range: Vec4,
    pub modes: UVec4,
    pub source: UVec4,
}

/// How the shader must read a texture (`params.modes.w >> 8`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SourceKind {
    Float = 0,
    FloatArray = 1,
    Uint = 2,
    UintArray = 3,
    Depth = 4,
    DepthArray = 5,
}

impl SourceKind {
    /// The kind for a texture, or None for formats the viewer cannot read (signed ints).
    pub fn of(texture: &wgpu::Texture) -> Option<Self> {
        let array = texture.depth_or_array_layers() > 1;
        let aspect = texture.format().is_depth_stencil_format().then_some(wgpu::TextureAspect::DepthOnly);
        Some(match (texture.format().sample_type(aspect, None)?, array) {
            (wgpu::TextureSampleType::Float { .. }, false) => Self::Float,
            (wgpu::TextureSampleType::Float { .. }, true) => Self::FloatArray,
            (wgpu::TextureSampleType::Uint, false) => Self::Uint,
            (wgpu::TextureSampleType::Uint, true) => Self::UintArray,
            (wgpu::TextureSampleType::Depth, false) => Self::Depth,
            (wgpu::TextureSampleType::Depth, true) => Self::DepthArray,
            _ => return None,
        })
    }

    fn binding(self) -> u32 {
        self as u32 + 1
    }

    fn dimension(self) -> wgpu::TextureViewDimension {
        match self {
            Self::FloatArray | Self::UintArray | Self::DepthArray => wgpu::TextureViewDimension::D2Array,
            _ => wgpu::TextureViewDimension::D2,
        }
    }
}

impl ViewParams {
    pub fn new(s: &ViewSettings, source: SourceKind) -> Self {
        let flags = s.log as u32 | (s.srgb as u32) << 1 | (s.flag_nan_inf as u32) << 2 | (s.flag_negative as u32) << 3;
        let mode = match s.mode {
            ViewMode::Rgb => 0,
            ViewMode::Channel => 1,
            ViewMode::Length => 2,
        };
        Self {
            range: Vec4::new(s.range[0], s.range[1], s.exposure_ev.exp2(), 0.0),
            modes: UVec4::new(mode, s.channel.min(3), s.colormap as u32, flags | (source as u32) << 8),
            source: UVec4::new(s.layer, s.level, 0, 0),
        }
    }
}

/// Output format of the view: display-encoded values; sample it through an
/// `Rgba8UnormSrgb` view (listed in its view formats) to get linear colour.
pub const VIEW_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

/// Pipeline, layout and the 1×1 stand-ins for the bindings a source does not use; shared
/// by every viewer.
pub struct ViewPipeline {
    pipeline: wgpu::RenderPipeline,
    /// The auto-range's reduction (`cs_range_*` in view.wgsl): clear, min–max, histogram.
    range: [wgpu::ComputePipeline; 3],
    layout: wgpu::BindGroupLayout,
    dummies: Vec<wgpu::TextureView>,
    colormaps: wgpu::Buffer,
}

impl ViewPipeline {
    pub fn new(ctx: &GpuContext) -> Arc<Self> {
        let device = &ctx.device;
        let layout = VIEW_INPUTS_BINDINGS.layout(device);
        let module = crate::shaders::create_module(device, "view/view.wgsl");
        let range = ["cs_range_clear", "cs_range_minmax", "cs_range_histogram"]
            .map(|entry| super::compute_pipeline(device, &format!("view.{entry}"), &module, entry, &[&layout]));
        let pl = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("view.pipeline_layout"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = device.counted_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("view.pipeline"),
            layout: Some(&pl),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: Default::default(),
            depth_stencil: None,
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &[Some(VIEW_FORMAT.into())],
            }),
            multiview_mask: None,
            cache: None,
        });
        let dummy = |label: &str, format, layers| {
            let t = device.counted_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size: wgpu::Extent3d { width: 1, height: 1, depth_or_array_layers: layers },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage: wgpu::TextureUsages::TEXTURE_BINDING,
                view_formats: &[],
            });
            let dimension =
                if layers > 1 { wgpu::TextureViewDimension::D2Array } else { wgpu::TextureViewDimension::D2 };
            t.counted_view(&wgpu::TextureViewDescriptor {
                label: Some(label),
                dimension: Some(dimension),
                ..Default::default()
            })
        };
        use wgpu::TextureFormat as F;
        let dummies = vec![
            dummy("view.dummy_float", F::Rgba32Float, 1),
            dummy("view.dummy_float_array", F::Rgba32Float, 2),
            dummy("view.dummy_uint", F::R32Uint, 1),
            dummy("view.dummy_uint_array", F::R32Uint, 2),
            dummy("view.dummy_depth", F::Depth32Float, 1),
            dummy("view.dummy_depth_array", F::Depth32Float, 2),
        ];
        let table: Vec<[f32; 4]> = crate::maths::colormap::COLORMAP_TABLES
            .iter()
            .flat_map(|t| t.iter().map(|c| [c[0], c[1], c[2], 1.0]))
            .collect();
        let colormaps = wgpu::util::DeviceExt::create_buffer_init(
            device,
            &wgpu::util::BufferInitDescriptor {
                label: Some("view.colormaps"),
                contents: bytemuck::cast_slice(&table),
                usage: wgpu::BufferUsages::STORAGE,
            },
        );
        Arc::new(Self { pipeline, range, layout, dummies, colormaps })
    }
}

/// One viewer's state on the GPU: its uniform, its output image and its auto-range
/// statistics.
pub struct BufferView {
    shared: Arc<ViewPipeline>,
    params: wgpu::Buffer,
    output: Option<wgpu::Texture>,
    range_stats: wgpu::Buffer,
}

impl BufferView {
    pub fn new(ctx: &GpuContext, shared: Arc<ViewPipeline>) -> Self {
        let params = ctx.device.counted_buffer(&wgpu::BufferDescriptor {
            label: Some("view.params"),
            size: std::mem::size_of::<ViewParams>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let range_stats = ctx.device.counted_buffer(&wgpu::BufferDescriptor {
            label: Some("view.range_stats"),
            size: crate::maths::colormap::RANGE_STATS_BYTES,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        Self { shared, params, output: None, range_stats }
    }

    /// The auto-range's statistics of the last [`BufferView::render`] asked for them
    /// (`cpu::view::RANGE_STATS_BYTES`, decoded by `cpu::view::range_from_stats`): read it
    /// back, without waiting, with `Readback::Storage`.
    pub fn range_stats(&self) -> &wgpu::Buffer {
        &self.range_stats
    }

    /// The last output (None before the first [`BufferView::render`]).
    pub fn output(&self) -> Option<&wgpu::Texture> {
        self.output.as_ref()
    }

    /// Maps `entry` (its `settings.layer` and `settings.level`) to colour; the output has
    /// the size of that level. With `range`, also reduces the values the mode shows into
    /// [`BufferView::range_stats`] (min, max and a histogram, for the auto-range). Returns
    /// whether the output texture was (re)created, so that a UI can re-point its texture
    /// handle.
    pub fn render(
        &mut self,
        ctx: &GpuContext,
        entry: &BufferEntry,
        settings: &ViewSettings,
        range: bool,
    ) -> Result<bool, BufferError> {
        let t = &entry.texture;
        let name = entry.name.clone();
        let source = SourceKind::of(t).ok_or(BufferError::Format { name: name.clone(), format: t.format() })?;
        if settings.level >= t.mip_level_count() {
            return Err(BufferError::Range { name, what: "level", have: t.mip_level_count(), want: settings.level });
        }
        if settings.layer >= t.depth_or_array_layers() {
            return Err(BufferError::Range {
                name,
                what: "layer",
                have: t.depth_or_array_layers(),
                want: settings.layer,
            });
        }
        let (w, h) = ((t.width() >> settings.level).max(1), (t.height() >> settings.level).max(1));
        let recreated = self.output.as_ref().is_none_or(|o| o.width() != w || o.height() != h);
        if recreated {
            self.output = Some(ctx.device.counted_texture(&wgpu::TextureDescriptor {
                label: Some("view.output"),
                size: wgpu::Extent3d { width: w, height: h, depth_or_array_layers: 1 },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: VIEW_FORMAT,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                    | wgpu::TextureUsages::TEXTURE_BINDING
                    | wgpu::TextureUsages::COPY_SRC,
                view_formats: &[wgpu::TextureFormat::Rgba8UnormSrgb],
            }));
        }
        let Some(output) = &self.output else { return Ok(recreated) };
        ctx.queue.upload(&self.params, 0, bytemuck::bytes_of(&ViewParams::new(settings, source)));
        let aspect = if t.format().is_depth_stencil_format() {
            wgpu::TextureAspect::DepthOnly
        } else {
            wgpu::TextureAspect::All
        };
        let src_view = t.counted_view(&wgpu::TextureViewDescriptor {
            label: Some("view.source"),
            dimension: Some(source.dimension()),
            aspect,
            ..Default::default()
        });
        // Bindings 1–6: the source at its kind's binding, the stand-ins at the others.
        let sources = self.shared.dummies.iter().enumerate().map(|(i, dummy)| {
            let view = if i as u32 + 1 == source.binding() { &src_view } else { dummy };
            wgpu::BindingResource::TextureView(view)
        });
        let group = VIEW_INPUTS_BINDINGS.group(
            &ctx.device,
            &self.shared.layout,
            std::iter::once(self.params.as_entire_binding())
                .chain(sources)
                .chain([self.shared.colormaps.as_entire_binding(), self.range_stats.as_entire_binding()]),
        );
        let out_view =
            output.counted_view(&wgpu::TextureViewDescriptor { label: Some("view.output"), ..Default::default() });
        let mut enc =
            ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("view.encoder") });
        if range {
            let mut pass = enc
                .begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("view.range"), timestamp_writes: None });
            pass.set_group(0, &group, &[]);
            let [clear, minmax, histogram] = &self.shared.range;
            pass.set_pipe(clear);
            pass.dispatch(((crate::maths::colormap::RANGE_STATS_BYTES / 4) as u32).div_ceil(256), 1, 1);
            for pipeline in [minmax, histogram] {
                pass.set_pipe(pipeline);
                pass.dispatch(w.div_ceil(8), h.div_ceil(8), 1);
            }
        }
        {
            let mut pass = enc.begin_counted_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("view.pass"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &out_view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipe(&self.shared.pipeline);
            pass.set_group(0, &group, &[]);
            pass.draw_counted(0..3, 0..1);
        }
        ctx.submit([enc.finish()]);
        Ok(recreated)
    }
}
