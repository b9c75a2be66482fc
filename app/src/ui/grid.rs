//! The comparison grid (View → Compare grid, issue #40 point 1): the live settings beside up
//! to five other cells, each a preset or the live settings frozen, and an optional truth cell
//! (a path tracer refining in the background: the GPU's on a real GPU, the CPU's otherwise). Every cell follows the live renderer's
//! scene, camera, animation time and lights (`ab::follow`), so orbiting in any cell moves all.
//! The cells render in turn within the frame budget (View → target frame rate), so the window
//! stays responsive however many there are; each cell's GPU memory is measured when it is
//! added, and a cell that would take the grid past its memory budget is refused.

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::mpsc::{Receiver, Sender, TryRecvError};
use std::time::{Duration, Instant};

use gi_render::readback::{Readback, Readout};
use gi_render::{ImageF32, LabSettings, Renderer};

/// The most cells besides the live one.
pub const MAX_CELLS: usize = 5;

/// What a cell renders with.
#[derive(Clone, Debug, PartialEq)]
pub enum CellSource {
    Preset(PathBuf),
    /// The live settings as they were when the cell was added.
    Frozen,
}

/// What a cell shows.
#[derive(Clone, Debug, PartialEq)]
pub enum CellView {
    Image,
    /// Its FLIP error map against the truth cell (inferno: black is no visible difference).
    Flip,
    /// Any of its buffers by name.
    Buffer(String),
}

/// Which cell: the live renderer, or an added cell by index.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Which {
    Live,
    Cell(usize),
}

/// A cell's measurements and what it shows, kept for the live cell too.
#[derive(Default)]
pub struct Shown {
    /// Mean FLIP against the truth (None until the truth has samples).
    pub flip: Option<f64>,
    /// The spp of the truth the FLIP was measured against.
    pub flip_spp: u32,
    /// A FLIP map arrived and not yet made a texture (the pane does, with egui's context).
    pub(crate) pending_map: Option<egui::ColorImage>,
    pub flip_map: Option<egui::TextureHandle>,
    pub(crate) buffer: Option<egui::TextureHandle>,
    /// The frame of the buffer image shown.
    pub(crate) buffer_frame: u64,
    pub view: Option<CellView>,
}

pub struct Cell {
    pub name: String,
    pub source: CellSource,
    pub renderer: Renderer,
    pub technique: String,
    /// The settings in which it differs from the live settings (`path = value`).
    pub differs: Vec<String>,
    /// GPU memory it took (the device allocator's bytes before and after its first frame).
    pub bytes: Option<u64>,
    /// Its last frame's time: the passes' GPU times summed (ms).
    pub frame_ms: f32,
    pub shown: Shown,
    pub(crate) texture: Option<(egui::TextureId, (u32, u32))>,
    pub error: Option<String>,
}

/// The path tracer refining the truth on a thread of its own.
pub struct Truth {
    pub bounces: u32,
    /// Samples per pixel of the newest image.
    pub spp: u32,
    pub image: Option<Arc<ImageF32>>,
    pub(crate) texture: Option<egui::TextureHandle>,
    /// The spp of the image in `texture`.
    pub(crate) texture_spp: u32,
    jobs: Sender<TruthJob>,
    /// (generation, spp, image, the tracer that made it in words).
    results: Receiver<(u64, u32, Arc<ImageF32>, Arc<str>)>,
    /// The inputs of the job running (a change restarts it).
    key: Option<String>,
    generation: u64,
    /// Which path tracer refines it, in words.
    pub tracer: String,
}

struct TruthJob {
    generation: u64,
    scene: gi_render::scene::Scene,
    time: f32,
    view_proj: glam::Mat4,
    eye: glam::Vec3,
    size: (u32, u32),
    bounces: u32,
    emitters: gi_render::passes::emitters::EmitterSettings,
    sky_background: bool,
}

/// The truth's spp at which refining stops.
pub const TRUTH_MAX_SPP: u32 = 1024;

