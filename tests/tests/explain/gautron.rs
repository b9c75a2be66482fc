//! Explain a pixel (issue #42) for Gautron et al.'s irradiance cache splatting (003, "From
//! Octree to Splatting"; Gautron et al. 2005, "Radiance cache splatting"), with the records lit
//! by their hemispheres (`presets/gautron-ic-splatting.ron`) and by VPLs (GI Lab's mix,
//! `presets/gautron-vpl-records.ron`): the GPU replay's contributions sum to `gautron.indirect`,
//! its Σ w·E and Σ w to `gautron.accum`, each record the splat adds has the CPU twin's Ward
//! weight (`cpu::gautron::weight`) and the twin's accumulation over the whole cache adds no
//! record the replay left out.

use gi_lab_tests::{default_scene, gpu, read, v3};
use gi_render::cpu::gautron::{self, Interpolation};
use gi_render::explain::{Contribution, Explanation, Rejection};
use gi_render::passes::gautron::{GpuRecord, SplatMethod};
use gi_render::{LabSettings, Renderer};
use glam::Vec3;

/// f32's unit roundoff.
const U: f32 = 1.0 / 16_777_216.0;

/// The tolerance of the checks of a pixel whose splat adds `n` records. Every buffer involved
/// (`gautron.accum`, `gautron.indirect`) is `Rgba32Float` and the replay evaluates the splat's
/// own functions (`gautron/common.wgsl`) on the same inputs and sums in the splat's order
/// (increasing index), so what differs is rounding only: the GPU's and the CPU's sums of n
/// positive terms, (n − 1)·u each; the terms themselves, re-evaluated by separately compiled
/// shaders (the splat's compute or fragment stage, the replay's compute stage) that may contract
/// other products into FMAs through ward_weight's and extrapolate's operations, allowed 24·u;
/// and the resolve's c·DI·(RGB/A)/π against c·DI/π·(w·E)/Σ w, four roundings. Measured on
/// lavapipe: 0 to 1e-7.
fn sum_tolerance(n: usize) -> f32 {
    (2.0 * n as f32 + 28.0) * U
}

/// The CPU twin's weight against the GPU's, relative (the brief's 1e-4: the G-buffer's inputs
/// are the same texels, the formula's few f32 operations differ by ulps).
const WEIGHT_TOLERANCE: f32 = 1e-4;

fn field(c: &Contribution, name: &str) -> f32 {
    c.fields.iter().find(|(k, _)| *k == name).map(|(_, v)| *v).unwrap_or_else(|| panic!("{}: no {name}", c.name))
}

/// A paused renderer of a shipped preset on the default scene at `size`², its settings edited
/// by `edit`.
fn preset_renderer(text: &str, name: &str, size: u32, edit: impl FnOnce(&mut LabSettings)) -> Renderer {
    let mut settings = gi_render::preset::load_lenient(text, name).expect("the preset loads").settings;
    edit(&mut settings);
    let mut r = Renderer::new(gpu(), default_scene(), settings, size, size).expect("renderer");
    r.clock.playing = false;
    r
}

/// Renders with `pixel` pinned until a frame makes no record and computes none again (then the
/// records the replay reads are those the frame splatted), at most `max` frames, and explains
/// that frame.
fn explain_warm(r: &mut Renderer, pixel: (u32, u32), max: u32) -> Explanation {
    r.set_explain(Some(pixel));
    for _ in 0..max {
        r.render_frame();
        let st = r.gautron().expect("Gautron's stage").read_state(&r.ctx).expect("the cache's counters");
        if st.made == 0 && st.refreshed == 0 {
            return r.explanation().unwrap_or_else(|e| panic!("pixel {pixel:?}: {e}"));
        }
    }
    panic!("pixel {pixel:?}: the cache was still changing after {max} frames");
}

/// The index of the record a contribution names ("record k").
fn record_index(c: &Contribution) -> usize {
    c.name.strip_prefix("record ").and_then(|k| k.parse().ok()).unwrap_or_else(|| panic!("{}", c.name))
}

