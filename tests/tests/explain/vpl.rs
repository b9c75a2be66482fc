//! Explain a pixel (issue #42) for instant radiosity's VPL gather (Knecht 002 §3.4–3.5, §4.5):
//! the GPU replay's contributions sum to the buffers the frame wrote, each VPL's term equals
//! its CPU twin (`cpu::knecht::vpl_radiance` × the tile's N / N_t × the chain's weight), and a
//! shadowed pixel lists the VPLs the exact maps hide as occluded, as a ray cast does.

use gi_lab_tests::paused_renderer;
use gi_render::Renderer;
use gi_render::cpu::knecht::{Receiver, Vpl, vpl_radiance};
use gi_render::explain::{Explanation, Rejection, luminance};
use gi_render::passes::knecht::temporal::MergeOrder;
use gi_render::scene::raycast::TriangleSoup;
use gi_render::settings::pipeline::{Reconstruction, ShadingPoints, Technique, Temporal, VplVisibility};
use glam::Vec3;

/// The sums are of f32 terms; the buffers they are checked against are half floats
/// (`indirect.merged`, `indirect.filtered`: a step of 2⁻¹¹ relative) and the merge reads them
/// (docs/architecture.md, "Half floats"): two half steps; and the merge's output,
/// `temporal.history`, is half floats too (issue #53), checked against or read by the filter
/// when it follows the merge: a third.
const SUM_TOLERANCE: f32 = 3.0 * 4.9e-4;

/// The demodulated filter's check (issue #51): `indirect.filtered` = k_p·mean(E) + mean(L −
/// k·E) is computed from two half-float buffers, L (`indirect.merged`) and E
/// (`indirect.irradiance`), a step each, with E entering twice (reflected with the pixel's
/// colour and with each neighbour's), and stored as a half float: four half steps.
const DEMODULATED_TOLERANCE: f32 = 4.0 * 4.9e-4;

fn field(c: &gi_render::explain::Contribution, name: &str) -> f32 {
    c.fields.iter().find(|(k, _)| *k == name).map(|(_, v)| *v).unwrap_or_else(|| panic!("{}: no {name}", c.name))
}

fn v3(v: glam::Vec4) -> Vec3 {
    v.truncate()
}

/// Renders `frames` frames with `pixel` pinned and explains it.
fn explain(r: &mut Renderer, pixel: (u32, u32), frames: u32) -> Explanation {
    r.set_explain(Some(pixel));
    for _ in 0..frames {
        r.render_frame();
    }
    r.explanation().unwrap_or_else(|e| panic!("pixel {pixel:?}: {e}"))
}

/// Every check of `e` holds to the half floats' rounding.
fn assert_sums(e: &Explanation) {
    let total = e.total_check();
    assert!(
        total.relative_error() <= SUM_TOLERANCE,
        "pixel {:?}: {}\n{}",
        e.pixel,
        total.relative_error(),
        e.to_text(8)
    );
    for c in &e.checks {
        let tolerance = if c.what.contains("demodulated") { DEMODULATED_TOLERANCE } else { SUM_TOLERANCE };
        assert!(
            c.relative_error() <= tolerance,
            "pixel {:?}: {} ({})\n{}",
            e.pixel,
            c.what,
            c.relative_error(),
            e.to_text(8)
        );
    }
    assert!(luminance(e.value) > 0.0, "pixel {:?} has no indirect light:\n{}", e.pixel, e.to_text(8));
}

