//! `gi-lab reference`: a ground-truth image path-traced on the CPU, or on the GPU with `--gpu`
//! (issue #56: the same estimator over the GPU ray caster, `passes::rays::pathtrace`).

use std::path::PathBuf;

use clap::Args;

use super::parse_size;
use crate::error::CliError;
use crate::scene_args::{SceneArgs, load_scene};

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
    /// Count only light whose first bounce lands on a surface the camera sees (in its frustum,
    /// unoccluded from the eye): the ground truth of what a screen-space gather (Soler et al.)
    /// can know, so that its own error shows apart from the light hidden from the screen.
    #[arg(long)]
    pub screen_visible_senders: bool,
    /// Trace on the GPU (the same estimator over the GPU ray caster; its own random numbers,
    /// so its image equals the CPU's up to noise). On a software adapter (lavapipe) it is
    /// slower than the CPU tracer.
    #[arg(long)]
    pub gpu: bool,
    /// Output EXR of the full image; `.direct.exr` and `.indirect.exr` go beside it.
    #[arg(long)]
    pub out: PathBuf,
}

pub(super) fn reference(args: &ReferenceArgs) -> Result<(), CliError> {
    use gi_render::cpu::pathtrace::{PathTracer, PtSettings, Senders};
    if args.spp == 0 {
        return Err(CliError::input("--spp must be at least 1"));
    }
    let scene = load_scene(&args.scene)?;
    let (w, h) = args.size;
    let bounds = scene.bounds(0.0);
    let camera = gi_render::renderer::default_camera(&scene, bounds, w as f32 / h as f32);
    let start = std::time::Instant::now();
    // The emitters and the sky's background as the preset says (`emitters.enabled`,
    // `emitters.two_sided`, `sky.background`).
    let preset = crate::scene_args::load_settings(&args.scene)?;
    let settings = PtSettings {
        bounces: args.bounces,
        spp: args.spp,
        seed: args.seed,
        senders: if args.screen_visible_senders { Senders::ScreenVisible } else { Senders::All },
    };
    let view_proj = camera.view_proj(w as f32 / h as f32);
    let (img, build_s, by) = if args.gpu {
        if args.screen_visible_senders {
            return Err(CliError::input(
                "--screen-visible-senders is the CPU tracer's alone; leave out --gpu to trace it",
            ));
        }
        use gi_render::passes::rays::pathtrace::GpuPathTracer;
        let ctx = gi_render::GpuContext::headless().map_err(|e| CliError::failure(e.to_string()))?;
        let mut pt = GpuPathTracer::new(&ctx, &scene, 0.0).map_err(CliError::input)?;
        pt.use_emitter_settings(&preset.emitters, &scene, 0.0);
        pt.set_sky_background(preset.sky.background);
        let build_s = start.elapsed().as_secs_f64();
        let img = pt.render(&ctx, view_proj, camera.position, (w, h), settings).map_err(CliError::failure)?;
        (img, build_s, format!("on the GPU ({})", ctx.adapter_summary()))
    } else {
        let mut pt = PathTracer::new(&scene, 0.0);
        pt.use_emitter_settings(&preset.emitters, &scene, 0.0);
        pt.set_sky_background(preset.sky.background);
        let build_s = start.elapsed().as_secs_f64();
        let img = pt.render(view_proj, camera.position, w, h, settings);
        (img, build_s, format!("on the CPU ({} threads)", rayon_threads()))
    };
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
    let paths = w as f64 * h as f64 * args.spp as f64;
    println!(
        "path traced {w}×{h}, {} spp, {} bounces{} {by} in {total_s:.2} s (scene prepared in {build_s:.2} s; \
         {:.2} M paths/s)",
        args.spp,
        args.bounces,
        if args.screen_visible_senders { " from screen-visible senders" } else { "" },
        paths / (total_s - build_s).max(1e-9) / 1e6
    );
    Ok(())
}

fn rayon_threads() -> usize {
    std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1)
}
