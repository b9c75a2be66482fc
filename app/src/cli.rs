//! The `gi-lab` command line: the app (default), `render`, `buffers`, `bench`,
//! `settings` and `gen-assets`. Bad arguments or input exit with code 2 and a message that
//! says what is wrong; a missing GPU exits with code 1 and says how to install lavapipe.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::{Args, Parser, Subcommand};
use gi_render::scene::{self, LoadOptions, Scene};
use gi_render::{GpuContext, LabSettings, Renderer};

#[derive(Parser, Debug)]
#[command(name = "gi-lab", version, about = "GI Lab: a laboratory for real-time global illumination")]
pub struct Cli {
    #[command(subcommand)]
    pub command: Option<Command>,
    #[command(flatten)]
    pub app: AppArgs,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Render headless and write final.png plus the named buffers (PNG, and EXR for float data).
    Render(RenderArgs),
    /// List the names of the inspectable buffers.
    Buffers(SceneArgs),
    /// Render frames and print per-pass times (GPU timestamps where available).
    Bench(BenchArgs),
    /// List every setting with its unit, range and default.
    Settings,
    /// Compare two images (PNG or EXR): RMSE, relative MSE and mean FLIP.
    Compare(CompareArgs),
    /// Path-trace a ground-truth image on the CPU (writes F, F.direct.exr, F.indirect.exr
    /// and a PNG preview).
    Reference(ReferenceArgs),
    /// Render every combination of swept settings; write sweep.csv (settings, per-pass ms,
    /// FLIP, RMSE, flicker) and pareto.png (quality against time).
    Sweep(crate::sweep::SweepArgs),
    /// Export a preset for engines: JSON or RON with schema id and provenance (GI Lab
    /// version, scene, camera, date); see docs/preset-schema.md.
    Export(ExportArgs),
    /// Print the hierarchical coherence buffer's samples per level as Table 1 of Nguyen et
    /// al. lays them out (the preset's technique is switched to the HCB).
    HcbStats(HcbStatsArgs),
    /// Regenerate the embedded default scene (assets/cornell_box.glb).
    GenAssets {
        /// Where to write the .glb.
        #[arg(long, default_value = "assets/cornell_box.glb")]
        out: PathBuf,
    },
}

#[derive(Args, Debug, Clone)]
pub struct ExportArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// json or ron.
    #[arg(long, default_value = "json")]
    pub format: String,
    /// Output file; standard output when omitted.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Instead of exporting, write the schema documentation (docs/preset-schema.md) here.
    #[arg(long)]
    pub schema_doc: Option<PathBuf>,
}

/// Options of the windowed app (the default command).
#[derive(Args, Debug, Clone)]
pub struct AppArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Save a screenshot of the window to this PNG after --frames frames, then exit.
    #[arg(long)]
    pub screenshot: Option<PathBuf>,
    /// Frames to render before the screenshot.
    #[arg(long, default_value_t = 30)]
    pub screenshot_frames: u64,
    /// Folder of the session file (default: $GI_LAB_CONFIG_DIR, else the platform config
    /// directory, e.g. ~/.config/gi-lab).
    #[arg(long)]
    pub config_dir: Option<PathBuf>,
    /// Start from defaults instead of restoring the last session (it is still autosaved).
    #[arg(long)]
    pub fresh: bool,
    /// Folder the preset browser lists (default: ./presets).
    #[arg(long, default_value = "presets")]
    pub presets_dir: PathBuf,
    /// Folder of WGSL sources watched by the shader hot reload.
    #[arg(long, default_value = "shaders")]
    pub shaders_dir: PathBuf,
    /// Shader hot reload on or off (default: on in debug builds).
    #[arg(long)]
    pub hot_reload: Option<bool>,
}

#[derive(Args, Debug, Clone)]
pub struct SceneArgs {
    /// glTF 2.0 scene (.gltf or .glb); the embedded Cornell box when omitted.
    #[arg(long)]
    pub scene: Option<PathBuf>,
    /// Multiply the scene's coordinates by this (e.g. 0.001 for millimetres).
    #[arg(long, default_value_t = 1.0)]
    pub unit_scale: f32,
    /// RON preset; the defaults when omitted.
    #[arg(long)]
    pub preset: Option<PathBuf>,
    /// Override a setting, e.g. --set direct.pcf_radius=2 (repeatable).
    #[arg(long = "set", value_name = "GROUP.FIELD=VALUE")]
    pub overrides: Vec<String>,
}

