//! `gi-lab bench --suite rays` (issue #56 points 1 and 2): for the default scene and every
//! scene below `--scenes-dir`, the GPU ray caster against the CPU's traversal (the path
//! tracer's BVH, on every core) on the same rays, and the GPU path tracer against the CPU's
//! at `--size` and `--spp`: build times, rays and paths per second, and their ratio. Wall
//! clock around each whole batch (upload, dispatch, read back on the GPU side): absolute
//! figures mean something on a real GPU only; on lavapipe the ratio is the figure.

use std::time::Instant;

use gi_render::GpuContext;
use gi_render::cpu::pathtrace::{PathTracer, PtSettings};
use gi_render::passes::rays::pathtrace::GpuPathTracer;
use gi_render::passes::rays::{CastRay, RayCastPass, RayScene};
use gi_render::scene::Scene;
use gi_render::scene::two_level::Query;
use rayon::prelude::*;

use crate::error::CliError;

/// One scene's row.
#[derive(Debug, Clone, serde::Serialize)]
pub struct RaysRow {
    pub scene: String,
    pub triangles: usize,
    /// The two-level hierarchy built and uploaded (ms), the CPU's BVH built (ms).
    pub gpu_build_ms: f64,
    pub cpu_build_ms: f64,
    /// Closest-hit rays per second (millions): the camera's rays through every pixel of
    /// `--size`, then a cosine-distributed bounce from each hit.
    pub rays: usize,
    pub gpu_mrays_s: f64,
    pub cpu_mrays_s: f64,
    /// Paths per second (millions) of the truth (one bounce) at `--size` × `--spp`.
    pub gpu_mpaths_s: f64,
    pub cpu_mpaths_s: f64,
}

/// The camera's rays through the pixels of a `w`×`h` image, then from each hit a cosine
/// bounce (found by the CPU): the rays a path tracer casts.
fn rays(scene: &Scene, pt: &PathTracer, (w, h): (u32, u32)) -> Vec<CastRay> {
    let camera = gi_render::renderer::default_camera(scene, scene.bounds(0.0), w as f32 / h as f32);
    let inv = camera.view_proj(w as f32 / h as f32).inverse();
    let mut out = Vec::with_capacity((2 * w * h) as usize);
    let mut bounces = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let (o, d) = gi_render::scene::raycast::primary_ray(inv, x, y, w, h);
            out.push(CastRay::new(o, d, 0.0, f32::INFINITY));
            if let Some(hit) = pt.closest_hit(o, d, 0.0, f32::INFINITY) {
                let k = gi_render::maths::pcg_hash(y * w + x);
                let (u1, u2) = ((k & 0xffff) as f32 / 65536.0, (k >> 16) as f32 / 65536.0);
                let t = hit.n.any_orthonormal_vector();
                let b = hit.n.cross(t);
                let (r, phi) = (u1.sqrt(), std::f32::consts::TAU * u2);
                let dir = (t * (r * phi.cos()) + b * (r * phi.sin()) + hit.n * (1.0 - u1).sqrt()).normalize();
                bounces.push(CastRay::new(hit.p + hit.n * pt.ray_offset(), dir, 0.0, f32::INFINITY));
            }
        }
    }
    out.extend(bounces);
    out
}

