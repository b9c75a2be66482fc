//! Instant radiosity with ISMs and temporal coherence (Knecht 002, issue #5): image quality
//! against exact visibility and the path-traced bounce, and the temporal behaviour of the
//! confidence (§3.5) — flicker, moving objects and a light that jumps. Bounds were measured
//! on lavapipe; each test prints what it measured.

use gi_lab_tests::{default_scene, gpu, stored_reference};
use gi_render::image_io::hdr_display;
use gi_render::settings::pipeline::{Temporal, VplVisibility};
use gi_render::{ImageF32, LabSettings, Renderer};
use glam::Vec3;

/// The `knecht-cornell-256` preset, edited, on the default scene at `size`², paused.
fn knecht(size: u32, edit: impl FnOnce(&mut LabSettings)) -> Renderer {
    let loaded = gi_render::preset::load_lenient(include_str!("../../presets/knecht-cornell-256.ron"), "knecht")
        .expect("the preset loads");
    let mut s = loaded.settings;
    edit(&mut s);
    let mut r = Renderer::new(gpu(), default_scene(), s, size, size).expect("renderer");
    r.clock.playing = false;
    r
}

fn frames(r: &mut Renderer, n: usize, buffer: &str) -> Vec<ImageF32> {
    (0..n)
        .map(|_| {
            r.render_frame();
            r.readback(buffer).unwrap_or_else(|e| panic!("{buffer}: {e}"))
        })
        .collect()
}

fn flip(a: &ImageF32, b: &ImageF32) -> f64 {
    gi_render::metrics::flip(&hdr_display(a), &hdr_display(b)).expect("flip").0
}

#[test]
fn imperfect_shadow_maps_stay_close_to_exact_shadow_maps_for_the_same_vpls() {
    let image = |vis: VplVisibility| {
        let mut r = knecht(128, |s| {
            s.vpl.new_set_each_frame = false;
            s.pipeline.temporal = Temporal::None;
            s.pipeline.vpl_visibility = vis;
        });
        frames(&mut r, 1, "final.hdr").remove(0)
    };
    let exact = image(VplVisibility::Exact);
    let ism = image(VplVisibility::Imperfect);
    let none = image(VplVisibility::None);
    let (f_ism, f_none) = (flip(&ism, &exact), flip(&none, &exact));
    println!("FLIP vs exact shadow maps, same 256 VPLs, 128²: ISM {f_ism:.4}, no visibility {f_none:.4}");
    // Measured: ISM 0.051, no visibility 0.099 (before the receiver normal offset the ISMs
    // shadowed their own surfaces and scored 0.119, worse than no visibility at all). The
    // bound keeps ISMs within 0.065 of exact and well below leaving visibility out.
    assert!(f_ism <= 0.065, "ISM vs exact shadow maps: FLIP {f_ism} > 0.065");
    assert!(f_ism < 0.6 * f_none, "ISMs must recover most of the visibility: {f_ism} vs {f_none} without");
}

#[test]
fn temporal_coherence_brings_256_vpls_closer_to_the_path_traced_bounce() {
    let reference = stored_reference("cornell_1bounce_256.exr");
    let run = |temporal: bool| {
        let mut r =
            knecht(256, |s| s.pipeline.temporal = if temporal { Temporal::ConfidenceMerge } else { Temporal::None });
        let t = std::time::Instant::now();
        let img = frames(&mut r, 16, "final.hdr").pop().expect("16 frames");
        println!("16 frames at 256² in {:.1} s", t.elapsed().as_secs_f32());
        img
    };
    let (on, off) = (run(true), run(false));
    let (f_on, f_off) = (flip(&on, &reference), flip(&off, &reference));
    println!(
        "FLIP vs the path-traced bounce, 256², 256 VPLs, frame 16: temporal coherence {f_on:.4}, without {f_off:.4}"
    );
    // Measured: 0.070 with, 0.080 without (ISM, interleaving and one-bounce VPL bias remain).
    assert!(f_on < f_off, "temporal coherence must help: {f_on} vs {f_off}");
    assert!(f_on <= 0.08, "ISM + temporal coherence vs the path-traced bounce: FLIP {f_on} > 0.08");
}