/// Each VPL's share equals its CPU twin's term at the pixel it came through.
fn assert_cpu_twin(r: &Renderer, e: &Explanation) {
    let slots = r.vpl_slots().expect("the VPL list");
    let s = r.settings();
    let d_min = if e.buffer == "indirect.accum" { s.reference.min_distance_m } else { s.vpl.min_distance_m };
    let eye = r.camera.position;
    let mut compared = 0;
    for c in e.contributions.iter().filter(|c| c.name.starts_with("VPL ")) {
        let k: usize = c.name[4..].parse().expect("slot");
        let g = slots[k];
        let vpl = Vpl {
            position: v3(g.position),
            normal: v3(g.normal),
            flux: v3(g.flux),
            incident: v3(g.incident),
            albedo: v3(g.albedo),
            di: g.normal.w,
            si: g.flux.w,
            sp: g.incident.w,
        };
        let q = c.via.unwrap_or(e.pixel);
        let probe = r.probe(&[q]).expect("probe");
        let at = |name: &str| probe[0].iter().find(|v| v.name == name).unwrap_or_else(|| panic!("{name}")).value;
        let (pos, nrm, alb, mat) =
            (at("gbuffer.position"), at("gbuffer.normal"), at("gbuffer.albedo"), at("gbuffer.material"));
        let x = Receiver {
            position: Vec3::new(pos[0], pos[1], pos[2]),
            normal: Vec3::new(nrm[0], nrm[1], nrm[2]).normalize(),
            albedo: Vec3::new(alb[0], alb[1], alb[2]),
            di: alb[3],
            si: mat[0],
            sp: mat[1],
        };
        // The tile's N / N_t (1 for the reference, which gathers every VPL of its batch).
        let scale = c.fields.iter().find(|(k, _)| *k == "N/N_t").map(|(_, v)| *v).unwrap_or(1.0);
        let cpu = vpl_radiance(&vpl, &x, eye, d_min) * scale;
        if c.rejected == Some(Rejection::NearField) {
            // Closer than the cut: the near field's; the far field's gather adds nothing.
            assert_eq!(field(c, "unshadowed (lum)"), 0.0, "{}", c.name);
            let cut = r.settings().soler.near_field_split(r.scale_radius());
            assert!((vpl.position - x.position).length() < cut * 1.0001, "{} is beyond the cut", c.name);
            compared += 1;
            continue;
        }
        let gpu_unshadowed = field(c, "unshadowed (lum)");
        let scale = luminance(cpu).abs().max(1e-6);
        assert!(
            (gpu_unshadowed - luminance(cpu)).abs() / scale < 2e-4,
            "{} via {q:?}: GPU {gpu_unshadowed} against the CPU twin's {}",
            c.name,
            luminance(cpu)
        );
        match &c.rejected {
            None => {
                let want = cpu * c.weight;
                let err = (c.value - want).abs().max_element() / want.abs().max_element().max(1e-9);
                assert!(err < 2e-4, "{}: share {} against the CPU twin's {want}", c.name, c.value);
            }
            Some(Rejection::Facing) => assert_eq!(cpu, Vec3::ZERO, "{} faces away on the GPU only", c.name),
            Some(_) => assert_eq!(c.value, Vec3::ZERO, "{} is rejected but has a share", c.name),
        }
        compared += 1;
    }
    assert!(compared > 0, "no VPL listed:\n{}", e.to_text(8));
}

/// Pixels of the default box at 64²: the floor, the back wall, the red wall, the tall block.
const PIXELS: [(u32, u32); 4] = [(32, 56), (32, 20), (6, 30), (24, 36)];

#[test]
fn every_pixel_gather_sums_to_its_buffer_and_equals_the_cpu_twin() {
    let mut r = paused_renderer(64, Technique::Knecht, |s| {
        s.pipeline.shading_points = ShadingPoints::EveryPixel;
        s.pipeline.reconstruction = Reconstruction::None;
        s.pipeline.temporal = Temporal::None;
        s.vpl.count = 64;
    });
    for p in PIXELS {
        let e = explain(&mut r, p, 1);
        assert_eq!(e.buffer, "indirect.merged");
        assert_sums(&e);
        assert_cpu_twin(&r, &e);
        // Every pixel gathers every VPL: all 64 slots are listed, none through another pixel.
        assert_eq!(e.contributions.len(), 64, "{}", e.to_text(0));
        assert!(e.contributions.iter().all(|c| c.via.is_none() && (field(c, "N/N_t") - 1.0).abs() < 1e-6));
    }
}

#[test]
fn interleaved_tiles_with_the_filter_and_the_merge_sum_to_their_buffers_in_both_orders() {
    for order in [MergeOrder::FilterThenMerge, MergeOrder::MergeThenFilter] {
        let mut r = paused_renderer(64, Technique::Knecht, |s| {
            s.temporal.order = order;
            s.vpl.count = 128;
        });
        assert_eq!(r.settings().pipeline.reconstruction, Reconstruction::GeometryAwareFilter);
        assert_eq!(r.settings().pipeline.temporal, Temporal::ConfidenceMerge);
        // Warm the history so that the confidence is above 0.
        for _ in 0..3 {
            r.render_frame();
        }
        for p in PIXELS {
            let e = explain(&mut r, p, 1);
            let want = if order == MergeOrder::FilterThenMerge { "temporal.history" } else { "indirect.filtered" };
            assert_eq!(e.buffer, want);
            assert_sums(&e);
            assert_cpu_twin(&r, &e);
            let history: Vec<_> = e.contributions.iter().filter(|c| c.name == "history").collect();
            assert!(!history.is_empty() && history.iter().any(|h| field(h, "c") > 0.0), "{order:?}: {}", e.to_text(4));
            // With the filter every VPL reaches the pixel through one pixel of the window: all
            // N slots are listed (those outside the image or filtered out as rejected).
            assert_eq!(e.contributions.iter().filter(|c| c.name.starts_with("VPL ")).count(), 128);
        }
    }
}

