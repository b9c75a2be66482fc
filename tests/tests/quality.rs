//! The quality table of issues #15, #16 and #17 (`gi_render::quality`, `gi-lab bench --suite quality`) on
//! the default scene at 256², against the stored path-traced bounce of 2048 spp
//! (`tests/data/cornell_1bounce_256_2048spp.exr`, the ground truth). Bounds are what
//! was measured on lavapipe plus a margin, or the goal where it is met (the first two
//! rows, and the HCB's since issue #51's glossy receiver); they guard against regressions.
//! Issue #51 adds the real scenes' cases (the chair seen from behind, …) with their own stored
//! truths.

use gi_lab_tests::{default_scene, gpu, stored_reference};

#[test]
fn the_quality_table_stays_within_its_measured_bounds() {
    let truth = stored_reference("cornell_1bounce_256_2048spp.exr");
    let rows = gi_render::quality::quality_table(
        &gpu(),
        &default_scene(),
        &truth,
        (256, 256),
        gi_render::quality::Timing::None,
    )
    .expect("the table");
    print!("{}", gi_render::quality::format_table(&rows));
    // Measured on lavapipe: 0.048, 0.033, 0.060, 0.022 (stratified reference VPLs, tangent-
    // plane splats and the inside-surfaces push; the HCB with the paper's 1024 VPLs and
    // d_max 0.1 × the scene radius); before: 0.062, 0.056, 0.078, 0.040, and before issue #15
    // 0.064, 0.056, 0.078, 0.040 with the HCB against its own levels = 1.
    // The goals: 0.05, 0.035, 0.06, 0.03 — the bounds, except the third, which the
    // measurement meets by less than its run-to-run spread (0.057–0.060 over VPL sets): 0.062.
    // Issue #16's rows: Soler's gather alone measured 0.273 after one frame, 0.264 after 16
    // with its temporal filter (it sees only the direct light on screen: 40 % of the indirect
    // light comes from senders the camera does not see), 0.2555 with the glossy reflection,
    // 0.2419 with the power-preserving vote (`soler.vote_power`); the near/far mix 0.0454,
    // 0.0449 with it; its goal is to beat both Knecht's row and Soler's.
    // Issue #17's row: Gautron's records measured 0.0546 (a hemisphere per pixel: 0.0542).
    // Issue #41 made soler-quarter-4-64 Fig. 9's configuration as the text gives it: glossy
    // reflection off (Fig. 9 times the diffuse pipeline) and the senders' diffuse light
    // (§5.3): 0.2419 → 0.2584 (0.2515 with the view-dependent senders; the truth's senders
    // reflect specularly too). Its bound follows the measurement, as the others do.
    // Issue #51's glossy receivers: nguyen-hcb 0.0504 (its goal, 0.06, met; the diffuse
    // receiver's 0.057–0.060 is what the row used to measure, now against the per-pixel gather
    // as the fourth row), gautron-ic-splatting 0.0519 (0.0546).
    // Issue #51's consistent vote (`soler.vote_consistent`: a coarse texel sends along its
    // winner's normal only the light of the sub-pixels that face that way, and stands for the
    // winner's surface over its block): soler 0.2584 → 0.2666, for the chair's floor shadow no
    // longer lit at 300× the truth (0.594 → 0.481 below); the mix 0.0456 (unchanged).
    // Issue #56's row: DDGI's probes (ddgi-probes, one bounce like the truth, the glossy
    // receiver ⚠[ddgi.glossy-receiver]) measured 0.1054 with 8×4×8 probes; of that, 0.105 →
    // 0.089 was the first frame's noise kept at weight α^15 (⚠[ddgi.cold-start]: the running
    // mean from a cold start), the rest the grid's spacing (converged: 8×4×8 0.083, 8×8×8
    // 0.067, 12³ 0.050, 16³ 0.044). With 12×12×12 probes and the running mean: 0.0566 after 16
    // frames (11³ 0.0580, 12×8×12 0.0594, 10³ at 192 rays 0.0589); with idle probes skipped
    // (⚠[ddgi.idle-probes]) 0.0577. The goal, 0.06, is the bound.
    within(&rows, &[0.05, 0.035, 0.06, 0.03, 0.275, 0.05, 0.06, 0.06]);
    // The exact-VPL reference is closer to the ground truth than the 256 VPLs of Knecht's
    // configuration, and the HCB closer to the per-pixel gather than to the ground truth.
    assert!(rows[1].flip < rows[0].flip, "{} vs {}", rows[1].flip, rows[0].flip);
    assert!(rows[3].flip < rows[2].flip, "{} vs {}", rows[3].flip, rows[2].flip);
    // The near/far mix beats both of its parts alone.
    assert!(rows[5].flip < rows[0].flip, "mix {} vs Knecht {}", rows[5].flip, rows[0].flip);
    assert!(rows[5].flip < rows[4].flip, "mix {} vs Soler {}", rows[5].flip, rows[4].flip);
}