impl Default for AppArgs {
    fn default() -> Self {
        Self {
            scene: SceneArgs::default(),
            screenshot: None,
            screenshot_frames: 30,
            config_dir: None,
            fresh: false,
            presets_dir: PathBuf::from("presets"),
            shaders_dir: PathBuf::from("shaders"),
            hot_reload: None,
        }
    }
}

impl Default for SceneArgs {
    /// The embedded scene at unit scale with the default preset (as the CLI's defaults).
    fn default() -> Self {
        Self { scene: None, unit_scale: 1.0, preset: None, overrides: Vec::new() }
    }
}

#[derive(Args, Debug)]
pub struct RenderArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Image size.
    #[arg(long, default_value = "512x512", value_parser = parse_size)]
    pub size: (u32, u32),
    /// Frames to render (animation advances by the fixed time step).
    #[arg(long, default_value_t = 1)]
    pub frames: u32,
    /// Keep the animation at time 0 for every frame (e.g. to let the exact-VPL reference
    /// accumulate: `--paused --frames 64 --set indirect.technique=ExactVpl`).
    #[arg(long)]
    pub paused: bool,
    /// A buffer to write besides final.png (repeatable; see `gi-lab buffers`); `NAME@K`
    /// picks array layer K (e.g. `direct.shadow_map@2`).
    #[arg(long = "buffer")]
    pub buffers: Vec<String>,
    /// Output folder (created).
    #[arg(long)]
    pub out: PathBuf,
}

#[derive(Args, Debug)]
pub struct ReferenceArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    #[arg(long, default_value = "128x128", value_parser = parse_size)]
    pub size: (u32, u32),
    /// Samples per pixel.
    #[arg(long, default_value_t = 64)]
    pub spp: u32,
    /// Indirect bounces (0 = direct light only).
    #[arg(long, default_value_t = 1)]
    pub bounces: u32,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Output EXR of the full image; `.direct.exr` and `.indirect.exr` go beside it.
    #[arg(long)]
    pub out: PathBuf,
}

#[derive(Args, Debug)]
pub struct HcbStatsArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    #[arg(long, default_value = "512x512", value_parser = parse_size)]
    pub size: (u32, u32),
    /// Frames to render (with `hcb.cache` on, one line of cache counts per frame; the table
    /// is the last frame's).
    #[arg(long, default_value_t = 1)]
    pub frames: u32,
    /// Play the scene's animation (otherwise time stays at 0).
    #[arg(long)]
    pub play: bool,
}

#[derive(Args, Debug)]
pub struct CompareArgs {
    /// The test image.
    pub test: PathBuf,
    /// The reference image (same size).
    pub reference: PathBuf,
    /// Write the FLIP error map here (PNG, turbo false colour).
    #[arg(long)]
    pub flip_map: Option<PathBuf>,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

#[derive(Args, Debug)]
pub struct BenchArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    #[arg(long, default_value = "1280x720", value_parser = parse_size)]
    pub size: (u32, u32),
    /// Measured frames (after 3 warm-up frames).
    #[arg(long, default_value_t = 30)]
    pub frames: u32,
    /// Frames of the paused scene over which temporal flicker is measured (0: skip).
    #[arg(long, default_value_t = 8)]
    pub flicker_frames: u32,
    /// Frames over which the afterglow of a sudden light change is measured (0: skip).
    #[arg(long, default_value_t = 12)]
    pub afterglow_frames: u32,
    /// A ground-truth EXR of the same scene, camera and size at animation time 0 (`gi-lab
    /// reference`): adds FLIP and RMSE of final.hdr at time 0 against it.
    #[arg(long)]
    pub reference: Option<PathBuf>,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Run a suite of rows instead of one configuration: `knecht` reproduces the shape of
    /// `knecht`: Knecht's Tables 5.1–5.3 (frame time against VPL count and ISM size, the
    /// temporal coherence overhead, multi-bounce against IRSM); `nguyen`: the HCB against
    /// gathering at every pixel at 1024 VPLs, with the samples' share of the pixels. Both
    /// start from --preset.
    #[arg(long, value_enum)]
    pub suite: Option<BenchSuite>,
}

/// Benchmark suites of `gi-lab bench --suite`.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum BenchSuite {
    Knecht,
    Nguyen,
}