#[test]
fn a_shadowed_pixel_lists_the_vpls_the_exact_maps_hide_as_a_ray_cast_does() {
    let mut r = paused_renderer(64, Technique::Knecht, |s| {
        s.pipeline.vpl_visibility = VplVisibility::Exact;
        s.pipeline.shading_points = ShadingPoints::EveryPixel;
        s.pipeline.reconstruction = Reconstruction::None;
        s.pipeline.temporal = Temporal::None;
        s.vpl.count = 64;
    });
    let state = r.scene().evaluate(0.0);
    let soup = TriangleSoup::new(r.scene(), &state);
    let eps = 1e-3 * r.bounds().radius();
    // The floor beside and behind the blocks: the pixel with the most occluded VPLs.
    let candidates = [(14, 58), (20, 52), (44, 50), (50, 46), (12, 48), (28, 46)];
    let explained: Vec<Explanation> = candidates.iter().map(|&p| explain(&mut r, p, 1)).collect();
    let occluded = |e: &Explanation| e.contributions.iter().filter(|c| c.rejected == Some(Rejection::Occluded)).count();
    let pixel = explained.iter().max_by_key(|e| occluded(e)).expect("candidates").pixel;
    // Explained again, so that the VPL list read below is its frame's.
    let e = &explain(&mut r, pixel, 1);
    assert_sums(e);
    assert_cpu_twin(&r, e);
    assert!(occluded(e) >= 4, "no shadowed pixel among the candidates:\n{}", e.to_text(0));
    let probe = r.probe(&[e.pixel]).expect("probe");
    let pos = probe[0].iter().find(|v| v.name == "gbuffer.position").expect("position").value;
    let nrm = probe[0].iter().find(|v| v.name == "gbuffer.normal").expect("normal").value;
    let x = Vec3::new(pos[0], pos[1], pos[2]) + Vec3::new(nrm[0], nrm[1], nrm[2]).normalize() * eps;
    let slots = r.vpl_slots().expect("the VPL list");
    let (mut agree, mut total) = (0, 0);
    for c in e.contributions.iter().filter(|c| matches!(c.rejected, None | Some(Rejection::Occluded))) {
        let k: usize = c.name[4..].parse().expect("slot");
        let y = v3(slots[k].position) + v3(slots[k].normal) * eps;
        let blocked = soup.occluded(x, y, eps);
        agree += (blocked == (c.rejected == Some(Rejection::Occluded))) as u32;
        total += 1;
    }
    eprintln!(
        "pixel {:?}: {} occluded; the exact maps and the ray cast agree on {agree} of {total} VPLs",
        e.pixel,
        occluded(e)
    );
    assert!(agree as f32 >= 0.9 * total as f32, "the exact maps and the ray cast agree on {agree} of {total} VPLs");
    // The occluded VPLs' depths are in the fields: the receiver lies beyond the stored depth.
    for c in e.contributions.iter().filter(|c| c.rejected == Some(Rejection::Occluded)) {
        assert!(field(c, "receiver depth") > field(c, "map depth"), "{}", c.name);
    }
}

#[test]
fn the_exact_vpl_reference_splits_the_pixel_into_its_batch_and_the_previous_average() {
    let mut r = paused_renderer(64, Technique::ExactVpl, |s| s.reference.vpls_per_frame = 64);
    for _ in 0..2 {
        r.render_frame();
    }
    for p in PIXELS {
        let e = explain(&mut r, p, 1);
        assert_eq!(e.buffer, "indirect.accum");
        assert_sums(&e);
        assert_cpu_twin(&r, &e);
        let prev = e.contributions.iter().find(|c| c.name == "previous batches").expect("the average's share");
        let k = field(prev, "batches");
        assert!(k >= 2.0 && (prev.weight - k / (k + 1.0)).abs() < 1e-6, "{}", e.to_text(4));
    }
}

#[test]
fn the_near_far_mix_explains_both_fields_against_the_sum_of_their_buffers() {
    let mut r = paused_renderer(64, Technique::SolerNearKnechtFar, |s| s.vpl.count = 128);
    for _ in 0..2 {
        r.render_frame();
    }
    // The back wall's corner with the floor and the floor by the blocks: senders nearby.
    for p in [(32, 44), (20, 50), (44, 48)] {
        let e = explain(&mut r, p, 1);
        assert_eq!(e.buffer, "temporal.history + soler.temporal");
        assert_sums(&e);
        assert_cpu_twin(&r, &e);
        assert!(e.contributions.iter().any(|c| c.name.starts_with("near: level ")), "{}", e.to_text(4));
        assert!(e.checks.iter().any(|c| c.buffer == "soler.indirect"));
    }
}

#[test]
fn explaining_what_is_not_written_yet_says_so() {
    // A complete exact-VPL average gathers no batch: nothing to replay, and it says why.
    let mut r = paused_renderer(32, Technique::ExactVpl, |s| {
        s.reference.vpls_per_frame = 64;
        s.reference.total_vpls = 128;
    });
    r.set_explain(Some((16, 28)));
    for _ in 0..3 {
        r.render_frame();
    }
    let err = r.explanation().expect_err("the average is complete");
    assert!(err.contains("complete"), "{err}");
}
