//! The kit's objects on a plain wgpu device: every resource of `resources` (zeroed, as a
//! fresh start needs), each shader module from the kit's WGSL, and each pipeline with a
//! layout made from what the step binds and what the shaders declare (docs/port-kit.md,
//! "Bringing a kit up").

use std::collections::{BTreeMap, HashMap};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

use crate::kit::{Binding, Manifest, Pipeline, Resource, Step};
use crate::names;

/// A stage's constants as wgpu takes them.
fn constants(c: &[(String, f64)]) -> Vec<(&str, f64)> {
    c.iter().map(|(k, v)| (k.as_str(), *v)).collect()
}

/// A texture of the kit with what a host needs to copy it.
pub struct Texture {
    pub texture: wgpu::Texture,
    pub format: wgpu::TextureFormat,
}

/// The device and every object of the kit, by the manifest's names.
pub struct Host {
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub adapter: wgpu::Adapter,
    pub kit: PathBuf,
    pub textures: HashMap<String, Texture>,
    pub buffers: HashMap<String, wgpu::Buffer>,
    samplers: HashMap<String, (wgpu::Sampler, bool)>,
    modules: HashMap<String, wgpu::ShaderModule>,
    compute: HashMap<String, wgpu::ComputePipeline>,
    render: HashMap<String, wgpu::RenderPipeline>,
    /// wgpu's validation errors since the last [`Host::take_errors`].
    errors: Arc<Mutex<Vec<String>>>,
    /// Staging buffers for read-backs, by size (`run::read_back`).
    pub staging: Mutex<HashMap<u64, wgpu::Buffer>>,
}

/// A pipeline made for one step.
pub enum Made {
    Compute(wgpu::ComputePipeline),
    Render(wgpu::RenderPipeline),
}

impl Host {
    /// Opens a device with the kit's features and limits, and makes its resources.
    pub fn new(kit: &Path, m: &Manifest) -> Result<Host, String> {
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        let backends = wgpu::Backends::from_env().unwrap_or(wgpu::Backends::all());
        let need = names::features(&m.device.features)?;
        let optional = names::features(&m.device.optional_features)?;
        let adapters = pollster::block_on(instance.enumerate_adapters(backends));
        let adapter = adapters
            .into_iter()
            .filter(|a| a.features().contains(need))
            .max_by_key(|a| a.get_info().backend == wgpu::Backend::Vulkan)
            .ok_or_else(|| format!("no adapter has the kit's features {:?}", m.device.features))?;
        let limits = adapter.limits();
        for (name, &value) in &m.device.limits {
            let have = match name.as_str() {
                "max_color_attachment_bytes_per_sample" => limits.max_color_attachment_bytes_per_sample as u64,
                other => return Err(format!("the kit needs the limit `{other}`, which this host does not know")),
            };
            if have < value {
                return Err(format!("the adapter's {name} is {have}, the kit needs {value}"));
            }
        }
        let desc = wgpu::DeviceDescriptor {
            label: Some("port-kit-host.device"),
            required_features: need | (optional & adapter.features()),
            required_limits: limits,
            experimental_features: wgpu::ExperimentalFeatures::disabled(),
            memory_hints: wgpu::MemoryHints::Performance,
            trace: wgpu::Trace::Off,
        };
        let (device, queue) = pollster::block_on(adapter.request_device(&desc)).map_err(|e| e.to_string())?;
        let errors = Arc::new(Mutex::new(Vec::new()));
        let sink = errors.clone();
        device.on_uncaptured_error(Arc::new(move |e| {
            if let Ok(mut v) = sink.lock() {
                v.push(e.to_string());
            }
        }));
        let mut host = Host {
            device,
            queue,
            adapter,
            kit: kit.to_path_buf(),
            textures: HashMap::new(),
            buffers: HashMap::new(),
            samplers: HashMap::new(),
            modules: HashMap::new(),
            compute: HashMap::new(),
            render: HashMap::new(),
            errors,
            staging: Mutex::new(HashMap::new()),
        };
        for r in &m.resources {
            host.make(r).map_err(|e| format!("resource {}: {e}", r.name))?;
        }
        host.take_errors().map_err(|e| format!("making the resources: {e}"))?;
        Ok(host)
    }