/// Parses `WIDTHxHEIGHT`.
pub fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(|| format!("'{s}' is not WIDTHxHEIGHT (e.g. 640x480)"))?;
    let w: u32 = w.trim().parse().map_err(|_| format!("width '{w}' is not a positive whole number"))?;
    let h: u32 = h.trim().parse().map_err(|_| format!("height '{h}' is not a positive whole number"))?;
    if w == 0 || h == 0 {
        return Err(format!("'{s}': width and height must be at least 1"));
    }
    Ok((w, h))
}

/// An error of the CLI with its exit code.
#[derive(Debug)]
pub struct CliError {
    pub code: u8,
    pub message: String,
}

impl CliError {
    /// Bad arguments or input (exit 2).
    pub fn input(message: impl Into<String>) -> Self {
        Self { code: 2, message: message.into() }
    }
    /// Environment or internal failure (exit 1).
    pub fn failure(message: impl Into<String>) -> Self {
        Self { code: 1, message: message.into() }
    }
}

/// Loads the scene named by the arguments (or the embedded default).
pub fn load_scene(args: &SceneArgs) -> Result<Scene, CliError> {
    if !(args.unit_scale.is_finite() && args.unit_scale > 0.0) {
        return Err(CliError::input(format!("--unit-scale {} must be a positive number", args.unit_scale)));
    }
    let opts = LoadOptions { unit_scale: args.unit_scale, ..LoadOptions::default() };
    let scene = match &args.scene {
        None => scene::cornell::default_scene().map_err(|e| CliError::failure(format!("embedded scene: {e}")))?,
        Some(p) => scene::load_gltf_file(p, &opts).map_err(|e| CliError::input(e.to_string()))?,
    };
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    Ok(scene)
}

/// Loads the preset and applies the `--set` overrides.
pub fn load_settings(args: &SceneArgs) -> Result<LabSettings, CliError> {
    let mut s = match &args.preset {
        None => LabSettings::default(),
        Some(p) => LabSettings::load(p).map_err(|e| CliError::input(e.to_string()))?,
    };
    for o in &args.overrides {
        s.apply_override(o).map_err(|e| CliError::input(format!("--set {o}: {e}")))?;
    }
    Ok(s)
}

pub fn renderer(args: &SceneArgs, size: (u32, u32)) -> Result<Renderer, CliError> {
    let scene = load_scene(args)?;
    let settings = load_settings(args)?;
    let ctx = GpuContext::headless().map_err(|e| CliError::failure(e.to_string()))?;
    Renderer::new(ctx, scene, settings, size.0, size.1).map_err(|e| CliError::input(e.to_string()))
}

/// Splits `NAME@LAYER` into the buffer name and the array layer (0 without `@`).
pub fn parse_buffer_spec(spec: &str) -> Result<(&str, u32), CliError> {
    match spec.rsplit_once('@') {
        None => Ok((spec, 0)),
        Some((name, layer)) => layer
            .parse()
            .map(|l| (name, l))
            .map_err(|_| CliError::input(format!("--buffer {spec}: '{layer}' is not a layer number"))),
    }
}

/// Writes a buffer (`NAME` or `NAME@LAYER`) as PNG, and as EXR for float formats, into
/// `dir`; returns the files.
pub fn write_buffer(r: &Renderer, spec: &str, dir: &Path) -> Result<Vec<PathBuf>, CliError> {
    let (name, layer) = parse_buffer_spec(spec)?;
    let entry = r.buffers().get(name).map_err(|e| CliError::input(e.to_string()))?;
    let img = r.buffers().readback(&r.ctx, name, layer, 0).map_err(|e| CliError::input(e.to_string()))?;
    let stem = if layer == 0 { name.to_string() } else { format!("{name}.layer{layer}") };
    let mut files = Vec::new();
    let png = dir.join(format!("{stem}.png"));
    gi_render::image_io::save_png(&png, &img, entry.kind)
        .map_err(|e| CliError::failure(format!("{}: {e}", png.display())))?;
    files.push(png);
    let is_float =
        !matches!(entry.texture.format(), wgpu::TextureFormat::Rgba8Unorm | wgpu::TextureFormat::Rgba8UnormSrgb);
    if is_float {
        let exr = dir.join(format!("{stem}.exr"));
        gi_render::image_io::save_exr(&exr, &img).map_err(|e| CliError::failure(format!("{}: {e}", exr.display())))?;
        files.push(exr);
    }
    Ok(files)
}

