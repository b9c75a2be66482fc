//! GPU upload of a scene: one vertex and one index buffer for all primitives, a uniform
//! and bind group per material (base colour and emissive textures with a CPU-built mip chain), and a
//! storage buffer of per-draw transforms rewritten every frame.

use crate::counters::prelude::*;

use glam::Mat4;

use super::{Scene, SceneState, Vertex};
use crate::gpu::GpuContext;
use crate::gpu::bindings::{Bindings, Kind, binding};

/// Per-draw transforms; WGSL twin: `Instance` in `shaders/gbuffer/gbuffer.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct InstanceUniform {
    pub model: glam::Mat4,
    pub prev_model: glam::Mat4,
    pub normal_matrix: glam::Mat4,
}

/// Material uniform; WGSL twin: `Material` in `shaders/common/material.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct MaterialUniform {
    pub base_color: [f32; 4],
    /// DI, SI, SP, has texture.
    pub params: [f32; 4],
    /// metallic, roughness, 0, 0.
    pub extra: [f32; 4],
    /// Emitted radiance (rgb), has emissive texture.
    pub emissive: [f32; 4],
    /// Normal texture scale (0: none), has metallic-roughness texture, alpha cutoff (< 0:
    /// opaque), has occlusion texture.
    pub maps: [f32; 4],
}

/// Where one primitive lives in the shared buffers.
#[derive(Clone, Copy, Debug)]
pub struct GpuPrimitive {
    pub first_index: u32,
    pub index_count: u32,
    pub base_vertex: i32,
    pub material: usize,
}

pub struct GpuScene {
    pub vertices: wgpu::Buffer,
    pub indices: wgpu::Buffer,
    /// `[mesh][primitive]`.
    pub primitives: Vec<Vec<GpuPrimitive>>,
    pub instances: wgpu::Buffer,
    pub instance_capacity: usize,
    /// What `instances` holds (written only when the frame's transforms differ).
    uploaded: std::sync::Mutex<Vec<InstanceUniform>>,
    pub instance_layout: wgpu::BindGroupLayout,
    pub instance_group: wgpu::BindGroup,
    pub material_layout: wgpu::BindGroupLayout,
    pub material_groups: Vec<wgpu::BindGroup>,
    /// glTF `doubleSided` per material (single-sided ones are drawn with back-face culling).
    pub double_sided: Vec<bool>,
    /// Whether each material has an alpha cutout (alphaMode MASK or BLEND).
    pub cutout: Vec<bool>,
    /// Whether each material reads a texture (base colour, normal, metallic-roughness,
    /// emissive or occlusion): the camera's G-buffer draws the others with a fragment stage
    /// without texture reads ([`Self::draw_by_material`]).
    pub textured: Vec<bool>,
    /// Whether any material writes the G-buffer's emission target: it emits (factor or
    /// texture) or has an occlusion texture to show. Otherwise the camera's G-buffer leaves
    /// the target out and the compose adds no emission (issue #53).
    pub emits: bool,
    _material_buffers: Vec<wgpu::Buffer>,
    _textures: Vec<wgpu::Texture>,
    /// What the upload changed to fit the device (textures downscaled), for the scene's
    /// warnings.
    pub warnings: Vec<String>,
}

/// The instances' bind group (group 1 of the scene's raster passes: the G-buffer, the shadow
/// and light views, Gautron's hemispheres, Soler's voxels).
pub const INSTANCES_BINDINGS: Bindings = Bindings {
    label: "scene.instances",
    shader: "gbuffer/gbuffer.wgsl",
    group: 1,
    entry: None,
    visibility: wgpu::ShaderStages::VERTEX,
    list: &[binding(0, "instances", Kind::Storage { read_only: true })],
};