    /// wgpu's errors since the last call, as one message.
    pub fn take_errors(&self) -> Result<(), String> {
        let errors = self.errors.lock().map(|mut v| std::mem::take(&mut *v)).unwrap_or_default();
        if errors.is_empty() { Ok(()) } else { Err(errors.join("; ")) }
    }

    fn make(&mut self, r: &Resource) -> Result<(), String> {
        let label = Some(r.name.as_str());
        match r.kind.as_str() {
            "texture" => {
                let format = names::format(r.format.as_deref().ok_or("a texture without a format")?)?;
                let [w, h, d] =
                    <[u64; 3]>::try_from(r.size.as_slice()).map_err(|_| "a texture's size has 3 numbers")?;
                let mut usage =
                    names::texture_usages(&r.usage)? | wgpu::TextureUsages::COPY_DST | wgpu::TextureUsages::COPY_SRC;
                if format.is_depth_stencil_format() {
                    // A depth input is filled by clearing it (`run::upload_depth`).
                    usage |= wgpu::TextureUsages::RENDER_ATTACHMENT;
                }
                let texture = self.device.create_texture(&wgpu::TextureDescriptor {
                    label,
                    size: wgpu::Extent3d { width: w as u32, height: h as u32, depth_or_array_layers: d as u32 },
                    mip_level_count: r.mips.unwrap_or(1),
                    sample_count: 1,
                    dimension: names::texture_dimension(r.dimension.as_deref().unwrap_or("D2"))?,
                    format,
                    usage,
                    view_formats: &[],
                });
                self.textures.insert(r.name.clone(), Texture { texture, format });
            }
            "buffer" => {
                let size = *r.size.first().ok_or("a buffer without a size")?;
                let usage =
                    (names::buffer_usages(&r.usage)? - wgpu::BufferUsages::MAP_READ - wgpu::BufferUsages::MAP_WRITE)
                        | wgpu::BufferUsages::COPY_DST
                        | wgpu::BufferUsages::COPY_SRC;
                let buffer = self.device.create_buffer(&wgpu::BufferDescriptor {
                    label,
                    size,
                    usage,
                    mapped_at_creation: false,
                });
                self.buffers.insert(r.name.clone(), buffer);
            }
            "sampler" => {
                let s = r.sampler.as_ref().ok_or("a sampler without its description")?;
                let [u, v, w] = &s.address_mode;
                let [mag, min, mip] = &s.filter;
                let filtering = s.filter.iter().any(|f| f == "Linear");
                let sampler = self.device.create_sampler(&wgpu::SamplerDescriptor {
                    label,
                    address_mode_u: names::address_mode(u)?,
                    address_mode_v: names::address_mode(v)?,
                    address_mode_w: names::address_mode(w)?,
                    mag_filter: names::filter(mag)?,
                    min_filter: names::filter(min)?,
                    mipmap_filter: names::mipmap_filter(mip)?,
                    compare: s.compare.as_deref().map(names::compare).transpose()?,
                    ..Default::default()
                });
                self.samplers.insert(r.name.clone(), (sampler, filtering));
            }
            other => return Err(format!("unknown resource kind `{other}`")),
        }
        Ok(())
    }