#[test]
fn temporal_coherence_cuts_flicker_at_least_five_times() {
    let run = |temporal: bool| {
        let mut r =
            knecht(128, |s| s.pipeline.temporal = if temporal { Temporal::ConfidenceMerge } else { Temporal::None });
        let all = frames(&mut r, 20, "final.hdr");
        gi_render::metrics::flicker(&all[8..]).expect("flicker")
    };
    let (on, off) = (run(true), run(false));
    // Measured: 0.0115 with, 0.0752 without (ratio 6.6). With the filter after the merge, as
    // in the thesis, the ratio was 2.6: see the stage order in `Renderer::knecht_frame`.
    println!(
        "flicker over frames 8…19, 128², a new VPL set each frame: with {on:.5}, without {off:.5}, ratio {:.2}",
        off / on
    );
    assert!(off >= 5.0 * on, "flicker with {on}, without {off}");
}

/// Pixels whose movement-buffer value is non-zero: the moving object (the camera is still).
fn moving(motion: &ImageF32) -> Vec<bool> {
    motion.data.iter().map(|m| m[0].hypot(m[1]) > 0.01).collect()
}

#[test]
fn confidence_is_low_on_a_moving_object_and_what_it_uncovers_and_high_elsewhere() {
    // The default scene's sphere slides across the floor; the camera stands still.
    let mut r = knecht(128, |_| {});
    r.clock.seek(1.5);
    r.clock.playing = true;
    let mut prev_mask = Vec::new();
    let (mut on, mut uncovered, mut rest) = (Vec::new(), Vec::new(), Vec::new());
    let mut speed = 0.0f32;
    for frame in 0..8 {
        r.render_frame();
        let motion = r.readback("gbuffer.motion").expect("motion");
        let normal = r.readback("gbuffer.normal").expect("normal");
        let conf = r.readback("temporal.confidence").expect("confidence");
        let mask = moving(&motion);
        if frame >= 3 {
            let (w, h) = (motion.width as i32, motion.height as i32);
            // Within 2 pixels of a mask: left out of "elsewhere" (the filter and the
            // rounding of the reprojection blur the borders).
            let near = |x: i32, y: i32, m: &[bool]| {
                (-2..=2).any(|dy| {
                    (-2..=2).any(|dx| {
                        let (qx, qy) = (x + dx, y + dy);
                        qx >= 0 && qy >= 0 && qx < w && qy < h && m[(qy * w + qx) as usize]
                    })
                })
            };
            for y in 0..h {
                for x in 0..w {
                    let i = (y * w + x) as usize;
                    if normal.data[i][3] < 0.5 {
                        continue;
                    }
                    let c = conf.data[i][0];
                    if mask[i] {
                        on.push(c);
                        speed = speed.max(motion.data[i][0].hypot(motion.data[i][1]));
                    } else if prev_mask[i] {
                        uncovered.push(c);
                    } else if !near(x, y, &mask) && !near(x, y, &prev_mask) {
                        rest.push(c);
                    }
                }
            }
        }
        prev_mask = mask;
    }
    let mean = |v: &[f32]| v.iter().sum::<f32>() / v.len().max(1) as f32;
    let (c_on, c_unc, c_rest) = (mean(&on), mean(&uncovered), mean(&rest));
    println!(
        "confidence (5 frames, 128², w_pos 300): on the sphere {c_on:.3} ({} px), uncovered {c_unc:.3} ({} px), elsewhere {c_rest:.3} ({} px); sphere moves up to {speed:.2} px per frame",
        on.len(),
        uncovered.len(),
        rest.len()
    );
    assert!(on.len() > 500 && !uncovered.is_empty() && rest.len() > 5000, "the masks are too small to judge");
    // Measured: 0.33 on the sphere, 0 uncovered (its depth jumps), 0.89 elsewhere (c_base 0.9).
    assert!(c_on < 0.5 * c_rest, "confidence on the moving sphere {c_on} vs {c_rest} elsewhere");
    assert!(c_unc < 0.1, "confidence where the sphere was: {c_unc}");
    assert!(c_rest > 0.8, "confidence on the still scene: {c_rest}");
}