/// A job's tracer and its samples so far: the CPU's, or the GPU's on a real GPU (issue #56).
enum Refining {
    Cpu(Box<gi_render::cpu::pathtrace::PathTracer>, gi_render::cpu::pathtrace::Accumulator),
    Gpu(Box<gi_render::passes::rays::pathtrace::GpuPathTracer>, gi_render::passes::rays::pathtrace::GpuAccumulator),
}

impl Refining {
    fn new(job: &TruthJob, gpu: Option<&gi_render::GpuContext>) -> Result<Self, String> {
        use gi_render::passes::rays::pathtrace::{GpuAccumulator, GpuPathTracer};
        Ok(match gpu {
            Some(ctx) => {
                let mut pt = GpuPathTracer::new(ctx, &job.scene, job.time)?;
                pt.use_emitter_settings(&job.emitters, &job.scene, job.time);
                pt.set_sky_background(job.sky_background);
                Self::Gpu(Box::new(pt), GpuAccumulator::new(ctx, job.size.0, job.size.1)?)
            }
            None => {
                let mut pt = gi_render::cpu::pathtrace::PathTracer::new(&job.scene, job.time);
                pt.use_emitter_settings(&job.emitters, &job.scene, job.time);
                pt.set_sky_background(job.sky_background);
                Self::Cpu(Box::new(pt), gi_render::cpu::pathtrace::Accumulator::new(job.size.0, job.size.1))
            }
        })
    }

    /// Adds `spp` samples and returns the image so far.
    fn add(
        &mut self,
        job: &TruthJob,
        spp: u32,
        gpu: Option<&gi_render::GpuContext>,
        pool: &rayon::ThreadPool,
    ) -> Result<ImageF32, String> {
        let settings =
            gi_render::cpu::pathtrace::PtSettings { bounces: job.bounces, spp, seed: 1, ..Default::default() };
        match (self, gpu) {
            (Self::Cpu(pt, acc), _) => {
                pool.install(|| acc.add_pass(pt, job.view_proj, job.eye, settings));
                Ok(acc.images().full)
            }
            (Self::Gpu(pt, acc), Some(ctx)) => {
                acc.add_pass(ctx, pt, job.view_proj, job.eye, settings)?;
                Ok(acc.images(ctx)?.full)
            }
            (Self::Gpu(..), None) => Err("the GPU tracer lost its device".into()),
        }
    }
}

impl Truth {
    /// Starts the truth's thread; with `gpu` (a real GPU's context: `TruthTracer::for_adapter`)
    /// it traces there, else on half the CPU's cores.
    pub fn start(bounces: u32, gpu: Option<gi_render::GpuContext>) -> Self {
        let (jobs, job_rx) = std::sync::mpsc::channel::<TruthJob>();
        let (tx, results) = std::sync::mpsc::channel();
        let tracer: Arc<str> = match &gpu {
            Some(ctx) => format!("GPU path tracer ({})", ctx.adapter_info.name).into(),
            None => "CPU path tracer".into(),
        };
        // Half the cores at most: the renderers (and, on a software device, the GPU itself)
        // keep the rest, so the window stays responsive while the truth refines.
        let threads = std::thread::available_parallelism().map_or(1, |n| (n.get() / 2).max(1));
        let pool =
            rayon::ThreadPoolBuilder::new().num_threads(threads).thread_name(|i| format!("grid-truth-{i}")).build();
        let label = tracer.to_string();
        let _ = std::thread::Builder::new().name("grid-truth".into()).spawn(move || {
            let Ok(pool) = pool else { return };
            let mut next = job_rx.recv().ok();
            while let Some(job) = next.take() {
                // The GPU's tracer, or the CPU's when there is no GPU or the GPU's cannot take
                // the scene (past the device's buffer sizes): the cell's caption says which.
                let (mut refining, by): (Refining, Arc<str>) = match Refining::new(&job, gpu.as_ref()) {
                    Ok(r) => (r, tracer.clone()),
                    Err(e) => match Refining::new(&job, None) {
                        Ok(r) => (r, format!("CPU path tracer (the GPU's: {e})").into()),
                        Err(_) => return,
                    },
                };
                let mut spp = 0;
                loop {
                    // A newer job (the camera moved, a light changed) replaces this one.
                    match job_rx.try_recv() {
                        Ok(newer) => {
                            next = Some(newer);
                            break;
                        }
                        Err(TryRecvError::Disconnected) => return,
                        Err(TryRecvError::Empty) => {}
                    }
                    if spp >= TRUTH_MAX_SPP {
                        next = job_rx.recv().ok();
                        break;
                    }
                    let batch = match (&refining, spp < 8) {
                        (_, true) => 1,
                        (Refining::Cpu(..), false) => 4,
                        (Refining::Gpu(..), false) => 16,
                    };
                    let Ok(image) = refining.add(&job, batch, gpu.as_ref(), &pool) else { return };
                    spp += batch;
                    if tx.send((job.generation, spp, Arc::new(image), by.clone())).is_err() {
                        return;
                    }
                }
            }
        });
        Self {
            bounces,
            spp: 0,
            image: None,
            texture: None,
            texture_spp: 0,
            jobs,
            results,
            key: None,
            generation: 0,
            tracer: label,
        }
    }

