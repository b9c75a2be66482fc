//! Explain a pixel (issue #42) for the hierarchical coherence buffer (Nguyen et al. 000
//! §4.2–4.3, Eq. 8–11): the GPU replay's contributions sum to the buffers the frame wrote
//! (`hcb.weight_sum`'s Σ w·E and Σ w, Eq. 11's `hcb.irradiance`, the stage's `hcb.indirect`),
//! each listed sample's Eq. 8 errors and Eq. 10 weight equal the CPU twin's
//! (`cpu::hcb::{coherence_errors, weight}`) from the sample list read back, with the sample cache
//! (§5), the confidence merge after the splat and the mix with Soler's ring gather at the
//! samples.

use gi_lab_tests::paused_renderer;
use gi_render::Renderer;
use gi_render::cpu::hcb::{HcbTexel, coherence_errors, weight};
use gi_render::explain::{Contribution, Explanation, Rejection, luminance};
use gi_render::passes::bins::SplatMethod;
use gi_render::passes::hcb::explain::{E_DISTANCE, E_NORMAL, E_POSE, LEVEL, WEIGHT};
use gi_render::settings::pipeline::{Technique, Temporal};
use glam::Vec3;

/// Every buffer the sums are checked against but one is `Rgba32Float` (`hcb.weight_sum`,
/// `hcb.irradiance`, `hcb.indirect`; `temporal.history` is half floats, [`HISTORY_TOLERANCE`]),
/// and the replay computes each term
/// with the splat's own functions (`hcb/common.wgsl`) and sums them in the splat's order
/// (increasing sample index), so the sums differ only by f32 rounding: the two shader modules'
/// contraction choices and the shares' divisions (Σ f·w·E / Σw against f·(Σ w·E / Σw)). For n
/// non-negative terms that is at most about n·2⁻²⁴ relative; a pixel's quads hold at most a
/// few dozen coherent samples here, so 1e-5 (n up to ~160) bounds it with room.
const SUM_TOLERANCE: f32 = 1e-5;

/// `temporal.history` is stored as half floats (issue #53): a sum checked against it differs by
/// the store's rounding too, up to one unit in the last place, 2⁻¹⁰ relative, where the store
/// truncates (lavapipe) — on top of [`SUM_TOLERANCE`].
const HISTORY_TOLERANCE: f32 = SUM_TOLERANCE + 9.8e-4;

/// Pixels of the default box at 64²: the floor, the back wall, the red wall, the tall block.
const PIXELS: [(u32, u32); 4] = [(32, 56), (32, 20), (6, 30), (24, 36)];

fn field(c: &Contribution, name: &str) -> f32 {
    c.fields.iter().find(|(k, _)| *k == name).map(|(_, v)| *v).unwrap_or_else(|| panic!("{}: no {name}", c.name))
}

/// Renders `frames` frames with `pixel` pinned and explains it.
fn explain(r: &mut Renderer, pixel: (u32, u32), frames: u32) -> Explanation {
    r.set_explain(Some(pixel));
    for _ in 0..frames {
        r.render_frame();
    }
    r.explanation().unwrap_or_else(|e| panic!("pixel {pixel:?}: {e}"))
}

/// Every check of `e` (Σ w·E, Σ w, Eq. 11, the contributions against the pixel's value) holds
/// to f32 rounding, and the pixel is lit by at least one coherent sample.
fn assert_sums(e: &Explanation) {
    for c in std::iter::once(e.total_check()).chain(e.checks.iter().cloned()) {
        let tolerance = if c.buffer.starts_with("temporal.history") { HISTORY_TOLERANCE } else { SUM_TOLERANCE };
        assert!(
            c.relative_error() <= tolerance,
            "pixel {:?}: {} against {} ({})\n{}",
            e.pixel,
            c.what,
            c.buffer,
            c.relative_error(),
            e.to_text(8)
        );
    }
    assert!(e.checks.iter().any(|c| c.buffer == "hcb.weight_sum (a)"), "{}", e.to_text(0));
    assert!(e.contributions.iter().any(|c| c.rejected.is_none()), "no coherent sample:\n{}", e.to_text(0));
    assert!(luminance(e.value) > 0.0, "pixel {:?} has no indirect light:\n{}", e.pixel, e.to_text(8));
}

