//! The GPU context: one device and queue, opened headless or adopted from eframe.
//!
//! Headless opening honours `WGPU_BACKEND` (e.g. `vulkan`), prefers a real GPU and
//! falls back to any adapter (lavapipe on machines without a GPU). The pipeline needs
//! float32 blending and filtering (additive splatting of Nguyen Eq. 11 and Gautron's
//! weights into `Rgba32Float`, filtered lookups into float pyramids), clip distances and
//! indirect draws with a first instance (Gautron's record hemispheres: every record's tile
//! of the atlas in one draw per scene draw, instance counts written by the GPU; lavapipe and
//! every desktop Vulkan, Metal and DX12 driver have them); timestamp queries are used when
//! the adapter has them.

pub mod bgl;
pub mod bindings;

use crate::counters::prelude::*;
use std::sync::Arc;

/// Features without which the pipeline cannot run (see the module docs).
pub const REQUIRED_FEATURES: wgpu::Features = wgpu::Features::FLOAT32_BLENDABLE
    .union(wgpu::Features::FLOAT32_FILTERABLE)
    .union(wgpu::Features::CLIP_DISTANCES)
    .union(wgpu::Features::INDIRECT_FIRST_INSTANCE);

/// Features used when present: GPU timestamps per pass and read-write storage textures
/// of more formats.
pub const OPTIONAL_FEATURES: wgpu::Features = wgpu::Features::TIMESTAMP_QUERY
    .union(wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS)
    .union(wgpu::Features::TEXTURE_ADAPTER_SPECIFIC_FORMAT_FEATURES);

/// Colour attachment bytes per sample the G-buffer needs (position 16 + normal 8 +
/// albedo 4 + material 8 + motion 8 + emission 8).
pub const REQUIRED_COLOR_BYTES_PER_SAMPLE: u32 = 52;

/// How to install a software Vulkan driver when no adapter is found.
pub const INSTALL_HINT: &str = "no usable GPU adapter. On Debian/Ubuntu install Mesa's software Vulkan driver \
(lavapipe) with `sudo apt-get install -y mesa-vulkan-drivers libvulkan1` and run with WGPU_BACKEND=vulkan, \
or run `bash scripts/test.sh`, which installs it";

#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    #[error("{INSTALL_HINT} (wgpu: {0})")]
    NoAdapter(String),
    #[error(
        "the adapter '{adapter}' lacks features the pipeline needs: {missing:?}. \
         Mesa's lavapipe (`apt-get install mesa-vulkan-drivers`, WGPU_BACKEND=vulkan) has them"
    )]
    MissingFeatures { adapter: String, missing: wgpu::Features },
    #[error("the adapter '{adapter}' allows {have} colour-attachment bytes per sample; the G-buffer needs {need}")]
    Limits { adapter: String, have: u32, need: u32 },
    #[error("could not open the device on '{adapter}': {source}")]
    Device { adapter: String, source: wgpu::RequestDeviceError },
}

/// Resources alive on a device (see [`GpuContext::live_resources`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LiveResources {
    pub buffers: usize,
    pub textures: usize,
    pub bind_groups: usize,
    pub pipelines: usize,
    /// Bytes the backend's memory allocator holds, where it reports them.
    pub allocated_bytes: Option<u64>,
}

/// The device the renderer runs on.
#[derive(Clone)]
pub struct GpuContext {
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub adapter_info: wgpu::AdapterInfo,
    /// Features enabled on the device.
    pub features: wgpu::Features,
    pub limits: wgpu::Limits,
    /// Keeps the instance alive for headless contexts.
    _instance: Option<Arc<wgpu::Instance>>,
    /// Why the device was lost, once it is (the device-lost callback writes it).
    lost: Arc<std::sync::Mutex<Option<String>>>,
    /// This context's number in the process: wgpu hashes handles by their id, which another
    /// instance reuses, so the object cache and the traffic table key by it too
    /// (`counters::set_context`).
    nonce: u64,
}

static CONTEXTS: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);

impl std::fmt::Debug for GpuContext {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GpuContext")
            .field("adapter", &self.adapter_info.name)
            .field("backend", &self.adapter_info.backend)
            .field("features", &self.features)
            .finish()
    }
}

impl GpuContext {
    /// Opens a device without a window.
    pub fn headless() -> Result<Self, GpuError> {
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        let adapter = pick_adapter(&instance)?;
        let desc = device_descriptor(&adapter)?;
        let info = adapter.get_info();
        let (device, queue) = pollster::block_on(adapter.request_device(&desc))
            .map_err(|source| GpuError::Device { adapter: info.name.clone(), source })?;
        log::info!("GPU: {} ({:?}, {:?})", info.name, info.backend, info.device_type);
        let lost = watch_loss(&device);
        // Headless runs keep wgpu's default for GPU errors (a panic: tests and CI must not
        // pass over one), except once the device is lost: then every call fails, and the
        // caller is told by `lost_reason` instead.
        let gone = lost.clone();
        device.on_uncaptured_error(Arc::new(move |e| {
            if gone.lock().map(|l| l.is_none()).unwrap_or(true) {
                panic!("wgpu error: {e}");
            }
        }));
        let nonce = CONTEXTS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        crate::counters::set_context(nonce);
        Ok(Self {
            nonce,
            features: device.features(),
            limits: device.limits(),
            device,
            queue,
            adapter_info: info,
            _instance: Some(Arc::new(instance)),
            lost,
        })
    }

