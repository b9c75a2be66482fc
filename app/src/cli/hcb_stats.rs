//! `gi-lab hcb-stats`: the HCB's samples per level as Table 1 of Nguyen et al.

use clap::Args;

use super::{parse_size, renderer};
use crate::error::CliError;
use crate::scene_args::SceneArgs;

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

/// `gi-lab hcb-stats`: `--frames` frames with the HCB (time 0, or playing), and the last
/// one's samples per level — count, share of the level's texels and of the G-buffer — as
/// Nguyen et al.'s Table 1; with the cache, each frame's cached, new and recomputed samples.
pub(super) fn hcb_stats(args: &HcbStatsArgs) -> Result<(), CliError> {
    if args.frames == 0 {
        return Err(CliError::input("--frames must be at least 1"));
    }
    let mut r = renderer(&args.scene, args.size)?;
    r.clock.playing = args.play;
    let mut s = r.settings().clone();
    if !s.pipeline.uses_hcb() {
        gi_render::settings::pipeline::Technique::Nguyen.apply(&mut s);
    }
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
pub fn format_hcb_stats(stats: &gi_render::passes::hcb::stage::HcbStats, size: (u32, u32)) -> String {
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