/// Each listed sample's Eq. 8 errors and Eq. 10 weight equal the CPU twin's from the sample
/// read back (`Renderer::hcb_stats`) and the G-buffer at the pixel; an incoherent one is
/// rejected by Eq. 9 on the CPU too. Returns how many samples were compared.
fn assert_cpu_twin(r: &Renderer, e: &Explanation) -> usize {
    let stats = r.hcb_stats().expect("HCB statistics");
    let t = r.settings().hcb.thresholds(r.scale_radius());
    let probe = r.probe(&[e.pixel]).expect("probe");
    let at = |name: &str| probe[0].iter().find(|v| v.name == name).unwrap_or_else(|| panic!("{name}")).value;
    let (pos, nrm) = (at("gbuffer.position"), at("gbuffer.normal"));
    let b = Vec3::new(pos[0], pos[1], pos[2]);
    let n_b = Vec3::new(nrm[0], nrm[1], nrm[2]).normalize();
    let (mut compared, mut worst) = (0, 0.0f32);
    for c in e.contributions.iter().filter(|c| c.name.starts_with("sample ")) {
        let k: usize = c.name["sample ".len()..].parse().expect("index");
        let s = stats.list[k];
        assert_eq!(field(c, LEVEL), s.level() as f32, "{}", c.name);
        let texel = HcbTexel {
            position: s.position.truncate(),
            distance: s.position.w,
            normal: s.normal.truncate(),
            coherence: s.normal.w,
        };
        let cpu = coherence_errors(&texel, b, n_b, t);
        for (name, want) in [(E_DISTANCE, cpu[0]), (E_NORMAL, cpu[1]), (E_POSE, cpu[2])] {
            let got = field(c, name);
            assert!(
                (got - want).abs() <= 1e-4 * want.abs().max(1e-2),
                "{} at {:?}: {name} {got} against the CPU twin's {want}",
                c.name,
                e.pixel
            );
        }
        match (weight(&texel, b, n_b, t), &c.rejected) {
            (Some(w), None) => {
                let got = field(c, WEIGHT);
                worst = worst.max((got - w).abs() / w);
                assert!((got - w).abs() <= 1e-4 * w, "{} at {:?}: w {got} against the CPU twin's {w}", c.name, e.pixel);
            }
            (None, Some(Rejection::Incoherent)) => assert_eq!(c.value, Vec3::ZERO, "{}", c.name),
            (cpu, gpu) => panic!("{} at {:?}: the CPU twin's weight {cpu:?}, the replay's {gpu:?}", c.name, e.pixel),
        }
        compared += 1;
    }
    eprintln!("pixel {:?}: {compared} samples against the CPU twin, worst w relative difference {worst:.2e}", e.pixel);
    compared
}

/// Both splats: the paper's blended quads and GI Lab's binned sums (the same sums; the replay's
/// quad test is the binned one's, and the quads' rasterization samples the same centres).
#[test]
fn hcb_pixels_sum_to_their_buffers_and_each_weight_equals_the_cpu_twin() {
    for method in [SplatMethod::Blend, SplatMethod::Binned] {
        let mut r = paused_renderer(64, Technique::Nguyen, |s| s.hcb.splat = method);
        let mut compared = 0;
        for p in PIXELS {
            let e = explain(&mut r, p, 1);
            eprintln!("{method:?}: {}", e.to_text(6));
            assert_eq!(e.buffer, "hcb.indirect");
            assert_sums(&e);
            compared += assert_cpu_twin(&r, &e);
            // The shares of the coherent samples are w_s / Σ w: they sum to 1.
            let shares: f32 = e.contributions.iter().map(|c| c.weight).sum();
            assert!((shares - 1.0).abs() < 1e-5, "{method:?}, pixel {p:?}: Σ w_s / Σ w = {shares}");
        }
        assert!(compared >= 8, "{method:?}: only {compared} samples compared");
    }
}