/// `gi-lab hcb-stats`: `--frames` frames with the HCB (time 0, or playing), and the last
/// one's samples per level — count, share of the level's texels and of the G-buffer — as
/// Nguyen et al.'s Table 1; with the cache, each frame's cached, new and recomputed samples.
fn hcb_stats(args: &HcbStatsArgs) -> Result<(), CliError> {
    if args.frames == 0 {
        return Err(CliError::input("--frames must be at least 1"));
    }
    let mut r = renderer(&args.scene, args.size)?;
    r.clock.playing = args.play;
    let mut s = r.settings().clone();
    s.indirect.technique = gi_render::lab_settings::IndirectTechnique::Hcb;
    r.set_settings(s).map_err(|e| CliError::input(e.to_string()))?;
    let mut stats = None;
    for frame in 0..args.frames {
        r.render_frame();
        let st = r.hcb_stats().ok_or_else(|| CliError::failure("the HCB produced no statistics"))?;
        if let Some(c) = &st.cache {
            println!("frame {frame:>3}: {c}");
        }
        stats = Some(st);
    }
    let stats = stats.ok_or_else(|| CliError::failure("no frame rendered"))?;
    print!("{}", format_hcb_stats(&stats, args.size));
    Ok(())
}

/// The statistics as Table 1 of Nguyen et al.: per level the samples, their share of the
/// level's texels and of the G-buffer's pixels.
pub fn format_hcb_stats(stats: &gi_render::frame::HcbStats, size: (u32, u32)) -> String {
    let pixels = (size.0 * size.1).max(1) as f64;
    let mut out = format!("HCB samples at {}×{} (Nguyen et al. Table 1)\n", size.0, size.1);
    out += &format!("{:<8} {:>10} {:>12} {:>12} {:>14}\n", "level", "texels", "samples", "% of level", "% of G-buffer");
    for (k, (&n, &t)) in stats.samples_per_level.iter().zip(&stats.texels_per_level).enumerate() {
        out += &format!(
            "{k:<8} {t:>10} {n:>12} {:>11.2}% {:>13.2}%\n",
            100.0 * n as f64 / t.max(1) as f64,
            100.0 * n as f64 / pixels
        );
    }
    out += &format!(
        "{:<8} {:>10} {:>12} {:>12} {:>13.2}%\n",
        "total",
        "",
        stats.samples(),
        "",
        100.0 * stats.samples() as f64 / pixels
    );
    out += &format!("covered pixels no sample reached: {}\n", stats.uncovered);
    out += &format!("d_max in use: {:.4} scene units\n", stats.d_max);
    out
}

fn render(args: &RenderArgs) -> Result<(), CliError> {
    if args.frames == 0 {
        return Err(CliError::input("--frames must be at least 1"));
    }
    let mut r = renderer(&args.scene, args.size)?;
    r.clock.playing = !args.paused;
    // Check buffer names before spending time rendering.
    for b in &args.buffers {
        let (name, _) = parse_buffer_spec(b)?;
        r.buffers().get(name).map_err(|e| CliError::input(e.to_string()))?;
    }
    std::fs::create_dir_all(&args.out).map_err(|e| CliError::input(format!("--out {}: {e}", args.out.display())))?;
    for _ in 0..args.frames {
        r.render_frame();
    }
    let img = r.readback("final.ldr").map_err(|e| CliError::failure(e.to_string()))?;
    let final_png = args.out.join("final.png");
    gi_render::image_io::save_png(&final_png, &img, gi_render::BufferKind::Ldr)
        .map_err(|e| CliError::failure(format!("{}: {e}", final_png.display())))?;
    println!("wrote {}", final_png.display());
    for b in &args.buffers {
        for f in write_buffer(&r, b, &args.out)? {
            println!("wrote {}", f.display());
        }
    }
    Ok(())
}

/// Per-pass statistics of a benchmark run.
#[derive(Debug, Clone, serde::Serialize)]
pub struct PassStats {
    pub pass: String,
    pub mean_ms: f64,
    pub min_ms: f64,
    pub max_ms: f64,
}