/// Issue #51's sky box: the default scene under a white sky at 128² against a 2048-spp
/// one-bounce path trace (`tests/data/sky_1bounce_128_2048spp.exr`). With the sky's 16
/// directions fixed every technique, the exact reference included, sat at 0.19–0.21 (the
/// direct light 14.7 % too bright); rotated every frame and averaged (`sky.rotate_each_frame`)
/// they converge.
#[test]
fn the_box_under_a_white_sky_stays_within_its_measured_bounds() {
    // Issue #51's goals: the exact reference ≤ 0.08, every VPL, HCB and Gautron row ≤ 0.10;
    // Soler's and the HCB's diffuse receiver against the per-pixel gather have none: their
    // bounds are the measurements plus a margin. Measured on lavapipe with the rotating sky
    // (before, 16 fixed directions): knecht 0.0938 (0.1977), exact 0.0796 (0.1971), nguyen-hcb
    // 0.0914 (0.1983), its diffuse receiver against the per-pixel gather 0.0184, soler 0.1877
    // (0.2255), the near/far mix 0.0880 (0.1958), gautron 0.0853 (0.1912). With the
    // consistent vote (`soler.vote_consistent`, see the chair): soler 0.1877 → 0.1964.
    real_scene_table_within(
        &gi_lab_tests::white_sky_box(),
        "sky_1bounce_128_2048spp.exr",
        // DDGI (issue #56): measured 0.0708 with 12³ probes, the running mean from a cold start
        // and idle probes skipped (8×4×8 as printed: 0.0970); bound the measurement plus a margin.
        [0.10, 0.08, 0.10, 0.025, 0.20, 0.10, 0.10, 0.075],
    );
}

/// Issue #51's chair: the shipped chair seen from behind, towards its sun
/// (`tests/data/chair-behind.glb`), at 128² against a 2048-spp one-bounce path trace
/// (`tests/data/chair_1bounce_128_2048spp.exr`). The chair's wood has an albedo of about 0.02:
/// what shows there is its specular lobe reflecting the sunlit floor, which the HCB's and
/// Gautron's diffuse receivers lost (FLIP 0.469 and 0.433 before; the goals are 0.20).
#[test]
fn the_chair_seen_from_behind_stays_within_its_measured_bounds() {
    // Measured on lavapipe after issue #51's glossy receivers (before them): knecht 0.1617,
    // exact 0.1080, nguyen-hcb 0.1823 (0.4687), its diffuse receiver against the per-pixel
    // diffuse gather 0.0580, soler 0.5946, the near/far mix 0.1922, gautron 0.1417 (0.4332).
    // The HCB's and Gautron's bounds are the goals; Knecht's (goal 0.15), the exact
    // reference's (goal 0.10) and Soler's (goal 0.50) are not met yet: their bounds are the
    // measurements plus a margin, so that they do not regress. Against path tracer 2's truth
    // (camera hits read the G-buffer's mip level; FLIP 0.012 from version 1's) and with the
    // demodulated filter: knecht 0.1608, exact 0.1060, nguyen-hcb 0.1816, its diffuse receiver
    // 0.0580, soler 0.5941, the mix 0.1914, gautron 0.1425. Two 2048-spp truths of different
    // seeds differ by FLIP 0.030, most of it in the floor's shadow, where Knecht's and the
    // exact reference's errors are too (a 16,384-spp truth gives the same figures: the error
    // is theirs; the truth's shadow holds indirect light, about 0.1, that the exact reference
    // leaves at 0). That light is the sun's glint off the chair's metal brackets (metallic,
    // roughness 0.3, SP ≈ 245) onto the floor: paths sun → metal → floor, found by tracing
    // pixels (20, 100) and (30, 110) (0.42 and 0.46 of their light from the metal, the rest
    // from the seat's sunlit side). The metal covers about 120 of the 512² texels of the
    // sun's view, so the 4,096 VPLs put about two there; 16,384 VPLs give 0.0998, and
    // resampling the VPLs by the peak of their BRDF (8 candidates) 0.1086: the exact
    // reference's own limit, shared by Knecht's VPLs, while Gautron's hemispheres see the
    // glint (0.1425, and the study's truth names Gautron where the exact reference names the
    // mix).
    // Soler's bound is its goal since the consistent vote (`soler.vote_consistent`): the
    // chair's sunlit seat inside blocks won by its unlit back no longer lights the floor's
    // shadow, 0.5941 → 0.4808 (against the screen-visible truth 0.366 → 0.185, the box's
    // 0.178 → 0.191); the near/far mix 0.1914 → 0.1592.
    let scene = gi_lab_tests::test_scene("chair-behind.glb");
    // DDGI (issue #56) measured 0.5912 with the papers' diffuse receiver, which loses the
    // wood's glint of the sunlit floor as the HCB's and Gautron's did before their glossy
    // receivers (0.47, 0.43); with its glossy receiver (⚠[ddgi.glossy-receiver]) 0.336, and
    // with 12³ probes, the running mean and idle probes skipped 0.3337: the probes' cosine lobe about the mirror
    // direction is far wider than the wood's, and lights the floor's shadow (about 2 against
    // the truth's 0.1). Bound the measurement plus a margin.
    real_scene_table_within(
        &scene,
        "chair_1bounce_128_2048spp.exr",
        [0.17, 0.115, 0.20, 0.065, 0.50, 0.20, 0.20, 0.35],
    );
}