/// A material's bind group (group 2, `shaders/common/material.wgsl`).
pub const MATERIAL_BINDINGS: Bindings = Bindings {
    label: "scene.material",
    shader: "gbuffer/gbuffer.wgsl",
    group: 2,
    entry: None,
    visibility: wgpu::ShaderStages::FRAGMENT,
    list: &[
        binding(0, "material", Kind::Uniform),
        binding(1, "base_tex", Kind::Texture { filterable: true }),
        binding(2, "base_sampler", Kind::Sampler(wgpu::SamplerBindingType::Filtering)),
        binding(3, "emissive_tex", Kind::Texture { filterable: true }),
        binding(4, "normal_tex", Kind::Texture { filterable: true }),
        binding(5, "mr_tex", Kind::Texture { filterable: true }),
        binding(6, "occlusion_tex", Kind::Texture { filterable: true }),
    ],
};

/// The layout of a material's bind group ([`MATERIAL_BINDINGS`]); a pass that makes its own
/// pipelines before it sees the scene makes an equal one (WebGPU: bind groups of equal layouts
/// are interchangeable).
pub fn material_layout(device: &wgpu::Device, label: &str) -> wgpu::BindGroupLayout {
    MATERIAL_BINDINGS.layout_labelled(device, label)
}

/// Vertex buffer layout of [`Vertex`].
pub const VERTEX_ATTRIBUTES: [wgpu::VertexAttribute; 4] =
    wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x2, 3 => Float32x4];

pub fn vertex_layout() -> wgpu::VertexBufferLayout<'static> {
    wgpu::VertexBufferLayout {
        array_stride: std::mem::size_of::<Vertex>() as u64,
        step_mode: wgpu::VertexStepMode::Vertex,
        attributes: &VERTEX_ATTRIBUTES,
    }
}