#[test]
fn a_light_jump_fades_out_within_a_few_frames() {
    let jump = |r: &mut Renderer| {
        let node = r.scene().nodes.iter().position(|n| n.light.is_some()).expect("the default scene has a light");
        r.scene_mut().nodes[node].transform.translation += Vec3::new(-0.6, 0.0, 0.0);
    };
    // Renderer a has the light at the old place for 12 frames, then at the new one;
    // renderer b has it at the new place all along. Same frame indices, same VPL samples.
    let mut a = knecht(128, |_| {});
    let mut b = knecht(128, |_| {});
    jump(&mut b);
    let rmse = |x: &ImageF32, y: &ImageF32| gi_render::metrics::rmse(x, y).expect("rmse");
    let before_a = frames(&mut a, 12, "final.hdr").pop().expect("frames");
    let before_b = frames(&mut b, 12, "final.hdr").pop().expect("frames");
    let change = rmse(&before_a, &before_b);
    jump(&mut a);
    let after_a = frames(&mut a, 24, "final.hdr");
    let after_b = frames(&mut b, 24, "final.hdr");
    let residual: Vec<f64> = after_a.iter().zip(&after_b).map(|(x, y)| rmse(x, y) / change).collect();
    println!(
        "light jump: change RMSE {change:.4}; residual / change per frame {:?}",
        residual.iter().map(|r| format!("{r:.3}")).collect::<Vec<_>>()
    );
    // Afterglow: frames until what is left of the old lighting is below 10 % of the change.
    // Measured: 3 frames (0.146, 0.123, 0.107, 0.092, …; the illumination term of Eq. 3.3
    // cuts the confidence from 0.9 to about 0.8 on the changed pixels), then a steady fade.
    let afterglow = residual.iter().position(|&r| r < 0.1).unwrap_or(residual.len());
    assert!(afterglow <= 4, "the old lighting stays above 10 % for {afterglow} frames");
    assert!(residual[23] < 0.02, "24 frames after the jump {} of the change is left", residual[23]);
    assert!(residual.windows(2).all(|w| w[1] <= w[0] + 1e-3), "the afterglow must fade: {residual:?}");
}

/// Mean luminance of an image.
fn mean_luminance(img: &ImageF32) -> f64 {
    img.data.iter().map(|p| (0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]) as f64).sum::<f64>() / img.data.len() as f64
}

#[test]
fn further_bounces_bring_the_image_closer_to_the_path_traced_three_bounces() {
    use gi_render::passes::knecht::vpl_bounce::{BounceMethod, BounceSelection};
    let reference = stored_reference("cornell_3bounce_128.exr");
    let run = |bounces: u32, selection: BounceSelection, method: BounceMethod| {
        let mut r = knecht(128, |s| {
            s.vpl.bounces = bounces;
            s.vpl.bounce_selection = selection;
            s.vpl.bounce_method = method;
        });
        let img = frames(&mut r, 16, "final.hdr").pop().expect("16 frames");
        (flip(&img, &reference), mean_luminance(&img))
    };
    let l_ref = mean_luminance(&reference);
    let (f1, l1) = run(1, BounceSelection::Strongest, BounceMethod::PointCloud);
    let (f3, l3) = run(3, BounceSelection::Strongest, BounceMethod::PointCloud);
    let (f3p, l3p) = run(3, BounceSelection::Proportional, BounceMethod::PointCloud);
    let (f3i, l3i) = run(3, BounceSelection::Strongest, BounceMethod::Irsm);
    println!(
        "vs the path-traced 3 bounces at 128², frame 16 (reference mean luminance {l_ref:.4}):\n  \
         1 bounce: FLIP {f1:.4}, mean {l1:.4}\n  3, strongest: FLIP {f3:.4}, mean {l3:.4}\n  \
         3, proportional: FLIP {f3p:.4}, mean {l3p:.4}\n  3, IRSM: FLIP {f3i:.4}, mean {l3i:.4}"
    );
    // Measured on lavapipe: 1 bounce FLIP 0.253 (mean 0.115 of the reference's 0.152);
    // 3 bounces strongest 0.125 (0.147), proportional 0.100 (0.144), IRSM 0.115 (0.141). More
    // bounces must recover the light the one-bounce image lacks by every method — FLIP at most
    // 0.6× the one-bounce image's and 0.14, mean luminance within 10 % of the reference and not
    // above it by more than 5 % (a VPL flux error of the new bounces would show here).
    for (name, f, l) in [("strongest", f3, l3), ("proportional", f3p, l3p), ("IRSM", f3i, l3i)] {
        assert!(f <= 0.6 * f1 && f <= 0.14, "{name}: 3 bounces FLIP {f} (1 bounce {f1})");
        assert!(l > 0.9 * l_ref && l < 1.05 * l_ref, "{name}: mean luminance {l} (1 bounce {l1}, reference {l_ref})");
    }
}