/// Issue #51's second goal for Soler: against what a screen-space gather can know (the
/// one-bounce truth from screen-visible senders only), soler-quarter-4-64 is no worse on the
/// chair seen from behind than on the default box. Before the consistent vote the chair's
/// floor shadow, lit by the seat's light sent along the back's normal, made it 0.366 against
/// the box's 0.178; measured with it on lavapipe: 0.185 against 0.191.
#[test]
fn soler_is_no_worse_on_the_chair_than_on_the_box_against_what_the_screen_sees() {
    let row = |scene: &gi_render::scene::Scene, truth: &str| {
        gi_render::quality::ground_truth_row(&gpu(), scene, &stored_reference(truth), (128, 128), "soler-quarter-4-64")
            .expect("Soler's row")
            .flip
    };
    let chair = row(&gi_lab_tests::test_scene("chair-behind.glb"), "chair_screen_visible_128_2048spp.exr");
    let the_box = row(&default_scene(), "cornell_screen_visible_128_2048spp.exr");
    println!("soler-quarter-4-64 against the screen-visible truth: chair {chair:.4}, box {the_box:.4}");
    assert!(chair <= the_box, "chair {chair:.4} > box {the_box:.4}");
}

/// The table of `scene` at 128² against the stored truth `truth_file`, printed without the
/// default scene's goals, and each row checked against its bound (issue #51's cases).
fn real_scene_table_within(scene: &gi_render::scene::Scene, truth_file: &str, bounds: [f64; 8]) {
    let truth = stored_reference(truth_file);
    let mut rows =
        gi_render::quality::quality_table(&gpu(), scene, &truth, (128, 128), gi_render::quality::Timing::None)
            .expect("the table");
    rows.iter_mut().for_each(|r| r.goal = None);
    print!("{}", gi_render::quality::format_table(&rows));
    within(&rows, &bounds);
}

/// Every row is above 0 (something was compared) and at most its bound.
fn within(rows: &[gi_render::quality::QualityRow], bounds: &[f64]) {
    assert_eq!(rows.len(), bounds.len());
    for (row, &bound) in rows.iter().zip(bounds) {
        assert!(row.flip > 0.0, "{}: FLIP 0 means nothing was compared", row.configuration);
        assert!(
            row.flip <= bound,
            "{} ({} frames) against {}: FLIP {:.4} > {bound}",
            row.configuration,
            row.frames,
            row.against,
            row.flip
        );
    }
}

/// Issue #51's hotel room at the view it opens on, lit by the point light the loader adds,
/// at 128² against a 2048-spp one-bounce path trace (`tests/data/hotel_1bounce_128_2048spp.exr`):
/// Knecht's configuration alone (the whole table costs minutes here). Its carpet's pattern
/// decided the verdict twice: the geometry-aware filter blurred it (`interleave.demodulate`)
/// and the path tracer read it at mip level 0, a sharper image than the G-buffer's (path
/// tracer version 2 reads the G-buffer's level).
#[test]
fn the_hotel_room_stays_within_the_goal() {
    // Measured on lavapipe: 0.0531 (before issue #51: 0.0898 against the level-0 truth; the
    // demodulated filter alone 0.0798 against it). The bound is the goal, 0.075.
    let scene = gi_lab_tests::asset_scene("scenes/hotel-room/hotel-room.glb");
    let truth = stored_reference("hotel_1bounce_128_2048spp.exr");
    let row = gi_render::quality::ground_truth_row(&gpu(), &scene, &truth, (128, 128), "knecht-cornell-256")
        .expect("the row");
    print!("{}", gi_render::quality::format_table(std::slice::from_ref(&row)));
    within(&[row], &[0.075]);
}