impl GpuScene {
    pub fn new(ctx: &GpuContext, scene: &Scene) -> Self {
        let device = &ctx.device;
        let mut vertices: Vec<Vertex> = Vec::new();
        let mut indices: Vec<u32> = Vec::new();
        let mut primitives = Vec::new();
        for mesh in &scene.meshes {
            let mut list = Vec::new();
            for p in &mesh.primitives {
                list.push(GpuPrimitive {
                    first_index: indices.len() as u32,
                    index_count: p.indices.len() as u32,
                    base_vertex: vertices.len() as i32,
                    material: p.material.min(scene.materials.len().saturating_sub(1)),
                });
                vertices.extend_from_slice(&p.vertices);
                indices.extend_from_slice(&p.indices);
            }
            primitives.push(list);
        }
        if vertices.is_empty() {
            vertices.push(bytemuck::Zeroable::zeroed());
        }
        if indices.is_empty() {
            indices.extend_from_slice(&[0, 0, 0]);
        }
        let vertex_buffer = device.counted_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("scene.vertices"),
            contents: bytemuck::cast_slice(&vertices),
            usage: wgpu::BufferUsages::VERTEX,
        });
        let index_buffer = device.counted_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("scene.indices"),
            contents: bytemuck::cast_slice(&indices),
            usage: wgpu::BufferUsages::INDEX,
        });

        let draw_count = scene.evaluate(0.0).draws.len().max(1);
        let instances = device.counted_buffer(&wgpu::BufferDescriptor {
            label: Some("scene.instances"),
            size: (draw_count * std::mem::size_of::<InstanceUniform>()) as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let instance_layout = INSTANCES_BINDINGS.layout(device);
        let instance_group = INSTANCES_BINDINGS.group(device, &instance_layout, [instances.as_entire_binding()]);

        let material_layout = material_layout(device, "scene.material");
        let sampler = device.counted_sampler(&wgpu::SamplerDescriptor {
            label: Some("scene.material_sampler"),
            address_mode_u: wgpu::AddressMode::Repeat,
            address_mode_v: wgpu::AddressMode::Repeat,
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            mipmap_filter: wgpu::MipmapFilterMode::Linear,
            anisotropy_clamp: 1,
            ..Default::default()
        });
        let white = upload_texture(
            ctx,
            &super::TextureImage { name: "white".into(), width: 1, height: 1, rgba8: vec![255; 4].into() },
        );
        let mut warnings = Vec::new();
        let mut textures: Vec<wgpu::Texture> = scene
            .textures
            .iter()
            .map(|t| {
                let tex = upload_texture(ctx, t);
                if (tex.width(), tex.height()) != (t.width.max(1), t.height.max(1)) {
                    warnings.push(format!(
                        "texture '{}' is {}×{}, larger than this device allows ({}²): it was downscaled to {}×{}",
                        t.name,
                        t.width,
                        t.height,
                        ctx.limits.max_texture_dimension_2d,
                        tex.width(),
                        tex.height()
                    ));
                }
                tex
            })
            .collect();
        let mut material_buffers = Vec::new();
        let mut material_groups = Vec::new();
        let mut textured = Vec::new();
        let mut emits = false;
        let default_material = [super::Material::default()];
        let materials: &[super::Material] =
            if scene.materials.is_empty() { &default_material } else { &scene.materials };
        for (i, m) in materials.iter().enumerate() {
            let tex = m.base_color_texture.filter(|&t| t < textures.len());
            let emissive_tex = m.emissive_texture.filter(|&t| t < textures.len());
            let normal_tex = m.normal_texture.filter(|&t| t < textures.len());
            let mr_tex = m.metallic_roughness_texture.filter(|&t| t < textures.len());
            let occlusion_tex = m.occlusion_texture.filter(|&t| t < textures.len());
            textured.push([tex, emissive_tex, normal_tex, mr_tex, occlusion_tex].iter().any(Option::is_some));
            emits |= m.emissive.max_element() > 0.0 || emissive_tex.is_some() || occlusion_tex.is_some();
            let u = MaterialUniform {
                base_color: m.base_color.to_array(),
                params: [
                    m.diffuse_intensity(),
                    m.specular_intensity(),
                    m.specular_power(),
                    tex.is_some() as u32 as f32,
                ],
                extra: [m.metallic, m.roughness, 0.0, 0.0],
                emissive: m.emissive.extend(emissive_tex.is_some() as u32 as f32).to_array(),
                maps: [
                    if normal_tex.is_some() { m.normal_scale } else { 0.0 },
                    mr_tex.is_some() as u32 as f32,
                    m.alpha_cutoff.unwrap_or(-1.0),
                    occlusion_tex.is_some() as u32 as f32,
                ],
            };
            let buffer = device.counted_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(&format!("scene.material[{i}]")),
                contents: bytemuck::bytes_of(&u),
                usage: wgpu::BufferUsages::UNIFORM,
            });
            let view = tex.map(|t| &textures[t]).unwrap_or(&white).counted_view(&wgpu::TextureViewDescriptor {
                label: Some("scene.material_texture"),
                ..Default::default()
            });
            let emissive_view =
                emissive_tex.map(|t| &textures[t]).unwrap_or(&white).counted_view(&wgpu::TextureViewDescriptor {
                    label: Some("scene.material_emissive_texture"),
                    ..Default::default()
                });
            // Data textures are read through linear views of the same sRGB-stored texels.
            let linear = |t: Option<usize>, label: &str| {
                t.map(|t| &textures[t]).unwrap_or(&white).counted_view(&wgpu::TextureViewDescriptor {
                    label: Some(label),
                    format: Some(wgpu::TextureFormat::Rgba8Unorm),
                    ..Default::default()
                })
            };
            let normal_view = linear(normal_tex, "scene.material_normal_texture");
            let mr_view = linear(mr_tex, "scene.material_metallic_roughness_texture");
            let occlusion_view = linear(occlusion_tex, "scene.material_occlusion_texture");
            let tv = wgpu::BindingResource::TextureView;
            material_groups.push(MATERIAL_BINDINGS.group_labelled(
                device,
                &format!("scene.material[{i}]"),
                &material_layout,
                [
                    buffer.as_entire_binding(),
                    tv(&view),
                    wgpu::BindingResource::Sampler(&sampler),
                    tv(&emissive_view),
                    tv(&normal_view),
                    tv(&mr_view),
                    tv(&occlusion_view),
                ],
            ));
            material_buffers.push(buffer);
        }
        textures.push(white);
        let double_sided = materials.iter().map(|m| m.double_sided).collect();
        let cutout = materials.iter().map(|m| m.alpha_cutoff.is_some()).collect();
        Self {
            double_sided,
            cutout,
            textured,
            emits,
            vertices: vertex_buffer,
            indices: index_buffer,
            primitives,
            instances,
            instance_capacity: draw_count,
            uploaded: Default::default(),
            instance_layout,
            instance_group,
            material_layout,
            material_groups,
            _material_buffers: material_buffers,
            _textures: textures,
            warnings,
        }
    }

    /// Writes this frame's transforms; `prev` holds last frame's world matrices in the same
    /// draw order (None on the first frame: no motion).
    pub fn update_instances(&self, ctx: &GpuContext, state: &SceneState, prev: Option<&[Mat4]>) {
        let data: Vec<InstanceUniform> = state
            .draws
            .iter()
            .take(self.instance_capacity)
            .enumerate()
            .map(|(i, d)| InstanceUniform {
                model: d.world,
                prev_model: prev.and_then(|p| p.get(i)).copied().unwrap_or(d.world),
                normal_matrix: d.world.inverse().transpose(),
            })
            .collect();
        // Static scenes upload their transforms once (issue #38): only a change is written.
        let mut last = self.uploaded.lock().unwrap_or_else(|p| p.into_inner());
        if !data.is_empty() && *last != data {
            ctx.queue.upload(&self.instances, 0, bytemuck::cast_slice(&data));
            *last = data;
        }
    }

    /// Issues the draws of `state`. The caller binds the instance group; materials are
    /// bound at `material_group` when given, and `pipelines` = (single-sided,
    /// double-sided) switches the pipeline by the material's culling mode when given.
    pub fn draw(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        state: &SceneState,
        material_group: Option<u32>,
        pipelines: Option<(&wgpu::RenderPipeline, &wgpu::RenderPipeline)>,
    ) {
        self.draw_by_material(pass, state, material_group, pipelines.map(|p| (p, p)));
    }

    /// [`Self::draw`] with pipelines `(textured, plain)`, each (single-sided, double-sided):
    /// materials without textures take the plain ones.
    pub fn draw_by_material(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        state: &SceneState,
        material_group: Option<u32>,
        pipelines: Option<PipelinePairs<'_>>,
    ) {
        self.bind_geometry(pass);
        for (inst, p) in self.primitives_of(state) {
            if let Some((textured, plain)) = pipelines {
                let ds = self.double_sided.get(p.material).copied().unwrap_or(true);
                let tex = self.textured.get(p.material).copied().unwrap_or(true);
                let (single, double) = if tex { textured } else { plain };
                pass.set_pipe(if ds { double } else { single });
            }
            if let Some(g) = material_group {
                pass.set_group(g, &self.material_groups[p.material.min(self.material_groups.len() - 1)], &[]);
            }
            pass.draw_indexed_counted(p.first_index..p.first_index + p.index_count, p.base_vertex, inst..inst + 1);
        }
    }
}