    /// Restarts the path tracer when what it traces changed, and takes its newest image.
    fn update(&mut self, live: &Renderer, settings: &LabSettings) {
        let scene = live.scene();
        let lights: Vec<String> = scene
            .nodes
            .iter()
            .filter(|n| n.light.is_some())
            .map(|n| format!("{:?}", n.transform))
            .chain(scene.lights.iter().map(|l| format!("{l:?}")))
            .collect();
        let time = live.clock.time_s();
        let key = format!(
            "{:?} {:?} {:?} {time} {} {:?} {} {:?}",
            live.view_proj().to_cols_array(),
            live.size(),
            lights,
            self.bounces,
            settings.emitters,
            settings.sky.background,
            scene.nodes.len()
        );
        if self.key.as_ref() != Some(&key) {
            self.key = Some(key);
            self.generation += 1;
            self.spp = 0;
            // The old image is of another view: nothing is compared with it.
            self.image = None;
            let _ = self.jobs.send(TruthJob {
                generation: self.generation,
                scene: scene.clone(),
                time,
                view_proj: live.view_proj(),
                eye: live.camera.position,
                size: live.size(),
                bounces: self.bounces,
                emitters: settings.emitters.clone(),
                sky_background: settings.sky.background,
            });
        }
        while let Ok((generation, spp, image, by)) = self.results.try_recv() {
            if generation == self.generation {
                self.spp = spp;
                self.tracer = by.to_string();
                self.image = Some(image);
            }
        }
    }
}

/// A FLIP of one cell against the truth, computed on a thread.
struct FlipJob {
    which: Which,
    spp: u32,
    rx: Receiver<Result<(f64, egui::ColorImage), String>>,
}

pub struct Grid {
    pub cells: Vec<Cell>,
    pub live: Shown,
    pub truth: Option<Truth>,
    /// The cell that renders next (the cells render in turn).
    next: usize,
    /// GPU memory the cells may take together (MiB).
    pub memory_budget_mib: u32,
    /// Why the last cell was refused, or what went wrong.
    pub message: Option<String>,
    flip_job: Option<FlipJob>,
    flip_turn: usize,
    last_flip: Option<Instant>,
}

impl Default for Grid {
    fn default() -> Self {
        Self {
            cells: Vec::new(),
            live: Shown::default(),
            truth: None,
            next: 0,
            memory_budget_mib: 4096,
            message: None,
            flip_job: None,
            flip_turn: 0,
            last_flip: None,
        }
    }
}

/// The technique of `s` in words.
pub fn technique_of(s: &LabSettings) -> String {
    match gi_render::settings::pipeline::Technique::of(&s.pipeline) {
        Some(t) => t.label().to_string(),
        None => "a mix of stages".into(),
    }
}

