//! `gi-lab bench --suite gautron`, the text's comparison (003 "Results: Comparison with
//! Radiance": the GPU cache 29.7× and 47.1× faster than Radiance, a CPU irradiance cache of
//! ray-traced hemispheres made one after the other and looked up in an octree): GI Lab's CPU
//! cache ([`gi_render::cpu::irradiance_cache`]) against the GPU cache, both with R_k = H (no
//! clamps, no neighbour clamping, as the text's records) at the same accuracies a, Ward's
//! weight, its clamp and "in front" test and both gradients as the preset has them.
//!
//! Per a: the CPU cache from empty over the image in scanline order (records, rays, the
//! hemispheres' time, the lookups' time) and the GPU cache cold until covered (the suite's
//! cold-run machinery: frames until one makes no record); FLIP of each against the suite's
//! path-traced truth. The CPU image is the GPU's frame with its indirect light swapped for
//! the CPU cache's (final.hdr − gautron.indirect + the CPU's E·c·DI/π): both share the direct
//! light, so the FLIPs differ by the caches alone. Each GPU row is paired with the CPU row of
//! nearest FLIP (the CPU's scanline image, the algorithm that was timed) for the ratio "at
//! equal FLIP". Then a walk (003 "Results": "the irradiance cache is reused across frames.
//! Hence the first frame has been computed in approximately 20s, while the other frames took
//! approximately 1s"): the camera orbits in steps from a cold cache, both caches keep their
//! records and make the ones each new view needs.

use gi_render::cpu::gautron::Interpolation;
use gi_render::cpu::irradiance_cache::{CacheSettings, IrradianceCache};
use gi_render::cpu::pathtrace::PathTracer;
use gi_render::{ImageF32, LabSettings, Renderer};

use super::gautron_cold::{cold_to_covered, flip_of};
use crate::error::CliError;

/// The accuracies of the comparison.
pub const ACCURACIES: [f32; 4] = [0.2, 0.3, 0.4, 0.6];
/// The CPU records' hemispheres: M×N rays (θ × φ cells).
pub const HEMISPHERE: (u32, u32) = (16, 32);
/// The walk: this accuracy, this many steps after the cold one, each turning the camera by
/// this yaw about its orbit point (degrees).
pub const WALK_ACCURACY: f32 = 0.4;
pub const WALK_STEPS: u32 = 10;
pub const WALK_YAW_DEG: f32 = 3.0;

/// The CPU cache at one accuracy.
#[derive(Debug, Clone, serde::Serialize)]
pub struct CpuCacheRow {
    pub accuracy: f32,
    pub records: u32,
    pub rays: u64,
    /// The camera rays (not the cache's cost: the GPU's G-buffer; ms).
    pub primary_ms: f64,
    /// The records' hemispheres (ms).
    pub create_ms: f64,
    /// The lookups and blends at every pixel (ms).
    pub interpolate_ms: f64,
    /// create + interpolate.
    pub total_ms: f64,
    /// The scanline image (each pixel from the records made before it, "Algorithm").
    pub flip_vs_truth: f64,
    /// Every pixel again from the final records (a second pass; not in the times).
    pub flip_second_pass_vs_truth: f64,
}

/// The GPU cache at one accuracy, cold until covered.
#[derive(Debug, Clone, serde::Serialize)]
pub struct GpuCacheRow {
    pub accuracy: f32,
    pub records: u32,
    pub frames_to_cover: u32,
    /// The Gautron passes of the frames that made records (ms).
    pub cold_ms: f64,
    /// The next frame, which shows the covered image (ms).
    pub warm_ms: f64,
    pub flip_vs_truth: f64,
}

/// A GPU row and the CPU row of nearest FLIP.
#[derive(Debug, Clone, serde::Serialize)]
pub struct EqualFlip {
    pub gpu_accuracy: f32,
    pub gpu_flip: f64,
    /// cold + warm: the GPU's time to the covered image.
    pub gpu_ms: f64,
    pub cpu_accuracy: f32,
    pub cpu_flip: f64,
    pub cpu_ms: f64,
    /// cpu_ms / gpu_ms.
    pub ratio: f64,
}

/// One camera of the walk.
#[derive(Debug, Clone, serde::Serialize)]
pub struct WalkStep {
    pub step: u32,
    pub cpu_made: u32,
    /// create + interpolate (ms).
    pub cpu_ms: f64,
    pub gpu_made: u32,
    /// Frames until one makes no record, that one included.
    pub gpu_frames: u32,
    /// The Gautron passes of those frames (ms).
    pub gpu_ms: f64,
}

