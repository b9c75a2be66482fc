//! `gi-lab bench --suite scenes` (issue #18, "Tests and measures"): for every scene in the
//! scenes folder (`--scenes-dir`, by default `assets/`, with the real scenes of `assets/scenes/`), its
//! triangles, punctual lights (and whether the lab added the default one), emissive
//! triangles, load time, and the mean frame time (sum of the passes) of each shipped
//! technique preset at `--size`. Scenes whose extent exceeds 100 units are read as
//! millimetres (× 0.001, as the hotel room needs). Then the default box with a glowing sphere
//! of 48, 960 and 6,016 emissive triangles: the emitter VPLs do not grow with the triangles,
//! so the frame time should not either (issue #18's many-emitter row).

use std::path::{Path, PathBuf};
use std::time::Instant;

use gi_render::{GpuContext, LabSettings};

use crate::error::CliError;

/// One scene's row.
#[derive(Debug, Clone, serde::Serialize)]
pub struct SceneRow {
    pub scene: String,
    pub triangles: usize,
    /// Punctual lights (with the default one the lab adds to a scene without lights).
    pub lights: usize,
    pub default_light: bool,
    /// Triangles whose material emits.
    pub emissive_triangles: usize,
    pub unit_scale: f32,
    pub load_ms: f64,
    /// Mean frame time of each preset (ms; the passes' sum over `frames` after 3 warm-up
    /// frames), or the error that stopped it.
    pub frame_ms: Vec<PresetTime>,
}

/// The glTF files of a folder and its subfolders (sorted).
pub(super) fn scene_files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let Ok(entries) = std::fs::read_dir(dir) else { return out };
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            out.extend(scene_files(&p));
        } else if p.extension().is_some_and(|x| x == "gltf" || x == "glb") {
            out.push(p);
        }
    }
    out.sort();
    out
}

pub(super) fn load(path: &Path, unit_scale: f32) -> Result<gi_render::scene::Scene, CliError> {
    let args = crate::scene_args::SceneArgs { scene: Some(path.to_path_buf()), unit_scale, ..Default::default() };
    crate::scene_args::load_scene(&args)
}

/// Runs the suite. `overrides` (`--set group.field=value`) apply on top of every technique's
/// preset (e.g. fewer VPLs for a quick pass over the scenes).
pub fn scenes(
    scenes_dir: &Path,
    size: (u32, u32),
    frames: u32,
    overrides: &[String],
) -> Result<Vec<SceneRow>, CliError> {
    let presets = technique_settings(overrides)?;
    let files = scene_files(scenes_dir);
    if files.is_empty() {
        return Err(CliError::input(format!(
            "no glTF scenes below {} (run from the project root, or give --scenes-dir)",
            scenes_dir.display()
        )));
    }
    let ctx = GpuContext::headless().map_err(|e| CliError::failure(e.to_string()))?;
    let mut rows = Vec::new();
    for path in files {
        let start = Instant::now();
        // The unit is read from the scene's extent, as everywhere (issue #37 point 2).
        let scene = load(&path, 0.0)?;
        let unit_scale = scene.units.as_ref().map_or(1.0, |u| u.0);
        let load_ms = start.elapsed().as_secs_f64() * 1e3;
        let emissive_triangles = scene
            .meshes
            .iter()
            .flat_map(|m| &m.primitives)
            .filter(|p| scene.materials.get(p.material).is_some_and(|m| m.emissive.max_element() > 0.0))
            .map(|p| p.indices.len() / 3)
            .sum();
        let row = SceneRow {
            scene: path.display().to_string(),
            triangles: scene.triangle_count(),
            lights: scene.lights.len(),
            default_light: scene.warnings.iter().any(|w| w.starts_with(gi_render::scene::default_light::NO_LIGHTS)),
            emissive_triangles,
            unit_scale,
            load_ms,
            frame_ms: preset_times(&ctx, &scene, &presets, size, frames),
        };
        rows.push(row);
    }
    for (rings, segments) in [(4, 8), (16, 32), (48, 64)] {
        let mut scene = gi_render::scene::cornell::default_scene()
            .map_err(|e| CliError::failure(format!("the default scene: {e}")))?;
        let b = scene.bounds(0.0);
        let radiance = glam::Vec3::splat(20.0);
        let tris = gi_render::scene::emitters::add_glowing_sphere(
            &mut scene,
            b.center(),
            0.08 * b.radius(),
            rings,
            segments,
            radiance,
        );
        let row = SceneRow {
            scene: format!("default box + glowing sphere ({rings}×{segments})"),
            triangles: scene.triangle_count(),
            lights: scene.lights.len(),
            default_light: false,
            emissive_triangles: tris,
            unit_scale: 1.0,
            load_ms: 0.0,
            frame_ms: preset_times(&ctx, &scene, &presets, size, frames),
        };
        rows.push(row);
    }
    Ok(rows)
}