/// The settings of `s` that differ from `base`, as `path = value`.
pub fn differs(s: &LabSettings, base: &LabSettings) -> Vec<String> {
    s.differences(base).into_iter().map(|(p, a, _)| format!("{p} = {a}")).collect()
}

fn allocated(live: &Renderer) -> Option<u64> {
    live.ctx.device.generate_allocator_report().map(|r| r.total_allocated_bytes)
}

impl Grid {
    /// GPU memory of the added cells together (bytes; cells whose memory is unknown count 0).
    pub fn memory_bytes(&self) -> u64 {
        self.cells.iter().filter_map(|c| c.bytes).sum()
    }

    /// Adds a cell rendering `source`; refuses it (with the reason in `message`) when there
    /// are already [`MAX_CELLS`], its settings or renderer fail, or it would take the grid
    /// past its memory budget.
    pub fn add(&mut self, live: &Renderer, live_settings: &LabSettings, source: CellSource) -> Result<(), String> {
        let r = self.try_add(live, live_settings, source);
        self.message = r.clone().err();
        r
    }

    fn try_add(&mut self, live: &Renderer, live_settings: &LabSettings, source: CellSource) -> Result<(), String> {
        if self.cells.len() >= MAX_CELLS {
            return Err(format!("the grid holds the live settings and {MAX_CELLS} cells: remove one first"));
        }
        let (name, settings) = match &source {
            CellSource::Preset(p) => {
                let name = p.file_stem().map(|s| s.to_string_lossy().to_string()).unwrap_or_default();
                let s = gi_render::preset::load_file(p).map_err(|e| format!("{name} not added: {e}"))?.settings;
                (name, s)
            }
            CellSource::Frozen => ("frozen settings".to_string(), live_settings.clone()),
        };
        let before = allocated(live);
        let (w, h) = live.size();
        let mut renderer = Renderer::new(live.ctx.clone(), live.scene().clone(), settings.clone(), w, h)
            .map_err(|e| format!("{name} not added: {e}"))?;
        renderer.set_interactive(true);
        crate::ui::ab::follow(live, &mut renderer).map_err(|e| format!("{name} not added: {e}"))?;
        renderer.render_frame();
        let bytes = match (before, allocated(live)) {
            (Some(b), Some(a)) => Some(a.saturating_sub(b)),
            _ => None,
        };
        let mib = |b: u64| b as f64 / (1024.0 * 1024.0);
        if let Some(b) = bytes {
            let total = self.memory_bytes() + b;
            if mib(total) > self.memory_budget_mib as f64 {
                return Err(format!(
                    "{name} not added: it needs {:.0} MiB of GPU memory and the cells already use {:.0} MiB of the grid's {} MiB budget (remove a cell, lower the render scale or raise the budget)",
                    mib(b),
                    mib(self.memory_bytes()),
                    self.memory_budget_mib
                ));
            }
        }
        self.cells.push(Cell {
            technique: technique_of(&settings),
            differs: differs(&settings, live_settings),
            name,
            source,
            renderer,
            bytes,
            frame_ms: 0.0,
            shown: Shown::default(),
            texture: None,
            error: None,
        });
        Ok(())
    }

    /// Removes cell `i` and frees its textures.
    pub fn remove(&mut self, i: usize, rs: &egui_wgpu::RenderState) {
        if i < self.cells.len() {
            let mut c = self.cells.remove(i);
            if let Some((id, _)) = c.texture.take() {
                rs.renderer.write().free_texture(&id);
            }
        }
        self.message = None;
    }

    /// Frees every cell's texture (the grid closes).
    pub fn release(&mut self, rs: &egui_wgpu::RenderState) {
        while !self.cells.is_empty() {
            self.remove(0, rs);
        }
    }