    /// Why the device was lost (a driver reset, `destroy`), if it was: everything on it is
    /// gone and a renderer must move to a new device (`Renderer::move_to`).
    pub fn lost_reason(&self) -> Option<String> {
        self.lost.lock().ok().and_then(|l| l.clone())
    }

    /// Adopts a device someone else opened (eframe's), checking that it has what we need.
    pub fn adopt(device: wgpu::Device, queue: wgpu::Queue, adapter_info: wgpu::AdapterInfo) -> Result<Self, GpuError> {
        let (features, limits) = (device.features(), device.limits());
        check_capabilities(&adapter_info.name, features, &limits)?;
        let lost = watch_loss(&device);
        let nonce = CONTEXTS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        crate::counters::set_context(nonce);
        Ok(Self { device, queue, adapter_info, features, limits, _instance: None, lost, nonce })
    }

    /// Whether per-pass GPU timestamps are available.
    pub fn has_timestamps(&self) -> bool {
        self.features.contains(wgpu::Features::TIMESTAMP_QUERY)
    }

    /// One line naming the adapter, for status bars and reports.
    pub fn adapter_summary(&self) -> String {
        format!("{} ({:?})", self.adapter_info.name, self.adapter_info.backend)
    }

    /// What lives on the device now: wgpu's count of buffers, textures, bind groups and
    /// pipelines, and the allocator's bytes where the backend reports them. `None` for an
    /// adopted device (eframe owns its instance). The soak watches these for leaks.
    pub fn live_resources(&self) -> Option<LiveResources> {
        let report = self._instance.as_ref()?.generate_report()?;
        let hub = report.hub_report();
        let allocated_bytes = self.device.generate_allocator_report().map(|r| r.total_allocated_bytes);
        Some(LiveResources {
            buffers: hub.buffers.num_allocated,
            textures: hub.textures.num_allocated,
            bind_groups: hub.bind_groups.num_allocated,
            pipelines: hub.render_pipelines.num_allocated + hub.compute_pipelines.num_allocated,
            allocated_bytes,
        })
    }

    /// Makes this context the one whose objects this thread creates next (keys of the object
    /// cache and the traffic table, `crate::counters`). Renderers call it before they record.
    pub fn make_current(&self) {
        crate::counters::set_context(self.nonce);
    }

    /// Blocks until the GPU has finished all submitted work.
    pub fn wait_idle(&self) {
        if let Err(e) = self.wait() {
            log::warn!("device poll failed: {e}");
        }
    }

    /// Blocks until the GPU has finished all submitted work. The one blocking wait of
    /// `gi-render`: every wait goes through it and is counted (`crate::counters`), so that
    /// a frame that waits is seen (the window's frames must not, issue #38).
    pub fn wait(&self) -> Result<(), String> {
        crate::counters::note_wait();
        self.device.poll(wgpu::PollType::wait_indefinitely()).map(|_| ()).map_err(|e| e.to_string())
    }

    /// Submits command buffers to the queue, counted (`crate::counters`).
    pub fn submit<I: IntoIterator<Item = wgpu::CommandBuffer>>(&self, buffers: I) -> wgpu::SubmissionIndex {
        crate::counters::note_submit();
        self.queue.submit(buffers)
    }
}

/// Why the last device this process lost was lost (see [`device_lost_in_process`]).
static LOST_IN_PROCESS: std::sync::Mutex<Option<String>> = std::sync::Mutex::new(None);

/// Whether any device of this process was lost, and why: a command line run that met a lost
/// device ends with this as its error, whatever failed after it.
pub fn device_lost_in_process() -> Option<String> {
    LOST_IN_PROCESS.lock().ok().and_then(|l| l.clone())
}

/// Records why `device` is lost when it is (wgpu calls the callback once).
fn watch_loss(device: &wgpu::Device) -> Arc<std::sync::Mutex<Option<String>>> {
    let lost = Arc::new(std::sync::Mutex::new(None));
    let sink = lost.clone();
    device.set_device_lost_callback(move |reason, message| {
        log::error!("the GPU device was lost ({reason:?}): {message}");
        let why = if message.is_empty() { format!("{reason:?}") } else { format!("{reason:?}: {message}") };
        if let Ok(mut l) = LOST_IN_PROCESS.lock() {
            *l = Some(why.clone());
        }
        if let Ok(mut l) = sink.lock() {
            *l = Some(why);
        }
    });
    lost
}

