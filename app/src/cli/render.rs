//! `gi-lab render`: headless frames to final.png plus the named buffers.

use std::path::{Path, PathBuf};

use clap::Args;
use gi_render::Renderer;

use super::{parse_size, renderer};
use crate::error::CliError;
use crate::scene_args::SceneArgs;

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
    /// accumulate: `--paused --frames 64 --preset presets/exact-vpl-reference.ron`).
    #[arg(long)]
    pub paused: bool,
    /// A buffer to write besides final.png (repeatable; see `gi-lab buffers`); `NAME@K`
    /// picks array layer K (e.g. `direct.shadow_map@2`).
    #[arg(long = "buffer")]
    pub buffers: Vec<String>,
    /// Explain pixel X,Y of the last frame (issue #42): print where its indirect light comes
    /// from (every contributor, its share, weights and rejections, and the sum checked
    /// against the buffers) and write explain.csv into the output folder.
    #[arg(long, value_parser = crate::args::parse_pixel)]
    pub explain: Option<(u32, u32)>,
    /// Rows of the explanation to print (0: all).
    #[arg(long, default_value_t = 24)]
    pub explain_rows: usize,
    /// Output folder (created).
    #[arg(long)]
    pub out: PathBuf,
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

pub(super) fn render(args: &RenderArgs) -> Result<(), CliError> {
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
    if let Some((x, y)) = args.explain {
        if x >= args.size.0 || y >= args.size.1 {
            return Err(CliError::input(format!(
                "--explain {x},{y}: outside the {}x{} image",
                args.size.0, args.size.1
            )));
        }
        if let Some(why) = r.explain_unsupported() {
            return Err(CliError::input(format!("--explain: {why}")));
        }
        r.set_explain(Some((x, y)));
    }
    std::fs::create_dir_all(&args.out).map_err(|e| CliError::input(format!("--out {}: {e}", args.out.display())))?;
    // GI_LAB_TEST_LOSE_DEVICE_AT=K destroys the device before frame K, as a driver reset
    // would (the test suite checks that the run ends with a clear error).
    let lose_at: Option<u32> = std::env::var("GI_LAB_TEST_LOSE_DEVICE_AT").ok().and_then(|v| v.parse().ok());
    for frame in 0..args.frames {
        if lose_at == Some(frame) {
            r.ctx.device.destroy();
        }
        r.render_frame();
        if r.ctx.lost_reason().is_some() {
            break;
        }
    }
    let img = r.readback("final.ldr").map_err(|e| CliError::failure(e.to_string()))?;
    let final_png = args.out.join("final.png");
    gi_render::image_io::save_png(&final_png, &img, gi_render::BufferKind::Ldr)
        .map_err(|e| CliError::failure(format!("{}: {e}", final_png.display())))?;
    println!("wrote {}", final_png.display());
    // The frame as a list (docs/architecture.md, "The frame as a list"): stages 3–7's steps.
    let steps: Vec<String> = r.frame_steps().iter().map(|(stage, name)| format!("{stage} {name}")).collect();
    println!("steps: {}", if steps.is_empty() { "none (direct light only)".into() } else { steps.join(" → ") });
    if let Some(step) = r.failed_step() {
        return Err(CliError::failure(format!("the step {step} found no pass to run")));
    }
    for b in &args.buffers {
        for f in write_buffer(&r, b, &args.out)? {
            println!("wrote {}", f.display());
        }
    }
    if args.explain.is_some() {
        let e = r.explanation().map_err(|e| CliError::failure(format!("--explain: {e}")))?;
        print!("{}", e.to_text(args.explain_rows));
        let csv = args.out.join("explain.csv");
        std::fs::write(&csv, e.to_csv()).map_err(|e| CliError::failure(format!("{}: {e}", csv.display())))?;
        println!("wrote {}", csv.display());
    }
    Ok(())
}