/// A preset's name and its mean frame time (ms) or the error that stopped it.
pub type PresetTime = (String, Result<f64, String>);

/// Every technique preset's settings with `overrides` applied (each refused with its reason).
fn technique_settings(overrides: &[String]) -> Result<Vec<(&'static str, LabSettings)>, CliError> {
    let mut out = Vec::new();
    for (name, text) in super::run::TECHNIQUE_PRESETS {
        let mut settings = gi_render::preset::load_lenient(text, name)
            .map(|l| l.settings)
            .map_err(|e| CliError::failure(format!("preset {name}: {e}")))?;
        for o in overrides {
            settings.apply_override(o).map_err(|e| CliError::input(format!("--set {o}: {e}")))?;
        }
        if let Some(e) = settings.validate().first() {
            return Err(CliError::input(format!("{name} with --set: {e}")));
        }
        out.push((name, settings));
    }
    Ok(out)
}

/// The mean frame time of every technique preset on `scene`.
fn preset_times(
    ctx: &GpuContext,
    scene: &gi_render::scene::Scene,
    presets: &[(&'static str, LabSettings)],
    size: (u32, u32),
    frames: u32,
) -> Vec<PresetTime> {
    presets
        .iter()
        .map(|(name, settings)| (name.to_string(), frame_ms(ctx, scene, settings.clone(), size, frames)))
        .collect()
}

fn frame_ms(
    ctx: &GpuContext,
    scene: &gi_render::scene::Scene,
    settings: LabSettings,
    size: (u32, u32),
    frames: u32,
) -> Result<f64, String> {
    let mut r = super::run::measuring_renderer(ctx, scene, settings, size).map_err(|e| e.to_string())?;
    Ok(super::run::bench_run(&mut r, frames.max(1), "").total_mean_ms)
}

/// The table.
pub fn format(rows: &[SceneRow], size: (u32, u32), frames: u32, overrides: &[String]) -> String {
    let mut s = format!(
        "GI Lab bench suite scenes — {}×{}, mean frame time (ms, sum of the passes) over {frames} frames after 3 warm-up frames",
        size.0, size.1
    );
    if !overrides.is_empty() {
        s += &format!("; every preset with --set {}", overrides.join(" --set "));
    }
    s += "\n\n";
    s += &format!("{:<62} {:>9} {:>7} {:>9} {:>8}", "scene", "triangles", "lights", "emissive", "load ms");
    for (name, _) in super::run::TECHNIQUE_PRESETS {
        s += &format!(" {name:>9}");
    }
    s += "\n";
    for r in rows {
        let lights = if r.default_light { format!("{}*", r.lights) } else { r.lights.to_string() };
        let name = if r.unit_scale != 1.0 { format!("{} (×{})", r.scene, r.unit_scale) } else { r.scene.clone() };
        s += &format!("{name:<62} {:>9} {lights:>7} {:>9} {:>8.1}", r.triangles, r.emissive_triangles, r.load_ms);
        for (_, t) in &r.frame_ms {
            s += &match t {
                Ok(ms) => format!(" {ms:>9.1}"),
                Err(_) => format!(" {:>9}", "error"),
            };
        }
        s += "\n";
        for (name, t) in &r.frame_ms {
            if let Err(e) = t {
                s += &format!("    {name}: {e}\n");
            }
        }
    }
    s += "\n* the lab's default light (the scene has neither punctual lights nor emitters); emissive: triangles whose material emits (lights: emitters.vpls VPLs on them, whatever their number)\n";
    s
}