#[derive(Debug, Clone, serde::Serialize)]
pub struct BenchReport {
    pub adapter: String,
    pub timing_source: String,
    pub scene: String,
    pub width: u32,
    pub height: u32,
    pub frames: u32,
    pub passes: Vec<PassStats>,
    pub total_mean_ms: f64,
    /// Temporal flicker of final.hdr with the animation paused and the camera still
    /// (`metrics::flicker`); None when not measured.
    pub flicker: Option<f64>,
    /// Quality against `--reference`: mean FLIP (tone-mapped x/(1+x)) and RMSE (linear).
    pub flip: Option<f64>,
    pub rmse: Option<f64>,
    /// Frames until the error against the settled image returns within 2× its steady state
    /// after the first light's intensity is halved (`metrics::afterglow`); None when not
    /// measured or when it did not settle.
    pub afterglow_frames: Option<usize>,
}

/// Renders warm-up and measured frames and aggregates the per-pass times.
pub fn bench_run(r: &mut Renderer, frames: u32, scene_name: &str) -> BenchReport {
    for _ in 0..3 {
        r.render_frame();
    }
    let mut names: Vec<String> = Vec::new();
    let mut samples: Vec<Vec<f64>> = Vec::new();
    for _ in 0..frames {
        for t in r.render_frame() {
            let i = match names.iter().position(|n| *n == t.name) {
                Some(i) => i,
                None => {
                    names.push(t.name.clone());
                    samples.push(Vec::new());
                    names.len() - 1
                }
            };
            samples[i].push(t.ms);
        }
    }
    let passes: Vec<PassStats> = names
        .into_iter()
        .zip(samples)
        .map(|(pass, s)| PassStats {
            pass,
            mean_ms: s.iter().sum::<f64>() / s.len().max(1) as f64,
            min_ms: s.iter().copied().fold(f64::INFINITY, f64::min),
            max_ms: s.iter().copied().fold(0.0, f64::max),
        })
        .collect();
    let (width, height) = r.size();
    BenchReport {
        adapter: r.ctx.adapter_summary(),
        timing_source: format!("{:?}", r.timing_source()),
        scene: scene_name.to_string(),
        width,
        height,
        frames,
        total_mean_ms: passes.iter().map(|p| p.mean_ms).sum(),
        passes,
        flicker: None,
        flip: None,
        rmse: None,
        afterglow_frames: None,
    }
}

pub fn format_bench_table(b: &BenchReport) -> String {
    let mut s = format!(
        "GI Lab bench — {} at {}×{}, {} frames, {} ({})\n",
        b.scene, b.width, b.height, b.frames, b.adapter, b.timing_source
    );
    s += &format!("{:<16} {:>10} {:>10} {:>10}\n", "pass", "mean ms", "min ms", "max ms");
    for p in &b.passes {
        s += &format!("{:<16} {:>10.3} {:>10.3} {:>10.3}\n", p.pass, p.mean_ms, p.min_ms, p.max_ms);
    }
    s += &format!("{:<16} {:>10.3}\n", "total", b.total_mean_ms);
    if let Some(f) = b.flicker {
        s += &format!("flicker (static scene) {f:.6}\n");
    }
    if let Some(a) = b.afterglow_frames {
        s += &format!("afterglow (first light halved) {a} frames\n");
    }
    if let (Some(flip), Some(rmse)) = (b.flip, b.rmse) {
        s += &format!("quality vs reference: FLIP {flip:.4}, RMSE {rmse:.5}\n");
    }
    s
}

/// Temporal flicker over `frames` frames with the animation paused (the clock restored).
pub fn measure_flicker(r: &mut Renderer, frames: u32) -> Result<f64, CliError> {
    let playing = r.clock.playing;
    r.clock.playing = false;
    let mut images = Vec::new();
    for _ in 0..frames {
        r.render_frame();
        images.push(r.readback("final.hdr").map_err(|e| CliError::failure(e.to_string()))?);
    }
    r.clock.playing = playing;
    gi_render::metrics::flicker(&images).map_err(|e| CliError::input(format!("--flicker-frames: {e}")))
}