#[derive(Debug, Clone, serde::Serialize)]
pub struct CpuComparison {
    pub hemisphere: String,
    pub gradients: String,
    pub cpu: Vec<CpuCacheRow>,
    pub gpu: Vec<GpuCacheRow>,
    pub equal_flip: Vec<EqualFlip>,
    pub walk_accuracy: f32,
    pub walk_yaw_deg: f32,
    pub walk: Vec<WalkStep>,
}

/// `base` with the text's records (R_k = H, no neighbour clamping) at accuracy `a`, both
/// gradients (the CPU cache computes both).
fn gpu_settings(base: &LabSettings, a: f32) -> LabSettings {
    let mut s = base.clone();
    let g = &mut s.gautron;
    (g.accuracy, g.r_clamps, g.neighbour_clamping) = (a, false, false);
    (g.rotational_gradient, g.translational_gradient) = (true, true);
    s
}

fn ms(d: std::time::Duration) -> f64 {
    d.as_secs_f64() * 1e3
}

/// `a` + `b` per pixel, alpha 1.
fn add(a: &ImageF32, b: &ImageF32) -> ImageF32 {
    let data = a.data.iter().zip(&b.data).map(|(x, y)| [x[0] + y[0], x[1] + y[1], x[2] + y[2], 1.0]).collect();
    ImageF32 { width: a.width, height: a.height, data }
}

/// The Gautron passes' time of a frame.
fn gautron_ms(t: &[gi_render::timing::PassTiming]) -> f64 {
    t.iter().filter(|p| p.name.starts_with("gautron.")).map(|p| p.ms).sum()
}

/// The comparison on `r` (its camera and size), `base` the suite's Gautron settings, `truth`
/// the suite's path-traced image of one bounce (at animation time 0: the clock is paused
/// there meanwhile). Leaves `r`'s settings to the caller, its camera and clock as they were.
pub fn cpu_comparison(r: &mut Renderer, base: &LabSettings, truth: &ImageF32) -> Result<CpuComparison, CliError> {
    let clock = r.clock;
    (r.clock.anim_frame, r.clock.playing) = (0, false);
    let camera = r.camera;
    let out = compare(r, base, truth);
    (r.clock, r.camera) = (clock, camera);
    r.reset_history();
    out
}