    fn module(&mut self, m: &Manifest, path: &str) -> Result<wgpu::ShaderModule, String> {
        if let Some(module) = self.modules.get(path) {
            return Ok(module.clone());
        }
        let shader = m.shaders.iter().find(|s| s.module == path).ok_or_else(|| format!("no shader `{path}`"))?;
        let file = self.kit.join(&shader.file);
        let source = std::fs::read_to_string(&file).map_err(|e| format!("{}: {e}", file.display()))?;
        let module = self.device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(path),
            source: wgpu::ShaderSource::Wgsl(source.into()),
        });
        self.modules.insert(path.to_string(), module.clone());
        Ok(module)
    }

    /// The layout entry of a step's binding: its kind and access from the manifest, its
    /// dimension and sample kind from the shader's declaration, a storage texture's format and
    /// a texture's filterability from the bound resource, a sampler's type from its filters.
    fn entry(&self, m: &Manifest, p: &Pipeline, b: &Binding) -> Result<wgpu::BindGroupLayoutEntry, String> {
        let decl = p
            .stages
            .iter()
            .filter_map(|s| m.shaders.iter().find(|x| x.module == s.module))
            .flat_map(|s| s.bindings.iter())
            .find(|d| d.group == b.group && d.binding == b.binding)
            .ok_or_else(|| format!("no shader of {} declares @group({}) @binding({})", p.label, b.group, b.binding))?;
        let dimension = || names::declared_dimension(decl.dimension.as_deref().unwrap_or("2d"));
        let texture_format =
            || self.textures.get(&b.resource).map(|t| t.format).ok_or_else(|| format!("no texture `{}`", b.resource));
        let writes = b.access != "read";
        let ty = match b.kind.as_str() {
            "uniform" => wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            "storage" => wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only: !writes },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            "texture" => {
                let format = texture_format()?;
                let sample_type = match decl.sample.as_deref() {
                    Some("uint") => wgpu::TextureSampleType::Uint,
                    Some("sint") => wgpu::TextureSampleType::Sint,
                    _ => {
                        let flags = self.adapter.get_texture_format_features(format).flags;
                        let filterable = !format.is_depth_stencil_format()
                            && flags.contains(wgpu::TextureFormatFeatureFlags::FILTERABLE);
                        wgpu::TextureSampleType::Float { filterable }
                    }
                };
                wgpu::BindingType::Texture { sample_type, view_dimension: dimension()?, multisampled: false }
            }
            "depth_texture" => wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Depth,
                view_dimension: dimension()?,
                multisampled: false,
            },
            "storage_texture" => wgpu::BindingType::StorageTexture {
                access: names::storage_access(&b.access)?,
                format: texture_format()?,
                view_dimension: dimension()?,
            },
            "sampler" => {
                let filtering = self.samplers.get(&b.resource).map(|s| s.1).unwrap_or(false);
                wgpu::BindingType::Sampler(match (decl.sample.as_deref(), filtering) {
                    (Some("comparison"), _) => wgpu::SamplerBindingType::Comparison,
                    (_, true) => wgpu::SamplerBindingType::Filtering,
                    (_, false) => wgpu::SamplerBindingType::NonFiltering,
                })
            }
            other => return Err(format!("unknown binding kind `{other}`")),
        };
        let writable = writes && matches!(b.kind.as_str(), "storage" | "storage_texture");
        let visibility = match (p.kind.as_str(), writable) {
            ("compute", _) => wgpu::ShaderStages::COMPUTE,
            (_, true) => wgpu::ShaderStages::FRAGMENT,
            (_, false) => wgpu::ShaderStages::VERTEX_FRAGMENT,
        };
        Ok(wgpu::BindGroupLayoutEntry { binding: b.binding, visibility, ty, count: None })
    }

    /// The layouts of a step's groups (empty ones where a group number is skipped).
    fn layouts(&self, m: &Manifest, p: &Pipeline, step: &Step) -> Result<Vec<wgpu::BindGroupLayout>, String> {
        let mut groups: BTreeMap<u32, Vec<wgpu::BindGroupLayoutEntry>> = BTreeMap::new();
        for b in &step.bindings {
            let e = self.entry(m, p, b).map_err(|e| format!("binding {} ({}): {e}", b.name, b.resource))?;
            groups.entry(b.group).or_default().push(e);
        }
        let count = groups.keys().next_back().map_or(0, |g| g + 1);
        Ok((0..count)
            .map(|g| {
                self.device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                    label: Some(&p.label),
                    entries: groups.get(&g).map(Vec::as_slice).unwrap_or(&[]),
                })
            })
            .collect())
    }

    /// The pipeline a step sets, made on first use for the layout its bindings give, with its
    /// bind groups.
    pub fn pipeline(&mut self, m: &Manifest, step: &Step) -> Result<(Made, Vec<wgpu::BindGroup>), String> {
        let label = step.pipeline.as_deref().ok_or("a step without a pipeline")?;
        let p = m.pipelines.iter().find(|p| p.label == label).ok_or_else(|| format!("no pipeline `{label}`"))?;
        let layouts = self.layouts(m, p, step)?;
        let groups = self.groups(step, &layouts)?;
        let key = format!("{label} {:?}", step.bindings.iter().map(|b| (&b.resource, &b.kind)).collect::<Vec<_>>());
        let layout = self.device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(label),
            bind_group_layouts: &layouts.iter().map(Some).collect::<Vec<_>>(),
            immediate_size: 0,
        });
        if p.kind == "compute" {
            if !self.compute.contains_key(&key) {
                let s = p.stages.first().ok_or("a compute pipeline without a stage")?;
                let module = self.module(m, &s.module)?;
                let constants = constants(&s.constants);
                let pipe = self.device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                    label: Some(label),
                    layout: Some(&layout),
                    module: &module,
                    entry_point: Some(&s.entry),
                    compilation_options: wgpu::PipelineCompilationOptions {
                        constants: &constants,
                        ..Default::default()
                    },
                    cache: None,
                });
                self.compute.insert(key.clone(), pipe);
            }
            return Ok((Made::Compute(self.compute[&key].clone()), groups));
        }
        if !self.render.contains_key(&key) {
            let pipe = self.make_render(m, p, &layout)?;
            self.render.insert(key.clone(), pipe);
        }
        Ok((Made::Render(self.render[&key].clone()), groups))
    }

    fn make_render(
        &mut self,
        m: &Manifest,
        p: &Pipeline,
        layout: &wgpu::PipelineLayout,
    ) -> Result<wgpu::RenderPipeline, String> {
        let vs = p.stages.first().ok_or("a render pipeline without a vertex stage")?;
        let vs_constants = constants(&vs.constants);
        let vs_module = self.module(m, &vs.module)?;
        let fs = p.stages.get(1);
        let fs_module = fs.map(|f| self.module(m, &f.module)).transpose()?;
        let fs_constants = fs.map(|f| constants(&f.constants)).unwrap_or_default();
        let attributes: Vec<Vec<wgpu::VertexAttribute>> = p
            .vertex_buffers
            .iter()
            .map(|v| {
                v.attributes
                    .iter()
                    .map(|(location, format, offset)| {
                        Ok(wgpu::VertexAttribute {
                            format: names::vertex_format(format)?,
                            offset: *offset,
                            shader_location: *location,
                        })
                    })
                    .collect::<Result<Vec<_>, String>>()
            })
            .collect::<Result<_, _>>()?;
        let buffers = p
            .vertex_buffers
            .iter()
            .zip(&attributes)
            .map(|(v, a)| {
                Ok(Some(wgpu::VertexBufferLayout {
                    array_stride: v.stride,
                    step_mode: names::step_mode(&v.step_mode)?,
                    attributes: a,
                }))
            })
            .collect::<Result<Vec<_>, String>>()?;
        let component = |c: &crate::kit::BlendComponent| -> Result<wgpu::BlendComponent, String> {
            Ok(wgpu::BlendComponent {
                src_factor: names::blend_factor(&c.src)?,
                dst_factor: names::blend_factor(&c.dst)?,
                operation: names::blend_operation(&c.operation)?,
            })
        };
        let targets = p
            .targets
            .iter()
            .map(|t| {
                let blend = match &t.blend {
                    Some(b) => Some(wgpu::BlendState { color: component(&b.color)?, alpha: component(&b.alpha)? }),
                    None => None,
                };
                Ok(Some(wgpu::ColorTargetState {
                    format: names::format(&t.format)?,
                    blend,
                    write_mask: wgpu::ColorWrites::from_bits(t.write_mask).ok_or("a write mask over 15")?,
                }))
            })
            .collect::<Result<Vec<_>, String>>()?;
        let prim = p.primitive.as_ref().ok_or("a render pipeline without its primitive state")?;
        let primitive = wgpu::PrimitiveState {
            topology: names::topology(&prim.topology)?,
            strip_index_format: prim.strip_index_format.as_deref().map(names::index_format).transpose()?,
            front_face: names::front_face(&prim.front_face)?,
            cull_mode: prim.cull_mode.as_deref().map(names::face).transpose()?,
            unclipped_depth: prim.unclipped_depth,
            polygon_mode: names::polygon_mode(&prim.polygon_mode)?,
            conservative: false,
        };
        let depth_stencil = match &p.depth {
            Some(d) => Some(wgpu::DepthStencilState {
                format: names::format(&d.format)?,
                depth_write_enabled: Some(d.write),
                depth_compare: d.compare.as_deref().map(names::compare).transpose()?,
                stencil: wgpu::StencilState::default(),
                bias: wgpu::DepthBiasState {
                    constant: d.bias.constant,
                    slope_scale: d.bias.slope_scale,
                    clamp: d.bias.clamp,
                },
            }),
            None => None,
        };
        Ok(self.device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(&p.label),
            layout: Some(layout),
            vertex: wgpu::VertexState {
                module: &vs_module,
                entry_point: Some(&vs.entry),
                compilation_options: wgpu::PipelineCompilationOptions {
                    constants: &vs_constants,
                    ..Default::default()
                },
                buffers: &buffers,
            },
            primitive,
            depth_stencil,
            multisample: wgpu::MultisampleState::default(),
            fragment: match (fs, &fs_module) {
                (Some(f), Some(module)) => Some(wgpu::FragmentState {
                    module,
                    entry_point: Some(&f.entry),
                    compilation_options: wgpu::PipelineCompilationOptions {
                        constants: &fs_constants,
                        ..Default::default()
                    },
                    targets: &targets,
                }),
                _ => None,
            },
            multiview_mask: None,
            cache: None,
        }))
    }

    /// A view of a texture as a binding or target names it.
    pub fn view(&self, resource: &str, v: Option<&crate::kit::ViewRange>) -> Result<wgpu::TextureView, String> {
        let t = self.textures.get(resource).ok_or_else(|| format!("no texture `{resource}`"))?;
        let desc = match v {
            Some(v) => wgpu::TextureViewDescriptor {
                label: Some(resource),
                dimension: Some(names::view_dimension(&v.dimension)?),
                base_mip_level: v.base_mip,
                mip_level_count: Some(v.mips),
                base_array_layer: v.base_layer,
                array_layer_count: Some(v.layers),
                ..Default::default()
            },
            None => wgpu::TextureViewDescriptor { label: Some(resource), ..Default::default() },
        };
        Ok(t.texture.create_view(&desc))
    }

    /// The bind groups of a step, for `layouts`.
    fn groups(&self, step: &Step, layouts: &[wgpu::BindGroupLayout]) -> Result<Vec<wgpu::BindGroup>, String> {
        let mut out = Vec::new();
        for (g, layout) in layouts.iter().enumerate() {
            let bs: Vec<&Binding> = step.bindings.iter().filter(|b| b.group == g as u32).collect();
            let views: Vec<Option<wgpu::TextureView>> = bs
                .iter()
                .map(|b| match b.kind.as_str() {
                    "texture" | "depth_texture" | "storage_texture" => {
                        self.view(&b.resource, b.view.as_ref()).map(Some)
                    }
                    _ => Ok(None),
                })
                .collect::<Result<_, _>>()?;
            let mut entries = Vec::new();
            for (b, view) in bs.iter().zip(&views) {
                let resource = match (b.kind.as_str(), view) {
                    (_, Some(v)) => wgpu::BindingResource::TextureView(v),
                    ("sampler", _) => wgpu::BindingResource::Sampler(
                        &self.samplers.get(&b.resource).ok_or_else(|| format!("no sampler `{}`", b.resource))?.0,
                    ),
                    _ => {
                        let buffer =
                            self.buffers.get(&b.resource).ok_or_else(|| format!("no buffer `{}`", b.resource))?;
                        wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                            buffer,
                            offset: b.offset.unwrap_or(0),
                            size: b.size.and_then(wgpu::BufferSize::new),
                        })
                    }
                };
                entries.push(wgpu::BindGroupEntry { binding: b.binding, resource });
            }
            out.push(self.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("port-kit-host.group"),
                layout,
                entries: &entries,
            }));
        }
        Ok(out)
    }
}