#[test]
fn the_sample_cache_s_pixels_sum_to_their_buffers() {
    let mut r = paused_renderer(64, Technique::NguyenCached, |_| {});
    // A few frames: the samples are kept, and a quarter of them re-gathered each frame (§5.3).
    for _ in 0..3 {
        r.render_frame();
    }
    let mut sources = Vec::new();
    for p in PIXELS {
        let e = explain(&mut r, p, 1);
        eprintln!("{}", e.to_text(6));
        assert_eq!(e.buffer, "hcb.indirect");
        assert_sums(&e);
        assert_cpu_twin(&r, &e);
        sources.extend(e.contributions.iter().map(|c| c.source.clone()));
    }
    assert!(sources.iter().any(|s| s.ends_with(", cached")), "no cached sample listed: {sources:?}");
}

#[test]
fn the_confidence_merge_after_the_splat_sums_to_its_history() {
    let mut r = paused_renderer(64, Technique::Nguyen, |s| s.pipeline.temporal = Temporal::ConfidenceMerge);
    for _ in 0..3 {
        r.render_frame();
    }
    for p in PIXELS {
        let e = explain(&mut r, p, 1);
        eprintln!("{}", e.to_text(3));
        assert_eq!(e.buffer, "temporal.history");
        assert_sums(&e);
        assert!(e.checks.iter().any(|c| c.buffer == "hcb.indirect"), "{}", e.to_text(0));
        let history = e.contributions.iter().find(|c| c.name == "history");
        assert!(history.is_some_and(|h| field(h, "c") > 0.0), "no history share:\n{}", e.to_text(4));
    }
}

#[test]
fn soler_s_gather_at_the_samples_sums_to_its_buffers() {
    let mut r = paused_renderer(64, Technique::SolerAtHcbSamples, |_| {});
    for p in PIXELS {
        let e = explain(&mut r, p, 1);
        assert_eq!(e.buffer, "hcb.indirect");
        assert!(e.technique.contains("Soler"), "{}", e.technique);
        assert_sums(&e);
        assert_cpu_twin(&r, &e);
    }
}

#[test]
fn gautron_s_hemispheres_at_the_samples_sum_to_their_buffers() {
    let mut r = paused_renderer(64, Technique::GautronAtHcbSamples, |_| {});
    for p in PIXELS {
        let e = explain(&mut r, p, 1);
        assert_eq!(e.buffer, "hcb.indirect");
        assert_sums(&e);
        assert_cpu_twin(&r, &e);
    }
}

#[test]
fn the_replay_s_structs_have_the_sizes_of_their_wgsl_twins() {
    let src = gi_render::shaders::resolve("hcb/explain.wgsl").expect("resolves");
    let module = naga::front::wgsl::parse_str(&src).unwrap_or_else(|e| panic!("{}", e.emit_to_string(&src)));
    let size = |name: &str| {
        module
            .types
            .iter()
            .find_map(|(_, t)| match (&t.name, &t.inner) {
                (Some(n), naga::TypeInner::Struct { span, .. }) if n == name => Some(*span as usize),
                _ => None,
            })
            .unwrap_or_else(|| panic!("struct {name} not found"))
    };
    assert_eq!(size("Header"), std::mem::size_of::<gi_render::passes::hcb::explain::GpuHeader>());
    assert_eq!(size("Entry"), std::mem::size_of::<gi_render::passes::hcb::explain::GpuEntry>());
    assert_eq!(size("HcbSample"), std::mem::size_of::<gi_render::passes::hcb::GpuHcbSample>());
}