/// Every check of `e` holds, its contributions sum to the resolve's output, each added record
/// has the CPU twin's Ward weight, and the twin's accumulation over the whole cache gives the
/// same Σ w and Σ w·E (no record the splat adds is missing). Returns the records added.
fn assert_explained(r: &Renderer, e: &Explanation) -> usize {
    let text = e.to_text(0);
    let added: Vec<&Contribution> = e.contributions.iter().filter(|c| c.rejected.is_none()).collect();
    assert!(!added.is_empty(), "pixel {:?}: no record covers it\n{text}", e.pixel);
    let tol = sum_tolerance(added.len());
    let total = e.total_check();
    assert!(
        total.relative_error() <= tol,
        "pixel {:?}: Σ contributions {} > {tol}\n{text}",
        e.pixel,
        total.relative_error()
    );
    assert_eq!(e.checks.len(), 3, "{text}");
    for c in &e.checks {
        assert!(c.relative_error() <= tol, "pixel {:?}: {}: {} > {tol}\n{text}", e.pixel, c.what, c.relative_error());
    }
    let shares: f32 = added.iter().map(|c| c.weight).sum();
    assert!((shares - 1.0).abs() <= tol, "pixel {:?}: the shares sum to {shares}\n{text}", e.pixel);

    let g = r.gautron().expect("Gautron's stage");
    let st = g.read_state(&r.ctx).expect("the cache's counters");
    let records: Vec<GpuRecord> = g.read_records(&r.ctx, st.count).expect("the records");
    let (position, normal) = (read(r, "gbuffer.position"), read(r, "gbuffer.normal"));
    let (x, y) = e.pixel;
    let (p, n) = (v3(position.at(x, y)), v3(normal.at(x, y)).normalize());
    let s = &r.settings().gautron;
    let interp = Interpolation::of(s);
    let mut sum_w = 0.0;
    for c in &added {
        let rec = gi_lab_tests::cpu_record(&records[record_index(c)]);
        let cpu = gautron::weight(&rec, p, n, s.weight_clamp, interp.in_front);
        let gpu = field(c, "w clamped");
        assert!(
            (gpu - cpu).abs() <= WEIGHT_TOLERANCE * cpu,
            "pixel {:?}, {}: Ward's weight {gpu} against the CPU twin's {cpu}\n{text}",
            e.pixel,
            c.name
        );
        let unclamped = gautron::weight(&rec, p, n, f32::INFINITY, interp.in_front);
        let w = field(c, "w");
        // both ∞ where the record lies at the pixel's point with its normal (1/0)
        let same = w == unclamped || (w - unclamped).abs() <= WEIGHT_TOLERANCE * unclamped;
        assert!(same, "pixel {:?}, {}: w before the clamp {w} against {unclamped}\n{text}", e.pixel, c.name);
        assert!(c.position.is_some_and(|q| q == rec.p), "{}", c.name);
        sum_w += cpu;
    }
    let cpu_records: Vec<gautron::Record> = records.iter().map(gi_lab_tests::cpu_record).collect();
    let (cpu_sum, cpu_w) = gautron::accumulate(&cpu_records, p, n, &interp);
    assert!(
        (cpu_w - sum_w).abs() <= 1e-3 * cpu_w,
        "pixel {:?}: the twin's Σ w {cpu_w}, the replay's {sum_w}\n{text}",
        e.pixel
    );
    let accum = e.checks[0].sum;
    let near = (accum - cpu_sum).abs().max_element() <= 2e-3 * cpu_sum.max_element();
    assert!(near, "pixel {:?}: the twin's Σ w·E {cpu_sum}, the replay's {accum}\n{text}", e.pixel);
    added.len()
}

/// A floor pixel in the middle of the image's lower part.
fn floor_pixel(r: &Renderer, size: u32) -> (u32, u32) {
    let normal = read(r, "gbuffer.normal");
    let floor = (size / 2 + size / 8, size - size / 12);
    let n = v3(normal.at(floor.0, floor.1));
    assert!(n.y > 0.9, "{floor:?} is not on the floor: {n}");
    floor
}

/// A back-wall pixel next to the left wall on the upper rows (a concave corner).
fn corner_pixel(r: &Renderer, size: u32) -> (u32, u32) {
    let normal = read(r, "gbuffer.normal");
    let n = |x: u32, y: u32| v3(normal.at(x, y));
    let y = size / 5;
    let x = (1..size / 2)
        .find(|&x| n(x - 1, y).x > 0.9 && n(x, y).z.abs() > 0.9)
        .unwrap_or_else(|| panic!("no left-wall / back-wall corner on row {y}"));
    (x, y)
}

/// Pixels of the sphere (its normals meet the records' at angles: Ward's normal term is not 0):
/// the lower left quarter's pixels whose normals lie away from every axis, every third.
fn sphere_pixels(r: &Renderer, size: u32) -> Vec<(u32, u32)> {
    let normal = read(r, "gbuffer.normal");
    let oblique = |x: u32, y: u32| normal.at(x, y)[3] > 0.5 && 1.0 - v3(normal.at(x, y)).abs().max_element() > 0.2;
    let pixels: Vec<(u32, u32)> =
        (size / 2..size).flat_map(|y| (0..size / 2).map(move |x| (x, y))).filter(|&(x, y)| oblique(x, y)).collect();
    assert!(pixels.len() > 8, "no sphere in the lower left quarter");
    pixels.into_iter().step_by(3).take(8).collect()
}