/// Picks an adapter: `WGPU_ADAPTER_NAME` (substring, case-insensitive) when set, else
/// the best by type (discrete > integrated > virtual > CPU), among those that have the
/// required features; an adapter without them is used only to report what is missing.
fn pick_adapter(instance: &wgpu::Instance) -> Result<wgpu::Adapter, GpuError> {
    let backends = wgpu::Backends::from_env().unwrap_or(wgpu::Backends::all());
    let mut adapters: Vec<wgpu::Adapter> = pollster::block_on(instance.enumerate_adapters(backends));
    if adapters.is_empty() {
        return Err(GpuError::NoAdapter(format!("no adapter for backends {backends:?}")));
    }
    if let Ok(name) = std::env::var("WGPU_ADAPTER_NAME") {
        let want = name.to_lowercase();
        adapters.retain(|a| a.get_info().name.to_lowercase().contains(&want));
        if adapters.is_empty() {
            return Err(GpuError::NoAdapter(format!("no adapter matches WGPU_ADAPTER_NAME='{name}'")));
        }
    }
    best_adapter(&adapters, None).ok_or_else(|| GpuError::NoAdapter("no adapter".into()))
}

/// The best of `adapters` for GI Lab: complete (has the required features) first, then by
/// type (discrete > integrated > virtual > CPU), Vulkan first among equals (the GL backend
/// of llvmpipe lacks float32 blending); with a surface, only adapters that can present to it.
/// Also used as eframe's adapter selector.
pub fn best_adapter(adapters: &[wgpu::Adapter], surface: Option<&wgpu::Surface<'_>>) -> Option<wgpu::Adapter> {
    let rank = |a: &wgpu::Adapter| {
        let complete = a.features().contains(REQUIRED_FEATURES) as u32;
        let ty = match a.get_info().device_type {
            wgpu::DeviceType::DiscreteGpu => 4,
            wgpu::DeviceType::IntegratedGpu => 3,
            wgpu::DeviceType::VirtualGpu => 2,
            wgpu::DeviceType::Cpu => 1,
            wgpu::DeviceType::Other => 0,
        };
        let backend = (a.get_info().backend == wgpu::Backend::Vulkan) as u32;
        (complete, ty, backend)
    };
    adapters.iter().filter(|a| surface.is_none_or(|s| a.is_surface_supported(s))).max_by_key(|a| rank(a)).cloned()
}

/// The device descriptor GI Lab asks for on `adapter`: the required features, the
/// optional ones it has, and the adapter's own limits (the G-buffer needs more colour
/// attachment bytes than WebGPU's default 32). Used headless and by the app for eframe.
pub fn device_descriptor(adapter: &wgpu::Adapter) -> Result<wgpu::DeviceDescriptor<'static>, GpuError> {
    let (have, limits) = (adapter.features(), adapter.limits());
    check_capabilities(&adapter.get_info().name, have, &limits)?;
    Ok(wgpu::DeviceDescriptor {
        label: Some("gi-lab.device"),
        required_features: REQUIRED_FEATURES | (OPTIONAL_FEATURES & have),
        required_limits: limits,
        experimental_features: wgpu::ExperimentalFeatures::disabled(),
        memory_hints: wgpu::MemoryHints::Performance,
        trace: wgpu::Trace::Off,
    })
}

/// Checks that a device or adapter has the features and limits the pipeline needs.
fn check_capabilities(adapter: &str, features: wgpu::Features, limits: &wgpu::Limits) -> Result<(), GpuError> {
    let missing = REQUIRED_FEATURES - features;
    if !missing.is_empty() {
        return Err(GpuError::MissingFeatures { adapter: adapter.into(), missing });
    }
    if limits.max_color_attachment_bytes_per_sample < REQUIRED_COLOR_BYTES_PER_SAMPLE {
        return Err(GpuError::Limits {
            adapter: adapter.into(),
            have: limits.max_color_attachment_bytes_per_sample,
            need: REQUIRED_COLOR_BYTES_PER_SAMPLE,
        });
    }
    Ok(())
}

/// A compute pipeline over one resolved shader module.
pub fn compute_pipeline(
    device: &wgpu::Device,
    label: &str,
    module: &wgpu::ShaderModule,
    entry: &str,
    layouts: &[&wgpu::BindGroupLayout],
) -> wgpu::ComputePipeline {
    compute_pipeline_with(device, label, (module, entry, &[]), layouts)
}

/// [`compute_pipeline`] with values for the module's pipeline-overridable constants
/// (`override` in WGSL), by name.
pub fn compute_pipeline_with(
    device: &wgpu::Device,
    label: &str,
    (module, entry, constants): (&wgpu::ShaderModule, &str, &[(&str, f64)]),
    layouts: &[&wgpu::BindGroupLayout],
) -> wgpu::ComputePipeline {
    let layouts: Vec<Option<&wgpu::BindGroupLayout>> = layouts.iter().map(|l| Some(*l)).collect();
    let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(label),
        bind_group_layouts: &layouts,
        immediate_size: 0,
    });
    device.counted_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(label),
        layout: Some(&layout),
        module,
        entry_point: Some(entry),
        compilation_options: wgpu::PipelineCompilationOptions { constants, ..Default::default() },
        cache: None,
    })
}