fn compare(r: &mut Renderer, base: &LabSettings, truth: &ImageF32) -> Result<CpuComparison, CliError> {
    let fail = |e: String| CliError::failure(e);
    let (width, height) = r.size();
    let bounds = r.scene().bounds(0.0);
    let pt = PathTracer::new(r.scene(), 0.0);
    let cache_for = |s: &LabSettings| {
        let interpolation = Interpolation::of(&s.gautron);
        let settings = CacheSettings { interpolation, theta: HEMISPHERE.0, phi: HEMISPHERE.1, seed: 1 };
        IrradianceCache::new(bounds.min, bounds.max, settings)
    };
    let (mut cpu, mut gpu) = (Vec::new(), Vec::new());
    for a in ACCURACIES {
        let s = gpu_settings(base, a);
        r.set_settings(s.clone()).map_err(|e| fail(e.to_string()))?;
        let (row, image) = cold_to_covered(r, a)?;
        let indirect = r.readback("gautron.indirect").map_err(|e| fail(e.to_string()))?;
        // The frame without its indirect light: emission, direct light, sky.
        let rest = ImageF32 {
            width,
            height,
            data: image
                .data
                .iter()
                .zip(&indirect.data)
                .map(|(f, i)| [(f[0] - i[0]).max(0.0), (f[1] - i[1]).max(0.0), (f[2] - i[2]).max(0.0), 1.0])
                .collect(),
        };
        gpu.push(GpuCacheRow {
            accuracy: a,
            records: row.records,
            frames_to_cover: row.frames_to_cover,
            cold_ms: row.cold_ms,
            warm_ms: row.warm_ms,
            flip_vs_truth: flip_of(&image, truth)?,
        });
        let mut cache = cache_for(&s);
        let f = cache.frame(&pt, r.view_proj(), width, height);
        let (second, _, _) = cache.interpolate(&f.surfaces, width, height);
        cpu.push(CpuCacheRow {
            accuracy: a,
            records: f.made,
            rays: f.rays,
            primary_ms: ms(f.primary),
            create_ms: ms(f.create),
            interpolate_ms: ms(f.interpolate),
            total_ms: ms(f.create + f.interpolate),
            flip_vs_truth: flip_of(&add(&rest, &f.indirect), truth)?,
            flip_second_pass_vs_truth: flip_of(&add(&rest, &second), truth)?,
        });
    }
    let equal_flip = gpu
        .iter()
        .filter_map(|g| {
            let c = cpu.iter().min_by(|x, y| {
                (x.flip_vs_truth - g.flip_vs_truth).abs().total_cmp(&(y.flip_vs_truth - g.flip_vs_truth).abs())
            })?;
            let gpu_ms = g.cold_ms + g.warm_ms;
            Some(EqualFlip {
                gpu_accuracy: g.accuracy,
                gpu_flip: g.flip_vs_truth,
                gpu_ms,
                cpu_accuracy: c.accuracy,
                cpu_flip: c.flip_vs_truth,
                cpu_ms: c.total_ms,
                ratio: c.total_ms / gpu_ms.max(1e-9),
            })
        })
        .collect();

    // The walk: both caches from empty, kept across the steps.
    let s = gpu_settings(base, WALK_ACCURACY);
    r.set_settings(s.clone()).map_err(|e| fail(e.to_string()))?;
    r.reset_history();
    let mut cache = cache_for(&s);
    let mut walk = Vec::new();
    for step in 0..=WALK_STEPS {
        if step > 0 {
            r.camera.orbit(WALK_YAW_DEG.to_radians(), 0.0);
        }
        let (mut gpu_made, mut gpu_frames, mut gpu_ms) = (0, 0, 0.0);
        loop {
            let t = r.render_frame();
            let st = r.gautron().and_then(|g| g.read_state(&r.ctx)).ok_or_else(|| fail("no Gautron stage".into()))?;
            gpu_frames += 1;
            gpu_ms += gautron_ms(&t);
            gpu_made += st.made;
            if st.made == 0 {
                break;
            }
            if gpu_frames >= 256 {
                return Err(fail(format!("walk step {step}: the cache still grew after 256 frames")));
            }
        }
        let f = cache.frame(&pt, r.view_proj(), width, height);
        walk.push(WalkStep {
            step,
            cpu_made: f.made,
            cpu_ms: ms(f.create + f.interpolate),
            gpu_made,
            gpu_frames,
            gpu_ms,
        });
    }
    Ok(CpuComparison {
        hemisphere: format!("{}×{} rays (θ × φ), stratified, cosine-weighted", HEMISPHERE.0, HEMISPHERE.1),
        gradients: "both (CPU: Ward & Heckbert 1992 over the θ × φ cells; GPU: the hemisphere's texels)".into(),
        cpu,
        gpu,
        equal_flip,
        walk_accuracy: WALK_ACCURACY,
        walk_yaw_deg: WALK_YAW_DEG,
        walk,
    })
}