#[test]
fn hemisphere_lit_records_explain_the_floor_and_a_wall_corner() {
    let size = 96;
    let mut r = preset_renderer(
        include_str!("../../../presets/gautron-ic-splatting.ron"),
        "gautron-ic-splatting",
        size,
        |_| {},
    );
    assert!(r.explain_unsupported().is_none(), "{:?}", r.explain_unsupported());
    r.set_explain(Some((0, 0)));
    r.render_frame();
    let (floor, corner) = (floor_pixel(&r, size), corner_pixel(&r, size));

    let e = explain_warm(&mut r, floor, 12);
    assert!(e.technique.contains("hemispheres"), "{}", e.technique);
    assert!(e.value.max_element() > 0.0, "the floor is lit:\n{}", e.to_text(0));
    assert_explained(&r, &e);

    let e = explain_warm(&mut r, corner, 12);
    let text = e.to_text(0);
    assert_explained(&r, &e);
    // The left wall's records near the corner reach the pixel's bound, and the splat rejects
    // them (Ward's "in front" test, or a weight below 1/a); none whose normal term alone is
    // at least a passes: w ≤ 1/√(1 − n·n_k) ≤ 1/a.
    let a = r.settings().gautron.accuracy;
    let other_wall: Vec<&Contribution> =
        e.contributions.iter().filter(|c| field(c, "√(1−n·n_k)") > 0.9 && field(c, "‖P−P_k‖/R_k") < a).collect();
    assert!(!other_wall.is_empty(), "pixel {corner:?}: no record of the left wall is listed\n{text}");
    for c in &other_wall {
        let why = c.rejected.as_ref();
        assert!(
            matches!(why, Some(Rejection::InFront | Rejection::WeightBelowCutoff)),
            "pixel {corner:?}: {} of the left wall: {why:?}\n{text}",
            c.name
        );
    }
    for c in e.contributions.iter().filter(|c| field(c, "√(1−n·n_k)") >= a) {
        assert!(c.rejected.is_some(), "pixel {corner:?}: {} passes Ward's normal term\n{text}", c.name);
    }
    for c in e.contributions.iter().filter(|c| c.rejected.is_some()) {
        assert_eq!(c.value, Vec3::ZERO, "{}", c.name);
    }

    // On the sphere the weights of the records the splat adds have normal terms.
    let mut oblique = 0;
    for pixel in sphere_pixels(&r, size) {
        let e = explain_warm(&mut r, pixel, 12);
        assert_explained(&r, &e);
        let added = e.contributions.iter().filter(|c| c.rejected.is_none());
        oblique += added.filter(|c| field(c, "√(1−n·n_k)") > 0.01).count();
    }
    assert!(oblique > 0, "no record the splat adds on the sphere has a normal other than the pixel's");
}

#[test]
fn vpl_lit_records_explain_a_floor_pixel() {
    let size = 64;
    let mut r =
        preset_renderer(include_str!("../../../presets/gautron-vpl-records.ron"), "gautron-vpl-records", size, |_| {});
    assert!(r.explain_unsupported().is_none(), "{:?}", r.explain_unsupported());
    r.set_explain(Some((0, 0)));
    r.render_frame();
    let floor = floor_pixel(&r, size);
    let e = explain_warm(&mut r, floor, 12);
    assert!(e.technique.contains("VPLs"), "{}", e.technique);
    assert!(e.value.max_element() > 0.0, "the floor is lit:\n{}", e.to_text(0));
    assert_explained(&r, &e);
}

/// The binned splat (GI Lab's, `Auto` on a GPU) sums the same records as the quads: the replay's
/// bound test is the bins' (`bins_next`), so its checks hold with either method.
#[test]
fn both_splat_methods_are_replayed() {
    for method in [SplatMethod::Blend, SplatMethod::Binned] {
        let size = 64;
        let text = include_str!("../../../presets/gautron-ic-splatting.ron");
        let mut r = preset_renderer(text, "gautron-ic-splatting", size, |s| s.gautron.splat = method);
        r.set_explain(Some((0, 0)));
        r.render_frame();
        let floor = floor_pixel(&r, size);
        let e = explain_warm(&mut r, floor, 12);
        assert!(e.technique.contains(&format!("{method:?}")), "{}", e.technique);
        assert_explained(&r, &e);
    }
}

/// Under animation the rounds make records, compute stale ones again in place and clamp the
/// cached ones by their new neighbours, after the cached records' splat: the replay reads each
/// record as the splat that added it read it (`gautron::explain::Snapshots`), so the sums hold
/// on every frame, not only on frames where the cache stands still.
#[test]
fn frames_that_change_the_cache_replay_their_records_as_the_splats_read_them() {
    let size = 64;
    let text = include_str!("../../../presets/gautron-ic-splatting.ron");
    let mut r = preset_renderer(text, "gautron-ic-splatting", size, |_| {});
    r.set_explain(Some((0, 0)));
    r.render_frame();
    let floor = floor_pixel(&r, size);
    r.set_explain(Some(floor));
    r.render_frame();
    // The sphere moves: the records it leaves go stale and are computed again.
    r.clock.playing = true;
    let mut changed = 0;
    for frame in 0..6 {
        r.render_frame();
        let st = r.gautron().expect("Gautron's stage").read_state(&r.ctx).expect("the cache's counters");
        changed += (st.made > 0 || st.refreshed > 0) as u32;
        let e = r.explanation().unwrap_or_else(|e| panic!("frame {frame}: {e}"));
        let added = e.contributions.iter().filter(|c| c.rejected.is_none()).count();
        let tol = sum_tolerance(added);
        for c in std::iter::once(e.total_check()).chain(e.checks.iter().cloned()) {
            assert!(c.relative_error() <= tol, "frame {frame}: {}: {}\n{}", c.what, c.relative_error(), e.to_text(0));
        }
    }
    assert!(changed > 0, "no frame changed the cache: the test shows nothing");
}