/// Afterglow of a sudden light change: the first light's intensity is halved and the RMSE of
/// each of the next `frames` frames is taken against the image the renderer settles on when
/// it starts with the halved light (`frames` frames after a history reset). The scene is
/// paused; the light and the clock are restored afterwards. None when the scene has no light
/// or the error does not settle.
pub fn measure_afterglow(r: &mut Renderer, frames: u32) -> Result<Option<usize>, CliError> {
    let Some(li) = r.scene().lights.iter().position(|_| true) else { return Ok(None) };
    let clock = r.clock;
    r.clock.playing = false;
    let original = r.scene().lights[li].intensity;
    let read = |r: &Renderer| r.readback("final.hdr").map_err(|e| CliError::failure(e.to_string()));
    let run = |r: &mut Renderer, intensity: f32, reset: bool| {
        r.scene_mut().lights[li].intensity = intensity;
        if reset {
            r.reset_history();
        }
    };
    run(r, original * 0.5, true);
    for _ in 0..frames {
        r.render_frame();
    }
    let settled = read(r)?;
    run(r, original, true);
    for _ in 0..frames {
        r.render_frame();
    }
    // The sudden change: no reset, the renderer must notice by itself.
    run(r, original * 0.5, false);
    let mut errors = Vec::with_capacity(frames as usize);
    for _ in 0..frames {
        r.render_frame();
        let e = gi_render::metrics::rmse(&read(r)?, &settled).map_err(|e| CliError::failure(e.to_string()))?;
        errors.push(e);
    }
    run(r, original, true);
    r.clock = clock;
    Ok(gi_render::metrics::afterglow(&errors, 0))
}

/// FLIP (tone-mapped) and RMSE (linear) of the renderer's final.hdr against a reference of
/// the scene at animation time 0 (as `gi-lab reference` renders it): the clock is set back
/// to 0 and paused for that frame.
pub fn quality_against(r: &mut Renderer, reference: &Path) -> Result<(f64, f64), CliError> {
    let (reference_img, _) = load_image(reference)?;
    let clock = r.clock;
    r.clock.anim_frame = 0;
    r.clock.playing = false;
    r.render_frame();
    r.clock = clock;
    let hdr = r.readback("final.hdr").map_err(|e| CliError::failure(e.to_string()))?;
    let err = |e: gi_render::metrics::MetricError| CliError::input(format!("--reference {}: {e}", reference.display()));
    let rmse = gi_render::metrics::rmse(&hdr, &reference_img).map_err(err)?;
    let (flip, map) = gi_render::metrics::flip(
        &gi_render::image_io::hdr_display(&hdr),
        &gi_render::image_io::hdr_display(&reference_img),
    )
    .map_err(err)?;
    r.set_flip_map(&map);
    Ok((flip, rmse))
}

fn bench(args: &BenchArgs) -> Result<(), CliError> {
    if args.frames == 0 {
        return Err(CliError::input("--frames must be at least 1"));
    }
    let mut r = renderer(&args.scene, args.size)?;
    if !gi_render::timing::GpuTimer::timestamps_reliable(&r.ctx) {
        // A software device's timestamps land in the wrong passes: time each pass by the
        // wall clock instead (each scope is submitted and awaited on its own).
        r.set_timing_source(gi_render::timing::TimingSource::CpuWallClock);
    }
    let name =
        args.scene.scene.as_ref().map(|p| p.display().to_string()).unwrap_or_else(|| "default Cornell box".into());
    if let Some(BenchSuite::Knecht) = args.suite {
        let report = crate::bench_suites::knecht(&mut r, args.frames, &name)?;
        if args.json {
            println!("{}", serde_json::to_string_pretty(&report).map_err(|e| CliError::failure(e.to_string()))?);
        } else {
            print!("{}", crate::bench_suites::format(&report));
        }
        return Ok(());
    }
    if let Some(BenchSuite::Nguyen) = args.suite {
        let report = crate::bench_suites::nguyen(&mut r, args.frames, &name)?;
        if args.json {
            println!("{}", serde_json::to_string_pretty(&report).map_err(|e| CliError::failure(e.to_string()))?);
        } else {
            print!("{}", crate::bench_suites::format_nguyen(&report));
        }
        return Ok(());
    }
    let mut report = bench_run(&mut r, args.frames, &name);
    if args.flicker_frames == 1 {
        return Err(CliError::input("--flicker-frames must be 0 or at least 2"));
    }
    if args.flicker_frames >= 2 {
        report.flicker = Some(measure_flicker(&mut r, args.flicker_frames)?);
    }
    if args.afterglow_frames > 0 && args.afterglow_frames < 4 {
        return Err(CliError::input("--afterglow-frames must be 0 or at least 4"));
    }
    if args.afterglow_frames >= 4 {
        report.afterglow_frames = measure_afterglow(&mut r, args.afterglow_frames)?;
    }
    if let Some(reference) = &args.reference {
        let (flip, rmse) = quality_against(&mut r, reference)?;
        report.flip = Some(flip);
        report.rmse = Some(rmse);
    }
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report).map_err(|e| CliError::failure(e.to_string()))?);
    } else {
        print!("{}", format_bench_table(&report));
    }
    Ok(())
}