fn row(ctx: &GpuContext, name: &str, scene: &Scene, size: (u32, u32), spp: u32) -> Result<RaysRow, CliError> {
    let triangles = scene.meshes.iter().flat_map(|m| &m.primitives).map(|p| p.indices.len() / 3).sum();
    let t = Instant::now();
    let pt = PathTracer::new(scene, 0.0);
    let cpu_build_ms = t.elapsed().as_secs_f64() * 1e3;
    let t = Instant::now();
    let rs = RayScene::new(ctx, scene, &scene.evaluate(0.0)).map_err(CliError::input)?;
    ctx.wait().map_err(CliError::failure)?;
    let gpu_build_ms = t.elapsed().as_secs_f64() * 1e3;
    let batch = rays(scene, &pt, size);
    let pass = RayCastPass::new(ctx, &rs);
    // Once to compile and warm, then timed.
    pass.cast(ctx, &rs, &batch[..batch.len().min(64)], Query::Closest).map_err(CliError::failure)?;
    let t = Instant::now();
    let gpu_hits = pass.cast(ctx, &rs, &batch, Query::Closest).map_err(CliError::failure)?;
    let gpu_s = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let cpu_hits: usize = batch
        .par_iter()
        .filter(|r| {
            let (o, d) = (r.origin.truncate(), r.dir.truncate());
            pt.closest_hit(o, d, 0.0, f32::INFINITY).is_some()
        })
        .count();
    let cpu_s = t.elapsed().as_secs_f64();
    let gpu_count = gpu_hits.iter().filter(|h| h.hit()).count();
    if gpu_count.abs_diff(cpu_hits) * 100 > batch.len() {
        return Err(CliError::failure(format!(
            "{name}: the GPU caster hit {gpu_count} of {} rays, the CPU {cpu_hits}",
            batch.len()
        )));
    }
    let camera = gi_render::renderer::default_camera(scene, scene.bounds(0.0), size.0 as f32 / size.1 as f32);
    let vp = camera.view_proj(size.0 as f32 / size.1 as f32);
    let settings = PtSettings { bounces: 1, spp, seed: 1, ..Default::default() };
    let mut gpt = GpuPathTracer::new(ctx, scene, 0.0).map_err(CliError::input)?;
    let warm = PtSettings { spp: 1, ..settings };
    gpt.render(ctx, vp, camera.position, (8, 8), warm).map_err(CliError::failure)?;
    let t = Instant::now();
    gpt.render(ctx, vp, camera.position, size, settings).map_err(CliError::failure)?;
    let gpu_pt_s = t.elapsed().as_secs_f64();
    let t = Instant::now();
    pt.render(vp, camera.position, size.0, size.1, settings);
    let cpu_pt_s = t.elapsed().as_secs_f64();
    let paths = size.0 as f64 * size.1 as f64 * spp as f64;
    Ok(RaysRow {
        scene: name.into(),
        triangles,
        gpu_build_ms,
        cpu_build_ms,
        rays: batch.len(),
        gpu_mrays_s: batch.len() as f64 / gpu_s / 1e6,
        cpu_mrays_s: batch.len() as f64 / cpu_s / 1e6,
        gpu_mpaths_s: paths / gpu_pt_s / 1e6,
        cpu_mpaths_s: paths / cpu_pt_s / 1e6,
    })
}

/// Runs the suite on the default scene and every scene below `scenes_dir`.
pub fn rays_suite(scenes_dir: &std::path::Path, size: (u32, u32), spp: u32) -> Result<Vec<RaysRow>, CliError> {
    if spp == 0 || size.0 == 0 || size.1 == 0 {
        return Err(CliError::input("--spp and --size must be at least 1"));
    }
    let ctx = GpuContext::headless().map_err(|e| CliError::failure(e.to_string()))?;
    let default = gi_render::scene::cornell::default_scene().map_err(|e| CliError::failure(e.to_string()))?;
    let mut rows = vec![row(&ctx, "default Cornell box", &default, size, spp)?];
    for path in super::scenes::scene_files(scenes_dir) {
        let scene = super::scenes::load(&path, 0.0)?;
        let name = path.strip_prefix(scenes_dir).unwrap_or(&path).display().to_string();
        rows.push(row(&ctx, &name, &scene, size, spp)?);
    }
    Ok(rows)
}

/// The rows as a table, with the adapter, size and spp.
pub fn format(rows: &[RaysRow], adapter: &str, size: (u32, u32), spp: u32) -> String {
    let mut o = format!(
        "GI Lab bench suite rays — {adapter}; rays: the camera's at {}x{} and one bounce from each hit; \
         paths: the one-bounce truth at {}x{}, {spp} spp; wall clock per batch\n\n",
        size.0, size.1, size.0, size.1
    );
    o += "| scene | triangles | build GPU / CPU ms | rays | GPU Mrays/s | CPU Mrays/s | GPU ÷ CPU | GPU Mpaths/s | CPU Mpaths/s | GPU ÷ CPU |\n";
    o += "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
    for r in rows {
        o += &format!(
            "| {} | {} | {:.0} / {:.0} | {} | {:.3} | {:.3} | {:.2} | {:.4} | {:.4} | {:.2} |\n",
            r.scene,
            r.triangles,
            r.gpu_build_ms,
            r.cpu_build_ms,
            r.rays,
            r.gpu_mrays_s,
            r.cpu_mrays_s,
            r.gpu_mrays_s / r.cpu_mrays_s.max(1e-12),
            r.gpu_mpaths_s,
            r.cpu_mpaths_s,
            r.gpu_mpaths_s / r.cpu_mpaths_s.max(1e-12)
        );
    }
    o
}