/// Pipelines (single-sided, double-sided) for textured materials, then for the others.
pub type PipelinePairs<'a> =
    ((&'a wgpu::RenderPipeline, &'a wgpu::RenderPipeline), (&'a wgpu::RenderPipeline, &'a wgpu::RenderPipeline));

impl GpuScene {
    /// Binds the shared vertex and index buffers.
    fn bind_geometry(&self, pass: &mut wgpu::RenderPass<'_>) {
        pass.vertex_buffer(0, &self.vertices);
        pass.index_buffer(&self.indices, wgpu::IndexFormat::Uint32);
    }

    /// The non-empty primitives `state` draws, with their instance index, in draw order (the
    /// order of every draw method and of [`Self::indexed_draws`]).
    fn primitives_of<'a>(&'a self, state: &'a SceneState) -> impl Iterator<Item = (u32, &'a GpuPrimitive)> + 'a {
        state.draws.iter().take(self.instance_capacity).enumerate().filter_map(|(i, d)| {
            let p = self.primitives.get(d.mesh).and_then(|m| m.get(d.primitive))?;
            (p.index_count > 0).then_some((i as u32, p))
        })
    }

    /// Draws `state` into a depth-only view: opaque materials with `opaque`, alpha-masked ones
    /// with `cutout` (its fragment stage reads the material group `material_group`).
    pub fn draw_depth(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        state: &SceneState,
        material_group: u32,
        (opaque, cutout): (&wgpu::RenderPipeline, &wgpu::RenderPipeline),
    ) {
        self.bind_geometry(pass);
        for (inst, p) in self.primitives_of(state) {
            let m = p.material.min(self.material_groups.len() - 1);
            // Both pipelines share one layout, whose material group must be bound.
            pass.set_pipe(if self.cutout.get(m).copied().unwrap_or(false) { cutout } else { opaque });
            pass.set_group(material_group, &self.material_groups[m], &[]);
            pass.draw_indexed_counted(p.first_index..p.first_index + p.index_count, p.base_vertex, inst..inst + 1);
        }
    }

    /// The indexed draws [`Self::draw`] issues for `state`: (first index, index count, base
    /// vertex, instance), in its order.
    pub fn indexed_draws(&self, state: &SceneState) -> Vec<(u32, u32, i32, u32)> {
        self.primitives_of(state).map(|(i, p)| (p.first_index, p.index_count, p.base_vertex, i)).collect()
    }

    /// [`Self::draw_by_material`] with indirect draws: draw k of [`Self::indexed_draws`] reads its
    /// arguments (5 words) at k·20 bytes of `args` (Gautron's hemispheres: the instance count
    /// is written by the GPU).
    pub fn draw_indirect(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        state: &SceneState,
        material_group: u32,
        (textured, plain): PipelinePairs<'_>,
        args: &wgpu::Buffer,
    ) {
        self.bind_geometry(pass);
        for (k, (_, p)) in self.primitives_of(state).enumerate() {
            let ds = self.double_sided.get(p.material).copied().unwrap_or(true);
            let tex = self.textured.get(p.material).copied().unwrap_or(true);
            let (single, double) = if tex { textured } else { plain };
            pass.set_pipe(if ds { double } else { single });
            pass.set_group(material_group, &self.material_groups[p.material.min(self.material_groups.len() - 1)], &[]);
            pass.draw_indexed_indirect_counted(args, k as u64 * 20);
        }
    }
}