/// The comparison as text.
pub fn format(c: &CpuComparison) -> String {
    let mut s =
        String::from("\nThe text's comparison (003 \"Results\"): a CPU irradiance cache against the GPU cache\n");
    s += &format!(
        "R_k = H (no clamps, no neighbour clamping) on both; CPU: {}, one core, scanline order, octree lookups; gradients: {}\n",
        c.hemisphere, c.gradients
    );
    s += &format!(
        "{:<8} {:>8} {:>9} {:>10} {:>10} {:>10} {:>10} {:>10} | {:>8} {:>7} {:>10} {:>9} {:>10}\n",
        "",
        "CPU rec",
        "rays",
        "create ms",
        "interp ms",
        "total ms",
        "FLIP",
        "FLIP 2nd",
        "GPU rec",
        "frames",
        "cold ms*",
        "warm ms*",
        "FLIP"
    );
    for (cr, g) in c.cpu.iter().zip(&c.gpu) {
        s += &format!(
            "{:<8} {:>8} {:>9} {:>10.1} {:>10.1} {:>10.1} {:>10.4} {:>10.4} | {:>8} {:>7} {:>10.2} {:>9.2} {:>10.4}\n",
            format!("a = {}", cr.accuracy),
            cr.records,
            cr.rays,
            cr.create_ms,
            cr.interpolate_ms,
            cr.total_ms,
            cr.flip_vs_truth,
            cr.flip_second_pass_vs_truth,
            g.records,
            g.frames_to_cover,
            g.cold_ms,
            g.warm_ms,
            g.flip_vs_truth
        );
    }
    s += "* the Gautron passes (create, hemispheres, splat, resolve); FLIP against the truth, the CPU's with the GPU frame's direct light; \"FLIP 2nd\": every pixel again from the final CPU records (untimed)\n";
    s += "at equal FLIP (each GPU row with the CPU row of nearest FLIP; GPU time = cold + warm):\n";
    for e in &c.equal_flip {
        s += &format!(
            "  GPU a = {} (FLIP {:.4}, {:.1} ms) ~ CPU a = {} (FLIP {:.4}, {:.1} ms): CPU/GPU = {:.1}×\n",
            e.gpu_accuracy, e.gpu_flip, e.gpu_ms, e.cpu_accuracy, e.cpu_flip, e.cpu_ms, e.ratio
        );
    }
    s += &format!(
        "walk (a = {}, the camera orbiting {}° a step, both caches kept; text: first frame ≈ 20 s, then ≈ 1 s):\n",
        c.walk_accuracy, c.walk_yaw_deg
    );
    s += &format!(
        "  {:>4} {:>9} {:>9} {:>9} {:>7} {:>9} {:>8}\n",
        "step", "CPU made", "CPU ms", "GPU made", "frames", "GPU ms", "CPU/GPU"
    );
    for w in &c.walk {
        s += &format!(
            "  {:>4} {:>9} {:>9.1} {:>9} {:>7} {:>9.2} {:>7.1}×\n",
            w.step,
            w.cpu_made,
            w.cpu_ms,
            w.gpu_made,
            w.gpu_frames,
            w.gpu_ms,
            w.cpu_ms / w.gpu_ms.max(1e-9)
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use gi_render::GpuContext;
    use gi_render::cpu::pathtrace::{PtSettings, Senders};
    use gi_render::settings::pipeline::{Technique, Temporal};

    /// The section runs at 32×32 and reports finite numbers with records on both sides (no
    /// timing is asserted: speed is the bench's to measure).
    #[test]
    fn the_cpu_cache_section_runs_at_a_tiny_size() {
        let scene = gi_render::scene::cornell::default_scene().expect("the default box");
        let ctx = GpuContext::headless().expect("a GPU adapter (lavapipe)");
        let mut s = LabSettings::default();
        Technique::Gautron.apply(&mut s);
        s.pipeline.temporal = Temporal::RecordCache;
        let mut r = Renderer::new(ctx, scene, s.clone(), 32, 32).expect("renderer");
        let pt = PathTracer::new(r.scene(), 0.0);
        let truth = pt
            .render(
                r.view_proj(),
                r.camera.position,
                32,
                32,
                PtSettings { bounces: 1, spp: 16, seed: 1, senders: Senders::All },
            )
            .full;
        let camera = r.camera;
        let c = cpu_comparison(&mut r, &s, &truth).expect("the section runs");
        assert_eq!(r.camera, camera, "the camera is put back");
        assert_eq!((c.cpu.len(), c.gpu.len(), c.equal_flip.len()), (4, 4, 4));
        for (cr, g) in c.cpu.iter().zip(&c.gpu) {
            assert!(cr.records > 0 && g.records > 0, "{cr:?} {g:?}");
            assert_eq!(cr.rays, u64::from(cr.records) * 512);
            for x in [cr.create_ms, cr.interpolate_ms, cr.total_ms, g.cold_ms, g.warm_ms] {
                assert!(x.is_finite() && x >= 0.0, "{cr:?} {g:?}");
            }
            for f in [cr.flip_vs_truth, cr.flip_second_pass_vs_truth, g.flip_vs_truth] {
                assert!(f.is_finite() && f > 0.0 && f < 1.0, "{cr:?} {g:?}");
            }
        }
        assert!(c.equal_flip.iter().all(|e| e.ratio.is_finite()));
        assert_eq!(c.walk.len(), WALK_STEPS as usize + 1);
        assert!(c.walk[0].cpu_made > 0 && c.walk[0].gpu_made > 0, "{:?}", c.walk[0]);
        assert!(c.walk.iter().all(|w| w.cpu_ms.is_finite() && w.gpu_ms.is_finite() && w.gpu_frames >= 1));
        // Both caches keep their records: a step makes fewer than the cold start.
        let later = |f: &dyn Fn(&WalkStep) -> u32| c.walk[1..].iter().map(f).max().unwrap_or(0);
        assert!(later(&|w| w.cpu_made) < c.walk[0].cpu_made, "{:?}", c.walk);
        assert!(later(&|w| w.gpu_made) < c.walk[0].gpu_made, "{:?}", c.walk);
        assert!(format(&c).contains("CPU irradiance cache against the GPU cache"));
    }
}