    /// Renders cells in turn, after the live frame, until `budget` is spent (at least one
    /// cell a frame), each in step with the live renderer; then refreshes the truth and the
    /// FLIP of one cell.
    pub fn render(&mut self, live: &Renderer, live_settings: &LabSettings, budget: Duration) {
        let started = Instant::now();
        let n = self.cells.len();
        for k in 0..n {
            if k > 0 && started.elapsed() >= budget {
                break;
            }
            let i = (self.next + k) % n;
            let c = &mut self.cells[i];
            match crate::ui::ab::follow(live, &mut c.renderer) {
                Ok(()) => {
                    let t0 = Instant::now();
                    let timings = c.renderer.render_frame();
                    let gpu: f64 = timings.iter().map(|t| t.ms).sum();
                    c.frame_ms = if gpu > 0.0 { gpu as f32 } else { t0.elapsed().as_secs_f32() * 1e3 };
                    c.differs = differs(c.renderer.settings(), live_settings);
                    c.error = None;
                }
                Err(e) => c.error = Some(e),
            }
            self.next = (i + 1) % n.max(1);
        }
        if let Some(t) = &mut self.truth {
            t.update(live, live_settings);
        }
        self.refresh_flip(live);
    }

    fn shown_mut(&mut self, w: Which) -> Option<&mut Shown> {
        match w {
            Which::Live => Some(&mut self.live),
            Which::Cell(i) => self.cells.get_mut(i).map(|c| &mut c.shown),
        }
    }

    /// The FLIP of one cell (the live one and the added ones in turn) against the newest
    /// truth: its final image read back without waiting, compared on a thread.
    fn refresh_flip(&mut self, live: &Renderer) {
        if let Some(job) = &self.flip_job {
            match job.rx.try_recv() {
                Err(TryRecvError::Empty) => return,
                Ok(Ok((mean, map))) => {
                    let (which, spp) = (job.which, job.spp);
                    self.flip_job = None;
                    if let Some(s) = self.shown_mut(which) {
                        s.flip = Some(mean);
                        s.flip_spp = spp;
                        s.pending_map = Some(map);
                    }
                }
                Ok(Err(e)) => {
                    self.flip_job = None;
                    self.message = Some(format!("FLIP: {e}"));
                }
                Err(TryRecvError::Disconnected) => self.flip_job = None,
            }
        }
        let Some((truth, spp)) = self.truth.as_ref().and_then(|t| Some((t.image.clone()?, t.spp))) else { return };
        if self.last_flip.is_some_and(|t| t.elapsed() < Duration::from_millis(250)) {
            return;
        }
        let count = self.cells.len() + 1;
        let which = match self.flip_turn % count {
            0 => Which::Live,
            i => Which::Cell(i - 1),
        };
        let r = match which {
            Which::Live => live,
            Which::Cell(i) => &self.cells[i].renderer,
        };
        let key = "grid.flip";
        let arrived = r.read_later(key, Readback::Image { name: "final.hdr".into(), layer: 0, mip: 0 }, 0);
        let Some(a) = arrived else { return };
        self.flip_turn += 1;
        self.last_flip = Some(Instant::now());
        let (tx, rx) = std::sync::mpsc::channel();
        let spawned = std::thread::Builder::new().name("grid-flip".into()).spawn(move || {
            let result = match &a.data {
                Ok(Readout::Image(img)) if (img.width, img.height) == (truth.width, truth.height) => {
                    flip_against(img, &truth)
                }
                Ok(Readout::Image(_)) => Err("the truth is still at the old size".to_string()),
                Ok(_) => Err("a read-back is not an image".to_string()),
                Err(e) => Err(e.clone()),
            };
            let _ = tx.send(result);
        });
        if spawned.is_ok() {
            self.flip_job = Some(FlipJob { which, spp, rx });
        }
    }
}

/// Mean FLIP of `img` against `truth` (both tone-mapped as the study does) and its map.
fn flip_against(img: &ImageF32, truth: &ImageF32) -> Result<(f64, egui::ColorImage), String> {
    let display = gi_render::image_io::hdr_display;
    let (mean, map) = gi_render::metrics::flip(&display(img), &display(truth)).map_err(|e| e.to_string())?;
    let rgba = gi_render::image_io::error_map_rgba8(&map);
    Ok((mean, egui::ColorImage::from_rgba_unmultiplied([map.width as usize, map.height as usize], rgba.as_raw())))
}