/// Metrics of one image pair.
#[derive(Debug, Clone, serde::Serialize)]
pub struct CompareReport {
    /// Whether the inputs were float (HDR) images; FLIP then runs on their tone-mapped
    /// versions (x / (1 + x), sRGB).
    pub hdr: bool,
    pub rmse: f64,
    pub rel_mse: f64,
    pub flip: f64,
}

/// Loads an image as f32 RGBA: EXR and other float formats as linear values, 8-bit images
/// as their display values in [0, 1]. Returns whether it was a float image.
pub fn load_image(path: &Path) -> Result<(gi_render::ImageF32, bool), CliError> {
    let img = image::open(path).map_err(|e| CliError::input(format!("{}: {e}", path.display())))?;
    let float = matches!(img.color(), image::ColorType::Rgb32F | image::ColorType::Rgba32F);
    let rgba = img.into_rgba32f();
    Ok((
        gi_render::ImageF32 { width: rgba.width(), height: rgba.height(), data: rgba.pixels().map(|p| p.0).collect() },
        float,
    ))
}

/// Compares two image files.
pub fn compare_files(test: &Path, reference: &Path, flip_map: Option<&Path>) -> Result<CompareReport, CliError> {
    use gi_render::metrics;
    let (t, t_float) = load_image(test)?;
    let (r, r_float) = load_image(reference)?;
    let hdr = t_float && r_float;
    let err = |e: metrics::MetricError| CliError::input(format!("{} vs {}: {e}", test.display(), reference.display()));
    let rmse = metrics::rmse(&t, &r).map_err(err)?;
    let rel_mse = metrics::rel_mse(&t, &r).map_err(err)?;
    let display = |i: &gi_render::ImageF32| if hdr { gi_render::image_io::hdr_display(i) } else { i.clone() };
    let (flip, map) = metrics::flip(&display(&t), &display(&r)).map_err(err)?;
    if let Some(path) = flip_map {
        let mut png = image::RgbaImage::new(map.width, map.height);
        for (px, e) in png.pixels_mut().zip(&map.data) {
            let [r, g, b] = gi_render::image_io::turbo(e[0]);
            *px = image::Rgba([r, g, b, 1.0].map(|x| (x * 255.0).round() as u8));
        }
        png.save(path).map_err(|e| CliError::input(format!("{}: {e}", path.display())))?;
    }
    Ok(CompareReport { hdr, rmse, rel_mse, flip })
}

fn compare(args: &CompareArgs) -> Result<(), CliError> {
    let r = compare_files(&args.test, &args.reference, args.flip_map.as_deref())?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&r).map_err(|e| CliError::failure(e.to_string()))?);
    } else {
        println!("RMSE     {:.6}{}", r.rmse, if r.hdr { " (linear HDR)" } else { " (display values)" });
        println!("relMSE   {:.6}", r.rel_mse);
        println!("FLIP     {:.6} (mean{})", r.flip, if r.hdr { ", on tone-mapped images" } else { "" });
    }
    Ok(())
}

fn reference(args: &ReferenceArgs) -> Result<(), CliError> {
    use gi_render::cpu::pathtrace::{PathTracer, PtSettings};
    if args.spp == 0 {
        return Err(CliError::input("--spp must be at least 1"));
    }
    let scene = load_scene(&args.scene)?;
    let (w, h) = args.size;
    let bounds = scene.bounds(0.0);
    let camera = gi_render::frame::default_camera(&scene, bounds, w as f32 / h as f32);
    let start = std::time::Instant::now();
    let pt = PathTracer::new(&scene, 0.0);
    let build_s = start.elapsed().as_secs_f64();
    let img = pt.render(
        camera.view_proj(w as f32 / h as f32),
        camera.position,
        w,
        h,
        PtSettings { bounces: args.bounces, spp: args.spp, seed: args.seed },
    );
    let total_s = start.elapsed().as_secs_f64();
    if let Some(dir) = args.out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| CliError::input(format!("--out {}: {e}", args.out.display())))?;
    }
    let stem = args.out.with_extension("");
    for (path, image) in [
        (args.out.clone(), &img.full),
        (stem.with_extension("direct.exr"), &img.direct),
        (stem.with_extension("indirect.exr"), &img.indirect),
    ] {
        gi_render::image_io::save_exr(&path, image).map_err(|e| CliError::input(format!("{}: {e}", path.display())))?;
        println!("wrote {}", path.display());
    }
    let preview = stem.with_extension("png");
    gi_render::image_io::save_png(&preview, &img.full, gi_render::BufferKind::Hdr)
        .map_err(|e| CliError::input(format!("{}: {e}", preview.display())))?;
    println!("wrote {} (preview: x/(1+x), sRGB)", preview.display());
    println!(
        "path traced {w}×{h}, {} spp, {} bounces in {total_s:.2} s (BVH {build_s:.2} s, {} threads)",
        args.spp,
        args.bounces,
        rayon_threads()
    );
    Ok(())
}