/// Uploads an sRGB RGBA8 image with a box-filtered mip chain; levels larger than the
/// device allows are dropped (the texture starts at the first level that fits).
fn upload_texture(ctx: &GpuContext, img: &super::TextureImage) -> wgpu::Texture {
    let (w, h) = (img.width.max(1), img.height.max(1));
    let max_dim = ctx.limits.max_texture_dimension_2d;
    let base = if img.rgba8.len() == (w as usize * h as usize * 4) {
        img.clone()
    } else {
        super::TextureImage {
            name: img.name.clone(),
            width: w,
            height: h,
            rgba8: vec![255; (w * h * 4) as usize].into(),
        }
    };
    let mut chain: Vec<(u32, u32, std::sync::Arc<[u8]>)> =
        std::iter::once(&base).chain(base.box_mips().iter()).map(|t| (t.width, t.height, t.rgba8.clone())).collect();
    chain.retain(|(cw, ch, _)| *cw <= max_dim && *ch <= max_dim);
    let (bw, bh, _) = chain[0];
    let tex = ctx.device.counted_texture(&wgpu::TextureDescriptor {
        label: Some(&format!("scene.texture.{}", img.name)),
        size: wgpu::Extent3d { width: bw, height: bh, depth_or_array_layers: 1 },
        mip_level_count: chain.len() as u32,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba8UnormSrgb,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        // Normal, metallic-roughness and occlusion maps are read through linear views.
        view_formats: &[wgpu::TextureFormat::Rgba8Unorm],
    });
    for (mip, (cw, ch, data)) in chain.iter().enumerate() {
        ctx.queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: &tex,
                mip_level: mip as u32,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            data,
            wgpu::TexelCopyBufferLayout { offset: 0, bytes_per_row: Some(cw * 4), rows_per_image: Some(*ch) },
            wgpu::Extent3d { width: *cw, height: *ch, depth_or_array_layers: 1 },
        );
    }
    tex
}