fn rayon_threads() -> usize {
    std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1)
}

fn buffers(args: &SceneArgs) -> Result<(), CliError> {
    let r = renderer(args, (16, 16))?;
    for e in r.buffers().entries() {
        println!("{:<22} {:<14} {}", e.name, format!("{:?}", e.texture.format()), e.description);
    }
    Ok(())
}

fn settings() {
    for (group, fields) in LabSettings::groups() {
        println!("[{group}]");
        let d = LabSettings::default();
        for m in fields {
            let path = format!("{group}.{}", m.name);
            let default = d.get(&path).map(|v| v.to_string()).unwrap_or_default();
            let range = match m.kind {
                gi_render::settings::FieldKind::F32 | gi_render::settings::FieldKind::U32 => {
                    format!("[{}, {}] {}", m.min, m.max, m.unit)
                }
                gi_render::settings::FieldKind::Bool => "on/off".into(),
                gi_render::settings::FieldKind::Choice(c) => c.join(" | "),
            };
            let doc = m.doc.lines().next().unwrap_or("");
            println!("  {:<26} default {:<10} {:<24} {}", path, default, range, doc);
        }
    }
}

/// `gi-lab export`: the preset (with overrides) as an engine export.
fn export(a: &ExportArgs) -> Result<(), CliError> {
    use gi_render::preset::{Export, ExportFormat, Provenance, schema_markdown, write_atomic};
    if let Some(path) = &a.schema_doc {
        return write_atomic(path, &schema_markdown())
            .map(|_| println!("wrote {}", path.display()))
            .map_err(|e| CliError::input(format!("{}: {e}", path.display())));
    }
    let format = ExportFormat::parse(&a.format)
        .ok_or_else(|| CliError::input(format!("--format {}: expected json or ron", a.format)))?;
    let settings = load_settings(&a.scene)?;
    let scene = load_scene(&a.scene)?;
    let camera = gi_render::frame::default_camera(&scene, scene.bounds(0.0), 16.0 / 9.0);
    let name = a.scene.scene.as_ref().map(|p| p.display().to_string()).unwrap_or_else(|| scene.name.clone());
    let text = Export::new(settings, Provenance::now(&name, camera)).to_text(format);
    match &a.out {
        None => {
            println!("{text}");
            Ok(())
        }
        Some(path) => write_atomic(path, &text)
            .map(|_| println!("wrote {}", path.display()))
            .map_err(|e| CliError::input(format!("{}: {e}", path.display()))),
    }
}

/// Runs the command line; returns the process exit code.
pub fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            // clap prints help/version with exit 0 and usage errors with exit 2.
            let _ = e.print();
            return ExitCode::from(e.exit_code().clamp(0, 255) as u8);
        }
    };
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    let result = match &cli.command {
        None => crate::app::run(cli.app.clone()).map_err(CliError::failure),
        Some(Command::Render(a)) => render(a),
        Some(Command::Buffers(a)) => buffers(a),
        Some(Command::Bench(a)) => bench(a),
        Some(Command::Compare(a)) => compare(a),
        Some(Command::Reference(a)) => reference(a),
        Some(Command::HcbStats(a)) => hcb_stats(a),
        Some(Command::Sweep(a)) => crate::sweep::sweep(a),
        Some(Command::Settings) => {
            settings();
            Ok(())
        }
        Some(Command::Export(a)) => export(a),
        Some(Command::GenAssets { out }) => std::fs::write(out, scene::cornell::build_glb())
            .map(|_| println!("wrote {}", out.display()))
            .map_err(|e| CliError::input(format!("{}: {e}", out.display()))),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("gi-lab: error: {}", e.message);
            ExitCode::from(e.code)
        }
    }
}
